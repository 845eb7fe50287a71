"""Quadrature over the microfacet normals seen from one incident direction, in polar coordinates about that
direction, so that the circle of facets at the critical angle (total internal reflection for light from the
denser side) is a line of the grid.

For light along ω (on the side s = sign ω_z), the facets it sees are the normals m with m_z > 0 and s (ω·m) > 0.
With v = s ω (v_z = μ = |cos θ| > 0), e₁ the unit vector of z − μ v and e₂ = v × e₁,

    m(ψ, χ) = cos ψ v + sin ψ (cos χ e₁ + sin χ e₂),   |ω·m| = cos ψ,   dω_m = sin ψ dψ dχ,

and m_z = μ cos ψ + sin θ sin ψ cos χ > 0 bounds χ by χ_max(ψ) = arccos(−cot ψ cot θ) once ψ > π/2 − θ. ψ is cut
into panels at the critical angle ψ_c = arccos √(1 − η_rel²) (η_rel = η_t/η_i < 1), where the Fresnel factor
has its √ kink (Born & Wolf §1.5.4), at π/2 − θ (where χ_max leaves π with a √ edge) and at θ (the facets along
the macro normal, the NDF's peak); Gauss-Legendre on each panel in ψ and on [−χ_max, χ_max] in χ. A smooth
integrand over facets then converges spectrally; the quadrature over slopes about the macro normal
(:func:`waveoptics.brdf.normal_quadrature`) crosses the kink inside its panels (measured: the rough dielectric's
single-scattering albedo from glass 4e-4 to 1e-3 off at α = 1 (30-70°); with these nodes within 2.5e-5 from
30° to 60° and 1.1e-4 up to 88°, α 0.2 to 1, against the same integral at twice the nodes without the θ panel).

The NDF's peak is resolved only when the lobe is wide against the ψ panels: :data:`INCIDENCE_ALPHA_MIN` is the
narrowest lobe for which :func:`waveoptics.brdf.albedo_single` uses these nodes.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, eqs. (14), (17) (the integrals over microfacet normals).
.. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.4 (total reflection).
.. [3] P. J. Davis, P. Rabinowitz, *Methods of Numerical Integration*, 2nd ed., Academic Press 1984, §2.7
   (Gauss-Legendre on panels split at the integrand's singular lines).
"""
from __future__ import annotations

import numpy as np

from .mu_pieces import critical_cosine

__all__ = ["INCIDENCE_NODES", "INCIDENCE_ALPHA_MIN", "incidence_panels", "incidence_normal_quadrature"]

#: Gauss-Legendre nodes per ψ panel and in χ (half of them on χ ≥ 0 for a symmetric integrand)
INCIDENCE_NODES = 64
#: narrowest lobe (min(α_x, α_y), slope units) integrated with these nodes: the NDF's peak spans ≥ 4 ψ nodes
INCIDENCE_ALPHA_MIN = 0.2


def incidence_panels(mu, eta_rel):
    """The ψ panel edges (radians, ascending, from 0 to π/2) for incidence cosine *mu* (> 0) and relative index
    *eta_rel* = η_t/η_i: the critical angle arccos √(1 − η_rel²) when η_rel < 1, π/2 − θ and θ."""
    theta = float(np.arccos(np.clip(mu, 0.0, 1.0)))
    edges = {0.0, 0.5 * np.pi, theta, 0.5 * np.pi - theta}
    mu_c = critical_cosine(1.0, eta_rel)
    if mu_c > 0.0:
        edges.add(float(np.arccos(mu_c)))
    return np.array(sorted(e for e in edges if 0.0 <= e <= 0.5 * np.pi))


def incidence_normal_quadrature(w1, eta_rel, n=INCIDENCE_NODES, symmetric=False):
    """Nodes over the facets seen from the direction *w1* (3,) (module doc) and their solid-angle weights (sr).

    Parameters
    ----------
    w1 : array_like (3,)
        Unit direction towards the light, on either side (w1_z ≠ 0).
    eta_rel : float
        η_t/η_i across the interface from *w1* (< 1: total internal reflection beyond the critical angle).
    n : int
        Gauss-Legendre nodes per ψ panel and in χ.
    symmetric : bool
        The integrand is even in χ (an isotropic lobe with *w1* in the xz plane): nodes on χ ≥ 0 only, weights
        doubled.

    Returns
    -------
    m : ndarray (K, 3)
        Unit normals with m_z > 0 and (w1·m) w1_z > 0.
    weights : ndarray (K,)
        dω_m (sr); they sum to the solid angle of the seen facets.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14); P. J. Davis, P. Rabinowitz 1984, §2.7.
    """
    w1 = np.asarray(w1, dtype=float)
    s = 1.0 if w1[2] > 0 else -1.0
    v = s * w1
    mu = float(v[2])
    sin_t = float(np.sqrt(max(1.0 - mu * mu, 0.0)))
    e1 = np.array([1.0, 0.0, 0.0]) if sin_t < 1e-12 else (np.array([0.0, 0.0, 1.0]) - mu * v) / sin_t
    e2 = np.cross(v, e1)
    x, wx = np.polynomial.legendre.leggauss(int(n))
    ms, ws = [], []
    edges = incidence_panels(mu, eta_rel)
    for a, b in zip(edges[:-1], edges[1:]):
        psi = a + 0.5 * (b - a) * (x + 1.0)
        # χ_max: m_z = μ cos ψ + sin θ sin ψ cos χ > 0 (π where every χ is above the horizon)
        lim = -mu * np.cos(psi) / np.maximum(sin_t * np.sin(psi), 1e-300)
        chi_max = np.arccos(np.clip(lim, -1.0, 1.0))
        lo = 0.0 if symmetric else -1.0
        chi = chi_max[:, None] * (lo + 0.5 * (1.0 - lo) * (x[None, :] + 1.0))
        wchi = chi_max[:, None] * 0.5 * (1.0 - lo) * wx[None, :] * (2.0 if symmetric else 1.0)
        P = np.broadcast_to(psi[:, None], chi.shape)
        m = (np.cos(P)[..., None] * v + np.sin(P)[..., None] * (np.cos(chi)[..., None] * e1
                                                               + np.sin(chi)[..., None] * e2))
        ms.append(m.reshape(-1, 3))
        ws.append((0.5 * (b - a) * wx[:, None] * np.sin(psi)[:, None] * wchi).ravel())
    m, w = np.concatenate(ms), np.concatenate(ws)
    keep = (m[:, 2] > 0) & (w > 0)
    return m[keep], w[keep]
