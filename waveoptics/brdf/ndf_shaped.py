"""The NDFs with a shape parameter (``ndf_shape``) and no closed-form Smith Λ: ABC (tail exponent C), EPD and SGD
(exponent p); their Λ is the radial quadrature of their slope law.

Every per-NDF function takes (vector, ax, ay, c), c the shape parameter (None: the NDF's default). Vectors are
unit; m_z <= 0 gives D = 0, w_z <= 0 gives Λ = inf.

References
----------
.. [1] J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient Rendering of
   Glossy Surfaces", ACM TOG 31(1):9, 2012 (ABC).
.. [2] N. Holzschuch, R. Pacanowski, ACM TOG 36(4):66, 2017 (EPD).
.. [3] M. M. Bagher, C. Soler, N. Holzschuch, Computer Graphics Forum 31(4), 2012 (SGD).
.. [4] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.
"""
from __future__ import annotations

import numpy as np
from scipy import special

from .anisotropy import STRETCH_EXPONENT, D_stretched, Lambda_stretched
from .smith import Lambda_radial

__all__ = ['ABC_C_DEFAULT', 'abc_normalization', 'D_abc', 'Lambda_abc', 'EPD_P_DEFAULT', 'epd_normalization',
           'D_epd', 'Lambda_epd', 'SGD_P_DEFAULT', 'gamma_upper', 'sgd_normalization', 'D_sgd', 'Lambda_sgd']

#: default tail exponent C of the ABC NDF (C = 2 has the same core as GGX)
ABC_C_DEFAULT = 2.0


def _one_minus_cos(m):
    """1 − m_z for unit m, as (m_x² + m_y²)/(1 + m_z) (no cancellation near the normal)."""
    s2 = m[..., 0] ** 2 + m[..., 1] ** 2
    return s2 / (1.0 + np.maximum(m[..., 2], 0.0))



def abc_B(ax):
    return 2.0 / (ax * ax)


def expm1_over(p, L):
    """(e^{pL} − 1)/p with its limit L at p = 0."""
    p = np.asarray(p, dtype=float)
    safe = np.where(p == 0, 1.0, p)
    return np.where(p == 0, L, np.expm1(p * L) / safe)


def abc_normalization(alpha, c=None):
    """Constant A of the ABC NDF D = A (1 + B(1 − n·m))^{−C}, B = 2/α², such that ∫ D (n·m) dω = 1.

    A = 1 / (2π (I₁ − I₂)), I₁ = ∫₀¹ (1 + Bu)^{−C} du, I₂ = ∫₀¹ u (1 + Bu)^{−C} du (u = 1 − cos θ), in closed
    form: with E(p) = ((1 + B)^p − 1)/p, I₁ = E(1 − C)/B and I₂ = (E(2 − C) − E(1 − C))/B².

    References
    ----------
    .. [1] J. Löw et al., ACM TOG 31(1), 2012, §5 (the ABC microfacet distribution).
    """
    c = ABC_C_DEFAULT if c is None else c
    B = abc_B(np.asarray(alpha, dtype=float))
    L = np.log1p(B)
    e1 = expm1_over(1.0 - c, L)
    e2 = expm1_over(2.0 - c, L)
    i1 = e1 / B
    i2 = (e2 - e1) / (B * B)
    return 1.0 / (2.0 * np.pi * (i1 - i2))


def D_abc(m, ax, ay=None, c=None):
    """ABC NDF of Löw et al. (2012): A / (1 + B(1 − n·m))^C with B = 2/α² (isotropic, α = ax).

    Near the normal 1 − n·m ≈ tan²θ/2, so D ∝ (1 + tan²θ/α²)^{−C}: α is the slope scale like GGX's and C sets
    the tail (C = 2: GGX-like core; smaller C: longer tail). A is :func:`abc_normalization`.

    References
    ----------
    .. [1] J. Löw, J. Kronander, A. Ynnerman, J. Unger, ACM TOG 31(1):9, 2012, §5.
    """
    c = ABC_C_DEFAULT if c is None else c
    A = abc_normalization(ax, c)
    val = A * (1.0 + abc_B(ax) * _one_minus_cos(m)) ** (-c)
    return np.where(m[..., 2] > 0, val, 0.0)



def _P22_abc(r, ax, c):
    # D(θ) cos⁴θ with cos θ = 1/√(1+r²); 1 − cos θ = r² / (√(1+r²) (1 + √(1+r²)))
    q = np.sqrt(1.0 + r * r)
    one_minus = r * r / (q * (1.0 + q))
    return abc_normalization(ax, c) * (1.0 + abc_B(ax) * one_minus) ** (-c) / (q ** 4)


def Lambda_abc(w, ax, ay=None, c=None):
    """Smith Λ of the ABC NDF (no closed form): :func:`Lambda_radial` of its slope law.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72).
    .. [2] J. Löw et al., ACM TOG 31(1), 2012.
    """
    c = ABC_C_DEFAULT if c is None else c
    return Lambda_radial(w, lambda r: _P22_abc(r, ax, c), ax)



# ----------------------------------------------------------------------------------------------------------
# EPD: exponential power distribution of slopes (Holzschuch & Pacanowski 2017)

#: default exponent p of the EPD (p = 1 is Beckmann)
EPD_P_DEFAULT = 1.0


def _tan2(m):
    """tan²θ from the components, (m_x² + m_y²)/m_z² (not (1 − m_z²)/m_z², which cancels near the normal)."""
    cz = m[..., 2]
    return np.where(cz > 0, (m[..., 0] ** 2 + m[..., 1] ** 2) / np.where(cz > 0, cz * cz, 1.0), np.inf)


def epd_normalization(alpha, p):
    """Constant of the EPD slope law P22(r) = N exp(−(r²/α²)^p): N = p / (π α² Γ(1/p)), so that
    ∫ P22 d²r = 2π ∫₀^∞ r P22 dr = 1 (substitute u = (r/α)^{2p})."""
    return p / (np.pi * alpha * alpha * special.gamma(1.0 / p))


def _P22_epd(r, ax, p):
    return epd_normalization(ax, p) * np.exp(-((r * r) / (ax * ax)) ** p)


def D_epd(m, ax, ay=None, c=None):
    """Exponential power NDF: D(m) = P22(tan θ_m) / cos⁴θ_m with the slope law P22(r) = N exp(−(r²/α²)^p).

    p = 1 is Beckmann; p < 1 has longer tails (closer to measured polished metals), p > 1 a flatter core and a
    faster fall-off. α is the slope scale, p the ``ndf_shape`` (default :data:`EPD_P_DEFAULT`). With α_y ≠ α_x
    the law is stretched (:func:`D_stretched`): P22 = N exp(−((x̃/α_x)² + (ỹ/α_y)²)^p) / (α_x α_y) with N of
    α = 1, which is anisotropic Beckmann at p = 1.

    References
    ----------
    .. [1] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
       diffraction", ACM TOG 36(4):66, 2017, §4.2 (EPD slope distribution).
    .. [2] E. Heitz, JCGT 3(2), 2014, eq. (8) (D from the slope distribution, D = P22 / cos⁴θ).
    """
    if ay is not None and np.any(np.asarray(ay) != np.asarray(ax)):
        return D_stretched(D_epd, m, ax, ay, c, STRETCH_EXPONENT["epd"])
    p = EPD_P_DEFAULT if c is None else c
    cz = m[..., 2]
    t2 = _tan2(m)
    with np.errstate(over="ignore", invalid="ignore"):
        val = epd_normalization(ax, p) * np.exp(-(t2 / (ax * ax)) ** p) / np.where(cz > 0, cz, 1.0) ** 4
    return np.where(cz > 0, np.nan_to_num(val, nan=0.0, posinf=0.0), 0.0)


def Lambda_epd(w, ax, ay=None, c=None):
    """Smith Λ of the EPD (no closed form for p ≠ 1): :func:`Lambda_radial` of its slope law (anisotropic:
    :func:`Lambda_stretched`).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72).
    """
    if ay is not None and np.any(np.asarray(ay) != np.asarray(ax)):
        return Lambda_stretched(Lambda_epd, w, ax, ay, c, STRETCH_EXPONENT["epd"])
    p = EPD_P_DEFAULT if c is None else c
    return Lambda_radial(w, lambda r: _P22_epd(r, ax, p), ax)


# ----------------------------------------------------------------------------------------------------------
# SGD: shifted gamma distribution (Bagher, Soler & Holzschuch 2012)

#: default exponent p of the SGD
SGD_P_DEFAULT = 1.0


def gamma_upper(a, y):
    """Upper incomplete gamma Γ(a, y) = ∫_y^∞ t^{a−1} e^{−t} dt for any real a and y > 0.

    a > 0: SciPy's regularized ``gammaincc`` times Γ(a); a = 0: E₁(y); a < 0: the recurrence
    Γ(a, y) = (Γ(a + 1, y) − y^a e^{−y}) / a, applied upward from a + n in [0, 1).

    References
    ----------
    .. [1] NIST DLMF §8.8.2 (recurrence), §8.4.4 (Γ(0, y) = E₁(y)).
    """
    a = float(a)
    y = np.asarray(y, dtype=float)
    if a > 0:
        return special.gammaincc(a, y) * special.gamma(a)
    n = int(np.ceil(-a)) if a != int(a) else int(-a)
    base = a + n                     # in [0, 1)
    g = special.exp1(y) if base == 0 else special.gammaincc(base, y) * special.gamma(base)
    for k in range(n, 0, -1):        # Γ(b − 1, y) = (Γ(b, y) − y^{b−1} e^{−y}) / (b − 1), b = a + k
        b = a + k
        g = (g - y ** (b - 1.0) * np.exp(-y)) / (b - 1.0)
    return g


def sgd_normalization(alpha, p):
    """Constant K of the SGD slope law P22(x) = K e^{−(α² + x)/α} / (α² + x)^p in x = tan²θ:
    K = α^{p−1} / Γ(1 − p, α), so that ∫₀^∞ P22 dx = 1 (y = (α² + x)/α turns the integral into
    α^{1−p} Γ(1 − p, α))."""
    return alpha ** (p - 1.0) / gamma_upper(1.0 - p, alpha)


def _P22x_sgd(x, ax, p):
    return sgd_normalization(ax, p) * np.exp(-(ax * ax + x) / ax) / (ax * ax + x) ** p


def D_sgd(m, ax, ay=None, c=None):
    """Shifted gamma NDF: D(m) = P22(tan²θ_m) / (π cos⁴θ_m), P22(x) = K e^{−(α² + x)/α} / (α² + x)^p.

    Fitted to the MERL measurements by Bagher et al., whose materials need tails between GGX's and Beckmann's:
    the power law (α² + x)^{−p} sets the tail, the exponential cuts it at tan²θ ~ α. α is a scale of tan²θ (the
    slope scale is about √α), p the ``ndf_shape`` (default :data:`SGD_P_DEFAULT`). Bagher et al. fit isotropic
    materials; with α_y ≠ α_x the law of ᾱ = √(α_x α_y) is stretched by √(α_x/ᾱ), √(α_y/ᾱ) in slope
    (:func:`D_stretched`), so that tan²θ scales as α_x along x and as α_y along y.

    References
    ----------
    .. [1] M. M. Bagher, C. Soler, N. Holzschuch, "Accurate fitting of measured reflectances using a Shifted
       Gamma micro-facet distribution", Computer Graphics Forum 31(4), 2012, §4 (eqs. 9–11).
    """
    if ay is not None and np.any(np.asarray(ay) != np.asarray(ax)):
        return D_stretched(D_sgd, m, ax, ay, c, STRETCH_EXPONENT["sgd"])
    p = SGD_P_DEFAULT if c is None else c
    cz = m[..., 2]
    x = _tan2(m)
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        val = _P22x_sgd(x, ax, p) / (np.pi * np.where(cz > 0, cz, 1.0) ** 4)
    return np.where(cz > 0, np.nan_to_num(val, nan=0.0, posinf=0.0), 0.0)


def Lambda_sgd(w, ax, ay=None, c=None):
    """Smith Λ of the SGD: :func:`Lambda_radial` of its slope law P22(r²)/π, nodes placed at the slope scale √α
    (anisotropic: :func:`Lambda_stretched`).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72).
    """
    if ay is not None and np.any(np.asarray(ay) != np.asarray(ax)):
        return Lambda_stretched(Lambda_sgd, w, ax, ay, c, STRETCH_EXPONENT["sgd"])
    p = SGD_P_DEFAULT if c is None else c
    return Lambda_radial(w, lambda r: _P22x_sgd(r * r, ax, p) / np.pi, np.sqrt(ax))

