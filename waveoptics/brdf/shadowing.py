"""Masking-shadowing terms G: separable and height-correlated Smith, Cook-Torrance V-cavity, implicit.

References
----------
.. [1] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.
.. [2] R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics", ACM TOG 1(1), 1982.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from scipy import special

from ..errors import unknown
from ..vocabulary import DEFAULT_NDF
from .directions import as_dirs, dot_last
from .ndf import check_alpha, ndf_by_name
from .smith import G1_from_lambda

__all__ = ['G_smith', 'G_smith_correlated', 'G_cook_torrance', 'G_implicit', 'SHADOWINGS', 'G', 'sided_lambda',
           'sided_G2']

# ----------------------------------------------------------------------------------------------------------
# masking-shadowing G(l, v, h): each entry takes (wi, wo, m, lam) with lam a callable w -> Λ(w)


def G_smith(wi, wo, m, lam):
    """Separable (uncorrelated) Smith: G1(l, m) G1(v, m).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (23).
    .. [2] E. Heitz, JCGT 3(2), 2014, eq. (98).
    """
    return G1_from_lambda(wi, m, lam(wi)) * G1_from_lambda(wo, m, lam(wo))


def G_smith_correlated(wi, wo, m, lam):
    """Height-correlated Smith: χ⁺(l·m) χ⁺(v·m) / (1 + Λ(l) + Λ(v)).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (99).
    """
    li, lo = lam(wi), lam(wo)
    with np.errstate(invalid="ignore"):
        g = 1.0 / (1.0 + li + lo)
    ok = (dot_last(wi, m) > 0) & (dot_last(wo, m) > 0) & (wi[..., 2] > 0) & (wo[..., 2] > 0)
    return np.where(ok, g, 0.0)


def G_cook_torrance(wi, wo, m, lam=None):
    """V-cavity shadowing of Cook & Torrance: min(1, 2(n·m)(n·v)/(v·m), 2(n·m)(n·l)/(v·m)).

    References
    ----------
    .. [1] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982, eq. (5) (after Blinn 1977).
    """
    vm = dot_last(wo, m)
    ok = (vm > 0) & (dot_last(wi, m) > 0) & (wi[..., 2] > 0) & (wo[..., 2] > 0)
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


def shadowing_by_name(name):
    if name not in SHADOWINGS:
        raise unknown("shadowing model", name, SHADOWINGS)
    return SHADOWINGS[name]


def G(wi, wo, m, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, shadowing="smith-correlated", ndf_shape=None):
    """Masking-shadowing G(l, v, m) in [0, 1] (``shadowing`` one of :data:`SHADOWINGS`).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light and to the viewer.
    m : array_like (..., 3)
        Unit microfacet normal (the half-vector for reflection).
    alpha, alpha_y, ndf, ndf_shape
        As in :func:`D` (used by the Smith terms).
    shadowing : str
        ``"smith"``, ``"smith-correlated"``, ``"cook-torrance"`` or ``"implicit"``.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §6.
    .. [2] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982.
    """
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    fn, _ = shadowing_by_name(shadowing)
    return fn(as_dirs(wi, "wi"), as_dirs(wo, "wo"), as_dirs(m, "m"), lambda w: spec.Lambda(w, ax, ay, ndf_shape))


# ----------------------------------------------------------------------------------------------------------
# the Smith terms of a BSDF over the sphere (rough dielectric: directions on either side of the macro surface)


def sided_lambda(spec, w, ax, ay, c):
    """Smith Λ (dimensionless) of directions *w* (n, 3) on either side of the macro surface: the microsurface seen
    from below is the one seen along −ω (*spec* an NDF of :data:`waveoptics.brdf.NDFS`, *ax*, *ay*, *c* its
    roughness and shape).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.1 (G of a transmitted direction); E. Heitz, JCGT 3(2), 2014, §6.
    """
    return spec.Lambda(np.where(w[:, 2:3] < 0, -w, w), ax, ay, c)


def sided_G2(lam_i, lam_o, transmission, shadowing):
    """Masking-shadowing (dimensionless) of a valid configuration from the Λ of both directions
    (:func:`sided_lambda`): ``smith`` separable (1 + Λ_i)⁻¹(1 + Λ_o)⁻¹, or ``smith-correlated`` 1/(1 + Λ_i + Λ_o)
    (reflection) and B(1 + Λ_i, 1 + Λ_o) (*transmission*, boolean array); 0 where a Λ is infinite.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §6.1-6.2.
    .. [2] B. Walter et al., EGSR 2007, eq. (23).
    """
    with np.errstate(invalid="ignore", over="ignore"):
        if shadowing == "smith":
            g = 1.0 / ((1.0 + lam_i) * (1.0 + lam_o))
        else:
            # guard: Λ = inf (grazing) has G = 0; B of finite arguments only
            fin = np.isfinite(lam_i) & np.isfinite(lam_o)
            li, lo = np.where(fin, lam_i, 0.0), np.where(fin, lam_o, 0.0)
            g = np.where(transmission, special.beta(1.0 + li, 1.0 + lo), 1.0 / (1.0 + li + lo))
            g = np.where(fin, g, 0.0)
    return np.where(np.isfinite(g), g, 0.0)
