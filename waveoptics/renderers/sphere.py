"""Pictures of BRDFs: spheres lit by a directional light, hemisphere previews, lobe cross-sections.

Sphere renders use an orthographic camera looking down −z (towards the sphere, so ω_o = +z in world space) and a
directional light of irradiance π (a white Lambertian sphere facing the light is 1.0). Every pixel evaluates the
BRDF function (:class:`waveoptics.brdf.BRDF`) at its own local (ω_i, ω_o): no table over incidence is
interpolated in absolute directions. The surface's tangent frame is fixed on the sphere (its x axis is the
projection of the world x axis onto the tangent plane), so anisotropic surfaces keep their orientation and the
light's azimuth in each pixel. Radiance spectra are integrated to linear sRGB with :mod:`waveoptics.colour`
(colour-science underneath).

References
----------
.. [1] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., §4.5 (radiometry of a
   directional light), §9.1 (BRDF frames).
.. [2] E. Reinhard et al., "Photographic tone reproduction for digital images", SIGGRAPH 2002 (global operator).
"""
from __future__ import annotations

import numpy as np
from colour import cctf_encoding  # colour-science (this package's own colour sub-package is imported below)

from .. import colour
from ..colour import reflectance_to_rgb_matrix
from ..io import figures

__all__ = ['sphere_geometry', 'tangent_frames', 'local_directions', 'PIXEL_CHUNK', 'render_sphere',
           'render_sphere_environment', 'KEY', 'EXPOSURE_MAX', 'key_exposure',
           'percentile_exposure', 'tonemap',
           'plot_spheres', 'SKIPPED_KEY', 'skipped_spheres']

#: how an output names the sphere renders in its ``skipped`` entry (what was not computed → why)
SKIPPED_KEY = "sphere renders"


def skipped_spheres(reason: str) -> dict:
    """The ``skipped`` entry of an output made without the sphere renders, ``{"sphere renders": reason}``: *reason*
    says why (e.g. "not asked (sphere=False)"). ``waveoptics simulate``'s summary.json carries it, and so does each
    row of a sweep table whose ΔE2000 columns over sphere renders are therefore null (not computed, not 0)."""
    return {SKIPPED_KEY: reason}


def sphere_geometry(size: int):
    """Normals (size, size, 3) of a unit sphere seen orthographically, and the mask of pixels on it."""
    c = (np.arange(size) + 0.5) / size * 2 - 1
    X, Y = np.meshgrid(c, -c)
    r2 = X * X + Y * Y
    mask = r2 < 1.0
    n = np.stack([X, Y, np.sqrt(np.clip(1 - r2, 0, 1))], axis=-1)
    return n, mask


def tangent_frames(n):
    """Tangent t (the world x axis projected onto the tangent plane) and bitangent b = n × t of normals (..., 3).

    Defined wherever n ≠ ±x, i.e. everywhere on the visible disc of a sphere seen along −z except its silhouette.
    """
    x = np.array([1.0, 0.0, 0.0])
    t = x - n[..., :1] * n
    t = t / np.maximum(np.linalg.norm(t, axis=-1, keepdims=True), 1e-12)
    return t, np.cross(n, t)


def local_directions(normals, light_world, view_world=(0.0, 0.0, 1.0)):
    """Light and view directions in each pixel's tangent frame (:func:`tangent_frames`): (ω_i, ω_o), (..., 3)."""
    t, b = tangent_frames(normals)
    L = np.asarray(light_world, dtype=float)
    V = np.asarray(view_world, dtype=float)
    wi = np.stack([t @ L, b @ L, normals @ L], axis=-1)
    wo = np.stack([t @ V, b @ V, normals @ V], axis=-1)
    return wi, wo


#: pixels evaluated per call of the BRDF (bounds the memory of per-pixel spectra)
PIXEL_CHUNK = 8192


def render_sphere(brdf_fn, wavelengths_nm, light_world, *, size=256, illuminant="D65", space="sRGB"):
    """Linear RGB image (size, size, 3) of a sphere with the BRDF function *brdf_fn* under a directional light.

    Parameters
    ----------
    brdf_fn : waveoptics.brdf.BRDF
        Evaluated per pixel at every wavelength (``eval(wi, wo, wavelength_nm)``).
    wavelengths_nm : array_like
        Wavelengths (nm) of the radiance spectra.
    light_world : array_like (3,)
        Direction to the light in world space (the camera looks down −z).

    Returns
    -------
    rgb : ndarray (size, size, 3)
        Linear RGB radiance (white Lambertian facing the light = 1); 0 off the sphere and in shadow.
    mask : ndarray of bool (size, size)
        Pixels on the lit part of the sphere.
    """
    n, on = sphere_geometry(size)
    L = np.asarray(light_world, dtype=float)
    L = L / np.linalg.norm(L)
    w = np.asarray(wavelengths_nm, dtype=float)
    wi, wo = local_directions(n[on], L)
    lit = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    spec = np.zeros((on.sum(), w.size))
    idx_lit = np.flatnonzero(lit)
    for a in range(0, idx_lit.size, PIXEL_CHUNK):
        sel = idx_lit[a:a + PIXEL_CHUNK]
        f = brdf_fn.eval(wi[sel, None, :], wo[sel, None, :], w[None, :])
        spec[sel] = np.pi * f * wi[sel, 2:3]
    rgb = np.zeros((size, size, 3))
    rgb[on] = colour.reflectance_to_rgb(spec, w, illuminant, space=space)
    mask = np.zeros((size, size), bool)
    idx = np.argwhere(on)
    mask[idx[lit][:, 0], idx[lit][:, 1]] = True
    return rgb, mask


def render_sphere_environment(brdf_fn, wavelengths_nm, env, *, size=128, spp=16, seed=0, illuminant="D65",
                              sample_wavelength_nm=None, progress=None):
    """Linear RGB image (size, size, 3) of a sphere with the BRDF *brdf_fn* under an environment map.

    Reflected radiance ∫ f(ω_i, ω_o) L(ω_i) cos θ_i dω_i per pixel by multiple importance sampling (balance
    heuristic, Veach & Guibas 1995): *spp* directions from the BRDF's own sampler (``sample`` with the view as its
    first direction, at *sample_wavelength_nm*, default the wavelength nearest 555 nm) and *spp* from the map's
    luminance (:class:`waveoptics.renderers.lighting.Environment`). The BRDF spectrum of every sample becomes RGB through
    :func:`waveoptics.colour.reflectance_to_rgb_matrix` and multiplies the map's RGB radiance (the usual RGB product: exact for a
    spectrally flat map). A white Lambertian sphere in a constant map of radiance 1 is 1.

    Returns
    -------
    rgb : ndarray (size, size, 3)
    mask : ndarray of bool (size, size)
        Pixels on the sphere.
    """
    w = np.asarray(wavelengths_nm, dtype=float)
    lam_s = float(w[np.argmin(np.abs(w - 555.0))]) if sample_wavelength_nm is None else float(sample_wavelength_nm)
    M = reflectance_to_rgb_matrix(w, illuminant)
    n, on = sphere_geometry(size)
    n = n[on]
    t, b = tangent_frames(n)
    view = np.array([0.0, 0.0, 1.0])
    wo = np.stack([t @ view, b @ view, n @ view], axis=-1)
    rng = np.random.default_rng(seed)
    acc = np.zeros((n.shape[0], 3))

    def to_world(d):
        return d[:, :1] * t + d[:, 1:2] * b + d[:, 2:3] * n

    def contribution(light_local, p_self, p_other):
        up = (light_local[:, 2] > 0) & (p_self > 0)
        li = np.where(up[:, None], light_local, [0.0, 0.0, 1.0])
        f = brdf_fn.eval(li[:, None, :], wo[:, None, :], w[None, :])             # (n, n_λ)
        weight = np.where(up, li[:, 2] / np.where(up, p_self + p_other, 1.0), 0.0)  # balance heuristic / pdf
        return (f @ M) * weight[:, None] * env.eval(to_world(li))

    for _ in range(int(spp)):
        s = brdf_fn.sample(wo, lam_s, rng.random((n.shape[0], 2)))
        ok = s.pdf > 0
        lw = to_world(np.where(ok[:, None], s.wo, [0.0, 0.0, 1.0]))
        acc += contribution(np.where(ok[:, None], s.wo, [0.0, 0.0, -1.0]), s.pdf, np.where(ok, env.pdf(lw), 0.0))
        lw = env.sample(rng.random((n.shape[0], 2)))
        ll = np.stack([np.sum(lw * t, -1), np.sum(lw * b, -1), np.sum(lw * n, -1)], axis=-1)
        p_b = brdf_fn.pdf(wo, np.where((ll[:, 2] > 0)[:, None], ll, [0.0, 0.0, 1.0]), lam_s)
        acc += contribution(ll, env.pdf(lw), np.where(ll[:, 2] > 0, p_b, 0.0))
        if progress is not None:
            progress(1)
    rgb = np.zeros((size, size, 3))
    rgb[on] = acc / int(spp)
    return rgb, on


#: the photographic key: the log-average luminance maps to this value (Reinhard et al. 2002)
KEY = 0.18
#: the largest automatic exposure, so that a nearly black image is not lifted into noise
EXPOSURE_MAX = 4.0


def key_exposure(rgb, mask=None, key: float = KEY) -> float:
    """The automatic exposure of a linear RGB image: *key* over the log-average luminance of its lit pixels
    (luminance > 1e-8, inside *mask* if given), at most :data:`EXPOSURE_MAX`; 1 for a black image. Every sphere
    picture (simulate, its environment renders, ``render``) uses this one rule, so a pair of images shares it.

    References
    ----------
    .. [1] E. Reinhard, M. Stark, P. Shirley, J. Ferwerda, "Photographic tone reproduction for digital images",
       ACM TOG 21(3), 2002, eq. (1) (the log-average luminance and the key value 0.18).
    """
    Y = colour.luminance(np.maximum(np.asarray(rgb, dtype=float), 0.0))
    if mask is not None:
        Y = Y[np.asarray(mask, dtype=bool)]
    lit = Y[Y > 1e-8]
    if not lit.size:
        return 1.0
    return float(min(key / np.exp(np.mean(np.log(lit))), EXPOSURE_MAX))


def percentile_exposure(images, mask=None, percentile: float = 99.0) -> float:
    """One exposure for sparse images (glints): the brightest image's *percentile* of luminance (inside *mask*)
    maps to 1. A log-average key would be set by the dark background and burn every glint out."""
    peaks = []
    for img in images:
        Y = colour.luminance(np.maximum(np.asarray(img, dtype=float), 0.0))
        peaks.append(float(np.percentile(Y[np.asarray(mask, dtype=bool)] if mask is not None else Y, percentile)))
    peak = max(peaks)
    return 1.0 / peak if peak > 0 else 1.0


def tonemap(rgb, exposure: float | None = None):
    """Display sRGB in [0, 1] from linear RGB: Reinhard's global operator on luminance, then the sRGB curve.

    *exposure* scales the input first (default: :func:`key_exposure` of the image).
    """
    rgb = np.maximum(np.asarray(rgb, dtype=float), 0.0)
    Y = colour.luminance(rgb)
    if exposure is None:
        exposure = key_exposure(rgb)
    Ys = Y * exposure
    scale = np.where(Y > 0, (Ys / (1 + Ys)) / np.maximum(Y, 1e-30), 0.0)
    out = rgb * scale[..., None]
    return np.clip(cctf_encoding(np.clip(out, 0, 1), function="sRGB"), 0, 1)


def plot_spheres(images, titles, path, *, overwrite=True, diff=None, diff_title="ΔE2000", light_deg=None,
                 exposure=None, caption=None):
    """A row of tone-mapped sphere renders (shared exposure), optionally with a ΔE2000 map.

    Every panel keeps a square aspect (the colour bar is attached beside its panel, not carved out of it); the
    light direction *light_deg* (θ, φ), the *exposure* and a *caption* are written under the row.
    """
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    plt = figures.pyplot()
    n = len(images) + (diff is not None)
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 3.7))
    axes = np.atleast_1d(axes)
    for ax, img, title in zip(axes, images, titles):
        ax.imshow(img)
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal")
        ax.axis("off")
    if diff is not None:
        im = axes[-1].imshow(diff, cmap="magma", vmin=0)
        axes[-1].set_title(diff_title, fontsize=9)
        axes[-1].set_aspect("equal")
        axes[-1].axis("off")
        cax = make_axes_locatable(axes[-1]).append_axes("right", size="5%", pad=0.05)
        fig.colorbar(im, cax=cax)
    notes = []
    if light_deg is not None:
        notes.append(f"directional light at θ = {light_deg[0]:g}°, φ = {light_deg[1]:g}° (camera looks down −z, "
                     "x right, y up)")
    if exposure is not None:
        notes.append(f"exposure × {exposure:.3g}, Reinhard tone map, sRGB")
    if caption:
        notes.append(caption)
    if notes:
        fig.text(0.5, 0.02, "; ".join(notes), ha="center", fontsize=8)
    figures.save_figure(fig, path, overwrite=overwrite)
