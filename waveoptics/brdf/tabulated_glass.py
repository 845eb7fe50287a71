"""A rough glass's BSDF tabulated over the sphere: cell averages of reflection and transmission on direction-cosine
grids, for light from the air and from inside the glass, and the function that reads them back.

**The table** (:func:`glass_cells`) holds, for each side of the light (air above, the dielectric below), incidence
angle θ_k (azimuth 0) and wavelength, two direction-cosine grids of the exit direction ω_o = (u, v, ±√(1 − u² − v²)):
the reflected hemisphere (ω_o on the light's side) and the transmitted one. Each cell holds the *average of f over
the cell's area in the (u, v) plane* inside the unit disc, f in 1/sr in the radiance convention (Veach 1997, §5.2:
f_t carries η_o²). Since |cos θ_o| dω_o = du dv, the light a cell receives is exactly its average times that area
(:func:`disc_fraction` du dv), so the cells' sums are
the reflectance R and transmittance T of the model at θ_k with no quadrature error of their own, however narrow the
lobes: a smooth-ish glass's microfacet lobes are a fraction of a cell wide (GGX α 0.01 has a reflected lobe of
deviation √2 α cos θ_i ≈ 0.014 in direction cosines at normal incidence; a 128² cell is 0.0156). The averages are
midpoint sums over sub-cells: at most :data:`SUBCELL_SIZE` wide far from the specular directions, and near them
(within :data:`LOBE_REACH` lobe deviations plus a cell) sub-cells at most half a deviation wide
(:func:`exit_lobe_width`: the micro lobe's deviation (α/√2) σ_min(J), J the Jacobian of the exit's direction
cosines with respect to the facet's slope, reflected or refracted, and the nano lobe's
:meth:`~waveoptics.surfaces.PSDModel.lobe_width` scaled by 1/η_o), up to :data:`SUBCELLS_MAX`, a narrower lobe refused; cells cut by the
horizon take :data:`SUBCELLS_RIM_FACTOR` times more (the part of the cell beyond it holds no light).

**Reading** (:class:`TabulatedGlassBSDF`): the light's azimuth is turned to 0 (the glass is isotropic), θ_i is
bracketed by two incidence nodes, and each node is read *relative to its specular direction* in index-scaled
direction cosines, where first-order scatter and a facet's refraction shift lobes rigidly (the grating equation
η_o o_∥ = η_i (−i_∥) + λ f, Harvey 1976; Krywonos et al. 2011): node k is read at o_∥ + (η_i/η_o)(i_∥ − i_∥ₖ), so
a transmitted lobe moves with its refracted direction as θ_i changes. The two reads are blended linearly in θ_i;
each read is the value of the cell it falls in (piecewise constant: the cell averages are the data), 0 beyond the
unit disc. Sampling picks one of the two nodes by its weight, then the hemisphere by the node's R/(R + T), then a
cell by its light and a uniform point in it, and maps the point back by the inverse shift (a point beyond the
horizon is an invalid sample, the light the shift moves past it); :meth:`pdf` is that mixture's exact density,
Σ_k w_k f_k(read_k) a_k / (R_k + T_k) · |cos θ_o| (a_k the read cell's fraction inside the disc; the translation
has Jacobian 1 in (u, v)).

**Reciprocity.** The read holds a pair (ω_i, ω_o) in the cell of ω_o at a node near θ_i and its swap in the cell
of ω_i at a node near θ_o, so it is reciprocal only to the size of its cells: BK7, α 0.3, 64² cells, refined
nodes, 4000 pairs sampled from the model up to 80°: |ln(f(i, o)/η_o² ÷ f(o, i)/η_i²)| median 0.09 (0.036
reflected, 0.096 transmitted), 90th percentile 0.29. :meth:`~TabulatedGlassBSDF.eval` keeps the read, whose
light is the cells' (energy first: a white furnace); :meth:`~TabulatedGlassBSDF.eval_reciprocal` is the mean
½ [f(ω_i, ω_o) + (η_o/η_i)² f(ω_o, ω_i)], reciprocal with the η² factor by construction (Veach 1997, §5.2) and
closer to the model point by point (lobe-weighted mean |f/f_model − 1| 0.077 → 0.048 on the same pairs), but its
light is not the cells': off by up to 0.7 % of the incident light on 64² cells (air 61°: T 0.888 for 0.895) and
up to 4.4 % on 16² (T at normal incidence 0.916 for 0.959), the swap read through cells of the other incidence.

References
----------
.. [1] J. E. Harvey, "Light-scattering characteristics of optical surfaces", PhD thesis, University of Arizona,
   1976 (shift-invariance of scattering in direction cosines).
.. [2] A. Krywonos, J. E. Harvey, N. Choi, "Linear systems formulation of scattering theory for rough surfaces
   with arbitrary incident and scattering angles", JOSA A 28(6), 1121-1138, 2011 (direction cosines scaled by the
   refractive index in transmission).
.. [3] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007, eqs. (16), (40)
   (refraction through a facet).
.. [4] E. Veach, PhD thesis, Stanford, 1997, §5.2 (radiance convention) and §9.2 (mixture densities).
.. [5] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 2023, §A.5 (sampling a
   piecewise-constant 2D distribution).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError
from ..scatter.grid import DirectionGrid
from .btdf import refract
from .facet_interface import facet_interface_of
from .protocol import SphereBSDF, broadcast_incidence, broadcast_pair, lobe_choice

__all__ = ['GLASS_SIDES', 'GLASS_HEMISPHERES', 'SUBCELL_SIZE', 'SUBCELLS_RIM_FACTOR', 'SUBCELLS_MAX', 'LOBE_REACH',
           'incident_direction', 'specular_exit', 'exit_lobe_width', 'cell_subdivisions', 'cell_averages',
           'DISC_SUBCELLS', 'disc_fraction', 'cells_light', 'glass_cells', 'NODE_TOLERANCE', 'NODE_MIN_STEP_DEG', 'refined_incidence_nodes',
           'TabulatedGlassBSDF', 'tabulate_glass']

#: sides the light comes from: the air above (z > 0) and the dielectric below
GLASS_SIDES = ("air", "dielectric")
#: exit hemispheres of a table: on the light's side and across the interface
GLASS_HEMISPHERES = ("reflection", "transmission")
#: largest sub-cell (direction cosines) far from the specular directions: midpoint sums of a smooth lobe, whose
#: kinks (the critical angle's edge inside the glass) are a fraction of a cell; at least 2 sub-cells per side
SUBCELL_SIZE = 2.0 / 256
#: sub-cells per side of a cell cut by the horizon, relative to the cell's far count (its area inside the disc)
SUBCELLS_RIM_FACTOR = 2
#: most sub-cells per side of a cell near a specular direction (a lobe narrower than two of them is refused)
SUBCELLS_MAX = 256
#: reach (lobe deviations, plus a cell) about a specular direction of the cells that take finer sub-cells
LOBE_REACH = 6.0


def incident_direction(side: str, theta_deg: float) -> np.ndarray:
    """ω_i (3,) towards the light at θ (degrees from the normal of its side) and azimuth 0: from the air
    (z > 0) or from inside the dielectric (z < 0)."""
    t = np.radians(float(theta_deg))
    return np.array([np.sin(t), 0.0, np.cos(t) if side == "air" else -np.cos(t)])


def specular_exit(wi, eta_i: float, eta_o: float, hemisphere: str):
    """Direction cosines (u, v) of the specular exit of ω_i: the mirror direction −i_∥, or the refracted one
    −(η_i/η_o) i_∥ (Snell's law in direction cosines); None under total internal reflection.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.1 (Snell's law).
    """
    s = -np.asarray(wi[:2], dtype=float) * (1.0 if hemisphere == "reflection" else eta_i / eta_o)
    return s if float(s @ s) < 1.0 else None


def _exit_through(wi, m, eta_i, eta_o, hemisphere):
    """The exit (u, v) of ω_i through a facet of normal *m* on ω_i's side: reflected, or refracted."""
    if hemisphere == "reflection":
        o = 2.0 * (wi @ m) * m - wi
    else:
        o, _ = refract(wi, m, eta_o / eta_i)
    return o[:2]


def exit_lobe_width(wi, eta_i: float, eta_o: float, hemisphere: str, alpha: float, psd=None,
                    wavelength_nm: float | None = None) -> float:
    """Standard deviation (direction cosines) of the narrowest lobe about a specular exit, across its narrower
    axis: the micro lobe's (α/√2) σ_min(J), J = ∂(u_o, v_o)/∂(slope) the Jacobian of the exit through a facet at
    zero slope (by central differences; reflection gives 2 cos θ_i and 2, the √2 α cos θ_i of the micro lobe), and
    the first-order nano lobe's :meth:`~waveoptics.surfaces.PSDModel.lobe_width` / η_o (the grating equation in
    the exit medium).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (40) (refraction through a facet).
    .. [2] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §2.4 (grating equation).
    """
    wi = np.asarray(wi, dtype=float)
    n = np.array([0.0, 0.0, np.sign(wi[2])])
    h = 1e-6
    cols = []
    for e in (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        mp, mm = n + h * e, n - h * e
        cols.append((_exit_through(wi, mp / np.linalg.norm(mp), eta_i, eta_o, hemisphere)
                     - _exit_through(wi, mm / np.linalg.norm(mm), eta_i, eta_o, hemisphere)) / (2 * h))
    width = alpha / np.sqrt(2.0) * float(np.linalg.svd(np.stack(cols, axis=1), compute_uv=False)[-1])
    if psd is not None and wavelength_nm is not None:
        width = min(width, psd.lobe_width(wavelength_nm) / eta_o)
    return width


def cell_subdivisions(grid: DirectionGrid, centre, width: float) -> np.ndarray:
    """Sub-cells per side (n_v, n_u) of each cell (module doc): enough for sub-cells of :data:`SUBCELL_SIZE`,
    :data:`SUBCELLS_RIM_FACTOR` times that where the horizon cuts the cell, and within :data:`LOBE_REACH` deviations *width* plus two cells of *centre* (None:
    no specular exit) enough that a sub-cell is at most half a deviation wide; a lobe that would need more than
    :data:`SUBCELLS_MAX` is refused (naming ``micro_alpha`` and ``resolution``: between two sub-points it would
    be missed)."""
    uu, vv = np.meshgrid(grid.u, grid.v)
    du, dv = grid.du, grid.dv
    base = max(2, int(np.ceil(max(du, dv) / SUBCELL_SIZE)))
    far = np.hypot(np.abs(uu) + du / 2, np.abs(vv) + dv / 2)
    s = np.where(far > 1.0, SUBCELLS_RIM_FACTOR * base, base)
    if centre is not None and width > 0:
        near = np.hypot(uu - centre[0], vv - centre[1]) < LOBE_REACH * width + max(du, dv)
        need = int(np.ceil(2.0 * max(du, dv) / width))
        if need > SUBCELLS_MAX:
            raise FieldError(f"a specular lobe {width:.2g} wide (direction cosines) is too narrow for cells "
                             f"{max(du, dv):.3g} wide: it needs {need} sub-cells per cell side, at most "
                             f"{SUBCELLS_MAX}; raise {{micro_alpha}} or {{resolution}}", "micro_alpha", "resolution")
        fine = max(base, need)
        s = np.where(near, np.maximum(s, fine), s)
    return s


#: sub-cells per side of the quadrature of a rim cell's area inside the unit disc (:func:`disc_fraction`)
DISC_SUBCELLS = 64


@functools.lru_cache(maxsize=8)
def disc_fraction(grid: DirectionGrid) -> np.ndarray:
    """The fraction (n_v, n_u) of each cell's area that lies inside the unit disc (directions above the horizon):
    1 inside, 0 beyond, the midpoint rule on :data:`DISC_SUBCELLS`² sub-cells where the rim cuts the cell."""
    uu, vv = np.meshgrid(grid.u, grid.v)
    near = np.hypot(np.abs(uu) - grid.du / 2, np.abs(vv) - grid.dv / 2)
    far = np.hypot(np.abs(uu) + grid.du / 2, np.abs(vv) + grid.dv / 2)
    frac = np.where(far <= 1.0, 1.0, 0.0)
    off = (np.arange(DISC_SUBCELLS) + 0.5) / DISC_SUBCELLS - 0.5
    ou, ov = np.meshgrid(off * grid.du, off * grid.dv)
    for iv, iu in zip(*np.nonzero((far > 1.0) & (near < 1.0))):
        frac[iv, iu] = np.mean(np.hypot(uu[iv, iu] + ou, vv[iv, iu] + ov) < 1.0)
    return frac


def cells_light(cells, grid: DirectionGrid):
    """The light Σ f du dv (dimensionless, per unit incident light) of cell averages (..., n_v, n_u): each cell's
    average times its area inside the unit disc (:func:`disc_fraction`)."""
    return np.sum(np.asarray(cells) * disc_fraction(grid), axis=(-2, -1)) * grid.du * grid.dv


def cell_averages(f_of, grid: DirectionGrid, below: bool, subdivisions: np.ndarray, n_out: int) -> np.ndarray:
    """Averages (n_out, n_v, n_u) over the part inside the unit disc of each cell's area in the (u, v) plane of
    ``f_of(wo)`` → (n, n_out), exits ω_o = (u, v, ±√(1 − u² − v²)) below the interface when *below*: midpoint sums
    over the *subdivisions*² sub-cells (:func:`cell_subdivisions`) inside the disc (0 for a cell beyond it). The
    light of a cell is its average times its area inside the disc (:func:`disc_fraction`)."""
    out = np.zeros((n_out, grid.n_v, grid.n_u))
    uu, vv = np.meshgrid(grid.u, grid.v)
    for s in np.unique(subdivisions):
        iv, iu = np.nonzero(subdivisions == s)
        off = (np.arange(s) + 0.5) / s - 0.5
        ou, ov = np.meshgrid(off * grid.du, off * grid.dv)
        u = uu[iv, iu][:, None] + ou.ravel()[None]
        v = vv[iv, iu][:, None] + ov.ravel()[None]
        r2 = u * u + v * v
        inside = r2 < 1.0
        z = np.sqrt(np.maximum(1.0 - r2[inside], 0.0)) * (-1.0 if below else 1.0)
        vals = np.zeros(u.shape + (n_out,))
        vals[inside] = f_of(np.stack([u[inside], v[inside], z], axis=-1))
        count = inside.sum(axis=1)
        out[:, iv, iu] = (vals.sum(axis=1) / np.maximum(count, 1)[:, None]).T
    return out


def glass_cells(model, side: str, theta_deg: float, wavelengths_nm, grid: DirectionGrid, psd=None) -> dict:
    """The cells of one incidence (module doc): ``reflection`` and ``transmission`` (n_λ, n_v, n_u) in 1/sr, cell
    averages of *model*'s f (a :class:`~waveoptics.brdf.RoughDielectricBSDF` or one of its nano-rough
    subclasses, whose micro roughness places the fine sub-cells; *psd* the nano statistics, whose lobe width does
    too) for light from *side* at *theta_deg* (degrees) and azimuth 0; ``eta`` (n_λ,) the glass's index."""
    wi = incident_direction(side, theta_deg)
    lam = np.asarray(wavelengths_nm, dtype=float)
    eta = np.array([facet_interface_of(model.material, float(x)).eta for x in lam])
    kw = model.micro.kw()
    alpha = min(kw["alpha"], kw["alpha_y"] if kw["alpha_y"] is not None else kw["alpha"])
    out = {"eta": eta}
    for hemi in GLASS_HEMISPHERES:
        below = (wi[2] > 0) == (hemi == "transmission")
        widths, centre = [], None
        for x, e in zip(lam, eta):
            ei, eo = (1.0, e) if side == "air" else (e, 1.0)
            eo = ei if hemi == "reflection" else eo
            c = specular_exit(wi, ei, eo, hemi)
            if c is not None:
                centre = c
                widths.append(exit_lobe_width(wi, ei, eo, hemi, alpha, psd, float(x)))
        sub = cell_subdivisions(grid, centre, min(widths) if widths else 0.0)
        out[hemi] = cell_averages(lambda wo: model.eval(wi, wo[:, None, :], lam[None, :]),
                                  grid, below, sub, lam.size)
    return out


#: tolerance of the read between incidence nodes (:func:`refined_incidence_nodes`): the difference of the light
#: in each exit hemisphere, Σ (f_read − f) du dv, as a fraction of the incident light. (The cells' L1 distance is
#: no criterion: a lobe narrower than a cell, shifted by a fraction of a cell and read back cell by cell, is
#: 3-7 % off in L1 however close the nodes are: BK7, α 0.1, 64², the transmitted lobe from the air.)
NODE_TOLERANCE = 0.005
#: smallest spacing (degrees) of refined incidence nodes
NODE_MIN_STEP_DEG = 0.25


def _read_cells(table, side: str, theta_deg: float, j: int) -> dict:
    """Cell averages (n_v, n_u) of *table*'s read at an incidence (midpoints of 8² sub-cells: the read is piecewise constant on cells shifted by a fraction of a cell), per hemisphere."""
    wi = incident_direction(side, theta_deg)
    lam = table.wavelengths_nm[j]
    sub = np.full((table.grid.n_v, table.grid.n_u), 8)
    return {h: cell_averages(lambda wo: table.eval(wi, wo, lam)[:, None], table.grid,
                             (wi[2] > 0) == (h == "transmission"), sub, 1)[0] for h in GLASS_HEMISPHERES}


def refined_incidence_nodes(model, thetas_deg, wavelengths_nm, grid: DirectionGrid, psd=None,
                            tolerance=NODE_TOLERANCE, min_step_deg: float = NODE_MIN_STEP_DEG,
                            progress=None) -> tuple:
    """The incidence nodes *thetas_deg* (degrees) with nodes added where the read between two nodes (module doc)
    misses the light of the cells computed at the interval's middle (:func:`glass_cells`, light from either side,
    at the first and last of *wavelengths_nm*) in either exit hemisphere by more than *tolerance* of the incident
    light (:data:`NODE_TOLERANCE`), down to
    *min_step_deg*; *progress* (optional) is called with 1 after each interval tested. A glass's R(θ) and T(θ) bend
    sharply where its facets pass the critical angle (light from
    inside: R 0.05 → 1 within a few degrees of θ_c ± the facets' tilt), and near grazing the lobes are pressed
    against the horizon, where the shifted read of a node 5° away loses light past it: BK7, α 0.1, 64² cells,
    nodes 5° apart, read at the middles: from inside at 32.5° R 19 % high, at 72.5° 4.7 % of the light lost.

    Returns
    -------
    (tuple of float, dict)
        The nodes, and the cells computed on the way by (side, θ) (each :func:`glass_cells` at the two
        wavelengths).

    References
    ----------
    .. [1] C. de Boor, *A Practical Guide to Splines*, Springer 1978, ch. 2 (the error of interpolation, estimated
       at the interval's middle).
    """
    lam = tuple(sorted({float(wavelengths_nm[0]), float(wavelengths_nm[-1])}))
    nodes = sorted(float(t) for t in thetas_deg)
    cells = {}

    def at(t):
        if t not in cells:
            cells[t] = [glass_cells(model, side, t, lam, grid, psd) for side in GLASS_SIDES]
        return cells[t]

    def close(a, b, m):
        pair = [at(a), at(b)]
        table = TabulatedGlassBSDF(wavelengths_nm=lam, thetas_deg=(a, b), grid=grid, eta=pair[0][0]["eta"],
                                   **{h: np.array([[pair[k][i][h] for k in (0, 1)] for i in (0, 1)])
                                      for h in GLASS_HEMISPHERES})
        for i, side in enumerate(GLASS_SIDES):
            for j in range(len(lam)):
                read = _read_cells(table, side, m, j)
                for h in GLASS_HEMISPHERES:
                    d = at(m)[i][h][j]
                    if abs(cells_light(read[h] - d, grid)) > tolerance:
                        return False
        return True

    todo = list(zip(nodes[:-1], nodes[1:]))
    while todo:
        a, b = todo.pop()
        m = 0.5 * (a + b)
        fine = b - a <= 2.0 * min_step_deg or close(a, b, m)
        if progress is not None:
            progress(1)
        if fine:
            continue
        nodes.append(m)
        todo += [(a, m), (m, b)]
    return tuple(sorted(nodes))


def _turned(w, phi):
    """Vectors (n, 3) turned about z by −phi (n,) (the light's azimuth to 0), or back with −phi."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * w[:, 0] + s * w[:, 1], -s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=-1)


@dataclass(frozen=True, eq=False)
class TabulatedGlassBSDF(SphereBSDF):
    """A rough glass's BSDF read from its tables (module doc), with ``eval`` / ``pdf`` / ``sample`` / ``albedo``
    over the sphere at the table's wavelengths.

    Parameters
    ----------
    wavelengths_nm : tuple of float
        The table's wavelengths (nm); other wavelengths are refused.
    thetas_deg : tuple of float
        Incidence nodes (degrees from the normal of the light's side, increasing), shared by both sides.
    grid : DirectionGrid
        The direction-cosine grid of every exit hemisphere.
    eta : array (n_λ,)
        The glass's (real) index at each wavelength (the shift of a transmitted read).
    reflection, transmission : arrays (2, n_θ, n_λ, n_v, n_u)
        Cell averages of f (1/sr) by light side (:data:`GLASS_SIDES`), node, wavelength and exit cell.
    """

    wavelengths_nm: tuple
    thetas_deg: tuple
    grid: DirectionGrid
    eta: np.ndarray
    reflection: np.ndarray
    transmission: np.ndarray

    def __post_init__(self):
        th = np.asarray(self.thetas_deg, dtype=float)
        if th.ndim != 1 or th.size < 1 or np.any(np.diff(th) <= 0) or th[0] < 0 or th[-1] >= 90:
            raise FieldError(f"{{thetas_deg}} {self.thetas_deg!r}: the incidence nodes must increase within "
                             "[0, 90) degrees", "thetas_deg")
        shape = (2, th.size, len(self.wavelengths_nm), self.grid.n_v, self.grid.n_u)
        for name in GLASS_HEMISPHERES:
            if np.shape(getattr(self, name)) != shape:
                raise FieldError(f"{{{name}}} has shape {np.shape(getattr(self, name))}, not {shape}", name)
        frac = disc_fraction(self.grid)
        object.__setattr__(self, "_frac", frac)
        cells = (frac * self.grid.du * self.grid.dv).ravel()
        sums = np.stack([np.asarray(getattr(self, h), dtype=float).reshape(shape[:3] + (-1,)) * cells
                         for h in GLASS_HEMISPHERES], axis=-2)            # (side, θ, λ, hemi, cell)
        object.__setattr__(self, "_sums", sums.sum(axis=-1))            # R and T of each node (side, θ, λ, 2)
        object.__setattr__(self, "_cdf", np.cumsum(sums, axis=-1))

    # -- the read -------------------------------------------------------------------------------------------------
    def _lam_index(self, lam: float) -> int:
        w = np.asarray(self.wavelengths_nm)
        j = int(np.argmin(np.abs(w - lam)))
        if abs(w[j] - lam) > 1e-6 * max(1.0, lam):
            raise FieldError(f"{{wavelength_nm}} {lam:g} nm is not one of the table's wavelengths "
                             f"({w[0]:g}-{w[-1]:g} nm, {w.size} of them)", "wavelength_nm")
        return j

    def _frame(self, wi, lam):
        """Per pair: side index, the light turned to azimuth 0, its azimuth, the two nodes and b's weight, the
        ratio η_i/η_o of each hemisphere."""
        phi = np.arctan2(wi[:, 1], wi[:, 0])
        wi0 = _turned(wi, phi)
        side = (wi[:, 2] < 0).astype(int)
        th = np.degrees(np.arccos(np.clip(np.abs(wi[:, 2]), 0.0, 1.0)))
        nodes = np.asarray(self.thetas_deg, dtype=float)
        f = np.interp(th, nodes, np.arange(nodes.size))
        a = np.floor(f).astype(int)
        b = np.minimum(a + 1, nodes.size - 1)
        eta = float(self.eta[self._lam_index(lam)])
        ratio_t = np.where(side == 0, 1.0 / eta, eta)
        return side, wi0, phi, a, b, f - a, ratio_t

    def _node_point(self, wi0, k, ratio):
        """The shift (n, 2) that takes an exit's (u, v) to its read point on node k: (η_i/η_o)(i_∥ − i_∥ₖ)."""
        t = np.radians(np.asarray(self.thetas_deg, dtype=float)[k])
        return ratio[:, None] * np.stack([wi0[:, 0] - np.sin(t), wi0[:, 1]], axis=-1)

    def _cell(self, p):
        """Cell indices (iv, iu) of points p (n, 2) in (u, v) and whether they lie on the grid (a read point may lie
        beyond the disc in a rim cell: the cell's value stands for the whole cell, which is where the sampler
        draws points from)."""
        g = self.grid
        iu = np.floor((p[:, 0] - g.u_range[0]) / g.du).astype(int)
        iv = np.floor((p[:, 1] - g.v_range[0]) / g.dv).astype(int)
        ok = (iu >= 0) & (iu < g.n_u) & (iv >= 0) & (iv < g.n_v)
        return np.where(ok, iv, 0), np.where(ok, iu, 0), ok

    def _reads(self, wi, wo, lam):
        """(f per pair, pdf over (u, v) per pair) of the blended nodes."""
        j = self._lam_index(lam)
        side, wi0, phi, a, b, w, ratio_t = self._frame(wi, lam)
        wo0 = _turned(wo, phi)
        refl = (wi[:, 2] > 0) == (wo[:, 2] > 0)
        ratio = np.where(refl, 1.0, ratio_t)
        f = np.zeros(len(wi))
        p = np.zeros(len(wi))
        for k, wk in ((a, 1.0 - w), (b, w)):
            iv, iu, ok = self._cell(wo0[:, :2] + self._node_point(wi0, k, ratio))
            val = np.where(refl, self.reflection[side, k, j, iv, iu], self.transmission[side, k, j, iv, iu])
            val = np.where(ok, val, 0.0)
            total = self._sums[side, k, j].sum(axis=-1)
            f += wk * val       # the sampler draws a cell by its light and a point uniformly on the whole cell
            p += wk * np.where(total > 0, val * self._frac[iv, iu] / np.where(total > 0, total, 1.0), 0.0)
        below_horizon = (wi[:, 2] == 0) | (wo[:, 2] == 0)
        return np.where(below_horizon, 0.0, f), np.where(below_horizon, 0.0, p)

    def _eval1(self, wi, wo, lam):
        return self._reads(wi, wo, lam)[0]

    def eval_reciprocal(self, wi, wo, wavelength_nm):
        """½ [f(ω_i, ω_o) + (η_o/η_i)² f(ω_o, ω_i)] (1/sr): reciprocal with the η² factor by construction, closer
        to the model point by point, its light off by up to a few % on coarse cells (module doc)."""
        wi, wo, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        eta = np.array([float(self.eta[self._lam_index(float(x))]) for x in lam])
        ratio2 = np.where((wi[:, 2] > 0) == (wo[:, 2] > 0), 1.0, np.where(wi[:, 2] > 0, eta * eta, 1.0 / (eta * eta)))
        return (0.5 * (self._eval_flat(wi, wo, lam) + ratio2 * self._eval_flat(wo, wi, lam))).reshape(shape)

    def eval_parts(self, wi, wo, wavelength_nm) -> dict:
        """:meth:`eval` split by exit hemisphere (1/sr): ``reflection`` (ω_o on the light's side) and
        ``transmission``."""
        f = self.eval(wi, wo, wavelength_nm)
        wi, wo = np.broadcast_arrays(np.asarray(wi, dtype=float), np.asarray(wo, dtype=float))
        same = (wi[..., 2] > 0) == (wo[..., 2] > 0)
        same = np.broadcast_to(same, f.shape) if same.shape != f.shape else same
        return {"reflection": np.where(same, f, 0.0), "transmission": np.where(same, 0.0, f)}

    def _pdf1(self, wi, wo, lam):
        return self._reads(wi, wo, lam)[1] * np.abs(wo[:, 2])

    def _sample1(self, wi, u, lam):
        j = self._lam_index(lam)
        side, wi0, phi, a, b, w, ratio_t = self._frame(wi, lam)
        node, u[:, 0] = lobe_choice(u[:, 0], [1.0 - w, w])
        k = np.where(node == 0, a, b)
        sums = self._sums[side, k, j]                                   # (n, 2): R and T of the node
        hemi, u[:, 0] = lobe_choice(u[:, 0], [sums[:, 0], sums[:, 1]])
        total = sums[np.arange(len(k)), hemi]
        target = u[:, 0] * total
        cell = np.zeros(len(k), dtype=int)
        lo = np.zeros(len(k))
        width = np.zeros(len(k))
        for key in set(zip(side.tolist(), k.tolist(), hemi.tolist())):
            sel = (side == key[0]) & (k == key[1]) & (hemi == key[2])
            cdf = self._cdf[key[0], key[1], j, key[2]]
            c = np.minimum(np.searchsorted(cdf, target[sel], side="right"), cdf.size - 1)
            cell[sel] = c
            lo[sel] = np.where(c > 0, cdf[c - 1], 0.0)
            width[sel] = cdf[c] - lo[sel]
        x = np.where(width > 0, (target - lo) / np.where(width > 0, width, 1.0), 0.5)
        g = self.grid
        iv, iu = np.divmod(cell, g.n_u)
        p = np.stack([g.u_range[0] + (iu + np.clip(x, 0.0, 1.0)) * g.du, g.v_range[0] + (iv + u[:, 1]) * g.dv], -1)
        ratio = np.where(hemi == 0, 1.0, ratio_t)
        o = p - self._node_point(wi0, k, ratio)
        r2 = np.sum(o * o, axis=-1)
        valid = (r2 < 1.0) & (total > 0)
        same = np.sign(wi[:, 2]) * np.where(hemi == 0, 1.0, -1.0)
        wo0 = np.concatenate([o, (same * np.sqrt(np.maximum(1.0 - r2, 0.0)))[:, None]], axis=-1)
        return np.where(valid[:, None], _turned(wo0, -phi), 0.0)

    # -- energy ---------------------------------------------------------------------------------------------------
    def albedo_parts(self, wi, wavelength_nm) -> dict:
        """``reflection`` and ``transmission`` (dimensionless): ∫ f |cos θ_o| dω_o = ∫ f du dv of the read over
        each exit hemisphere, by midpoint sums on sub-cells of :data:`SUBCELL_SIZE` (the read is piecewise
        constant on the cells, shifted between nodes): on a node the cells' sums; between nodes less the light the
        shift moves past the horizon, which the sampler's invalid samples are."""
        wi_f, lam_f, shape = broadcast_incidence(wi, wavelength_nm)
        out = {h: np.zeros(lam_f.size) for h in GLASS_HEMISPHERES}
        g = self.grid
        sub = np.full((g.n_v, g.n_u), max(2, int(np.ceil(max(g.du, g.dv) / SUBCELL_SIZE))))
        for n, (w1, l1) in enumerate(zip(wi_f, lam_f)):
            if w1[2] == 0:
                continue
            for h in GLASS_HEMISPHERES:
                cells = cell_averages(lambda wo: self.eval(w1, wo, float(l1))[:, None], g,
                                      (w1[2] > 0) == (h == "transmission"), sub, 1)
                out[h][n] = cells_light(cells[0], g)
        return {k: v.reshape(shape) for k, v in out.items()}


def tabulate_glass(model, thetas_deg, wavelengths_nm, grid: DirectionGrid, psd=None) -> TabulatedGlassBSDF:
    """*model* (a rough glass, :func:`glass_cells`) tabulated in memory at the incidence nodes *thetas_deg*
    (degrees, both sides) and *wavelengths_nm* on *grid*; ``waveoptics table --transmission`` computes the same
    cells on Dask and :func:`waveoptics.open_table` reads them back."""
    th = tuple(float(t) for t in thetas_deg)
    cells = [[glass_cells(model, side, t, wavelengths_nm, grid, psd) for t in th] for side in GLASS_SIDES]
    stack = {h: np.array([[c[h] for c in row] for row in cells]) for h in GLASS_HEMISPHERES}
    return TabulatedGlassBSDF(wavelengths_nm=tuple(float(x) for x in wavelengths_nm), thetas_deg=th, grid=grid,
                              eta=cells[0][0]["eta"], **stack)
