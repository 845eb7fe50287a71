"""The Fresnel factor choices of the microfacet BRDF (exact, Schlick, one) and the hemispherical mean of F used by
the diffuse-specular trade-off.

References
----------
.. [1] C. Schlick, "An Inexpensive BRDF Model for Physically-based Rendering", Computer Graphics Forum 13(3), 1994.
.. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5 and §14.2 (Fresnel equations, conductors).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import WaveopticsError, unknown
from ..materials import fresnel as _fresnel
from .smith import gl01

__all__ = ['FRESNELS', 'F_mean', 'MaterialFresnel']


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


class MaterialFresnel:
    """The Fresnel factor F(cos θ) of a material with no single interface index (a thin-film stack,
    :class:`waveoptics.materials.Stack`) at *wavelength_nm* (nm): given as ``fresnel`` to the NumPy BRDF, it plays
    the part of ``eta`` with ``fresnel="exact"``, and :meth:`reshape` shapes its wavelengths as ``eta`` would be
    shaped (``(n_λ, 1, ...)``) to broadcast against the directions."""

    def __init__(self, material, wavelength_nm):
        self.material = material
        self.wavelength_nm = np.asarray(wavelength_nm, dtype=float)

    def reshape(self, shape) -> "MaterialFresnel":
        return MaterialFresnel(self.material, self.wavelength_nm.reshape(shape))

    def __call__(self, cos_theta):
        return self.material.F(cos_theta, self.wavelength_nm)


def fresnel_fn(fresnel, eta, F0):
    if isinstance(fresnel, MaterialFresnel):   # the material's own reflectance (a film stack)
        return fresnel
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
    x, w = gl01(n)
    mu = x.reshape((-1,) + (1,) * batch_ndim)
    Fv = np.asarray(F_fn(mu), dtype=float)
    Fv = np.broadcast_to(Fv, np.broadcast_shapes(Fv.shape, mu.shape))
    wts = (2.0 * w * x).reshape(mu.shape)
    return np.sum(wts * Fv, axis=0)
