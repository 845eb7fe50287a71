"""Geometric-optics microfacet BRDF: NDFs, masking-shadowing, Fresnel, diffuse terms and their quadrature.

The specular term of Cook & Torrance (1982) in the normalization of Walter et al. (2007),

    f_s(l, v) = F(v·h) G(l, v, h) D(h) / (4 (n·l)(n·v)),   h = (l + v) / |l + v|,

with a choice of normal distribution function D (:data:`NDFS`), masking-shadowing term G (:data:`SHADOWINGS`)
and Fresnel factor F (:data:`FRESNELS`), plus a Lambertian or Oren-Nayar diffuse term that receives only the
light the specular interface did not reflect (:func:`diffuse_tradeoff`).

Conventions
-----------
* Directions are unit vectors ``(..., 3)`` in the local frame of the macro surface, z the normal n.
  ``wi`` (= l) points towards the light, ``wo`` (= v) towards the viewer. Arrays broadcast against each other
  and against per-wavelength parameters (``eta``, ``F0``, ``kd`` of shape ``(n_wavelengths, 1)`` with
  directions of shape ``(n, 3)`` give results of shape ``(n_wavelengths, n)``).
* The BRDF is only defined with both directions above the surface; every function returns exactly 0 when
  ``wi_z <= 0`` or ``wo_z <= 0`` (never NaN).
* Roughness is the slope-scale α of the NDF (α is the rms slope for Beckmann). The "perceptual roughness" r of
  Burley (2012) maps to α = r² (:func:`alpha_from_roughness`). The Blinn-Phong exponent is derived from α by
  Walter et al.'s equivalence α_p = 2/α² − 2 (:func:`blinn_phong_exponent`), so every NDF takes the same α.
* α is floored at :data:`ALPHA_MIN` (a mirror is a delta function, which a BRDF evaluated at sampled
  directions cannot represent); α = 0 is therefore accepted and means "as sharp as representable".
* Units: BRDF values in 1/sr; angles in radians in this module (degrees only on the command line);
  wavelengths in nm.

OpenCL twins: ``kernels/microfacet.h`` holds the device functions with the same names (``D_ggx``, ``Lambda``,
``G1``, ``G``, ``specular``, ``oren_nayar``, ``brdf`` ...), selected by ``-D`` switches; ``kernels/microfacet.cl``
evaluates them in bulk through :func:`D_cl`, :func:`Lambda_cl` and :func:`brdf_cl`.

References
----------
.. [1] R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics", ACM TOG 1(1):7-24, 1982.
.. [2] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007.
.. [3] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2):48-107,
   2014.
.. [4] J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient Rendering of
   Glossy Surfaces", ACM TOG 31(1):9, 2012.
.. [5] M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994, 239-246.
.. [6] P. Shirley, H. Hu, B. Smits, E. Lafortune, "A Practitioners' Assessment of Light Reflection Models",
   Pacific Graphics 1997.
.. [7] M. Ashikhmin, P. Shirley, "An Anisotropic Phong BRDF Model", Journal of Graphics Tools 5(2):25-32, 2000.
.. [8] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes.
.. [9] T. S. Trowbridge, K. P. Reitz, "Average irregularity representation of a rough surface for ray
   reflection", JOSA 65(5):531-536, 1975.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import special

from . import fresnel as _fresnel
from .errors import WaveopticsError, unknown

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


def abc_normalization(alpha, c=ABC_C_DEFAULT):
    """Constant A of the ABC NDF D = A (1 + B(1 − n·m))^{−C}, B = 2/α², such that ∫ D (n·m) dω = 1.

    A = 1 / (2π (I₁ − I₂)), I₁ = ∫₀¹ (1 + Bu)^{−C} du, I₂ = ∫₀¹ u (1 + Bu)^{−C} du (u = 1 − cos θ), in closed
    form: with E(p) = ((1 + B)^p − 1)/p, I₁ = E(1 − C)/B and I₂ = (E(2 − C) − E(1 − C))/B².

    References
    ----------
    .. [1] J. Löw et al., ACM TOG 31(1), 2012, §5 (the ABC microfacet distribution).
    """
    B = _abc_B(np.asarray(alpha, dtype=float))
    L = np.log1p(B)
    e1 = _expm1_over(1.0 - c, L)
    e2 = _expm1_over(2.0 - c, L)
    i1 = e1 / B
    i2 = (e2 - e1) / (B * B)
    return 1.0 / (2.0 * np.pi * (i1 - i2))


def D_abc(m, ax, ay=None, c=ABC_C_DEFAULT):
    """ABC NDF of Löw et al. (2012): A / (1 + B(1 − n·m))^C with B = 2/α² (isotropic, α = ax).

    Near the normal 1 − n·m ≈ tan²θ/2, so D ∝ (1 + tan²θ/α²)^{−C}: α is the slope scale like GGX's and C sets
    the tail (C = 2: GGX-like core; smaller C: longer tail). A is :func:`abc_normalization`.

    References
    ----------
    .. [1] J. Löw, J. Kronander, A. Ynnerman, J. Unger, ACM TOG 31(1):9, 2012, §5.
    """
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


def Lambda_abc(w, ax, ay=None, c=ABC_C_DEFAULT):
    """Smith Λ of the ABC NDF (no closed form): :func:`Lambda_radial` of its slope law.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (72).
    .. [2] J. Löw et al., ACM TOG 31(1), 2012.
    """
    return Lambda_radial(w, lambda r: _P22_abc(r, ax, c), ax)


@dataclass(frozen=True)
class NDF:
    """A registry entry: the NDF and its Smith Λ, whether it has an anisotropic form, its kernel switch."""

    name: str
    D: Callable
    Lambda: Callable
    anisotropic: bool
    cl_id: int
    reference: str


#: Normal distribution functions by name (``method=`` style registry)
NDFS: dict[str, NDF] = {
    "ggx": NDF("ggx", D_ggx, Lambda_ggx, True, 0, "Trowbridge & Reitz 1975; Walter et al. 2007"),
    "beckmann": NDF("beckmann", D_beckmann, Lambda_beckmann, True, 1, "Beckmann & Spizzichino 1963"),
    "blinn-phong": NDF("blinn-phong", D_blinn_phong, Lambda_blinn_phong, False, 2, "Blinn 1977; Walter 2007"),
    "abc": NDF("abc", D_abc, Lambda_abc, False, 3, "Löw et al. 2012"),
}


def _ndf(name) -> NDF:
    if name not in NDFS:
        raise unknown("NDF", name, NDFS)
    return NDFS[name]


def _check_alpha(alpha, alpha_y, ndf: NDF, abc_c):
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
    if ndf.name == "abc" and not (np.isfinite(abc_c) and abc_c > 0):
        raise WaveopticsError(f"abc_c={abc_c!r} is not allowed; the ABC tail exponent C must be > 0")
    return ax, ay


def D(m, alpha, alpha_y=None, *, ndf="ggx", abc_c=ABC_C_DEFAULT):
    """Normal distribution function D(m) in 1/sr (``ndf`` one of :data:`NDFS`).

    Parameters
    ----------
    m : array_like (..., 3)
        Unit microfacet normals (z = macro normal).
    alpha : float
        Slope scale α (α_x for anisotropic NDFs), dimensionless, in [0, 2]; floored at :data:`ALPHA_MIN`.
    alpha_y : float, optional
        α_y for ``"ggx"`` and ``"beckmann"`` (default: isotropic).
    ndf : str
        ``"ggx"``, ``"beckmann"``, ``"blinn-phong"`` or ``"abc"``.
    abc_c : float
        Tail exponent C of ``"abc"``.

    Returns
    -------
    ndarray
        D(m) ≥ 0 in 1/sr, with ∫ D(m)(n·m) dω_m = 1; 0 below the surface.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §2 (definition and normalization).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    return spec.D(_as_dirs(m, "m"), ax, ay, abc_c)


def Lambda(w, alpha, alpha_y=None, *, ndf="ggx", abc_c=ABC_C_DEFAULT):
    """Smith's Λ(w) of an NDF (dimensionless, ≥ 0; +inf for w_z <= 0, where G1 = 0).

    Parameters are those of :func:`D`; *w* are unit directions (..., 3).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5 (eq. 72), eqs. (81), (86).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    return spec.Lambda(_as_dirs(w, "w"), ax, ay, abc_c)


def G1(w, m, alpha, alpha_y=None, *, ndf="ggx", abc_c=ABC_C_DEFAULT):
    """Smith masking function G1(w, m) = χ⁺(w·m) / (1 + Λ(w)), in [0, 1].

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (43).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    w = _as_dirs(w, "w")
    m = _as_dirs(m, "m")
    return _G1(w, m, spec.Lambda(w, ax, ay, abc_c))


def _G1(w, m, lam):
    with np.errstate(invalid="ignore"):
        g = 1.0 / (1.0 + lam)
    return np.where((_dot(w, m) > 0) & (w[..., 2] > 0), g, 0.0)


# ----------------------------------------------------------------------------------------------------------
# masking-shadowing G(l, v, h): each entry takes (wi, wo, m, lam) with lam a callable w -> Λ(w)


def G_smith(wi, wo, m, lam):
    """Separable (uncorrelated) Smith: G1(l, m) G1(v, m).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (23).
    .. [2] E. Heitz, JCGT 3(2), 2014, eq. (98).
    """
    return _G1(wi, m, lam(wi)) * _G1(wo, m, lam(wo))


def G_smith_correlated(wi, wo, m, lam):
    """Height-correlated Smith: χ⁺(l·m) χ⁺(v·m) / (1 + Λ(l) + Λ(v)).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (99).
    """
    li, lo = lam(wi), lam(wo)
    with np.errstate(invalid="ignore"):
        g = 1.0 / (1.0 + li + lo)
    ok = (_dot(wi, m) > 0) & (_dot(wo, m) > 0) & (wi[..., 2] > 0) & (wo[..., 2] > 0)
    return np.where(ok, g, 0.0)


def G_cook_torrance(wi, wo, m, lam=None):
    """V-cavity shadowing of Cook & Torrance: min(1, 2(n·m)(n·v)/(v·m), 2(n·m)(n·l)/(v·m)).

    References
    ----------
    .. [1] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982, eq. (5) (after Blinn 1977).
    """
    vm = _dot(wo, m)
    ok = (vm > 0) & (_dot(wi, m) > 0) & (wi[..., 2] > 0) & (wo[..., 2] > 0)
    safe = np.where(ok, vm, 1.0)
    g = np.minimum(1.0, np.minimum(2 * m[..., 2] * wo[..., 2] / safe, 2 * m[..., 2] * wi[..., 2] / safe))
    return np.where(ok, np.maximum(g, 0.0), 0.0)


def G_implicit(wi, wo, m=None, lam=None):
    """Implicit G = (n·l)(n·v), which cancels the BRDF denominator (f = F D / 4).

    References
    ----------
    .. [1] N. Hoffman, "Background: Physics and Math of Shading", SIGGRAPH 2013 PBS course, p. 22.
    """
    return np.maximum(wi[..., 2], 0.0) * np.maximum(wo[..., 2], 0.0)


#: masking-shadowing terms by name, with their kernel switch value
SHADOWINGS: dict[str, tuple[Callable, int]] = {
    "smith": (G_smith, 0),
    "smith-correlated": (G_smith_correlated, 1),
    "cook-torrance": (G_cook_torrance, 2),
    "implicit": (G_implicit, 3),
}


def _shadowing(name):
    if name not in SHADOWINGS:
        raise unknown("shadowing model", name, SHADOWINGS)
    return SHADOWINGS[name]


def G(wi, wo, m, alpha, alpha_y=None, *, ndf="ggx", shadowing="smith-correlated", abc_c=ABC_C_DEFAULT):
    """Masking-shadowing G(l, v, m) in [0, 1] (``shadowing`` one of :data:`SHADOWINGS`).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light and to the viewer.
    m : array_like (..., 3)
        Unit microfacet normal (the half-vector for reflection).
    alpha, alpha_y, ndf, abc_c
        As in :func:`D` (used by the Smith terms).
    shadowing : str
        ``"smith"``, ``"smith-correlated"``, ``"cook-torrance"`` or ``"implicit"``.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §6.
    .. [2] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982.
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    fn, _ = _shadowing(shadowing)
    return fn(_as_dirs(wi, "wi"), _as_dirs(wo, "wo"), _as_dirs(m, "m"), lambda w: spec.Lambda(w, ax, ay, abc_c))


# ----------------------------------------------------------------------------------------------------------
# Fresnel factor


def _F_exact(cos_theta, eta, F0):
    return _fresnel.F(cos_theta, eta)


def _F_schlick(cos_theta, eta, F0):
    return _fresnel.F_schlick(cos_theta, _fresnel.F0(eta) if F0 is None else F0)


def _F_one(cos_theta, eta, F0):
    return np.ones_like(np.asarray(cos_theta, dtype=float))


#: Fresnel factors by name: callables (cos θ, eta, F0) -> reflectance, and their kernel switch value.
#: ``"one"`` (F = 1) is the white-furnace setting.
FRESNELS: dict[str, tuple[Callable, int]] = {
    "exact": (_F_exact, 0),
    "schlick": (_F_schlick, 1),
    "one": (_F_one, 2),
}


def _fresnel_fn(fresnel, eta, F0):
    if fresnel not in FRESNELS:
        raise unknown("Fresnel model", fresnel, FRESNELS)
    if fresnel == "exact" and eta is None:
        raise WaveopticsError("fresnel='exact' needs eta (complex index n+ik); give eta or use fresnel='schlick' "
                              "with F0")
    if fresnel == "schlick" and eta is None and F0 is None:
        raise WaveopticsError("fresnel='schlick' needs F0 (or eta to compute it)")
    if F0 is not None:
        F0 = np.asarray(F0, dtype=float)
        if np.any(~np.isfinite(F0) | (F0 < 0) | (F0 > 1)):
            raise WaveopticsError(f"F0={F0!r} is not allowed; F0 must be in [0, 1]")
    fn = FRESNELS[fresnel][0]
    return lambda c: fn(c, eta, F0)


def F_mean(F_fn: Callable, batch_ndim: int = 0, n: int = 64):
    """Cosine-weighted hemispherical mean reflectance F̄ = 2 ∫₀¹ F(μ) μ dμ (Gauss-Legendre, *n* nodes).

    Parameters
    ----------
    F_fn : callable
        cos θ -> reflectance, broadcasting over its own parameters (e.g. per-wavelength eta).
    batch_ndim : int
        Number of trailing axes of the result to keep as size-1 axes (so F̄ broadcasts like F's parameters).

    References
    ----------
    .. [1] P. Shirley et al., Pacific Graphics 1997, §4 (the normalization of the coupled diffuse term).
    """
    x, w = _gl01(n)
    mu = x.reshape((-1,) + (1,) * batch_ndim)
    Fv = np.asarray(F_fn(mu), dtype=float)
    Fv = np.broadcast_to(Fv, np.broadcast_shapes(Fv.shape, mu.shape))
    wts = (2.0 * w * x).reshape(mu.shape)
    return np.sum(wts * Fv, axis=0)


# ----------------------------------------------------------------------------------------------------------
# the specular term


def specular(wi, wo, *, alpha, alpha_y=None, ndf="ggx", shadowing="smith-correlated", fresnel="exact",
             eta=None, F0=None, abc_c=ABC_C_DEFAULT):
    """Microfacet specular BRDF F(v·h) G(l, v, h) D(h) / (4 (n·l)(n·v)) in 1/sr.

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light (l) and to the viewer (v); they broadcast.
    alpha, alpha_y, ndf, abc_c
        NDF and its roughness, as in :func:`D`.
    shadowing : str
        One of :data:`SHADOWINGS`.
    fresnel : str
        ``"exact"`` (needs *eta*), ``"schlick"`` (needs *F0* or *eta*) or ``"one"`` (F = 1, white furnace).
    eta : array_like of complex, optional
        Relative index n + ik of the surface, broadcasting with the direction batch (e.g. shape (n_λ, 1)).
    F0 : array_like, optional
        Normal-incidence reflectance for Schlick.

    Returns
    -------
    ndarray
        f_s ≥ 0 in 1/sr, shape of the broadcast batch; 0 where wi_z <= 0 or wo_z <= 0.

    References
    ----------
    .. [1] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982, eq. (4) (with 4 for π as corrected in [2]).
    .. [2] B. Walter et al., EGSR 2007, eq. (20).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    gfn, _ = _shadowing(shadowing)
    F_fn = _fresnel_fn(fresnel, eta, F0)
    wi = _as_dirs(wi, "wi")
    wo = _as_dirs(wo, "wo")
    wi, wo = np.broadcast_arrays(wi, wo)
    return _specular(wi, wo, spec, ax, ay, abc_c, gfn, F_fn)


def _specular(wi, wo, spec, ax, ay, c, gfn, F_fn):
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    h = half_vector(wi, wo)
    cos_d = np.clip(_dot(wi, h), 0.0, 1.0)
    g = gfn(wi, wo, h, lambda w: spec.Lambda(w, ax, ay, c))
    d = spec.D(h, ax, ay, c)
    # guard: f grows like 1/cos θ towards the horizon (G ~ cos θ / α); flooring the cosines of the denominator
    # at COS_MIN bounds f (below float32 overflow for α >= ALPHA_MIN) and only changes θ > 89.999994°, where
    # f then goes continuously to 0 with G
    denom = 4.0 * np.where(up, np.maximum(wi[..., 2], COS_MIN) * np.maximum(wo[..., 2], COS_MIN), 1.0)
    val = F_fn(cos_d) * g * d / denom
    # guard: 0 below the surface (and in the product of 0 and a huge D at exactly grazing directions)
    return np.where(up & (g > 0), val, 0.0)


# ----------------------------------------------------------------------------------------------------------
# diffuse terms


def lambert(wi, wo, kd=1.0):
    """Lambertian BRDF kd/π (1/sr) for both directions above the surface, else 0.

    Parameters
    ----------
    kd : array_like
        Diffuse albedo c in [0, 1] (may vary with wavelength; broadcasts with the batch).

    References
    ----------
    .. [1] J. H. Lambert, *Photometria*, 1760.
    """
    wi = _as_dirs(wi, "wi")
    wo = _as_dirs(wo, "wo")
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    return np.where(up, np.asarray(kd, dtype=float) / np.pi, 0.0)


def oren_nayar(wi, wo, kd=1.0, sigma=0.0):
    """Oren-Nayar rough-diffuse BRDF (the qualitative model), in 1/sr.

        f = (kd/π) [A + B max(0, cos(φ_i − φ_o)) sin α tan β],  α = max(θ_i, θ_o), β = min(θ_i, θ_o),
        A = 1 − 0.5 σ²/(σ² + 0.33),  B = 0.45 σ²/(σ² + 0.09),

    computed from the vectors as max(0, wi_xy·wo_xy)/max(cos θ_i, cos θ_o) for the cos Δφ sin α tan β product
    (reciprocal, no division by zero).

    Parameters
    ----------
    kd : array_like
        Albedo ρ of the facets in [0, 1].
    sigma : float
        Standard deviation of the facet slope angle, radians (0 gives Lambert). This is the diffuse roughness,
        independent of the specular α.

    Notes
    -----
    The qualitative model is an approximation of the V-cavity model with interreflections dropped; it is not
    exactly energy conserving: with kd = 1 its directional albedo is A ≤ 1 at normal incidence but rises to
    about A + B/2 at grazing incidence, slightly above 1 for σ ≈ 0.2-0.4 (see ``docs/microfacet.md``).

    References
    ----------
    .. [1] M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994, eq. (30).
    """
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma < 0:
        raise WaveopticsError(f"sigma={sigma!r} is not allowed; the Oren-Nayar roughness must be >= 0 radians")
    wi = _as_dirs(wi, "wi")
    wo = _as_dirs(wo, "wo")
    return _oren_nayar(wi, wo, kd, sigma)


def _oren_nayar(wi, wo, kd, sigma):
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    cmax = np.where(up, np.maximum(wi[..., 2], wo[..., 2]), 1.0)
    proj = np.maximum(0.0, wi[..., 0] * wo[..., 0] + wi[..., 1] * wo[..., 1])
    return np.where(up, np.asarray(kd, dtype=float) / np.pi * (A + B * proj / cmax), 0.0)


def diffuse_tradeoff(wi, wo, F_fn: Callable, batch_ndim: int = 0):
    """Energy-conserving weight of the diffuse term: (1 − F(θ_i))(1 − F(θ_o)) / (1 − F̄).

    The diffuse layer receives only the light the interface did not reflect, 1 − F(θ_i), and its light leaves
    through the interface with weight 1 − F(θ_o) (reciprocity), renormalized so that the diffuse albedo is
    exactly kd (1 − F(θ_i)) for a Lambertian layer: F̄ = 2∫ F(μ) μ dμ (:func:`F_mean`). With Schlick's F this is
    Shirley et al.'s coupled model, f_d = 21/(20π) kd (1 − F0)(1 − (1 − cos θ_i)⁵)(1 − (1 − cos θ_o)⁵), and
    Ashikhmin & Shirley (2000) use the same structure with a different constant; here F is the exact spectral
    Fresnel factor. The weight goes to 0 at grazing incidence or exitance, where F → 1.

    Returns
    -------
    ndarray
        Weight ≥ 0 (dimensionless); 0 where F̄ = 1 (nothing enters the surface).

    References
    ----------
    .. [1] P. Shirley, H. Hu, B. Smits, E. Lafortune, Pacific Graphics 1997, eq. (7).
    .. [2] M. Ashikhmin, P. Shirley, JGT 5(2), 2000, eq. (5).
    """
    Fi = F_fn(np.clip(wi[..., 2], 0.0, 1.0))
    Fo = F_fn(np.clip(wo[..., 2], 0.0, 1.0))
    Fbar = F_mean(F_fn, batch_ndim)
    t = 1.0 - Fbar
    return np.where(t > 0, (1.0 - Fi) * (1.0 - Fo) / np.where(t > 0, t, 1.0), 0.0)


#: diffuse terms by name: callables (wi, wo, kd, sigma) and kernel switch values
DIFFUSES: dict[str, tuple[Callable, int]] = {
    "none": (lambda wi, wo, kd, sigma: np.zeros(np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1])), 0),
    "lambert": (lambda wi, wo, kd, sigma: _oren_nayar(wi, wo, kd, 0.0), 1),
    "oren-nayar": (_oren_nayar, 2),
}


# ----------------------------------------------------------------------------------------------------------
# the whole BRDF


def brdf(wi, wo, *, alpha, alpha_y=None, ndf="ggx", shadowing="smith-correlated", fresnel="exact", eta=None,
         F0=None, abc_c=ABC_C_DEFAULT, diffuse="lambert", kd=0.0, sigma=0.0, tradeoff=True):
    """Microfacet BRDF f = f_s + w f_d: specular lobe plus an optional diffuse term, in 1/sr (not × cos).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light and to the viewer (normalized here; they broadcast).
    alpha, alpha_y, ndf, abc_c
        Specular NDF and roughness (see :func:`D`).
    shadowing : str
        ``"smith"``, ``"smith-correlated"``, ``"cook-torrance"`` or ``"implicit"``.
    fresnel : str
        ``"exact"``, ``"schlick"`` or ``"one"``.
    eta : array_like of complex, optional
        Complex index n + ik (per wavelength: shape (n_λ, 1) against directions (n, 3)).
    F0 : array_like, optional
        Normal-incidence reflectance (Schlick).
    diffuse : str
        ``"none"``, ``"lambert"`` or ``"oren-nayar"``.
    kd : array_like
        Diffuse albedo in [0, 1] (0: no diffuse term; metals have none).
    sigma : float
        Oren-Nayar roughness (radians), separate from the specular α.
    tradeoff : bool
        Weight the diffuse term by :func:`diffuse_tradeoff` (energy conservation between the two terms).

    Returns
    -------
    ndarray
        f ≥ 0 in 1/sr; 0 for directions below the surface.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007 (specular term).
    .. [2] P. Shirley et al., Pacific Graphics 1997 (diffuse-specular coupling).
    .. [3] M. Oren, S. K. Nayar, SIGGRAPH 1994 (rough diffuse).
    """
    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    gfn, _ = _shadowing(shadowing)
    F_fn = _fresnel_fn(fresnel, eta, F0)
    if diffuse not in DIFFUSES:
        raise unknown("diffuse model", diffuse, DIFFUSES)
    kd = np.asarray(kd, dtype=float)
    if np.any(~np.isfinite(kd) | (kd < 0) | (kd > 1)):
        raise WaveopticsError(f"kd={np.asarray(kd).tolist()!r} is not allowed; the diffuse albedo must be in [0, 1]")
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma < 0:
        raise WaveopticsError(f"sigma={sigma!r} is not allowed; the Oren-Nayar roughness must be >= 0 radians")
    wi = _as_dirs(wi, "wi")
    wo = _as_dirs(wo, "wo")
    wi, wo = np.broadcast_arrays(wi, wo)
    f = _specular(wi, wo, spec, ax, ay, abc_c, gfn, F_fn)
    if diffuse != "none" and np.any(kd > 0):
        fd = DIFFUSES[diffuse][0](wi, wo, kd, sigma)
        if tradeoff:
            # F̄ must broadcast like F(θ): as many axes as the directions' batch or the Fresnel parameters
            nb = max(wi.ndim - 1, np.ndim(eta) if eta is not None else 0, np.ndim(F0) if F0 is not None else 0)
            fd = fd * diffuse_tradeoff(wi, wo, F_fn, batch_ndim=nb)
        f = f + fd
    return f


def fresnel_inputs(material, wavelength_nm, fresnel="exact") -> dict:
    """Per-wavelength Fresnel inputs of a material for :func:`brdf` / :func:`brdf_cl`.

    Parameters
    ----------
    material : str or waveoptics.materials.Material
        Anything :func:`waveoptics.materials.get_material` accepts.
    wavelength_nm : array_like
        Wavelengths in nm (1-D).
    fresnel : str
        ``"exact"`` or ``"schlick"`` (``"one"`` gives F = 1). F0-only materials always use Schlick.

    Returns
    -------
    dict
        ``{"fresnel": str, "eta": complex array (n_λ,) or None, "F0": array (n_λ,) or None}``.
    """
    from .materials import get_material
    from .units import check_wavelengths

    mat = get_material(material)
    w = check_wavelengths(wavelength_nm)
    if fresnel not in FRESNELS:
        raise unknown("Fresnel model", fresnel, FRESNELS)
    if fresnel == "one":
        return {"fresnel": "one", "eta": None, "F0": None}
    if mat.schlick_only or fresnel == "schlick":
        return {"fresnel": "schlick", "eta": None, "F0": np.asarray(mat.F0(w), dtype=float)}
    return {"fresnel": "exact", "eta": mat.eta(w), "F0": None}


def spectral_brdf(wi, wo, wavelength_nm, material, *, fresnel="exact", **kwargs):
    """:func:`brdf` for a material at several wavelengths: result shape (n_λ, *batch).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions (broadcasting batch).
    wavelength_nm : array_like
        Wavelengths in nm (1-D).
    material : str or Material
        Any specification accepted by :func:`waveoptics.materials.get_material`.
    fresnel : str
        ``"exact"`` (Material.F: exact for indices, Schlick for F0-only materials) or ``"schlick"``.
    **kwargs
        The other parameters of :func:`brdf`; ``kd`` may be per wavelength (shape (n_λ,)).
    """
    fi = fresnel_inputs(material, wavelength_nm, fresnel)
    wi = np.asarray(wi, dtype=float)
    wo = np.asarray(wo, dtype=float)
    nb = max(wi.ndim, wo.ndim) - 1
    shape = (-1,) + (1,) * nb
    eta = None if fi["eta"] is None else fi["eta"].reshape(shape)
    F0 = None if fi["F0"] is None else fi["F0"].reshape(shape)
    kd = np.asarray(kwargs.pop("kd", 0.0), dtype=float)
    if kd.ndim == 1:
        kd = kd.reshape(shape)
    n_w = np.atleast_1d(np.asarray(wavelength_nm)).size
    out = brdf(wi[None], wo[None], fresnel=fi["fresnel"], eta=eta, F0=F0, kd=kd, **kwargs)
    return np.broadcast_to(out, (n_w,) + out.shape[1:])


# ----------------------------------------------------------------------------------------------------------
# quadrature over microfacet normals and directional albedo


@functools.lru_cache(maxsize=64)
def _normal_nodes(ax, ay, n_rho, n_phi):
    x, w = _gl01(n_rho)
    amin = min(ax, ay)
    # radial segments in stretched slope units ρ (slope = (α_x ρ cos φ, α_y ρ sin φ)): geometric edges from
    # ρ = 1/8 until the slope reaches 8 (θ_m ≈ 83°), then a tail [ρ_K, ∞) mapped by ρ = ρ_K / t
    kmax = int(np.ceil(np.log2(8.0 / amin)))
    edges = 2.0 ** np.arange(-3, max(kmax, -2) + 1)
    # also an edge at slope 1 (θ_m = 45°), where the reflected direction of normal incidence meets the horizon
    # (a kink of the integrand of directional_albedo): it replaces the geometric edge closest to it
    k1 = 1.0 / max(ax, ay)
    if edges[0] < k1 < edges[-1]:
        edges[np.argmin(np.abs(np.log(edges / k1)))] = k1
    edges = np.concatenate([[0.0], np.sort(edges)])
    rho, wr = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        rho.append(a + (b - a) * x)
        wr.append((b - a) * w)
    rk = edges[-1]
    rho.append(rk / x)
    wr.append(rk / x ** 2 * w)
    rho = np.concatenate(rho)
    wr = np.concatenate(wr)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    R, P = np.meshgrid(rho, phi, indexing="ij")
    WR = np.broadcast_to(wr[:, None], R.shape)
    sx = ax * R * np.cos(P)
    sy = ay * R * np.sin(P)
    cz = 1.0 / np.sqrt(1.0 + sx * sx + sy * sy)
    m = np.stack([-sx * cz, -sy * cz, cz], axis=-1).reshape(-1, 3)
    # dω_m = cos³θ_m d²slope, d²slope = α_x α_y ρ dρ dφ
    wgt = (cz ** 3 * ax * ay * R * WR * (2 * np.pi / n_phi)).ravel()
    m.setflags(write=False)
    wgt.setflags(write=False)
    return m, wgt


def normal_quadrature(alpha=1.0, alpha_y=None, *, n_rho=16, n_phi=64):
    """Quadrature nodes over the hemisphere of microfacet normals that resolve a lobe of width α.

    Slope space is sampled in polar coordinates stretched by (α_x, α_y): Gauss-Legendre (*n_rho* nodes) on
    geometrically growing radial segments from 1/8 α to slope 8, a mapped tail to infinite slope, and the
    midpoint rule (spectrally accurate for periodic integrands) with *n_phi* nodes in φ, multiplied by
    ⌈α_max/(3 α_min)⌉ for anisotropic lobes. dω = cos³θ d²slope.

    Parameters
    ----------
    alpha, alpha_y : float
        Lobe widths (slope units); the finer one sets the smallest segment. Floored at :data:`ALPHA_MIN`.

    Returns
    -------
    m : ndarray (K, 3)
        Unit normals with m_z > 0.
    weights : ndarray (K,)
        Solid-angle weights in sr (they sum to 2π).
    """
    ax = max(float(alpha), ALPHA_MIN)
    ay = ax if alpha_y is None else max(float(alpha_y), ALPHA_MIN)
    # far from the lobe an anisotropic stretch makes the φ integrand peaked (width ~ α_min/α_max): scale the
    # number of φ nodes with the anisotropy ratio (measured: Σ weights = 2π to 1e-8 up to a ratio of 100)
    ratio = max(ax, ay) / min(ax, ay)
    n_phi = int(n_phi) * max(1, int(np.ceil(ratio / 3.0)))
    return _normal_nodes(ax, ay, int(n_rho), n_phi)


def directional_albedo(f: Callable, wi, *, alpha=1.0, alpha_y=None, n_rho=16, n_phi=64):
    """Directional albedo E(wi) = ∫ f(wi, wo) cos θ_o dω_o by quadrature over half-vectors.

    The integral is written over h (wo = 2(wi·h)h − wi, dω_o = 4 (wi·h) dω_h) with the nodes of
    :func:`normal_quadrature`, which concentrate at the mirror direction with the lobe width α and still cover
    the whole hemisphere, so both a sharp lobe (α = 0.001) and a diffuse term are resolved. Nodes whose
    reflected direction is below the surface contribute 0; f cos θ_o is continuous there for physical BRDFs,
    so the error stays small (Lambert: |E − 1| < 1e-4 for α in [0.001, 1], ``tests/test_microfacet.py``).

    Parameters
    ----------
    f : callable
        f(wi, wo) -> BRDF (1/sr); called with wi of shape (n, 1, 3) and wo of shape (n, K, 3); it may add
        leading axes (e.g. wavelength), which are kept.
    wi : array_like (3,) or (n, 3)
        Incident unit direction(s), above the surface.
    alpha, alpha_y : float
        Width of the sharpest lobe of f (slope units), used to place the nodes.

    Returns
    -------
    ndarray
        E (dimensionless) of shape (..., n) (or (...) for a single wi).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14) (Jacobian of the reflection mapping).
    """
    wi_arr = _as_dirs(wi, "wi")
    single = wi_arr.ndim == 1
    wi2 = wi_arr.reshape(-1, 3)
    m, wm = normal_quadrature(alpha, alpha_y, n_rho=n_rho, n_phi=n_phi)
    out = []
    for w1 in wi2:
        ih = m @ w1
        wo = reflect(w1, m)
        jac = np.where((ih > 0) & (wo[:, 2] > 0), 4.0 * ih * wm * np.maximum(wo[:, 2], 0.0), 0.0)
        vals = np.asarray(f(w1[None, :], wo))
        out.append(np.sum(np.where(jac > 0, vals, 0.0) * jac, axis=-1))
    res = np.stack(out, axis=-1)
    return res[..., 0] if single else res


def albedo(wi, **kwargs):
    """Directional albedo ∫ f cos θ_o dω_o of :func:`brdf` with the given parameters (quadrature tuned to α).

    Parameters
    ----------
    wi : array_like (3,) or (n, 3)
        Incident unit direction(s).
    **kwargs
        Parameters of :func:`brdf` (``alpha`` required). Per-wavelength ``eta``/``F0``/``kd`` must have shape
        (n_λ, 1); the result then has shape (n_λ, n).
    """
    a = kwargs["alpha"]
    ay = kwargs.get("alpha_y")
    return directional_albedo(lambda a_, b_: brdf(a_, b_, **kwargs), wi, alpha=a, alpha_y=ay)


# ----------------------------------------------------------------------------------------------------------
# OpenCL twins


def _cl_setup(runtime, precision, defines=()):
    from .runtime import build_options, build_program, get_runtime

    rt = runtime if runtime is not None else get_runtime()
    dt = rt.real_dtype(precision)
    prg = build_program(rt, "microfacet.cl", build_options(dt, tuple(defines)))
    return rt, dt, prg


_kernels: dict = {}


def _kernel(prg, name):
    """The kernel object *name* of *prg*, retrieved once (pyopencl warns on repeated retrieval)."""
    import pyopencl as cl

    key = (id(prg), name)
    k = _kernels.get(key)
    if k is None:
        k = _kernels[key] = (prg, cl.Kernel(prg, name))
    return k[1]


def _defines(ndf=None, shadowing=None, fresnel=None, diffuse=None, tradeoff=None):
    d = []
    if ndf is not None:
        d.append(f"-DWO_NDF={_ndf(ndf).cl_id}")
    if shadowing is not None:
        d.append(f"-DWO_SHADOWING={_shadowing(shadowing)[1]}")
    if fresnel is not None:
        if fresnel not in FRESNELS:
            raise unknown("Fresnel model", fresnel, FRESNELS)
        d.append(f"-DWO_FRESNEL={FRESNELS[fresnel][1]}")
    if diffuse is not None:
        if diffuse not in DIFFUSES:
            raise unknown("diffuse model", diffuse, DIFFUSES)
        d.append(f"-DWO_DIFFUSE={DIFFUSES[diffuse][1]}")
    if tradeoff is not None:
        d.append(f"-DWO_TRADEOFF={int(bool(tradeoff))}")
    return d


def _vec_dev(queue, w, dt):
    import pyopencl.array as cla

    return cla.to_device(queue, np.ascontiguousarray(np.asarray(w, dtype=dt).reshape(-1, 3)).ravel())


def _ndf_kernel(kname, w, alpha, alpha_y, ndf, abc_c, runtime, precision):
    import pyopencl.array as cla

    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    w = _as_dirs(w, "w")
    rt, dt, prg = _cl_setup(runtime, precision, _defines(ndf=ndf))
    n = w.size // 3
    d_w = _vec_dev(rt.queue, w, dt)
    d_out = cla.empty(rt.queue, max(n, 1), dt)
    _kernel(prg, kname)(rt.queue, (max(n, 1),), None, d_w.data, d_out.data, dt(ax), dt(ay), dt(abc_c),
                        np.int32(n))
    return d_out.get()[:n].reshape(w.shape[:-1]).astype(np.float64)


def D_cl(m, alpha, alpha_y=None, *, ndf="ggx", abc_c=ABC_C_DEFAULT, runtime=None, precision="float32"):
    """OpenCL twin of :func:`D` (kernel ``D_eval`` in ``kernels/microfacet.cl``)."""
    return _ndf_kernel("D_eval", m, alpha, alpha_y, ndf, abc_c, runtime, precision)


def Lambda_cl(w, alpha, alpha_y=None, *, ndf="ggx", abc_c=ABC_C_DEFAULT, runtime=None, precision="float32"):
    """OpenCL twin of :func:`Lambda` (kernel ``Lambda_eval``); +inf below the surface like the NumPy one."""
    return _ndf_kernel("Lambda_eval", w, alpha, alpha_y, ndf, abc_c, runtime, precision)


def brdf_cl(wi, wo, *, alpha, alpha_y=None, ndf="ggx", shadowing="smith-correlated", fresnel="exact", eta=None,
            F0=None, abc_c=ABC_C_DEFAULT, diffuse="lambert", kd=0.0, sigma=0.0, tradeoff=True, runtime=None,
            precision="float32"):
    """OpenCL twin of :func:`brdf` for N direction pairs at M wavelengths (kernel ``brdf_eval``).

    Parameters
    ----------
    wi, wo : array_like (N, 3)
        Pairs of unit directions (broadcast to a common N).
    eta, F0, kd : array_like, shape (M,) or scalar
        Per-wavelength complex index, Schlick F0 and diffuse albedo (M = 1 when all are scalars).
    runtime : waveoptics.runtime.Runtime, optional
        Defaults to :func:`waveoptics.runtime.get_runtime`.
    precision : str
        ``"float32"`` or ``"float64"`` (needs device fp64).
    Other parameters
        As in :func:`brdf`; the model switches become ``-D`` build options.

    Returns
    -------
    ndarray (M, N)
        f in 1/sr (float64 copy of the device result).
    """
    import pyopencl.array as cla

    spec = _ndf(ndf)
    ax, ay = _check_alpha(alpha, alpha_y, spec, abc_c)
    F_fn = _fresnel_fn(fresnel, eta, F0)
    kd_a = np.atleast_1d(np.asarray(kd, dtype=float))
    if np.any(~np.isfinite(kd_a) | (kd_a < 0) | (kd_a > 1)):
        raise WaveopticsError(f"kd={np.asarray(kd).tolist()!r} is not allowed; the diffuse albedo must be in [0, 1]")
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma < 0:
        raise WaveopticsError(f"sigma={sigma!r} is not allowed; the Oren-Nayar roughness must be >= 0 radians")
    wi = _as_dirs(wi, "wi").reshape(-1, 3)
    wo = _as_dirs(wo, "wo").reshape(-1, 3)
    wi, wo = np.broadcast_arrays(wi, wo)
    n = wi.shape[0]
    eta_a = np.atleast_1d(np.asarray(1.0 if eta is None else eta, dtype=np.complex128))
    F0_a = np.atleast_1d(np.asarray(_fresnel.F0(eta_a) if F0 is None else F0, dtype=float))
    m = max(eta_a.size, F0_a.size, kd_a.size)
    eta_a, F0_a, kd_a = (np.broadcast_to(a.ravel(), (m,)) for a in (eta_a, F0_a, kd_a))
    Fbar = F_mean(F_fn, 1).reshape(-1) if (tradeoff and diffuse != "none") else np.zeros(1)
    Fbar = np.broadcast_to(Fbar, (m,))
    rt, dt, prg = _cl_setup(runtime, precision, _defines(ndf, shadowing, fresnel, diffuse, tradeoff))
    q = rt.queue
    args = [_vec_dev(q, wi, dt), _vec_dev(q, wo, dt)]
    args += [cla.to_device(q, np.ascontiguousarray(a, dtype=dt)) for a in (eta_a.real, eta_a.imag, F0_a, kd_a, Fbar)]
    d_out = cla.empty(q, max(n * m, 1), dt)
    _kernel(prg, "brdf_eval")(q, (max(n, 1), m), None, *[a.data for a in args], d_out.data, dt(ax), dt(ay), dt(abc_c),
                  dt(sigma), np.int32(n))
    return d_out.get()[: n * m].reshape(m, n).astype(np.float64)
