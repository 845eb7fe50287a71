"""``waveoptics sweep``: a parameter sweep of the two-scale model on Dask, summarized in a CSV/JSON table."""
from __future__ import annotations

from ..errors import WaveopticsError
from ..units import parse_direction
from ._common import add_common, emit, not_asked, progress, spheres_skipped_text
from ._options import option
from .table import add_case_options, add_cluster_options, case_from_args

#: --vary names listed in the help (kept equal to waveoptics.distributed.VARY by tests/test_distributed.py; the
#: module is not imported here because importing Dask would slow down every command's start)
VARY_NAMES = ("material", "sigma_nano", "micro_alpha", "alpha_y", "theta", "kd", "ndf", "illuminant", "diffraction")


def register(sub):
    names = ", ".join(VARY_NAMES)
    p = sub.add_parser(
        "sweep", help="parameter sweep (materials, roughnesses, ...) with albedo, ΔE vs microfacet and cost, on Dask",
        description="Simulate every combination of the --vary lists (one Dask task per point) and write one row "
                    "per point: linear sRGB albedo of the two-scale and microfacet models, their ΔE2000 "
                    "(albedo colour, and per pixel over sphere renders), coherent fraction and cost in seconds. "
                    f"Parameters: {names}, or nano.KEY for any parameter of the --nano model.")
    p.add_argument("source", nargs="?", metavar="SCENE|SURFACE",
                   help="scene file (.toml) or nano height-field file; else the base case comes from the options")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=VALUES", required=True,
                   help="a parameter and its values, repeatable: material=Au,Ag,Cu  sigma_nano=1nm:20nm:5 (START:"
                        "STOP:STEP, a bare STEP in START's unit)  micro_alpha=0.05,0.2  theta=0:60:30")
    option(p, "--incident", note="default 30; with a scene file, its light's first direction")
    option(p, "--sphere-size", default=64, note="for the per-pixel ΔE2000; 0 skips the renders")
    option(p, "--no-spheres", action="store_true", default=False,
           note="as simulate's; the same as --sphere-size 0 (the dE_sphere columns are then empty: not computed, "
                "and a skipped column says why)"),
    add_case_options(p, command="sweep", resolution=64)
    option(p, "--output", short="-o", required=True, metavar="OUT.csv", note="a table (.csv or .json)")
    add_cluster_options(p)
    add_common(p)
    p.set_defaults(func=run)


def run(args):

    from .. import distributed

    args.incident_deg = None
    if args.incident is not None:
        theta, phi = parse_direction(args.incident, name="--incident")
        if theta >= 90:
            raise WaveopticsError(f"--incident θ={theta:g}° is not allowed; the light must be above the horizon "
                                  "(< 90)")
        args.incident_deg = (theta, phi)
    if not (0 <= args.sphere_size <= 1024):
        raise WaveopticsError(f"--sphere-size {args.sphere_size} is not allowed; use 0..1024")
    reason = not_asked("--no-spheres" if args.no_spheres else "--sphere-size 0")
    if args.no_spheres:        # one option for one meaning across commands (simulate --no-spheres)
        args.sphere_size = 0
    base, surface = case_from_args(args, source=args.source)
    varies = [distributed.parse_vary(v, base) for v in args.vary]
    n_points = len(distributed.sweep_points(base, varies))
    bar = progress(total=n_points, desc="sweep", args=args)
    try:
        res = distributed.run_sweep(base, varies, args.output, surface=surface, sphere_size=args.sphere_size, workers=args.workers,
                                    scheduler=args.scheduler, resume=args.resume, overwrite=args.overwrite,
                                    device=args.device, progress=bar.update, no_sphere_reason=reason)
    finally:
        bar.close()
    emit(args, res, sweep_text(res, [n for n, _ in varies]))
    return 0


def sweep_text(res: dict, names: list) -> str:
    """The text output of a sweep: one line for the run (with the sphere renders it skipped and why), one per point
    (its sphere ΔE2000 only where it was computed)."""
    from ..renderers.sphere import SKIPPED_KEY

    skipped = {k: v for r in res["rows"] for k, v in (r.get("skipped") or {}).items()}
    lines = [f"sweep {res['output']}: {res['points']} points ({res['computed']} computed, {res['skipped']} already "
             f"done) in {res['wall_s']:.1f} s" + (f"; {spheres_skipped_text(skipped[SKIPPED_KEY])}"
                                                    if SKIPPED_KEY in skipped else "")]
    for r in res["rows"]:
        vals = " ".join(f"{n}={r[n]}" for n in names)
        sphere = "" if r["dE_sphere_mean"] is None else f" {float(r['dE_sphere_mean']):.2f} (sphere mean)"
        lines.append(f"  {vals}: albedo RGB {float(r['albedo_R']):.3f} {float(r['albedo_G']):.3f} "
                     f"{float(r['albedo_B']):.3f}, ΔE2000 vs microfacet {float(r['dE_albedo']):.2f} (albedo)"
                     f"{sphere}, {float(r['cost_s']):.2f} s")
    return "\n".join(lines)
