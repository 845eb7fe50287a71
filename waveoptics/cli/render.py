"""``waveoptics render -o OUTDIR``: the wave-optics BRDF and Mitsuba 3's own rough model on a sphere under an
environment map, rendered by Mitsuba 3, side by side with their ΔE2000 (:mod:`waveoptics.renderers.scene`)."""
from __future__ import annotations

from ..renderers.requests import GlintRequest, RendererModel, RenderRequest, field_default
from ._common import add_common, add_output, add_workers, emit, parse_budget, progress
from ._options import option
from ._renderer import add_model, model_fields


def _d(name, cls=RenderRequest):
    return field_default(cls, name)


#: most samples per pixel of --target-noise by default
MAX_SPP_DEFAULT = _d("max_spp")


def register(sub):
    from ..vocabulary import GLINT_SHAPES, NANO_FRAMES
    from ..vocabulary import RENDER_BSDF_AUTO, RENDER_MODELS
    from ..vocabulary import RENDER_BSDFS as WAVE_BSDFS

    p = sub.add_parser(
        "render", help="render a sphere with the wave-optics BRDF and with Mitsuba 3's own rough model",
        description="Mitsuba 3 renders a sphere (on a ground plane unless --no-ground) under an environment map "
                    "twice: (a) with the two-scale wave-optics BRDF (the Dr.Jit plugin, Mitsuba's 'measured' model "
                    "reading its RGL export, or the NumPy plugin), (b) with Mitsuba's roughconductor (metals) or roughplastic "
                    "(dielectrics) of the same micro roughness and index. Writes linear sRGB EXRs of both, their "
                    "CIEDE2000 map, a labelled PNG and summary.json. Needs the 'render' extra.")
    add_model(p)
    g = p.add_argument_group("render")
    g.add_argument("--model", choices=RENDER_MODELS, default=_d("model"),
                   help="BRDF model rendered: twoscale (the two-scale BRDF of the options above) or "
                        "rough-dielectric (the nano-rough glass: a rough dielectric with --material, --micro-alpha, "
                        "--alpha-y, --ndf, --nano, --nano-frame, --multiple-scattering and --wavelength-step, "
                        "reflecting and "
                        "transmitting, beside Mitsuba's roughdielectric; through the NumPy glass plugin) "
                        f"(default {_d('model')})")
    option(g, "--nano-frame", choices=NANO_FRAMES, default=_d("nano_frame"), note="--model rough-dielectric only")
    option(g, "--environment", default=_d("environment"), note="sky and studio are built by the code")
    g.add_argument("--no-ground", dest="ground", action="store_false", help="no ground plane under the sphere")
    g.add_argument("--variant", default=_d("variant"), metavar="NAME",
                   help="Mitsuba 3 variant, e.g. llvm_ad_spectral, llvm_ad_rgb, scalar_spectral (default "
                        f"{_d('variant')})")
    g.add_argument("--bsdf", choices=WAVE_BSDFS + (RENDER_BSDF_AUTO,), default=_d("bsdf"),
                   help="how the wave-optics BRDF enters Mitsuba: measured (its RGL export read by Mitsuba's "
                        "measured model; spectral variants), plugin (the model itself through NumPy; slow), native "
                        "(the model itself in Dr.Jit; fast in LLVM and CUDA variants; GGX and Beckmann, tabulated "
                        "lobes) or auto (native where it runs compiled and takes the model, else measured in "
                        "spectral variants, else plugin; summary.json says which and why) "
                        f"(default {_d('bsdf')})")
    option(g, "--sphere-size", default=_d("sphere_size"), note="the image is PX x PX")
    option(g, "--spp", default=_d("spp"), note="of each render; with --target-noise the first round's")
    g.add_argument("--target-noise", type=float, metavar="DE",
                   help="double the samples per pixel until the noise floor (mean ΔE2000 on the sphere between two "
                        "renders of the wave-optics model with different seeds) is below DE, or --max-spp or "
                        "--budget is reached (default: one round at --spp)")
    g.add_argument("--max-spp", type=int, default=MAX_SPP_DEFAULT, metavar="N",
                   help=f"most samples per pixel --target-noise doubles to (default {MAX_SPP_DEFAULT})")
    option(g, "--budget", default=f"{_d('budget_s'):g}",
           note="of the --target-noise renders; a doubling predicted to pass it is not started")
    gl = p.add_argument_group("glints (--glints)")
    gl.add_argument("--glints", action="store_true",
                    help="render the --surface height field as a plane where every pixel's footprint gives its "
                         "own BRDF, wave optics beside geometric optics (an OpenCL sum per pixel; docs/glints.md); takes "
                         "--material, --incident (the light), --light-radius, --view, --wavelengths, --sphere-size, "
                         "--shape, --coherence; --surface may be a .npy (memory-mapped), .h5 (chunked) or "
                         "procedural:NAME:SIZE:SPACING[:SEED] (brushed, scratched, flakes, psd: nothing stored); "
                         "prints its estimated cost before it starts")
    option(gl, "--incident",
           note=f"the point light's direction from the field's centre (default {_d('incident', GlintRequest)})")
    gl.add_argument("--view", metavar="THETA[,PHI]",
                    help="the camera's direction from the field's centre, degrees "
                         f"(default {_d('view', GlintRequest)})")
    option(gl, "--wavelengths", note=f"default {_d('wavelengths', GlintRequest)}")
    gl.add_argument("--shape", choices=GLINT_SHAPES,
                    help="what the height field textures: a plane, or a sphere (latitude-longitude map about the "
                         f"camera) (default {_d('shape', GlintRequest)})")
    option(p, "--coherence", group=gl, note="default: each footprint coherent")
    gl.add_argument("--light-radius", metavar="ANGLE",
                    help="angular radius of the light (a disk seen from the field), degrees or an angle with unit "
                         "(0.5, 0.5deg, 0.01rad); each pixel's BRDF is averaged over that cone (default: a point "
                         "light)")
    add_workers(p, group=gl)
    add_output(p)
    add_common(p, device=False)
    p.set_defaults(func=run)


#: sphere-render options that --glints does not take, with their defaults
_SPHERE_ONLY = {"target_noise": _d("target_noise"), "max_spp": _d("max_spp"), "budget": f"{_d('budget_s'):g}",
                "model": _d("model"), "nano_frame": _d("nano_frame")}
#: --glints options and their defaults (their options default to None, so that a sphere render can tell them given)
_GLINT_DEFAULTS = {k: _d(k, GlintRequest) for k in ("incident", "view", "wavelengths", "shape", "workers",
                                                     "scheduler", "coherence", "light_radius")}
#: model options that --glints does not take (the height field is the whole geometry), with their defaults
_NOT_GLINTS = {k: _d(k, RendererModel) for k in ("alpha", "alpha_y", "nano", "kd", "scene", "exact")}


def run(args):
    from ..errors import WaveopticsError

    if args.glints:
        return run_glints(args)
    given = [k for k, v in _GLINT_DEFAULTS.items() if getattr(args, k) is not None and getattr(args, k) != v]
    if given:
        raise WaveopticsError(f"--{given[0].replace('_', '-')} belongs to --glints renders; the sphere render takes "
                              "its light from "
                              "--environment")
    return run_render(args)


def _dask_executor(args):
    """A context manager factory entering a Dask client's executor (--workers / --scheduler), or None."""
    if args.workers is None and args.scheduler is None:
        return None
    import contextlib

    @contextlib.contextmanager
    def executor():
        import importlib

        from ..distributed import dask_client

        with dask_client(args.workers, args.scheduler) as client:
            # each worker imports the renderer before the clock starts (seconds per process): the render's own
            # wall time is then the pixels', the start-up is the command's
            client.run(importlib.import_module, "waveoptics.renderers.glints")
            yield client.get_executor()

    return executor


def run_glints(args):
    """``render --glints``: footprint BRDFs per pixel over a height field (:func:`waveoptics.renderers.glint_job.
    glints_job`)."""
    import sys
    from functools import partial

    from ..errors import WaveopticsError
    from ..renderers.glint_job import GLINT_OUTPUTS, glints_job

    given = [k for k, v in _SPHERE_ONLY.items() if getattr(args, k) != v]
    if given:
        raise WaveopticsError(f"--{given[0].replace('_', '-')} belongs to the sphere render; --glints renders "
                              "each pixel's footprint BRDF once, without Monte Carlo noise")
    given = [k for k, v in _NOT_GLINTS.items() if getattr(args, k) != v]
    if given:
        flag = {"alpha": "micro-alpha"}.get(given[0], given[0].replace("_", "-"))
        raise WaveopticsError(f"--glints renders the --surface height field itself; drop --{flag}")
    if args.surface is None:
        raise WaveopticsError("--glints needs --surface FILE (the height field to render) or "
                              "procedural:NAME:SIZE:SPACING[:SEED]")
    given = {k: getattr(args, k) for k in _GLINT_DEFAULTS if getattr(args, k) is not None}
    request = GlintRequest(surface=args.surface, spacing=args.spacing, units=args.units, channel=args.channel,
                           material=args.material, sphere_size=args.sphere_size, **given)

    def announce(est):
        if not args.json:
            print(f"estimate: {est.describe()}", file=sys.stderr)

    r = glints_job(request, args.output, overwrite=args.overwrite, progress=partial(progress, args=args),
                   executor=_dask_executor(args), on_estimate=announce)
    t = r.timings_s
    emit(args, r.summary, f"wrote {r.outdir}/ ({', '.join(GLINT_OUTPUTS)}); {t['pixels']} pixels in "
                          f"{t['wall']:.1f} s: {t['per_pixel'] * 1e3:.3g} ms/pixel (sums "
                          f"{t['sums_per_pixel'] * 1e3:.3g} ms/pixel, {t['footprints_per_s']:.0f} footprints/s; "
                          f"reading the field {t['read']:.1f} s); estimated {r.estimate.estimate_s:.0f} s")
    return 0


def run_render(args):
    """``render``: the sphere render (:func:`waveoptics.renderers.jobs.render_job`)."""
    import sys
    from functools import partial

    from ..renderers.jobs import render_job

    budget = parse_budget(args.budget)
    request = RenderRequest(**model_fields(args), model=args.model, environment=args.environment,
                            ground=args.ground, variant=args.variant, bsdf=args.bsdf, sphere_size=args.sphere_size,
                            spp=args.spp, target_noise=args.target_noise, max_spp=args.max_spp, budget_s=budget,
                            nano_frame=args.nano_frame)
    r = render_job(request, args.output, overwrite=args.overwrite, progress=partial(progress, args=args))
    if r.stop and not args.json:
        print(r.stop, file=sys.stderr)
    s, t = r.summary, r.timings_s
    model_de, floor = s["delta_e2000"], s["noise_floor_delta_e2000"]
    emit(args, s, f"wrote {r.outdir}/ ({', '.join(s['outputs'])}); mean ΔE2000 on the sphere {model_de['mean']:.2f} "
                  f"(p95 {model_de['p95']:.2f}), noise floor {floor['mean']:.2f} at {s['spp']} spp; render "
                  f"{t['render_wave_s']:.1f} s + {t['render_wave_repeat_s']:.1f} s (noise floor) "
                  f"+ {t['render_reference_s']:.1f} s, model {t['model_s']:.1f} s; wave-optics BSDF {s['bsdf']}")
    return 0
