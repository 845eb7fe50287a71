"""``waveoptics simulate``: the main job (two-scale BRDF vs microfacet, spectral → RGB, pictures)."""
from __future__ import annotations

import os

from ..errors import FieldError
from ..io.files import prepare_outdir
from ..vocabulary import DIFFRACTION, NANO_SOLVERS, POLARIZATIONS, PRECISIONS
from ..units import parse_direction, parse_wavelengths
from ._common import SURFACE_FORMATS_HELP, add_common, add_output, add_surface, emit, load_surface, progress


def add_scene_options(p) -> None:
    """Options that describe the surface, light and sampling (shared by simulate and compare)."""
    src = p.add_mutually_exclusive_group()
    add_surface(p, group=src, help=f"nano height field (fft or direct solver): {SURFACE_FORMATS_HELP}")
    src.add_argument("--nano", metavar="MODEL:PARAMS", default=None,
                     help="nano roughness, e.g. abc:sigma=10nm,B=2um,C=2.6 | gaussian:sigma=5nm,T=1um | "
                          "exponential:sigma=5nm,T=1um | sinusoid:amplitude=40nm,period=2um | "
                          "scratches:count=20,width=200nm,depth=30nm (default abc:sigma=10nm,B=2um,C=2.6; "
                          "sigma=0 disables it)")
    p.add_argument("--micro-alpha", type=float, default=0.05, metavar="A",
                   help="micro NDF roughness α (default 0.05)")
    p.add_argument("--ndf", default="beckmann", choices=["ggx", "beckmann"], help="micro NDF (default beckmann)")
    p.add_argument("--material", default="Al", metavar="M", help="material name, shelf/book/page, n+kj or f0:... "
                                                                   "(default Al)")
    p.add_argument("--incident", default="30", metavar="THETA[,PHI]", help="light direction in degrees (default 30)")
    p.add_argument("--illuminant", default="D65", help="light source: D65, A, F2, blackbody:3000K, laser:532, "
                                                       "rgb-laser, FILE.csv (default D65)")
    p.add_argument("--wavelengths", metavar="NM", help="wavelengths in nm (400:700:10 or 450,550,650); "
                                                       "default: chosen from the illuminant and --accuracy")
    p.add_argument("--accuracy", type=float, default=1.0, metavar="DE",
                   help="colour accuracy (ΔE2000) that picks the wavelength step (default 1.0)")
    p.add_argument("--resolution", type=int, default=128, metavar="N", help="direction grid N×N (default 128)")
    p.add_argument("--solver", default="auto", choices=NANO_SOLVERS,
                   help="nano lobe: psd (statistics), fft or direct (height field); auto picks (default)")
    p.add_argument("--kd", type=float, default=0.5, help="diffuse albedo of a dielectric (metals: none)")
    p.add_argument("--precision", default="float32", choices=PRECISIONS,
                   help="OpenCL precision for height-field solvers (default float32)")
    p.add_argument("--seed", type=int, default=0, help="seed of generated nano surfaces (default 0)")
    p.add_argument("--diffraction", default="kirchhoff", choices=DIFFRACTION,
                   help="diffraction model of the nano lobe: kirchhoff (default), ghs, rghs, ohs, rohs "
                        "(docs/physics.md §10)")
    p.add_argument("--polarization", default="unpolarized", choices=POLARIZATIONS,
                   help="polarization of the incident light relative to the plane of incidence; each facet "
                        "reflects its own s/p split (default unpolarized)")
    p.add_argument("--split", action="store_true",
                   help="--surface holds both scales: split it at a cut-off period of 10 λmax; the micro α comes "
                        "from the long-period slopes, the short-period part diffracts")


def request_from_args(args):
    """The :class:`~waveoptics.request.SimulationRequest` the scene options describe (its fields validate them)."""
    from ..request import DEFAULT_NANO
    from ..request import SimulationRequest

    return SimulationRequest(
        material=args.material, nano=args.nano or DEFAULT_NANO, surface=args.surface, micro_alpha=args.micro_alpha,
        ndf=args.ndf, incident_deg=parse_direction(args.incident), illuminant=args.illuminant,
        wavelengths_nm=None if args.wavelengths is None else tuple(parse_wavelengths(args.wavelengths)),
        accuracy_dE=args.accuracy, resolution=args.resolution, solver=args.solver, kd=args.kd,
        precision=args.precision, seed=args.seed, split=args.split, diffraction=args.diffraction,
        polarization=args.polarization)


def _surface(args):
    """The --surface height field read with its metadata options (None without --surface)."""
    return load_surface(args, required=False)


def simulation_from_args(args, bar=None):
    """Run :func:`waveoptics.simulate.run` on the request of the scene options."""
    from .. import simulate as sim_mod

    return sim_mod.run(request_from_args(args), device=args.device,
                       progress=None if bar is None else bar.update, surface=_surface(args))


def register(sub):
    p = sub.add_parser(
        "simulate", help="simulate a two-scale (micro + nano) surface and compare with the microfacet model",
        description="Two-scale BRDF: microfacet NDF for the micro-roughness, Kirchhoff diffraction for the "
                    "nano-roughness, integrated over the spectrum to RGB; writes spectral and RGB EXRs, PNG "
                    "previews, sphere renders of both models and their ΔE2000, lobe cross-sections and "
                    "summary.json. With no options it runs a nano-rough aluminium under D65.")
    add_scene_options(p)
    p.add_argument("--sphere-size", type=int, default=256, metavar="PX", help="sphere render size (default 256)")
    p.add_argument("--environment", metavar="MAP",
                   help="also render both spheres lit by an environment: sky, studio, constant or an equirectangular "
                        ".exr (+y up; multiple importance sampling at --sphere-size; sphere_env_*.exr and "
                        "sphere_env.png)")
    p.add_argument("--max-memory", metavar="SIZE",
                   help="memory budget of the run, e.g. 4GB (default: half the machine's memory, or "
                        "$WAVEOPTICS_MAX_MEMORY); a larger estimate is refused before any work")
    p.add_argument("--spp", type=int, default=16, metavar="N",
                   help="samples per pixel and technique of the environment render (default 16)")
    p.add_argument("--colourspace", default="sRGB", choices=["sRGB", "ACEScg", "Display P3"],
                   help="linear RGB space of brdf_rgb.exr and the RGB albedos (default sRGB; PNGs are sRGB)")
    add_output(p)
    add_common(p)
    p.set_defaults(func=run)


def run(args):
    from .. import simulate as sim_mod

    if not (16 <= args.sphere_size <= 4096):
        raise FieldError(f"{{sphere_size}} {args.sphere_size} is not allowed; use 16..4096 pixels", "sphere_size")
    if not (1 <= args.spp <= 4096):
        raise FieldError(f"{{spp}} {args.spp} is not allowed; use 1..4096 samples", "spp")
    env = None
    if args.environment is not None:
        from .. import lighting
        env = lighting.environment(args.environment)   # a bad map fails here, before any computing
    req = request_from_args(args)
    sim_mod.check_request_memory(req, max_memory=args.max_memory)   # before anything is created
    prepare_outdir(args.output, overwrite=args.overwrite, expected=sim_mod.output_files(env is not None))
    bar = progress(total=sim_mod.sphere_steps(req), desc="simulate", args=args)
    try:
        sim = sim_mod.run(req, device=args.device, progress=bar.update, max_memory=args.max_memory,
                          surface=_surface(args))
    finally:
        bar.close()
    summary = sim_mod.write_outputs(sim, args.output, overwrite=args.overwrite, sphere_size=args.sphere_size,
                                    space=args.colourspace, environment=env, spp=args.spp,
                                    env_size=args.sphere_size)
    d = summary["delta_e2000"]
    theta = sim.params["incident_deg"][0]
    text = (f"{sim.params['material']} θi={theta:g}°: albedo {summary['rgb_albedo'].round(3).tolist()} (two-scale) vs "
            f"{summary['microfacet_rgb_albedo'].round(3).tolist()} (microfacet), sphere ΔE2000 mean {d['mean']:.2f} "
            f"max {d['max']:.2f}, solver {summary['solver']}, {sum(summary['timings_s'].values()):.1f} s\n"
            f"outputs in {os.path.join(os.path.normpath(args.output), '')}: " + ", ".join(summary["files"]))
    emit(args, summary, text)
    return 0
