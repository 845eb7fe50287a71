"""The sphere render job (``waveoptics render``) and the model of every renderer front end (``render``,
``export``): a :class:`waveoptics.renderers.requests.RenderRequest` in, the outputs written whole or not at all,
the summary out.

* :func:`model_parameters`, :func:`build_model`, :func:`describe_model`, :func:`plugin_parameters`: the
  :class:`~waveoptics.renderers.requests.RendererModel` as keywords of :func:`waveoptics.renderers.renderer_brdf`,
  as the built model, as the description summaries echo, and as the Mitsuba plugin's parameters;
* :func:`export_job`: the model written as a file a renderer reads (the RGL ``.bsdf`` of
  :mod:`waveoptics.renderers.rgl`);
* :func:`render_job`: the model rendered by Mitsuba 3 on a sphere under an environment map beside Mitsuba's own
  rough model (:mod:`waveoptics.renderers.scene`), their CIEDE2000 map and its noise floor; writes wave.exr,
  reference.exr, delta_e.exr, render.png, summary.json (last: it says the set is complete) and, for the
  ``measured`` BSDF, material.bsdf;
* :func:`choose_bsdf`: how the model enters Mitsuba when the request says ``auto`` (the Dr.Jit plugin where it
  runs compiled and takes the model, else the RGL export in spectral variants, else the NumPy plugin);
* :data:`RENDER_MODEL_KINDS`: the surface models :func:`render_job` renders (the request's ``model``), each as the
  functions that build it, choose how it enters Mitsuba, give its BSDF and Mitsuba's reference, and describe it:
  ``twoscale`` (the functions above) and ``rough-dielectric`` (:mod:`waveoptics.renderers.glass_render`).

Errors are :class:`waveoptics.errors.FieldError` naming the request's fields.

References
----------
.. [1] W. Jakob et al., Mitsuba 3, 2022 (the renders; :mod:`waveoptics.renderers.scene`).
.. [2] CIE 142-2001 (CIEDE2000, the colour difference of the renders; :mod:`waveoptics.colour`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import FieldError
from ..vocabulary import DEFAULT_NANO, RENDER_BSDF_AUTO, RENDER_BSDFS
from . import glass_render
from .requests import RendererModel, RenderRequest, field_default

__all__ = ["OUTPUTS", "EXPORT_FORMATS", "RenderResult", "load_height_field", "model_parameters", "build_model",
           "describe_model", "plugin_parameters", "export_job", "choose_bsdf", "RenderModelKind",
           "RENDER_MODEL_KINDS", "render_job"]

#: files of one sphere render (summary.json last: it says the set is complete); the ``measured`` BSDF adds
#: material.bsdf
OUTPUTS = ("wave.exr", "reference.exr", "delta_e.exr", "render.png", "summary.json")

#: export formats → (what it is, file suffix)
EXPORT_FORMATS = {"rgl": ("RGL tabulated BSDF (Dupuy & Jakob 2018) for Mitsuba 3's and pbrt-v4's 'measured' models",
                          ".bsdf")}

#: model fields a scene's material replaces
_SCENE_REPLACES = ("material", "alpha", "alpha_y", "ndf", "nano", "surface", "kd")


def load_height_field(surface, spacing=None, units=None, channel=None, *, required: bool = True):
    """The height field *surface* (a field, or a file read with its metadata *spacing*, *units*, *channel* by
    :func:`waveoptics.surfaces.load`); None when no file is named and *required* is False. Metadata without a
    file are refused."""
    if surface is None:
        given = [k for k, v in (("spacing", spacing), ("units", units), ("channel", channel)) if v is not None]
        if given:
            raise FieldError(f"{' and '.join('{' + k + '}' for k in given)} describe a {{surface}} file; give one",
                             *given, "surface")
        return None
    if not isinstance(surface, (str, Path)):
        return surface
    from .. import surfaces

    return surfaces.load(surface, spacing=spacing, units=units, channel=channel)


def _scene_parameters(model: RendererModel) -> dict:
    """Model keywords from the scene's material (its nano as statistics text, a height-field file or a generated
    height field)."""
    given = [k for k in _SCENE_REPLACES if getattr(model, k) != getattr(RendererModel, k)]
    if given:
        raise FieldError(f"{{scene}} sets the model; do not also give {{{given[0]}}}", "scene", given[0])
    sc = model.scene
    mats = {m.name: m for m in sc.materials}
    name = model.scene_material or sc.materials[0].name
    if name not in mats:
        raise FieldError(f"{{scene_material}} {name!r} is not in {sc.path}; it has: {', '.join(mats)}",
                         "scene_material")
    m = mats[name]
    kw = dict(material=m.material, alpha=m.roughness, alpha_y=m.roughness_y, ndf=m.ndf, nano="none", surface=None,
              kd=m.diffuse_albedo, diffraction=model.diffraction if m.diffraction == "auto" else m.diffraction)
    if m.nano is not None:
        if m.nano.kind == "statistics":
            kw["nano"] = m.nano.text
        else:
            kw.update(nano=None, surface=m.nano.height_field(sc.seed))
    return kw


def model_parameters(model: RendererModel) -> dict:
    """Keywords of :func:`waveoptics.renderers.renderer_brdf` of *model* (the surface as given: a file name, or
    a height field the scene generates)."""
    from ..units import parse_length

    if model.scene_material and model.scene is None:
        raise FieldError("{scene_material} names a material of a {scene} file; give one", "scene_material", "scene")
    step = parse_length(model.wavelength_step, name="wavelength_step") * 1e9
    if model.scene is not None:
        return dict(_scene_parameters(model), diffuse=model.diffuse, wavelength_step_nm=step,
                    resolution=model.resolution, exact=model.exact, multiple_scattering=model.multiple_scattering)
    if model.surface is not None and model.nano is not None:
        raise FieldError("give only one of {nano} MODEL:params and {surface} FILE", "nano", "surface")
    return dict(material=model.material, alpha=model.alpha, alpha_y=model.alpha_y, ndf=model.ndf, nano=model.nano,
                surface=model.surface, diffraction=model.diffraction, kd=model.kd, diffuse=model.diffuse,
                wavelength_step_nm=step, resolution=model.resolution, exact=model.exact,
                multiple_scattering=model.multiple_scattering)


def build_model(model: RendererModel):
    """(the :class:`waveoptics.brdf.SpectralNodes` model, its :func:`model_parameters`)."""
    from .model import renderer_brdf

    kw = model_parameters(model)
    built = dict(kw)
    if model.scene is None:
        built["surface"] = load_height_field(model.surface, model.spacing, model.units, model.channel,
                                             required=False)
    out = renderer_brdf(**built)
    if kw.get("resolution") is None:   # chosen from the nano lobe (model.model_resolution): say which
        kw["resolution"] = getattr(out.base, "resolution", None) if hasattr(out.base, "table") else None
    return out, kw


def plugin_parameters(model: RendererModel, kw: dict) -> dict:
    """The model of :func:`model_parameters` *kw* as parameters of the Mitsuba plugin
    (:mod:`waveoptics.renderers.mitsuba`)."""
    if model.surface is not None and any(v is not None for v in (model.spacing, model.units, model.channel)):
        raise FieldError("the waveoptics plugin reads {surface} itself and cannot take {spacing}, {units} or "
                         "{channel}; use a file that states them (e.g. .npz, .x3p) or {bsdf} measured",
                         "surface", "spacing", "units", "channel", "bsdf")
    if kw["surface"] is not None and not isinstance(kw["surface"], str):
        raise FieldError("the waveoptics plugin reads a nano height field from a file; this scene generates "
                         "one: use {bsdf} measured", "bsdf")
    names = {"wavelength_step_nm": "wavelength_step"}
    return {names.get(k, k): v for k, v in kw.items() if v is not None}


def describe_model(model: RendererModel, kw: dict) -> dict:
    """The model's parameters *kw* (:func:`model_parameters`) as given, for summaries and file descriptions."""
    if model.scene is not None:
        d = {k: v for k, v in kw.items() if k not in ("surface", "nano")}
        d.update(scene=str(model.scene.path), scene_material=model.scene_material,
                 nano=kw["nano"] if kw["nano"] is not None else "height field of the scene")
        return d
    d = {k: getattr(model, k) for k in ("material", "alpha", "alpha_y", "ndf", "diffraction", "kd", "diffuse",
                                        "wavelength_step", "resolution", "exact", "multiple_scattering")}
    d["resolution"] = kw.get("resolution", model.resolution)
    if model.surface:
        d["surface"] = model.surface
    else:
        d["nano"] = model.nano or DEFAULT_NANO
    return d


def export_job(model: RendererModel, output, *, format: str = "rgl", incidence_nodes: int = 18,
               table_resolution: int = 32, azimuth_nodes: int = 9, overwrite: bool = False) -> dict:
    """Write the BRDF of *model* to the file *output* in *format* (:data:`EXPORT_FORMATS`): the RGL tensor format
    tabulated at *incidence_nodes* incidences over 0-89°, *table_resolution* × *table_resolution* sample-space
    cells per incidence and *azimuth_nodes* light azimuths (an anisotropic BRDF); an existing file only with
    *overwrite*. Returns the summary: the file, the model's description, the table's wavelengths (nm), incidences
    (deg), array shapes, its size in bytes and the times (s) of the model and of the table."""
    import numpy as np

    from .. import __version__
    from . import rgl

    out = Path(output)
    suffix = EXPORT_FORMATS[format][1]
    if out.suffix.lower() != suffix:
        raise FieldError(f"{{output}} {str(output)!r} must end in {suffix} for {{format}} {format}", "output", "format")
    if out.exists() and not overwrite:
        raise FieldError(f"{{output}} {str(output)!r} exists; give {{overwrite}} to replace it", "output", "overwrite",
                         python={"overwrite": "overwrite=True"})
    grid = rgl.RGLGrid(n_theta_i=incidence_nodes, resolution=table_resolution, n_phi_i=azimuth_nodes)
    t0 = time.perf_counter()
    brdf, params = build_model(model)
    t1 = time.perf_counter()
    desc = describe_model(model, params)
    text = f"waveoptics {__version__} two-scale BRDF: " + ", ".join(f"{k}={v}" for k, v in desc.items()
                                                                      if v is not None)
    fields = rgl.export_rgl(brdf, out, grid=grid, description=text, overwrite=overwrite)
    t2 = time.perf_counter()
    return {"output": str(out), "format": format, "model": desc,
            "isotropic": int(fields["phi_i"].size) == 2,
            "wavelengths_nm": [float(x) for x in fields["wavelengths"]],
            "theta_i_deg": [round(float(x), 6) for x in np.degrees(fields["theta_i"])],
            "shape": {k: list(v.shape) for k, v in fields.items() if hasattr(v, "shape")},
            "bytes": out.stat().st_size, "time_model_s": round(t1 - t0, 3), "time_export_s": round(t2 - t1, 3)}


@dataclass(frozen=True)
class RenderResult:
    """What :func:`render_job` did: its *summary* (the content of summary.json), the output directory, the
    reason the noise target stopped short (*stop*, empty when it did not) and the timings in s (unrounded)."""

    summary: dict
    outdir: Path
    stop: str = ""
    timings_s: dict = field(default_factory=dict)


def _check(request: RenderRequest) -> None:
    """Validate the render fields before any work (the model's are checked where it is built)."""
    if request.model not in RENDER_MODEL_KINDS:
        raise FieldError(f"{{model}} {request.model!r} is not allowed; use one of {', '.join(RENDER_MODEL_KINDS)}",
                         "model")
    if request.bsdf not in RENDER_BSDFS + (RENDER_BSDF_AUTO,):
        raise FieldError(f"{{bsdf}} {request.bsdf!r} is not allowed; use one of "
                         f"{', '.join(RENDER_BSDFS + (RENDER_BSDF_AUTO,))}", "bsdf")
    if request.model != "rough-dielectric" and request.nano_frame != field_default(RenderRequest, "nano_frame"):
        raise FieldError(f"{{nano_frame}} {request.nano_frame!r} belongs to the rough-dielectric {{model}} (the "
                         f"nano-rough glass), not {request.model!r}", "nano_frame", "model")
    if request.bsdf == "measured" and "spectral" not in request.variant:
        raise FieldError(f"{{bsdf}} measured needs a spectral {{variant}} (Mitsuba's measured model), not "
                         f"{request.variant!r}; use {{bsdf}} plugin for RGB variants", "bsdf", "variant")


#: Mitsuba variants whose kernels Dr.Jit compiles (the native plugin runs there in symbolic mode; in scalar variants
#: it runs per sample in Python)
_JIT_PREFIXES = ("llvm_", "cuda_")


def choose_bsdf(request: RenderRequest, model) -> tuple[str, str]:
    """(how the built *model* enters Mitsuba, why): the request's :attr:`~RenderRequest.bsdf` when it names one
    (``native`` checked against the model and variant), else ``native`` (the Dr.Jit plugin,
    :mod:`waveoptics.renderers.mitsuba_native`) in LLVM and CUDA variants where it takes the model, else
    ``measured`` (Mitsuba's C++ model reading the RGL export) in spectral variants, else ``plugin`` (NumPy)."""
    from .mitsuba_native import native_unsupported

    variant = request.variant
    if request.bsdf != RENDER_BSDF_AUTO:
        if request.bsdf == "native":
            why = native_unsupported(model, variant)
            if why is not None:
                raise FieldError(f"{{bsdf}} native: {why[0]}; use {{bsdf}} plugin or measured", "bsdf", why[1])
        return request.bsdf, "given"
    if variant.startswith(_JIT_PREFIXES):
        why = native_unsupported(model, variant)
        if why is None:
            return "native", (f"auto: {variant} compiles the Dr.Jit plugin's kernels and the plugin takes this "
                              "model")
        not_native = f"the Dr.Jit plugin does not take this model ({why[0]})"
    else:
        not_native = f"{variant} is not an LLVM or CUDA variant (the Dr.Jit plugin would run per sample in Python)"
    if "spectral" in variant:
        return "measured", f"auto: {not_native}; Mitsuba's measured model reads the RGL export in spectral variants"
    return "plugin", f"auto: {not_native}; the NumPy plugin (measured needs a spectral variant)"


def _twoscale_wave(mi, how: str, model, params: dict, request: RenderRequest, stage) -> dict:
    """The two-scale model's BSDF as *how* says (:func:`waveoptics.renderers.scene.wave_bsdf`)."""
    from . import scene

    return scene.wave_bsdf(mi, how, bsdf_file=stage / "material.bsdf",
                           plugin_parameters=plugin_parameters(request, params) if how == "plugin" else None,
                           model=model)


def _twoscale_reference(mi, model, params: dict):
    """Mitsuba's roughconductor or roughplastic (:func:`waveoptics.renderers.scene.reference_bsdf`)."""
    from . import scene

    return scene.reference_bsdf(mi, model, **{k: params[k] for k in ("material", "alpha", "alpha_y", "ndf", "kd")})


@dataclass(frozen=True)
class RenderModelKind:
    """One surface model of :func:`render_job`: ``build(request)`` → (model, parameters); ``choose(request,
    model)`` → (how it enters Mitsuba, why); ``wave(mi, how, model, parameters, request, stage)`` → its Mitsuba
    dict; ``reference(mi, model, parameters)`` → (Mitsuba's own model, notes); ``describe(request, parameters)``
    → the description summaries echo."""

    build: Callable
    choose: Callable
    wave: Callable
    reference: Callable
    describe: Callable


#: the surface models of :func:`render_job` by the request's ``model``
#: (:data:`waveoptics.vocabulary.RENDER_MODELS`)
RENDER_MODEL_KINDS = {
    "twoscale": RenderModelKind(build_model, choose_bsdf, _twoscale_wave, _twoscale_reference, describe_model),
    "rough-dielectric": RenderModelKind(glass_render.glass_build, glass_render.glass_choose, glass_render.glass_wave,
                                        glass_render.glass_reference, glass_render.glass_describe),
}


def render_job(request: RenderRequest, output, *, overwrite: bool = False, progress=None) -> RenderResult:
    """Render *request* into the directory *output* (see the module doc); the set of files is written whole or not
    at all (:func:`waveoptics.io.files.staged_outputs`), an existing set only with *overwrite*.

    *progress*, optional, makes a progress bar: ``progress(total=N, desc=TEXT)`` returning an object with tqdm's
    ``n``, ``total``, ``update(k)`` and ``close()``; it is called when the rendering starts. The reference's notes
    (e.g. an NDF Mitsuba lacks) are issued as :class:`UserWarning`.
    """
    import warnings

    from ..io import files
    from . import lighting, scene
    from . import mitsuba as wm

    settings = scene.RenderSettings(size=request.sphere_size, spp=request.spp, variant=request.variant,
                                    ground=request.ground)
    mi = wm.register(request.variant)                  # Mitsuba missing or an unknown variant: one line, first
    _check(request)
    outputs = OUTPUTS + (("material.bsdf",) if request.bsdf == "measured" else ())
    outdir = files.prepare_outdir(output, overwrite=overwrite, expected=outputs)
    env = lighting.environment(request.environment)   # a bad map fails here, before any work
    if request.environment in lighting.PROCEDURAL:
        env = lighting.procedural_environment(request.environment, height=256)
    if request.target_noise is not None and not request.target_noise > 0:
        raise FieldError(f"{{target_noise}} {request.target_noise!r} is not allowed; give a ΔE2000 > 0",
                         "target_noise")
    if request.max_spp < request.spp:
        raise FieldError(f"{{max_spp}} {request.max_spp} is below {{spp}} {request.spp}", "max_spp", "spp")
    timings = {}
    t0 = time.perf_counter()
    kind = RENDER_MODEL_KINDS[request.model]
    model, params = kind.build(request)
    timings["model_s"] = time.perf_counter() - t0
    bsdf = kind.choose(request, model)
    if bsdf[0] == "measured" and "material.bsdf" not in outputs:       # chosen by auto: check its file too
        outputs += ("material.bsdf",)
        files.prepare_outdir(outdir, overwrite=overwrite, expected=outputs)
    desc = kind.describe(request, params)
    with files.staged_outputs(outdir, outputs, last="summary.json") as stage:
        summary, cmp = _render(request, kind, bsdf, mi, model, params, desc, env, settings, stage, timings,
                               progress)
        summary["outputs"] = list(outputs)
        files.write_json(stage / "summary.json", summary)
    for note in summary["reference_notes"]:
        warnings.warn(note, UserWarning, stacklevel=2)
    return RenderResult(summary, outdir, cmp.stop, timings)


def _render(request, kind, bsdf, mi, model, params, desc, env, settings, stage, timings, progress):
    """The renders of :func:`render_job` and every output but summary.json, written into *stage*, of the surface
    model *kind* (:class:`RenderModelKind`) with the BSDF *bsdf* of its ``choose``; (the summary, the
    :class:`waveoptics.renderers.scene.Comparison`)."""
    import json

    from ..io import files
    from . import rgl, scene
    from .sphere import key_exposure, plot_spheres, tonemap

    bar = None if progress is None else progress(total=3 * max(1, min(settings.passes, settings.spp)),
                                                 desc="render")

    def tick(done, total):
        if bar is not None:
            bar.total = total
            bar.update(done - bar.n)

    on = scene.sphere_mask(settings.size)
    t0 = time.perf_counter()
    how = bsdf[0]
    if how == "measured":
        rgl.export_rgl(model, stage / "material.bsdf", description="waveoptics render: " + json.dumps(desc))
    timings["export_s"] = time.perf_counter() - t0
    wave = kind.wave(mi, how, model, params, request, stage)
    ref, notes = kind.reference(mi, model, params)
    scenes = {k: scene.scene_dict(mi, b, env.radiance, settings) for k, b in (("wave", wave), ("reference", ref))}
    cmp = scene.render_comparison(mi, scenes, settings, on, target_noise=request.target_noise,
                                  max_spp=request.max_spp, budget_s=request.budget_s, progress=tick)
    if bar is not None:
        bar.close()
    images = cmp.images
    timings.update({f"render_{k}_s": v for k, v in cmp.render_s.items()})
    de = scene.delta_e_map(images["wave"], images["reference"])
    for key in ("wave", "reference"):
        files.write_rgb_exr(stage / f"{key}.exr", images[key],
                            {"waveoptics": f"linear sRGB radiance, {request.variant}, {cmp.spp} spp"})
    files.write_exr(stage / "delta_e.exr", {"Y": de, "noise": cmp.noise_floor},
                    {"waveoptics": "Y: CIEDE2000 wave vs reference; noise: CIEDE2000 between two renders of the "
                                   "wave-optics model with different seeds (the noise floor)"})
    floor, model_de = _stats(cmp.noise_floor, on), _stats(de, on)
    exposure = key_exposure(images["reference"], on)
    plot_spheres([tonemap(images["wave"], exposure), tonemap(images["reference"], exposure)],
                 [f"wave optics ({how})\n{params['material']}, α = {params['alpha']:g}, "
                  f"{desc.get('nano') or 'surface'}", f"Mitsuba {ref['type']}\nsame α and index"],
                 stage / "render.png", diff=de,
                 diff_title=f"ΔE2000 (sphere mean {model_de['mean']:.2f}; noise floor {floor['mean']:.2f})",
                 exposure=exposure,
                 caption=f"environment {env.name}; Mitsuba 3 {request.variant}, {cmp.spp} spp, "
                         f"{settings.size}² px; camera looks down −z, y up")
    summary = _render_summary(request, bsdf, desc, ref["type"], notes, env, settings, cmp, de, model_de, floor,
                              timings)
    return summary, cmp


def _render_summary(request, bsdf, desc, ref_name, notes, env, settings, cmp, de, model_de, floor, timings) -> dict:
    """summary.json of a render: the model, the BSDF used (and why), both ΔE2000 statistics (model vs reference,
    and the noise floor) with their meaning, the stopping rule, timings and outputs."""
    return {"model": desc, "bsdf": bsdf[0], "bsdf_requested": request.bsdf, "bsdf_reason": bsdf[1],
            "reference": ref_name, "reference_notes": notes,
            "variant": request.variant, "environment": env.name, "ground": request.ground,
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
            "target_noise": request.target_noise, "noise_history": [[n, f] for n, f in cmp.history],
            "stop": cmp.stop or None,
            "timings_s": {k: round(v, 3) for k, v in timings.items()}}


def _stats(de, on) -> dict:
    """Mean, 95th percentile and maximum of a ΔE2000 map over the pixels *on*."""
    import numpy as np

    return {"mean": float(de[on].mean()), "p95": float(np.percentile(de[on], 95)), "max": float(de[on].max())}
