"""Normal distribution functions D and Smith's Λ for GGX, Beckmann, Blinn-Phong, ABC, EPD and SGD, isotropic and
anisotropic, and the roughness conversions.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007.
.. [2] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.
.. [3] J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient Rendering of
   Glossy Surfaces", ACM TOG 31(1):9, 2012 (ABC).
.. [4] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes (α = r²).
.. [5] N. Holzschuch, R. Pacanowski, ACM TOG 36(4):66, 2017 (EPD).
.. [6] M. M. Bagher, C. Soler, N. Holzschuch, Computer Graphics Forum 31(4), 2012 (SGD).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import special

from ..errors import WaveopticsError, unknown
from .measured_ndf import D_tabulated, Lambda_tabulated, SlopeTable

__all__ = ['ALPHA_MIN', 'ALPHA_MAX', 'COS_MIN', 'ABC_C_DEFAULT', 'LAMBDA_GL_ORDER', 'alpha_from_roughness', 'roughness_from_alpha', 'blinn_phong_exponent', 'alpha_from_blinn_phong', 'half_vector', 'reflect', 'D_ggx', 'Lambda_ggx', 'D_beckmann', 'Lambda_beckmann', 'D_blinn_phong', 'Lambda_blinn_phong', 'abc_normalization', 'D_abc', 'Lambda_radial', 'Lambda_abc', 'stretch_factors', 'D_stretched', 'Lambda_stretched', 'STRETCH_EXPONENT', 'EPD_P_DEFAULT', 'epd_normalization', 'D_epd', 'Lambda_epd', 'SGD_P_DEFAULT', 'gamma_upper', 'sgd_normalization', 'D_sgd', 'Lambda_sgd', 'SHAPE_RANGE', 'NDF', 'NDFS', 'D', 'Lambda', 'G1']

#: roughness floor (guard): narrower lobes are not representable at sampled directions
ALPHA_MIN = 1e-4
#: largest accepted α (mean slope 2, i.e. facets at 63° on average; larger is not a surface model any more)
ALPHA_MAX = 2.0
#: floor of the cosines in the specular denominator (guard against 1/cos θ growth at the horizon)
COS_MIN = 1e-7
#: default tail exponent C of the ABC NDF (C = 2 has the same core as GGX)
ABC_C_DEFAULT = 2.0
#: Gauss-Legendre order of the radial quadrature used for Λ of NDFs without a closed form (ABC), and of the
#: kernel's Λ for Blinn-Phong; the kernel keeps the same nodes in ``kernels/microfacet.h``
LAMBDA_GL_ORDER = 32


# ----------------------------------------------------------------------------------------------------------
# roughness conventions


def alpha_from_roughness(roughness):
    """NDF width α from the perceptual roughness r of Burley (2012): α = r².

    Parameters
    ----------
    roughness : array_like
        Perceptual roughness in [0, 1] (dimensionless).

    References
    ----------
    .. [1] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes, §5.4.
    """
    r = np.asarray(roughness, dtype=float)
    if np.any(~np.isfinite(r) | (r < 0)):
        bad = r[~np.isfinite(r) | (r < 0)].ravel()[0] if r.ndim else r
        raise WaveopticsError(f"roughness={float(bad)!r} is not allowed; the perceptual roughness r must be >= 0 "
                              "(α = r²)")
    return r ** 2


def roughness_from_alpha(alpha):
    """Perceptual roughness r = √α, inverse of :func:`alpha_from_roughness`."""
    return np.sqrt(np.asarray(alpha, dtype=float))


def blinn_phong_exponent(alpha):
    """Blinn-Phong exponent α_p = 2/α² − 2 equivalent to a Beckmann NDF of rms slope α.

    The two NDFs agree to second order in θ_m around the normal; the exponent is what :data:`NDFS`'s
    ``"blinn-phong"`` uses for a given α.

    References
    ----------
    .. [1] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007, §5.2.
    """
    a = np.asarray(alpha, dtype=float)
    return 2.0 / (a * a) - 2.0


def alpha_from_blinn_phong(exponent):
    """Beckmann α = √(2 / (α_p + 2)) equivalent to Blinn-Phong exponent α_p (inverse of
    :func:`blinn_phong_exponent`).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.2.
    """
    return np.sqrt(2.0 / (np.asarray(exponent, dtype=float) + 2.0))


# ----------------------------------------------------------------------------------------------------------
# small vector helpers


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def _as_dirs(w, name):
    w = np.asarray(w, dtype=np.float64)
    if w.shape[-1:] != (3,):
        raise WaveopticsError(f"{name} must have shape (..., 3) (unit vectors), got {w.shape}")
    if not np.all(np.isfinite(w)):
        raise WaveopticsError(f"{name} contains non-finite values; directions must be finite unit vectors")
    norm = np.linalg.norm(w, axis=-1, keepdims=True)
    # guard: a zero vector is not a direction; it is treated as below the surface (result 0)
    return np.where(norm > 0, w / np.where(norm > 0, norm, 1.0), np.array([0.0, 0.0, -1.0]))


def half_vector(wi, wo):
    """Unit half-vector h = (wi + wo)/|wi + wo| (returns n where wi = −wo, which only occurs below the surface).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions.
    """
    s = np.asarray(wi, dtype=float) + np.asarray(wo, dtype=float)
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    return np.where(n > 0, s / np.where(n > 0, n, 1.0), np.array([0.0, 0.0, 1.0]))


def reflect(w, m):
    """Mirror direction of *w* about the unit normal *m*: 2 (w·m) m − w."""
    return 2.0 * _dot(w, m)[..., None] * m - w


# ----------------------------------------------------------------------------------------------------------
# NDFs: D(m) and Smith's Λ(w)
#
# Every per-NDF function takes (vector, ax, ay, c): c is the ABC tail exponent and is ignored by the others,
# so the registry can call them uniformly. Vectors are unit; m_z <= 0 gives D = 0, w_z <= 0 gives Λ = inf.


def _tan2_stretched(w, ax, ay):
    """(α_x² w_x² + α_y² w_y²) / w_z², i.e. α(φ)² tan²θ, for w_z > 0 (else inf)."""
    wz = w[..., 2]
    num = (ax * w[..., 0]) ** 2 + (ay * w[..., 1]) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(wz > 0, num / np.where(wz > 0, wz * wz, 1.0), np.inf)


def D_ggx(m, ax, ay, c=None):
    """Trowbridge-Reitz / GGX NDF, anisotropic: 1 / (π α_x α_y (m_x²/α_x² + m_y²/α_y² + m_z²)²).

    Parameters
    ----------
    m : ndarray (..., 3)
        Unit microfacet normals.
    ax, ay : float
        Slope scales along x and y (dimensionless, ≥ :data:`ALPHA_MIN`).

    Returns
    -------
    ndarray
        D in 1/sr; 0 for m_z <= 0.

    References
    ----------
    .. [1] T. S. Trowbridge, K. P. Reitz, JOSA 65(5), 1975.
    .. [2] B. Walter et al., EGSR 2007, eq. (33).
    .. [3] E. Heitz, JCGT 3(2), 2014, eq. (85) (anisotropic form).
    """
    q = (m[..., 0] / ax) ** 2 + (m[..., 1] / ay) ** 2 + m[..., 2] ** 2
    return np.where(m[..., 2] > 0, 1.0 / (np.pi * ax * ay * q * q), 0.0)


def Lambda_ggx(w, ax, ay, c=None):
    """Smith Λ of GGX: (√(1 + α² tan²θ) − 1)/2, written t/(2(1 + √(1+t))) to avoid cancellation.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (86).
    """
    t = _tan2_stretched(w, ax, ay)
    with np.errstate(invalid="ignore"):
        lam = t / (2.0 * (1.0 + np.sqrt(1.0 + t)))
    return np.where(np.isinf(t), np.inf, lam)


def D_beckmann(m, ax, ay, c=None):
    """Beckmann NDF, anisotropic: exp(−(m_x²/α_x² + m_y²/α_y²)/m_z²) / (π α_x α_y m_z⁴).

    α is the rms slope of the surface (|∇h| rms for the isotropic case, see ``physics.md`` §1).

    References
    ----------
    .. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, 1963.
    .. [2] B. Walter et al., EGSR 2007, eq. (25).
    .. [3] E. Heitz, JCGT 3(2), 2014, eq. (80).
    """
    mz = m[..., 2]
    ok = mz > 1e-150  # guard: exp(-inf) * inf at m_z -> 0; the limit is 0
    inv2 = 1.0 / np.where(ok, mz * mz, 1.0)
    t = ((m[..., 0] / ax) ** 2 + (m[..., 1] / ay) ** 2) * inv2
    return np.where(ok, np.exp(-t) * inv2 * inv2 / (np.pi * ax * ay), 0.0)


def Lambda_beckmann(w, ax, ay, c=None):
    """Exact Smith Λ of Beckmann: (e^{−a²}/(a√π) − erfc a)/2 with a = 1/(α tanθ).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (27).
    .. [2] E. Heitz, JCGT 3(2), 2014, eq. (81).
    """
    t = _tan2_stretched(w, ax, ay)
    fin = np.isfinite(t) & (t > 0)
    a = 1.0 / np.sqrt(np.where(fin, t, 1.0))
    lam = 0.5 * (np.exp(-a * a) / (a * np.sqrt(np.pi)) - special.erfc(a))
    lam = np.maximum(lam, 0.0)  # guard: rounding of the difference of two tiny numbers for a >> 1
    return np.where(fin, lam, np.where(np.isinf(t), np.inf, 0.0))


def _one_minus_cos(m):
    """1 − m_z for unit m, as (m_x² + m_y²)/(1 + m_z) (no cancellation near the normal)."""
    s2 = m[..., 0] ** 2 + m[..., 1] ** 2
    return s2 / (1.0 + np.maximum(m[..., 2], 0.0))


def D_blinn_phong(m, ax, ay=None, c=None):
    """Normalized Blinn-Phong NDF (α_p + 2)/(2π) (n·m)^α_p with α_p = 2/α² − 2 (isotropic, α = ax).

    References
    ----------
    .. [1] J. F. Blinn, "Models of light reflection for computer synthesized pictures", SIGGRAPH 1977.
    .. [2] B. Walter et al., EGSR 2007, eq. (30) (normalization) and §5.2 (α_p from α).
    """
    ap = blinn_phong_exponent(ax)
    mz = m[..., 2]
    s2 = np.minimum(m[..., 0] ** 2 + m[..., 1] ** 2, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        # log m_z: from 1 − m_z² near the normal (no cancellation), from m_z near the horizon (finite)
        logc = np.where(s2 < 0.5, 0.5 * np.log1p(-np.minimum(s2, 0.5)), np.log(np.maximum(mz, 1e-300)))
        val = (ap + 2.0) / (2.0 * np.pi) * np.exp(ap * logc)
    return np.where(mz > 0, val, 0.0)


def Lambda_blinn_phong(w, ax, ay=None, c=None):
    """Exact Smith Λ of the Blinn-Phong NDF (closed form through the incomplete beta function).

    The slope distribution of Blinn-Phong is P22(r) = (α_p + 2)/(2π) (1 + r²)^{−(α_p+4)/2} (a Student-t law of
    slopes), whose 1-D marginal is P2(x) = K (1 + x²)^{−s}, s = (α_p + 3)/2, K = (α_p + 2) B(½, s)/(2π). With
    μ = cot θ, Λ = (1/μ) ∫_μ^∞ (x − μ) P2(x) dx [1]_ gives

        Λ = K [ (1 + μ²)^{1−s} / (2(s − 1)) − (μ/2) B(s − ½, ½) I_{1/(1+μ²)}(s − ½, ½) ] / μ,

    with I the regularized incomplete beta function. (Walter et al. approximate it by Beckmann's Λ at the
    equivalent α; this is the exact value, which satisfies the Smith identity.) The OpenCL twin evaluates the
    same Λ by the radial quadrature of :func:`Lambda_radial` (agreement ~1e-8).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72) and §5.3.
    .. [2] M. Ribardière, B. Bringier, D. Meneveaux, L. Simonot, "STD: Student's t-Distribution of Slopes for
       Microfacet Based BSDFs", Computer Graphics Forum 36(2), 2017.
    """
    ap = float(blinn_phong_exponent(ax))
    s = 0.5 * (ap + 3.0)
    wz = w[..., 2]
    st = np.sqrt(np.maximum(w[..., 0] ** 2 + w[..., 1] ** 2, 0.0))
    ok = (wz > 0) & (st > 0)
    mu = np.where(ok, wz / np.where(st > 0, st, 1.0), 1.0)
    K = (ap + 2.0) / (2.0 * np.pi) * special.beta(0.5, s)
    i1 = (1.0 + mu * mu) ** (1.0 - s) / (2.0 * (s - 1.0))
    i0 = 0.5 * special.beta(s - 0.5, 0.5) * special.betainc(s - 0.5, 0.5, 1.0 / (1.0 + mu * mu))
    lam = np.maximum(K * (i1 - mu * i0) / mu, 0.0)  # guard: rounding when μ >> α (Λ ≈ 0)
    return np.where(ok, lam, np.where(wz > 0, 0.0, np.inf))


def _abc_B(ax):
    return 2.0 / (ax * ax)


def _expm1_over(p, L):
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
    B = _abc_B(np.asarray(alpha, dtype=float))
    L = np.log1p(B)
    e1 = _expm1_over(1.0 - c, L)
    e2 = _expm1_over(2.0 - c, L)
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
    val = A * (1.0 + _abc_B(ax) * _one_minus_cos(m)) ** (-c)
    return np.where(m[..., 2] > 0, val, 0.0)


@functools.lru_cache(maxsize=8)
def _gl01(n):
    """Gauss-Legendre nodes and weights on [0, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (x + 1.0), 0.5 * w


def Lambda_radial(w, P22: Callable, alpha):
    """Smith Λ of an isotropic NDF from its slope distribution P22(r) by 1-D quadrature.

    For an isotropic slope law, Λ(μ) = (1/μ) ∫∫_{x>μ} (x − μ) P22 dx dy (μ = cot θ) becomes, with r² = μ² + ρ²,

        Λ(μ) = (2/μ) ∫₀^∞ ρ P22(√(μ² + ρ²)) [ρ − μ atan(ρ/μ)] dρ,

    evaluated with :data:`LAMBDA_GL_ORDER`-point Gauss-Legendre in s after ρ = c tan(πs/2), c = √(α² + μ²)
    (which puts the nodes on the lobe at any μ). Checked against the closed forms of GGX, Beckmann and
    Blinn-Phong to 1e-8 in G1 for α in [0.001, 1] and θ up to 89.99° (``tests/test_microfacet.py``).

    Parameters
    ----------
    w : ndarray (..., 3)
        Unit directions.
    P22 : callable
        Slope distribution P22(r) (1/slope²), r the slope magnitude tan θ_m.
    alpha : float
        Slope scale of the lobe (dimensionless).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72).
    """
    wz = w[..., 2]
    st = np.sqrt(w[..., 0] ** 2 + w[..., 1] ** 2)
    ok = (wz > 0) & (st > 0)
    mu = np.where(ok, wz / np.where(st > 0, st, 1.0), 1.0)[..., None]
    s, ws = _gl01(LAMBDA_GL_ORDER)
    c = np.sqrt(alpha * alpha + mu * mu)
    half = 0.5 * np.pi * s
    rho = c * np.tan(half)
    drho = c * 0.5 * np.pi / np.cos(half) ** 2
    r = np.sqrt(mu * mu + rho * rho)
    bracket = rho - mu * np.arctan(rho / mu)
    lam = 2.0 / mu[..., 0] * np.sum(ws * rho * P22(r) * bracket * drho, axis=-1)
    return np.where(ok, lam, np.where(wz > 0, 0.0, np.inf))


def _P22_abc(r, ax, c):
    # D(θ) cos⁴θ with cos θ = 1/√(1+r²); 1 − cos θ = r² / (√(1+r²) (1 + √(1+r²)))
    q = np.sqrt(1.0 + r * r)
    one_minus = r * r / (q * (1.0 + q))
    return abc_normalization(ax, c) * (1.0 + _abc_B(ax) * one_minus) ** (-c) / (q ** 4)


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
# anisotropy by stretching (Heitz 2014, §5.3): for NDFs defined isotropically (EPD, SGD)


def stretch_factors(ax, ay, exponent):
    """(ᾱ, k_x, k_y) of the stretched form of an isotropic NDF: the base roughness ᾱ = √(α_x α_y) and the slope
    stretches k = (α/ᾱ)^e, where e is how the NDF's slope scale grows with α (1 for a slope scale α, as EPD;
    ½ for a tan²θ scale α, as SGD), so that along x the law has the slope scale of α_x and along y that of α_y.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3 (stretch invariance of the slope distribution and of Λ).
    """
    ax = np.asarray(ax, dtype=float)
    ay = ax if ay is None else np.asarray(ay, dtype=float)
    base = np.sqrt(ax * ay)
    return base, (ax / base) ** exponent, (ay / base) ** exponent


def D_stretched(D_iso, m, ax, ay, c, exponent):
    """D of the isotropic NDF *D_iso* stretched to (α_x, α_y), 1/sr.

    The slopes of the stretched surface are (k_x x̃, k_y ỹ) with (x̃, ỹ) distributed as the isotropic law of
    roughness ᾱ (:func:`stretch_factors`), so P22(x̃, ỹ) = P22_ᾱ(x̃/k_x, ỹ/k_y) / (k_x k_y); with D = P22 / cos⁴θ
    and m' ∝ (m_x/k_x, m_y/k_y, m_z) of norm n this is D(m) = D_ᾱ(m') / (n⁴ k_x k_y). Equal α gives *D_iso*.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3, eqs. (8) and (79).
    """
    if ay is None or np.all(np.asarray(ay) == np.asarray(ax)):
        return D_iso(m, ax, None, c)
    base, kx, ky = stretch_factors(ax, ay, exponent)
    v = np.stack([m[..., 0] / kx, m[..., 1] / ky, m[..., 2]], axis=-1)
    n = np.linalg.norm(v, axis=-1)
    return D_iso(v / n[..., None], base, None, c) / (n ** 4 * kx * ky)


def Lambda_stretched(Lambda_iso, w, ax, ay, c, exponent):
    """Smith Λ of the stretched NDF: the isotropic Λ of roughness ᾱ at the stretched direction
    (k_x w_x, k_y w_y, w_z) (its cot θ divided by the projected stretch √(k_x² cos²φ + k_y² sin²φ)).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3, eq. (80).
    """
    if ay is None or np.all(np.asarray(ay) == np.asarray(ax)):
        return Lambda_iso(w, ax, None, c)
    base, kx, ky = stretch_factors(ax, ay, exponent)
    v = np.stack([w[..., 0] * kx, w[..., 1] * ky, w[..., 2]], axis=-1)
    return Lambda_iso(v / np.linalg.norm(v, axis=-1, keepdims=True), base, None, c)


#: how each stretched NDF's slope scale grows with α (:func:`stretch_factors`)
STRETCH_EXPONENT = {"epd": 1.0, "sgd": 0.5}


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


@dataclass(frozen=True)
class NDF:
    """One microfacet distribution (as pbrt-v4's ``TrowbridgeReitzDistribution``): D, Smith Λ and G1, whether it has
    an anisotropic form, its kernel switch (``cl_id``) and its source.

    ``D(m, ax, ay, c)`` and ``Lambda(w, ax, ay, c)`` take unit vectors (..., 3) and the roughness (α_x, α_y and, for
    ABC, the exponent c); :meth:`G1` is Smith's masking 1 / (1 + Λ(w)) on the side where w · m > 0 (Heitz 2014,
    eq. 43).
    """

    name: str
    D: Callable
    Lambda: Callable
    anisotropic: bool
    cl_id: int | None
    reference: str
    shape: str | None = None            # the symbol of its shape parameter (``ndf_shape``), if it has one
    shape_default: float | None = None

    def G1(self, w, m, ax, ay=None, c=None):
        """Smith masking G1(w, m) = χ⁺(w · m) / (1 + Λ(w)) (unitless)."""
        return _G1(w, m, self.Lambda(w, ax, ay, c))


#: Normal distribution functions by name (``method=`` style registry)
NDFS: dict[str, NDF] = {
    "ggx": NDF("ggx", D_ggx, Lambda_ggx, True, 0, "Trowbridge & Reitz 1975; Walter et al. 2007"),
    "beckmann": NDF("beckmann", D_beckmann, Lambda_beckmann, True, 1, "Beckmann & Spizzichino 1963"),
    "blinn-phong": NDF("blinn-phong", D_blinn_phong, Lambda_blinn_phong, False, 2, "Blinn 1977; Walter 2007"),
    "abc": NDF("abc", D_abc, Lambda_abc, False, 3, "Löw et al. 2012", "C", ABC_C_DEFAULT),
    "epd": NDF("epd", D_epd, Lambda_epd, True, None, "Holzschuch & Pacanowski 2017", "p", EPD_P_DEFAULT),
    "sgd": NDF("sgd", D_sgd, Lambda_sgd, True, None, "Bagher, Soler & Holzschuch 2012", "p", SGD_P_DEFAULT),
    # the slopes of a micro-scale height field, tabulated (its ndf_shape is the SlopeTable; α is not used)
    "tabulated": NDF("tabulated", D_tabulated, Lambda_tabulated, True, None, "Heitz 2014 (measured slopes)",
                     "table", None),
}


#: allowed range (open below) of each NDF's shape parameter: ABC's C > 0; EPD's p in (0, 20] (Γ(1/p) overflows
#: below 0.006, and p → ∞ is a flat disc); SGD's p in (0, 5] (the recurrence of :func:`gamma_upper` stays
#: accurate there, and Bagher et al. fit p in [0, 2])
SHAPE_RANGE = {"abc": (0.0, np.inf), "epd": (0.0, 20.0), "sgd": (0.0, 5.0)}


def _ndf(name) -> NDF:
    if name not in NDFS:
        raise unknown("NDF", name, NDFS)
    return NDFS[name]


def _check_alpha(alpha, alpha_y, ndf: NDF, ndf_shape):
    """Validate (public boundary) and floor α (guard); returns (ax, ay)."""
    for label, a in (("alpha", alpha), ("alpha_y", alpha_y)):
        if a is None:
            continue
        a = float(a)
        if not np.isfinite(a) or a < 0 or a > ALPHA_MAX:
            raise WaveopticsError(f"{label}={a!r} is not allowed; α must be in [0, {ALPHA_MAX:g}] "
                                  f"(0 means the sharpest representable lobe, α = {ALPHA_MIN:g})")
    ax = max(float(alpha), ALPHA_MIN)
    ay = ax if alpha_y is None else max(float(alpha_y), ALPHA_MIN)
    if ay != ax and not ndf.anisotropic:
        raise WaveopticsError(f"alpha_y={alpha_y!r} is not allowed for NDF {ndf.name!r}, which is isotropic; "
                              "anisotropic NDFs: " + ", ".join(k for k, v in NDFS.items() if v.anisotropic))
    if ndf.name == "blinn-phong" and ax > 1.0:
        raise WaveopticsError(f"alpha={alpha!r} is not allowed for blinn-phong; need α <= 1 "
                              "(exponent 2/α² − 2 >= 0)")
    if ndf.name == "tabulated":
        if not isinstance(ndf_shape, SlopeTable):
            raise WaveopticsError("NDF 'tabulated' needs its slope table as ndf_shape "
                                  "(waveoptics.brdf.slope_table(height_field))")
    elif ndf_shape is not None:
        if ndf.shape is None:
            raise WaveopticsError(f"ndf_shape={ndf_shape!r} is not allowed for NDF {ndf.name!r}, which has no shape "
                                  "parameter; NDFs with one: " + ", ".join(f"{k} ({v.shape})" for k, v in NDFS.items()
                                                                          if v.shape and k in SHAPE_RANGE))
        lo, hi = SHAPE_RANGE[ndf.name]
        if not (np.isfinite(ndf_shape) and lo < ndf_shape <= hi):
            raise WaveopticsError(f"ndf_shape={ndf_shape!r} is not allowed for {ndf.name}; its {ndf.shape} must be in "
                                  f"({lo:g}, {hi:g}]")
    return ax, ay


def D(m, alpha, alpha_y=None, *, ndf="ggx", ndf_shape=None):
    """Normal distribution function D(m) in 1/sr (``ndf`` one of :data:`NDFS`).

    Parameters
    ----------
    m : array_like (..., 3)
        Unit microfacet normals (z = macro normal).
    alpha : float
        Slope scale α (α_x for anisotropic NDFs), dimensionless, in [0, 2]; floored at :data:`ALPHA_MIN`.
    alpha_y : float, optional
        α_y for the anisotropic NDFs ``"ggx"``, ``"beckmann"``, ``"epd"``, ``"sgd"`` (default: isotropic).
    ndf : str
        ``"ggx"``, ``"beckmann"``, ``"blinn-phong"``, ``"abc"``, ``"epd"`` or ``"sgd"``.
    ndf_shape : float, optional
        Shape parameter of the NDFs that have one (:data:`SHAPE_RANGE`): ABC's tail exponent C, EPD's and SGD's
        exponent p; None takes the NDF's default.

    Returns
    -------
    ndarray
        D(m) ≥ 0 in 1/sr, with ∫ D(m)(n·m) dω_m = 1; 0 below the surface.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §2 (definition and normalization).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, ndf_shape)
    return spec.D(_as_dirs(m, "m"), ax, ay, ndf_shape)


def Lambda(w, alpha, alpha_y=None, *, ndf="ggx", ndf_shape=None):
    """Smith's Λ(w) of an NDF (dimensionless, ≥ 0; +inf for w_z <= 0, where G1 = 0).

    Parameters are those of :func:`D`; *w* are unit directions (..., 3).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5 (eq. 72), eqs. (81), (86).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, ndf_shape)
    return spec.Lambda(_as_dirs(w, "w"), ax, ay, ndf_shape)


def G1(w, m, alpha, alpha_y=None, *, ndf="ggx", ndf_shape=None):
    """Smith masking function G1(w, m) = χ⁺(w·m) / (1 + Λ(w)), in [0, 1].

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (43).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, ndf_shape)
    w = _as_dirs(w, "w")
    m = _as_dirs(m, "m")
    return _G1(w, m, spec.Lambda(w, ax, ay, ndf_shape))


def _G1(w, m, lam):
    with np.errstate(invalid="ignore"):
        g = 1.0 / (1.0 + lam)
    return np.where((_dot(w, m) > 0) & (w[..., 2] > 0), g, 0.0)
