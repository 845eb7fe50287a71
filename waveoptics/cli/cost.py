"""``waveoptics cost``: what accuracy costs in time — one configuration at a ladder of settings (solver, grid
resolution, wavelengths, realizations, precision) against a reference computed once; errors, wall times, the
Pareto front and the cheapest setting meeting ``--target-error`` (logic in :mod:`waveoptics.study.accuracy_cost`).
"""
from __future__ import annotations

from ..errors import WaveopticsError
from ..io.files import prepare_outdir
from ..units import parse_direction, parse_number_list
from ..vocabulary import COST_BUDGET_S, COST_DELTA_E, COST_TARGET_ERROR, DEFAULT_MATERIAL
from ._common import add_common, add_output, add_surface, emit, load_surface, parse_budget, progress
from ._options import option, renamed


def _list(text, conv, name):

    try:
        vals = [conv(t.strip()) for t in str(text).split(",") if t.strip()]
    except ValueError:
        raise WaveopticsError(f"{name} {text!r} is not allowed; give a comma-separated list") from None
    if not vals:
        raise WaveopticsError(f"{name} {text!r} is empty")
    return vals


def register(sub) -> None:
    p = sub.add_parser("cost", help="accuracy-cost study: error vs time over solver/grid/wavelength settings",
                       description="Run the same Kirchhoff configuration at a ladder of settings against a "
                                   "high-accuracy reference (direct solver, float64, finest grid, dense spectrum) "
                                   "and report for each the relative L2 error of the lobe, the albedo error, the "
                                   "ΔE2000 of the albedo colour and the wall time; mark the Pareto front and "
                                   "recommend the fastest setting meeting --target-error.")
    src = p.add_mutually_exclusive_group()
    add_surface(p, group=src)
    option(p, "--generator", group=src, default="gaussian:sigma=20nm,corr_length=1um", metavar="MODEL:k=v,...",
           note="and its parameters, e.g. sinusoid:amplitude=40nm,period=1.6um")
    renamed(p, "cost", "--model", dest="generator")
    option(p, "--size", default="12.8um")
    option(p, "--samples", default="128")
    option(p, "--seed", default=0, note="of the first realization")
    option(p, "--material", default=DEFAULT_MATERIAL, note="or 'one' for F = 1")
    option(p, "--incident", default="30,0")
    option(p, "--illuminant", default="D65")
    p.add_argument("--solvers", default="fft0,fft,direct", help="solvers of the ladder (default fft0,fft,direct)")
    p.add_argument("--resolutions", default="32,64,128",
                   help="direction-grid resolutions; each must divide the largest (default 32,64,128)")
    option(p, "--delta-e", default=list(COST_DELTA_E), nargs="+",
           note="one rung of the ladder per value, e.g. --delta-e 4 1 0.5 (default 4 1 0.5)")
    # the old flag took a comma list (4,1,0.5); the new one takes values apart (--delta-e 4 1 0.5)
    renamed(p, "cost", "--colour-accuracy", dest="delta_e", type=lambda s: parse_number_list(s, name="delta_e"))
    p.add_argument("--realization-counts", default=None, metavar="N,...",
                   help="numbers of surface realizations averaged, one ladder step each (default 1,2 for random "
                        "models, 1 otherwise)")
    renamed(p, "cost", "--realizations", dest="realization_counts")
    p.add_argument("--precisions", default="float32,float64", help="direct solver precisions")
    option(p, "--budget", default=f"{COST_BUDGET_S:g}",
           note="of the ladder after the reference; settings predicted to overrun are skipped and listed")
    p.add_argument("--target-error", type=float, default=COST_TARGET_ERROR, metavar="E",
                   help=f"recommend the fastest setting whose --metric is <= E (default {COST_TARGET_ERROR:g})")
    p.add_argument("--reference", choices=("fft", "direct"), default="fft",
                   help="solver of the reference (float64, finest grid, denser spectrum): fft (default; exact "
                        "Kirchhoff to 1e-8) or direct (the independent direct sum, about 20x slower on a CPU)")
    p.add_argument("--metric", default="error_rel_l2", choices=("error_rel_l2", "error_albedo", "delta_e2000"),
                   help="error used for the Pareto front and the recommendation (default error_rel_l2)")
    add_output(p, required=False, note="a directory: cost.json, cost.png (error vs time), cost.md")
    add_common(p)
    p.set_defaults(func=run)


def run(args) -> int:

    from ..study import accuracy_cost as cost
    from ..materials import fresnel_function
    from ..runtime import get_runtime

    theta, phi = parse_direction(args.incident, name="--incident")
    mat = args.material

    fresnel_function(mat)                                   # refuse a bad material before computing
    if args.surface:
        hf = load_surface(args)
        cfg = cost.Config(hf, mat, (theta, phi), args.illuminant, False, args.seed, str(args.surface))
    else:
        cfg = cost.model_config(args.generator, args.size, int(_list(args.samples, int, "--samples")[0]), material=mat,
                                incident=(theta, phi), illuminant=args.illuminant, seed=args.seed)
    reals = (_list(args.realization_counts, int, "--realization-counts") if args.realization_counts
             else ([1, 2] if cfg.random else [1]))
    settings = cost.ladder(_list(args.solvers, str, "--solvers"), _list(args.resolutions, int, "--resolutions"),
                           [float(x) for x in args.delta_e], reals,
                           _list(args.precisions, str, "--precisions"))
    out = prepare_outdir(args.output, overwrite=args.overwrite, expected=cost.FILES) if args.output else None
    rt = get_runtime(args.device)          # the direct rungs (and a direct reference) run on it
    bar = progress(total=len(settings) + 1, desc="cost", args=args)
    res = cost.study(cfg, settings, budget_s=parse_budget(args.budget), target_error=args.target_error,
                     metric=args.metric, reference_solver=args.reference, runtime=rt, progress=bar.update)
    bar.close()
    if out is not None:
        paths = cost.write(res, out, overwrite=args.overwrite)
        res["outputs"] = {k: str(v) for k, v in paths.items()}
    ref = res["reference"]
    rec = res["recommendation"]
    text = (f"reference: {ref['solver']} {ref['precision']} {ref['resolution']}² {ref['wavelengths']} wavelengths "
            f"x{ref['realizations']} ({ref['time_s']:.3g} s)\n{cost.table(res)}\n"
            f"Pareto front ({res['metric']}): {res['pareto']}"
            + (f"\nrecommended ({rec['reason']}): {rec.get('in_words', rec.get('setting', '-'))}"
               + (f", {rec['time_s']:.3g} s" if "time_s" in rec else "") if rec else ""))
    emit(args, res, text)
    return 0
