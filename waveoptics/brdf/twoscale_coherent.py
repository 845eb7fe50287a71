"""The coherent part of the two-scale BRDF on a direction grid: the microfacet specular lobe with F, times the
coherent fraction A(λ, θ_d) of each facet (:meth:`waveoptics.brdf.Nano.coherent_fraction`; docs/physics.md §7, §9).

A micro lobe narrower than a cell (α ≲ du) cannot be sampled: its energy F·A·ρ_mf is deposited in the mirror cell as a
spike of height E/(du dv), which keeps albedo and colour exact on the grid.

A thin-film stack's reflectance R(θ) has interference fringes and, towards grazing incidence, resonance dips a few
degrees wide (Al|Al2O3:300nm at 560 nm: R = 0.715 at 80°, 0.606 at 86°, 0.719 at 89°), narrower than the cells of a
coarse grid near the rim of the disc, where a grazing lobe is squeezed: read at the cell centres, F·A of a micro
lobe (GGX α = 0.05) at 89° came out 0.673 on 32² cells (0.641 on 64², 0.617 on 128²) against 0.610 by the
half-vector quadrature, above the light the facets reflect less what they scatter, and the diffracted budget
(:func:`waveoptics.brdf.twoscale.cap_to_coherent_loss`) then removed 78 % of the diffracted lobe (issues 28/33). For
a stack the factors F and F·A of every cell are therefore their averages over the cell,
weighted by the F = 1 lobe, and the F = 1 lobe itself is its cell average (:class:`SubCells`); a single interface's
R(θ) is smooth on the scale of a cell and keeps the cell-centre value.

A measured slope table (NDF ``tabulated``, :mod:`waveoptics.brdf.measured_ndf`) takes the cell averages too: its
D is a histogram, constant on slope bins smaller than a cell (64² bins of a Gaussian surface, α ≈ 0.066: a bin
0.006 in slope, a 64² cell about 0.015), so a cell-centre value reads one bin's count, noisy by several percent,
for the whole cell. Read so, the coherent albedo of Au at θ_i = 70° (550 nm, Gaussian σ 8 nm ℓ 1 µm) was 0.80658
on 32² cells, 0.80521 on 64², 0.80506 on 96², 0.80489 on 128² and 0.80477 on 256², against 0.80473 by a direct
sum over the table's slopes (Walter's integral, 8² points per bin): the diffracted budget (the light the facets
reflect less the coherent albedo, :func:`waveoptics.brdf.twoscale.cap_to_coherent_loss`) lost up to half its
0.0033, and the energy guard removed 55 % of the diffracted lobe on 32² and 13 % on 64² (128²: the lobe 1.030x
its budget; issue 28). Cell averages: 0.80466 to 0.80477 on 32² to 128², the lobe within 1.007x its budget
(tests/test_slope_table_energy.py).

Towards grazing light the disc squeezes a micro lobe across the plane of incidence to a standard deviation
√2 α cos θ_i, a fraction of a cell on a coarse grid: read at cell centres, F·A landed on the wrong facets (Au,
Beckmann α 0.066, Gaussian σ 8 nm ℓ 1 µm, 550 nm, θ_i 80°: coherent albedo 0.8236 on 32², 0.8340 on 64², 0.8369 on
256², against 0.8372 by a slope-space integral; α 0.1 at 85°: 0.7874, 0.7990, 0.8060 against 0.8073). Where the
lobe spans fewer than :data:`COHERENT_CELLS_PER_WIDTH` cells per deviation its cells hold averages too, over
sub-cells half a deviation wide: 0.8369 and 0.8065-0.8069 on every grid from 32² (tests/test_coherent_cells.py).

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (coherent part of the two-scale model).
.. [2] H. Davies, Proc. IEE 101, 209 (1954) (coherent fraction).
"""
from __future__ import annotations

import numpy as np

from .. import scatter
from ..runtime import parallel_map
from ..materials import cos2_eta_i
from ..scatter.grid import DirectionGrid
from .facet_polarization import facet_coherent_fraction
from .microfacet import specular
from .quadrature import albedo
from .roughness_scales import Micro, Nano
from .twoscale_grid import azimuth_deg, fresnel_at_mirror, mirror_cell, sharp_micro_lobe, significant_cells

__all__ = ['STACK_SUBCELL', 'COHERENT_CELLS_PER_WIDTH', 'SUBCELLS_MAX', 'LOBE_CELLS_REACH', 'micro_lobe_width',
           'lobe_cells', 'coarse_micro_lobe',
           'coherent_lobe', 'SubCells']


#: width (direction cosines) of the sub-cells over which :class:`SubCells` averages a stack's F and F·A
#: in each cell (32² cells: 8² sub-cells each)
STACK_SUBCELL = 2.0 / 256
#: a micro lobe whose standard deviation across the plane of incidence, √2 α cos θ_i (direction cosines: the lobe
#: is squeezed by cos θ_i towards the rim of the disc), spans fewer cells than this takes cell averages
#: (:func:`coarse_micro_lobe`), over sub-cells at most half that deviation wide
COHERENT_CELLS_PER_WIDTH = 2.0
#: most sub-cells per cell side (towards θ_i = 90° the squeezed lobe's width goes to 0)
SUBCELLS_MAX = 16


def micro_lobe_width(micro: Micro, wi) -> float:
    """Standard deviation (direction cosines) of the micro lobe across the plane of incidence, where the disc
    squeezes it: √2 α cos θ_i (the reflected direction turns twice the facet's tilt of rms α/√2, and its direction
    cosine along the plane of incidence by cos θ_i of that), α the NDF's smaller width.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007 (the microfacet lobe about the mirror direction).
    """
    a = micro.alpha if micro.alpha_y is None else min(micro.alpha, micro.alpha_y)
    return float(np.sqrt(2.0) * a * abs(wi[2]))


#: reach (in the micro lobe's unsqueezed standard deviations √2 α, plus two cells) of the cells about the mirror
#: point that a squeezed lobe averages (:func:`lobe_cells`): beyond 6 deviations a Beckmann lobe is below e^-18 of
#: its peak; a GGX lobe's heavier tail beyond keeps its cell-centre values (smooth on the scale of a cell there)
LOBE_CELLS_REACH = 6.0


def lobe_cells(grid: DirectionGrid, wi, micro: Micro) -> np.ndarray:
    """Mask (n_v, n_u) of the cells whose centres lie within :data:`LOBE_CELLS_REACH` deviations √2 α (the NDF's
    larger width) plus two cells of ω_i's mirror point (−u_i, −v_i) in direction cosines: where a squeezed micro
    lobe's light is."""
    a = micro.alpha if micro.alpha_y is None else max(micro.alpha, micro.alpha_y)
    wo = grid.directions()
    r = LOBE_CELLS_REACH * np.sqrt(2.0) * a + 2.0 * max(grid.du, grid.dv)
    return (wo[..., 0] + wi[0]) ** 2 + (wo[..., 1] + wi[1]) ** 2 < r * r


def coarse_micro_lobe(micro: Micro, grid: DirectionGrid, wi) -> bool:
    """Whether the micro lobe spans fewer than :data:`COHERENT_CELLS_PER_WIDTH` cells per standard deviation
    (:func:`micro_lobe_width`): its cells then hold averages (module doc)."""
    return micro_lobe_width(micro, wi) < COHERENT_CELLS_PER_WIDTH * max(grid.du, grid.dv)


def coherent_lobe(wi, wavelengths_nm, F, micro: Micro, nano: Nano | None, grid: DirectionGrid, diffraction,
                  material, polarization: str = "unpolarized", reference_grid: DirectionGrid | None = None):
    """(microfacet lobe f_mf with F, the same lobe with F = 1, coherent part A f_mf), each (n_λ, n_v, n_u) in 1/sr.

    The F = 1 lobe is all the light the facets receive (a dielectric's diffracted budget). Its cell quadrature is
    scaled to the accurate quadrature albedo ρ_mf (:func:`waveoptics.brdf.albedo`; of *reference_grid* when *grid* is
    a patch of it): near grazing a narrow lobe is squeezed against the rim of the (u, v) disc and the cell
    quadrature over- or under-counts it. A thin-film stack's and a slope table's cells hold their averages over
    the cell (module doc). A is evaluated per cell at the facet's local incidence θ_d = ∠(ω_i, h);
    a height field's facets beyond the lobe's main light (:func:`waveoptics.brdf.twoscale_grid.significant_cells`)
    keep the coherent fraction of θ_i, as their diffracted weights do. For s or p light a conductor's A is that
    of the facet's mix of its own s and p light (:func:`waveoptics.brdf.facet_coherent_fraction`), as its F is.

    References
    ----------
    .. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (f_c = A F G D / (4 cosθ_i cosθ_o)).
    .. [2] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000 (facet frame).
    """
    w = np.asarray(wavelengths_nm, dtype=float)
    shape = (w.size, grid.n_v, grid.n_u)
    sigma_nano = 0.0 if nano is None else nano.sigma
    phi = azimuth_deg(wi)
    if sharp_micro_lobe(micro, grid):
        mf = np.zeros(shape)
        cell = mirror_cell(grid, wi)
        rho = float(albedo(wi, fresnel="one", **micro.kw()))
        mf_one = np.zeros(shape)   # the same lobe with F = 1: all the light the facets receive
        if cell is not None:
            Fi = np.array([float(np.ravel(fresnel_at_mirror(F, wi, lam))[0]) for lam in w])
            mf[:, cell[0], cell[1]] = Fi * rho / (grid.du * grid.dv)
            mf_one[:, cell[0], cell[1]] = rho / (grid.du * grid.dv)
        A = np.array([float(nano.coherent_fraction(wi[2], lam, diffraction, material, polarization, phi))
                      if sigma_nano > 0 else 1.0 for lam in w])
        return mf, mf_one, mf * A[:, None, None]
    inside = grid.inside
    wo = grid.directions()
    h = wi[None, None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
    c2 = cos2_eta_i(wi, h)   # each cell's facet turns the macro s/p basis by η_i (Priest & Germer 2000)
    mf = np.empty(shape)
    coherent = np.empty(shape)
    f1 = np.where(inside, specular(wi, wo, fresnel="one", **micro.kw()), 0.0)
    # a stack's R(θ) varies within a cell, a slope table's D is a histogram finer than a cell: cell averages
    # (module doc)
    whole = scatter.is_stack(material) or micro.ndf == "tabulated"
    stack = whole or coarse_micro_lobe(micro, grid, wi)
    sub_width = min(STACK_SUBCELL, micro_lobe_width(micro, wi) / 2)
    # a stack's or table's every cell; a squeezed lobe's cells about its mirror point (the others keep their centres)
    cells = inside if whole else inside & lobe_cells(grid, wi, micro)
    if stack:
        sub = SubCells(wi, grid, micro, cells, sub_width)
        f1[cells] = sub.mean(1.0)
    grid_rho = float(f1.sum()) * grid.du * grid.dv
    if reference_grid is not None:  # a patch: the quadrature of the whole grid it belongs to
        ref = reference_grid
        f_ref = np.where(ref.inside, specular(wi, ref.directions(), fresnel="one", **micro.kw()), 0.0)
        if stack:
            ref_cells = ref.inside if whole else ref.inside & lobe_cells(ref, wi, micro)
            f_ref[ref_cells] = SubCells(wi, ref, micro, ref_cells, sub_width).mean(1.0)
        grid_rho = float(np.sum(f_ref)) * ref.du * ref.dv
    rho = float(albedo(wi, fresnel="one", **micro.kw()))
    if grid_rho > 0:
        f1 = f1 * (rho / grid_rho)
    used = inside if nano is None or nano.surface is None else inside & significant_cells(np.where(inside, f1, 0))

    def one(i):
        """mf and the coherent part at wavelength *i*: the wavelengths in parallel threads (the first incidence
        builds every wavelength's band series and albedo tables here, ~0.5 s CPU each)."""
        lam = w[i]
        mf[i] = f1 * (F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam))
        A = np.ones(cos_d.shape)
        if sigma_nano > 0:
            A[:] = nano.coherent_fraction(wi[2], lam, diffraction, material, polarization, phi)
            if used.any():
                A[used] = facet_coherent_fraction(nano, cos_d[used], c2[used], lam, diffraction, material,
                                                  polarization, phi)
        coherent[i] = mf[i] * A
        if stack:   # F and F·A averaged over each cell, weighted by the F = 1 lobe (cells of f1 = 0 stay 0)
            Fs = sub.fresnel(F, lam)
            A_sub = np.ones(Fs.shape)
            if sigma_nano > 0:
                A_sub[:] = nano.coherent_fraction(wi[2], lam, diffraction, material, polarization, phi)
                u_sub = used[cells]
                if u_sub.any():
                    A_sub[u_sub] = facet_coherent_fraction(nano, sub.cos_d[u_sub], sub.c2[u_sub], lam, diffraction,
                                                           material, polarization, phi)
            mf[i][cells] = f1[cells] * sub.weighted(Fs)
            coherent[i][cells] = f1[cells] * sub.weighted(Fs * A_sub)

    parallel_map(one, range(w.size))
    return (np.where(inside, mf, 0.0), np.broadcast_to(np.where(inside, f1, 0.0), shape),
            np.where(inside, coherent, 0.0))


class SubCells:
    """The sub-cells, at most *width* wide (and at most :data:`SUBCELLS_MAX` per cell side), of the cells *cells*
    (mask (n_v, n_u)) of *grid*, and
    the F = 1 micro lobe f_mf at their centres (composite midpoint rule): :meth:`mean` gives cell averages
    ∫_cell f_mf X du dv / (du dv), :meth:`weighted` the lobe-weighted averages ∫_cell f_mf X / ∫_cell f_mf (0
    where f_mf vanishes in the whole cell). Sub-cells outside the unit disc weigh 0. Attributes ``cos_d`` and ``c2``
    (n_cells, s, s): cos θ_d and cos²η_i of each sub-cell's facet (half-vector).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (20) (the microfacet lobe f_mf = F G D / (4 cosθ_i cosθ_o)).
    .. [2] P. J. Davis, P. Rabinowitz, *Methods of Numerical Integration*, 2nd ed., 1984, §2.2 (composite midpoint
       rule).
    """

    def __init__(self, wi, grid: DirectionGrid, micro: Micro, cells, width: float = STACK_SUBCELL):
        s = min(max(1, int(np.ceil(max(grid.du, grid.dv) / width - 1e-9))), SUBCELLS_MAX)
        rows, cols = np.nonzero(cells)
        off = (np.arange(s) + 0.5) / s
        u = grid.u_range[0] + (cols[:, None, None] + off[None, None, :]) * grid.du      # (n, 1, s)
        v = grid.v_range[0] + (rows[:, None, None] + off[None, :, None]) * grid.dv      # (n, s, 1)
        u, v = np.broadcast_arrays(u, v)
        r2 = u * u + v * v
        ok = r2 < 1.0
        wo = np.stack([u, v, np.sqrt(np.maximum(1.0 - r2, 0.0))], axis=-1)
        self.wi, self.wo = wi, np.where(ok[..., None], wo, np.array([0.0, 0.0, 1.0]))
        h = wi + self.wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        self.cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
        self.c2 = cos2_eta_i(wi, h)
        self.f1 = np.where(ok, specular(wi, self.wo, fresnel="one", **micro.kw()), 0.0)
        self._den = np.sum(self.f1, axis=(1, 2))

    def fresnel(self, F, lam):
        """F at each sub-cell (n_cells, s, s): R(θ_d), or the facet's polarized reflectance (``F.at``)."""
        Fs = F.at(self.wi, self.wo, lam) if hasattr(F, "at") else F(self.cos_d, lam)
        return np.broadcast_to(np.asarray(Fs, dtype=float), self.f1.shape)

    def mean(self, x):
        """∫_cell f_mf x du dv / (du dv) per cell (n_cells,)."""
        return np.mean(self.f1 * x, axis=(1, 2))

    def weighted(self, x):
        """∫_cell f_mf x / ∫_cell f_mf per cell (n_cells,); 0 where f_mf is 0 in the whole cell."""
        den = self._den
        return np.where(den > 0, np.sum(self.f1 * x, axis=(1, 2)) / np.where(den > 0, den, 1.0), 0.0)
