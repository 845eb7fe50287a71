"""The grid of the facet-frame route's tables of PSD statistics (Lambert's azimuthal equal-area projection) and
the cores of nano lobes narrower than its cells: held as cell averages (:func:`narrow_core_cells`) and sampled no finer
than a cell (:func:`proposal_floor`).

References
----------
.. [1] J. P. Snyder, *Map Projections: A Working Manual*, USGS Prof. Paper 1395, 1987, §24.
.. [2] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (a BRDF carried by each facet).
"""
from __future__ import annotations

import numpy as np

from ..scatter.grid import DirectionGrid
from .nano_grid import CORE_CELLS, CORE_MAX_SUBSAMPLES, CORE_SUBSAMPLE_STEP, NARROW_CELLS

__all__ = ['RIM_RADIUS', 'FACET_TABLE_MAX_CELLS', 'facet_table_grid', 'equal_area', 'from_equal_area', 'v_symmetric',
           'cell_centres', 'narrow_table_lobe', 'NARROW_TABLE_FACTOR', 'narrow_core_cells', 'proposal_floor', 'FLOOR_CELLS']


def v_symmetric(grid: DirectionGrid) -> bool:
    """Whether the rows of *grid* are symmetric about v = 0 (row i and n_v − 1 − i at opposite v)."""
    return grid.n_v % 2 == 0 and np.isclose(grid.v_range[0], -grid.v_range[1])


def cell_centres(grid: DirectionGrid):
    """(u, v) of the cell centres of *grid*, (n_v, n_u) each."""
    u = grid.u_range[0] + (np.arange(grid.n_u) + 0.5) * grid.du
    v = grid.v_range[0] + (np.arange(grid.n_v) + 0.5) * grid.dv
    return np.meshgrid(u, v)


#: radius of the disc (of the equal-area projection, in direction cosines for a height field's tables) at which
#: :func:`_facet_table` evaluates the cells beyond its rim
RIM_RADIUS = 1.0 - 1e-6
#: the finest facet table of PSD statistics (cells per axis; 0.2° a cell)
FACET_TABLE_MAX_CELLS = 1024


def facet_table_grid(grid: DirectionGrid, length_scale_m: float | None = None,
                     wavelength_nm: float | None = None) -> DirectionGrid:
    """The grid of PSD statistics' facet tables for lobes on *grid* (a hemisphere): cells of Lambert's azimuthal
    equal-area projection (:func:`equal_area`), as many per axis as *grid* has over the disc (2 / du, even, at most
    :data:`FACET_TABLE_MAX_CELLS`): a cell spans 1.7-2.4° at any angle on 96², where direction cosines give a
    cell at θ an angle du / cos θ (1.2° at the pole, 5.7° at 78°, 11° at the rim on 96²), too coarse for the
    lobe's bend over the hand-over window (70-80°, :mod:`waveoptics.scatter.tangent_blend`) and its fall towards
    grazing exit. Read there bilinearly, the facet-frame sum was non-reciprocal by up to 3.5 % (Beckmann α 0.1,
    96²; 384² cells in direction cosines: 0.8 %); as many cells as the lobe grid, so the tables cost the same per
    incidence node.

    A nano lobe of length scale *length_scale_m* narrower than those cells at *wavelength_nm*
    (:func:`narrow_table_lobe`) gets :data:`NARROW_TABLE_FACTOR` times the cells per axis: its core is held as cell
    averages (:func:`narrow_core_cells`), which widen it by about a cell, and that blur moved light into the
    falling flank of a narrow micro lobe (ABC B 200 µm, C 3, 450 nm, Beckmann α 0.05, 30°, 128² lobes: 4.5-7.2 %
    too much 0.1-0.4 from the mirror against the pointwise facet-frame form on 128² tables, 1.2-1.5 % on 256²).
    """
    n = 2 * int(np.ceil(1.0 / max(grid.du, grid.dv)))
    tables = DirectionGrid.hemisphere(min(max(n, 16), FACET_TABLE_MAX_CELLS))
    if length_scale_m is None or not narrow_table_lobe(length_scale_m, wavelength_nm, tables):
        return tables
    return DirectionGrid.hemisphere(min(NARROW_TABLE_FACTOR * max(n, 16), FACET_TABLE_MAX_CELLS))


#: the factor on the cells per axis of the tables of a nano lobe narrower than their cells (:func:`facet_table_grid`)
NARROW_TABLE_FACTOR = 2


def equal_area(u, v, z):
    """(x, y) of directions (u, v, z) in Lambert's azimuthal equal-area projection about the normal, scaled so that
    the horizon is the unit circle: (u, v) / √(1 + z), radius √(1 − cos θ) = √2 sin(θ/2). A cell spans an angle
    between dx/0.71 at the pole and dx/0.5 at the horizon (1.7° and 2.4° on 96² cells), nearly uniform, where
    direction cosines give du / cos θ; one square root a point.

    References
    ----------
    .. [1] J. P. Snyder, *Map Projections: A Working Manual*, USGS Prof. Paper 1395, 1987, §24 (Lambert azimuthal
       equal-area projection).
    """
    k = 1.0 / np.sqrt(1.0 + np.maximum(z, 0.0))
    return u * k, v * k


def from_equal_area(x, y):
    """Unit directions (..., 3) at the points (x, y) of :func:`equal_area`; points beyond its rim are taken at
    radius :data:`RIM_RADIUS` on their azimuth."""
    r = np.hypot(x, y)
    s = np.where(r > RIM_RADIUS, RIM_RADIUS / np.where(r > 0, r, 1.0), 1.0)
    x, y = x * s, y * s
    z = 1.0 - (x * x + y * y)
    k = np.sqrt(1.0 + z)
    return np.stack([x * k, y * k, z], axis=-1)


def narrow_table_lobe(length_scale_m: float, wavelength_nm: float, grid: DirectionGrid) -> bool:
    """Whether a nano lobe of width λ/(π ℓ) (direction cosines) is narrower than :data:`NARROW_CELLS` cells of the
    table *grid* (the lobe grid's rule, :func:`waveoptics.brdf.nano_lobe`; a cell of the equal-area tables spans 1 to
    √2 its width in direction cosines, :func:`equal_area`)."""
    return wavelength_nm * 1e-9 / (np.pi * length_scale_m) < NARROW_CELLS * max(grid.du, grid.dv)


def narrow_core_cells(values, wi, grid: DirectionGrid, width: float):
    """The cells of a table (equal-area *grid*) about the mirror direction of *wi* that hold a narrow lobe's core,
    and the lobe's average over each: (rows, cols, average (n_cells, k)). *values* (wo (n, 3)) → (n, k) evaluates
    the lobe's table quantities at directions; *width* is the lobe's width in direction cosines.

    Cells whose centre lies within :data:`CORE_CELLS` cells of the mirror direction are averaged over n × n
    midpoints of their (equal-area, so equal solid angle) square, n set by :data:`CORE_SUBSAMPLE_STEP` of
    max(*width* / √2, the cell's distance from the mirror) as :func:`waveoptics.brdf.nano_lobe`
    does on the lobe grid; a point sample at the cell centre would hold a core narrower than the cell 0 or many
    times over. Midpoints beyond the rim take the rim direction (:func:`from_equal_area`), as the table's rim cells.

    References
    ----------
    .. [1] J. P. Snyder, 1987, §24 (the projection is equal-area: a cell's mean over its square is its mean over
       its solid angle).
    """
    mx, my = equal_area(-wi[0], -wi[1], wi[2])
    x, y = cell_centres(grid)
    cell = max(grid.du, grid.dv)
    rows, cols = np.nonzero(np.hypot(x - mx, y - my) <= CORE_CELLS * cell)
    pts, owner, count = [], [], np.zeros(rows.size)
    for k, (i, j) in enumerate(zip(rows, cols)):
        near = np.hypot(max(abs(x[i, j] - mx) - grid.du / 2, 0.0), max(abs(y[i, j] - my) - grid.dv / 2, 0.0))
        n = int(np.clip(np.ceil(cell / (CORE_SUBSAMPLE_STEP * max(width / np.sqrt(2.0), near))), 2,
                        CORE_MAX_SUBSAMPLES))
        t = (np.arange(n) + 0.5) / n - 0.5
        sx, sy = np.meshgrid(x[i, j] + t * grid.du, y[i, j] + t * grid.dv)
        pts.append(np.stack([sx.ravel(), sy.ravel()], axis=-1))
        owner.append(np.full(n * n, k))
        count[k] = n * n
    if rows.size == 0:
        return rows, cols, np.zeros((0, 0))
    xy = np.concatenate(pts)
    f = np.asarray(values(from_equal_area(xy[:, 0], xy[:, 1])))
    own = np.concatenate(owner)
    avg = np.stack([np.bincount(own, weights=f[:, c], minlength=rows.size) for c in range(f.shape[1])], axis=-1)
    return rows, cols, avg / count[:, None]


#: the half-vector proposal of a lobe narrower than the table's cells spreads its core uniformly over a disc whose
#: radius is this many table cells (direction cosines, at the largest scale of a cell: √2 its equal-area width)
FLOOR_CELLS = 1.0


def proposal_floor(length_scale_m: float, wavelength_nm: float, grid: DirectionGrid) -> float:
    """The radius (direction cosines) below which :class:`waveoptics.brdf.facet.NanoRadial` spreads the nano lobe's
    mass uniformly when its tables on *grid* hold the core as cell averages (:func:`narrow_table_lobe`), else 0:
    :data:`FLOOR_CELLS` cells at √2 their equal-area width. Normals drawn inside the true core would read its cell
    average at the true core's density (its light times core area / cell area)."""
    if not narrow_table_lobe(length_scale_m, wavelength_nm, grid):
        return 0.0
    return FLOOR_CELLS * np.sqrt(2.0) * max(grid.du, grid.dv)
