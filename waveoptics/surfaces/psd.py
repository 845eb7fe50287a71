"""Power spectral densities of isotropic random surfaces, in one vocabulary (σ and a length scale).

Two-sided PSDs S(f) with ∫ S d²f = σ², f in cycles per metre (docs/physics.md §4), their normalized
autocorrelations c(r) = C(r)/σ², and :class:`PSDModel`, the statistics of a nano surface used by the series
(:mod:`waveoptics.scatter.series`), the generators and the planner.

References
----------
.. [1] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012.
.. [2] E. L. Church, P. Z. Takacs, T. A. Leonard, "The prediction of BRDFs from surface profile measurements",
   Proc. SPIE 1165 (1989) (K-correlation / ABC model).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
from scipy import special

from ..errors import WaveopticsError, unknown

__all__ = ['S_gaussian', 'S1_gaussian', 'c_gaussian', 'S_exponential', 'S1_exponential', 'c_exponential', 'abc_A',
           'abc_sigma', 'S_abc', 'S1_abc', 'c_abc', 'PSDModel', 'PSDFamily', 'PSD_MODELS']

# --- PSD models (two-sided, ∫ S d²f = σ²) and their correlation functions -------------------------------

def S_gaussian(f, sigma, T):
    """Gaussian-correlation PSD π σ² T² exp(−π² T² f²); f in 1/m, σ and T in m (docs/physics.md §4)."""
    return np.pi * sigma ** 2 * T ** 2 * np.exp(-(np.pi * T * np.asarray(f)) ** 2)


def S1_gaussian(f, sigma, T):
    """Profile (1-D) PSD of the Gaussian-correlated surface: √π σ² T exp(−π² T² f²), m³.

    It is ∫ S(f_x, f_y) df_y of :func:`S_gaussian`, with ∫ S₁ df = σ² (Church, Takacs & Leonard 1989).
    """
    return math.sqrt(math.pi) * sigma ** 2 * T * np.exp(-(np.pi * T * np.asarray(f, dtype=float)) ** 2)


def c_gaussian(r, T):
    """Normalized Gaussian correlation exp(−r²/T²)."""
    return np.exp(-(np.asarray(r) / T) ** 2)


def S_exponential(f, sigma, T):
    """Exponential-correlation PSD 2π σ² T² / (1 + (2π T f)²)^{3/2} (docs/physics.md §4)."""
    return 2 * np.pi * sigma ** 2 * T ** 2 / (1 + (2 * np.pi * T * np.asarray(f)) ** 2) ** 1.5


def S1_exponential(f, sigma, T):
    """Profile (1-D) PSD of the exponentially correlated surface: 2 σ² T / (1 + (2π T f)²), m³."""
    return 2 * sigma ** 2 * T / (1 + (2 * np.pi * T * np.asarray(f, dtype=float)) ** 2)


def c_exponential(r, T):
    """Normalized exponential correlation exp(−r/T)."""
    return np.exp(-np.asarray(r) / T)


def _check_C(C):
    if not C > 2:
        raise WaveopticsError(f"ABC exponent C={C!r} is not allowed; it must be > 2 for a finite rms height")


def abc_A(sigma, B, C):
    """Plateau A (m⁴) of the ABC PSD with rms height σ: A = σ² B² (C − 2) / (2π) (docs/physics.md §4)."""
    _check_C(C)
    return sigma ** 2 * B ** 2 * (C - 2) / (2 * np.pi)


def abc_sigma(A, B, C):
    """rms height σ (m) of the ABC PSD with plateau A: σ² = 2π A / (B² (C − 2)) (Church & Takacs 1991).

    Examples
    --------
    >>> round(abc_sigma(abc_A(10e-9, 2e-6, 2.6), 2e-6, 2.6) * 1e9, 12)
    10.0
    """
    _check_C(C)
    return math.sqrt(2 * math.pi * A / (B ** 2 * (C - 2)))


def S_abc(f, sigma, B, C):
    """ABC / K-correlation PSD A / (1 + (B f)²)^{C/2}, with A set by σ (Church et al. 1989)."""
    return abc_A(sigma, B, C) / (1 + (B * np.asarray(f)) ** 2) ** (C / 2)


def S1_abc(f, sigma, B, C):
    """Profile (1-D) PSD of the ABC surface: A √π Γ((C−1)/2) / (B Γ(C/2)) · (1 + (B f)²)^{(1−C)/2}, m³.

    From ∫ (1 + B²(f_x² + f_y²))^{−C/2} df_y; it integrates to the same σ² as :func:`S_abc` (Church & Takacs
    1991).
    """
    pref = abc_A(sigma, B, C) * math.sqrt(math.pi) / B * math.exp(special.gammaln((C - 1) / 2)
                                                                   - special.gammaln(C / 2))
    return pref * (1 + (B * np.asarray(f, dtype=float)) ** 2) ** ((1 - C) / 2)


def c_abc(r, B, C):
    """Normalized K-correlation function: (a/2)^ν K_ν(a) · 2/Γ(ν), a = 2π r / B, ν = (C − 2)/2.

    It is the 2-D Hankel transform of the ABC PSD (Gradshteyn & Ryzhik 6.565.4), equal to 1 at r = 0.
    """
    nu = (C - 2) / 2
    a = 2 * np.pi * np.asarray(r, dtype=float) / B
    with np.errstate(invalid="ignore", over="ignore"):
        out = 2 / special.gamma(nu) * (a / 2) ** nu * special.kv(nu, a)
    return np.where(a < 1e-12, 1.0, out)


@dataclass(frozen=True)
class PSDModel:
    """An isotropic height PSD: ``kind`` in PSD_MODELS, σ (m) and shape parameters (m or unitless).

    ``T`` is the formulas' symbol for the correlation length, which nano text, :func:`~waveoptics.surfaces.generate`,
    the CLI and JSON call ``corr_length``.
    """

    kind: str
    sigma: float
    T: float | None = None  # T, the correlation length (corr_length) of gaussian and exponential, m
    B: float | None = None  # ABC: m
    C: float | None = None  # ABC: exponent > 2

    def __post_init__(self):
        if self.kind not in PSD_MODELS:
            raise unknown("PSD model", self.kind, PSD_MODELS)
        if not np.isfinite(self.sigma) or self.sigma < 0:
            raise WaveopticsError(f"sigma={self.sigma!r} m is not allowed; rms height must be >= 0")
        if self.kind in ("gaussian", "exponential"):
            if self.T is None or not np.isfinite(self.T) or self.T <= 0:
                raise WaveopticsError(f"correlation length T={self.T!r} m is not allowed; it must be > 0")
        else:
            if self.B is None or not np.isfinite(self.B) or self.B <= 0:
                raise WaveopticsError(f"ABC parameter B={self.B!r} m is not allowed; it must be > 0")
            if self.C is None or not np.isfinite(self.C) or self.C <= 2:
                raise WaveopticsError(f"ABC parameter C={self.C!r} is not allowed; it must be > 2 (finite σ)")

    @property
    def shape(self) -> tuple:
        """The shape parameters of this family, in the order of its functions: (T,) or (B, C)."""
        return tuple(getattr(self, k) for k in PSD_MODELS[self.kind].shape)

    def S(self, f):
        """Two-sided PSD at spatial frequency |f| (1/m), m⁴ (σ² per unit frequency area)."""
        return PSD_MODELS[self.kind].S(f, self.sigma, *self.shape)

    def S1(self, f):
        """Profile (1-D) PSD at frequency f (1/m), m³."""
        return PSD_MODELS[self.kind].S1(f, self.sigma, *self.shape)

    def c(self, r):
        """Normalized correlation C(r)/σ² at lag r (m)."""
        return PSD_MODELS[self.kind].c(r, *self.shape)

    @property
    def length_scale(self) -> float:
        """A correlation length (m): T, or B/(2π) for ABC."""
        return self.T if self.T is not None else self.B / (2 * np.pi)

    def lobe_width(self, wavelength_nm: float) -> float:
        """Standard deviation (direction cosines) of the first-order scattered lobe at *wavelength_nm* (nm):
        λ / (√2 π ℓ) with ℓ = :attr:`length_scale`. For a Gaussian PSD π σ² T² exp(−π² T² f²) the spatial frequency
        has rms 1/(√2 π T) per axis, and a frequency f turns the light by λ f in direction cosines (the grating
        equation); for ABC it is √2 times the knee's turn λ/B.

        References
        ----------
        .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §2.4 (grating equation), §4.3 (the PSD
           families).
        """
        return float(wavelength_nm) * 1e-9 / (np.sqrt(2.0) * np.pi * self.length_scale)

    def lobe_curvature(self, wavelength_nm: float, floor: float = 1e-3) -> float:
        """Largest |f''/f| (per direction cosine squared) of the first-order lobe's radial profile f(u) ∝ S(u/λ)
        (u the turn in direction cosines, λ *wavelength_nm* in nm) where f is at least *floor* of its peak: linear
        interpolation on cells du apart errs there by at most du² |f''/f| / 8 of the value (de Boor 1978). A
        Gaussian lobe of std s gives (2 ln(1/floor) − 1)/s², set by its steep flanks; a power law (ABC,
        exponential) its core's. Evaluated by finite differences of log f on 20001 radii evenly spaced up to
        100 :meth:`lobe_width` (at most 2).

        References
        ----------
        .. [1] C. de Boor, *A Practical Guide to Splines*, Springer 1978, ch. II (error of linear interpolation).
        .. [2] E. L. Church, P. Z. Takacs, T. A. Leonard, Proc. SPIE 1165, 136-150, 1989 (the lobe ∝ S(f),
           f = turn / λ, to first order).
        """
        u = np.linspace(0.0, min(2.0, 100.0 * self.lobe_width(wavelength_nm)), 20001)
        f = self.S(u / (float(wavelength_nm) * 1e-9))
        keep = f >= floor * f[0]
        log_f = np.log(np.maximum(f, np.finfo(float).tiny))
        d1 = np.gradient(log_f, u)
        return float(np.max(np.abs(np.gradient(d1, u) + d1 * d1)[keep]))


class PSDFamily(NamedTuple):
    """One PSD family: 2-D PSD S(f, σ, *shape), profile PSD S1(f, σ, *shape), correlation c(r, *shape)."""

    S: Callable
    S1: Callable
    c: Callable
    shape: tuple  # names of the shape parameters, e.g. ("T",) or ("B", "C")


#: the PSD families, one vocabulary (σ and shape parameters) for generators, fits, the series and scenes
PSD_MODELS = {
    "gaussian": PSDFamily(S_gaussian, S1_gaussian, c_gaussian, ("T",)),
    "exponential": PSDFamily(S_exponential, S1_exponential, c_exponential, ("T",)),
    "abc": PSDFamily(S_abc, S1_abc, c_abc, ("B", "C")),
}
