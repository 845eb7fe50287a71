"""The NDFs whose Smith Λ has a closed form: GGX (Trowbridge-Reitz) and Beckmann, isotropic and anisotropic, and
normalized Blinn-Phong.

Every per-NDF function takes (vector, ax, ay, c): c is the shape parameter of the NDFs that have one and is ignored
here, so the registry :data:`waveoptics.brdf.ndf.NDFS` can call them uniformly. Vectors are unit; m_z <= 0 gives
D = 0, w_z <= 0 gives Λ = inf.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007.
.. [2] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.
"""
from __future__ import annotations

import numpy as np
from scipy import special

from .anisotropy import tan2_stretched
from .roughness import blinn_phong_exponent

__all__ = ['D_ggx', 'Lambda_ggx', 'D_beckmann', 'Lambda_beckmann', 'D_blinn_phong', 'Lambda_blinn_phong']


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
    t = tan2_stretched(w, ax, ay)
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
    t = tan2_stretched(w, ax, ay)
    fin = np.isfinite(t) & (t > 0)
    a = 1.0 / np.sqrt(np.where(fin, t, 1.0))
    lam = 0.5 * (np.exp(-a * a) / (a * np.sqrt(np.pi)) - special.erfc(a))
    lam = np.maximum(lam, 0.0)  # guard: rounding of the difference of two tiny numbers for a >> 1
    return np.where(fin, lam, np.where(np.isinf(t), np.inf, 0.0))



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

