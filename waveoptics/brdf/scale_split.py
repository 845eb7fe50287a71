"""Split a height field holding both scales into a micro NDF and a nano height field (:func:`split_scales`).

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017, §3 (scale separation).
.. [2] P. Beckmann, A. Spizzichino, 1963 (slope statistics).
"""
from __future__ import annotations

import numpy as np

from .. import surfaces
from ..errors import WaveopticsError
from ..surfaces.heightfield import HeightField
from ..units import check_wavelengths
from .ndf import NDFS
from .roughness_scales import Micro

__all__ = ['SPLIT_PERIODS_OF_LAMBDA', 'split_scales']


#: default split: spatial periods longer than this many λ_max are micro-geometry (geometric optics)
SPLIT_PERIODS_OF_LAMBDA = 10.0


def _alpha_of_slopes(hf, ndf, ndf_shape, sx, sy):
    """(α_x, α_y) of NDF *ndf* matching the slopes of *hf*: Beckmann √2 × rms slope per axis (exact for Gaussian
    slopes); GGX per axis from the median |slope| (√3 × median, :data:`waveoptics.brdf.ndf_fit.GGX_AXIS_MEDIAN`);
    the other (isotropic) NDFs from the median slope magnitude (:func:`waveoptics.brdf.alpha_for_median_slope`)."""
    from .ndf_fit import GGX_AXIS_MEDIAN, alpha_for_median_slope

    if ndf == "beckmann":
        return float(np.sqrt(2) * (sx if sx is not None else sy)), float(np.sqrt(2) * (sy if sy is not None else sx))
    gy, gx = np.gradient(hf.heights, hf.dy, hf.dx)
    if ndf == "ggx":
        return (float(np.median(np.abs(gx)) / GGX_AXIS_MEDIAN), float(np.median(np.abs(gy)) / GGX_AXIS_MEDIAN))
    a = alpha_for_median_slope(ndf, float(np.median(np.hypot(gx, gy))), ndf_shape)
    return a, a


def split_scales(surface: HeightField, wavelengths_nm, *, cutoff_period_m: float | None = None,
                 ndf: str = "beckmann", ndf_shape=None):
    """Split a height field holding both scales into a micro NDF and a nano height field.

    The surface spectrum is cut at the spatial frequency f_c = 1 / Λ_c (default Λ_c = 10 λ_max): components of
    longer period form the micro-geometry, the rest the nano-geometry. The split is a smooth (Gaussian-edged)
    partition of unity in frequency, so micro + nano = surface exactly. The micro part's slopes give the NDF
    roughness: for Gaussian slopes the Beckmann α along an axis is √2 times the rms slope along it
    (docs/physics.md §1: α = rms |∇h| = 2σ/T for an isotropic Gaussian surface); the other NDFs (*ndf*, with
    *ndf_shape*) match the median slope instead (:mod:`waveoptics.brdf.ndf_fit`: GGX has no finite rms slope).

    Why 10 λ_max: a component of period Λ deflects light by sin θ = λ/Λ; beyond 10 λ that is < 0.1 (6°), where
    a slope distribution describes the deflection (stationary phase, docs/physics.md §1), while shorter periods
    scatter into wide angles only diffraction describes. Pass *cutoff_period_m* to choose another scale.

    Returns
    -------
    micro : Micro
        NDF (α_x, α_y) from the micro part's slopes (α_y omitted when isotropic within 5 %).
    nano : HeightField
        The high-pass part (same grid).
    info : dict
        ``cutoff_period_m``, micro/nano rms heights and slopes.

    References
    ----------
    .. [1] Holzschuch & Pacanowski 2017, §3 (scale separation); Beckmann & Spizzichino 1963 (slope statistics).
    """

    w = check_wavelengths(wavelengths_nm)
    Lc = float(cutoff_period_m) if cutoff_period_m is not None else SPLIT_PERIODS_OF_LAMBDA * float(w.max()) * 1e-9
    if not np.isfinite(Lc) or Lc <= 0:
        raise WaveopticsError(f"cut-off period {cutoff_period_m!r} m is not allowed; it must be > 0")
    h = surface.heights - surface.heights.mean()
    ny, nx = h.shape
    fx = np.fft.fftfreq(nx, surface.dx)
    fy = np.fft.fftfreq(ny, surface.dy)
    f = np.hypot(fx[None, :], fy[:, None])
    low = np.exp(-np.log(2) * (f * Lc) ** 2)  # 1/2 at f = 1/Λ_c, smooth edge (no ringing)
    micro_h = np.real(np.fft.ifft2(np.fft.fft2(h) * low))
    nano_h = h - micro_h
    meta = dict(surface.meta)
    micro_hf = HeightField(micro_h, surface.dx, surface.dy, surface.mask, dict(meta))
    nano_hf = HeightField(nano_h, surface.dx, surface.dy, surface.mask, {**meta, "split_cutoff_period_m": Lc})
    sx, sy = surfaces.rms_slopes(micro_hf)
    ax, ay = _alpha_of_slopes(micro_hf, ndf, ndf_shape, sx, sy)
    iso = abs(ax - ay) <= 0.05 * max(ax, ay)
    if not iso and not NDFS[ndf].anisotropic:
        ax = ay = float(np.sqrt(ax * ay))   # the NDF has no anisotropic form: the geometric mean, said in info
        iso = True
    micro = Micro(alpha=float(np.sqrt(ax * ay)) if iso else float(ax), alpha_y=None if iso else float(ay), ndf=ndf,
                  ndf_shape=ndf_shape)
    info = {"cutoff_period_m": Lc, "micro_rms_height_m": float(micro_h.std()), "micro_rms_slopes": [sx, sy],
            "nano_rms_height_m": float(nano_h.std()), "micro_alpha": [float(ax), float(ay)]}
    return micro, nano_hf, info
