"""``waveoptics f0 MATERIAL...``: characteristic specular colour F0 = F(0°), computed spectrally."""
from __future__ import annotations

from ._common import add_colour, add_common, emit


def register(sub):
    p = sub.add_parser(
        "f0", help="specular colour F0 of materials (spectral, linear sRGB and 8-bit sRGB)",
        description="Normal-incidence reflectance F0(λ) of each material weighted by the illuminant and the "
                    "colour-matching functions to XYZ, then linear sRGB (not clipped: gold's red exceeds 1) and "
                    "8-bit sRGB (clipped), with the category by F0 (metal >= 0.45, dielectric < 0.2, "
                    "semiconductor in the 0.2-0.45 'forbidden zone').")
    p.add_argument("materials", nargs="+", metavar="MATERIAL",
                   help="preset (Au, gold, Si, BK7, ...), refractiveindex.info shelf/book/page, n+kj or f0:...")
    add_colour(p)
    add_common(p, device=False)
    p.set_defaults(func=run)


def run(args):

    from .. import colour
    from ..materials.database import get_material

    spd = colour.illuminant(args.illuminant)
    observer = colour.observer_name(args.observer)
    keys = ("material", "f0_linear", "f0_srgb8", "category", "source")
    rows, lines = [], []
    for spec in args.materials:
        d = colour.f0_colour(get_material(spec), spd, observer)
        rows.append({k: d[k] for k in keys})
        r, g, b = d["f0_linear"]
        flag = "  (forbidden zone 0.2-0.45)" if d["forbidden_zone"] else ""
        lines.append(f"{d['material']:<16} {r:7.4f} {g:7.4f} {b:7.4f}   {str(tuple(d['f0_srgb8'])):<16} "
                     f"{d['category']:<13} {d['source']}{flag}")
    header = (f"F0 under {spd.name}, {observer}, linear sRGB (unclipped) and 8-bit sRGB\n"
              f"{'material':<16} {'R':>7} {'G':>7} {'B':>7}   {'sRGB8':<16} {'category':<13} source")
    emit(args, rows, "\n".join([header, *lines]))
    return 0
