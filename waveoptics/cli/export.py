"""``waveoptics export --format rgl -o material.bsdf``: the two-scale BRDF as a file a renderer reads."""
from __future__ import annotations

from ..renderers.jobs import EXPORT_FORMATS as FORMATS
from ._common import add_common, add_output, emit
from ._renderer import add_model, model_fields


def register(sub):
    p = sub.add_parser(
        "export", help="write the BRDF as a file a renderer reads (RGL .bsdf for Mitsuba 3 and pbrt-v4)",
        description="Tabulate the two-scale BRDF in the RGL tensor format (Dupuy & Jakob 2018): its NDF, "
                    "projected area and visible-normal warp computed from the model, and the spectra at the "
                    "wavelength nodes on the warp's sample grid. Mitsuba 3 loads it with <bsdf type=\"measured\"> "
                    "and pbrt-v4 with its \"measured\" material; docs/renderers.md gives the measured accuracy.")
    p.add_argument("--format", choices=sorted(FORMATS), default="rgl",
                   help="; ".join(f"{k}: {v[0]}" for k, v in FORMATS.items()) + " (default rgl)")
    add_model(p)
    g = p.add_argument_group("RGL table")
    g.add_argument("--incidence-nodes", type=int, default=18, metavar="N",
                   help="incidence angles tabulated, evenly spaced over 0-89 degrees (default 18)")
    g.add_argument("--table-resolution", type=int, default=32, metavar="N",
                   help="sample-space grid of the spectra, N x N per incidence (default 32)")
    g.add_argument("--azimuth-nodes", type=int, default=9, metavar="N",
                   help="light azimuths over -180..180 degrees of an anisotropic BRDF (default 9)")
    add_output(p, note="the .bsdf file", metavar="FILE.bsdf")
    add_common(p, device=False)
    p.set_defaults(func=run)


def run(args):
    """``export``: :func:`waveoptics.renderers.jobs.export_job` of the options."""
    from ..renderers.jobs import export_job
    from ..renderers.requests import RendererModel

    data = export_job(RendererModel(**model_fields(args)), args.output, format=args.format,
                      incidence_nodes=args.incidence_nodes, table_resolution=args.table_resolution,
                      azimuth_nodes=args.azimuth_nodes, overwrite=args.overwrite)
    out = data["output"]
    emit(args, data, f"wrote {out} ({data['bytes'] / 1e6:.2f} MB; {'isotropic' if data['isotropic'] else 'anisotropic'}"
                     f", {len(data['wavelengths_nm'])} wavelengths {data['wavelengths_nm'][0]:g}-"
                     f"{data['wavelengths_nm'][-1]:g} nm, {len(data['theta_i_deg'])} incidences; model "
                     + (f"on {res}² cells " if (res := data["model"].get("resolution")) else "")
                     + f"{data['time_model_s']:.1f} s, table {data['time_export_s']:.1f} s)\n"
                     f"Mitsuba 3: <bsdf type=\"measured\"><string name=\"filename\" value=\"{out}\"/></bsdf>")
    return 0
