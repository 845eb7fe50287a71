"""The light's solid angle in a glint render: an area light seen as a disk of angular radius ρ, the BRDF averaged
over the directions ω_i in that cone (a uniform emitter of radiance L_e gives L_o = L_e ∫_cone f cos θ_i dω_i,
the rendering equation [1]_, so the mean of f cos θ_i over the cone times the irradiance I/d² = L_e Ω).

The average over the spherical cap |ω − a| ≤ ρ about the axis a (uniform in solid angle, dω = d(cos θ) dφ) is taken
with a product rule in u = (1 − cos θ)/(1 − cos ρ) ∈ [0, 1] and φ: Gauss-Legendre in u (``rings`` nodes) times
``2 rings + 2`` equally spaced φ (every other ring turned by half a step). It is exact for functions that are
polynomials of degree < 2 rings in u times trigonometric polynomials of degree < 2 rings + 2 in φ, hence for the
polynomials of degree ≤ 2 rings − 1 in the offsets (x, y) = sin θ (cos φ, sin φ) from the axis (sin²θ is
quadratic in u; a monomial of odd degree has only odd harmonics in φ and averages to zero on both sides).

References
----------
.. [1] J. T. Kajiya, "The rendering equation", Computer Graphics 20(4) (SIGGRAPH 1986), 143-150.
.. [2] A. H. Stroud, *Approximate Calculation of Multiple Integrals*, Prentice-Hall, 1971, §2.7 (product rules
   on the disk: Gauss in r², equal angles).
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["cone_rule", "cone_directions"]


def cone_rule(rings: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nodes (u, φ) and weights (summing to 1) of the cap rule of the module doc.

    Parameters
    ----------
    rings : int
        Gauss-Legendre nodes in u (≥ 1); the rule has rings × (2 rings + 2) nodes.

    Returns
    -------
    u, phi, w : ndarray (m,)
        u ∈ (0, 1), φ in radians, weights.
    """
    x, wx = np.polynomial.legendre.leggauss(int(rings))
    n_phi = 2 * int(rings) + 2
    u, phi, w = [], [], []
    for k, (xk, wk) in enumerate(zip(x, wx)):
        turn = 0.5 * (k % 2)
        u += [0.5 * (xk + 1.0)] * n_phi
        phi += [2 * math.pi * (m + turn) / n_phi for m in range(n_phi)]
        w += [0.5 * wk / n_phi] * n_phi
    return np.array(u), np.array(phi), np.array(w)


def cone_directions(axis, radius_rad: float, rings: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions (n, m, 3) of the cap rule about each unit *axis* (n, 3) of angular radius *radius_rad*,
    and their weights (m,); *radius_rad* = 0 gives the axis alone (weight 1): a point light."""
    axis = np.atleast_2d(np.asarray(axis, dtype=float))
    if radius_rad == 0:
        return axis[:, None, :].copy(), np.ones(1)
    u, phi, w = cone_rule(rings)
    cos_t = 1.0 - u * (1.0 - math.cos(radius_rad))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    # an orthonormal frame (e1, e2, axis) per axis: e1 from the world axis least aligned with it
    helper = np.where(np.abs(axis[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(helper, axis)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(axis, e1)
    d = (cos_t[None, :, None] * axis[:, None, :]
         + (sin_t * np.cos(phi))[None, :, None] * e1[:, None, :]
         + (sin_t * np.sin(phi))[None, :, None] * e2[:, None, :])
    return d, w
