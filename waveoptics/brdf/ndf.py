"""The NDF registry: each normal distribution (GGX, Beckmann, Blinn-Phong, ABC, EPD, SGD, tabulated) as an
:class:`NDF` record, and D(m), Smith's Λ(w) and G1(w, m) by name, with the validation of α and of the shape
parameter. The distributions themselves live in :mod:`.ndf_closed` and :mod:`.ndf_shaped`, the roughness
conventions in :mod:`.roughness`, anisotropy by stretching in :mod:`.anisotropy`, Smith's masking in :mod:`.smith`.

References
----------
.. [1] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014.
.. [2] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., §9.6 (the distribution as an
   object with D, Λ and G1).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import WaveopticsError, unknown
from ..vocabulary import DEFAULT_NDF
from .directions import as_dirs, reflect  # noqa: F401  (reflect: imported from here by pointwise, issue 28)
from .measured_ndf import D_tabulated, Lambda_tabulated, SlopeTable
from .ndf_closed import D_beckmann, D_blinn_phong, D_ggx, Lambda_beckmann, Lambda_blinn_phong, Lambda_ggx
from .ndf_shaped import (ABC_C_DEFAULT, EPD_P_DEFAULT, SGD_P_DEFAULT, D_abc, D_epd, D_sgd, Lambda_abc, Lambda_epd,
                         Lambda_sgd)
from .smith import G1_from_lambda

__all__ = ['ALPHA_MIN', 'ALPHA_MAX', 'COS_MIN', 'SHAPE_RANGE', 'NDF', 'NDFS', 'D', 'Lambda', 'G1']

#: roughness floor (guard): narrower lobes are not representable at sampled directions
ALPHA_MIN = 1e-4
#: largest accepted α (mean slope 2, i.e. facets at 63° on average; larger is not a surface model any more)
ALPHA_MAX = 2.0
#: floor of the cosines in the specular denominator (guard against 1/cos θ growth at the horizon)
COS_MIN = 1e-7


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
        return G1_from_lambda(w, m, self.Lambda(w, ax, ay, c))


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


def ndf_by_name(name) -> NDF:
    if name not in NDFS:
        raise unknown("NDF", name, NDFS)
    return NDFS[name]


def check_alpha(alpha, alpha_y, ndf: NDF, ndf_shape):
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


def D(m, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, ndf_shape=None):
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
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    return spec.D(as_dirs(m, "m"), ax, ay, ndf_shape)


def Lambda(w, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, ndf_shape=None):
    """Smith's Λ(w) of an NDF (dimensionless, ≥ 0; +inf for w_z <= 0, where G1 = 0).

    Parameters are those of :func:`D`; *w* are unit directions (..., 3).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5 (eq. 72), eqs. (81), (86).
    """
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    return spec.Lambda(as_dirs(w, "w"), ax, ay, ndf_shape)


def G1(w, m, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, ndf_shape=None):
    """Smith masking function G1(w, m) = χ⁺(w·m) / (1 + Λ(w)), in [0, 1].

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (43).
    """
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    w = as_dirs(w, "w")
    m = as_dirs(m, "m")
    return G1_from_lambda(w, m, spec.Lambda(w, ax, ay, ndf_shape))

