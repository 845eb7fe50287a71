"""``waveoptics render -o OUTDIR``: the wave-optics BRDF and Mitsuba 3's own rough model on a sphere under an
environment map, rendered by Mitsuba 3, side by side with their ΔE2000 (:mod:`waveoptics.renderers.scene`)."""
from __future__ import annotations

from ._common import add_common, add_output, add_workers, emit, load_surface, parse_budget, progress
from ._options import option
from ._renderer import add_model, model_description, model_from_args, plugin_parameters

#: most samples per pixel of --target-noise by default (:data:`waveoptics.renderers.scene.MAX_SPP_DEFAULT`; kept
#: here so that building the parser imports nothing heavy)
MAX_SPP_DEFAULT = 4096

#: files of one run (summary.json last: it says the set is complete)
OUTPUTS = ("wave.exr", "reference.exr", "delta_e.exr", "render.png", "summary.json")


def register(sub):
    from ..vocabulary import GLINT_SHAPES
    from ..vocabulary import RENDER_BSDFS as WAVE_BSDFS

    p = sub.add_parser(
        "render", help="render a sphere with the wave-optics BRDF and with Mitsuba 3's own rough model",
        description="Mitsuba 3 renders a sphere (on a ground plane unless --no-ground) under an environment map "
                    "twice: (a) with the two-scale wave-optics BRDF (Mitsuba's 'measured' model reading its RGL "
                    "export, or the waveoptics plugin), (b) with Mitsuba's roughconductor (metals) or roughplastic "
                    "(dielectrics) of the same micro roughness and index. Writes linear sRGB EXRs of both, their "
                    "CIEDE2000 map, a labelled PNG and summary.json. Needs the 'render' extra.")
    add_model(p)
    g = p.add_argument_group("render")
    option(g, "--environment", default="sky", note="sky and studio are built by the code")
    g.add_argument("--no-ground", dest="ground", action="store_false", help="no ground plane under the sphere")
    g.add_argument("--variant", default="llvm_ad_spectral", metavar="NAME",
                   help="Mitsuba 3 variant, e.g. llvm_ad_spectral, llvm_ad_rgb, scalar_spectral (default "
                        "llvm_ad_spectral)")
    g.add_argument("--bsdf", choices=WAVE_BSDFS, default="measured",
                   help="how the wave-optics BRDF enters Mitsuba: measured (its RGL export, native and fast; "
                        "spectral variants) or plugin (the model itself through NumPy; slower) (default measured)")
    option(g, "--sphere-size", default=256, note="the image is PX x PX")
    option(g, "--spp", default=32, note="of each render; with --target-noise the first round's")
    g.add_argument("--target-noise", type=float, metavar="DE",
                   help="double the samples per pixel until the noise floor (mean ΔE2000 on the sphere between two "
                        "renders of the wave-optics model with different seeds) is below DE, or --max-spp or "
                        "--budget is reached (default: one round at --spp)")
    g.add_argument("--max-spp", type=int, default=MAX_SPP_DEFAULT, metavar="N",
                   help=f"most samples per pixel --target-noise doubles to (default {MAX_SPP_DEFAULT})")
    option(g, "--budget", default="600", note="of the --target-noise renders; a doubling predicted to pass it is "
                                              "not started")
    gl = p.add_argument_group("glints (--glints)")
    gl.add_argument("--glints", action="store_true",
                    help="render the --surface height field as a plane where every pixel's footprint gives its "
                         "own BRDF, wave optics beside geometric optics (an OpenCL sum per pixel; docs/glints.md); takes "
                         "--material, --incident (the light), --view, --wavelengths, --sphere-size, --shape, "
                         "--coherence; --surface may be a .npy (memory-mapped), .h5 (chunked) or "
                         "procedural:NAME:SIZE:SPACING[:SEED] (brushed, scratched, flakes, psd: nothing stored); "
                         "prints its estimated cost before it starts")
    option(gl, "--incident", note="the point light's direction from the field's centre (default 30,0)")
    gl.add_argument("--view", metavar="THETA[,PHI]",
                    help="the camera's direction from the field's centre, degrees (default 30,180)")
    option(gl, "--wavelengths", note="default 450:650:50")
    gl.add_argument("--shape", choices=GLINT_SHAPES,
                    help="what the height field textures: a plane, or a sphere (latitude-longitude map about the "
                         "camera) (default plane)")
    option(p, "--coherence", group=gl, note="default: each footprint coherent")
    add_workers(p, group=gl)
    add_output(p)
    add_common(p, device=False)
    p.set_defaults(func=run)


#: sphere-render options that --glints does not take, with their defaults
_SPHERE_ONLY = {"target_noise": None, "max_spp": MAX_SPP_DEFAULT, "budget": "600"}
#: --glints options and their defaults
_GLINT_DEFAULTS = {"incident": "30,0", "view": "30,180", "wavelengths": "450:650:50", "shape": "plane",
                   "workers": None, "scheduler": None, "coherence": None}


def run(args):
    from ..errors import WaveopticsError

    if args.glints:
        return run_glints(args)
    given = [k for k, v in _GLINT_DEFAULTS.items() if getattr(args, k) is not None and getattr(args, k) != v]
    if given:
        raise WaveopticsError(f"--{given[0]} belongs to --glints renders; the sphere render takes its light from "
                              "--environment")
    return run_render(args)


#: model options that --glints does not take (the height field is the whole geometry), with their defaults
_NOT_GLINTS = {"alpha": 0.1, "alpha_y": None, "nano": None, "kd": 0.0, "scene": None, "exact": False}


def run_glints(args):
    """``render --glints``: footprint BRDFs per pixel over a height field (:mod:`waveoptics.renderers.glints`)."""
    import contextlib
    import importlib
    import sys
    from pathlib import Path

    import numpy as np

    from .. import colour, surfaces
    from ..errors import WaveopticsError
    from ..io import files
    from ..renderers.sphere import percentile_exposure, plot_spheres, tonemap
    from ..renderers import glints
    from ..units import parse_direction, parse_length, parse_wavelengths

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
    out_names = ("glints_wave.exr", "glints_geometric.exr", "glints_layers.exr", "glints.png", "summary.json")
    outdir = files.prepare_outdir(args.output, overwrite=args.overwrite, expected=out_names)
    for k, v in _GLINT_DEFAULTS.items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    lt, lp = parse_direction(args.incident, name="--incident")
    vt, vp = parse_direction(args.view, name="--view")
    settings = glints.GlintSettings(size=args.sphere_size, view_deg=vt, view_azimuth_deg=vp, light_deg=lt,
                                    light_azimuth_deg=lp, wavelengths_nm=tuple(parse_wavelengths(args.wavelengths)),
                                    shape=args.shape, coherence_m=None if args.coherence is None
                                    else parse_length(args.coherence, name="--coherence"))
    field = _glint_field(args, surfaces)
    est = glints.estimate_glints(field, args.material, settings)
    if not args.json:
        print(f"estimate: {est.describe()}", file=sys.stderr)
    bar = progress(total=settings.size, desc="glints", args=args)
    with contextlib.ExitStack() as stack:
        executor = None
        if args.workers is not None or args.scheduler is not None:   # pixel rows as Dask tasks
            from ..distributed import dask_client

            client = stack.enter_context(dask_client(args.workers, args.scheduler))
            # each worker imports the renderer before the clock starts (seconds per process): the render's own
            # wall time is then the pixels', the start-up is the command's
            client.run(importlib.import_module, "waveoptics.renderers.glints")
            executor = client.get_executor()
        r = glints.render_glints(field, args.material, settings, progress=bar.update, executor=executor)
    bar.close()
    on = r.on_field
    de = np.where(on, colour.delta_e2000(r.wave, r.geometric), 0.0)
    exposure = percentile_exposure((r.wave, r.geometric), on)   # one exposure for both; glints are sparse
    with files.staged_outputs(outdir, out_names, last="summary.json") as stage:
        for name, img in (("glints_wave.exr", r.wave), ("glints_geometric.exr", r.geometric)):
            files.write_rgb_exr(stage / name, img, {"waveoptics": "linear sRGB radiance of a unit-intensity point light"})
        files.write_exr(stage / "glints_layers.exr", _glint_layers(r, settings),
                        {"waveoptics": "per pixel: footprint (x, y, sigma1, sigma2 in m, angle in degrees) and "
                                       "spectral radiance per wavelength (wave., geometric.)"})
        plot_spheres([tonemap(r.wave, exposure), tonemap(r.geometric, exposure)],
                     [f"wave optics (footprint Kirchhoff)\n{args.material}, {Path(args.surface).name}",
                      "geometric optics (footprint NDF)"], stage / "glints.png", diff=de,
                     diff_title=f"ΔE2000 (mean {float(de[on].mean()):.1f})", exposure=exposure,
                     caption=f"{settings.shape}; light at θ = {lt:g}°, φ = {lp:g}°; camera at θ = {vt:g}°, "
                             f"φ = {vp:g}°; footprint σ "
                             f"≈ {r.footprint_sigma_m[0] * 1e6:.3g} × {r.footprint_sigma_m[1] * 1e6:.3g} µm")
        summary = {"surface": str(args.surface), "material": args.material, "size_px": settings.size,
                   "shape": settings.shape, "workers": args.workers, "scheduler": args.scheduler,
                   "light_deg": [lt, lp], "view_deg": [vt, vp], "wavelengths_nm": list(settings.wavelengths_nm),
                   "footprint_sigma_m": list(r.footprint_sigma_m),
                   "pixels_on_field": int(on.sum()), "delta_e2000_mean": float(de[on].mean()),
                   "timings_s": {k: (round(v, 6) if isinstance(v, float) else v) for k, v in r.timings_s.items()},
                   "estimate": {"pixels": est.pixels, "samples": est.samples, "per_pixel_s": est.per_pixel_s,
                                "estimate_s": est.estimate_s, "probe_pixels": est.probe_pixels},
                   "outputs": list(out_names)}
        files.write_json(stage / "summary.json", summary)
    t = r.timings_s
    emit(args, summary, f"wrote {outdir}/ ({', '.join(out_names)}); {t['pixels']} pixels in {t['wall']:.1f} s: "
                        f"{t['per_pixel'] * 1e3:.3g} ms/pixel (sums {t['sums_per_pixel'] * 1e3:.3g} ms/pixel, "
                        f"{t['footprints_per_s']:.0f} footprints/s; reading the field {t['read']:.1f} s); "
                        f"estimated {est.estimate_s:.0f} s")
    return 0


def _glint_field(args, surfaces):
    """The height field of a glint render: ``procedural:NAME:SIZE:SPACING[:SEED]``, a .h5 / .hdf5 (chunked), a .npy
    (memory-mapped) or any other height-field file."""
    from ..units import parse_length
    from .brdf import spacing_from_args

    text = str(args.surface)
    if text.startswith("procedural:"):
        from ..errors import WaveopticsError

        parts = text.split(":")
        if len(parts) not in (4, 5):
            raise WaveopticsError(f"--surface {text!r}: give procedural:NAME:SIZE:SPACING[:SEED], e.g. "
                                  "procedural:brushed:2mm:0.1um")
        return surfaces.procedural(parts[1], parse_length(parts[2], name="--surface"),
                                   parse_length(parts[3], name="--surface"), int(parts[4]) if len(parts) > 4 else 0)
    if text.lower().endswith((".h5", ".hdf5")):
        return surfaces.HDF5Field(text)
    if text.lower().endswith(".npy") and args.channel is None:
        return surfaces.open_large(args.surface, spacing=spacing_from_args(args), units=args.units)
    return load_surface(args)


def _glint_layers(r, settings) -> dict:
    """EXR channels of a glint render: the footprint and the spectral radiance of both models per pixel."""
    ch = {f"footprint.{k}": r.footprints[..., n] for n, k in enumerate(("x", "y", "sigma1", "sigma2", "angle"))}
    for k, lam in enumerate(settings.wavelengths_nm):
        ch[f"wave.{lam:g}nm"] = r.wave_spectral[..., k]
        ch[f"geometric.{lam:g}nm"] = r.geometric_spectral[..., k]
    return ch


def run_render(args):
    import json
    import sys
    import time
    import warnings

    from ..renderers import lighting
    from ..errors import WaveopticsError
    from ..io import files
    from ..renderers.sphere import key_exposure, plot_spheres, tonemap
    from ..renderers import mitsuba as wm
    from ..renderers import rgl, scene

    settings = scene.RenderSettings(size=args.sphere_size, spp=args.spp, variant=args.variant, ground=args.ground)
    mi = wm.register(args.variant)                     # Mitsuba missing or an unknown variant: one line, first
    if args.bsdf == "measured" and "spectral" not in args.variant:
        raise WaveopticsError(f"--bsdf measured needs a spectral --variant (Mitsuba's measured model), not "
                              f"{args.variant!r}; use --bsdf plugin for RGB variants")
    outputs = OUTPUTS + (("material.bsdf",) if args.bsdf == "measured" else ())
    outdir = files.prepare_outdir(args.output, overwrite=args.overwrite, expected=outputs)
    env = lighting.environment(args.environment)       # a bad map fails here, before any work
    if args.environment in lighting.PROCEDURAL:
        env = lighting.procedural_environment(args.environment, height=256)
    budget = parse_budget(args.budget)
    if args.target_noise is not None and not args.target_noise > 0:
        raise WaveopticsError(f"--target-noise {args.target_noise!r} is not allowed; give a ΔE2000 > 0")
    if args.max_spp < args.spp:
        raise WaveopticsError(f"--max-spp {args.max_spp} is below --spp {args.spp}")
    timings = {}
    t0 = time.perf_counter()
    model, params = model_from_args(args)
    timings["model_s"] = time.perf_counter() - t0
    desc = model_description(args, params)
    bar = progress(total=3 * max(1, min(settings.passes, settings.spp)), desc="render", args=args)

    def tick(done, total):
        bar.total = total
        bar.update(done - bar.n)

    on = scene.sphere_mask(settings.size)
    with files.staged_outputs(outdir, outputs, last="summary.json") as stage:
        t0 = time.perf_counter()
        if args.bsdf == "measured":
            rgl.export_rgl(model, stage / "material.bsdf", description="waveoptics render: " + json.dumps(desc))
        timings["export_s"] = time.perf_counter() - t0
        wave = scene.wave_bsdf(mi, args.bsdf, bsdf_file=stage / "material.bsdf",
                               plugin_parameters=plugin_parameters(args, params) if args.bsdf == "plugin" else None)
        ref, notes = scene.reference_bsdf(mi, model, **{k: params[k] for k in ("material", "alpha", "alpha_y",
                                                                               "ndf", "kd")})
        scenes = {k: scene.scene_dict(mi, b, env.radiance, settings) for k, b in (("wave", wave), ("reference", ref))}
        cmp = scene.render_comparison(mi, scenes, settings, on, target_noise=args.target_noise,
                                      max_spp=args.max_spp, budget_s=budget, progress=tick)
        bar.close()
        images = cmp.images
        timings.update({f"render_{k}_s": v for k, v in cmp.render_s.items()})
        de = scene.delta_e_map(images["wave"], images["reference"])
        for key in ("wave", "reference"):
            img = images[key]
            files.write_rgb_exr(stage / f"{key}.exr", img,
                                {"waveoptics": f"linear sRGB radiance, {args.variant}, {cmp.spp} spp"})
        files.write_exr(stage / "delta_e.exr", {"Y": de, "noise": cmp.noise_floor},
                        {"waveoptics": "Y: CIEDE2000 wave vs reference; noise: CIEDE2000 between two renders of the "
                                       "wave-optics model with different seeds (the noise floor)"})
        ref_name = ref["type"]
        floor = _stats(cmp.noise_floor, on)
        model_de = _stats(de, on)
        exposure = key_exposure(images["reference"], on)
        plot_spheres([tonemap(images["wave"], exposure), tonemap(images["reference"], exposure)],
                     [f"wave optics ({args.bsdf})\n{params['material']}, α = {params['alpha']:g}, "
                      f"{desc.get('nano') or 'surface'}", f"Mitsuba {ref_name}\nsame α and index"],
                     stage / "render.png", diff=de,
                     diff_title=f"ΔE2000 (sphere mean {model_de['mean']:.2f}; noise floor {floor['mean']:.2f})",
                     exposure=exposure,
                     caption=f"environment {env.name}; Mitsuba 3 {args.variant}, {cmp.spp} spp, "
                             f"{settings.size}² px; camera looks down −z, y up")
        summary = _render_summary(args, desc, ref_name, notes, env, settings, cmp, de, model_de, floor, timings,
                                  outputs)
        files.write_json(stage / "summary.json", summary)
    for note in notes:
        warnings.warn(note, UserWarning, stacklevel=1)
    if cmp.stop and not args.json:
        print(cmp.stop, file=sys.stderr)
    emit(args, summary, f"wrote {outdir}/ ({', '.join(outputs)}); mean ΔE2000 on the sphere {model_de['mean']:.2f} "
                        f"(p95 {model_de['p95']:.2f}), noise floor {floor['mean']:.2f} at {cmp.spp} spp; render "
                        f"{timings['render_wave_s']:.1f} s + {timings['render_wave_repeat_s']:.1f} s (noise floor) "
                        f"+ {timings['render_reference_s']:.1f} s, model {timings['model_s']:.1f} s")
    return 0



def _render_summary(args, desc, ref_name, notes, env, settings, cmp, de, model_de, floor, timings,
                    outputs) -> dict:
    """summary.json of a render: the model, both ΔE2000 statistics (model vs reference, and the noise floor) with
    their meaning, the stopping rule, timings and outputs."""
    return {"model": desc, "bsdf": args.bsdf, "reference": ref_name, "reference_notes": notes,
            "variant": args.variant, "environment": env.name, "ground": args.ground,
            "size_px": settings.size, "spp": cmp.spp,
            "delta_e2000": dict(model_de, pixels="sphere", mean_image=float(de.mean()),
                                meaning="CIEDE2000 (unitless; 1 is about a just-noticeable difference) "
                                        "between the wave-optics render and the reference render, per "
                                        "pixel: the models' difference plus Monte Carlo noise"),
            "noise_floor_delta_e2000": dict(floor, pixels="sphere",
                                            meaning="CIEDE2000 between two renders of the wave-optics "
                                                    "model that differ only in their seeds, each at spp "
                                                    "samples per pixel: what sampling noise alone gives "
                                                    "(the reference shares the first render's seeds); a "
                                                    "model difference shows where delta_e2000 stands "
                                                    "well above it"),
            "model_to_noise": model_de["mean"] / floor["mean"] if floor["mean"] > 0 else None,
            "target_noise": args.target_noise, "noise_history": [[n, f] for n, f in cmp.history],
            "stop": cmp.stop or None,
            "timings_s": {k: round(v, 3) for k, v in timings.items()},
            "outputs": list(outputs)}


def _stats(de, on) -> dict:
    """Mean, 95th percentile and maximum of a ΔE2000 map over the pixels *on*."""
    import numpy as np

    return {"mean": float(de[on].mean()), "p95": float(np.percentile(de[on], 95)), "max": float(de[on].max())}

