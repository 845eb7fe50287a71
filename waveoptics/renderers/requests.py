"""The requests of the render jobs (:mod:`waveoptics.renderers.jobs`, :mod:`waveoptics.renderers.glint_job`): small
typed dataclasses whose fields own their defaults, so that every front end (the ``render`` and ``export`` commands,
a Python caller) builds the same request and reads the defaults from here.

This module imports nothing numerical: the command line reads its defaults from it while it builds its parser.

* :class:`RendererModel`: the two-scale BRDF a renderer receives (the parameters of
  :func:`waveoptics.renderers.renderer_brdf`, a nano height-field file with its metadata, or a scene file's
  material);
* :class:`RenderRequest`: a :class:`RendererModel` rendered on a sphere by Mitsuba 3 beside Mitsuba's own rough
  model (:func:`waveoptics.renderers.jobs.render_job`);
* :class:`GlintRequest`: a height field rendered footprint by footprint (:func:`waveoptics.renderers.glint_job.
  glints_job`).
"""
from __future__ import annotations

from dataclasses import dataclass, fields

from ..vocabulary import (DEFAULT_MATERIAL, DEFAULT_NANO_FRAME, DEFAULT_NDF, RENDER_BSDF_AUTO, RENDER_MODELS,
                          RENDER_WAVELENGTH_STEP_NM)

__all__ = ["RendererModel", "RenderRequest", "GlintRequest", "field_default"]


def field_default(cls, name: str):
    """The default of field *name* of the dataclass *cls* (where a front end shows or compares it)."""
    for f in fields(cls):
        if f.name == name:
            return f.default
    raise KeyError(f"{cls.__name__} has no field {name!r}")


@dataclass(frozen=True)
class RendererModel:
    """The two-scale BRDF a renderer receives (:func:`waveoptics.renderers.renderer_brdf`).

    Parameters
    ----------
    material : str
        Material name (``waveoptics materials``), a constant complex index ``n+kj``, ``f0:VALUE`` or a thin-film
        stack; a metal gets no diffuse term.
    alpha, alpha_y : float
        Micro-scale roughness α of the NDF (dimensionless); *alpha_y* for an anisotropic NDF (None: isotropic).
    ndf : str
        Micro NDF (:data:`waveoptics.vocabulary.PARAMETRIC_NDF_NAMES`).
    nano : str or None
        Nano-roughness statistics ``MODEL:params`` with units, ``none`` for none; None: the default
        (:data:`waveoptics.vocabulary.DEFAULT_NANO`) unless *surface* is given.
    surface : str, Path or HeightField, optional
        The nano height field (heights and spacing in m), or its file, instead of *nano*.
    spacing, units, channel : str, optional
        Metadata of the *surface* file: grid spacing with unit (``50nm`` or ``50nm,80nm``), unit of the heights,
        data channel (as :func:`waveoptics.surfaces.load`).
    diffraction : str
        Diffraction model of the nano lobe (:data:`waveoptics.vocabulary.DIFFRACTION`).
    kd : float
        Diffuse albedo (dimensionless, dielectrics only).
    diffuse : str
        Diffuse model of a dielectric's substrate.
    multiple_scattering : bool
        Add the Kulla-Conty compensation lobe of the micro NDF.
    wavelength_step : str
        Largest spacing of the wavelength nodes over 360-830 nm, a length with unit (e.g. ``20nm``).
    resolution : int or None
        Direction-grid cells per axis of the tabulated diffracted lobes; None chooses them from the nano lobe's
        width (:func:`waveoptics.renderers.model.model_resolution`: 64-128).
    exact : bool
        Evaluate the diffracted part pointwise (PSD statistics only; ~200x slower).
    scene : Scene, optional
        A loaded scene file (:func:`waveoptics.planning.scene.load`) whose material gives the model instead of
        the fields above (which then keep their defaults).
    scene_material : str, optional
        Which material of *scene* (default its first).
    """

    material: str = DEFAULT_MATERIAL
    alpha: float = 0.1
    alpha_y: float | None = None
    ndf: str = DEFAULT_NDF
    nano: str | None = None
    surface: object = None
    spacing: str | None = None
    units: str | None = None
    channel: object = None
    diffraction: str = "kirchhoff"
    kd: float = 0.0
    diffuse: str = "lambert"
    multiple_scattering: bool = False
    wavelength_step: str = f"{RENDER_WAVELENGTH_STEP_NM:g}nm"
    resolution: int | None = None
    exact: bool = False
    scene: object = None
    scene_material: str | None = None


@dataclass(frozen=True)
class RenderRequest(RendererModel):
    """A sphere (on a ground plane) under an environment map, rendered by Mitsuba 3 with the wave-optics BRDF of
    the :class:`RendererModel` fields and with Mitsuba's own rough model of the same micro roughness and index.

    Parameters
    ----------
    model : str
        The surface model rendered (:data:`waveoptics.vocabulary.RENDER_MODELS`): ``twoscale`` (the two-scale BRDF
        of the :class:`RendererModel` fields) or ``rough-dielectric`` (the nano-rough glass of *material*, *alpha*,
        *alpha_y*, *ndf*, *nano*, *multiple_scattering* and *wavelength_step*, with transmission:
        :mod:`waveoptics.renderers.glass_render`).
    environment : str
        Environment light: ``sky``, ``studio``, ``constant`` or an equirectangular .exr (+y up).
    ground : bool
        Put the sphere on a ground plane.
    variant : str
        Mitsuba 3 variant (``measured`` needs a spectral one).
    bsdf : str
        How the wave-optics BRDF enters Mitsuba (:data:`waveoptics.vocabulary.RENDER_BSDFS`): ``measured`` (its
        RGL export), ``plugin`` (the model through NumPy), ``native`` (the model in Dr.Jit,
        :mod:`waveoptics.renderers.mitsuba_native`) or ``auto``: native in LLVM and CUDA variants where it takes the
        model, else measured in spectral variants, else plugin (:func:`waveoptics.renderers.jobs.choose_bsdf`).
    sphere_size : int, px
        The image is *sphere_size* × *sphere_size* pixels.
    spp : int
        Samples per pixel of each render; with *target_noise* the first round's.
    target_noise : float, optional
        ΔE2000 (unitless): double the samples per pixel until the noise floor is below it, or *max_spp* or
        *budget_s* is reached; None: one round at *spp*.
    max_spp : int
        Most samples per pixel *target_noise* doubles to.
    budget_s : float, s, optional
        Time budget of the *target_noise* renders (None: none); a doubling predicted to pass it is not started.
    nano_frame : str
        Frame of the nano lobes of the ``rough-dielectric`` glass (:data:`waveoptics.vocabulary.NANO_FRAMES`):
        ``macro`` (about the macro normal) or ``facet`` (each micro facet's: the two-scale glass); the
        ``twoscale`` model takes only the default.

    Examples
    --------
    >>> r = RenderRequest(material="gold", spp=64)
    >>> r.spp, r.alpha, field_default(RenderRequest, "max_spp")
    (64, 0.1, 4096)
    """

    model: str = RENDER_MODELS[0]
    environment: str = "sky"
    ground: bool = True
    variant: str = "llvm_ad_spectral"
    bsdf: str = RENDER_BSDF_AUTO
    sphere_size: int = 256
    spp: int = 32
    target_noise: float | None = None
    max_spp: int = 4096
    budget_s: float | None = 600.0
    nano_frame: str = DEFAULT_NANO_FRAME


@dataclass(frozen=True)
class GlintRequest:
    """A height field rendered as a plane (or a sphere) where every pixel's footprint gives its own BRDF, wave
    optics beside geometric optics (:mod:`waveoptics.renderers.glints`).

    Parameters
    ----------
    surface : str, Path or HeightField
        The height field: a file (.npy memory-mapped, .h5 / .hdf5 chunked, or any height-field format), a field,
        or ``procedural:NAME:SIZE:SPACING[:SEED]`` (lengths with units; nothing stored).
    spacing, units, channel : str, optional
        Metadata of the *surface* file (as :func:`waveoptics.surfaces.load`).
    material : str
        The material (as :class:`RendererModel`).
    sphere_size : int, px
        The image is *sphere_size* × *sphere_size* pixels.
    incident, view : str
        Directions of the point light and of the camera from the field's centre, ``THETA[,PHI]`` in degrees.
    wavelengths : str
        Wavelengths in nm summed to RGB (``450:650:50``, ``450,550,650``).
    shape : str
        What the field textures (:data:`waveoptics.vocabulary.GLINT_SHAPES`).
    coherence : str, optional
        Coherence width of the light, a length with unit; None: each footprint is coherent.
    light_radius : str, optional
        Angular radius of the light (a disk seen from the field), an angle (degrees unless a unit is given:
        ``0.5``, ``0.5deg``, ``0.01rad``); None or 0: a point light. Each pixel's BRDF is averaged over that cone.
    workers, scheduler : int, str, optional
        The Dask cluster the pixel rows run on (echoed in the summary; the job receives its executor).
    """

    surface: object = None
    spacing: str | None = None
    units: str | None = None
    channel: object = None
    material: str = RendererModel.material
    sphere_size: int = RenderRequest.sphere_size
    incident: str = "30,0"
    view: str = "30,180"
    wavelengths: str = "450:650:50"
    shape: str = "plane"
    coherence: str | None = None
    light_radius: str | None = None
    workers: int | None = None
    scheduler: str | None = None
