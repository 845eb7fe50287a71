"""``waveoptics render``: a sphere (optionally on a ground plane) under an environment map, rendered by Mitsuba 3
with the two-scale wave-optics BRDF and with Mitsuba's own rough microfacet model of the same micro roughness and
index, side by side.

World space (as :mod:`waveoptics.renderers.lighting`): camera looking down −z, x right, y up; Mitsuba 3's ``envmap`` uses
the same equirectangular convention, so a map shows the same light in both renderers. The sphere has radius 1 at
the origin, the ground (grey Lambertian, reflectance 0.4) is the plane y = −1.

The wave-optics BSDF is either Mitsuba's native ``measured`` model reading the RGL export of the model
(:mod:`waveoptics.renderers.rgl`; fast, spectral variants only) or the ``waveoptics`` plugin
(:mod:`waveoptics.renderers.mitsuba`; the model itself, evaluated with NumPy in wavefront mode). The reference is
``roughconductor`` for metals (its η and k spectra from the same material data) and ``roughplastic`` for
dielectrics (its index at 550 nm, diffuse reflectance k_d), with the same GGX or Beckmann α; these are Mitsuba's
single-scattering microfacet models, like the coherent part of the two-scale model.

References
----------
.. [1] W. Jakob et al., Mitsuba 3, 2022 (``path``, ``envmap``, ``roughconductor``, ``roughplastic``,
   ``measured`` plugins).
.. [2] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007.
.. [3] CIE 142-2001 / colour-science ``delta_E`` (CIEDE2000 colour difference of the two renders).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import colour
from ..errors import FieldError, WaveopticsError
from ..vocabulary import RENDER_BSDFS

__all__ = ["WAVE_BSDFS", "REFERENCE_NDFS", "RenderSettings", "reference_bsdf", "wave_bsdf", "scene_dict",
           "render_image", "delta_e_map", "sphere_mask", "CAMERA"]

#: how the wave-optics BRDF enters Mitsuba
WAVE_BSDFS = RENDER_BSDFS
#: NDFs Mitsuba's rough models have (others are rendered with ggx of the same α, and said so)
REFERENCE_NDFS = ("ggx", "beckmann")
#: reflectance of the ground plane (grey Lambertian)
GROUND_REFLECTANCE = 0.4


@dataclass(frozen=True)
class RenderSettings:
    """Image and sampling settings.

    Parameters
    ----------
    size : int
        Image width and height (pixels).
    spp : int
        Samples per pixel.
    variant : str
        Mitsuba variant.
    ground : bool
        Put the sphere on a ground plane.
    max_depth : int
        Path length limit of Mitsuba's ``path`` integrator.
    passes : int
        The spp are split over this many passes (different seeds, averaged) to report progress.
    """

    size: int = 256
    spp: int = 32
    variant: str = "llvm_ad_spectral"
    ground: bool = True
    max_depth: int = 6
    passes: int = 8

    def __post_init__(self):
        if not (isinstance(self.size, (int, np.integer)) and 8 <= self.size <= 4096):
            raise FieldError(f"{{sphere_size}} {self.size!r} px (the image size) is not allowed; give 8 to 4096",
                             "sphere_size")
        if not (isinstance(self.spp, (int, np.integer)) and 1 <= self.spp <= 1 << 16):
            raise FieldError(f"{{spp}} {self.spp!r} is not allowed; give 1 to 65536 samples per pixel", "spp")


def _spectrum(mi, wavelengths, values):
    """A Mitsuba spectrum: piecewise linear in spectral variants, its RGB in RGB variants (Mitsuba converts)."""
    return {"type": "spectrum", "value": [(float(w), float(v)) for w, v in zip(wavelengths, values)]}


def reference_bsdf(mi, model, *, material, alpha, alpha_y, ndf, kd) -> tuple[dict, list[str]]:
    """Mitsuba's own rough model of the same micro roughness and index, and notes on what differs."""
    from ..materials import get_material

    notes = []
    if getattr(model.base, "multiple_scattering", False):
        notes.append("the wave-optics BRDF has the multiple-scattering compensation; Mitsuba's rough models do not")
    distribution = ndf if ndf in REFERENCE_NDFS else "ggx"
    if distribution != ndf:
        notes.append(f"Mitsuba's rough models have no {ndf} NDF; the reference uses ggx with the same alpha")
    rough = {"distribution": distribution}
    if alpha_y is None:
        rough["alpha"] = float(alpha)
    else:
        rough.update(alpha_u=float(alpha), alpha_v=float(alpha_y))
    mat = get_material(material)
    if not (mat.has_index or mat.schlick_only):
        raise FieldError(f"{{material}} {mat.name!r}: Mitsuba's reference models (roughconductor, roughplastic) take "
                         "one interface index; a thin-film stack has none", "material")
    lam = np.asarray(model.wavelengths_nm, dtype=float)
    if mat.is_metal:
        eta = mat.eta(np.clip(lam, *mat.wavelength_range_nm))
        return {"type": "roughconductor", "eta": _spectrum(mi, lam, eta.real), "k": _spectrum(mi, lam, eta.imag),
                **rough}, notes
    n550 = float(np.real(mat.eta(550.0)))
    if alpha_y is not None:
        rough = {"distribution": distribution, "alpha": float(np.sqrt(alpha * alpha_y))}
        notes.append("Mitsuba's roughplastic is isotropic; the reference uses alpha = sqrt(alpha_x alpha_y)")
    notes.append(f"roughplastic: index {n550:.4g} (550 nm), its own diffuse-specular coupling")
    return {"type": "roughplastic", "int_ior": n550, "ext_ior": 1.0, "nonlinear": False,
            "diffuse_reflectance": {"type": "rgb", "value": [float(kd)] * 3}, **rough}, notes


def wave_bsdf(mi, how: str, *, bsdf_file=None, plugin_parameters=None) -> dict:
    """The wave-optics BSDF as a Mitsuba dict: ``measured`` from an RGL file or the ``waveoptics`` plugin."""
    if how == "measured":
        if not mi.is_spectral:
            raise FieldError(f"Mitsuba's measured model needs a spectral variant, not {mi.variant()!r}; use the "
                             "plugin or a spectral variant", "variant")
        return {"type": "measured", "filename": str(bsdf_file)}
    if how == "plugin":
        from .mitsuba import PLUGIN_NAME

        return {"type": PLUGIN_NAME, **(plugin_parameters or {})}
    raise FieldError(f"BSDF {how!r} is not allowed; use one of {', '.join(WAVE_BSDFS)}", "bsdf")


#: camera of the scene: position, target, up (world space) and horizontal field of view (degrees)
CAMERA = dict(origin=(0.0, 0.9, 4.6), target=(0.0, -0.1, 0.0), up=(0.0, 1.0, 0.0), fov_deg=30.0)


def sphere_mask(size: int) -> np.ndarray:
    """Pixels (size, size) whose centre ray hits the unit sphere at the origin, for :data:`CAMERA` (pinhole,
    horizontal field of view, square image: Mitsuba's ``perspective`` with ``fov_axis = x``)."""
    o, t, up = (np.asarray(CAMERA[k], dtype=float) for k in ("origin", "target", "up"))
    fwd = (t - o) / np.linalg.norm(t - o)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    half = np.tan(np.radians(CAMERA["fov_deg"]) / 2)
    c = (np.arange(size) + 0.5) / size * 2 - 1
    X, Y = np.meshgrid(c * half, -c * half)
    d = fwd + X[..., None] * right + Y[..., None] * true_up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    b = d @ o
    return b * b - (o @ o - 1.0) > 0


def scene_dict(mi, bsdf: dict, radiance: np.ndarray, settings: RenderSettings) -> dict:
    """The Mitsuba scene: camera, sphere with *bsdf*, optional ground, environment map of *radiance* (H, W, 3)
    linear sRGB."""
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": int(settings.max_depth)},
        "sensor": {
            "type": "perspective", "fov": CAMERA["fov_deg"], "fov_axis": "x",
            "to_world": T().look_at(origin=list(CAMERA["origin"]), target=list(CAMERA["target"]),
                                    up=list(CAMERA["up"])),
            "film": {"type": "hdrfilm", "width": int(settings.size), "height": int(settings.size),
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": int(settings.spp)},
        },
        "environment": {"type": "envmap",
                        "bitmap": mi.Bitmap(np.ascontiguousarray(radiance, dtype=np.float32))},
        "sphere": {"type": "sphere", "center": [0.0, 0.0, 0.0], "radius": 1.0, "bsdf": bsdf},
    }
    if settings.ground:
        scene["ground"] = {"type": "rectangle",
                           "to_world": T().translate([0.0, -1.0, 0.0]) @ T().rotate([1, 0, 0], -90.0)
                           @ T().scale(8.0),
                           "bsdf": {"type": "diffuse",
                                    "reflectance": {"type": "rgb", "value": [GROUND_REFLECTANCE] * 3}}}
    return scene


def render_image(mi, scene: dict, settings: RenderSettings, *, progress=None) -> np.ndarray:
    """Linear sRGB image (size, size, 3): the mean of ``settings.passes`` renders with their own seeds."""
    passes = max(1, min(int(settings.passes), int(settings.spp)))
    spp = [settings.spp // passes + (1 if i < settings.spp % passes else 0) for i in range(passes)]
    loaded = mi.load_dict(scene)
    acc = np.zeros((settings.size, settings.size, 3))
    for i, k in enumerate(spp):
        acc += k * np.array(mi.render(loaded, spp=k, seed=i), dtype=float)[..., :3]
        if progress is not None:
            progress(1)
    img = acc / settings.spp
    if not np.all(np.isfinite(img)):
        raise WaveopticsError("the render holds non-finite pixels")
    return img


def delta_e_map(rgb_a, rgb_b) -> np.ndarray:
    """CIEDE2000 per pixel between two linear sRGB images (:func:`waveoptics.colour.delta_e2000`)."""
    return colour.delta_e2000(rgb_a, rgb_b)
