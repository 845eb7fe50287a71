"""Where the micro lobe's mirror direction falls on a direction grid, whether the lobe is narrower than a cell, and
which of its cells hold its light: the geometry the two-scale routes share.
"""
from __future__ import annotations

import numpy as np

from ..scatter.grid import DirectionGrid
from .roughness_scales import Micro

__all__ = ['mirror_direction', 'fresnel_at_mirror', 'mirror_cell', 'sharp_micro_lobe', 'azimuth_deg',
           'FACET_TAIL_SHARE', 'significant_cells']


def mirror_direction(wi):
    """The mirror direction of *wi* about the macro normal z."""
    return np.array([-wi[0], -wi[1], wi[2]])


def fresnel_at_mirror(F, wi, lam):
    """The Fresnel factor at the mirror direction (R(θ_i), or R_s / R_p for polarized light)."""
    if hasattr(F, "at"):
        return F.at(wi, mirror_direction(wi), lam)
    return F(wi[2], lam)


def mirror_cell(grid: DirectionGrid, wi):
    """(row, col) of the cell containing the mirror direction, or None if outside the grid."""
    u, v = -wi[0], -wi[1]
    j = int(np.floor((u - grid.u_range[0]) / grid.du))
    i = int(np.floor((v - grid.v_range[0]) / grid.dv))
    if 0 <= i < grid.n_v and 0 <= j < grid.n_u:
        return i, j
    return None


def sharp_micro_lobe(micro: Micro, grid: DirectionGrid) -> bool:
    """Whether the micro lobe is narrower than a grid cell (then it is a spike on this grid)."""
    a = micro.alpha if micro.alpha_y is None else min(micro.alpha, micro.alpha_y)
    return a < 0.75 * min(grid.du, grid.dv)


def azimuth_deg(wi) -> float:
    """Azimuth (degrees) of a direction: the plane of incidence a height field's coherent fraction is taken in."""
    return float(np.degrees(np.arctan2(wi[1], wi[0]))) if np.hypot(wi[0], wi[1]) > 0 else 0.0



#: a height field's facets that together hold less than this share of a micro lobe's light take the coherent
#: fraction of the macro incidence instead of their own (both halves alike, so the energy balance is kept): their
#: own would cost table nodes far from θ_i for a change in the coherent/diffracted split below this share
FACET_TAIL_SHARE = 1e-3


def significant_cells(weights) -> np.ndarray:
    """Mask of the largest cells of *weights* (≥ 0) that hold all but :data:`FACET_TAIL_SHARE` of their sum."""
    flat = np.ravel(weights)
    order = np.argsort(flat)[::-1]
    c = np.cumsum(flat[order])
    keep = np.zeros(flat.size, bool)
    if c.size and c[-1] > 0:
        keep[order[:int(np.searchsorted(c, (1.0 - FACET_TAIL_SHARE) * c[-1])) + 1]] = True
    return keep.reshape(np.shape(weights))

