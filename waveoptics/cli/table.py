"""``waveoptics table``: a spectral BRDF table over incident angles and wavelengths, computed on Dask.

Also holds the options shared with ``waveoptics sweep`` (the two-scale case and where to run it).
"""
from __future__ import annotations

from pathlib import Path


from ..errors import WaveopticsError
from ..units import parse_number_list, parse_wavelengths
from ..vocabulary import DIFFRACTION, NANO_SOLVERS, PRECISIONS
from ._common import add_common, emit, progress

SCENE_SUFFIXES = (".toml",)


def add_case_options(p, *, resolution: int) -> None:
    """Options describing one two-scale case (material, nano/micro roughness, spectrum, grid, solver).

    With a scene file they override the scene's values; their defaults are None so that "not given" is visible.
    """
    p.add_argument("--nano", metavar="MODEL:PARAMS",
                   help="nano roughness instead of a SURFACE file, e.g. abc:sigma=10nm,B=2um,C=2.6 (the default) "
                        "| gaussian:sigma=5nm,T=1um | sinusoid:amplitude=40nm,period=2um")
    p.add_argument("--material", default=None, metavar="M",
                   help="material name, shelf/book/page, n+kj or f0:... (default Al); with a scene file: the name "
                        "of one of its materials (default the first)")
    p.add_argument("--light", default=None, metavar="NAME",
                   help="with a scene file: the name of one of its lights (default the first)")
    p.add_argument("--micro-alpha", type=float, default=None, metavar="A",
                   help="micro NDF roughness α (default 0 with a SURFACE file, whose heights are the whole "
                        "geometry; 0.05 with --nano)")
    p.add_argument("--ndf", default=None, choices=["ggx", "beckmann"], help="micro NDF (default beckmann)")
    p.add_argument("--wavelengths", metavar="NM", help="wavelengths in nm (400:700:10 or 450,550,650); default: "
                                                       "chosen from the illuminant and --accuracy")
    p.add_argument("--illuminant", default=None, help="light for RGB and the default wavelengths: D65 (default), A, "
                                                      "F2, blackbody:3000K, laser:532, FILE.csv")
    p.add_argument("--accuracy", type=float, default=None, metavar="DE",
                   help="colour accuracy (ΔE2000) that picks the wavelength step (default 1.0)")
    p.add_argument("--resolution", type=int, default=None, metavar="N",
                   help=f"direction grid N×N over the projected hemisphere (default {resolution})")
    p.set_defaults(default_resolution=resolution)
    p.add_argument("--solver", default="auto", choices=NANO_SOLVERS,
                   help="nano lobe: psd (statistics), fft or direct (height field); auto picks (default)")
    p.add_argument("--diffraction", default="kirchhoff", choices=DIFFRACTION,
                   help="diffraction model of the nano lobe (default kirchhoff; docs/physics.md §10)")
    p.add_argument("--kd", type=float, default=None, help="diffuse albedo of a dielectric (default 0.5; metals: none)")
    p.add_argument("--precision", default="float32", choices=PRECISIONS,
                   help="OpenCL precision of the height-field solvers (default float32)")
    p.add_argument("--seed", type=int, default=None, help="seed of generated nano surfaces (default 0)")


def add_cluster_options(p) -> None:
    """Where to run (embedded, local processes, existing scheduler) and the resume/overwrite rules."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, metavar="N",
                   help="start a local Dask cluster of N single-threaded worker processes on 127.0.0.1 "
                        "(default: run in-process)")
    g.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="use an existing Dask scheduler")
    p.add_argument("--resume", action="store_true",
                   help="continue OUT.partial left by an interrupted run (computes only the missing tasks)")
    p.add_argument("--overwrite", action="store_true", help="replace OUT and discard OUT.partial if they exist")


def _is_scene(source) -> bool:
    return source is not None and Path(source).suffix.lower() in SCENE_SUFFIXES


def case_from_args(args, *, source=None):
    """(:class:`~waveoptics.request.SimulationRequest`, HeightField or None) from the options, a SURFACE or a scene
    file. Options left unset take the request's defaults (or the scene's values)."""
    from .. import distributed
    from ..planning import scene
    from ..request import DEFAULT_NANO
    from ..request import SimulationRequest

    given = dict(wavelengths_nm=tuple(parse_wavelengths(args.wavelengths)) if args.wavelengths else None,
                 micro_alpha=args.micro_alpha, ndf=args.ndf, illuminant=args.illuminant, accuracy_dE=args.accuracy,
                 resolution=args.resolution, solver=args.solver, kd=args.kd, precision=args.precision,
                 diffraction=args.diffraction,
                 seed=args.seed, incident_deg=getattr(args, "incident_deg", None))
    if _is_scene(source):
        if args.nano:
            raise WaveopticsError("--nano cannot be used with a scene file: the scene's material defines its nano "
                                  "roughness")
        sc = scene.load(source)
        if given["resolution"] is None and sc.output.resolution is None:
            given["resolution"] = args.default_resolution
        return distributed.case_from_scene(sc, material=args.material, light=args.light, **given)
    if args.light:
        raise WaveopticsError("--light names a light of a scene file; without one use --illuminant and --incident")
    if source is not None and args.nano:
        raise WaveopticsError("give either a SURFACE file or --nano MODEL:params, not both")
    if source is not None and not Path(source).is_file():
        raise WaveopticsError(f"surface file {source!r} does not exist")
    kw = {k: v for k, v in given.items() if v is not None}
    kw.setdefault("resolution", args.default_resolution)
    if source is not None:
        kw.setdefault("micro_alpha", 0.0)  # a height field carries its own slopes
    if args.material:
        kw["material"] = args.material
    case = SimulationRequest(nano=None if source else (args.nano or DEFAULT_NANO),
                             surface=str(source) if source else None, **kw)
    return case, None


def register(sub):
    p = sub.add_parser(
        "table", help="spectral BRDF table over incident angles × wavelengths (HDF5), on Dask",
        description="Compute the two-scale BRDF for every incident angle and wavelength on the hemisphere's "
                    "direction-cosine grid and write one HDF5 file with coordinates (theta_i, wavelength, v, u), "
                    "the spectral table, the plain microfacet table, albedos, linear sRGB and the parameters as "
                    "attributes (layout: docs/scaling.md). Tasks (incident angle × wavelength batch) run "
                    "in-process by default, on N local worker processes with --workers N, or on a cluster with "
                    "--scheduler; finished tasks are kept in OUT.partial so --resume continues a run.")
    p.add_argument("source", nargs="?", metavar="SURFACE|SCENE",
                   help="nano height-field file (.npz/.npy/.exr/.txt; fft/direct solver) or a scene file (.toml)")
    p.add_argument("--incident-angles", default="0:85:5", metavar="DEG",
                   help="incident zenith angles in degrees, START:STOP:STEP or A,B,C (default 0:85:5)")
    p.add_argument("--phi", type=float, default=0.0, metavar="DEG", help="incident azimuth in degrees (default 0)")
    p.add_argument("--realizations", type=int, default=1, metavar="N",
                   help="average N surface realizations: tiles of the SURFACE file, or seeds of a generated "
                        "--nano surface with --solver fft/direct (default 1)")
    p.add_argument("--batch", type=int, default=None, metavar="B",
                   help="wavelengths per task (default 8)")
    add_case_options(p, resolution=128)
    p.add_argument("-o", "--output", required=True, metavar="OUT.h5", help="output HDF5 file")
    add_cluster_options(p)
    add_common(p)
    p.set_defaults(func=run)


def run(args):


    from .. import distributed
    import numpy as np

    case, surface = case_from_args(args, source=args.source)
    thetas = parse_number_list(args.incident_angles, name="--incident-angles")
    spec = distributed.TableSpec(case, thetas_deg=tuple(thetas), phi_deg=args.phi, realizations=args.realizations,
                                 batch=args.batch if args.batch is not None else distributed.DEFAULT_BATCH)
    plan = distributed.table_plan(spec, args.output, resume=args.resume)
    bar = progress(total=plan["todo"], desc="table", args=args)
    try:
        res = distributed.run_table(spec, args.output, surface=surface, workers=args.workers, scheduler=args.scheduler,
                                    resume=args.resume, overwrite=args.overwrite, device=args.device,
                                    progress=bar.update)
    finally:
        bar.close()
    n = res["computed"]
    out = {k: v for k, v in res.items() if k not in ("written", "task_costs_s", "task_cpu_s")}
    out.update(incident_angles_deg=list(spec.thetas_deg), wavelengths=plan["wavelengths"],
               resolution=case.resolution, task_cost_mean_s=res["task_cost_s"] / n if n else None,
               task_cpu_median_s=float(np.median(res["task_cpu_s"])) if n else None)
    text = (f"table {res['output']}: {len(spec.thetas_deg)} incident angles × {plan['wavelengths']} wavelengths × "
            f"{case.resolution}² directions"
            + (f" × {spec.realizations} realizations" if spec.realizations > 1 else "")
            + f"; {res['tasks']} tasks ({n} computed, {res['skipped']} already done) in {res['wall_s']:.1f} s"
            + (f", {out['task_cost_mean_s']:.2f} s per task" if n else ""))
    emit(args, out, text)
    return 0
