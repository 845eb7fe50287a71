"""Statistical scattering from a surface's height statistics (PSD), without a height field.

For a surface with Gaussian height statistics, rms height σ and autocorrelation C(r), the Kirchhoff
(tangent-plane) BRDF of docs/physics.md §1 has the ensemble average (Beckmann & Spizzichino 1963, ch. 5)

    ⟨|U|²⟩ / A_w = e^{−g} ∫ (e^{v_z² C(r)} − 1) e^{i v_xy·r} d²r  (diffuse part)
                 = Σ_{m≥1} p_m(g) · H_m(|v_xy|),   p_m(g) = e^{−g} g^m / m!,   g = v_z² σ²,

with v = k(ω_i + ω_o) and H_m(q) = ∫ c(r)^m e^{i q·r} d²r = 2π ∫ c(r)^m J0(q r) r dr the Fourier transform of
the m-th power of the normalized correlation c = C/σ². The m = 1 term is the Rayleigh-Rice first-order
perturbation result (docs/physics.md §4), since H_1(q) = S(q/2π)/σ². For a Gaussian correlation the H_m are closed
form and the sum is the Beckmann-Spizzichino series of docs/physics.md §3; this module evaluates the series for *any*
isotropic PSD (Gaussian, exponential, ABC/K-correlation) by Hankel transforms of c^m, once per surface (the
tables do not depend on λ or direction), so lobes for many wavelengths and directions cost only table look-ups.

The BRDF of the scattered (diffuse) part is then, with the obliquity factor of docs/physics.md §1,

    f_s(ω_i, ω_o) = F(θ_d) |ω_i + ω_o|⁴ / (4 λ² cosθ_i cosθ_o (cosθ_i + cosθ_o)²) · Σ_m p_m(g) H_m(|v_xy|),

and the coherent (specular) part carries the fraction e^{−g} of F (Davies 1954; docs/physics.md §2).

Where it breaks
---------------
* Gaussian height statistics are assumed; real polished surfaces are often close, scratched ones are not.
* The series is truncated at ``m_max`` terms; for g ≳ 30 (σ cosθ ≳ 0.45 λ) the truncation loses energy and
  :func:`scattered_lobe` reports the captured fraction — use a height-field solver (waveoptics.scatter)
  or the geometric (microfacet) limit there.
* Tangent-plane approximation: correlation lengths below ~λ and grazing angles are outside its validity.

References
----------
.. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, 1963, ch. 5.
.. [2] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 209 (1954).
.. [3] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012 (Rayleigh-Rice; PSDs).
.. [4] E. L. Church, P. Z. Takacs, T. A. Leonard, "The prediction of BRDFs from surface profile measurements",
   Proc. SPIE 1165 (1989) (K-correlation / ABC model).
.. [5] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 2017 (ABC PSD for nano-roughness).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy import special, stats

from ..surfaces.psd import PSDModel
from .models import K_kirchhoff

__all__ = ['M_MAX', 'SeriesTables', 'series_tables', 'SeriesSum', 'series_sum', 'poisson_weights', 'roughness_g', 'series_terms', 'debye_waller', 'obliquity', 'rayleigh_rice']

#: most terms of the series (:func:`scattered_lobe`)
M_MAX = 48

# --- Kirchhoff-series tables -----------------------------------------------------------------------------

@dataclass(frozen=True)
class SeriesTables:
    """H_m(q) for m = 1..m_max on a q grid (rad/m): ``H[m-1, iq]`` in m²."""

    q: np.ndarray
    H: np.ndarray
    model: PSDModel

    def Hm(self, q):
        """Interpolated H_m(|q|) for all m: array (m_max, *q.shape); zero beyond the table."""
        q = np.asarray(q, dtype=float)
        out = np.empty((self.H.shape[0],) + q.shape)
        for i in range(1, self.H.shape[0]):
            out[i] = np.interp(q, self.q, self.H[i], right=0.0)
        # m = 1 is the PSD itself, exactly (no quadrature error, and correct tails); S ∝ σ², so S/σ² is the PSD
        # at σ = 1 (guard: σ² underflows to 0 for σ < 1e-154 m, and S/σ² was then NaN)
        out[0] = replace(self.model, sigma=1.0).S(q / (2 * np.pi))
        return out


@functools.lru_cache(maxsize=32)
def series_tables(model: PSDModel, q_max: float, m_max: int = M_MAX, n_q: int = 1536) -> SeriesTables:
    """Hankel transforms H_m(q) = 2π ∫ c(r)^m J0(q r) r dr, m = 1..m_max, for 0 ≤ q ≤ q_max (rad/m).

    The radial integral uses the trapezoid rule on a grid that resolves both the correlation length and the
    shortest period 2π/q_max, out to where c^2 has decayed below 1e-10 (m = 1 is taken from the closed-form PSD).

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963, ch. 5, eq. (5.21) (series of Fourier transforms of C^m).
    """
    L = model.length_scale
    # r_max: where c(r)^2 < 1e-10 (c^m for m >= 2 decays at least as fast)
    r_probe = L * np.logspace(-3, 4, 2000)
    cp = model.c(r_probe)
    idx = np.nonzero(cp ** 2 < 1e-10)[0]
    r_max = r_probe[idx[0]] if idx.size else r_probe[-1]
    dr = min(L / 40, 2 * np.pi / q_max / 12)
    n_r = int(min(max(r_max / dr, 400), 20000))
    r = np.linspace(0.0, r_max, n_r)
    w = np.full(n_r, r[1] - r[0])
    w[0] = w[-1] = 0.5 * (r[1] - r[0])
    q = np.linspace(0.0, q_max, n_q)
    c = model.c(r)
    H = np.empty((m_max, n_q))
    J = special.j0(np.outer(q, r)) * (2 * np.pi * r * w)  # (n_q, n_r)
    cm = np.ones_like(c)
    # Euler-Maclaurin end correction: the integrand 2π r c^m J0(q r) has slope 2π at r = 0 for every q and m,
    # so the plain trapezoid rule carries a q-independent bias of −2π dr²/12. Left in, that floor is amplified
    # by the 1/cosθ_o obliquity near the horizon (docs/physics.md §1 warns about exactly this).
    end_fix = 2 * np.pi * (r[1] - r[0]) ** 2 / 12
    # c^m for m = 1..m_max as the columns of one matrix: every H_m in one pass over J (a product per term read the
    # (n_q, n_r) matrix m_max times)
    powers = np.empty((n_r, m_max))
    for m in range(1, m_max + 1):
        cm = cm * c
        powers[:, m - 1] = cm
    H[:] = (J @ powers).T + end_fix
    # guard: H_m is the Fourier transform of a positive-definite function (Bochner), so it is >= 0;
    # values below 1e-12 of the peak are quadrature noise and are set to 0.
    H = np.where(H > 1e-12 * H[:, :1], H, 0.0)
    return SeriesTables(q=q, H=H, model=model)


@dataclass(frozen=True)
class SeriesSum:
    """The summed series Σ_m p_m(g) H_m(q) (m²) of one PSD model at one wavelength, for look-ups at any (q, c).

    c = cosθ_i + cosθ_o (g = (kσc)²). The terms m ≥ 2 are tabulated on a uniform (c, q) grid and interpolated
    bilinearly; the m = 1 term g e^{−g} S(q/2π)/σ² is exact (it holds the far tail). Built once per model and λ,
    a look-up costs the same for any number of terms, which is what lets the two-scale BRDF be evaluated at
    many direction pairs (:class:`waveoptics.brdf.TwoScaleBRDF`).
    """

    model: PSDModel
    wavelength_nm: float
    q: np.ndarray
    c: np.ndarray
    S: np.ndarray

    def __call__(self, q, cos_sum):
        q = np.asarray(q, dtype=float)
        c = np.clip(np.asarray(cos_sum, dtype=float), self.c[0], self.c[-1])
        g = roughness_g(self.model.sigma, c, self.wavelength_nm)
        fq = q / (self.q[1] - self.q[0])
        iq = np.minimum(fq.astype(np.int64), self.q.size - 2)
        tq = fq - iq
        fc = (c - self.c[0]) / (self.c[1] - self.c[0])
        ic = np.minimum(fc.astype(np.int64), self.c.size - 2)
        tc = fc - ic
        S = self.S
        rest = ((1 - tc) * ((1 - tq) * S[ic, iq] + tq * S[ic, iq + 1])
                + tc * ((1 - tq) * S[ic + 1, iq] + tq * S[ic + 1, iq + 1]))
        rest = np.where(fq <= self.q.size - 1, rest, 0.0)
        first = g * np.exp(-g) * replace(self.model, sigma=1.0).S(q / (2 * np.pi))
        return first + rest


@functools.lru_cache(maxsize=64)
def series_sum(model: PSDModel, wavelength_nm: float, n_c: int = 513, m_max: int = M_MAX) -> SeriesSum:
    """:class:`SeriesSum` of *model* at *wavelength_nm* (nm) for c = cosθ_i + cosθ_o in [0, 2] (every model's
    vertical phase lies there) and q up to the table's q_max ≥ 2k (every reflected direction).

    The c grid of *n_c* points resolves the Poisson weights: at the largest g the series allows (≈ 30) one step
    moves g by < 0.25; measured against the term-by-term sum, the bilinear error is < 2e-3 wherever the lobe
    exceeds 1e-4 of its peak (``tests/test_brdf_function.py``).
    """
    lam = float(wavelength_nm)
    k = 2 * np.pi / (lam * 1e-9)
    q_max = 2.0 ** math.ceil(math.log2(2 * k * 1.001 + 1.0))
    tab = series_tables(model, q_max, m_max)
    c = np.linspace(0.0, 2.0, int(n_c))
    g = roughness_g(model.sigma, c, lam)
    m_use = series_terms(float(g.max()), m_max)
    p = poisson_weights(g, m_use)                   # (M, n_c)
    S = p[1:].T @ tab.H[1:m_use]                    # m >= 2
    return SeriesSum(model=model, wavelength_nm=lam, q=tab.q, c=c, S=S)


def poisson_weights(g, m_max):
    """p_m(g) = e^{−g} g^m / m!, m = 1..m_max, computed stably (array (m_max, *g.shape))."""
    g = np.asarray(g, dtype=float)
    m = np.arange(1, m_max + 1).reshape((-1,) + (1,) * g.ndim)
    return stats.poisson.pmf(m, g)


def roughness_g(sigma_m, cos_sum, wavelength_nm):
    """Roughness factor g = [k σ (cosθ_i + cosθ_o)]², k = 2π/λ (docs/physics.md §2, §3).

    Parameters
    ----------
    sigma_m : float, m
        rms height.
    cos_sum : array_like
        cosθ_i + cosθ_o (2 cosθ_i at the mirror direction, where g = (4πσ cosθ_i / λ)²).
    wavelength_nm : array_like, nm
    """
    k = 2 * np.pi / (np.asarray(wavelength_nm, dtype=float) * 1e-9)
    return (k * sigma_m * np.asarray(cos_sum, dtype=float)) ** 2


def series_terms(g, m_max: int = M_MAX) -> int:
    """Terms of the Poisson series worth summing at roughness factor *g*: beyond g + 8√g + 10 the terms carry
    < 1e-12 of the Poisson mass (at most *m_max*)."""
    g = float(g)
    return int(min(m_max, math.ceil(g + 8 * math.sqrt(g) + 10)))


def debye_waller(cos_theta_i, wavelength_nm, sigma):
    """exp(−g) with g = (4πσ cosθ_i/λ)²: the Debye-Waller factor of the whole rms height σ, the coherent fraction
    of the reflected light of a surface with Gaussian heights whose roughness all lies in the propagating band.
    The band-limited factor is :meth:`waveoptics.scatter.BandSeries.debye_waller`; the two-scale model's coherent
    fraction is :meth:`waveoptics.brdf.Nano.coherent_fraction`.

    References
    ----------
    .. [1] H. Davies, Proc. IEE 101, 209 (1954); H. E. Bennett, J. O. Porteus, JOSA 51, 123 (1961).
    """
    return np.exp(-roughness_g(sigma, 2 * np.asarray(cos_theta_i, dtype=float), wavelength_nm))


def obliquity(wi, wo, wavelength_nm):
    """|ω_i + ω_o|⁴ / (4 λ² cosθ_i cosθ_o (cosθ_i + cosθ_o)²) in 1/m² (docs/physics.md §1); 0 below the surface: the
    Kirchhoff factor of :data:`waveoptics.scatter.DIFFRACTION_MODELS`."""
    return K_kirchhoff(wi, wo, wavelength_nm)


def rayleigh_rice(wi, wo, wavelength_nm, model: PSDModel, Q=1.0):
    """First-order (Rayleigh-Rice) BRDF (16π²/λ⁴) cosθ_i cosθ_o Q S(f_x, f_y), f = (ω_i + ω_o)_xy / λ.

    *model* is a :class:`~waveoptics.surfaces.PSDModel` (isotropic, S(|f|)) or a PSD with ``S_xy(f_x, f_y)``
    such as a height field's :class:`~waveoptics.surfaces.PeriodogramPSD` (anisotropy kept; S is even in f).

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., eq. (4.1); docs/physics.md §4.
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    s = wi + wo
    if hasattr(model, "S_xy"):
        S = model.S_xy(s[..., 0] / lam, s[..., 1] / lam)
    else:
        S = model.S(np.hypot(s[..., 0], s[..., 1]) / lam)
    ok = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    return np.where(ok, 16 * np.pi ** 2 / lam ** 4 * wi[..., 2] * wo[..., 2] * np.asarray(Q) * S, 0.0)
