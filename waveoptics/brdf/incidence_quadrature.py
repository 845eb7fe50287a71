"""Quadrature over the microfacet normals seen from one incident direction, in polar coordinates about that
direction, so that the circle of facets at the critical angle (total internal reflection for light from the
denser side) is a line of the grid.

For light along ω (on the side s = sign ω_z), the facets it sees are the normals m with m_z > 0 and s (ω·m) > 0.
With v = s ω (v_z = μ = |cos θ| > 0), e₁ the unit vector of z − μ v and e₂ = v × e₁,

    m(ψ, χ) = cos ψ v + sin ψ (cos χ e₁ + sin χ e₂),   |ω·m| = cos ψ,   dω_m = sin ψ dψ dχ,

and m_z = μ cos ψ + sin θ sin ψ cos χ > 0 bounds χ by χ_max(ψ) = arccos(−cot ψ cot θ) once ψ > π/2 − θ. ψ is cut
into panels at the critical angle ψ_c = arccos √(1 − η_rel²) (η_rel = η_t/η_i < 1), where the Fresnel factor
has its √ kink (Born & Wolf §1.5.4), at π/2 − θ (where χ_max leaves π with a √ edge) and at θ (the facets along
the macro normal, the NDF's peak). In χ, [0, χ_max] is cut where the facets' mirror direction and refracted
direction graze the macro surface (there Smith's G of the outgoing direction falls to 0 with a kink; Walter
eq. 40 gives the cuts in closed form, :func:`_horizon_cuts`), and ψ also at the angles where those cuts enter
the seen facets (ψ = π/4 ± θ/2 for the mirror direction; found numerically for the refracted one). Gauss-Legendre
with :data:`INCIDENCE_NODES` nodes on every panel. The quadrature over slopes about the macro normal
(:func:`waveoptics.brdf.normal_quadrature`) crosses these kinks inside its panels (measured: the rough
dielectric's single-scattering albedo from glass 4e-4 to 1e-3 off at α = 1, 30-70°); these nodes are within
2.3e-5 (α = 0.2) and 3.4e-6 (α = 1) from 30° to 60°, 3.9e-5 at 0-88°, of the same integral without the χ cuts at
192 nodes per panel (ggx and beckmann, smith-correlated, η = 1.5).

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
from scipy import optimize

from .mu_pieces import critical_cosine

__all__ = ["INCIDENCE_NODES", "INCIDENCE_ALPHA_MIN", "incidence_panels", "incidence_normal_quadrature"]

#: Gauss-Legendre nodes per ψ panel and per χ panel (χ ≥ 0 only for a symmetric integrand)
INCIDENCE_NODES = 24
#: narrowest lobe (min(α_x, α_y), slope units) integrated with these nodes: the NDF's peak spans ≥ 4 ψ nodes
INCIDENCE_ALPHA_MIN = 0.2


def _horizon_cuts(psi, mu, sin_t, eta_rel):
    """cos χ (P, 2) of the facets at ψ (P,) whose mirror (column 0) and refracted (column 1) directions graze the
    macro surface (module doc; NaN where there is none): the mirror direction stays on ω_i's side while
    m_z > μ / (2 cos ψ), the refracted one crosses while a m_z < μ / η_rel with a = cos ψ / η_rel − √k,
    k = 1 − sin²ψ / η_rel² (Walter eq. 40); m_z = μ cos ψ + sin θ sin ψ cos χ."""
    c, s = np.cos(psi), np.sin(psi)
    den = np.maximum(sin_t * s, 1e-300)
    with np.errstate(divide="ignore", invalid="ignore"):
        g_r = (mu / (2.0 * c) - mu * c) / den
        k = 1.0 - s * s / (eta_rel * eta_rel)
        a = c / eta_rel - np.sqrt(np.where(k > 0, k, 0.0))
        g_t = np.where((k > 0) & (a > 0), (mu / (eta_rel * a) - mu * c) / den, np.nan)
    return np.stack([g_r, g_t], axis=-1)


def _event_angles(mu, sin_t, eta_rel, samples=257):
    """ψ (radians) where a grazing cut of :func:`_horizon_cuts` enters or leaves χ ∈ [0, π] (cos χ = ±1), or, at
    normal incidence, where the grazing facets lie. The mirror direction's: −μ cos 2ψ = ± sin θ sin 2ψ, i.e.
    ψ = π/4 ± θ/2 in closed form; the refracted direction's: sign changes on *samples* points of (0, π/2), refined
    by Brent's method."""
    theta = float(np.arctan2(sin_t, mu))
    out = [0.25 * np.pi + 0.5 * theta, 0.25 * np.pi - 0.5 * theta]
    psi = np.linspace(1e-9, 0.5 * np.pi - 1e-9, samples)
    normal = sin_t < 1e-12      # then the grazing facets are circles ψ = const: the cut's numerator vanishes there
    for target in ((0.0,) if normal else (1.0, -1.0)):
        def h(p):
            return float(_horizon_cuts(np.atleast_1d(p), mu, 1.0 if normal else sin_t, eta_rel)[0, 1] - target)
        v = _horizon_cuts(psi, mu, 1.0 if normal else sin_t, eta_rel)[:, 1] - target
        for j in np.nonzero(np.isfinite(v[:-1]) & np.isfinite(v[1:]) & (np.sign(v[:-1]) != np.sign(v[1:])))[0]:
            out.append(optimize.brentq(h, psi[j], psi[j + 1], xtol=1e-13))
    return out


def incidence_panels(mu, eta_rel):
    """The ψ panel edges (radians, ascending, from 0 to π/2) for incidence cosine *mu* (> 0) and relative index
    *eta_rel* = η_t/η_i: the critical angle arccos √(1 − η_rel²) when η_rel < 1, π/2 − θ, θ, and where the
    grazing mirror or refracted directions enter the facets seen (:func:`_event_angles`)."""
    theta = float(np.arccos(np.clip(mu, 0.0, 1.0)))
    edges = {0.0, 0.5 * np.pi, theta, 0.5 * np.pi - theta}
    mu_c = critical_cosine(1.0, eta_rel)
    if mu_c > 0.0:
        edges.add(float(np.arccos(mu_c)))
    edges.update(float(e) for e in _event_angles(float(mu), float(np.sin(theta)), eta_rel))
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
        Gauss-Legendre nodes per ψ panel and per χ panel.
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
    .. [1] B. Walter et al., EGSR 2007, eqs. (14), (40); P. J. Davis, P. Rabinowitz 1984, §2.7.
    """
    w1 = np.asarray(w1, dtype=float)
    s = 1.0 if w1[2] > 0 else -1.0
    v = s * w1
    mu = float(v[2])
    sin_t = float(np.sqrt(max(1.0 - mu * mu, 0.0)))
    e1 = np.array([1.0, 0.0, 0.0]) if sin_t < 1e-12 else (np.array([0.0, 0.0, 1.0]) - mu * v) / sin_t
    e2 = np.cross(v, e1)
    x, wx = np.polynomial.legendre.leggauss(int(n))
    u, wu = 0.5 * (x + 1.0), 0.5 * wx
    edges = incidence_panels(mu, eta_rel)
    psi = np.concatenate([a + (b - a) * u for a, b in zip(edges[:-1], edges[1:])])
    wpsi = np.concatenate([(b - a) * wu for a, b in zip(edges[:-1], edges[1:])])
    # χ panels: [0, χ_max] cut where the mirror and refracted directions graze (kinks of the integrand)
    lim = -mu * np.cos(psi) / np.maximum(sin_t * np.sin(psi), 1e-300)
    chi_max = np.arccos(np.clip(lim, -1.0, 1.0))
    g = _horizon_cuts(psi, mu, sin_t, eta_rel)
    cuts = np.where(np.isfinite(g) & (np.abs(g) < 1.0), np.arccos(np.clip(np.nan_to_num(g), -1.0, 1.0)),
                    chi_max[:, None])
    bounds = np.concatenate([np.zeros((psi.size, 1)), np.sort(np.minimum(cuts, chi_max[:, None]), axis=1),
                             chi_max[:, None]], axis=1)
    lo, hi = bounds[:, :-1, None], bounds[:, 1:, None]
    chi = (lo + (hi - lo) * u).reshape(psi.size, -1)
    wchi = ((hi - lo) * wu).reshape(psi.size, -1)
    if not symmetric:
        chi, wchi = np.concatenate([chi, -chi], axis=1), np.concatenate([wchi, wchi], axis=1)
    else:
        wchi = 2.0 * wchi
    P = np.broadcast_to(psi[:, None], chi.shape)
    m = (np.cos(P)[..., None] * v + np.sin(P)[..., None] * (np.cos(chi)[..., None] * e1
                                                           + np.sin(chi)[..., None] * e2))
    w = (wpsi[:, None] * np.sin(psi)[:, None] * wchi).ravel()
    m = m.reshape(-1, 3)
    keep = (m[:, 2] > 0) & (w > 0)
    return m[keep], w[keep]
