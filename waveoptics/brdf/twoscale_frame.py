"""The facet-frame route: Walter's integral over facet normals of the nano lobe in each facet's own frame, read from
tables over local incidence (:func:`facet_frame_diffraction`), and the choice between it and the paraxial route
(:func:`facet_route`).

References
----------
.. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (a BRDF carried by each facet).
.. [2] E. Veach, PhD thesis, Stanford 1997, §9.2 (balance heuristic).
"""
from __future__ import annotations

import numpy as np

from .. import scatter
from ..errors import unknown
from ..materials import cos2_eta_i, facet_sp_mix
from ..runtime import parallel_map
from ..scatter.grid import DirectionGrid
from ..scatter.tangent_blend import first_order_over_fresnel, tangent_plane_weight, uses_vector_first_order
from .facet import (FACET_NODE_SPLIT, FACET_REFERENCE_NM, bridge_nodes, bridge_point, half_vector_nodes, ndf_nodes,
                    wide_micro_lobe, with_bridge_density)
from .facet_frame_cl import facet_frame_backend, facet_frame_sum_cl
from .facet_energy import facet_budget
from .facet_field_tables import (FACET_NODES_ANISOTROPIC_FIELD, anisotropic_field, anisotropic_field_read,
                                 anisotropic_field_stack, cell_shifted_nodes, field_facet_table)
from .field_lobe import field_anisotropy, field_proposal_model
from .nano_grid import NARROW_CELLS
from .roughness_scales import Micro, Nano, check_series
from .facet_tables import (FACET_TABLE_MAX_CELLS, RIM_RADIUS, cell_centres, equal_area, facet_table_grid,
                           from_equal_area, narrow_core_cells, narrow_table_lobe, proposal_floor, v_symmetric)
from .twoscale_grid import sharp_micro_lobe

__all__ = ['FACET_THETAS_DEG', 'FACET_THETAS_PSD_DEG', 'facet_thetas', 'FACET_NODES_NARROW', 'FACET_NODES_WIDE', 'FACET_NODES_FIELD', 'FACET_NODE_SPLIT', 'FACET_REFERENCE_NM',
           'FACET_GRAZING_DEG', 'grazing_cells', 'FACET_ROUTES', 'facet_route', 'paraxial_reason', 'nano_statistics', 'facet_nodes', 'RIM_RADIUS', 'facet_frame_diffraction',
           'FACET_TABLE_MAX_CELLS', 'facet_table_grid', 'equal_area', 'from_equal_area']


#: local incidences θ' (degrees) at which the facet-frame route tabulates a height field's nano lobe on the direction grid: the
#: nano lobe of a facet at any incidence is read between the two nodes around it, relative to the mirror direction.
#: The nodes reach 89.9°: every rough surface's scatter falls to 0 at grazing incidence (first-order TIS of
#: Al|Al2O3:300nm, ABC σ 15 nm, 560 nm: 0.0206 at 88°, 0.0152 at 89°, 0.0094 at 89.5°, 0.0022 at 89.9°), and
#: with 88° the last node the facets beyond it carried the 88° lobe: at θ_i = 89° (GGX α = 0.05, 32² cells) the
#: diffracted part came out 4 % above the light the facets scatter (Al: 1.3 %), 0.3 % with these nodes
FACET_THETAS_DEG = np.array([0.0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 78, 81, 84, 86, 88,
                             89, 89.5, 89.9])
#: local incidences θ' (degrees) of the facet tables of PSD statistics: 2° apart, about as fine as the tables' exit
#: angles (:func:`facet_table_grid`, 1.9° a cell on 96² lobes). With :data:`FACET_THETAS_DEG` (5° apart to 75°) the
#: facet-frame sum's f(i,o)/f(o,i) − 1 was up to 3.7 % (Beckmann α 0.05-0.3, 96²), 2° apart from 40° ≤ 0.84 %. Below
#: 40° too since the first-order tables hold q = g / cos²θ_o (:func:`_facet_table`): the turned reads at the two
#: nodes around a facet's θ' see its exit up to half a spacing higher and lower, where q bends (Q/F of a metal
#: towards its pseudo-Brewster angle): 5° apart, θ' 7-12° → 77-82° in the plane read 3.5-5.4 % high (Al, 550 nm),
#: 2° ≤ 1.7 %; tabulated max f(i,o)/f(o,i) − 1 (tests/test_tabulated_rim.py, Beckmann α 0.05 / 0.1) 3.5 / 2.6 %
#: against 1.8 / 1.3 %. 48 tables, not 36: 27 % more CPU time to build (128², 25 wavelengths, under load)
FACET_THETAS_PSD_DEG = np.array([*range(0, 89, 2), 89, 89.5, 89.9], dtype=float)
#: facet normals of the grid route's quadrature (:func:`facet_nodes`): (D(m) cos θ_m normals turned to each
#: cell's half-vector azimuth; drawn about each cell's half-vector through the nano lobe's radial law), for a micro
#: lobe narrower than :data:`FACET_NODE_SPLIT` nano lobe widths, and for a wider one. Measured per cell (with the
#: earlier NDF normals fixed in the surface's frame; :func:`.facet.ndf_nodes` gives the present rule's error) against the
#: pointwise form (ABC σ = 10 nm, B = 2 µm, C = 2.6, 550 nm, Beckmann, 96²-128² grids): α = 0.05 at 30° with
#: (64, 16) ≤ 2.7 % (32 + 16: 4.8 %). Wide lobes towards grazing incidence need more: Beckmann α = 0.3 on 96²,
#: every cell with θ_o ≤ 85° against 2048 + 2048 normals, max / rms error at θ_i = 30 / 60 / 77 / 80°: (64, 64)
#: 9.7 / 7.7 / 15.4 / 14.4 %, rms 1.5-3.7 % (the lobe 3-5 % below a Monte-Carlo facet-frame integral at θ_i
#: 74-80°); (128, 256) 1.4 / 2.2 / 2.9 / 2.8 %, rms 0.2-0.6 %; (256, 128) 1.0 / 2.2 / 3.2 / 3.5 %; (256, 64)
#: 2.6 / 3.1 / 5.1 / 5.3 %; (128, 128) 2.0 / 3.8 / 6.2 / 6.1 %; at 60 / 77 / 80° only: (64, 256) 3.4 / 5.9 / 6.9 %,
#: (256, 256) 1.8 / 1.8 / 1.5 % (the NDF normals, drawn with D(m) cos θ_m whatever the light, limit it at grazing
#: incidence, where many face away from it). Cost per incidence (96² and 128², 3 wavelengths, OpenCL on PoCL's
#: CPU device, under load): (128, 256) 2.7-2.8x (64, 64)
FACET_NODES_NARROW, FACET_NODES_WIDE = (64, 16), (128, 256)
#: cells where the light or the exit is this far from the normal or further (degrees) take twice the narrow lobes'
#: NDF normals (:data:`FACET_NODES_NARROW`, analytic NDFs, :func:`grazing_cells`): there the integrand reaches
#: facets tilted 60-70°, deep in the NDF's tail. GGX α 0.05 / 0.1, ABC σ 10 nm, B 2 µm, C 2.6, Al, 550 nm, θ_i 80°,
#: exits 30-85° at φ_o 0-180° above 1e-3 of the peak, against a Monte-Carlo facet-frame integral
#: (tests/twoscale_reference.py): 64 normals max 5.1 / 9.0 % (one pair of 30 beyond 3 % + 3 s.e. each), 128: 2.7 /
#: 2.4 % (none); at θ_i 85° (exits to 89°) 25 / 18 %, 256: 6.8 / 2.8 %. By max(θ_i, θ_o): reciprocal. Cost on 64²,
#: 25 wavelengths: 0.12 → 0.19 s per incidence from 70°. Wide lobes' 128 normals hold GGX α 0.3 / 0.5 at 80° within
#: 2.9 / 4.7 % (none flagged; 256: 2.3 / 4.0 %); a slope table's histogram has no tail beyond its largest slope
FACET_GRAZING_DEG = 70.0
#: the grid route's (NDF normals, half-vector normals per cell) for a height field: its lobe is speckle (a
#: windowed patch's |U|² varies on the scale λ/(2L)), which one shared stencil of 64 half-vector normals per cell
#: reads with a bias: the diffracted albedo came out 1.7-7.6 % above the light the facets scatter (Gaussian patch
#: σ 15 nm, T 1 µm, 32 λ, Beckmann α 0.1-0.3, θ_i 30-75°, 96² cells), with 128 within -0.6 to +2.6 % (256: the same)
FACET_NODES_FIELD = (64, 128)
#: evaluate's facet integration: ``frame`` (Walter's integral, each facet's nano lobe in its own frame),
#: ``paraxial`` (the nano lobe at the macro incidence shifted to every facet's mirror direction: an FFT
#: convolution), ``auto`` (frame where :func:`facet_route` allows it)
FACET_ROUTES = ("auto", "frame", "paraxial")


def facet_route(micro: Micro, nano: Nano | None, grid: DirectionGrid, wavelengths_nm, facet: str = "auto") -> str:
    """``frame`` or ``paraxial``: how :func:`waveoptics.brdf.evaluate` carries the nano lobe by the facets.

    ``auto`` takes ``frame`` for PSD statistics (a lobe narrower than the table cells held as their averages on
    finer tables: :func:`facet_table_grid`) and for a statistically isotropic height field
    (:func:`waveoptics.brdf.field_anisotropy`) whose nano lobe (width λ_min/(π ℓ), ℓ the correlation length of the
    field, :func:`nano_statistics`) is wider than :data:`waveoptics.brdf.NARROW_CELLS` grid cells; else ``paraxial``
    (:func:`paraxial_reason` says why): an anisotropic height field (its facet tables run over the azimuth of
    incidence too, :func:`waveoptics.brdf.anisotropic_field_stack`, and its lobe's few narrow peaks take 4x the
    normals: ~5x the isotropic field's time, ~40x the shift's, 128² cells, 3 wavelengths; asked by name, ``frame``
    takes them); a micro lobe narrower than a cell (its facets tilt by less than a cell, where the shift and the
    turn of their lobes agree); a height field's nano lobe the grid cannot resolve.

    For narrow PSD lobes the paraxial shift, the route before, lost or gained the light of grazing light's tail
    (ABC B 200 µm, C 3, 450 nm, 128²: 1.27-1.51x the pointwise facet-frame form 0.1-3 from the mirror at θ_i 80°,
    α 0.05, while it carried the tangent-plane shape; with the blended lobe it carries now still 1.03-1.78x at 85°,
    α 0.1); the frame route holds it within 1.5 % there and within 2.8 % at 0-70° (docs/two-scale.md, "Narrow
    nano lobes").
    """
    if facet not in FACET_ROUTES:
        raise unknown("facet", facet, FACET_ROUTES)
    if nano is None:
        return "paraxial"
    if facet in ("paraxial", "frame"):
        return facet
    return "paraxial" if paraxial_reason(micro, nano, grid, wavelengths_nm) else "frame"


def paraxial_reason(micro: Micro, nano: Nano, grid: DirectionGrid, wavelengths_nm) -> str | None:
    """Why ``facet="auto"`` carries *nano* paraxially (a sentence), or None where :func:`facet_route` takes the
    frame route."""
    if anisotropic_field(nano):
        return (field_anisotropy(nano.surface) + ": its facet tables over the azimuth of incidence cost ~5x an "
                "isotropic field's (facet 'frame' takes them)")
    if sharp_micro_lobe(micro, grid):
        return "the micro lobe is narrower than a grid cell"
    # PSD statistics' tables hold a narrow core as cell averages on finer cells (facet_table_grid); a height
    # field's tables and proposal are not measured there
    wn = float(np.min(wavelengths_nm)) * 1e-9 / (np.pi * nano_statistics(nano).length_scale)
    if nano.surface is not None and wn < NARROW_CELLS * max(grid.du, grid.dv):
        return "the height field's nano lobe is narrower than the grid resolves"
    return None


def nano_statistics(nano: Nano):
    """The PSD model that sizes *nano*'s lobe for the quadrature: its statistics, or for a height field a Gaussian
    model of its rms height and correlation length (:func:`waveoptics.brdf.field_proposal_model`, cached)."""
    if nano.model is not None:
        return nano.model
    cache = nano.__dict__.setdefault("_cache", {})
    if "proposal-model" not in cache:
        cache["proposal-model"] = field_proposal_model(nano.surface)
    return cache["proposal-model"]


def facet_nodes(micro: Micro, nano: Nano, wavelengths_nm) -> tuple[int, int]:
    """(NDF normals, half-vector normals per cell) of the grid route's quadrature: :data:`FACET_NODES_NARROW` when
    the micro lobe's mirror directions spread over less than :data:`FACET_NODE_SPLIT` nano lobe widths (2α < 0.5
    λ/(π ℓ) at λ = :data:`FACET_REFERENCE_NM`), where the NDF's normals carry the integral, else
    :data:`FACET_NODES_WIDE` (*wavelengths_nm* is not used: every wavelength gets the same nodes); for a height field
    :data:`FACET_NODES_FIELD`, an anisotropic one :data:`waveoptics.brdf.FACET_NODES_ANISOTROPIC_FIELD`."""
    if nano.surface is not None:
        return FACET_NODES_ANISOTROPIC_FIELD if anisotropic_field(nano) else FACET_NODES_FIELD
    kw = micro.kw()
    a = max(kw["alpha"], kw["alpha_y"] or 0.0)
    return FACET_NODES_WIDE if wide_micro_lobe(a, nano_statistics(nano).length_scale) else FACET_NODES_NARROW


def grazing_cells(wi, wo) -> np.ndarray:
    """Cells (n_cells,) bool of exits *wo* (n_cells, 3) that, with the light *wi* (3,), take twice the NDF normals
    in :func:`facet_frame_diffraction`: max(θ_i, θ_o) ≥ :data:`FACET_GRAZING_DEG` (symmetric in ω_i and ω_o)."""
    return np.minimum(wi[2], wo[:, 2]) < np.cos(np.radians(FACET_GRAZING_DEG))


def _facet_table(nano: Nano, k: int, w, grid: DirectionGrid, dm, material, polarization):
    """g = f_nano cos θ_o of the nano lobe at local incidence :func:`facet_thetas` [k] (azimuth 0) at the cell
    centres of *grid*, (n_v, n_u, n_λ) float32, for PSD statistics in Lambert's azimuthal equal-area projection
    (:func:`equal_area`; a height field's in direction cosines): F = 1 for the Kirchhoff family (its F(θ_d) is frame-independent
    and applied afterwards), the Rayleigh-Rice lobe with its own factor Q of *material* and *polarization* (for s or
    p light Q of the facet's own s or p light: :func:`facet_frame_diffraction` mixes the s and p tables of each
    facet by cos²η_i, sin²η_i, its rotation of the macro basis).

    g is finite up to the horizon (f grows like 1/cos θ_o there); cells beyond the rim of the disc hold g of the
    rim direction on their radius, so that bilinear reads within a cell of the rim are not pulled towards 0.

    A first-order lobe f_RR ∝ cos θ_i cos θ_o Q S (Church et al. 1979) gives g ∝ cos²θ_o ≈ 4 (1 − r)² towards the
    rim r = 1 of the projection: read bilinearly it came out 3-14x the exact g at θ_o' 88-90°, 5-9 % high at 84-86°,
    and the facet-frame sum 4-7 % above a Monte-Carlo reference at θ_i 74-80° → 80-85° forward (Beckmann α 0.3,
    96²). So PSD statistics' tables hold first-order lobes as q = f_RR / cos θ_o = g / cos²θ_o (finite at the
    horizon) and :func:`_facet_read` multiplies q by the facet's exact cos²θ_o' (a height field's tables hold g).

    Returns (g, first): for the Kirchhoff family of PSD statistics g holds the tangent-plane lobe f_K cos θ_o and
    first the first-order lobe's q = f_RR / (F cos θ_o), both smooth across the hand-over window of
    :mod:`waveoptics.scatter.tangent_blend`, and the blended lobe is W g + (1 − W) first with W = w(θ_i') w(θ_o') taken
    at the facet's exact local directions (:func:`_facet_read`); baked into one table, W (which falls from 1 to 0
    over 70-80°, two 96² cells in u at the horizon) was read bilinearly at the exit and linearly between incidence
    nodes, a different rule for ω_i and ω_o: the facet-frame sum came out non-reciprocal by up to 5 % (Beckmann
    α 0.1, pairs with an end at 75-80°). So for a height field's Kirchhoff lobe, whose first-order lobe is that of
    its periodogram (:func:`_field_table`). Under Rayleigh-Rice g is the lobe (for PSD statistics its q) and
    first None. Cached on *nano*.

    References
    ----------
    .. [1] E. L. Church, H. A. Jenkinson, J. M. Zavada, Opt. Eng. 18(2), 125-136, 1979 (f_RR = (16π²/λ⁴) cos θ_i
       cos θ_o Q S).
    """
    cache = nano.__dict__.setdefault("_cache", {})
    key = ("facet-table", k, tuple(float(x) for x in w), grid.n_u, grid.n_v, tuple(grid.u_range),
           tuple(grid.v_range), dm.name, getattr(material, "name", None), polarization)
    if key not in cache and nano.surface is not None:
        cache[key] = _field_table(nano, k, w, grid, dm, material, polarization)
    if key not in cache:
        th = np.radians(FACET_THETAS_PSD_DEG[k])
        wi = np.array([np.sin(th), 0.0, np.cos(th)])
        x, y = cell_centres(grid)
        # the lobe of an isotropic PSD is even in v: rows from the middle up, mirrored onto the rows below; cells
        # further than 3 cells beyond the rim are never read (a read lies inside the disc) and hold 0
        half = slice(grid.n_v // 2 - 1, grid.n_v) if v_symmetric(grid) else slice(0, grid.n_v)
        sel = np.zeros(x.shape, bool)
        sel[half] = np.hypot(x[half], y[half]) < 1.0 + 3.0 * max(grid.du, grid.dv)
        wo = from_equal_area(x[sel], y[sel])
        out = np.zeros((grid.n_v, grid.n_u, len(w)), dtype=np.float32)
        first = None if dm.perturbative else np.zeros_like(out)
        for i, lam in enumerate(w):
            if not dm.perturbative:
                check_series(nano.model, lam)
            out[sel, i], q = _table_values(nano, wi, wo, lam, dm, material, polarization)
            if first is not None:
                first[sel, i] = q
        for a in (out, first):
            if half.start > 0 and a is not None:
                a[:half.start] = a[grid.n_v - 1:grid.n_v - 1 - half.start:-1]
        for i, lam in enumerate(w):   # a core narrower than a cell: its cells hold their averages
            if narrow_table_lobe(nano.model.length_scale, lam, grid):
                r, c, avg = narrow_core_cells(lambda d: np.stack([x for x in _table_values(
                    nano, wi, d, lam, dm, material, polarization) if x is not None], -1), wi, grid,
                    lam * 1e-9 / (np.pi * nano.model.length_scale))
                out[r, c, i] = avg[:, 0]
                if first is not None:
                    first[r, c, i] = avg[:, 1]
        cache[key] = (out, first)
    return cache[key]


def _table_values(nano: Nano, wi, wo, lam, dm, material, polarization):
    """(g, first) of :func:`_facet_table` for PSD statistics at directions *wo* (n, 3): first-order q = f_RR / cos θ_o
    (first None) under Rayleigh-Rice; else g = f_K cos θ_o (F = 1) and q = f_RR / (F cos θ_o) (its docstring)."""
    if dm.perturbative:   # first order: q = f_RR / cos θ_o, read times the facet's cos²θ_o'
        return scatter.rayleigh_rice_lobe(wi, wo, lam, nano.model, material, polarization) / wo[:, 2], None
    f = scatter.scattered_lobe(wi, wo, lam, nano.model, F=1.0, diffraction=dm)
    # beyond the tangent plane's validity the lobe hands over to first order, reciprocal (W f_K + (1 − W) f_RR / F,
    # F applied afterwards: waveoptics.scatter.tangent_blend; docs/physics.md §9): f_K and f_RR / F held apart,
    # W applied at each facet's exact local directions
    Fl = ((lambda a, b, lam=lam: material.F_facet(a, b, lam, polarization))
          if uses_vector_first_order(material) else None)
    rr = first_order_over_fresnel(np.broadcast_to(wi, wo.shape), wo, lam, nano.model, material, polarization, Fl)
    return f * wo[:, 2], rr / wo[:, 2]


def _field_table(nano: Nano, k: int, w, grid: DirectionGrid, dm, material, polarization):
    """:func:`_facet_table` of a height field, (g, first): :func:`waveoptics.brdf.field_facet_table` at local
    incidence :data:`FACET_THETAS_DEG` [k] at azimuth 0."""
    th = np.radians(FACET_THETAS_DEG[k])
    return field_facet_table(nano, np.array([np.sin(th), 0.0, np.cos(th)]), w, grid, dm, material, polarization)



def _facet_stack(nano: Nano, w, grid: DirectionGrid, dm, material, polarization):
    """:func:`_facet_table` at every :func:`facet_thetas` node, stacked: (g, first), each (n_θ, n_v, n_u,
    n_λ), first None where the tables hold no hand-over; cached."""
    cache = nano.__dict__.setdefault("_cache", {})
    key = ("facet-stack", tuple(float(x) for x in w), grid.n_u, grid.n_v, tuple(grid.u_range), tuple(grid.v_range),
           dm.name, getattr(material, "name", None), polarization)
    if key not in cache:
        if nano.model is not None and not dm.perturbative:   # the series of every wavelength, built in parallel
            scatter.band_series_built(nano.model, w)
        # the incidence nodes in parallel threads (each ~0.3 s CPU on 128² cells and 25 wavelengths)
        parts = parallel_map(lambda k: _facet_table(nano, k, w, grid, dm, material, polarization),
                             range(facet_thetas(nano).size))
        cache[key] = (np.stack([p[0] for p in parts]),
                      None if parts[0][1] is None else np.stack([p[1] for p in parts]))
    return cache[key]


def facet_thetas(nano: Nano) -> np.ndarray:
    """The local incidences (degrees) of *nano*'s facet tables: :data:`FACET_THETAS_PSD_DEG` for PSD statistics,
    :data:`FACET_THETAS_DEG` for a height field (each node one solve of the field)."""
    return FACET_THETAS_DEG if nano.surface is not None else FACET_THETAS_PSD_DEG


def _facet_read(stack, grid: DirectionGrid, theta, lo, blend=False, projected=False, thetas_deg=FACET_THETAS_DEG):
    """The tabulated g = f_nano cos θ_o (n, n_λ) at local incidences *theta* (rad, (n,) or scalar) and local
    directions *lo* (n, 3) whose incidence lies in the local x–z plane: the two nodes θ_k around θ, each read at
    *lo* turned about the local y axis by θ − θ_k (which takes θ's mirror direction to θ_k's; the lobe of a tilted
    facet is a turned lobe), blended linearly in θ; a node whose turned direction falls below its horizon drops
    out of the blend. With *blend* the last axis of *stack* holds :func:`_facet_table`'s g and first (2 n_λ, read
    with the same stencil) and the result is W g + (1 − W) first, W = w(θ) w(θ_o) of
    :mod:`waveoptics.scatter.tangent_blend` at the exact local angles: the
    same for the facet's incidence and exit swapped (reciprocal). *projected*: the tables are PSD statistics' on
    the equal-area projection (:func:`facet_table_grid`), not in direction cosines, and their first-order lobes
    (first; a Rayleigh-Rice stack) hold q = g / cos²θ_o, multiplied here by cos²θ_o' of *lo* (:func:`_facet_table`);
    *thetas_deg* the tables' incidences (:func:`facet_thetas`)."""
    nodes = np.radians(thetas_deg)
    theta = np.asarray(theta, dtype=float)   # one incidence (an NDF node shared by all cells) stays a scalar
    if theta.ndim:
        theta = np.broadcast_to(theta, lo.shape[:1])
    f = np.interp(theta, nodes, np.arange(nodes.size))
    a = np.minimum(np.floor(f).astype(int), nodes.size - 1)
    b = np.minimum(a + 1, nodes.size - 1)
    wb = f - a
    n_v, n_u = stack.shape[1:3]
    flat = stack.reshape(-1, stack.shape[-1])
    n_lam = stack.shape[-1] // 2 if blend else stack.shape[-1]
    idx, wts = [], []
    den = np.zeros(lo.shape[0])
    for k, wk in ((a, 1.0 - wb), (b, wb)):
        beta = theta - nodes[k]
        cb, sb = np.cos(beta), np.sin(beta)
        u = lo[:, 0] * cb + lo[:, 2] * sb
        z = -lo[:, 0] * sb + lo[:, 2] * cb
        k0, j0, av, au, ok = grid.bilinear(*(equal_area(u, lo[:, 1], z) if projected else (u, lo[:, 1])))
        wk = np.where(ok & (z > 0), wk, 0.0)
        i00 = (k * n_v + k0) * n_u + j0
        idx += [i00, i00 + 1, i00 + n_u, i00 + n_u + 1]
        wts += [wk * (1 - av) * (1 - au), wk * (1 - av) * au, wk * av * (1 - au), wk * av * au]
        den += wk
    # np.take gathers whole rows (n_λ values) ~3x faster than fancy indexing, the same values
    rows = np.take(flat, np.stack(idx, axis=1), axis=0)
    val = np.einsum("cj,cjl->cl", np.stack(wts, axis=1).astype(np.float32), rows)
    c2 = lo[:, 2:3] ** 2 if projected else 1.0   # PSD statistics' first-order tables hold q = g / cos²θ_o
    if blend:
        W = np.reshape(tangent_plane_weight(np.cos(theta)) * tangent_plane_weight(lo[:, 2]), (-1, 1))
        val = W * val[:, :n_lam] + (1.0 - W) * c2 * val[:, n_lam:]
    else:   # projected: a Rayleigh-Rice table (the Kirchhoff family's come with their first-order part)
        val = c2 * val
    return np.where(den[:, None] > 0, val / np.where(den > 0, den, 1.0)[:, None], 0.0)


def _facet_reader(wi, wo, m, cos_i, cos_o, tgrid: DirectionGrid, projected: bool, thetas_deg, anisotropic: bool):
    """read(stack, blend) → g (n, n_λ) of the facets *m* ((3,) or (n, 3)) for the light *wi* and the exits *wo*
    (n, 3) (:func:`facet_frame_diffraction`), *cos_i* = ω_i·m, *cos_o* = ω_o·m: an anisotropic field's tables in
    its axes on each facet (:func:`waveoptics.brdf.anisotropic_field_read`), else :func:`_facet_read` of the
    local directions turned so that ω_i^m lies in the x–z plane."""
    from .facet import facet_basis

    if anisotropic:
        return lambda stack, blend: anisotropic_field_read(stack, tgrid, wi, wo, m, blend)
    t, b = facet_basis(m)
    lx, ly = np.sum(t * wi, axis=-1), np.sum(b * wi, axis=-1)
    r = np.hypot(lx, ly)
    cp, sp = np.where(r > 0, lx / np.where(r > 0, r, 1), 1.0), np.where(r > 0, ly / np.where(r > 0, r, 1), 0.0)
    ux, uy = np.sum(wo * t, axis=-1), np.sum(wo * b, axis=-1)   # turned so that ω_i^m lies in x–z
    lo = np.stack([cp * ux + sp * uy, -sp * ux + cp * uy, cos_o], axis=-1)
    theta = np.arccos(np.clip(cos_i, 0.0, 1.0))
    return lambda stack, blend: _facet_read(stack, tgrid, theta, lo, blend, projected, thetas_deg)


def _extra_nodes(symmetric: bool, nodes, wi, wo, h, cos_d, rad, level, na: int, nb: int, **ndf):
    """PSD statistics' extra normals in :func:`facet_frame_diffraction`: the cells that graze (2 N_a NDF normals,
    :func:`grazing_cells`, with the default narrow-lobe nodes of an analytic NDF only: :data:`FACET_GRAZING_DEG`),
    N_a per cell, and each cell's (bridge point, widths, β) (:func:`.facet.bridge_point`: a lobe's deep tail); a
    height field's (its nodes' layout is not symmetric): none."""
    doubles = symmetric and nodes is None and (na, nb) == FACET_NODES_NARROW and ndf.get("ndf") != "tabulated"
    graze = grazing_cells(wi, wo) & doubles
    bridge = (bridge_point(h, cos_d, rad, level, (na, nb), **ndf) if symmetric
              else (h, np.zeros((h.shape[0], 2)), np.zeros(h.shape[0])))
    return graze, np.where(graze, 2 * na, na), bridge


def _tables_and_proposal(nano: Nano, w, grid: DirectionGrid, dm, nb: int):
    """(the facet tables' grid, the half-vector nodes' radial law) of :func:`facet_frame_diffraction` for lobes on
    *grid*: PSD statistics' equal-area tables (:func:`facet_table_grid`) and a proposal no finer than they hold a
    core (:func:`proposal_floor`); a height field's tables on *grid* itself."""
    from .facet import NanoRadial

    if nano.surface is not None:
        return grid, NanoRadial(nano_statistics(nano), FACET_REFERENCE_NM, dm, nb)
    ell, lam = nano.model.length_scale, float(np.min(w))
    tgrid = facet_table_grid(grid, ell, lam)
    return tgrid, NanoRadial(nano.model, FACET_REFERENCE_NM, dm, nb, proposal_floor(ell, lam, tgrid))


def facet_frame_diffraction(wi, wavelengths_nm, material, micro: Micro, nano: Nano, grid: DirectionGrid, F, *,
                            diffraction="kirchhoff", polarization: str = "unpolarized",
                            table_grid: DirectionGrid | None = None, nodes: tuple[int, int] | None = None,
                            backend: str = "auto", device=None, precision: str = "float32"):
    """The diffracted part on *grid*: Walter's integral over facet normals m of the nano lobe in each facet's
    frame (docs/physics.md §7),

        f_diff(ω_i, ω_o) = ∫ |ω_i·m| |ω_o·m| / (|ω_i·n| |ω_o·n|) f_nano(ω_i^m, ω_o^m) G(ω_i, ω_o, m) D(m) dm,

    by the balance heuristic of two fixed node sets: N_a normals with density D(m) cos θ_m (:func:`.facet.ndf_nodes`) and
    N_b normals about the half-vector drawn through the nano lobe's radial law (:func:`.facet.half_vector_nodes`; they
    hold a heavy-tailed NDF's far facets and a nano lobe narrower than the micro lobe); (N_a, N_b) = *nodes* or
    :func:`facet_nodes`, whose N_a doubles for PSD statistics in the cells where the pair grazes
    (:func:`grazing_cells`); for PSD statistics, in a lobe's deep tail where the integrand peaks between both sets'
    normals, a third: :data:`.facet.BRIDGE_NODES` Gaussian normals about that point, counted β times
    (:func:`.facet.bridge_point`, :func:`.facet.bridge_nodes`). Both sets are laid out per cell about its
    half-vector h, in a frame that turns with h
    about z: they are the same for ω_i and ω_o swapped and for the pair turned about the normal, so the discrete
    sum is reciprocal up to the tables' reads (the integrand is), and a table over incidence at azimuth 0 read
    turned (:class:`waveoptics.brdf.TabulatedTwoScaleBRDF`) keeps it: measured f(ω_i, ω_o)/f(ω_o, ω_i) − 1 ≤ 0.5 %
    at θ ≤ 65° (α 0.05-0.1; normals fixed in the surface's frame: up to 5.6 %), for 6-13 % more CPU time per
    incidence (96² cells). Each facet's nano lobe is read from tables
    over local incidence (:func:`facet_thetas`, :func:`_facet_read`) on *table_grid* (default *grid*, a
    hemisphere); F(θ_d), the same in every facet's frame, multiplies the sum. A nano height field's tables are its
    own lobe at azimuth 0 (:func:`_field_table`), read turned for facets of every azimuth, where the field is
    statistically isotropic; an anisotropic field's (:func:`waveoptics.brdf.field_anisotropy`) run over the
    azimuth of incidence in the field's axes on each facet too (:func:`waveoptics.brdf.anisotropic_field_stack`,
    read by :func:`waveoptics.brdf.anisotropic_field_read`); its half-vector normals are placed by the lobe width
    of its rms height and correlation length (:func:`nano_statistics`).

    Polarized light (s or p of the macro plane of incidence): each facet sees cos²η_i of its own s or p light and
    sin²η_i of the other (:func:`waveoptics.materials.cos2_eta_i`, Priest & Germer 2000). The Kirchhoff family's F
    is that of the nano facet h ∝ ω_i + ω_o rotated by η(ω_i, h) (:func:`waveoptics.materials.F_facet_polarized`),
    exact for the stationary-phase reflection in every facet frame; integrated over a facet's isotropic lobe its
    s–p term, odd about the facet's plane of incidence, vanishes, so the facet scatters cos²η_i S_pol + sin²η_i
    S_other, the mix the budget *scattered* takes (:func:`waveoptics.brdf.facet_scattered_share`). The
    Rayleigh-Rice lobe mixes the facet's s and p tables the same way (its s–p interference term, odd in the facet's
    azimuth, is left out: exact in energy, not pointwise). The first-order part of the Kirchhoff tables
    towards grazing angles (:mod:`waveoptics.scatter.tangent_blend`) carries Q of the macro polarization, not the
    facet's mix (on glass the s and p factors differ by 2 % at 81°, 10 % at 88°; that part is off by that
    difference times sin²η_i).

    The per-cell sum runs on *backend* (:data:`waveoptics.brdf.facet_frame_cl.FACET_FRAME_BACKENDS`): the OpenCL
    kernel ``kernels/facet_frame.cl`` (:func:`waveoptics.brdf.facet_frame_cl.facet_frame_sum_cl`, on *device* in
    *precision*) or its NumPy twin here; ``auto`` takes the kernel where an OpenCL device exists, for PSD
    statistics and an NDF with a kernel twin (:func:`waveoptics.brdf.facet_frame_cl.kernel_reason`).

    Returns
    -------
    diffraction : ndarray (n_λ, n_v, n_u), 1/sr
    scattered : ndarray (n_λ,)
        The light the facets' lobes scatter, F(θ_m) (1 − A(θ_m)) per facet on a conductor and the lobe's own
        absolute albedo on a dielectric (:meth:`waveoptics.brdf.Nano.scattered_share`), averaged over the facets the light
        sees (:func:`waveoptics.brdf.facet_budget`: :data:`waveoptics.brdf.FACET_BUDGET_NODES` normals of the NDF,
        weights D (ω_i·m) G1 / p, normalized by their sum, which is 1 in expectation; a slope table's bins), the
        diffracted part's albedo falls short of it by the light masked on the way out or sent below the macro
        horizon.
    reflected : ndarray (n_λ,)
        F(θ_m) averaged the same way: the light the facets reflect, coherent and diffracted together, before
        masking on the way out.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14) (a BRDF carried by each facet); §5.3 (sampling normals).
    .. [2] E. Veach, PhD thesis, 1997, §9.2 (balance heuristic of several techniques).
    .. [3] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000 (facet frames of
       polarized light).
    """
    from .facet import facet_basis, meridian_basis, unit_nodes
    from .ndf import ndf_by_name
    from .sampling import sample_normal, sampler_for
    from .shadowing import shadowing_by_name

    w = np.asarray(wavelengths_nm, dtype=float)
    dm = scatter.get_model(diffraction, perturbative=True)
    kw = micro.kw()
    ndf, ax, ay = kw["ndf"], kw["alpha"], kw["alpha_y"] if kw["alpha_y"] is not None else kw["alpha"]
    c, spec = kw["ndf_shape"], ndf_by_name(kw["ndf"])
    na, nb = nodes or facet_nodes(micro, nano, w)
    m_a = (sample_normal(np.broadcast_to(wi, (na, 3)), unit_nodes(na), ndf=ndf, ax=ax, ay=ay, c=c)
           if nano.surface is not None else None)   # a height field's NDF nodes (PSD statistics: ndf_nodes)
    inside = grid.inside
    wo = grid.directions()[inside]
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    cos_d = np.maximum(h @ wi, 1e-6)
    symmetric = nano.surface is None
    tgrid, rad = _tables_and_proposal(nano, w, table_grid or grid, dm, nb)
    level = rad.level(cos_d)
    Li, Lo = float(spec.Lambda(wi, ax, ay, c)), spec.Lambda(wo, ax, ay, c)
    gfn, _ = shadowing_by_name(micro.shadowing)
    # PSD statistics: nodes laid out about each cell's half-vector, reciprocal (:func:`.facet.ndf_nodes`); a height
    # field's speckle keeps the NDF sampler's nodes for ω_i shared by all cells and the Sobol half-vector nodes
    # (FACET_NODES_FIELD was measured with them; the symmetric layout read its speckle 5-11 % off the reference)
    visible = sampler_for(ndf).visible
    tables = anisotropic_field_stack if anisotropic_field(nano) else _facet_stack   # over (θ', φ') or θ' only
    stack, first = tables(nano, w, tgrid, dm, material, polarization)
    # Rayleigh-Rice tables hold Q of the facet's own s or p light: macro s or p light mixes both (Priest & Germer)
    other = {"s": "p", "p": "s"}.get(polarization) if dm.perturbative and material is not None else None
    stack_other = None if other is None else tables(nano, w, tgrid, dm, material, other)[0]
    graze, na_cell, (mc, bw, beta) = _extra_nodes(symmetric, nodes, wi, wo, h, cos_d, rad, level, na, nb, ndf=ndf,
                                                  ax=ax, ay=ay, c=c)
    out = (facet_frame_sum_cl(wi, wo, h, cos_d, level, Lo, Li, micro, (na, nb), rad, stack, stack_other, tgrid,
                              facet_thetas(nano), device=device, precision=precision, first=first,
                              projected=symmetric, graze=graze, bridge=(mc, bw, beta))
           if facet_frame_backend(backend, micro, nano) == "opencl" else None)

    def add(m, valid, share=1.0, cells=slice(None)):
        """Add the nodes m (3,) (shared) or (n, 3) (one per cell of *cells*) by the balance heuristic, times *share*."""
        wo_c, h_c, cd_c, lev_c, Lo_c = wo[cells], h[cells], cos_d[cells], level[cells], Lo[cells]
        om = wo_c @ m if m.ndim == 1 else np.sum(wo_c * m, axis=-1)
        im = m @ wi
        D = spec.D(m, ax, ay, c)
        if symmetric:   # the NDF nodes' density D(m) cos θ_m, the same for ω_i and ω_o swapped
            pa = D * m[..., 2]
        else:           # a height field's: the micro NDF's sampler for ω_i
            pa = np.where(im > 0, D * im / (1.0 + Li), 0.0) / wi[2] if visible else D * m[..., 2]
        mh = np.clip(h_c @ m if m.ndim == 1 else np.sum(m * h_c, axis=-1), 0.0, 1.0)
        pb = np.where(mh > 0, rad.pdf_r(lev_c, 2 * cd_c * np.sqrt(np.maximum(1 - mh * mh, 0.0)))
                      * 4 * cd_c ** 2 * mh, 0.0)
        den = with_bridge_density(na_cell[cells] * pa + nb * pb, m, np.arange(wo.shape[0])[cells], beta, mc, bw, h)
        ok = valid & (im > 0) & (om > 0) & (den > 0) & (D > 0)
        if not ok.any():
            return
        wok, Lok, Lik = wo_c[ok], Lo_c[ok], np.full(int(ok.sum()), Li)
        mk = np.broadcast_to(m, wok.shape) if m.ndim == 1 else m[ok]
        G = gfn(np.broadcast_to(wi, wok.shape), wok, mk, lambda d: Lok if d is wok else Lik)
        share = share[cells][ok] if np.ndim(share) else share   # × |ω_o·m| f_nano below
        weight = (im * D if m.ndim == 1 else (im * D)[ok]) * G * share / (wi[2] * wok[:, 2] * den[ok])
        read = _facet_reader(wi, wok, mk if m.ndim > 1 else m, im if m.ndim == 1 else im[ok], om[ok], tgrid,
                             symmetric, facet_thetas(nano), tables is not _facet_stack)
        g = read(pair, first is not None)
        if stack_other is not None:   # cos²η_i g_pol + sin²η_i g_other (the s-p term is odd about the facet plane)
            g_sp = {polarization: g, other: read(stack_other, False)}
            g = facet_sp_mix(g_sp["s"], g_sp["p"], cos2_eta_i(wi, mk)[:, None], polarization)
        out[np.arange(wo.shape[0])[cells][ok]] += weight[:, None] * g

    e1, e2 = meridian_basis(h) if symmetric else facet_basis(h)
    if tables is not _facet_stack:   # an anisotropic field's normals drawn apart per cell (cell_shifted_nodes)
        m_a, (e1, e2) = cell_shifted_nodes(wi, e1, e2, unit_nodes(na), lambda a, u: sample_normal(
            a, u, ndf=ndf, ax=ax, ay=ay, c=c))
    if out is None:   # the NumPy twin of kernels/facet_frame.cl
        out = np.zeros((wo.shape[0], w.size))
        pair = stack if first is None else np.concatenate([stack, first], axis=-1)   # one gather for both
        for n_a, cells in ((na, ~graze), (2 * na, graze)) if symmetric else ((na, None),):   # 2 N_a where it grazes
            m_n = m_a if cells is None else ndf_nodes(n_a, e2, ndf=ndf, ax=ax, ay=ay, c=c) if cells.any() else ()
            for m in m_n:
                add(m, np.ones(wo.shape[0], bool) if cells is None else cells)
        for s_k, cp, sp in half_vector_nodes(rad, level, nb, cos_d, antithetic=symmetric):
            ok = s_k < 1                                      # a tilt s from h sends ω_i to q = 2k cosθ_d s
            s_k = np.where(ok, s_k, 0.0)
            m = (s_k * cp)[:, None] * e1 + (s_k * sp)[:, None] * e2 + np.sqrt(1 - s_k ** 2)[:, None] * h
            add(m, ok)
        on = np.flatnonzero(beta > 0)
        m_c, ok_c = bridge_nodes(mc[on], bw[on], h[on])
        for k in range(m_c.shape[1] if on.size else 0):   # in the cells that have a bridge only
            add(m_c[:, k], ok_c[:, k], beta, on)
    diffraction = np.zeros((w.size, grid.n_v, grid.n_u))
    for i, lam in enumerate(w):
        if dm.perturbative:
            Fc = np.ones(wo.shape[0])
        else:
            Fc = F.at(np.broadcast_to(wi, wo.shape), wo, lam) if hasattr(F, "at") else F(np.clip(h @ wi, 0, 1), lam)
        diffraction[i][inside] = out[:, i] * Fc
    scattered, reflected = facet_budget(wi, w, micro, nano, F, dm, material, polarization)
    return diffraction, scattered, reflected
