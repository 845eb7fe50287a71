"""Glint renders: a plane textured by a large height field, seen by a perspective camera under a small light, where
every pixel's footprint gives its own BRDF — in wave optics and in geometric optics, side by side (Yan et al. 2014,
2016, 2018).

Geometry (world = the surface's frame): the height field lies on the plane z = 0 with its first sample at the
origin, x along the grid's axis 1 and y along axis 0. The camera looks at the field's centre from elevation
θ_v (from the normal) and azimuth φ_v; the light is a point at elevation θ_l, azimuth φ_l and the same distance.
For each pixel the ray through its centre meets the plane at c; the pixel filter (a Gaussian of ``filter_px``
pixels) maps to the footprint Σ = J diag(s², s²) Jᵀ on the plane, with J the change of c per pixel (finite
differences): an ellipse that stretches along the view direction at oblique views (Yan et al. 2014, §5).

Per pixel, with ω_i towards the light and ω_o towards the camera (both from c):

* wave optics: f = F(θ_d) K |Σ_j G_j e^{i k (ω_i + ω_o)·r_j} ΔxΔy|² / (λ² Σ_j G_j² ΔxΔy), the windowed
  Kirchhoff integral of the footprint (:mod:`waveoptics.scatter.footprint`) at this one direction pair;
* geometric optics: f = F(θ_d) D(h) / (4 cos θ_i cos θ_o) with D the footprint's facet-normal distribution, each
  facet smoothed by a Gaussian of rms slope ``intrinsic_slope`` per axis (Yan et al. 2016's intrinsic roughness:
  the histogram of a few hundred facets is otherwise a set of spikes), D = P22(s_h)/cos⁴θ_h (Heitz 2014); no
  shadowing (as Yan et al.).

The radiance is L = f cos θ_i I / d² for a light of intensity I (W/sr per unit spectrum) at distance d, summed to
linear sRGB with the colour-matching functions (:func:`waveoptics.colour.reflectance_to_rgb_matrix`, the light's
spectrum white). Wavelengths are few (the glint's colour comes from diffraction's λ dependence).

References
----------
.. [1] L.-Q. Yan, M. Hašan, W. Jakob, J. Lawrence, S. Marschner, R. Ramamoorthi, ACM TOG 33(4), 116, 2014.
.. [2] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, ACM TOG 35(4), 56, 2016 (intrinsic roughness).
.. [3] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, ACM TOG 37(4), 75, 2018.
.. [4] E. Heitz, JCGT 3(2), 2014 (D from the slope distribution).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .. import colour
from ..errors import FieldError
from ..materials import get_material
from ..surfaces.footprint import Footprint, footprint_patch

__all__ = ["GlintSettings", "GlintRender", "camera_rays", "render_glints"]


@dataclass(frozen=True)
class GlintSettings:
    """Camera, light and sampling of a glint render (angles in degrees, sizes in pixels).

    Parameters
    ----------
    size : int
        Image width and height (pixels).
    view_deg, view_azimuth_deg : float
        Camera elevation from the normal and azimuth.
    light_deg, light_azimuth_deg : float
        Light elevation and azimuth (a point light at the camera's distance).
    fov_deg : float
        Horizontal field of view; default: the field's width fills the image at the centre.
    filter_px : float
        Width (σ, pixels) of the Gaussian pixel filter that makes the footprint.
    intrinsic_slope : float
        rms slope per axis of each facet in the geometric NDF (Yan et al. 2016's intrinsic roughness).
    wavelengths_nm : tuple
        Wavelengths (nm) summed to RGB.
    """

    size: int = 64
    view_deg: float = 30.0
    view_azimuth_deg: float = 180.0
    light_deg: float = 30.0
    light_azimuth_deg: float = 0.0
    fov_deg: float | None = None
    filter_px: float = 0.5
    intrinsic_slope: float = 0.01
    wavelengths_nm: tuple = (450.0, 500.0, 550.0, 600.0, 650.0)

    def __post_init__(self):
        if not (isinstance(self.size, (int, np.integer)) and 4 <= self.size <= 2048):
            raise FieldError(f"{{sphere_size}} {self.size!r} px is not allowed; give 4 to 2048", "sphere_size")
        for name in ("view_deg", "light_deg"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v < 89):
                raise FieldError(f"{name}={v!r} is not allowed; an elevation must be in [0, 89) degrees", name)
        if not (self.filter_px > 0 and self.intrinsic_slope > 0):
            raise FieldError("filter_px and intrinsic_slope must be > 0", "filter_px")


@dataclass
class GlintRender:
    """Linear sRGB images (size, size, 3) of the wave and geometric renders (saturated diffraction colours can lie
    outside the sRGB gamut: negative components), their radiance spectra (size, size, n_λ), the mask of pixels
    on the field, timings (s) and the median footprint widths (m)."""

    wave: np.ndarray
    geometric: np.ndarray
    on_field: np.ndarray
    timings_s: dict
    footprint_sigma_m: tuple
    wave_spectral: np.ndarray
    geometric_spectral: np.ndarray


def _dir(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def camera_rays(field, s: GlintSettings):
    """(camera position (3,), plane points c (size, size, 3), Jacobian dc/dpixel (size, size, 2, 2), distance) of
    the pinhole camera of *s* looking at the centre of *field* (see the module doc)."""
    ny, nx = field.shape
    W, H = nx * field.dx, ny * field.dy
    centre = np.array([W / 2, H / 2, 0.0])
    dist = 1.5 * max(W, H)
    eye = centre + dist * _dir(s.view_deg, s.view_azimuth_deg)
    fwd = (centre - eye) / np.linalg.norm(centre - eye)
    up0 = np.array([0.0, 0.0, 1.0]) if abs(fwd[2]) < 0.999 else np.array([0.0, 1.0, 0.0])
    right = np.cross(fwd, up0)
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    fov = math.radians(s.fov_deg) if s.fov_deg else 2 * math.atan(0.5 * min(W, H) / dist)
    half = math.tan(fov / 2)

    def hit(px, py):
        x = ((px + 0.5) / s.size * 2 - 1) * half
        y = (1 - (py + 0.5) / s.size * 2) * half
        d = fwd + x[..., None] * right + y[..., None] * up
        t = -eye[2] / d[..., 2]
        return eye + t[..., None] * d

    py, px = np.meshgrid(np.arange(s.size, dtype=float), np.arange(s.size, dtype=float), indexing="ij")
    c = hit(px, py)
    J = np.stack([hit(px + 0.5, py) - hit(px - 0.5, py), hit(px, py + 0.5) - hit(px, py - 0.5)], axis=-1)[..., :2, :]
    return eye, c, J, dist


def _footprint(c, J, filter_px):
    """The Gaussian footprint of a pixel: Σ = J diag(s², s²) Jᵀ as (σ_x, σ_y, angle) of its principal axes."""
    C = (filter_px ** 2) * (J @ J.T)
    vals, vecs = np.linalg.eigh(C)
    angle = math.degrees(math.atan2(vecs[1, 1], vecs[0, 1]))
    return Footprint(float(c[0]), float(c[1]), float(math.sqrt(vals[1])), float(math.sqrt(max(vals[0], 1e-30))),
                     angle)


def _wave_f(patch, G, wi, wo, lam_nm, F):
    """Windowed Kirchhoff BRDF (1/sr) of one footprint at one direction pair, per wavelength (n_λ,)."""
    ny, nx = patch.shape
    x = np.arange(nx) * patch.dx
    y = np.arange(ny) * patch.dy
    w2 = G * G
    h = patch.heights - np.sum(w2 * patch.heights) / np.sum(w2)
    area = np.sum(w2) * patch.dx * patch.dy
    s = wi + wo
    ci, co = wi[2], wo[2]
    out = np.empty(len(lam_nm))
    for i, lam in enumerate(lam_nm):
        k = 2 * np.pi / (lam * 1e-9)
        phase = np.exp(1j * k * s[0] * x)[None, :] * np.exp(1j * k * s[1] * y)[:, None] * np.exp(1j * k * s[2] * h)
        U = np.sum(G * phase) * patch.dx * patch.dy
        K = np.dot(s, s) ** 2 / (4 * (lam * 1e-9) ** 2 * ci * co * (ci + co) ** 2)
        out[i] = F[i] * K * abs(U) ** 2 / area
    return out


def _geometric_f(patch, G, wi, wo, F, slope_sigma):
    """Footprint microfacet BRDF (1/sr) at one direction pair, per wavelength."""
    h = wi + wo
    h = h / np.linalg.norm(h)
    sxh, syh = -h[0] / h[2], -h[1] / h[2]
    gx = np.gradient(patch.heights, patch.dx, axis=1)
    gy = np.gradient(patch.heights, patch.dy, axis=0)
    kern = np.exp(-0.5 * ((gx - sxh) ** 2 + (gy - syh) ** 2) / slope_sigma ** 2) / (2 * np.pi * slope_sigma ** 2)
    P22 = np.sum(G * kern) / np.sum(G)
    D = P22 / h[2] ** 4
    return F * D / (4 * wi[2] * wo[2])


def render_glints(field, material, settings: GlintSettings = GlintSettings(), *, progress=None) -> GlintRender:
    """Render *field* (HeightField or memory-mapped LargeHeightField) of *material* as described in the module
    doc; pixels whose footprint box leaves the field stay black (``on_field`` False)."""
    mat = get_material(material)
    lam = np.asarray(settings.wavelengths_nm, dtype=float)
    M = colour.reflectance_to_rgb_matrix(lam)
    eye, c, J, dist = camera_rays(field, settings)
    light = np.array([field.shape[1] * field.dx / 2, field.shape[0] * field.dy / 2, 0.0]) \
        + dist * _dir(settings.light_deg, settings.light_azimuth_deg)
    n = settings.size
    wave = np.zeros((n, n, len(lam)))
    geo = np.zeros((n, n, len(lam)))
    on = np.zeros((n, n), bool)
    t_wave = t_geo = 0.0
    sig = []
    for j in range(n):
        for i in range(n):
            try:
                fp = _footprint(c[j, i], J[j, i], settings.filter_px)
                patch, G = footprint_patch(field, fp)
            except FieldError:
                continue
            p = np.array([c[j, i, 0], c[j, i, 1], 0.0])
            wi, wo = light - p, eye - p
            r2 = float(wi @ wi)
            wi, wo = wi / math.sqrt(r2), wo / np.linalg.norm(wo)
            cos_d = float(np.clip(wi @ ((wi + wo) / np.linalg.norm(wi + wo)), 0.0, 1.0))
            F = mat.F(cos_d, lam)
            E = wi[2] / r2 * dist ** 2          # irradiance of a unit-intensity light, normalized at distance d
            t0 = time.perf_counter()
            wave[j, i] = _wave_f(patch, G, wi, wo, lam, F) * E
            t1 = time.perf_counter()
            geo[j, i] = _geometric_f(patch, G, wi, wo, F, settings.intrinsic_slope) * E
            t_wave += t1 - t0
            t_geo += time.perf_counter() - t1
            on[j, i] = True
            sig.append((fp.sigma, fp.sigma_y or fp.sigma))
        if progress is not None:
            progress(1)
    if not on.any():
        raise FieldError("no pixel's footprint lies inside the height field; use a larger field or image",
                         "surface")
    s = np.array(sig)
    return GlintRender(wave=wave @ M, geometric=geo @ M, on_field=on,
                       timings_s={"wave": t_wave, "geometric": t_geo, "pixels": int(on.sum()),
                                  "wave_per_pixel": t_wave / on.sum(), "geometric_per_pixel": t_geo / on.sum()},
                       footprint_sigma_m=(float(np.median(s[:, 0])), float(np.median(s[:, 1]))),
                       wave_spectral=wave, geometric_spectral=geo)
