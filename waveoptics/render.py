"""Pictures of BRDFs: spheres lit by a directional light, hemisphere previews, lobe cross-sections.

Sphere renders use an orthographic camera looking down −z (towards the sphere, so ω_o = +z in world space) and a
directional light of irradiance π (a white Lambertian sphere facing the light is 1.0). Each pixel's BRDF is
looked up in a table of lobes on the direction-cosine grid, tabulated over incidence angles θ_i with the light's
azimuth rotated to φ = 0, i.e. the surface is treated as azimuthally isotropic (state this for anisotropic nano
surfaces such as gratings, whose lobes then follow the local plane of incidence). Radiance spectra are integrated
to linear sRGB with :mod:`waveoptics.colour` (colour-science underneath).

References
----------
.. [1] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., §4.5 (radiometry of a
   directional light), §9.1 (BRDF frames).
.. [2] E. Reinhard et al., "Photographic tone reproduction for digital images", SIGGRAPH 2002 (global operator).
"""
from __future__ import annotations

import numpy as np
from colour import cctf_encoding  # colour-science (this package's own colour sub-package is imported below)

from . import colour
from .io import figures
from .scatter.grid import DirectionGrid

__all__ = ['sphere_geometry', 'local_directions', 'lookup', 'render_sphere', 'tonemap', 'plot_spheres']

def sphere_geometry(size: int):
    """Normals (size, size, 3) of a unit sphere seen orthographically, and the mask of pixels on it."""
    c = (np.arange(size) + 0.5) / size * 2 - 1
    X, Y = np.meshgrid(c, -c)
    r2 = X * X + Y * Y
    mask = r2 < 1.0
    n = np.stack([X, Y, np.sqrt(np.clip(1 - r2, 0, 1))], axis=-1)
    return n, mask


def _frames(n):
    """Tangent t and bitangent b for normals n (..., 3), continuous away from the poles of the y axis."""
    up = np.broadcast_to(np.array([0.0, 1.0, 0.0]), n.shape)
    t = np.cross(up, n)
    norm = np.linalg.norm(t, axis=-1, keepdims=True)
    alt = np.cross(np.broadcast_to(np.array([1.0, 0.0, 0.0]), n.shape), n)
    t = np.where(norm > 1e-6, t / np.maximum(norm, 1e-12), alt / np.maximum(np.linalg.norm(alt, axis=-1,
                                                                                          keepdims=True), 1e-12))
    b = np.cross(n, t)
    return t, b


def local_directions(normals, light_world, view_world=(0.0, 0.0, 1.0)):
    """θ_i (rad) and the outgoing direction's (u, v) with the light's azimuth rotated to φ = 0, per pixel."""
    t, b = _frames(normals)
    L = np.asarray(light_world, dtype=float)
    V = np.asarray(view_world, dtype=float)
    li = np.stack([t @ L, b @ L, normals @ L], axis=-1)
    lo = np.stack([t @ V, b @ V, normals @ V], axis=-1)
    phi_i = np.arctan2(li[..., 1], li[..., 0])
    c, s = np.cos(-phi_i), np.sin(-phi_i)
    u = c * lo[..., 0] - s * lo[..., 1]
    v = s * lo[..., 0] + c * lo[..., 1]
    theta_i = np.arccos(np.clip(li[..., 2], -1, 1))
    return theta_i, u, v, li[..., 2], lo[..., 2]


def lookup(table, thetas_rad, grid: DirectionGrid, theta_i, u, v):
    """Bilinear in (u, v) and linear in θ_i lookup of ``table[iθ, λ, v, u]`` → (..., n_λ)."""
    thetas_rad = np.asarray(thetas_rad)
    ti = np.interp(theta_i, thetas_rad, np.arange(thetas_rad.size))
    i0 = np.clip(np.floor(ti).astype(int), 0, thetas_rad.size - 1)
    i1 = np.clip(i0 + 1, 0, thetas_rad.size - 1)
    wt = ti - i0
    fu = (u - grid.u_range[0]) / grid.du - 0.5
    fv = (v - grid.v_range[0]) / grid.dv - 0.5
    j0 = np.clip(np.floor(fu).astype(int), 0, grid.n_u - 2)
    k0 = np.clip(np.floor(fv).astype(int), 0, grid.n_v - 2)
    au = np.clip(fu - j0, 0, 1)
    av = np.clip(fv - k0, 0, 1)

    out = 0.0
    for it, w_t in ((i0, 1 - wt), (i1, wt)):
        for dk, w_v in ((0, 1 - av), (1, av)):
            for dj, w_u in ((0, 1 - au), (1, au)):
                # advanced indices separated by a slice: the pixel axis comes first -> (n_pix, n_λ)
                vals = table[it, :, k0 + dk, j0 + dj]
                out = out + vals * (w_t * w_v * w_u)[..., None]
    return out


def render_sphere(table, thetas_rad, grid: DirectionGrid, wavelengths_nm, light_world, *, size=256,
                  illuminant="D65", space="sRGB"):
    """Linear RGB image (size, size, 3) of a sphere with BRDF ``table[iθ, λ, v, u]`` under a directional light.

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
    theta_i, u, v, cos_i, cos_o = local_directions(n[on], L)
    lit = (cos_i > 0) & (cos_o > 0)
    spec = np.zeros((on.sum(), len(wavelengths_nm)))
    f = lookup(table, thetas_rad, grid, theta_i[lit], u[lit], v[lit])
    spec[lit] = np.pi * f * cos_i[lit][:, None]
    rgb = np.zeros((size, size, 3))
    rgb[on] = colour.reflectance_to_rgb(spec, wavelengths_nm, illuminant, space=space)
    mask = np.zeros((size, size), bool)
    idx = np.argwhere(on)
    mask[idx[lit][:, 0], idx[lit][:, 1]] = True
    return rgb, mask


def tonemap(rgb, exposure: float | None = None):
    """Display sRGB in [0, 1] from linear RGB: Reinhard's global operator on luminance, then the sRGB curve.

    *exposure* scales the input first (default: key 0.18 at the log-average luminance of the non-zero pixels).
    """
    rgb = np.maximum(np.asarray(rgb, dtype=float), 0.0)
    Y = colour.luminance(rgb)
    if exposure is None:
        pos = Y[Y > 1e-8]
        exposure = 0.18 / np.exp(np.mean(np.log(pos))) if pos.size else 1.0
        exposure = min(exposure, 4.0)
    Ys = Y * exposure
    scale = np.where(Y > 0, (Ys / (1 + Ys)) / np.maximum(Y, 1e-30), 0.0)
    out = rgb * scale[..., None]
    return np.clip(cctf_encoding(np.clip(out, 0, 1), function="sRGB"), 0, 1)


def plot_spheres(images, titles, path, *, overwrite=True, diff=None, diff_title="ΔE2000"):
    """A row of tone-mapped sphere renders (shared exposure), optionally with a ΔE2000 map."""
    plt = figures.pyplot()
    n = len(images) + (diff is not None)
    fig, axes = plt.subplots(1, n, figsize=(3.2 * n, 3.4))
    axes = np.atleast_1d(axes)
    for ax, img, title in zip(axes, images, titles):
        ax.imshow(img)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    if diff is not None:
        im = axes[-1].imshow(diff, cmap="magma", vmin=0)
        axes[-1].set_title(diff_title, fontsize=9)
        axes[-1].axis("off")
        fig.colorbar(im, ax=axes[-1], fraction=0.046, pad=0.04)
    figures.save_figure(fig, path, overwrite=overwrite)
