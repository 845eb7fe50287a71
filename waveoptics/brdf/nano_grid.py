"""The nano lobe f_n on a direction grid at the macro incidence (:func:`nano_lobe`): the PSD series, Rayleigh-Rice,
or a Kirchhoff solver on a height field, with energy-preserving sampling of a lobe narrower than the cells.

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale energy split).
.. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (band-limited relevant roughness).
"""
from __future__ import annotations

import numpy as np

from .. import scatter
from ..errors import FieldError, WaveopticsError, unknown
from ..scatter.grid import DirectionGrid, integrate
from ..units import check_wavelengths
from .field_lobe import (field_cell_averages, field_cell_split, field_cells_resolve, field_scattered_lobe,
                         lobe_sampling_warnings)
from ..scatter.tangent_blend import blend_with_first_order
from .roughness_scales import SERIES_MIN_CAPTURED, Nano
from .twoscale_grid import fresnel_at_mirror, mirror_cell

__all__ = ['NARROW_CELLS', 'nano_lobe', 'CORE_CELLS', 'CORE_SUBSAMPLE_STEP',
           'CORE_MAX_SUBSAMPLES']


#: a PSD nano lobe narrower than this many grid cells (width λ/(π T)) is resampled preserving its energy
NARROW_CELLS = 2.0


def nano_lobe(wi, wavelengths_nm, nano: Nano, grid: DirectionGrid, F, *, solver: str = "auto",
              device=None, precision="float32", diffraction="kirchhoff", material=None):
    """The diffracted (incoherent) nano lobe f_n (n_λ, n_v, n_u) in 1/sr for incidence *wi* on *grid*.

    Parameters
    ----------
    F : callable (cos_theta_d, wavelength_nm) -> reflectance
        Fresnel factor at the half-vector angle (docs/physics.md §1).
    solver : str
        ``"psd"`` (statistics), ``"fft"`` or ``"direct"`` (height field), ``"auto"`` picks by what is given.
    """
    w = check_wavelengths(wavelengths_nm)
    wo = grid.directions()
    wi = np.asarray(wi, dtype=float)
    h = wi[None, None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
    if solver == "auto":
        solver = "psd" if nano.model is not None else "fft"
    dm = scatter.get_model(diffraction, perturbative=True)
    if dm.perturbative:   # Rayleigh-Rice: the PSD's first-order lobe with its own polarization factor Q (no F)
        psd = nano.model if nano.model is not None else nano.periodogram()
        if nano.surface is not None:   # the periodogram of samples coarser than λ/4 folds the band (as Kirchhoff's)
            for msg in lobe_sampling_warnings(scatter.samples(nano.surface), wi, grid, w):
                scatter.solvers.warn_or_collect(msg)
        pol = getattr(F, "polarization", "unpolarized")
        out = np.stack([np.where(grid.inside, scatter.rayleigh_rice_lobe(wi[None, None, :], wo, lam, psd, material,
                                                                         pol), 0.0) for lam in w])
        if nano.model is not None and (np.min(w) * 1e-9 / (np.pi * nano.model.length_scale)
                                       < NARROW_CELLS * max(grid.du, grid.dv)):
            out = _resample_narrow_lobe(out, wi, w, nano, grid, F, dm, material)
        return out
    if solver == "psd":
        if nano.model is None:
            raise WaveopticsError("solver 'psd' needs nano statistics, not a height field; use fft or direct")
        out = np.empty((w.size, grid.n_v, grid.n_u))
        pol = getattr(F, "polarization", "unpolarized")
        for i, lam in enumerate(w):
            Fi = F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam)
            f_k, cap = scatter.scattered_lobe(wi, wo, lam, nano.model, F=1.0, return_captured=True,
                                              diffraction=diffraction)
            # beyond the tangent plane's validity the lobe hands over to first order (W f_K + (1 − W) f_RR,
            # W = w(θ_i) w(θ_o): waveoptics.scatter.tangent_blend), the lobe the facet tables and the pointwise
            # form carry; its albedo is the continued one (BandSeries.scattered_albedo)
            out[i] = Fi * blend_with_first_order(f_k, wi, wo, lam, nano.model, material, pol, Fi)
            # guard: the truncated series misses the light of its terms m > m_max once g = (kσ(cosθ_i + cosθ_o))²
            # ≳ 30 (σ ≳ λ/2): refuse rather than return a lobe that silently lacks that energy
            low = float(np.min(np.where(grid.inside, cap, 1.0)))
            if low < SERIES_MIN_CAPTURED:
                raise WaveopticsError(
                    f"nano-roughness sigma = {nano.model.sigma * 1e9:.4g} nm is too rough for the PSD series at "
                    f"{lam:g} nm (it holds only {100 * low:.3g}% of the scattered light in some directions); use a "
                    "nano height field (solver fft or direct), or describe roughness this large by the micro "
                    "NDF (alpha)")
        out = np.where(grid.inside, out, 0.0)
        if np.min(w) * 1e-9 / (np.pi * nano.model.length_scale) < NARROW_CELLS * max(grid.du, grid.dv):
            out = _resample_narrow_lobe(out, wi, w, nano, grid, F, diffraction, material)
        return out
    if solver in ("fft", "direct"):
        if nano.surface is None:
            raise FieldError(f"solver {solver!r} needs a nano height field ({{surface}} or {{nano}} MODEL:...)", 'surface', 'nano')
        # the Kirchhoff lobe handed over to the first order of the field's periodogram towards grazing angles, as
        # the PSD route's; averaged over each cell where the cells are coarser than λ/L, which their centres no
        # longer sum exactly
        held = {float(lam): [] for lam in w}

        def one(lam):
            with scatter.diffraction_warnings_held(held[float(lam)]):
                return field_cell_averages(
                    lambda g: field_scattered_lobe(nano.surface, wi, g, [lam], F, psd=nano.periodogram(),
                                                   material=material, solver=solver, device=device,
                                                   diffraction=diffraction, precision=precision),
                    grid, 1 if field_cells_resolve(nano.surface, grid, lam) else field_cell_split(nano.surface, grid,
                                                                                                  lam))
        out = np.concatenate([one(lam) for lam in w])
        # said once per run, not per wavelength: the shortest's lines (aliasing, dx > λ/(2|u_i + u_o|), and a cell
        # wider than λ/L are both strictest there) hold every other wavelength's
        for msg in held[float(np.min(w))]:
            scatter.solvers.warn_or_collect(msg)
        return out
    raise unknown("solver", solver, ("auto", "psd", "fft", "direct"))


#: cells whose centre lies within this many cells of the mirror direction form the core of a narrow nano lobe:
#: they are cell-averaged (:func:`_resample_narrow_lobe`); beyond, the point samples of a power-law tail
#: f ∝ ρ^−C are within C² / (24 (ρ/du)²) of the cell average (≤ 2.3 % for C ≤ 3 at 4 cells)
CORE_CELLS = 4.0
#: sub-samples per core cell and axis resolve the lobe to this fraction of its width or of the cell's distance
#: from the mirror, whichever is larger (between 2 and :data:`CORE_MAX_SUBSAMPLES` per axis)
CORE_SUBSAMPLE_STEP = 0.125
CORE_MAX_SUBSAMPLES = 64


def _lobe_at(wi, wo, lam, nano: Nano, F, diffraction, material):
    """The PSD nano lobe (1/sr) at directions *wo* (..., 3): the functions :func:`nano_lobe` samples the grid with
    (the Rayleigh-Rice lobe with its own Q, or the Kirchhoff series with F at each half-vector)."""
    dm = scatter.get_model(diffraction, perturbative=True)
    if dm.perturbative:
        return scatter.rayleigh_rice_lobe(wi[None, :], wo, lam, nano.model, material,
                                          getattr(F, "polarization", "unpolarized"))
    h = wi[None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
    Fi = F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam)
    return scatter.scattered_lobe(wi, wo, lam, nano.model, F=Fi, diffraction=diffraction)


def _core_cell_averages(wi, lam, nano: Nano, grid: DirectionGrid, F, diffraction, material, width):
    """(core mask (n_v, n_u), cell averages of the lobe over the core cells): each cell within
    :data:`CORE_CELLS` cells of the mirror direction, sub-sampled at midpoints of a regular n × n split, n set by
    :data:`CORE_SUBSAMPLE_STEP` of max(lobe *width*, the cell's distance from the mirror); sub-samples below the
    horizon count as 0 (the cell's share of the disc)."""
    mu, mv = -wi[0], -wi[1]
    cell = max(grid.du, grid.dv)
    U, V = np.meshgrid(grid.u, grid.v)
    core = grid.inside & (np.hypot(U - mu, V - mv) <= CORE_CELLS * cell)
    rows, cols = np.nonzero(core)
    if rows.size == 0:   # the mirror direction lies off the grid
        return core, np.zeros(0)
    pts, owner, count = [], [], np.zeros(rows.size)
    for k, (i, j) in enumerate(zip(rows, cols)):
        # distance from the mirror to the nearest point of the cell: the scale the lobe varies on there
        near = np.hypot(max(abs(grid.u[j] - mu) - grid.du / 2, 0.0), max(abs(grid.v[i] - mv) - grid.dv / 2, 0.0))
        n = int(np.clip(np.ceil(cell / (CORE_SUBSAMPLE_STEP * max(width, near))), 2, CORE_MAX_SUBSAMPLES))
        t = (np.arange(n) + 0.5) / n - 0.5
        su, sv = np.meshgrid(grid.u[j] + t * grid.du, grid.v[i] + t * grid.dv)
        up = su**2 + sv**2 < 1.0
        pts.append(np.stack([su[up], sv[up]], axis=-1))
        owner.append(np.full(int(up.sum()), k))
        count[k] = n * n
    uv = np.concatenate(pts)
    wo = np.concatenate([uv, np.sqrt(1.0 - np.sum(uv**2, axis=-1))[:, None]], axis=-1)
    f = _lobe_at(wi, wo, lam, nano, F, diffraction, material)
    return core, np.bincount(np.concatenate(owner), weights=f, minlength=rows.size) / count


def _resample_narrow_lobe(out, wi, wavelengths_nm, nano: Nano, grid: DirectionGrid, F, diffraction="kirchhoff",
                          material=None):
    """Energy-preserving sampling of a nano lobe narrower than the grid cells (PSD route).

    guard: the lobe's core is ~λ/(π T) wide in direction cosines; sampled at cell centres, a narrower one is missed
    or over-counted (measured: Au, σ = 20 nm, T = 30 µm, 128² grid: 18 % of the light at 450 nm lost). The cells
    near the mirror direction (the core, :data:`CORE_CELLS`) take the lobe's average over each cell instead of its
    centre value (:func:`_core_cell_averages`); the tail beyond keeps its point samples, which a heavy ABC tail's
    slow variation leaves accurate. The lobe's energy is then made its scattered albedo: on a conductor F(θ_i) · E,
    E = 1 − A the share of the reflected light the nano lobe scatters (:meth:`waveoptics.brdf.Nano.coherent_fraction`, the
    complement of the coherent fraction the specular lobe keeps, so the two add up to the reflected light; while
    the lobe is paraxial E ≈ 1 − exp(−g_i), g_i = (4πσ_rel cosθ_i / λ)², docs/physics.md §3, §9); on a dielectric
    the lobe's own absolute albedo (:meth:`waveoptics.scatter.BandSeries.scattered_albedo`), since there the coherent
    part is the Debye-Waller factor and not the complement of the scattered light. Only the core cells are scaled
    to reach it (the cell averages leave them within about 1 % of it); the tail, which the grid samples well, is
    never scaled: ABC σ = 10 nm, B = 200 µm, C = 3, 450 nm, 30°, 128² grid: the energy beyond 0.1 direction-cosine
    units within 2 % of a 1024² grid's (tests/test_narrow_lobes.py). When no core cell holds any of the lobe, that
    energy is deposited in the mirror cell (as a micro lobe narrower than a cell is, see :func:`waveoptics.brdf.evaluate`).

    References
    ----------
    .. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale energy split).
    .. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (band-limited relevant roughness).
    """
    cell = mirror_cell(grid, wi)
    pol = getattr(F, "polarization", "unpolarized")
    theta_i = float(np.degrees(np.arccos(np.clip(wi[2], 0.0, 1.0))))
    for i, lam in enumerate(wavelengths_nm):
        Fi = float(np.ravel(fresnel_at_mirror(F, wi, lam))[0])
        if scatter.is_conductor(material):   # the light the coherent lobe gives up, F(θ_i)(1 − A)
            energy = Fi * (1.0 - float(nano.coherent_fraction(wi[2], lam, diffraction, material, pol)))
        else:   # a dielectric's lobe keeps its own albedo (the coherent part is the Debye-Waller factor)
            energy = float(scatter.band_series(nano.model, float(lam)).scattered_albedo(
                theta_i, diffraction, material, pol, absolute=True))
        width = float(lam) * 1e-9 / (np.pi * nano.model.length_scale)
        core, avg = _core_cell_averages(wi, float(lam), nano, grid, F, diffraction, material, width)
        out[i][core] = avg
        tail = float(integrate(np.where(core, 0.0, out[i]), grid))
        in_core = float(np.sum(avg)) * grid.du * grid.dv
        rest = energy - tail
        if in_core > 0 and rest > 0:
            out[i][core] *= rest / in_core
        elif cell is not None and grid.inside[cell] and rest > 0:
            out[i, cell[0], cell[1]] += rest / (grid.du * grid.dv)
    return out

