"""The fft solver: chirp-z transforms of the windowed field onto the common (u, v) grid, with v_z frozen
(order 0) or in bands with a Taylor series in Δv_z h (exact Kirchhoff to a tolerance).

References
----------
.. [1] L. R. Rabiner, R. W. Schafer, C. M. Rader, "The chirp z-transform algorithm", IEEE Trans. Audio
   Electroacoustics 17(2), 1969 (scipy.signal.ZoomFFT).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import WaveopticsError
from .grid import DirectionGrid
from .patch import Samples

__all__ = ['FFT_TOL', 'FFT_BAND_X', 'FFT_MAX_ORDER', 'fft_plan', 'field_fft']

#: highest Taylor order a user may ask of the fft solver (the heights' powers h^K underflow and the coefficients
#: overflow well before K = 150 for nanometre heights; 'auto' never needs more than a few tens per band)
FFT_MAX_ORDER = 60

#: relative tolerance (of Σ w) of the fft solver's Taylor series in "auto" order
FFT_TOL = 1e-8
#: largest |Δv_z h| (rad) a Taylor band may span in "auto" order (terms stay ≤ e^4, so no cancellation)
FFT_BAND_X = 4.0


# ----------------------------------------------------------------------------------------------------------------
# The fft solver: chirp-z transforms on the common (u, v) grid, frozen v_z or banded Taylor series
# ----------------------------------------------------------------------------------------------------------------

class _DTFT2:
    """DTFT of (ny, nx) arrays at the (u, v) grid of one wavelength: dx dy Σ g e^{2πi (ix a_x + iy a_y + c0)}."""

    def __init__(self, smp: Samples, wi, grid: DirectionGrid, wavelength_nm: float):

        lam = wavelength_nm * 1e-9
        ax = (wi[0] + grid.u) * smp.dx / lam          # cycles per sample, (n_u,)
        ay = (wi[1] + grid.v) * smp.dy / lam
        sx, sy = grid.du * smp.dx / lam, grid.dv * smp.dy / lam
        # zoom_fft computes Σ x[n] e^{-2πi n f}: ask for f = -a (steps may be negative)
        from scipy.signal import ZoomFFT   # scipy.signal costs ~0.4 s to import: only where it is used

        self._zx = ZoomFFT(smp.nx, [-ax[0], -ax[0] - grid.n_u * sx], grid.n_u, fs=1, endpoint=False)
        self._zy = ZoomFFT(smp.ny, [-ay[0], -ay[0] - grid.n_v * sy], grid.n_v, fs=1, endpoint=False)
        cx, cy = (smp.nx - 1) / 2.0, (smp.ny - 1) / 2.0
        self._px = np.exp(-2j * np.pi * cx * (ax - np.round(ax)))
        self._py = np.exp(-2j * np.pi * cy * (ay - np.round(ay)))
        self._scale = smp.dx * smp.dy

    def __call__(self, g: np.ndarray) -> np.ndarray:
        t = self._zx(g, axis=1)
        t = self._zy(t, axis=0)
        return t * (self._py[:, None] * self._px[None, :] * self._scale)


def _taylor_terms(x: float, tol: float) -> int:
    """Smallest K with x^(K+1)/(K+1)! ≤ tol (Lagrange bound of the remainder of exp(i y), |y| ≤ x)."""
    K, term = 0, x
    while term > tol and K < 400:
        K += 1
        term *= x / (K + 1)
    return K


def fft_plan(smp: Samples, wi, grid: DirectionGrid, wavelength_nm: float, order="auto",
             tol: float = FFT_TOL, frozen_cos_sum: float | None = None) -> list[tuple[float, int, np.ndarray]]:
    """Bands of the ``fft`` solver: a list of (cz_b in cycles/m, Taylor order K_b, boolean cell mask).

    ``order=0`` (or any int) gives one band expanded about the specular cz0 = 2 cos θ_i / λ to that order.
    ``order="auto"`` splits the range of cz = (cos θ_i + cos θ_o)/λ over the disc into bands no wider than
    |Δv_z h| ≤ 2 :data:`FFT_BAND_X` and picks K_b from the Lagrange bound so that the field is within
    *tol* · Σ w of the exact Kirchhoff sum. A model whose phase is frozen (*frozen_cos_sum*, v_z = k · that) needs
    one band and no expansion: its field is exactly one transform.
    """
    lam = wavelength_nm * 1e-9
    inside = grid.inside
    if frozen_cos_sum is not None:
        return [(float(frozen_cos_sum) / lam, 0, inside)]
    cz = (wi[2] + grid.cos_theta) / lam
    if order != "auto":
        if int(order) != order or order < 0 or order > FFT_MAX_ORDER:
            raise WaveopticsError(f"fft order {order!r} is not allowed; use 'auto' or an integer in [0, "
                                  f"{FFT_MAX_ORDER}] (higher orders overflow: (v_z h)^K / K! and h^K leave double "
                                  "range; 'auto' splits v_z into bands instead)")
        return [(2 * wi[2] / lam, int(order), inside)]
    hmax = float(np.max(np.abs(smp.h))) if smp.size else 0.0
    lo, hi = float(cz[inside].min()), float(cz[inside].max())
    span = 2 * np.pi * (hi - lo) * hmax            # |Δv_z h| range over the disc
    nb = max(1, int(math.ceil(span / (2 * FFT_BAND_X))))
    edges = np.linspace(lo, hi, nb + 1)
    bands = []
    for b in range(nb):
        m = inside & (cz >= edges[b]) & ((cz < edges[b + 1]) if b < nb - 1 else (cz <= edges[b + 1]))
        if not m.any():
            continue
        c = 0.5 * (edges[b] + edges[b + 1])
        x = 2 * np.pi * float(np.max(np.abs(cz[m] - c))) * hmax
        bands.append((c, _taylor_terms(x, tol), m))
    return bands


def field_fft(smp: Samples, wi, grid: DirectionGrid, wavelength_nm: float, order="auto",
              tol: float = FFT_TOL, frozen_cos_sum: float | None = None) -> tuple[np.ndarray, dict]:
    """Field U on *grid* at one wavelength by the ``fft`` solver (see the module docstring).

    Returns
    -------
    U : ndarray of complex128 (n_v, n_u), m²
        Zero outside the disc.
    info : dict
        ``bands`` and ``transforms`` (number of 2-D chirp-z transforms) used.
    """
    lam = wavelength_nm * 1e-9
    T = _DTFT2(smp, wi, grid, wavelength_nm)
    h, w = smp.grid_arrays()
    cz_o = (wi[2] + grid.cos_theta if frozen_cos_sum is None else np.full(grid.cos_theta.shape,
                                                                           float(frozen_cos_sum))) / lam
    U = np.zeros((grid.n_v, grid.n_u), np.complex128)
    plan = fft_plan(smp, wi, grid, wavelength_nm, order, tol, frozen_cos_sum)
    n_tr = 0
    # the Taylor terms (i Δv_z h)^n / n! are formed as (h/s)^n and (i Δv_z s)^n / n! with s = max |h|: both stay
    # in double range at any order (h^n alone underflows and (Δv_z)^n overflows: NaN beyond n ≈ 40)
    s = float(np.max(np.abs(h))) if np.any(h) else 1.0
    hs = h / s
    for c, K, m in plan:
        g = w * np.exp(2j * np.pi * c * h)
        d = np.where(m, 2j * np.pi * (cz_o - c) * s, 0.0)
        acc = T(g)
        n_tr += 1
        coef = np.ones_like(d)
        for n in range(1, K + 1):
            g = g * hs
            coef = coef * d / n
            acc = acc + coef * T(g)
            n_tr += 1
        U[m] = acc[m]
    return U, {"bands": len(plan), "transforms": n_tr, "max_order": max(K for _, K, _ in plan)}
