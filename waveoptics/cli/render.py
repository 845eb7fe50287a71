"""``waveoptics render -o OUTDIR``: the wave-optics BRDF and Mitsuba 3's own rough model on a sphere under an
environment map, rendered by Mitsuba 3, side by side with their ΔE2000 (:mod:`waveoptics.renderers.scene`)."""
from __future__ import annotations

from ._common import add_common, add_output, emit, progress
from ._options import option
from ._renderer import add_model, model_description, model_from_args, plugin_parameters

#: files of one run (summary.json last: it says the set is complete)
OUTPUTS = ("wave.exr", "reference.exr", "delta_e.exr", "render.png", "summary.json")


def register(sub):
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
    option(g, "--spp", default=32)
    add_output(p)
    add_common(p, device=False)
    p.set_defaults(func=run)


def run(args):
    import json
    import time
    import warnings

    import numpy as np

    from .. import colour, lighting
    from ..errors import WaveopticsError
    from ..io import files
    from ..render import plot_spheres, tonemap
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
    timings = {}
    t0 = time.perf_counter()
    model, params = model_from_args(args)
    timings["model_s"] = time.perf_counter() - t0
    desc = model_description(args, params)
    bar = progress(total=2 * max(1, min(settings.passes, settings.spp)), desc="render", args=args)
    with files.staged_outputs(outdir, outputs, last="summary.json") as stage:
        t0 = time.perf_counter()
        if args.bsdf == "measured":
            rgl.export_rgl(model, stage / "material.bsdf", description="waveoptics render: " + json.dumps(desc))
        timings["export_s"] = time.perf_counter() - t0
        wave = scene.wave_bsdf(mi, args.bsdf, bsdf_file=stage / "material.bsdf",
                               plugin_parameters=plugin_parameters(args, params) if args.bsdf == "plugin" else None)
        ref, notes = scene.reference_bsdf(mi, model, **{k: params[k] for k in ("material", "alpha", "alpha_y",
                                                                               "ndf", "kd")})
        images = {}
        for key, bsdf in (("wave", wave), ("reference", ref)):
            t0 = time.perf_counter()
            images[key] = scene.render_image(mi, scene.scene_dict(mi, bsdf, env.radiance, settings), settings,
                                             progress=bar.update)
            timings[f"render_{key}_s"] = time.perf_counter() - t0
        bar.close()
        de = scene.delta_e_map(images["wave"], images["reference"])
        on = scene.sphere_mask(settings.size)
        for key in ("wave", "reference"):
            img = images[key]
            files.write_exr(stage / f"{key}.exr", {"R": img[..., 0], "G": img[..., 1], "B": img[..., 2]},
                            {"waveoptics": f"linear sRGB radiance, {args.variant}, {settings.spp} spp"})
        files.write_exr(stage / "delta_e.exr", {"Y": de}, {"waveoptics": "CIEDE2000 wave vs reference"})
        ref_name = ref["type"]
        exposure = 0.18 / np.exp(np.mean(np.log(np.maximum(colour.luminance(images["reference"]), 1e-8))))
        plot_spheres([tonemap(images["wave"], exposure), tonemap(images["reference"], exposure)],
                     [f"wave optics ({args.bsdf})\n{params['material']}, α = {params['alpha']:g}, "
                      f"{desc.get('nano') or 'surface'}", f"Mitsuba {ref_name}\nsame α and index"],
                     stage / "render.png", diff=de,
                     diff_title=f"ΔE2000 (sphere mean {float(de[on].mean()):.2f})",
                     exposure=exposure,
                     caption=f"environment {env.name}; Mitsuba 3 {args.variant}, {settings.spp} spp, "
                             f"{settings.size}² px; camera looks down −z, y up")
        summary = {"model": desc, "bsdf": args.bsdf, "reference": ref_name, "reference_notes": notes,
                   "variant": args.variant, "environment": env.name, "ground": args.ground,
                   "size_px": settings.size, "spp": settings.spp,
                   "delta_e2000": {"mean": float(de[on].mean()), "p95": float(np.percentile(de[on], 95)),
                                   "max": float(de[on].max()), "pixels": "sphere",
                                   "mean_image": float(de.mean())},
                   "timings_s": {k: round(v, 3) for k, v in timings.items()},
                   "outputs": list(outputs)}
        files.write_json(stage / "summary.json", summary)
    for note in notes:
        warnings.warn(note, UserWarning, stacklevel=1)
    emit(args, summary, f"wrote {outdir}/ ({', '.join(outputs)}); mean ΔE2000 on the sphere {summary['delta_e2000']['mean']:.2f} "
                        f"(p95 {summary['delta_e2000']['p95']:.2f}); render {timings['render_wave_s']:.1f} s + "
                        f"{timings['render_reference_s']:.1f} s, model {timings['model_s']:.1f} s")
    return 0
