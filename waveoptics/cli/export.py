"""``waveoptics export --format rgl -o material.bsdf``: the two-scale BRDF as a file a renderer reads."""
from __future__ import annotations

from ._common import add_common, add_output, emit
from ._renderer import add_model, model_fields

#: export formats → (what it is, file suffix)
FORMATS = {"rgl": ("RGL tabulated BSDF (Dupuy & Jakob 2018) for Mitsuba 3's and pbrt-v4's 'measured' models",
                   ".bsdf")}


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
    import time
    from pathlib import Path

    from .. import __version__
    from ..errors import WaveopticsError
    from ..renderers import rgl
    from ..renderers.jobs import build_model, describe_model
    from ..renderers.requests import RendererModel

    out = Path(args.output)
    suffix = FORMATS[args.format][1]
    if out.suffix.lower() != suffix:
        raise WaveopticsError(f"--output {args.output!r} must end in {suffix} for --format {args.format}")
    if out.exists() and not args.overwrite:
        raise WaveopticsError(f"--output {args.output!r} exists; give --overwrite to replace it")
    grid = rgl.RGLGrid(n_theta_i=args.incidence_nodes, resolution=args.table_resolution,
                       n_phi_i=args.azimuth_nodes)
    t0 = time.perf_counter()
    request = RendererModel(**model_fields(args))
    model, params = build_model(request)
    t1 = time.perf_counter()
    desc = describe_model(request, params)
    text = f"waveoptics {__version__} two-scale BRDF: " + ", ".join(f"{k}={v}" for k, v in desc.items()
                                                                      if v is not None)
    fields = rgl.export_rgl(model, out, grid=grid, description=text, overwrite=args.overwrite)
    t2 = time.perf_counter()
    data = {"output": str(out), "format": args.format, "model": desc,
            "isotropic": int(fields["phi_i"].size) == 2,
            "wavelengths_nm": [float(x) for x in fields["wavelengths"]],
            "theta_i_deg": [round(float(x), 6) for x in __import__("numpy").degrees(fields["theta_i"])],
            "shape": {k: list(v.shape) for k, v in fields.items() if hasattr(v, "shape")},
            "bytes": out.stat().st_size, "time_model_s": round(t1 - t0, 3), "time_export_s": round(t2 - t1, 3)}
    emit(args, data, f"wrote {out} ({data['bytes'] / 1e6:.2f} MB; {'isotropic' if data['isotropic'] else 'anisotropic'}"
                     f", {len(data['wavelengths_nm'])} wavelengths {data['wavelengths_nm'][0]:g}-"
                     f"{data['wavelengths_nm'][-1]:g} nm, {len(data['theta_i_deg'])} incidences; model "
                     f"{data['time_model_s']:.1f} s, table {data['time_export_s']:.1f} s)\n"
                     f"Mitsuba 3: <bsdf type=\"measured\"><string name=\"filename\" value=\"{out}\"/></bsdf>")
    return 0
