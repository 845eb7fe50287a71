"""Reads of the tables of :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` shared by the library and the Dr.Jit
plugin (:mod:`waveoptics.renderers.drjit_lobes`): where a node's lobe is read for a light between nodes, and the
lobes filled beyond the rim of the direction-cosine disc for bilinear reads near the horizon.

References
----------
.. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007 (the microfacet BRDF and its half-vector).
"""
from __future__ import annotations

import numpy as np

__all__ = ['half_vector_exit', 'filled_beyond_rim']


def half_vector_exit(wi, wo, wn, where=np.where):
    """Where a table computed for the light ω_n' = *wn* is read for the pair (*wi*, *wo*): the exit ω_n whose
    half-vector with ω_n' is that of (ω_i, ω_o), ω_n = 2 (ω_n'·h) h − ω_n' (reflection of ω_n' about
    h ∝ ω_i + ω_o, written 2 (ω_n'·h) h / |h|² unnormalized), and the factor cos θ_n' cos θ_n / (cos θ_i cos θ_o)
    that carries a microfacet lobe f = F G D(h) / (4 cos θ_i cos θ_o) from (ω_n', ω_n) to (ω_i, ω_o) at the same
    D(h) (F and G taken as the node's). Returns (x, y, z, factor) of ω_n; the factor is 0 where
    cos θ_i cos θ_o ≤ 0. Each argument is a sequence of 3 component arrays (NumPy, or Dr.Jit's with *where* =
    ``drjit.select``: the Dr.Jit plugin's read is this same arithmetic).

    References
    ----------
    .. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eqs. (13) (the half-vector), (20) (the
       microfacet BRDF) and (39) (reflection about a normal).
    """
    hx, hy, hz = wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]
    c = 2 * (wn[0] * hx + wn[1] * hy + wn[2] * hz) / (hx * hx + hy * hy + hz * hz)
    x, y, z = c * hx - wn[0], c * hy - wn[1], c * hz - wn[2]
    den = wi[2] * wo[2]
    return x, y, z, where(den > 0, wn[2] * z / where(den > 0, den, 1.0), 0.0)


def filled_beyond_rim(lobes, inside):
    """The lobes (..., n_v, n_u) with each cell outside the disc (*inside* False, (n_v, n_u)) next to it given the
    mean of its neighbours known so far, in two passes (a copy): a bilinear read within a cell of the horizon
    would otherwise blend in zeros."""
    n_v, n_u = inside.shape
    filled, known = np.array(lobes, copy=True), inside.copy()
    # neighbours (row, column offsets) of a cell, wrapping round the grid's edges
    steps = ((0, -1), (0, 1), (-1, 0), (1, 0))
    for _ in range(2):
        count = np.zeros(known.shape)
        for dv, du in steps:
            count += np.roll(known, (-dv, -du), axis=(0, 1))
        new = ~known & (count > 0)
        rows, cols = np.nonzero(new)   # only the ring of new cells is read and written (all lobes at once)
        total = np.zeros(filled.shape[:-2] + rows.shape)
        for dv, du in steps:
            r, c = (rows + dv) % n_v, (cols + du) % n_u
            total += np.where(known[r, c], filled[..., r, c], 0.0)
        filled[..., rows, cols] = total / np.maximum(count[rows, cols], 1)
        known = known | new
    return filled
