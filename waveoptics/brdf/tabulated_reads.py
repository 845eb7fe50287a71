"""Reads of the tables of :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` shared by the library and the Dr.Jit
plugin (:mod:`waveoptics.renderers.drjit_lobes`): how many light azimuths a table holds and whether it is read by the
half-vector (one rule for the renderer model and export and for ``waveoptics simulate``'s sphere renders and their
cost and progress counts), where a node's lobe is read for a light between nodes, and the lobes filled beyond the
rim of the direction-cosine disc for bilinear reads near the horizon.

References
----------
.. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007 (the microfacet BRDF and its half-vector).
"""
from __future__ import annotations

import numpy as np

from .roughness_scales import isotropic

__all__ = ['PHI_NODES_ANISOTROPIC', 'PHI_NODES_ANISOTROPIC_NDF', 'reads_by_half_vector', 'light_azimuth_nodes',
           'half_vector_exit', 'filled_beyond_rim']

#: azimuth nodes over [0°, 360°) for surfaces whose lobe depends on the light's azimuth. Measured on a grating and
#: on scratches at light azimuths between nodes (θ_i 25-30°): 1 node (shift only): energy within 2 %, L1 5-26 %;
#: 4 nodes: energy within 0.6 %, L1 2-5 %; 12 nodes: energy within 0.7 %, L1 1-2.4 %
PHI_NODES_ANISOTROPIC = 4
#: azimuth nodes over [0°, 360°) of an anisotropic analytic micro NDF with PSD statistics, read by the half-vector
#: (:func:`half_vector_exit`). Measured (Al, Beckmann α 0.15 × 0.4, 64², θ_i 30° / 60°, φ_i every 7.5°, exits to
#: 60° above 1 % of the peak; 90th percentile / max error against the lobe computed at that light): 4 nodes 9.7 /
#: 20 %, 20 / 82 %; 8 nodes 3.3 / 5.1 %, 7.1 / 17 %; 12 nodes 1.7 / 5.2 %, 3.4 / 8.6 % (midway between incidence
#: nodes 10° apart too: 2.3 / 5.8 %, 4.0 / 9.5 %); scripts/aniso_light_azimuth.py
PHI_NODES_ANISOTROPIC_NDF = 12


def _statistics(nano) -> bool:
    """Whether *nano* (a Nano, None, or a caller's bool) is nano-roughness given by PSD statistics."""
    return nano if isinstance(nano, bool) else nano is not None and nano.model is not None


def reads_by_half_vector(micro, nano) -> bool:
    """Whether a table of the two-scale lobe is read by the half-vector (:func:`half_vector_exit`): an anisotropic
    analytic micro NDF (``alpha_y`` given, not a slope table) with PSD statistics, whose lobe changes its shape with
    the light's azimuth as D(h) does.

    Parameters
    ----------
    micro : Micro
    nano : Nano, None or bool
        The nano-roughness, or (for a caller that knows only the request) whether it is given by PSD statistics.
    """
    return micro.alpha_y is not None and micro.ndf != "tabulated" and _statistics(nano)


def light_azimuth_nodes(micro, nano) -> int:
    """Light azimuth nodes over [0°, 360°) of the diffracted-lobe table of a two-scale surface: 1 where the lobe
    depends on the azimuths only through φ_o − φ_i (:func:`waveoptics.brdf.roughness_scales.isotropic`),
    :data:`PHI_NODES_ANISOTROPIC_NDF` where it is read by the half-vector (:func:`reads_by_half_vector`: between
    4 nodes that read was 9.7 % off at the 90th percentile, 20 % at most, at θ_i 30°), :data:`PHI_NODES_ANISOTROPIC`
    for the others (height fields, slope tables, gratings). The choice of
    :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` for ``n_phi=None`` and of :func:`waveoptics.simulate.sphere_nodes`.

    Parameters
    ----------
    micro : Micro
    nano : Nano, None or bool
        As :func:`reads_by_half_vector`. A bool True stands for PSD statistics or none, as
        :func:`~waveoptics.brdf.roughness_scales.isotropic` takes it: a request's σ = 0 (no nano lobe, a table of
        zeros at 4 azimuths) is not known before its nano-roughness is made, and is counted as statistics.
    """
    if isotropic(micro, nano):
        return 1
    return PHI_NODES_ANISOTROPIC_NDF if reads_by_half_vector(micro, nano) else PHI_NODES_ANISOTROPIC


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
