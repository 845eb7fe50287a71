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
    p.add_argument("--compare", action="store_true",
                   help="for each preset, F0 of every measured data set of the bundled refractiveindex.info "
                        "database that covers 380-780 nm (select one as PRESET@PAGE, e.g. Au@Babar), with the "
                        "spread over the experimental ones of bulk material")
    add_colour(p)
    add_common(p, device=False)
    p.set_defaults(func=run)


def run(args):
    if args.compare:
        return run_compare(args)

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


def _bulk_experimental(kind: str) -> bool:
    """A measured data set of the bulk material: the database's "Experimental data" headings, less thin films."""
    k = kind.lower()
    return "experimental" in k and "thin film" not in k


def run_compare(args):
    """F0 per data set and its spread (``f0 --compare``)."""
    import numpy as np

    from .. import colour
    from ..materials.database import data_sets, get_material

    spd = colour.illuminant(args.illuminant)
    observer = colour.observer_name(args.observer)
    out, lines = [], [f"F0 per data set under {spd.name}, {observer}, linear sRGB (unclipped); * = the preset's "
                      "default; spread over the experimental sets of bulk material (no thin films, no models)"]
    for name in args.materials:
        sets = [d for d in data_sets(name) if d["covers_visible"]]
        rows = []
        for d in sets:
            f0 = colour.f0_colour(get_material(d["spec"]), spd, observer)["f0_linear"]
            rows.append({**d, "f0_linear": [float(x) for x in f0]})
        bulk = np.array([r["f0_linear"] for r in rows if _bulk_experimental(r["kind"])])
        spread = (bulk.max(axis=0) - bulk.min(axis=0)).tolist() if len(bulk) >= 2 else None
        out.append({"material": name, "data_sets": rows, "bulk_spread_linear": spread})
        lines.append(f"\n{name}")
        for r in rows:
            rr, gg, bb = r["f0_linear"]
            lines.append(f"  {'*' if r['default'] else ' '} {r['spec']:<26} {rr:7.4f} {gg:7.4f} {bb:7.4f}   "
                         f"{r['kind']}: {r['name']}")
        if spread is not None:
            lines.append(f"    spread (max - min) over {len(bulk)} bulk sets: {spread[0]:.4f} {spread[1]:.4f} "
                         f"{spread[2]:.4f}")
    emit(args, out, "\n".join(lines))
    return 0
