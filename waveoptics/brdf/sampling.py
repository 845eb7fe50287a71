"""Importance sampling of microfacet normals: visible normals of GGX, D(m) cos θ_m for the other NDFs.

A sampler draws a microfacet normal m for an incident direction ω_i from two uniform numbers u ∈ [0, 1)² and
gives its density p(m) in 1/sr (over normals); the outgoing direction is the mirror ω_o = 2(ω_i·m)m − ω_i, with
density p(ω_o) = p(m) / (4 |ω_i·m|) (Walter et al. 2007, eq. 14). Samplers by NDF (:data:`NORMAL_SAMPLERS`):

* ``ggx``: the distribution of visible normals D_ωi(m) = G1(ω_i) max(0, ω_i·m) D(m) / cos θ_i, sampled exactly
  (Heitz 2018): the weight f cos θ_o / p of the specular term is then F · G2/G1(ω_o), never above 1.
* ``beckmann``: D(m) cos θ_m, sampled exactly from its Gaussian slope law (anisotropic).
* ``blinn-phong``: D(m) cos θ_m, cos θ_m = (1 − u₁)^{1/(α_p + 2)} (Walter et al. 2007, eq. 35).
* ``abc``: D(m) cos θ_m by inverting its closed-form radial CDF (bisection to double precision).
* ``epd``: D(m) cos θ_m exactly: (r/α)^{2p} is gamma-distributed with shape 1/p (anisotropic: stretched slopes).
* ``sgd``: D(m) cos θ_m by inverting the incomplete gamma function of its shifted slope law (closed form for
  p < 1, Newton's method from a tabulated inverse for p ≥ 1).

Where D(m) cos θ_m is used, normals the light cannot see are drawn too (their ω_o falls below the surface or G
vanishes): the weight is then larger and noisier near grazing incidence than with visible normals, never biased.

References
----------
.. [1] E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4):1-13, 2018.
.. [2] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, §5.3 (normal sampling) and eq. (14) (Jacobian of the reflection).
.. [3] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014,
   eq. (38) (distribution of visible normals).
.. [4] J. Löw, J. Kronander, A. Ynnerman, J. Unger, ACM TOG 31(1):9, 2012 (ABC NDF).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import WaveopticsError, unknown
from scipy import special

from .measured_ndf import sample_dcos_tabulated

from .anisotropy import STRETCH_EXPONENT, stretch_factors
from .directions import dot_last, reflect
from .ndf import NDFS
from .ndf_shaped import (ABC_C_DEFAULT, EPD_P_DEFAULT, SGD_P_DEFAULT, abc_B, expm1_over, abc_normalization,
                         gamma_upper)
from .roughness import blinn_phong_exponent

__all__ = ['NormalSampler', 'NORMAL_SAMPLERS', 'sample_normal', 'pdf_normal', 'pdf_reflected', 'sample_reflected',
           'sample_normal_dcos']


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sample_vndf_ggx(wi, ax, ay, c, u):
    """Visible GGX normal for *wi* (..., 3) from *u* (..., 2) (Heitz 2018, listing 1)."""
    vh = _unit(np.stack([ax * wi[..., 0], ay * wi[..., 1], wi[..., 2]], axis=-1))
    lensq = vh[..., 0] ** 2 + vh[..., 1] ** 2
    safe = np.sqrt(np.where(lensq > 0, lensq, 1.0))
    t1 = np.where((lensq > 0)[..., None],
                  np.stack([-vh[..., 1] / safe, vh[..., 0] / safe, np.zeros_like(lensq)], axis=-1),
                  np.array([1.0, 0.0, 0.0]))
    t2 = np.cross(vh, t1)
    r = np.sqrt(u[..., 0])
    phi = 2.0 * np.pi * u[..., 1]
    p1 = r * np.cos(phi)
    p2 = r * np.sin(phi)
    s = 0.5 * (1.0 + vh[..., 2])
    p2 = (1.0 - s) * np.sqrt(np.maximum(1.0 - p1 * p1, 0.0)) + s * p2
    nh = (p1[..., None] * t1 + p2[..., None] * t2
          + np.sqrt(np.maximum(1.0 - p1 * p1 - p2 * p2, 0.0))[..., None] * vh)
    return _unit(np.stack([ax * nh[..., 0], ay * nh[..., 1], np.maximum(nh[..., 2], 1e-12)], axis=-1))


def pdf_vndf(ndf_name):
    """Density of visible normals G1(ω_i, m) max(0, ω_i·m) D(m) / cos θ_i (Heitz 2014, eq. 38), 1/sr."""
    spec = NDFS[ndf_name]

    def pdf(wi, m, ax, ay, c):
        g1 = spec.G1(wi, m, ax, ay, c)
        wz = wi[..., 2]
        val = g1 * np.maximum(dot_last(wi, m), 0.0) * spec.D(m, ax, ay, c) / np.where(wz > 0, wz, 1.0)
        return np.where(wz > 0, val, 0.0)
    return pdf


def pdf_dcos(ndf_name):
    """Density D(m) cos θ_m of the normal-distribution samplers, 1/sr."""
    spec = NDFS[ndf_name]

    def pdf(wi, m, ax, ay, c):
        return spec.D(m, ax, ay, c) * np.maximum(m[..., 2], 0.0)
    return pdf


def _normal_from_slopes(sx, sy):
    """Unit normal of the facet with slopes (∂h/∂x, ∂h/∂y) = (sx, sy): (−sx, −sy, 1)/norm."""
    return _unit(np.stack([-sx, -sy, np.ones_like(sx)], axis=-1))


def sample_dcos_beckmann(wi, ax, ay, c, u):
    """Beckmann normal with density D(m) cos θ_m: its slopes are Gaussian with variances α_x²/2, α_y²/2
    (Walter et al. 2007, eq. 28, anisotropic)."""
    r = np.sqrt(-np.log1p(-u[..., 0]))
    phi = 2.0 * np.pi * u[..., 1]
    return _normal_from_slopes(ax * r * np.cos(phi), ay * r * np.sin(phi))


def sample_dcos_ggx(wi, ax, ay, c, u):
    """GGX normal with density D(m) cos θ_m (not the visible normals): its slopes follow the stretched
    P22(x, y) = 1 / (π α_x α_y (1 + x²/α_x² + y²/α_y²)²), whose unit-α radius r has CDF r²/(1 + r²), so
    r = √(u₁/(1 − u₁)) (Walter et al. 2007, §5.2: θ_m = arctan(α √ξ₁/√(1 − ξ₁)); Heitz 2014, §5.3 stretching)."""
    u1 = np.clip(u[..., 0], 0.0, 1.0 - 1e-12)   # u₁ → 1 is a slope at infinity
    r = np.sqrt(u1 / (1.0 - u1))
    phi = 2.0 * np.pi * u[..., 1]
    ay = ax if ay is None else ay
    return _normal_from_slopes(ax * r * np.cos(phi), ay * r * np.sin(phi))


def _from_cos(cos_t, phi):
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    return np.stack([sin_t * np.cos(phi), sin_t * np.sin(phi), cos_t], axis=-1)


def sample_dcos_blinn_phong(wi, ax, ay, c, u):
    """Blinn-Phong normal with density D(m) cos θ_m: cos θ_m = (1 − u₁)^{1/(α_p + 2)} (Walter 2007, eq. 35)."""
    ap = float(blinn_phong_exponent(ax))
    cos_t = np.exp(np.log1p(-u[..., 0]) / (ap + 2.0))
    return _from_cos(cos_t, 2.0 * np.pi * u[..., 1])


def abc_cdf(t, ax, c):
    """Radial CDF of the ABC normal density D(m) cos θ_m in t = 1 − cos θ_m:
    2πA ∫₀ᵗ (1 + Bs)^{−C} (1 − s) ds = 2πA [E₁/B − (E₂ − E₁)/B²], E_p = ((1 + Bt)^p − 1)/p at p = 1 − C, 2 − C
    (the integral of :func:`waveoptics.brdf.abc_normalization` stopped at t; 1 at t = 1)."""
    c = ABC_C_DEFAULT if c is None else c
    B = abc_B(ax)
    L = np.log1p(B * np.asarray(t, dtype=float))
    e1 = expm1_over(1.0 - c, L)
    e2 = expm1_over(2.0 - c, L)
    return 2.0 * np.pi * abc_normalization(ax, c) * (e1 / B - (e2 - e1) / (B * B))


def sample_dcos_abc(wi, ax, ay, c, u):
    """ABC normal with density D(m) cos θ_m: t = 1 − cos θ_m solves CDF(t) = u₁ (bisection, 64 halvings: the
    CDF is increasing on [0, 1])."""
    target = u[..., 0]
    lo = np.zeros_like(target)
    hi = np.ones_like(target)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        below = abc_cdf(mid, ax, c) < target
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return _from_cos(1.0 - 0.5 * (lo + hi), 2.0 * np.pi * u[..., 1])


def _from_slope(r, phi):
    """Unit normal of slope magnitude r (tan θ_m) at azimuth φ."""
    cos_t = 1.0 / np.sqrt(1.0 + r * r)
    return _from_cos(cos_t, phi)


def _stretch_sample(sample_iso, name):
    """The sampler of the stretched (anisotropic) form of an isotropic NDF sampler: draw the normal of the base
    roughness ᾱ and stretch its slopes by (k_x, k_y), m ∝ (k_x m'_x, k_y m'_y, m'_z); slopes drawn from P22_ᾱ become
    slopes drawn from the stretched P22, so the density stays D(m) cos θ_m (Heitz 2014, §5.3;
    :func:`waveoptics.brdf.anisotropy.D_stretched`)."""
    def sample(wi, ax, ay, c, u):
        if ay is None or np.all(np.asarray(ay) == np.asarray(ax)):
            return sample_iso(wi, ax, None, c, u)
        base, kx, ky = stretch_factors(ax, ay, STRETCH_EXPONENT[name])
        m = sample_iso(wi, float(base), None, c, u)
        return _unit(np.stack([kx * m[..., 0], ky * m[..., 1], m[..., 2]], axis=-1))
    sample.__name__ = sample_iso.__name__
    sample.__doc__ = sample_iso.__doc__ + " Anisotropic α: the stretched form of the isotropic sample."
    return sample


def _sample_dcos_epd(wi, ax, ay, c, u):
    """EPD normal with density D(m) cos θ_m, exactly: the slope law N exp(−(r/α)^{2p}) makes g = (r/α)^{2p}
    Gamma(1/p)-distributed, so r = α g^{1/(2p)} with g = P⁻¹(1/p, u₁) (SciPy's ``gammaincinv``)."""
    p = EPD_P_DEFAULT if c is None else c
    g = special.gammaincinv(1.0 / p, u[..., 0])
    return _from_slope(ax * g ** (0.5 / p), 2.0 * np.pi * u[..., 1])


def sgd_y_survival(y, ax, p):
    """P(Y > y) for Y = (α² + tan²θ_m)/α of SGD normals drawn with density D cos θ_m: Γ(1 − p, y) / Γ(1 − p, α)
    (the density of Y is ∝ y^{−p} e^{−y} on [α, ∞))."""
    return gamma_upper(1.0 - p, y) / gamma_upper(1.0 - p, ax)


@functools.lru_cache(maxsize=32)
def _sgd_inverse_table(ax, p):
    """(log y, P(Y > y)) on 2049 nodes from α to α + 750 (beyond, e^{−y} underflows): the start of Newton's
    method in :func:`sample_dcos_sgd`."""
    t = np.linspace(np.log(ax), np.log(ax + 750.0), 2049)
    return t, sgd_y_survival(np.exp(t), ax, p)


def _sample_dcos_sgd(wi, ax, ay, c, u):
    """SGD normal with density D(m) cos θ_m: Y = (α² + tan²θ)/α solves P(Y > y) = 1 − u₁ — in closed form with
    ``gammainccinv`` for p < 1; for p ≥ 1 by Newton's method in log y (the derivative of P(Y > y) is the density
    −y^{−p} e^{−y} / Γ(1 − p, α)) from a tabulated inverse, kept inside the table's bracket; then
    tan²θ = αY − α²."""
    p = SGD_P_DEFAULT if c is None else c
    target = 1.0 - u[..., 0]
    if p < 1.0:
        a = 1.0 - p
        y = special.gammainccinv(a, target * special.gammaincc(a, ax))
    else:
        t_tab, s_tab = _sgd_inverse_table(float(ax), float(p))
        t = np.interp(-target, -s_tab, t_tab)          # s_tab falls: interpolate on its negative
        g = gamma_upper(1.0 - p, ax)
        for _ in range(6):
            yy = np.exp(t)
            f = gamma_upper(1.0 - p, yy) / g - target
            df = -(yy ** (1.0 - p)) * np.exp(-yy) / g   # d/dt of P(Y > e^t)
            step = np.where(df < 0, f / np.where(df < 0, df, -1.0), 0.0)
            t = np.clip(t - step, t_tab[0], t_tab[-1])
        y = np.exp(t)
    x = np.maximum(ax * y - ax * ax, 0.0)
    return _from_slope(np.sqrt(x), 2.0 * np.pi * u[..., 1])


sample_dcos_epd = _stretch_sample(_sample_dcos_epd, "epd")
sample_dcos_sgd = _stretch_sample(_sample_dcos_sgd, "sgd")


@dataclass(frozen=True)
class NormalSampler:
    """Sampling of microfacet normals for one NDF: ``sample(wi, ax, ay, c, u)`` → m and ``pdf(wi, m, ax, ay, c)``
    in 1/sr over normals; ``visible`` says whether only normals seen from ω_i are drawn."""

    sample: Callable
    pdf: Callable
    visible: bool
    reference: str


#: normal samplers by NDF name (the keys of :data:`waveoptics.brdf.NDFS`)
NORMAL_SAMPLERS: dict[str, NormalSampler] = {
    "ggx": NormalSampler(sample_vndf_ggx, pdf_vndf("ggx"), True, "Heitz 2018"),
    "beckmann": NormalSampler(sample_dcos_beckmann, pdf_dcos("beckmann"), False, "Walter et al. 2007, eq. 28"),
    "blinn-phong": NormalSampler(sample_dcos_blinn_phong, pdf_dcos("blinn-phong"), False,
                                 "Walter et al. 2007, eq. 35"),
    "abc": NormalSampler(sample_dcos_abc, pdf_dcos("abc"), False, "Löw et al. 2012 (radial CDF inverted)"),
    "epd": NormalSampler(sample_dcos_epd, pdf_dcos("epd"), False, "Holzschuch & Pacanowski 2017 (gamma slopes)"),
    "sgd": NormalSampler(sample_dcos_sgd, pdf_dcos("sgd"), False, "Bagher et al. 2012 (incomplete gamma inverted)"),
    "tabulated": NormalSampler(sample_dcos_tabulated, pdf_dcos("tabulated"), False,
                               "marginal row, conditional bin, a slope uniformly in it (Pharr et al.)"),
}


def sampler_for(ndf) -> NormalSampler:
    if ndf not in NORMAL_SAMPLERS:
        raise unknown("NDF", ndf, NORMAL_SAMPLERS)
    return NORMAL_SAMPLERS[ndf]


def sample_normal(wi, u, *, ndf, ax, ay, c):
    """A microfacet normal (..., 3) for incident *wi* (..., 3) from uniform *u* (..., 2) (see module doc)."""
    return sampler_for(ndf).sample(np.asarray(wi, float), ax, ay, c, np.asarray(u, float))


def sample_normal_dcos(u, *, ndf, ax, ay, c):
    """A microfacet normal (..., 3) drawn with density D(m) cos θ_m (:func:`pdf_dcos`) from uniform *u* (..., 2),
    whatever the light's direction: for GGX :func:`sample_dcos_ggx`, for the other NDFs their own sampler. Normals
    that do not depend on ω_i serve a quadrature that must treat ω_i and ω_o alike (reciprocity)."""
    u = np.asarray(u, float)
    up = np.broadcast_to(np.array([0.0, 0.0, 1.0]), u.shape[:-1] + (3,))
    if ndf == "ggx":
        return sample_dcos_ggx(up, ax, ay, c, u)
    spl = sampler_for(ndf)
    if spl.visible:   # a visible-normal sampler added without its D cos θ_m twin
        raise WaveopticsError(f"NDF {ndf!r} has no D(m) cos θ_m sampler")
    return spl.sample(up, ax, ay, c, u)


def pdf_normal(wi, m, *, ndf, ax, ay, c):
    """Density (1/sr over normals) with which :func:`sample_normal` draws *m* for *wi*."""
    return sampler_for(ndf).pdf(np.asarray(wi, float), np.asarray(m, float), ax, ay, c)


def sample_reflected(wi, u, *, ndf, ax, ay, c):
    """Outgoing direction ω_o = reflect(ω_i, m) for a sampled normal, and the normal m; ω_o may lie below the
    surface (the caller gives such a sample weight 0)."""
    m = sample_normal(wi, u, ndf=ndf, ax=ax, ay=ay, c=c)
    return reflect(np.asarray(wi, float), m), m


def pdf_reflected(wi, wo, *, ndf, ax, ay, c):
    """Density (1/sr over ω_o) of :func:`sample_reflected`: p(m) / (4 ω_i·m) with m the half-vector
    (Walter et al. 2007, eq. 14); 0 where either direction is below the surface."""
    wi = np.asarray(wi, float)
    wo = np.asarray(wo, float)
    s = wi + wo
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    m = s / np.where(n > 0, n, 1.0)
    dot = dot_last(wi, m)
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0) & (dot > 0) & (n[..., 0] > 0)
    p = pdf_normal(wi, np.where(up[..., None], m, np.array([0.0, 0.0, 1.0])), ndf=ndf, ax=ax, ay=ay, c=c)
    return np.where(up, p / (4.0 * np.where(dot > 0, dot, 1.0)), 0.0)
