"""Multiple-scattering energy compensation of microfacet BRDFs (Kulla & Conty 2017).

A single-scattering microfacet BRDF loses the light that bounces more than once between facets: its white-furnace
albedo E(μ) (F = 1) falls below 1 as α grows (31 % lost at α = 0.5, 69 % at α = 1 for GGX at normal incidence,
docs/microfacet.md). Kulla & Conty add a lobe that returns exactly that energy,

    f_ms(μ_i, μ_o) = (1 − E(μ_i)) (1 − E(μ_o)) / (π (1 − E_avg)),   E_avg = 2 ∫₀¹ E(μ) μ dμ,

reciprocal and diffuse-like, so that with F = 1 the albedo is E(μ_i) + (1 − E(μ_i)) = 1 at every μ_i. With a
Fresnel factor the lobe is scaled by the average Fresnel of a multiply-bounced path,

    F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)),   F_avg = 2 ∫₀¹ F(μ) μ dμ.

E(μ) is tabulated once per NDF and roughness on Gauss-Legendre nodes in μ by the library's albedo quadrature and
interpolated linearly. Anisotropic roughness uses the isotropic table of √(α_x α_y) (Kulla & Conty's tables are
isotropic too); the lobe's shape is an approximation of the true multiple scattering (Heitz et al. 2016), its
energy is exact by construction.

References
----------
.. [1] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course
   (Physically Based Shading in Theory and Practice), slides 14-19.
.. [2] E. Heitz, J. Hanika, E. d'Eon, C. Dachsbacher, "Multiple-scattering microfacet BSDFs with the Smith
   model", ACM TOG 35(4), 2016 (the random-walk reference the compensation approximates).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .microfacet import specular
from .smith import gl01
from .quadrature import directional_albedo, slope_table_of

__all__ = ['MS_NODES', 'AlbedoTable', 'albedo_table', 'f_ms', 'F_ms']

#: Gauss-Legendre nodes in μ of the albedo table
MS_NODES = 64


@dataclass(frozen=True)
class AlbedoTable:
    """E(μ) of a microfacet lobe with F = 1 on nodes ``mu`` (ascending), and E_avg = 2 ∫ E μ dμ."""

    mu: np.ndarray
    E: np.ndarray
    E_avg: float

    def __call__(self, mu):
        """E at cosines *mu* (linear between nodes, held at the end nodes)."""
        return np.interp(np.clip(np.asarray(mu, dtype=float), 0.0, 1.0), self.mu, self.E)


@functools.lru_cache(maxsize=64)
def albedo_table(ndf: str, alpha: float, shadowing: str, ndf_shape: float | None) -> AlbedoTable:
    """E(μ) and E_avg of the F = 1 specular lobe (isotropic *alpha*) by :func:`waveoptics.brdf.directional_albedo`."""
    x, w = gl01(MS_NODES)
    E = np.empty(x.size)
    for i, mu in enumerate(x):
        wi = np.array([np.sqrt(max(1.0 - mu * mu, 0.0)), 0.0, mu])
        E[i] = float(directional_albedo(
            lambda a, b: specular(a, b, alpha=alpha, ndf=ndf, shadowing=shadowing, fresnel="one", ndf_shape=ndf_shape),
            wi, alpha=alpha, table=slope_table_of(ndf, ndf_shape)))
    # guard: a single-scattering albedo cannot exceed 1, but the quadrature's error can put it up to 2.3e-4 above
    # (measured over the four NDFs, α from 1e-4 to 2, all 64 nodes); above 1 the lobe 1 − E would turn negative
    E = np.minimum(E, 1.0)
    return AlbedoTable(mu=x, E=E, E_avg=float(2.0 * np.sum(w * E * x)))


def f_ms(cos_i, cos_o, table: AlbedoTable):
    """The compensation lobe (1 − E(μ_i))(1 − E(μ_o)) / (π (1 − E_avg)) in 1/sr; 0 below the surface."""
    ci = np.asarray(cos_i, dtype=float)
    co = np.asarray(cos_o, dtype=float)
    denom = np.pi * max(1.0 - table.E_avg, 1e-12)
    val = (1.0 - table(ci)) * (1.0 - table(co)) / denom
    return np.where((ci > 0) & (co > 0), val, 0.0)


def F_ms(F_avg, E_avg):
    """Average Fresnel of multiply scattered light, F_avg² E_avg / (1 − F_avg (1 − E_avg)) (Kulla & Conty 2017)."""
    F_avg = np.asarray(F_avg, dtype=float)
    return F_avg ** 2 * E_avg / (1.0 - F_avg * (1.0 - E_avg))
