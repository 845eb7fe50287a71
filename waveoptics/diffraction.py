"""Kirchhoff (tangent-plane, scalar Huygens-Fresnel) scattering from a height-field patch, per wavelength.

With s = ω_i + ω_o (ω_i towards the light, ω_o towards the viewer), v = k s, a smooth window w(x, y) over the
patch and A_w = ∫ w² dx dy (physics.md §1):

    U(ω_i, ω_o) = ∫ w(x, y) exp(i v · (x, y, h(x, y))) dx dy

    f(ω_i, ω_o) = F(θ_d) |s|⁴ / (4 λ² A_w cos θ_i cos θ_o (cos θ_i + cos θ_o)²) · |U|²      [sr⁻¹]

with F(θ_d) the Fresnel reflectance at the half-vector angle, cos θ_d = ω_i · s/|s| = |s|/2. On the grid the
integral is the sum over samples times dx dy and A_w = Σ w² dx dy.

Solvers (registry :data:`SOLVERS`):

``direct``
    The sum evaluated for every (outgoing direction, wavelength) pair on the OpenCL device
    (``kernels/kirchhoff.cl``, :func:`kirchhoff_U_cl`), or in NumPy (:func:`kirchhoff_U`, float64, the
    reference). Exact within the tangent-plane model; O(samples × directions × wavelengths).
``fft``
    The field on a regular grid of direction cosines by chirp-z transforms (:func:`scipy.signal.ZoomFFT`) of
    w · hⁿ · exp(i v_z0 h), which samples the patch's discrete-time Fourier transform exactly on each
    wavelength's part of the common (u, v) grid (no interpolation, no zero padding). The vertical component
    v_z = k (cos θ_i + cos θ_o) depends on the outgoing direction; ``order=0`` freezes it at the specular value
    v_z0 = 2 k cos θ_i (the paraxial / Harvey-Shack-style approximation: exact for a flat surface and at the
    specular direction, wrong away from it by a phase error (v_z − v_z0) h). ``order="auto"`` (default) removes
    that error: the outgoing directions are split into bands of v_z and in each band exp(i (v_z − v_zb) h) is
    expanded in a Taylor series, U = Σ_n (i Δv_z)ⁿ/n! · DTFT[w hⁿ exp(i v_zb h)], truncated where the Lagrange
    bound |Δv_z h|^(K+1)/(K+1)! falls below ``tol`` relative to Σ w. This is exact Kirchhoff to that tolerance
    at O(bands × terms × N log N) cost.

References
----------
.. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon,
   1963, ch. 3 and 5 (Kirchhoff integral, obliquity factor, stationary-phase limit).
.. [2] Z. Dong, B. Walter, S. Marschner, D. P. Greenberg, "Predicting appearance from measured microgeometry of
   metal surfaces", ACM TOG 35(1), 2015 (windowed Kirchhoff BRDF of measured height fields, FFT evaluation).
.. [3] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 2018 (OHS/GHS obliquity variants).
.. [4] J. E. Harvey, R. N. Pfisterer, "Understanding diffraction grating behavior", Opt. Eng. 59(1) 017103, 2020
   (paraxial / generalized Harvey-Shack surface scatter).
.. [5] L. R. Rabiner, R. W. Schafer, C. M. Rader, "The chirp z-transform algorithm", IEEE Trans. Audio
   Electroacoustics 17(2), 1969 (scipy.signal.ZoomFFT).
.. [6] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 1954;
   H. E. Bennett, J. O. Porteus, "Relation between surface roughness and specular reflectance at normal
   incidence", JOSA 51(2), 1961 (coherent fraction exp(−g), TIS).
"""
from __future__ import annotations

import functools
import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .errors import WaveopticsError, unknown
from .surfaces import HeightField
from .units import check_theta, check_wavelengths, direction_from_angles

#: default smooth window (scipy.signal.windows name, symmetric form), applied separably along x and y
DEFAULT_WINDOW = "hann"
#: sinθ_o above which a direction counts as "near the horizon" (1/cosθ_o > 3.2) in the reported horizon share
HORIZON_SIN = 0.95
#: relative tolerance (of Σ w) of the fft solver's Taylor series in "auto" order
FFT_TOL = 1e-8
#: largest |Δv_z h| (rad) a Taylor band may span in "auto" order (terms stay ≤ e^4, so no cancellation)
FFT_BAND_X = 4.0
#: largest albedo of the F = 1 lobe that :func:`scatter` accepts without an "energy not conserved" warning
ENERGY_TOL = 1.05
#: the incident cosine is floored here: at exactly θ_i = 90° the BRDF's 1/cos θ_i has no finite limit
COS_I_MIN = 1e-4
#: samples per SIMD step in kernels/kirchhoff.cl (16 measured fastest under PoCL on AVX-512; GPUs unroll it)
VECTOR_WIDTH = 16
#: target number of sample-direction terms per OpenCL launch (keeps each launch ~0.1-1 s on a CPU)
TERMS_PER_LAUNCH = 2**29


class DiffractionWarning(UserWarning):
    """A result is computed but an approximation or sampling condition is violated (aliasing, coarse grid...)."""


def _warn(msg: str, sink: list | None = None) -> None:
    if sink is not None:
        sink.append(msg)
    warnings.warn(msg, DiffractionWarning, stacklevel=3)


# ----------------------------------------------------------------------------------------------------------------
# Direction-cosine grid
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class DirectionGrid:
    """A regular grid of cell centres in the direction-cosine plane (u, v) = (sin θ cos φ, sin θ sin φ).

    cos θ_o dω_o = du dv, so a directional albedo is Σ f du dv over the cells inside the unit disc. Cells are
    centred (u_j = u0 + (j + ½) du), so no cell sits exactly on the horizon. Row index = v, column index = u.

    Parameters
    ----------
    n_u, n_v : int
        Cells along u (columns) and v (rows).
    u_range, v_range : (float, float)
        Edges of the covered rectangle; the whole projected hemisphere is (−1, 1) × (−1, 1).

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963; physics.md §1 (projected solid angle).
    """

    n_u: int
    n_v: int
    u_range: tuple = (-1.0, 1.0)
    v_range: tuple = (-1.0, 1.0)

    def __post_init__(self):
        for name, n in (("n_u", self.n_u), ("n_v", self.n_v)):
            if int(n) != n or n < 1 or n > 16384:
                raise WaveopticsError(f"direction grid {name}={n!r} is not allowed; use an integer in 1..16384")
        for name, (a, b) in (("u_range", self.u_range), ("v_range", self.v_range)):
            if not (np.isfinite(a) and np.isfinite(b) and -1 <= a < b <= 1):
                raise WaveopticsError(f"direction grid {name}=({a}, {b}) is not allowed; need -1 <= a < b <= 1")
        object.__setattr__(self, "n_u", int(self.n_u))
        object.__setattr__(self, "n_v", int(self.n_v))
        object.__setattr__(self, "u_range", (float(self.u_range[0]), float(self.u_range[1])))
        object.__setattr__(self, "v_range", (float(self.v_range[0]), float(self.v_range[1])))

    @classmethod
    def hemisphere(cls, resolution: int) -> "DirectionGrid":
        """The whole projected hemisphere, *resolution* × *resolution* cells."""
        return cls(int(resolution), int(resolution))

    @property
    def du(self) -> float:
        return (self.u_range[1] - self.u_range[0]) / self.n_u

    @property
    def dv(self) -> float:
        return (self.v_range[1] - self.v_range[0]) / self.n_v

    @property
    def u(self) -> np.ndarray:
        """Cell centres along u, (n_u,)."""
        return self.u_range[0] + (np.arange(self.n_u) + 0.5) * self.du

    @property
    def v(self) -> np.ndarray:
        """Cell centres along v, (n_v,)."""
        return self.v_range[0] + (np.arange(self.n_v) + 0.5) * self.dv

    @property
    def sin_theta(self) -> np.ndarray:
        """sin θ_o = √(u² + v²) per cell, (n_v, n_u)."""
        return np.hypot(self.u[None, :], self.v[:, None])

    @property
    def inside(self) -> np.ndarray:
        """True for cells whose centre lies inside the unit disc (above the horizon), (n_v, n_u)."""
        return self.sin_theta < 1.0

    @property
    def cos_theta(self) -> np.ndarray:
        """cos θ_o per cell (0 outside the disc), (n_v, n_u)."""
        return np.sqrt(np.clip(1.0 - self.sin_theta**2, 0.0, 1.0))

    def directions(self) -> np.ndarray:
        """Unit vectors ω_o (n_v, n_u, 3); z = 0 outside the disc."""
        U, V = np.meshgrid(self.u, self.v)
        return np.stack([U, V, self.cos_theta], axis=-1)

    def header(self) -> dict:
        """The parametrization as string attributes (for image headers)."""
        return {
            "parametrization": "direction cosines: u = sin(theta_o) cos(phi_o) along columns (x), "
                               "v = sin(theta_o) sin(phi_o) along rows (y); cell centres; row 0 = lowest v",
            "u_range": f"{self.u_range[0]:.17g} {self.u_range[1]:.17g}",
            "v_range": f"{self.v_range[0]:.17g} {self.v_range[1]:.17g}",
            "n_u": str(self.n_u), "n_v": str(self.n_v),
            "measure": "cos(theta_o) d(omega_o) = du dv; albedo = sum(f) du dv over cells with u^2 + v^2 < 1",
        }


def integrate(f, grid: DirectionGrid, *, region=None) -> np.ndarray:
    """Directional albedo ∫ f cos θ_o dω_o = Σ f du dv over the disc (optionally also a boolean *region*).

    Parameters
    ----------
    f : ndarray (..., n_v, n_u), sr⁻¹
        BRDF on *grid*.

    Returns
    -------
    ndarray (...)
    """
    m = grid.inside if region is None else grid.inside & region
    return np.sum(np.where(m, f, 0.0), axis=(-2, -1)) * grid.du * grid.dv


# ----------------------------------------------------------------------------------------------------------------
# Window, samples, Fresnel
# ----------------------------------------------------------------------------------------------------------------

def window(hf: HeightField, name: str = DEFAULT_WINDOW) -> np.ndarray:
    """Smooth window w(x, y) = w_x(x) w_y(y) over the patch, zero where the mask is False.

    Parameters
    ----------
    hf : HeightField
    name : str
        A :func:`scipy.signal.windows.get_window` name (symmetric form), e.g. ``"hann"`` (default),
        ``"blackmanharris"``, ``("tukey", 0.5)``, or ``"boxcar"`` (no taper: edge ringing, for comparison).

    Returns
    -------
    ndarray (ny, nx)
        Weights in [0, 1]. The normalization of the BRDF uses A_w = Σ w² dx dy (:func:`window_area`).

    Notes
    -----
    A hard-edged patch diffracts like a rectangular aperture: sinc² side lobes that fall off as 1/q² and, after
    the 1/cos θ_o of the BRDF, spread light towards the horizon. The Hann taper's side lobes fall off as 1/q⁶
    (Harris 1978) at the cost of a main lobe twice as wide.

    References
    ----------
    .. [1] F. J. Harris, "On the use of windows for harmonic analysis with the discrete Fourier transform",
       Proc. IEEE 66(1), 1978.
    """
    from scipy.signal.windows import get_window

    ny, nx = hf.shape
    try:
        wx = get_window(name, nx, fftbins=False) if nx > 1 else np.ones(1)
        wy = get_window(name, ny, fftbins=False) if ny > 1 else np.ones(1)
    except (ValueError, TypeError) as exc:
        raise WaveopticsError(f"window {name!r} is not allowed ({exc}); use a scipy.signal.windows name "
                              "such as 'hann', 'blackmanharris', ('tukey', 0.5) or 'boxcar'") from None
    w = np.outer(wy, wx) * hf.valid
    if not np.any(w > 0):
        raise WaveopticsError("the window leaves no sample with positive weight (mask empty or patch too small)")
    return w


def window_area(w, dx: float, dy: float) -> float:
    """A_w = Σ w² dx dy (m²), the normalization area of physics.md §1."""
    return float(np.sum(np.asarray(w) ** 2) * dx * dy)


@dataclass(frozen=True)
class Samples:
    """The patch as a list of samples with positive window weight, as the kernels take it.

    Attributes
    ----------
    ix, iy : ndarray of int32
        Grid indices (column, row).
    h : ndarray of float64, m
        Heights with the w²-weighted mean (or plane) removed, see :func:`samples`.
    w : ndarray of float64
        Window weights.
    dx, dy : float, m
    nx, ny : int
    area : float, m²
        A_w = Σ w² dx dy.
    """

    ix: np.ndarray
    iy: np.ndarray
    h: np.ndarray
    w: np.ndarray
    dx: float
    dy: float
    nx: int
    ny: int
    area: float

    @property
    def size(self) -> int:
        return int(self.w.size)

    @property
    def extent(self) -> tuple[float, float]:
        return self.nx * self.dx, self.ny * self.dy

    def grid_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(h, w) back on the (ny, nx) grid (zeros where no sample)."""
        h = np.zeros((self.ny, self.nx))
        w = np.zeros((self.ny, self.nx))
        h[self.iy, self.ix] = self.h
        w[self.iy, self.ix] = self.w
        return h, w


def samples(hf: HeightField, window_name=DEFAULT_WINDOW, detrend: str = "mean") -> Samples:
    """Window the height field and list the samples with w > 0 (see :class:`Samples`).

    Parameters
    ----------
    detrend : {'mean', 'plane', 'none'}
        'plane' also removes the patch's tilt (least squares weighted by w², the weight of each sample in |U|²).
        A finite patch of a random surface has a mean slope; the Kirchhoff model reflects it like a tilted
        mirror, whose albedo differs from the untilted one by about tan θ_i times that slope. The (weighted)
        mean is removed in every case, 'none' included — it changes only the phase of U, but float32 rounding
        of h v_z grows with |h| (a 1 m offset changes nothing: ``tests/hard_cases.py``, offset cases).
    """
    from .surfaces import DETRENDS

    if not isinstance(hf, HeightField):
        raise WaveopticsError(f"surface must be a HeightField, got {type(hf).__name__}")
    if detrend not in DETRENDS:
        raise unknown("detrend", detrend, DETRENDS)
    w = window(hf, window_name)
    iy, ix = np.nonzero(w > 0)
    ww = w[iy, ix]
    hh = hf.heights[iy, ix]
    w2 = ww**2
    # least squares weighted by w² (the weight each sample has in |U|²): mean, or mean and tilt
    cols = [np.ones_like(hh)]
    if detrend == "plane":
        cols += [c - np.sum(w2 * c) / np.sum(w2) for c in (ix * hf.dx, iy * hf.dy) if np.ptp(c) > 0]
    X = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(X * ww[:, None], hh * ww, rcond=None)
    hh = hh - X @ coef
    ny, nx = hf.shape
    if max(nx, ny) > 2**30:
        raise WaveopticsError(f"patch {nx}x{ny} is too large; at most 2^30 samples per side")
    return Samples(ix.astype(np.int32), iy.astype(np.int32), hh, ww, hf.dx, hf.dy, nx, ny,
                   window_area(ww, hf.dx, hf.dy))


def fresnel_function(material):
    """A function F(cos θ_d, wavelength_nm) from a material specification.

    Parameters
    ----------
    material : None, float, str, Material or callable
        None → F = 1 (the bare Kirchhoff lobe); a number in [0, 1] → constant F; a string →
        :func:`waveoptics.materials.get_material`; an object with ``.F(cos, wavelength_nm)``; or a callable
        ``F(cos, wavelength_nm)``.

    Returns
    -------
    callable
        Broadcasting F(cos_theta_d, wavelength_nm) → reflectance in [0, 1].
    """
    if material is None:
        return lambda c, wl: np.ones(np.broadcast_shapes(np.shape(c), np.shape(wl)))
    if isinstance(material, (int, float, np.floating, np.integer)) and not isinstance(material, bool):
        F0 = float(material)
        if not 0.0 <= F0 <= 1.0:
            raise WaveopticsError(f"constant reflectance {F0!r} is not allowed; it must be in [0, 1]")
        return lambda c, wl: np.full(np.broadcast_shapes(np.shape(c), np.shape(wl)), F0)
    if isinstance(material, str):
        from .materials import get_material

        material = get_material(material)
    if hasattr(material, "F"):
        return material.F
    if callable(material):
        return material
    raise WaveopticsError(f"material {material!r} is not allowed; give None, a number, a name, a Material "
                          "or a callable F(cos, wavelength_nm)")


def _incident(wi) -> np.ndarray:
    """ω_i from (θ, φ) in degrees or a 3-vector; validated, cos θ_i floored at COS_I_MIN."""
    a = np.asarray(wi, dtype=float).ravel()
    if a.size == 2 or a.size == 1:
        theta, phi = float(a[0]), float(a[1]) if a.size == 2 else 0.0
        check_theta(theta, name="incident")
        w = direction_from_angles(theta, phi)
    elif a.size == 3:
        n = np.linalg.norm(a)
        if not np.isfinite(n) or n == 0 or a[2] < 0:
            raise WaveopticsError(f"incident direction {tuple(a)} is not allowed; it must be finite, non-zero "
                                  "and above the surface (z >= 0)")
        w = a / n
    else:
        raise WaveopticsError(f"incident direction {wi!r} is not allowed; give (theta_deg, phi_deg) or (x, y, z)")
    # guard: a grazing light has cos θ_i -> 0 and the BRDF's 1/cos θ_i diverges; floor it
    if w[2] < COS_I_MIN:
        w = np.array([w[0], w[1], 0.0])
        w[:2] *= math.sqrt(1 - COS_I_MIN**2) / max(np.hypot(w[0], w[1]), 1e-300)
        w[2] = COS_I_MIN
    return w


def _outgoing(wo) -> np.ndarray:
    a = np.asarray(wo, dtype=float)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3 or not np.all(np.isfinite(a)):
        raise WaveopticsError(f"outgoing directions must be finite (n, 3) unit vectors, got shape {a.shape}")
    n = np.linalg.norm(a, axis=1, keepdims=True)
    if np.any(n == 0):
        raise WaveopticsError("outgoing direction (0, 0, 0) is not allowed")
    return a / n


# ----------------------------------------------------------------------------------------------------------------
# The Kirchhoff factor and BRDF from a field
# ----------------------------------------------------------------------------------------------------------------

def kirchhoff_factor(wi, wo, wavelength_nm) -> np.ndarray:
    """Obliquity and normalization |s|⁴ / (4 λ² cos θ_i cos θ_o (cos θ_i + cos θ_o)²), m⁻².

    Parameters
    ----------
    wi : ndarray (3,)
        Unit vector towards the light.
    wo : ndarray (..., 3)
        Unit vectors towards the viewer.
    wavelength_nm : array_like, nm
        Broadcast against ``wo[..., 0]``.

    Returns
    -------
    ndarray
        The factor (m⁻²); f = F(θ_d) · factor · |U|² / A_w. Zero for directions at or below the horizon.

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963; physics.md §1 (checked there against the flat and σ ≫ λ limits).
    """
    wi = np.asarray(wi, dtype=float)
    wo = np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    ci = max(float(wi[2]), COS_I_MIN)
    co = wo[..., 2]
    s2 = np.sum((wo + wi) ** 2, axis=-1)
    # guard: directions at or below the horizon do not reflect (and would divide by zero)
    up = co > 0
    co_safe = np.where(up, co, 1.0)
    val = s2**2 / (4.0 * lam**2 * ci * co_safe * (ci + co_safe) ** 2)
    return np.where(up, val, 0.0)


def cos_theta_d(wi, wo) -> np.ndarray:
    """cos θ_d = ω_i · h = |ω_i + ω_o| / 2, the Fresnel angle of the half vector."""
    return np.clip(0.5 * np.linalg.norm(np.asarray(wo) + np.asarray(wi), axis=-1), 0.0, 1.0)


def brdf_from_field(U, wi, wo, wavelengths_nm, area: float, F=None) -> np.ndarray:
    """BRDF f = F(θ_d) |s|⁴ |U|² / (4 λ² A_w cos θ_i cos θ_o (cos θ_i + cos θ_o)²), sr⁻¹.

    Parameters
    ----------
    U : ndarray (n_wl, ...), m²
        Field (including dx dy) for each wavelength and direction.
    wo : ndarray (..., 3)
    wavelengths_nm : ndarray (n_wl,), nm
    area : float, m²
        A_w.
    F : callable, optional
        F(cos θ_d, wavelength_nm); None → 1.
    """
    wl = np.asarray(wavelengths_nm, dtype=float)
    shape = (wl.size,) + (1,) * (np.ndim(wo) - 1)
    K = kirchhoff_factor(wi, wo[None], wl.reshape(shape))
    out = K * np.abs(U) ** 2 / area
    if F is not None:
        out = out * np.asarray(F(cos_theta_d(wi, wo)[None], wl.reshape(shape)), dtype=float)
    return out


# ----------------------------------------------------------------------------------------------------------------
# Phase coefficients and the direct sum (NumPy twin and OpenCL)
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PhaseCoefficients:
    """Per-pair phase coefficients, all in cycles (shape (n_pairs,)).

    phase_j = ix_j a_x + iy_j a_y + h_j cz + c0 with a = A / 2³² + lo (A a uint32, exact fixed point of
    a mod 1) — see ``kernels/kirchhoff.cl``.
    """

    Ax: np.ndarray
    Ay: np.ndarray
    lox: np.ndarray
    loy: np.ndarray
    cz: np.ndarray
    c0: np.ndarray

    @property
    def size(self) -> int:
        return int(self.cz.size)

    def take(self, sl) -> "PhaseCoefficients":
        return PhaseCoefficients(*(getattr(self, k)[sl] for k in ("Ax", "Ay", "lox", "loy", "cz", "c0")))


def _fixed_point(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split cycles-per-sample *a* into (A uint32, lo) with a ≡ A / 2³² + lo (mod 1), |lo| ≤ 2⁻³³."""
    r = a - np.round(a)                       # in [-1/2, 1/2], exact in float64 for |a| < 2^52
    Ai = np.round(r * 2.0**32)
    lo = r - Ai * 2.0**-32
    return np.mod(Ai.astype(np.int64), 2**32).astype(np.uint32), lo


def phase_coefficients(smp: Samples, wi, wo, wavelengths_nm, *, frozen_vz: bool = False) -> PhaseCoefficients:
    """Phase coefficients for every (wavelength, direction) pair, wavelength-major (pair = l · n_dir + d).

    Parameters
    ----------
    smp : Samples
    wi : ndarray (3,)
    wo : ndarray (n_dir, 3)
    wavelengths_nm : ndarray (n_wl,), nm
    frozen_vz : bool
        Use cz = 2 cos θ_i / λ for every direction (the ``fft`` solver's order-0 approximation) instead of
        (cos θ_i + cos θ_o) / λ.
    """
    lam = np.asarray(wavelengths_nm, dtype=float)[:, None] * 1e-9
    s = np.asarray(wo)[None, :, :] + np.asarray(wi)[None, None, :]
    ax = s[..., 0] * smp.dx / lam
    ay = s[..., 1] * smp.dy / lam
    cz = (np.broadcast_to(2 * wi[2], s[..., 2].shape) if frozen_vz else s[..., 2]) / lam
    cx, cy = (smp.nx - 1) / 2.0, (smp.ny - 1) / 2.0
    c0 = -(cx * (ax - np.round(ax)) + cy * (ay - np.round(ay)))   # origin at the patch centre
    c0 = c0 - np.round(c0)
    Ax, lox = _fixed_point(ax.ravel())
    Ay, loy = _fixed_point(ay.ravel())
    return PhaseCoefficients(Ax, Ay, lox, loy, cz.ravel(), c0.ravel())


def kirchhoff_phase(ix, iy, h, Ax, Ay, lox, loy, cz, c0) -> np.ndarray:
    """NumPy twin (float64) of the ``kirchhoff_phase`` kernel: phase in cycles reduced to [−½, ½].

    Parameters
    ----------
    ix, iy : ndarray of int, h : ndarray (m)
        Samples (broadcast against the coefficients).
    Ax, Ay : uint32; lox, loy, cz (cycles/m), c0 : float
        Coefficients of :class:`PhaseCoefficients`.
    """
    fixed = (np.asarray(ix, np.int64) * np.int64(Ax) + np.asarray(iy, np.int64) * np.int64(Ay)) % 2**32
    fixed = np.where(fixed >= 2**31, fixed - 2**32, fixed).astype(np.float64)
    p = fixed * 2.0**-32 + (np.asarray(ix) * lox + np.asarray(iy) * loy) + (np.asarray(h) * cz + c0)
    return p - np.round(p)


def kirchhoff_U(smp: Samples, coef: PhaseCoefficients, *, chunk_terms: int = 2**22) -> np.ndarray:
    """NumPy twin (float64) of the ``kirchhoff_U`` kernel: U_p = dx dy Σ_j w_j exp(2πi phase_pj).

    Returns
    -------
    ndarray of complex128 (n_pairs,), m²
    """
    n = coef.size
    out = np.empty(n, np.complex128)
    step = max(1, chunk_terms // max(smp.size, 1))
    ix, iy, h, w = smp.ix[None, :], smp.iy[None, :], smp.h[None, :], smp.w
    for a in range(0, n, step):
        c = coef.take(slice(a, a + step))
        ph = kirchhoff_phase(ix, iy, h, c.Ax[:, None].astype(np.int64), c.Ay[:, None].astype(np.int64),
                             c.lox[:, None], c.loy[:, None], c.cz[:, None], c.c0[:, None])
        out[a:a + step] = np.exp(2j * np.pi * ph) @ w
    return out * (smp.dx * smp.dy)


#: pairs summed by one work-item of ``kirchhoff_U`` (register blocking; measured fastest under PoCL on 2 cores:
#: float32 8 (5.2 G terms/s vs 4.7 for 4 and 5.1 for 16), float64 4 (1.9 vs 1.7 for 8); see docs/performance.md)
PAIRS_PER_ITEM = {"float32": 8, "float64": 4}
#: (sine, cosine) polynomial lengths of the kernels' sin/cos(2πt): sin(fπ/2) = f S(f²), cos(fπ/2) = 1 + f² C'(f²)
SINCOS_TERMS = {"float32": (4, 3), "float64": (7, 7)}


def _precision_name(dtype) -> str:
    return "float64" if np.dtype(dtype) == np.float64 else "float32"


@functools.lru_cache(maxsize=4)
def sincos_poly(precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (S, C) of the kernels' sin/cos polynomials (``kernels/wo_sincos.h``).

    sin(f π/2) ≈ f Σ_n S_n f^{2n} and cos(f π/2) ≈ Σ_n C_n f^{2n} (C_0 = 1) on |f| ≤ ½, fitted by least squares
    on 4000 Chebyshev nodes (relative error for the sine, absolute for the cosine), which is within a few per
    cent of the minimax error (Muller, *Elementary Functions*, 2016, ch. 3). Truncation error: float32 2.6e-9 /
    3.4e-8 (below half an ulp of 1), float64 7.8e-16 / 3.3e-16.

    Returns
    -------
    S, C : ndarray of float64
    """
    n_sin, n_cos = SINCOS_TERMS[precision]
    k = np.arange(4000)
    f = 0.25 + 0.25 * np.cos(np.pi * (k + 0.5) / 4000)       # Chebyshev nodes on (0, 1/2)
    x = f * f
    ys = np.sin(0.5 * np.pi * f) / f
    S = np.linalg.lstsq(np.vander(x, n_sin, increasing=True) / ys[:, None], np.ones_like(ys), rcond=None)[0]
    C = np.linalg.lstsq(np.vander(x, n_cos + 1, increasing=True)[:, 1:], np.cos(0.5 * np.pi * f) - 1.0,
                        rcond=None)[0]
    return S, np.concatenate([[1.0], C])


def _sincos_options(precision: str) -> tuple[str, ...]:
    """``-DWO_SIN_C<n>=...`` / ``-DWO_COS_C<n>=...`` build options carrying :func:`sincos_poly`."""
    S, C = sincos_poly(precision)
    suffix = "f" if precision == "float32" else ""
    return (tuple(f"-DWO_SIN_C{n}={c!r}{suffix}" for n, c in enumerate(S.tolist()))
            + tuple(f"-DWO_COS_C{n}={c!r}{suffix}" for n, c in enumerate(C.tolist()) if n > 0))


def sincos_2pi(t, precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """NumPy twin of ``wo_sincos_2pi`` (``kernels/wo_sincos.h``): (sin 2πt, cos 2πt) in *precision*.

    4t = q + f with q = rint(4t) (exact), then the polynomials of :func:`sincos_poly` in f and the quadrant q.

    References
    ----------
    .. [1] W. J. Cody, W. Waite, *Software Manual for the Elementary Functions*, Prentice-Hall, 1980, ch. 8.
    """
    dt = np.float64 if precision == "float64" else np.float32
    S, C = (c.astype(dt) for c in sincos_poly(precision))
    t4 = dt(4) * np.asarray(t, dt)
    qf = np.rint(t4)
    f = t4 - qf
    x = f * f
    sp = f * np.polynomial.polynomial.polyval(x, S).astype(dt)
    cp = np.polynomial.polynomial.polyval(x, C).astype(dt)
    q = qf.astype(np.int64)
    odd = (q & 1) != 0
    s = np.where(odd, cp, sp) * np.where(q & 2, -1, 1)
    c = np.where(odd, sp, cp) * np.where((q + 1) & 2, -1, 1)
    return s.astype(dt), c.astype(dt)


def _cl_setup(runtime, precision, vector_width, smp: Samples, fast_math: bool = False):
    """(runtime, real dtype, program, queue, padded device sample arrays (ix, iy, h, w), padded count)."""
    import pyopencl.array as cla

    from .runtime import build_options, build_program, get_runtime

    rt = runtime if runtime is not None else get_runtime()
    dt = rt.real_dtype(precision)
    pname = _precision_name(dt)
    vw = int(vector_width or VECTOR_WIDTH)
    if vw not in (2, 4, 8, 16):
        raise WaveopticsError(f"vector_width={vw!r} is not allowed; use 2, 4, 8 or 16")
    extra = (f"-DWO_VW={vw}", f"-DWO_ND={PAIRS_PER_ITEM[pname]}") + _sincos_options(pname)
    if fast_math:
        extra += ("-cl-fast-relaxed-math",)
    prg = build_program(rt, "kirchhoff.cl", build_options(dt, extra))
    q = rt.queue
    pad = (-smp.size) % vw                       # padding samples carry w = 0

    def dev(a, t):
        return cla.to_device(q, np.ascontiguousarray(np.concatenate([a.astype(t), np.zeros(pad, t)])))

    arrays = (dev(smp.ix, np.int32), dev(smp.iy, np.int32), dev(smp.h, dt), dev(smp.w, dt))
    return rt, dt, prg, q, arrays, smp.size + pad


def _default_local_size(rt):
    """1 on CPU devices (PoCL then runs the kernels' explicit vectors as written: measured 2x), else the
    driver's choice."""
    import pyopencl as cl

    return 1 if rt.device.type & cl.device_type.CPU else None


def kirchhoff_phase_cl(smp: Samples, coef: PhaseCoefficients, pair: int = 0, *, runtime=None,
                       precision: str = "float32", vector_width: int | None = None) -> np.ndarray:
    """OpenCL ``kirchhoff_phase``: per-sample phase (cycles) of one pair, in *precision* (twin:
    :func:`kirchhoff_phase`)."""
    import pyopencl as cl
    import pyopencl.array as cla

    rt, dt, prg, q, (d_ix, d_iy, d_h, _), ns = _cl_setup(runtime, precision, vector_width, smp)
    d_out = cla.empty(q, ns, dt)
    vw = int(vector_width or VECTOR_WIDTH)
    cl.Kernel(prg, "kirchhoff_phase")(
        q, (ns // vw,), None, d_ix.data, d_iy.data, d_h.data, np.int32(ns), np.uint32(coef.Ax[pair]),
        np.uint32(coef.Ay[pair]), dt(coef.lox[pair]), dt(coef.loy[pair]), dt(coef.cz[pair]), dt(coef.c0[pair]),
        d_out.data)
    return d_out.get()[: smp.size].astype(np.float64)


def sincos_2pi_cl(t, *, runtime=None, precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """OpenCL ``sincos_2pi`` (the kernels' sin/cos of 2πt; twin: :func:`sincos_2pi`)."""
    import pyopencl as cl
    import pyopencl.array as cla

    t = np.asarray(t, dtype=float).ravel()
    empty = Samples(*(np.zeros(0, np.int32),) * 2, np.zeros(0), np.zeros(0), 1.0, 1.0, 1, 1, 0.0)
    rt, dt, prg, q, _, _ = _cl_setup(runtime, precision, None, empty)
    n = t.size + (-t.size) % VECTOR_WIDTH
    d_t = cla.to_device(q, np.concatenate([t.astype(dt), np.zeros(n - t.size, dt)]))
    s, c = cla.empty(q, n, dt), cla.empty(q, n, dt)
    cl.Kernel(prg, "sincos_2pi")(q, (max(1, n // VECTOR_WIDTH),), None, d_t.data, np.int32(n), s.data, c.data)
    return s.get()[: t.size], c.get()[: t.size]


#: direct-sum kernels of kernels/kirchhoff.cl (the ``kernel=`` registry of :func:`kirchhoff_U_cl`)
DIRECT_KERNELS = {
    "kirchhoff_U": "exact fixed-point phase, shared-reduction sin/cos polynomials, register-blocked pairs (default)",
    "kirchhoff_U_sinpi": "the kernel before issue 6 (benchmark's before/after): exact phase, SLEEF sinpi/cospi, one "
                         "pair per work-item",
    "kirchhoff_U_naive": "baseline for the benchmark: float phase in radians, native_sin/native_cos, one pair per "
                         "work-item (inaccurate for large phases in float32)",
}


def kirchhoff_U_cl(smp: Samples, coef: PhaseCoefficients, *, runtime=None, precision: str = "float32",
                   local_size: int | None = None, vector_width: int | None = None, progress=None,
                   kernel: str = "kirchhoff_U", fast_math: bool = False) -> np.ndarray:
    """OpenCL direct sum (``kernels/kirchhoff.cl``), twin of :func:`kirchhoff_U`.

    All pairs (every direction × wavelength) go through one program; launches are split into chunks of about
    :data:`TERMS_PER_LAUNCH` sample-pair terms so that *progress* (a callable taking a number of finished
    pairs) can report and no single launch runs for long.

    Parameters
    ----------
    precision : {'float32', 'float64'}
        float64 needs device fp64 support (``rt.fp64``).
    local_size : int, optional
        Work-group size (default: 1 on CPU devices, else the driver's choice; 0: the driver's choice).
    vector_width : int, optional
        Samples per SIMD step of the inner loop (``-DWO_VW``; default :data:`VECTOR_WIDTH`).
    kernel : str
        A name in :data:`DIRECT_KERNELS`; ``kirchhoff_U_naive`` is the benchmark's baseline.
    fast_math : bool
        Build with ``-cl-fast-relaxed-math`` (lets the compiler reassociate sums and use faster, less accurate
        math; its effect on speed and error is measured by ``waveoptics bench``). Default off.

    Returns
    -------
    ndarray of complex128 (n_pairs,), m²
    """
    import pyopencl as cl
    import pyopencl.array as cla

    if kernel not in DIRECT_KERNELS:
        raise unknown("kernel", kernel, DIRECT_KERNELS)
    rt, dt, prg, q, (d_ix, d_iy, d_h, d_w), ns = _cl_setup(runtime, precision, vector_width, smp, fast_math)
    knl = cl.Kernel(prg, kernel)
    naive = kernel == "kirchhoff_U_naive"
    nd = PAIRS_PER_ITEM[_precision_name(dt)] if kernel == "kirchhoff_U" else 1
    n = coef.size
    out = np.empty(n, np.complex128)
    lsz = _default_local_size(rt) if local_size is None else (int(local_size) or None)   # 0: driver's choice
    chunk = max(256, TERMS_PER_LAUNCH // max(ns, 1))
    chunk -= chunk % nd
    if naive:
        # radians per metre from the cycles-per-sample coefficients (reduced mod 1 cycle: same exp)
        lat = [(np.asarray(A, np.float64) * 2.0**-32 + lo) for A, lo in ((coef.Ax, coef.lox), (coef.Ay, coef.loy))]
        lat = [np.where(a >= 0.5, a - 1.0, a) for a in lat]
        kx, ky, kz = 2 * np.pi * lat[0] / smp.dx, 2 * np.pi * lat[1] / smp.dy, 2 * np.pi * coef.cz
    for a in range(0, n, chunk):
        c = coef.take(slice(a, a + chunk))
        m = c.size
        if naive:
            dev = [cla.to_device(q, np.ascontiguousarray(x[a:a + m].astype(dt))) for x in (kx, ky, kz)]
            args = (*[d.data for d in dev], dt(smp.dx), dt(smp.dy), dt((smp.nx - 1) / 2), dt((smp.ny - 1) / 2))
        else:
            dev = [cla.to_device(q, np.ascontiguousarray(x)) for x in
                   (c.Ax, c.Ay, c.lox.astype(dt), c.loy.astype(dt), c.cz.astype(dt), c.c0.astype(dt))]
            args = tuple(d.data for d in dev)
        re, im = cla.empty(q, m, dt), cla.empty(q, m, dt)
        items = -(-m // nd)
        gsz = items if lsz is None else -(-items // lsz) * lsz
        knl(q, (gsz,), None if lsz is None else (lsz,), d_ix.data, d_iy.data, d_h.data, d_w.data,
            np.int32(ns), *args, np.int32(m), re.data, im.data)
        out[a:a + m] = re.get() + 1j * im.get()
        if progress is not None:
            progress(m)
    return out * (smp.dx * smp.dy)


# ----------------------------------------------------------------------------------------------------------------
# The fft solver: chirp-z transforms on the common (u, v) grid, frozen v_z or banded Taylor series
# ----------------------------------------------------------------------------------------------------------------

class _DTFT2:
    """DTFT of (ny, nx) arrays at the (u, v) grid of one wavelength: dx dy Σ g e^{2πi (ix a_x + iy a_y + c0)}."""

    def __init__(self, smp: Samples, wi, grid: DirectionGrid, wavelength_nm: float):
        from scipy.signal import ZoomFFT

        lam = wavelength_nm * 1e-9
        ax = (wi[0] + grid.u) * smp.dx / lam          # cycles per sample, (n_u,)
        ay = (wi[1] + grid.v) * smp.dy / lam
        sx, sy = grid.du * smp.dx / lam, grid.dv * smp.dy / lam
        # zoom_fft computes Σ x[n] e^{-2πi n f}: ask for f = -a (steps may be negative)
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
             tol: float = FFT_TOL) -> list[tuple[float, int, np.ndarray]]:
    """Bands of the ``fft`` solver: a list of (cz_b in cycles/m, Taylor order K_b, boolean cell mask).

    ``order=0`` (or any int) gives one band expanded about the specular cz0 = 2 cos θ_i / λ to that order.
    ``order="auto"`` splits the range of cz = (cos θ_i + cos θ_o)/λ over the disc into bands no wider than
    |Δv_z h| ≤ 2 :data:`FFT_BAND_X` and picks K_b from the Lagrange bound so that the field is within
    *tol* · Σ w of the exact Kirchhoff sum.
    """
    lam = wavelength_nm * 1e-9
    inside = grid.inside
    cz = (wi[2] + grid.cos_theta) / lam
    if order != "auto":
        if int(order) != order or order < 0:
            raise WaveopticsError(f"fft order {order!r} is not allowed; use 'auto' or an integer >= 0")
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
              tol: float = FFT_TOL) -> tuple[np.ndarray, dict]:
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
    cz_o = (wi[2] + grid.cos_theta) / lam
    U = np.zeros((grid.n_v, grid.n_u), np.complex128)
    plan = fft_plan(smp, wi, grid, wavelength_nm, order, tol)
    n_tr = 0
    for c, K, m in plan:
        g = w * np.exp(2j * np.pi * c * h)
        d = np.where(m, 2j * np.pi * (cz_o - c), 0.0)
        acc = T(g)
        n_tr += 1
        coef = np.ones_like(d)
        for n in range(1, K + 1):
            g = g * h
            coef = coef * d / n
            acc = acc + coef * T(g)
            n_tr += 1
        U[m] = acc[m]
    return U, {"bands": len(plan), "transforms": n_tr, "max_order": max(K for _, K, _ in plan)}


# ----------------------------------------------------------------------------------------------------------------
# Coherent part
# ----------------------------------------------------------------------------------------------------------------

def coherent_amplitude(smp: Samples, wi, wavelength_nm) -> complex:
    """χ̂ = Σ w² exp(i v_z h) / Σ w², v_z = 2 k cos θ_i: the patch estimate of ⟨exp(i v_z h)⟩ (physics.md §2)

    The ensemble-mean field is ⟨U⟩ = χ · U_flat, so the coherent (specular) fraction is |χ|² = exp(−g) for
    Gaussian heights. The spatial average over the patch replaces the ensemble average (ergodicity); the w²
    weights make exp(i v_z h) − χ̂ orthogonal to w, so that the coherent and the scattered lobes add without a
    cross term in the albedo. One patch's |χ̂|² is biased high by about (1 − |χ|²) · A_c / A_w (A_c the
    correlation area); averaging χ̂ over realizations removes that bias.

    References
    ----------
    .. [1] H. Davies, Proc. IEE 101, 1954; Beckmann & Spizzichino 1963, ch. 5 (coherent field ⟨exp(i v_z h)⟩).
    """
    cz = 2 * wi[2] / (wavelength_nm * 1e-9)
    w2 = smp.w**2
    return complex(np.sum(w2 * np.exp(2j * np.pi * cz * smp.h)) / np.sum(w2))


# ----------------------------------------------------------------------------------------------------------------
# High-level API
# ----------------------------------------------------------------------------------------------------------------

#: solver name -> description (the ``method=`` registry)
SOLVERS = {
    "direct": "direct Kirchhoff sum on the OpenCL device (exact tangent-plane model; O(samples x directions))",
    "fft": "chirp-z transforms on the direction-cosine grid, banded Taylor series in v_z (order='auto') or "
           "frozen v_z (order=0)",
}
BACKENDS = ("opencl", "numpy")


def _check_solver(solver, backend):
    if solver not in SOLVERS:
        raise unknown("solver", solver, SOLVERS)
    if backend not in BACKENDS:
        raise unknown("backend", backend, BACKENDS)


def _realizations(surface, realizations, seed=0) -> list[HeightField]:
    """The list of height fields to average over (see :func:`scatter`)."""
    n = 1 if realizations is None else realizations
    try:
        ok = not isinstance(n, bool) and float(n) == int(n) and int(n) >= 1
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise WaveopticsError(f"realizations={realizations!r} is not allowed; it must be an integer >= 1")
    n = int(n)
    if isinstance(surface, HeightField):
        return split_patch(surface, n) if n > 1 else [surface]
    if callable(surface):
        return [surface(seed + r) for r in range(n)]
    try:
        hfs = list(surface)
    except TypeError:
        raise WaveopticsError(f"surface must be a HeightField, a list of them or a callable seed -> HeightField, "
                              f"got {type(surface).__name__}") from None
    if not hfs or not all(isinstance(h, HeightField) for h in hfs):
        raise WaveopticsError("surface list must hold at least one HeightField and nothing else")
    if realizations is not None and int(realizations) != len(hfs):
        raise WaveopticsError(f"realizations={realizations} differs from the {len(hfs)} height fields given")
    return hfs


def split_patch(hf: HeightField, n: int) -> list[HeightField]:
    """Split *hf* into *n* equal, non-overlapping tiles (as square a layout as possible) for ensemble averages.

    Tiles of one large measured or generated patch stand in for independent realizations when the patch spans
    many correlation lengths; each tile is smaller, so the angular resolution λ/L is coarser.
    """
    if int(n) != n or n < 1:
        raise WaveopticsError(f"realizations={n!r} is not allowed; it must be an integer >= 1")
    ny, nx = hf.shape
    best = None
    for a in range(1, n + 1):
        if n % a:
            continue
        b = n // a                                   # a tiles along y, b along x
        if ny // a < 2 or nx // b < 2:
            continue
        score = abs(math.log((nx / b) / (ny / a)))
        if best is None or score < best[0]:
            best = (score, a, b)
    if best is None:
        raise WaveopticsError(f"cannot split a {nx}x{ny} patch into {n} tiles of at least 2x2 samples")
    _, a, b = best
    ty, tx = ny // a, nx // b
    out = []
    for i in range(a):
        for j in range(b):
            sl = (slice(i * ty, (i + 1) * ty), slice(j * tx, (j + 1) * tx))
            mask = None if hf.mask is None else hf.mask[sl]
            out.append(HeightField(hf.heights[sl], hf.dx, hf.dy, mask, dict(hf.meta, tile=(i, j))))
    return out


def sampling_warnings(smp: Samples, wi, wavelengths_nm, grid: DirectionGrid | None = None,
                      wo=None) -> list[str]:
    """Messages for violated sampling conditions (physics.md §1).

    * Aliasing: the sum is periodic in s_x dx / λ with period 1, so directions with |u_i + u_o| > λ/(2 dx)
      (or the same along y) receive light that belongs elsewhere. The whole disc is safe when dx, dy ≤ λ/4.
    * Lobe sampling (grids only): the specular spike of a patch of length L has width ~λ/L in u; the grid
      sums it exactly (Poisson summation of |Û|², whose transform — the window's autocorrelation — has
      support |x| < L) only when du ≤ λ/Lx and dv ≤ λ/Ly.
    """
    msgs = []
    lam = np.asarray(wavelengths_nm, dtype=float) * 1e-9
    if grid is not None:
        sx = np.abs(wi[0] + grid.u[grid.inside.any(axis=0)]).max()
        sy = np.abs(wi[1] + grid.v[grid.inside.any(axis=1)]).max()
    else:
        wo = np.asarray(wo)
        sx = float(np.max(np.abs(wo[:, 0] + wi[0])))
        sy = float(np.max(np.abs(wo[:, 1] + wi[1])))
    lmin = float(lam.min())
    if sx * smp.dx / lmin > 0.5 + 1e-12 or sy * smp.dy / lmin > 0.5 + 1e-12:
        msgs.append(f"aliasing: sample spacing {smp.dx * 1e9:.4g} x {smp.dy * 1e9:.4g} nm is too coarse for "
                    f"{lmin * 1e9:.4g} nm at these directions (needs |u_i + u_o| <= lambda/(2 dx) = "
                    f"{lmin / (2 * smp.dx):.3g}); use dx <= lambda/4 = {lmin / 4 * 1e9:.4g} nm for the whole "
                    "hemisphere")
    if grid is not None:
        Lx, Ly = smp.extent
        if grid.du > lmin / Lx * (1 + 1e-9) or grid.dv > lmin / Ly * (1 + 1e-9):
            need = int(math.ceil((grid.u_range[1] - grid.u_range[0]) * Lx / lmin))
            msgs.append(f"coarse direction grid: du = {grid.du:.3g} > lambda/L = {lmin / Lx:.3g}; the specular "
                        f"spike is under-sampled and its albedo quadrature is inexact (use resolution >= {need})")
    return msgs


def brdf(surface, wi, wo, wavelengths_nm, material=None, *, solver: str = "direct", backend: str = "opencl",
         precision: str = "float32", window_name=DEFAULT_WINDOW, detrend: str = "mean", order="auto",
         resolution: int | None = None, realizations=None, seed: int = 0, runtime=None,
         progress=None) -> np.ndarray:
    """Kirchhoff BRDF for arbitrary outgoing directions, averaged over realizations.

    Parameters
    ----------
    surface : HeightField, list of HeightField, or callable seed -> HeightField
        The patch (or the ensemble; see :func:`scatter`).
    wi : (theta_deg, phi_deg) or ndarray (3,)
        Direction towards the light.
    wo : ndarray (n, 3)
        Unit vectors towards the viewer.
    wavelengths_nm : array_like, nm
    material : see :func:`fresnel_function`
    solver : {'direct', 'fft'}
        ``fft`` evaluates on a hemisphere grid (*resolution*, default: fine enough to resolve the specular spike
        at the shortest wavelength) and interpolates bilinearly in (u, v).
    backend : {'opencl', 'numpy'}
        For ``direct``: the kernel or its float64 NumPy twin.
    window_name, detrend : see :func:`window` and :func:`samples`.

    Returns
    -------
    ndarray (n_wl, n), sr⁻¹
    """
    _check_solver(solver, backend)
    wi = _incident(wi)
    wo = _outgoing(wo)
    wl = check_wavelengths(wavelengths_nm)
    F = fresnel_function(material)
    hfs = _realizations(surface, realizations, seed)
    acc = np.zeros((wl.size, wo.shape[0]))
    for hf in hfs:
        smp = samples(hf, window_name, detrend)
        if solver == "direct":
            for m in sampling_warnings(smp, wi, wl, wo=wo):
                _warn(m)
            coef = phase_coefficients(smp, wi, wo, wl)
            if backend == "numpy":
                U = kirchhoff_U(smp, coef)
            else:
                U = kirchhoff_U_cl(smp, coef, runtime=runtime, precision=precision, progress=progress)
            acc += brdf_from_field(U.reshape(wl.size, -1), wi, wo, wl, smp.area, F)
        else:
            from scipy.interpolate import RegularGridInterpolator

            res = resolution or min(2048, max(64, int(math.ceil(2 * max(smp.extent) / (wl.min() * 1e-9)))))
            grid = DirectionGrid.hemisphere(res)
            dirs = grid.directions()
            for m in sampling_warnings(smp, wi, wl, grid=grid):
                _warn(m)
            for i, lam in enumerate(wl):
                U, _ = field_fft(smp, wi, grid, lam, order)
                f = brdf_from_field(U[None], wi, dirs, [lam], smp.area, F)[0]
                interp = RegularGridInterpolator((grid.v, grid.u), f, bounds_error=False, fill_value=None)
                acc[i] += np.where(wo[:, 2] > 0, interp(np.stack([wo[:, 1], wo[:, 0]], axis=1)), 0.0)
                if progress is not None:
                    progress(1)
    return np.clip(acc / len(hfs), 0.0, None)


@dataclass
class ScatterResult:
    """Per-wavelength Kirchhoff lobes over a direction-cosine grid and their integrals.

    Attributes
    ----------
    wavelengths_nm : ndarray (n_wl,), nm
    grid : DirectionGrid
    brdf : ndarray (n_wl, n_v, n_u), sr⁻¹
        Ensemble-mean BRDF; 0 outside the unit disc.
    albedo : ndarray (n_wl,)
        Directional albedo ∫ f cos θ_o dω_o over the whole disc.
    albedo_inner : ndarray (n_wl,)
        The same over sin θ_o ≤ :data:`HORIZON_SIN` (the rest is the near-horizon share, where 1/cos θ_o
        amplifies any error and the tangent-plane model itself is least reliable).
    coherent_specular_fraction : ndarray (n_wl,)
        |⟨χ̂⟩|², the fraction of the specular reflectance that stays coherent (exp(−g) for Gaussian heights).
    scattered_fraction : ndarray (n_wl,)
        albedo − |⟨χ̂⟩|² · flat_albedo: the diffusely scattered reflectance (TIS = F (1 − exp(−g))).
    flat_albedo : ndarray (n_wl,)
        Albedo of the same window without heights on the same grid (≈ F(θ_i); the quadrature reference).
    fresnel_specular : ndarray (n_wl,)
        F(θ_i).
    """

    wavelengths_nm: np.ndarray
    grid: DirectionGrid
    brdf: np.ndarray
    albedo: np.ndarray
    albedo_inner: np.ndarray
    coherent_specular_fraction: np.ndarray
    scattered_fraction: np.ndarray
    flat_albedo: np.ndarray
    fresnel_specular: np.ndarray
    incident: np.ndarray
    solver: str
    realizations: int
    timings_s: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """Plain data for ``summary.json`` (lists, one entry per wavelength)."""
        th = math.degrees(math.acos(min(1.0, float(self.incident[2]))))
        ph = math.degrees(math.atan2(self.incident[1], self.incident[0]))
        return {
            "wavelengths_nm": self.wavelengths_nm, "albedo": self.albedo,
            "coherent_specular_fraction": self.coherent_specular_fraction,
            "scattered_fraction": self.scattered_fraction, "albedo_inner": self.albedo_inner,
            "horizon_sin": HORIZON_SIN, "flat_albedo": self.flat_albedo, "fresnel_specular": self.fresnel_specular,
            "incident_deg": [th, ph], "solver": self.solver, "realizations": self.realizations,
            "grid": {"n_u": self.grid.n_u, "n_v": self.grid.n_v, "u_range": self.grid.u_range,
                     "v_range": self.grid.v_range},
            "timings_s": self.timings_s, "warnings": self.warnings, "info": self.info,
        }


def scatter(surface, wi, wavelengths_nm, material=None, *, solver: str = "fft", resolution: int = 256,
            grid: DirectionGrid | None = None, realizations=None, seed: int = 0, backend: str = "opencl",
            precision: str = "float32", window_name=DEFAULT_WINDOW, detrend: str = "mean", order="auto",
            tol: float = FFT_TOL, runtime=None, progress=None) -> ScatterResult:
    """Kirchhoff lobes over the projected hemisphere, per wavelength, with albedo and coherent/scattered split.

    Parameters
    ----------
    surface : HeightField, list of HeightField, or callable seed -> HeightField
        One patch, an explicit ensemble, or a generator called with seeds ``seed .. seed + realizations − 1``.
        A single HeightField with ``realizations = n > 1`` is split into n tiles (:func:`split_patch`).
    wi : (theta_deg, phi_deg) or ndarray (3,)
        Direction towards the light.
    wavelengths_nm : array_like, nm
    material : see :func:`fresnel_function` (None: F = 1)
    solver : {'fft', 'direct'}
    resolution : int
        Cells per side of the hemisphere grid (ignored when *grid* is given).
    grid : DirectionGrid, optional
        A custom (sub-)grid of the direction-cosine plane.
    realizations : int, optional
    backend, precision : for the ``direct`` solver (OpenCL float32/float64, or the NumPy twin).
    window_name, detrend : see :func:`window` and :func:`samples`.
    order, tol : for the ``fft`` solver (see :func:`fft_plan`).
    progress : callable, optional
        Called with the number of finished work units (wavelengths × realizations); total is
        ``len(wavelengths) * realizations``.

    Returns
    -------
    ScatterResult
    """
    t0 = time.perf_counter()
    _check_solver(solver, backend)
    wi = _incident(wi)
    wl = check_wavelengths(wavelengths_nm)
    F = fresnel_function(material)
    grid = grid if grid is not None else DirectionGrid.hemisphere(resolution)
    if not grid.inside.any():
        raise WaveopticsError(f"direction grid u_range={grid.u_range}, v_range={grid.v_range} has no cell centre "
                              "inside the unit disc (above the horizon)")
    hfs = _realizations(surface, realizations, seed)
    dirs = grid.directions()
    inside = grid.inside
    horizon = grid.sin_theta <= HORIZON_SIN
    n_wl, R = wl.size, len(hfs)
    f_sum = np.zeros((n_wl, grid.n_v, grid.n_u))
    alb = np.zeros(n_wl)
    alb_in = np.zeros(n_wl)
    flat = np.zeros(n_wl)
    chi = np.zeros(n_wl, np.complex128)
    msgs: list[str] = []
    info = {"window": str(window_name)}
    t_solve = t_flat = 0.0
    d_in = dirs[inside]
    for r, hf in enumerate(hfs):
        smp = samples(hf, window_name, detrend)
        for m in sampling_warnings(smp, wi, wl, grid=grid):
            if m not in msgs:
                _warn(m, msgs)
        t1 = time.perf_counter()
        if solver == "direct":
            coef = phase_coefficients(smp, wi, d_in, wl)
            step = (lambda n, _k=d_in.shape[0]: progress(n / _k)) if progress is not None else None
            if backend == "numpy":
                Uin = kirchhoff_U(smp, coef)
                if progress is not None:
                    progress(n_wl)
            else:
                Uin = kirchhoff_U_cl(smp, coef, runtime=runtime, precision=precision, progress=step)
            U = np.zeros((n_wl, grid.n_v, grid.n_u), np.complex128)
            U[:, inside] = Uin.reshape(n_wl, -1)
            info.update(precision=precision if backend == "opencl" else "float64", backend=backend)
        else:
            U = np.empty((n_wl, grid.n_v, grid.n_u), np.complex128)
            for i, lam in enumerate(wl):
                U[i], inf = field_fft(smp, wi, grid, lam, order, tol)
                if r == 0:
                    info.setdefault("fft", []).append({"wavelength_nm": float(lam), **inf})
                if progress is not None:
                    progress(1)
        t_solve += time.perf_counter() - t1
        f = brdf_from_field(U, wi, dirs, wl, smp.area, F)
        f = np.where(inside, np.clip(f, 0.0, None), 0.0)
        f_sum += f
        alb += integrate(f, grid)
        alb_in += integrate(f, grid, region=horizon)
        t1 = time.perf_counter()
        for i, lam in enumerate(wl):
            chi[i] += coherent_amplitude(smp, wi, lam)
            U0, _ = field_fft(Samples(smp.ix, smp.iy, np.zeros_like(smp.h), smp.w, smp.dx, smp.dy, smp.nx,
                                      smp.ny, smp.area), wi, grid, lam, 0)
            flat[i] += integrate(brdf_from_field(U0[None], wi, dirs, [lam], smp.area, F)[0], grid)
        t_flat += time.perf_counter() - t1
    f_mean, alb, alb_in, flat, chi = f_sum / R, alb / R, alb_in / R, flat / R, chi / R
    coh = np.abs(chi) ** 2
    # guard: quadrature round-off can make the difference a hair negative for a flat patch
    scat = np.clip(alb - coh * flat, 0.0, None)
    spec_share = alb - alb_in
    bad = (spec_share > 0.05 * np.maximum(alb, 1e-300)) & (alb > 0)
    if np.any(bad):
        i = int(np.argmax(np.where(bad, spec_share / np.maximum(alb, 1e-300), 0)))
        _warn(f"{100 * spec_share[i] / alb[i]:.0f}% of the albedo at {wl[i]:g} nm lies near the horizon "
              f"(sin theta_o > {HORIZON_SIN}), where 1/cos theta_o amplifies errors and the tangent-plane model "
              "(no shadowing) is least reliable" + (" and the frozen-v_z fft approximation fails; use "
                                                    "order='auto' or solver='direct'"
                                                    if solver == "fft" and order != "auto" else ""), msgs)
    Fspec = np.asarray(F(np.full(n_wl, wi[2]), wl), dtype=float)
    # energy check: the lobe with F = 1 must not reflect more than the light that arrives (the flat patch's
    # albedo on this grid is 1 to quadrature accuracy); near grazing incidence the tangent-plane obliquity
    # factor grows as 1/cos θ_i and the model, which has no shadowing, breaks this (albedo 260 at 90°)
    Fg = np.asarray(F(cos_theta_d(wi, dirs)[None], wl[:, None, None]), dtype=float)
    alb1 = integrate(np.where(Fg > 0, f_mean / np.where(Fg > 0, Fg, 1.0), 0.0), grid)
    if np.any(alb1 > ENERGY_TOL):
        i = int(np.argmax(alb1))
        _warn(f"energy not conserved: the Kirchhoff albedo with F = 1 is {alb1[i]:.3g} > 1 at {wl[i]:g} nm for "
              f"theta_i = {math.degrees(math.acos(min(1.0, wi[2]))):.4g} deg; the tangent-plane model fails this "
              "close to grazing incidence (obliquity ~ 1/cos theta_i, no shadowing) and these lobes are not "
              "physical", msgs)
    timings = {"solve": t_solve, "flat_and_coherent": t_flat, "total": time.perf_counter() - t0}
    return ScatterResult(wl, grid, f_mean, alb, alb_in, coh, scat, flat, Fspec, wi, solver, R, timings, msgs, info)


# ----------------------------------------------------------------------------------------------------------------
# Output
# ----------------------------------------------------------------------------------------------------------------

#: files written by :func:`write_scatter`
SCATTER_FILES = ("lobes.exr", "summary.json", "lobes.png")


def plot_scatter(result: ScatterResult, path, *, overwrite: bool = True, max_lobes: int = 4):
    """PNG: the lobes at a few wavelengths (log scale, direction-cosine plane) and the fractions vs wavelength."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .io import atomic_path

    wl = result.wavelengths_nm
    idx = np.unique(np.linspace(0, wl.size - 1, min(max_lobes, wl.size)).round().astype(int))
    fig, axes = plt.subplots(1, idx.size + 1, figsize=(3.2 * (idx.size + 1) + 1.2, 3.4), layout="constrained")
    g = result.grid
    ext = (*g.u_range, *g.v_range)
    top = float(result.brdf.max()) if result.brdf.max() > 0 else 1.0
    im = None
    for ax, i in zip(axes[:-1], idx):
        f = np.where(g.inside, result.brdf[i], np.nan)
        im = ax.imshow(np.log10(np.maximum(f, top * 1e-8)), origin="lower", extent=ext, vmin=np.log10(top) - 8,
                       vmax=np.log10(top), cmap="magma")
        ax.set_title(f"{wl[i]:g} nm")
        ax.set_xlabel("u = sinθ cosφ")
        ax.set_ylabel("v = sinθ sinφ")
    if im is not None:
        fig.colorbar(im, ax=axes[idx.size - 1], label="log10 BRDF (1/sr)", shrink=0.8)
    ax = axes[-1]
    ax.plot(wl, result.albedo, "k-", label="albedo")
    ax.plot(wl, result.coherent_specular_fraction * result.flat_albedo, "b--", label="coherent")
    ax.plot(wl, result.scattered_fraction, "r:", label="scattered")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylim(bottom=0)
    ax.legend(fontsize=8)
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    plt.close(fig)


def write_scatter(result: ScatterResult, outdir, *, overwrite: bool = False, header: dict | None = None) -> dict:
    """Write ``lobes.exr`` (spectral OpenEXR, one ``T.<λ>nm`` layer per wavelength, BRDF in 1/sr on the
    direction-cosine grid), ``summary.json`` and ``lobes.png`` into *outdir*. Returns {name: path}."""
    from .io import prepare_outdir, write_json, write_spectral_exr

    out = prepare_outdir(outdir, overwrite=overwrite, expected=SCATTER_FILES)
    th = math.degrees(math.acos(min(1.0, float(result.incident[2]))))
    ph = math.degrees(math.atan2(result.incident[1], result.incident[0]))
    hdr = {**result.grid.header(), "quantity": "BRDF f (1/sr), Kirchhoff model, ensemble mean",
           "incident_theta_deg": f"{th:.17g}", "incident_phi_deg": f"{ph:.17g}", "solver": result.solver,
           "realizations": str(result.realizations), **(header or {})}
    layers = {float(w): result.brdf[i] for i, w in enumerate(result.wavelengths_nm)}
    paths = {"lobes.exr": write_spectral_exr(out / "lobes.exr", layers, hdr, overwrite=overwrite)}
    plot_scatter(result, out / "lobes.png", overwrite=overwrite)
    paths["lobes.png"] = out / "lobes.png"
    paths["summary.json"] = write_json(out / "summary.json", {**result.summary(), **(header or {})},
                                       overwrite=overwrite)
    return paths
