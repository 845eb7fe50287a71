"""``waveoptics render``: a sphere (optionally on a ground plane) under an environment map, rendered by Mitsuba 3
with the two-scale wave-optics BRDF and with Mitsuba's own rough microfacet model of the same micro roughness and
index, side by side.

World space (as :mod:`waveoptics.renderers.lighting`): camera looking down −z, x right, y up; Mitsuba 3's ``envmap`` uses
the same equirectangular convention, so a map shows the same light in both renderers. The sphere has radius 1 at
the origin, the ground (grey Lambertian, reflectance 0.4) is the plane y = −1.

The wave-optics BSDF is either Mitsuba's native ``measured`` model reading the RGL export of the model
(:mod:`waveoptics.renderers.rgl`; fast, spectral variants only) or the ``waveoptics`` plugin
(:mod:`waveoptics.renderers.mitsuba`; the model itself, evaluated with NumPy in wavefront mode) or the Dr.Jit plugin
(:mod:`waveoptics.renderers.mitsuba_native`; the model itself, compiled by Dr.Jit). The reference is
``roughconductor`` for metals (its η and k spectra from the same material data) and ``roughplastic`` for
dielectrics (its index at 550 nm, diffuse reflectance k_d), with the same GGX or Beckmann α; these are Mitsuba's
single-scattering microfacet models, like the coherent part of the two-scale model.

References
----------
.. [1] W. Jakob et al., Mitsuba 3, 2022 (``path``, ``envmap``, ``roughconductor``, ``roughplastic``,
   ``measured`` plugins).
.. [2] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007.
.. [3] CIE 142-2001 / colour-science ``delta_E`` (CIEDE2000 colour difference of the two renders).
.. [4] E. Veach, PhD thesis, Stanford, 1997, §2.4 (a Monte Carlo estimate's standard error falls as 1/√N).

**Noise floor.** Each image is a Monte Carlo estimate, so the ΔE2000 of two renders holds their sampling noise as
well as the models' difference. :func:`render_comparison` renders the wave-optics model a second time with seeds of
its own (:data:`SEED_STREAMS`) and reports the ΔE2000 between its two renders, the noise floor: what two renders of
one and the same model differ by at this many samples per pixel. The noise of each pixel falls as 1/√spp and, for
differences small enough that ΔE2000 is linear in them, so does the floor; with a target it doubles the samples per
pixel of all three renders (adding renders with new seeds) until the floor is below the target or a limit is hit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import colour
from ..errors import FieldError, WaveopticsError
from ..vocabulary import RENDER_BSDFS
from .requests import RenderRequest

__all__ = ["WAVE_BSDFS", "NATIVE_RENDER_NAME", "REFERENCE_NDFS", "RenderSettings", "reference_bsdf", "wave_bsdf",
           "scene_dict",
           "render_image", "delta_e_map", "sphere_mask", "CAMERA", "SEED_STREAMS", "Progressive", "Comparison",
           "render_comparison", "MAX_SPP_DEFAULT"]

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

    size: int = RenderRequest.sphere_size
    spp: int = RenderRequest.spp
    variant: str = RenderRequest.variant
    ground: bool = RenderRequest.ground
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


#: name under which :func:`wave_bsdf` registers the Dr.Jit plugin holding a render's model
NATIVE_RENDER_NAME = "waveoptics_native_render"


def wave_bsdf(mi, how: str, *, bsdf_file=None, plugin_parameters=None, model=None) -> dict:
    """The wave-optics BSDF as a Mitsuba dict: ``measured`` from an RGL file, the ``waveoptics`` plugin (NumPy,
    from *plugin_parameters*) or ``native``, the Dr.Jit plugin holding the built *model*
    (:func:`waveoptics.renderers.mitsuba_native.register_native`), whose kernels run in Dr.Jit's symbolic mode
    (turned back on here: the NumPy plugin's registration turns it off)."""
    if how == "native":
        if model is None:
            raise ValueError("wave_bsdf('native') renders a built model; pass model=")
        import drjit as dr

        from .mitsuba_native import register_native

        register_native(model=model, name=NATIVE_RENDER_NAME)
        if not mi.variant().startswith("scalar"):
            dr.set_flag(dr.JitFlag.SymbolicLoops, True)
            dr.set_flag(dr.JitFlag.SymbolicCalls, True)
        return {"type": NATIVE_RENDER_NAME}
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


def _split(spp: int, passes: int) -> list[int]:
    """*spp* samples per pixel over at most *passes* passes (as even as integers allow)."""
    passes = max(1, min(int(passes), int(spp)))
    return [spp // passes + (1 if i < spp % passes else 0) for i in range(passes)]


#: first sampler seed of each render of a comparison (each pass takes the next seed): the wave-optics model, its
#: repeat (seeds of its own: its difference from the first is the noise floor) and the reference, which shares the
#: first render's seeds (common random numbers, as before the noise floor was measured). Below 2^24: Mitsuba's
#: scalar variants render seed 2^24 as seed 0 (measured, Mitsuba 3.9)
SEED_STREAMS = {"wave": 0, "wave_repeat": 1 << 20, "reference": 0}
#: most samples per pixel a --target-noise render doubles to by default
MAX_SPP_DEFAULT = RenderRequest.max_spp


class Progressive:
    """One Mitsuba scene rendered in passes with consecutive seeds from *seed*, accumulated: :meth:`add` renders
    more samples per pixel, :attr:`image` is the mean of all of them (each pixel's estimate over :attr:`spp`
    samples)."""

    def __init__(self, mi, scene: dict, size: int, seed: int = 0):
        self.mi, self.loaded, self.size = mi, mi.load_dict(scene), int(size)
        self.sum = np.zeros((self.size, self.size, 3))
        self.spp, self.seed = 0, int(seed)

    def add(self, spp: int, passes: int, progress=None) -> None:
        """Render *spp* more samples per pixel over at most *passes* passes, each with the next seed."""
        for k in _split(int(spp), passes):
            self.sum += k * np.array(self.mi.render(self.loaded, spp=k, seed=self.seed), dtype=float)[..., :3]
            self.seed += 1
            self.spp += k
            if progress is not None:
                progress(1)

    @property
    def image(self) -> np.ndarray:
        img = self.sum / max(self.spp, 1)
        if not np.all(np.isfinite(img)):
            raise WaveopticsError("the render holds non-finite pixels")
        return img


def render_image(mi, scene: dict, settings: RenderSettings, *, progress=None) -> np.ndarray:
    """Linear sRGB image (size, size, 3): the mean of ``settings.passes`` renders with their own seeds."""
    r = Progressive(mi, scene, settings.size, SEED_STREAMS["wave"])
    r.add(settings.spp, settings.passes, progress)
    return r.image


@dataclass
class Comparison:
    """The renders of :func:`render_comparison`.

    Attributes
    ----------
    images : dict
        ``wave``, ``wave_repeat``, ``reference``: linear sRGB (size, size, 3), each at :attr:`spp`.
    spp : int
        Samples per pixel of every image.
    noise_floor : ndarray
        ΔE2000 per pixel between ``wave`` and ``wave_repeat`` (size, size).
    history : list of (int, float)
        (spp, mean noise floor over the mask) after each round.
    stop : str
        Why the rounds stopped, one line (empty without a target).
    render_s : dict
        Seconds spent rendering each image.
    """

    images: dict
    spp: int
    noise_floor: np.ndarray
    history: list
    stop: str
    render_s: dict


def render_comparison(mi, scenes: dict, settings: RenderSettings, mask, *, target_noise: float | None = None,
                      max_spp: int = MAX_SPP_DEFAULT, budget_s: float | None = None, progress=None) -> Comparison:
    """Render ``scenes["wave"]`` twice (seeds :data:`SEED_STREAMS`) and ``scenes["reference"]`` at
    ``settings.spp``; with *target_noise* (ΔE2000) double the samples per pixel of all three, by adding as many
    again with new seeds, until the mean noise floor over *mask* (module doc) is below it, the next doubling would
    pass *max_spp*, or it would pass *budget_s* seconds in all (each doubling costs about what the renders so far
    cost).

    *progress* is called as ``progress(done, total)`` (render passes) after each pass.

    References
    ----------
    .. [1] E. Veach, PhD thesis, Stanford, 1997, §2.4 (the standard error of a Monte Carlo estimate ∝ 1/√N).
    """
    import time

    if target_noise is not None and not (np.isfinite(target_noise) and target_noise > 0):
        raise FieldError(f"{{target_noise}} {target_noise!r} is not allowed; give a ΔE2000 > 0", "target_noise")
    if not (isinstance(max_spp, (int, np.integer)) and max_spp >= settings.spp):
        raise FieldError(f"{{max_spp}} {max_spp!r} is not allowed; give at least the samples per pixel "
                         f"({settings.spp})", "max_spp")
    if budget_s is not None and not (np.isfinite(budget_s) and budget_s > 0):
        raise FieldError(f"{{budget}} {budget_s!r} s is not allowed; give seconds > 0", "budget")
    t_start = time.perf_counter()
    keys = ("wave", "wave_repeat", "reference")
    runs = {k: Progressive(mi, scenes["reference" if k == "reference" else "wave"], settings.size, SEED_STREAMS[k])
            for k in keys}
    passes = max(1, min(int(settings.passes), int(settings.spp)))
    state = {"done": 0, "total": 3 * passes}
    render_s = dict.fromkeys(keys, 0.0)

    def tick(_):
        state["done"] += 1
        if progress is not None:
            progress(state["done"], state["total"])

    def round_(spp):
        for k in keys:
            t0 = time.perf_counter()
            runs[k].add(spp, passes, tick)
            render_s[k] += time.perf_counter() - t0
        de = delta_e_map(runs["wave"].image, runs["wave_repeat"].image)
        history.append((runs["wave"].spp, float(np.mean(de[mask]))))
        return de

    history = []
    de = round_(settings.spp)
    stop = ""
    while target_noise is not None:
        spp, floor = history[-1]
        if floor < target_noise:
            stop = f"noise floor {floor:.3g} ΔE2000 is below the target {target_noise:g} at {spp} spp"
            break
        elapsed = time.perf_counter() - t_start
        if 2 * spp > max_spp:
            stop = (f"stopped at {spp} spp (the most samples per pixel, {max_spp}): noise floor {floor:.3g} ΔE2000, "
                    f"target {target_noise:g}")
            break
        if budget_s is not None and 2 * elapsed > budget_s:
            stop = (f"stopped at {spp} spp (the next doubling, about {elapsed:.0f} s, would pass the time budget "
                    f"{budget_s:g} s): noise floor {floor:.3g} ΔE2000, target {target_noise:g}")
            break
        state["total"] += 3 * passes
        de = round_(spp)
    return Comparison(images={k: runs[k].image for k in keys}, spp=runs["wave"].spp, noise_floor=de,
                      history=history, stop=stop, render_s=render_s)


def delta_e_map(rgb_a, rgb_b) -> np.ndarray:
    """CIEDE2000 per pixel between two linear sRGB images (:func:`waveoptics.colour.delta_e2000`)."""
    return colour.delta_e2000(rgb_a, rgb_b)
