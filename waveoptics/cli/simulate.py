"""``waveoptics simulate``: the main job (two-scale BRDF vs microfacet, spectral → RGB, pictures)."""
from __future__ import annotations

import os

from ..errors import FieldError
from ..io.files import prepare_outdir
from ..request import SimulationRequest, request_default
from ..vocabulary import DIFFRACTION, NANO_SOLVERS, PARAMETRIC_NDF_NAMES, POLARIZATIONS, PRECISIONS
from ..units import parse_direction, parse_wavelengths
from ._common import (add_common, add_output, add_surface, emit, load_surface, not_asked, progress,
                      spheres_skipped_text, warn_if_long)
from ._options import option, renamed


def add_scene_options(p) -> None:
    """Options that describe the surface, light and sampling (shared by simulate and compare); their defaults are
    the fields of :class:`~waveoptics.request.SimulationRequest` (:func:`~waveoptics.request.request_default`)."""
    d = request_default
    src = p.add_mutually_exclusive_group()
    add_surface(p, group=src, note="the nano height field (fft or direct solver)")
    option(p, "--nano", group=src, note=f"default {d('nano')}; sigma=0 disables it; also "
                                         "exponential:sigma=5nm,corr_length=1um, scratches:count=20,width=200nm,depth=30nm")
    # micro α, NDF and shape stay None when not given (--micro-surface refuses them), the request fills them in
    option(p, "--micro-alpha", note=f"default {d('micro_alpha'):g}")
    option(p, "--alpha-y", note="ggx, beckmann, epd and sgd; default: isotropic")
    option(p, "--ndf", choices=PARAMETRIC_NDF_NAMES, note=f"default {d('ndf')}")
    option(p, "--ndf-shape")
    option(p, "--micro-surface", note="its own file metadata gives the spacing")
    option(p, "--multiple-scattering", action="store_true", default=d("multiple_scattering"),
           note="added to both models")
    option(p, "--material", default=d("material"))
    option(p, "--incident", default=format_direction(d("incident_deg")))
    option(p, "--illuminant", default=d("illuminant"))
    option(p, "--wavelengths", note="default: chosen from the illuminant and --delta-e")
    option(p, "--delta-e", default=d("delta_e"))
    option(p, "--resolution", default=d("resolution"))
    option(p, "--solver", default=d("solver"), choices=NANO_SOLVERS,
           note="psd (statistics), fft or direct (height field); auto picks")
    option(p, "--kd", default=d("kd"), note="of a dielectric; metals have none")
    option(p, "--precision", default=d("precision"), choices=PRECISIONS)
    option(p, "--seed", default=d("seed"))
    option(p, "--diffraction", default=d("diffraction"), choices=DIFFRACTION)
    option(p, "--polarization", default=d("polarization"), choices=POLARIZATIONS,
           note="each facet reflects its own s/p split")
    option(p, "--roughness-correlation", default=d("roughness_correlation"),
           note="of a --material stack's interfaces when --diffraction is rayleigh-rice")
    p.add_argument("--split", action="store_true", default=d("split"),
                   help="--surface holds both scales: split it at a cut-off period of 10 λmax; the micro α comes "
                        "from the long-period slopes, the short-period part diffracts")


def format_direction(theta_phi) -> str:
    """``θ`` or ``θ,φ`` (degrees) as --incident takes it."""
    theta, phi = theta_phi
    return f"{theta:g}" if phi == 0 else f"{theta:g},{phi:g}"


def request_from_args(args):
    """The :class:`~waveoptics.request.SimulationRequest` the scene options describe (its fields validate them;
    options left unset take the fields' defaults)."""
    if args.micro_surface is not None:
        given = [f for f, v in (("--micro-alpha", args.micro_alpha), ("--alpha-y", args.alpha_y), ("--ndf", args.ndf),
                                ("--ndf-shape", args.ndf_shape)) if v is not None]
        if given:
            raise FieldError(f"--micro-surface sets the NDF from the file's slopes; drop {', '.join(given)}",
                             "micro_surface")
    optional = {"nano": args.nano, "micro_alpha": args.micro_alpha, "alpha_y": args.alpha_y, "ndf": args.ndf,
                "ndf_shape": args.ndf_shape}
    return SimulationRequest(
        surface=args.surface, material=args.material, micro_surface=args.micro_surface,
        multiple_scattering=args.multiple_scattering, incident_deg=parse_direction(args.incident),
        illuminant=args.illuminant,
        wavelengths_nm=None if args.wavelengths is None else tuple(parse_wavelengths(args.wavelengths)),
        delta_e=args.delta_e, resolution=args.resolution, solver=args.solver, kd=args.kd,
        precision=args.precision, seed=args.seed, split=args.split, diffraction=args.diffraction,
        polarization=args.polarization, roughness_correlation=args.roughness_correlation,
        **{k: v for k, v in optional.items() if v is not None})


def _surface(args):
    """The --surface height field read with its metadata options (None without --surface)."""
    return load_surface(args, required=False)


def simulation_from_args(args, bar=None, req=None):
    """Run :func:`waveoptics.simulate.run` on the request of the scene options (or *req*, built from them), after
    a warning when the cost model expects it to be long."""
    from .. import simulate as sim_mod

    req = req if req is not None else request_from_args(args)
    surface = _surface(args)
    _announce_if_long(req, surface)
    return sim_mod.run(req, device=args.device, progress=None if bar is None else bar.update, surface=surface,
                       max_memory=getattr(args, "max_memory", None))


def _announce_if_long(req, surface) -> None:
    from ..planning.estimate import simulation_time

    warn_if_long(simulation_time(req, surface=surface), "lower --resolution or the number of --wavelengths (or "
                                                        "the nano roughness's height)")


def register(sub):
    p = sub.add_parser(
        "simulate", help="simulate a two-scale (micro + nano) surface and compare with the microfacet model",
        description="Two-scale BRDF: microfacet NDF for the micro-roughness, Kirchhoff diffraction for the "
                    "nano-roughness, integrated over the spectrum to RGB; writes spectral and RGB EXRs, PNG "
                    "previews, sphere renders of both models and their ΔE2000, lobe cross-sections and "
                    "summary.json. With no options it runs a nano-rough aluminium under D65.")
    add_scene_options(p)
    renamed(p, "simulate", "--accuracy", dest="delta_e")
    option(p, "--sphere-size", default=256)
    option(p, "--no-spheres", action="store_true", default=False)
    option(p, "--environment", note="also render both spheres lit by it (multiple importance sampling at "
                                    "--sphere-size; sphere_env_*.exr and sphere_env.png)")
    option(p, "--max-memory")
    option(p, "--spp", default=16, note="and technique, of the environment render")
    p.add_argument("--colourspace", default="sRGB", choices=["sRGB", "ACEScg", "Display P3"],
                   help="linear RGB space of brdf_rgb.exr and the RGB albedos (default sRGB; PNGs are sRGB)")
    add_output(p)
    add_common(p)
    p.set_defaults(func=run)


def run(args):
    from .. import simulate as sim_mod
    from ..renderers.sphere import SKIPPED_KEY

    if not (16 <= args.sphere_size <= 4096):
        raise FieldError(f"{{sphere_size}} {args.sphere_size} is not allowed; use 16..4096 pixels (--no-spheres "
                         "skips the sphere renders)", "sphere_size")
    if not (1 <= args.spp <= 4096):
        raise FieldError(f"{{spp}} {args.spp} is not allowed; use 1..4096 samples", "spp")
    if args.no_spheres and args.environment is not None:
        raise FieldError("--environment renders spheres; drop --environment or --no-spheres", "environment")
    env = None
    if args.environment is not None:
        from ..renderers import lighting
        env = lighting.environment(args.environment)   # a bad map fails here, before any computing
    req = request_from_args(args)
    spheres = not args.no_spheres
    sim_mod.check_request_memory(req, sphere=spheres, max_memory=args.max_memory)   # before anything is created
    surface = _surface(args)
    _announce_if_long(req, surface)   # before the output directory (a refusal creates nothing) and the progress bar
    prepare_outdir(args.output, overwrite=args.overwrite,
                   expected=sim_mod.output_files(env is not None, req.diffraction == "rayleigh-rice", spheres))
    bar = progress(total=sim_mod.sphere_steps(req, spheres), desc="simulate", args=args)
    try:
        sim = sim_mod.run(req, device=args.device, progress=bar.update, max_memory=args.max_memory,
                          surface=surface, sphere=spheres)
    finally:
        bar.close()
    summary = sim_mod.write_outputs(sim, args.output, overwrite=args.overwrite, sphere_size=args.sphere_size,
                                    space=args.colourspace, environment=env, spp=args.spp,
                                    env_size=args.sphere_size, no_sphere_reason=not_asked("--no-spheres"))
    d = summary["delta_e2000"]
    spheres_text = (f"sphere ΔE2000 mean {d['mean']:.2f} max {d['max']:.2f}" if d is not None
                    else spheres_skipped_text(summary["skipped"][SKIPPED_KEY]))
    theta = sim.params["incident_deg"][0]
    text = (f"{sim.params['material']} θi={theta:g}°: albedo {summary['rgb_albedo'].round(3).tolist()} (two-scale) vs "
            f"{summary['microfacet_rgb_albedo'].round(3).tolist()} (microfacet), {spheres_text}, "
            f"solver {summary['solver']}, {sum(summary['timings_s'].values()):.1f} s\n"
            f"outputs in {os.path.join(os.path.normpath(args.output), '')}: " + ", ".join(summary["files"]))
    emit(args, summary, text)
    return 0
