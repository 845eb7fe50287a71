"""``waveoptics table``: a spectral BRDF table over incident angles and wavelengths, computed on Dask.

Also holds the options shared with ``waveoptics sweep`` (the two-scale case and where to run it).
"""
from __future__ import annotations

from pathlib import Path


from ..errors import WaveopticsError
from ..request import request_default
from ..units import ANGLE_UNITS, parse_number_list, parse_wavelengths
from ..vocabulary import DIFFRACTION, NANO_FRAMES, NANO_SOLVERS, PARAMETRIC_NDF_NAMES, PRECISIONS
from ._common import SURFACE_FORMATS_HELP, add_common, add_workers, emit, progress
from ._options import option, renamed

SCENE_SUFFIXES = (".toml",)


def add_case_options(p, *, command: str, resolution: int) -> None:
    """Options describing one two-scale case (material, nano/micro roughness, spectrum, grid, solver).

    With a scene file they override the scene's values; their defaults are None so that "not given" is visible, and
    the help states the :class:`~waveoptics.request.SimulationRequest` field's default
    (:func:`~waveoptics.request.request_default`).
    """
    d = request_default
    option(p, "--nano", note=f"instead of a SURFACE file (default {d('nano')})")
    for flag in ("--spacing", "--units", "--channel"):
        option(p, flag)
    option(p, "--material", note=f"default {d('material')}; with a scene file: the name of one of its materials "
                                 "(default the first)")
    p.add_argument("--light", default=None, metavar="NAME",
                   help="with a scene file: the name of one of its lights (default the first)")
    option(p, "--micro-alpha", note="default 0 with a SURFACE file, whose heights are the whole geometry; "
                                    f"{d('micro_alpha'):g} with --nano")
    option(p, "--alpha-y", note="ggx, beckmann, epd and sgd; default: isotropic (with a scene file: the material's)")
    option(p, "--ndf", choices=PARAMETRIC_NDF_NAMES, note=f"default {d('ndf')}")
    option(p, "--ndf-shape")
    option(p, "--wavelengths", note="default: chosen from the illuminant and --delta-e")
    option(p, "--illuminant", note=f"for RGB and the default wavelengths (default {d('illuminant')})")
    option(p, "--delta-e", note=f"default {d('delta_e')}")
    renamed(p, command, "--accuracy", dest="delta_e")
    option(p, "--resolution", note=f"default {resolution}")
    p.set_defaults(default_resolution=resolution)
    option(p, "--solver", default=d("solver"), choices=NANO_SOLVERS,
           note="psd (statistics), fft or direct (height field); auto picks")
    option(p, "--diffraction", default=d("diffraction"), choices=DIFFRACTION)
    option(p, "--kd", note=f"of a dielectric; metals have none (default {d('kd')})")
    option(p, "--precision", default=d("precision"), choices=PRECISIONS)
    option(p, "--seed", note=f"default {d('seed')}")


def add_cluster_options(p) -> None:
    """Where to run (embedded, local processes, existing scheduler) and the resume/overwrite rules."""
    add_workers(p)
    p.add_argument("--resume", action="store_true",
                   help="continue OUT.partial left by an interrupted run (computes only the missing tasks)")
    option(p, "--overwrite", action="store_true", note="and discard OUT.partial")


def _is_scene(source) -> bool:
    return source is not None and Path(source).suffix.lower() in SCENE_SUFFIXES


def case_from_args(args, *, source=None):
    """(:class:`~waveoptics.request.SimulationRequest`, HeightField or None) from the options, a SURFACE or a scene
    file. Options left unset take the request's defaults (or the scene's values)."""
    from .. import distributed
    from ..planning import scene
    from ..request import SimulationRequest

    given = dict(wavelengths_nm=tuple(parse_wavelengths(args.wavelengths)) if args.wavelengths else None,
                 micro_alpha=args.micro_alpha, alpha_y=args.alpha_y, ndf=args.ndf, ndf_shape=args.ndf_shape,
                 illuminant=args.illuminant, delta_e=args.delta_e,
                 resolution=args.resolution, solver=args.solver, kd=args.kd, precision=args.precision,
                 diffraction=args.diffraction,
                 seed=args.seed, incident_deg=getattr(args, "incident_deg", None))
    meta_opts = [f for f in ("spacing", "units", "channel") if getattr(args, f, None) is not None]
    if _is_scene(source):
        if meta_opts:
            raise WaveopticsError(f"--{meta_opts[0]} describes a SURFACE file; a scene file states its surface's "
                                  "spacing and units in its file = {...} table")
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
    if source is None and args.nano:
        kw["nano"] = args.nano
    case = SimulationRequest(**({"nano": None, "surface": str(source)} if source else {}), **kw)
    if source is None and meta_opts:
        raise WaveopticsError(f"--{meta_opts[0]} describes a SURFACE file; give one")
    hf = None
    if source is not None and meta_opts:   # the file needs its metadata completed: read it here, once
        from .. import surfaces

        hf = surfaces.load(source, spacing=args.spacing, units=args.units, channel=args.channel)
    return case, hf


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
                   help=f"nano height-field file ({SURFACE_FORMATS_HELP}; fft/direct solver) or a scene file (.toml)")
    option(p, "--incident-angles", default="0:85:5")
    p.add_argument("--phi", type=float, default=0.0, metavar="DEG", help="incident azimuth in degrees (default 0)")
    option(p, "--realizations", default=1, note="seeds of a generated --nano surface need --solver fft/direct")
    p.add_argument("--batch", type=int, default=None, metavar="B",
                   help="wavelengths per task (default 8)")
    p.add_argument("--transmission", action="store_true",
                   help="tabulate the rough glass's BSDF over the sphere instead (a transparent --material, --nano "
                        "statistics): reflection and transmission, light from the air and from inside, cell "
                        "averages on direction-cosine grids, incidence nodes added where the read between them "
                        "would miss more than 0.5%% of the light (layout: docs/scaling.md)")
    p.add_argument("--exact-angles", action="store_true",
                   help="with --transmission: tabulate exactly --incident-angles (no nodes added)")
    option(p, "--nano-frame", choices=NANO_FRAMES, default="macro", note="with --transmission (default macro)")
    option(p, "--multiple-scattering", action="store_true", default=False,
           note="with --transmission: the rough dielectric's compensation lobes")
    add_case_options(p, command="table", resolution=128)
    option(p, "--output", short="-o", required=True, metavar="OUT.h5", note="an HDF5 file")
    option(p, "--max-memory", note="of one task")
    add_cluster_options(p)
    add_common(p)
    p.set_defaults(func=run)


def _glass_options(args) -> dict:
    """The TableSpec fields of --transmission; its companions refused without it (one line naming them)."""
    if not args.transmission:
        for flag, given in (("--exact-angles", args.exact_angles), ("--nano-frame", args.nano_frame != "macro"),
                            ("--multiple-scattering", args.multiple_scattering)):
            if given:
                raise WaveopticsError(f"{flag} applies to a glass table; add --transmission")
        return {}
    return {"transmission": True, "nano_frame": args.nano_frame, "refine": not args.exact_angles}


def run(args):
    import dataclasses

    from .. import distributed
    import numpy as np

    case, surface = case_from_args(args, source=args.source)
    thetas = parse_number_list(args.incident_angles, name="thetas_deg", units=ANGLE_UNITS)
    glass = _glass_options(args)
    if args.multiple_scattering:   # a glass table's (refused without --transmission above)
        case = dataclasses.replace(case, multiple_scattering=True)
    spec = distributed.TableSpec(case, thetas_deg=tuple(thetas), phi_deg=args.phi, realizations=args.realizations,
                                 batch=args.batch if args.batch is not None else distributed.DEFAULT_BATCH, **glass)
    if spec.transmission and spec.refine:   # the nodes come before the tasks: say so on a terminal
        bar = progress(desc="incidence nodes (intervals tested)", args=args)
        try:
            distributed.glass_nodes(spec, progress=bar.update)
        finally:
            bar.close()
    plan = distributed.table_plan(spec, args.output, resume=args.resume)
    bar = progress(total=plan["todo"], desc="table", args=args)
    try:
        res = distributed.run_table(spec, args.output, surface=surface, workers=args.workers, scheduler=args.scheduler,
                                    resume=args.resume, overwrite=args.overwrite, device=args.device,
                                    progress=bar.update, max_memory=args.max_memory)
    finally:
        bar.close()
    n = res["computed"]
    out = {k: v for k, v in res.items() if k not in ("written", "task_costs_s", "task_cpu_s")}
    out.update(incident_angles_deg=list(spec.thetas_deg), wavelengths=plan["wavelengths"],
               resolution=case.resolution, task_cost_mean_s=res["task_cost_s"] / n if n else None,
               task_cpu_median_s=float(np.median(res["task_cpu_s"])) if n else None)
    if spec.transmission:
        out["incident_angles_deg"] = list(distributed.glass_nodes(spec))
    out["units"] = {"wall_s": "s", "task_cost_s": "s", "timings_s": "s", "incident_angles_deg": "deg",
                    "task_cost_mean_s": "s", "task_cpu_median_s": "s", "resolution": "cells per axis"}
    text = (f"table {res['output']}: {len(out['incident_angles_deg'])} incident angles"
            + (" × 2 sides × 2 hemispheres" if spec.transmission else "")
            + f" × {plan['wavelengths']} wavelengths × {case.resolution}² directions"
            + (f" × {spec.realizations} realizations" if spec.realizations > 1 else "")
            + f"; {res['tasks']} tasks ({n} computed, {res['skipped']} already done) in {res['wall_s']:.1f} s"
            + (f", {out['task_cost_mean_s']:.2f} s per task" if n else ""))
    emit(args, out, text)
    return 0
