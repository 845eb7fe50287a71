"""Which roughness scatters: the propagating band of surface frequencies and the relevant rms roughness
(docs/physics.md §9).

A surface frequency f scatters light of wavelength λ incident at (θ_i, φ_i) into the direction whose direction
cosines are (u, v) = −(sinθ_i cosφ_i, sinθ_i sinφ_i) − λ f (grating equation; the sign follows ω_i pointing
towards the light). The direction propagates only when |(u, v)| ≤ 1, so the frequencies that scatter at all fill
the disc

    |f + (sinθ_i cosφ_i, sinθ_i sinφ_i) / λ| ≤ 1 / λ

of the frequency plane: centred on −sinθ_i/λ (along the incident azimuth), radius 1/λ. Its share of the height
variance is the relevant roughness

    σ_rel² = ∫∫_band S(f_x, f_y) df_x df_y  ≤  σ²,

and the rest, σ² − σ_rel², lies in evanescent orders: it neither scatters nor (in the generalized Harvey-Shack
theory) reduces the specular reflection, exp(−(4π σ_rel cosθ_i / λ)²). A model that uses the full σ in exp(−g)
while its diffracted lobe receives only the band loses the difference (docs/physics.md §9).

For an isotropic PSD the band integral reduces to one radial integral: the circle |f| = r lies inside the disc
for r ≤ 1/λ − s and meets it in an arc of angle 2 arccos((r² + s² − 1/λ²) / (2 r s)) for |1/λ − s| < r < 1/λ + s,
with s = sinθ_i / λ.

References
----------
.. [1] A. Krywonos, J. E. Harvey, N. Choi, "Linear systems formulation of scattering theory for rough surfaces
   with arbitrary incident and scattering angles", JOSA A 28(6), 1121–1138, 2011 (relevant roughness).
.. [2] J. E. Harvey, N. Choi, S. Schröder, A. Duparré, "Total integrated scatter from surfaces with arbitrary
   roughness, correlation widths, and incident angles", Opt. Eng. 51(1) 013402, 2012.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..surfaces.heightfield import HeightField
from ..surfaces.psd import PSDModel
from ..surfaces.statistics import detrended

__all__ = ["band_arc", "relevant_variance", "relevant_variance_of_field", "beyond_band_fraction"]


def band_arc(r, sin_theta_i, wavelength_nm):
    """Angle (radians, 0 … 2π) of the circle |f| = r (1/m) that lies inside the propagating band."""
    R = 1.0 / (np.asarray(wavelength_nm, dtype=float) * 1e-9)
    s = np.asarray(sin_theta_i, dtype=float) * R
    r = np.asarray(r, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_half = (r * r + s * s - R * R) / (2 * r * s)
    arc = 2 * np.arccos(np.clip(np.nan_to_num(cos_half, nan=-1.0), -1.0, 1.0))
    # guard: s = 0 (normal incidence) or r = 0 make the ratio undefined: inside ⇔ r + s ≤ R there
    return np.where(r + s <= R, 2 * np.pi, np.where(r >= R + s, 0.0, arc))


def relevant_variance(model: PSDModel, wavelength_nm: float, sin_theta_i: float) -> float:
    """σ_rel² (m²): the height variance of *model* inside the propagating band at (λ, sinθ_i).

    The radial integral ∫ S(r) arc(r) r dr is split at the band's edges (r = 1/λ − s and 1/λ + s), where its
    integrand has kinks, and integrated adaptively (scipy.integrate.quad, relative tolerance 1e-10).
    """
    R = 1.0 / (float(wavelength_nm) * 1e-9)
    s = float(sin_theta_i) * R
    edges = sorted({0.0, max(R - s, 0.0), R + s})

    def integrand(r):
        return float(model.S(r)) * float(band_arc(r, sin_theta_i, wavelength_nm)) * r

    total = 0.0
    scale = 1.0 / model.length_scale
    for a, b in zip(edges[:-1], edges[1:]):
        if b <= a:
            continue
        # the PSD falls off on the scale 1/T (or 1/B): tell quad where its knee is
        pts = [x for x in (0.1 * scale, scale, 10 * scale) if a < x < b]
        val, _ = integrate.quad(integrand, a, b, points=pts or None, limit=400, epsrel=1e-10, epsabs=0.0)
        total += val
    return total


def relevant_variance_of_field(hf: HeightField, wavelength_nm: float, sin_theta_i: float,
                               phi_i_deg: float = 0.0) -> float:
    """σ_rel² (m²) of a height field: the periodogram of its detrended heights summed over the band.

    By Parseval the sum over all frequencies is the field's variance; a periodic field (no window) gives the
    exact split, a masked or non-periodic one the split of its samples as they are.
    """
    h = detrended(hf)
    ny, nx = hf.shape
    valid = hf.valid
    n = int(valid.sum())
    P = np.abs(np.fft.fft2(np.where(valid, h, 0.0))) ** 2 / (n * nx * ny)
    fy = np.fft.fftfreq(ny, hf.dy)[:, None]
    fx = np.fft.fftfreq(nx, hf.dx)[None, :]
    R = 1.0 / (float(wavelength_nm) * 1e-9)
    c = float(sin_theta_i) * R
    phi = math.radians(phi_i_deg)
    inside = np.hypot(fx + c * math.cos(phi), fy + c * math.sin(phi)) <= R
    inside[0, 0] = False  # the mean is not roughness
    return float(np.sum(P[inside]))


def beyond_band_fraction(sigma2_total: float, sigma2_band: float) -> float:
    """(σ² − σ_rel²) / σ²: the share of the height variance that does not scatter (0 for a flat surface)."""
    if sigma2_total <= 0:
        return 0.0
    # guard: quadrature round-off can put σ_rel² a hair (1e-10 relative) above σ²
    return max(0.0, 1.0 - sigma2_band / sigma2_total)
