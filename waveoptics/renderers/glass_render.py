"""The nano-rough glass in ``waveoptics render`` (render model ``rough-dielectric``): the sphere is the rough
dielectric of :mod:`waveoptics.renderers.mitsuba_glass` (reflection and transmission, the nano-roughness's
first-order scatter into both half-spaces), rendered beside Mitsuba's ``roughdielectric`` of the same micro
roughness and index.

The pieces :data:`waveoptics.renderers.jobs.RENDER_MODEL_KINDS` holds for it: the model built from the request
(:func:`glass_build`), how it enters Mitsuba (:func:`glass_choose`: the NumPy glass plugin only; the RGL export
and the Dr.Jit plugin are reflection-only), the plugin's scene dict (:func:`glass_wave`), the reference
(:func:`glass_reference`) and the description summaries echo (:func:`glass_describe`).

References
----------
.. [1] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007 (the rough dielectric;
   Mitsuba's ``roughdielectric`` implements it).
.. [2] W. Jakob et al., Mitsuba 3, 2022 (``roughdielectric``; its Beckmann masking is Walter's rational
   approximation, its exterior index defaults to air's 1.000277, set to 1 here).
"""
from __future__ import annotations

from ..errors import FieldError
from ..vocabulary import DEFAULT_NANO, RENDER_BSDF_AUTO
from .requests import RendererModel, RenderRequest

__all__ = ["GLASS_RENDER_NAME", "GLASS_FIELDS", "glass_parameters", "glass_build", "glass_choose", "glass_wave",
           "glass_reference", "glass_describe"]

#: name under which :func:`glass_wave` registers the glass plugin holding a render's model
GLASS_RENDER_NAME = "waveoptics_glass_render"
#: the :class:`~waveoptics.renderers.requests.RendererModel` fields the glass takes
GLASS_FIELDS = ("material", "alpha", "alpha_y", "ndf", "nano", "nano_frame", "multiple_scattering",
                "wavelength_step")
#: NDFs of Mitsuba's roughdielectric
_REFERENCE_NDFS = ("ggx", "beckmann")


def glass_parameters(request: RenderRequest) -> dict:
    """Keywords of :func:`waveoptics.renderers.mitsuba_glass.glass_model` from *request*; a two-scale field given
    (a height field, a diffuse substrate, a scene, ...) is refused, naming it."""
    from ..units import parse_length
    from .requests import field_default

    given = [f for f in ("surface", "spacing", "units", "channel", "diffraction", "kd", "diffuse", "resolution",
                         "exact", "scene", "scene_material")
             if getattr(request, f) != field_default(RendererModel, f)]
    if given:
        raise FieldError(f"{{model}} rough-dielectric (the nano-rough glass) takes {', '.join(GLASS_FIELDS)}, not "
                         f"{{{given[0]}}}", "model", given[0])
    step = parse_length(request.wavelength_step, name="wavelength_step") * 1e9
    return dict(material=request.material, alpha=request.alpha, alpha_y=request.alpha_y, ndf=request.ndf,
                nano=request.nano, multiple_scattering=request.multiple_scattering, wavelength_step_nm=step,
                nano_frame=request.nano_frame)


def glass_build(request: RenderRequest):
    """(the glass model, a :class:`waveoptics.brdf.SpectralNodes`; its :func:`glass_parameters`)."""
    from .mitsuba_glass import glass_model

    kw = glass_parameters(request)
    return glass_model(**kw), kw


def glass_choose(request: RenderRequest, model) -> tuple[str, str]:
    """(how the glass enters Mitsuba, why): the NumPy plugin, given or chosen by ``auto``."""
    if request.bsdf == "plugin":
        return "plugin", "given"
    if request.bsdf != RENDER_BSDF_AUTO:
        raise FieldError(f"{{bsdf}} {request.bsdf}: the rough-dielectric {{model}} transmits light, which only the "
                         "glass plugin renders (the RGL export and the Dr.Jit plugin reflect only); use {bsdf} plugin "
                         "or auto", "bsdf", "model")
    return "plugin", ("auto: the rough-dielectric model transmits light; only the NumPy glass plugin "
                      "(waveoptics_glass) takes it")


def glass_wave(mi, how: str, model, params: dict, request: RenderRequest, stage) -> dict:
    """The glass plugin holding the built *model*, as a Mitsuba dict (*how* is ``plugin``)."""
    from .mitsuba_glass import register_glass

    register_glass(model=model, name=GLASS_RENDER_NAME)
    return {"type": GLASS_RENDER_NAME}


def glass_reference(mi, model, params: dict) -> tuple[dict, list[str]]:
    """Mitsuba's ``roughdielectric`` of the same NDF, α and index (at 550 nm, air outside), and notes on what
    differs."""
    import numpy as np

    notes = []
    ndf = params["ndf"]
    distribution = ndf if ndf in _REFERENCE_NDFS else "ggx"
    if distribution != ndf:
        notes.append(f"Mitsuba's roughdielectric has no {ndf} NDF; the reference uses ggx with the same alpha")
    rough = {"alpha": float(params["alpha"])} if params["alpha_y"] is None else {
        "alpha_u": float(params["alpha"]), "alpha_v": float(params["alpha_y"])}
    from ..brdf import bulk_medium

    mat = model.base.material
    glass = bulk_medium(mat)   # roughdielectric takes one interface: a stack's bare substrate
    coated = glass is not mat
    n550 = float(np.real(glass.eta(np.array([550.0]))[0]))
    notes.append(f"roughdielectric: index {n550:.4g} (550 nm) at every wavelength, separable Smith masking")
    if coated:
        notes.append(f"roughdielectric takes one interface: the reference is the bare substrate {glass.name}, "
                     f"without the films of {mat.name} (the difference shown is the coating's and the model's)")
    if model.base.multiple_scattering:
        notes.append("the wave-optics glass has the multiple-scattering compensation; roughdielectric does not")
    if getattr(model.base, "psd", None) is not None:
        notes.append("the nano-roughness's first-order scatter (and the coherent light it takes) is the wave-optics "
                     "glass's only")
    return {"type": "roughdielectric", "distribution": distribution, "int_ior": n550, "ext_ior": 1.0,
            **rough}, notes


def glass_describe(request: RenderRequest, params: dict) -> dict:
    """The glass's parameters as given, for summaries and file descriptions."""
    d = {k: getattr(request, k) for k in GLASS_FIELDS}
    d.update(model="rough-dielectric", nano=request.nano or DEFAULT_NANO)
    return d
