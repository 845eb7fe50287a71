"""The diffracted lobe of a nano height field and its albedo (the coherent fraction of a height field's facets).

The Kirchhoff field of the patch minus its coherent part, δU = U − χ̂ U_flat, as a BRDF
(:func:`kirchhoff_scattered_lobe`), and the share of the specular light it scatters at one incidence
(:func:`field_scattered_albedo`, tabulated over :data:`FIELD_THETAS_DEG` by
:meth:`waveoptics.brdf.Nano.coherent_fraction`).

References
----------
.. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, 1963, ch. 5
   (coherent and incoherent fields).
.. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (only the propagating band scatters).
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .. import scatter
from ..runtime import get_runtime
from ..scatter.grid import DirectionGrid, integrate
from ..scatter.kirchhoff import cos_theta_d
from ..scatter.tangent_blend import (blend_weight, first_order_over_fresnel, tangent_plane_weight,
                                     uses_vector_first_order)
from ..surfaces.heightfield import HeightField
from ..units import check_wavelengths

__all__ = ['BAND_MARGIN_BINS', 'band_limited_field', 'kirchhoff_scattered_lobe', 'lobe_sampling_warnings', 'nyquist_band', 'fresnel_at_pairs',
           'field_first_order_over_fresnel', 'field_scattered_lobe', 'FIELD_THETAS_DEG',
           'FIELD_GRID_OVERSAMPLING', 'field_cell_split', 'field_cells_resolve', 'field_cell_averages', 'field_scattered_albedo', 'bracketing_nodes', 'ISOTROPIC_FIELD_MODELS',
           'ANISOTROPIC_FIELD_MODELS', 'ISOTROPY_SECTORS', 'ISOTROPY_MAX_RATIO', 'field_anisotropy',
           'field_proposal_model']


#: frequency bins (1/L) by which :func:`band_limited_field` widens the propagating band: the main lobe of the
#: Hann window (± 2 bins) and half a direction cell
BAND_MARGIN_BINS = 3.0


def band_limited_field(surface: HeightField, wavelength_nm: float, wi) -> HeightField:
    """The height field restricted to the surface frequencies that scatter light of *wavelength_nm* (nm) incident
    from *wi* into propagating directions: the disc D = {|f + (ω_i,x, ω_i,y)/λ| ≤ 1/λ} of
    :mod:`waveoptics.scatter.band` and its mirror image −D (the union keeps the heights real), each widened by
    :data:`BAND_MARGIN_BINS` frequency bins 1/L (the Hann window's main lobe: without it the cells at the rim of
    the direction disc lose 5 % of their light, measured on ABC fields at 20°).

    Roughness outside the band diffracts only into evanescent orders: by the relevant-roughness argument it
    neither scatters nor reduces the specular reflection, whereas inside the Kirchhoff integral its phase
    modulation exp(i v_z h_beyond) would damp the in-band lobe by exp(−g_beyond), g_beyond = (v_z σ_beyond)², and
    hand that light to the coherent part. The filter is a DFT mask, exact for a periodic (generated) field; invalid
    samples are filled with the mean of the valid ones before filtering and stay masked. The part of −D outside D
    is kept although it does not scatter either (at normal incidence D = −D); its share of σ² is small next to
    the band's.

    References
    ----------
    .. [1] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness: the band
       D scatters, the rest neither scatters nor reduces the specular beam).
    .. [2] J. E. Harvey, N. Choi, S. Schröder, A. Duparré, Opt. Eng. 51(1) 013402, 2012 (total integrated scatter
       of the band-limited roughness).
    """
    ny, nx = surface.shape
    valid = surface.valid
    h = np.where(valid, surface.heights, np.mean(surface.heights[valid]))
    fy = np.fft.fftfreq(ny, surface.dy)[:, None]
    fx = np.fft.fftfreq(nx, surface.dx)[None, :]
    # the Hann-windowed patch's directions see each frequency spread over ± 2 bins (1/L) of its window's main
    # lobe, so the band is widened by BAND_MARGIN_BINS bins: the rim's cells keep their light
    R = 1.0 / (float(wavelength_nm) * 1e-9) + BAND_MARGIN_BINS / min(nx * surface.dx, ny * surface.dy)
    cx, cy = float(wi[0]) / (float(wavelength_nm) * 1e-9), float(wi[1]) / (float(wavelength_nm) * 1e-9)
    keep = (np.hypot(fx + cx, fy + cy) <= R) | (np.hypot(fx - cx, fy - cy) <= R)
    hb = np.fft.ifft2(np.fft.fft2(h) * keep).real
    return dataclasses.replace(surface, heights=hb, meta={**surface.meta, "band_limited_nm": float(wavelength_nm)})


def kirchhoff_scattered_lobe(surface: HeightField, wi, grid: DirectionGrid, wavelengths_nm, F, *,
                             solver: str = "fft", device=None, precision: str = "float32", warnings=None,
                             diffraction="kirchhoff", band_limit: bool = True):
    """Incoherent Kirchhoff lobe of a height field: the field minus its coherent (mean) part, as a BRDF (1/sr).

    δU = U − χ̂ U_flat, with χ̂ the patch estimate of ⟨exp(i v_z h)⟩ (:func:`waveoptics.scatter.
    coherent_amplitude`) and U_flat the field of the same window without heights, removes the specular spike
    (which the two-scale model carries as the micro lobe × A) and keeps the diffracted light; the BRDF follows
    docs/physics.md §1 (:func:`waveoptics.scatter.brdf_from_field`). ``fft`` evaluates the whole grid
    (frozen-v_z expansion, see :mod:`waveoptics.scatter`); ``direct`` sums the integral on the OpenCL device
    for every grid direction inside the disc.

    With *band_limit* (the default) each wavelength's field is computed on the heights restricted to the surface
    frequencies that can scatter it (:func:`band_limited_field`), as the PSD route's series
    (:class:`waveoptics.scatter.BandSeries`) takes only the relevant roughness: the roughness beyond the band
    would otherwise damp the lobe by exp(−g_beyond) through its phase modulation, a Kirchhoff artefact (a 1-D
    method-of-moments check on a perfect conductor finds no such damping). ``band_limit=False`` is the plain
    Kirchhoff integral of the whole field. Directions outside the sampled field's band (:func:`nyquist_band`) are 0:
    a field sampled coarser than λ/4 would send them a replica of the band's light.

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963, ch. 5 (coherent and incoherent fields); docs/physics.md §1-§2.
    .. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness).
    """
    w = check_wavelengths(wavelengths_nm)
    smp = scatter.samples(surface)
    for msg in lobe_sampling_warnings(smp, wi, grid, w):   # once for all wavelengths: the shortest's conditions
        scatter.solvers.warn_or_collect(msg, warnings)
    if band_limit:
        with scatter.diffraction_warnings_held([]):   # each wavelength's own lines would repeat the ones above
            return np.concatenate([kirchhoff_scattered_lobe(band_limited_field(surface, lam, wi), wi, grid, [lam],
                                                            F, solver=solver, device=device, precision=precision,
                                                            diffraction=diffraction, band_limit=False)
                                   for lam in w])
    flat = dataclasses.replace(smp, h=np.zeros_like(smp.h))
    dirs = grid.directions()
    inside = grid.inside
    out = np.zeros((w.size, grid.n_v, grid.n_u))
    chi = np.array([scatter.coherent_amplitude(smp, wi, lam, diffraction) for lam in w])
    sol = scatter.get_solver(solver)
    opts = dict(runtime=get_runtime(device) if solver == "direct" else None, precision=precision,
                diffraction=diffraction)
    U, _ = sol.grid_field(smp, wi, grid, w, **opts)
    U0, _ = sol.grid_field(flat, wi, grid, w, **opts)
    out[:, inside] = scatter.brdf_from_field((U - chi[:, None, None] * U0)[:, inside], wi, dirs[inside], w,
                                             smp.area, F, diffraction)
    return np.where(inside & nyquist_band(smp, wi, grid, w), np.maximum(out, 0.0), 0.0)


def lobe_sampling_warnings(smp, wi, grid: DirectionGrid, wavelengths_nm) -> list[str]:
    """The lines :func:`kirchhoff_scattered_lobe` warns for a field's samples *smp*
    (:class:`waveoptics.scatter.Samples`) on *grid* at *wavelengths_nm* (nm), each for the shortest wavelength:
    aliasing (:func:`waveoptics.scatter.sampling_warnings` at the grid's directions; the replicas themselves are
    masked, :func:`nyquist_band`) and a direction grid coarser than the patch's diffraction width λ/L. The specular
    spike is removed (δU), but a periodic surface's orders and a patch's speckle are just as narrow (≈ λ/L): a
    coarser grid samples them at arbitrary points and their energy comes out wrong.

    References
    ----------
    .. [1] C. E. Shannon, Proc. IRE 37(1), 10–21, 1949 (a sampled function's band); docs/physics.md §1.
    """
    w = np.asarray(wavelengths_nm, dtype=float)
    msgs = scatter.sampling_warnings(smp, wi, w, wo=grid.directions()[grid.inside])
    Lx, Ly = smp.extent
    lmin = float(w.min()) * 1e-9
    if grid.du > lmin / Lx * (1 + 1e-9) or grid.dv > lmin / Ly * (1 + 1e-9):
        need = int(np.ceil(2 * max(Lx, Ly) / lmin))
        msgs.append(f"direction grid cell {grid.du:.3g} is coarser than the patch's diffraction width lambda/L = "
                    f"{lmin / max(Lx, Ly):.3g}: sharp features (grating orders, speckle) are under-sampled and "
                    f"their energy is inexact; use resolution >= {need} or a smaller patch")
    return msgs


def nyquist_band(smp, wi, grid: DirectionGrid, wavelengths_nm) -> np.ndarray:
    """Mask (n_λ, n_v, n_u) of the directions whose surface frequency (u_i + u_o, v_i + v_o)/λ lies in the
    sampled field's principal band |f_x| ≤ 1/(2 dx), |f_y| ≤ 1/(2 dy) (*smp*: :class:`waveoptics.scatter.Samples`).

    The Kirchhoff sum over samples is periodic in (u_i + u_o) dx/λ with period 1: beyond the band a field sampled
    coarser than λ/4 returns the light of the band once more (a replica), counted as if it were scattered there.
    The samples define the surface whose spectrum is the band's (Whittaker-Shannon), so the replicas are no light:
    measured on the brushed-aluminium scene's scratches (250 nm wide, 40 nm deep) sampled at 312 nm, the replicas
    made the diffracted share at 40° 0.81 at 380 nm, 5.6x the periodic field's Kirchhoff order sum (0.145); masked,
    0.141 (tests/test_field_cells.py). A field sampled at dx ≤ λ/4 has the whole disc in its band.

    References
    ----------
    .. [1] C. E. Shannon, Proc. IRE 37(1), 10–21, 1949 (a sampled function's band); R. N. Bracewell, *The Fourier
       Transform and its Applications*, 3rd ed., ch. 10 (the DFT's periodic replicas).
    """
    lam = np.asarray(wavelengths_nm, dtype=float)[:, None, None] * 1e-9
    d = grid.directions()
    return ((np.abs(wi[0] + d[None, ..., 0]) * smp.dx <= lam / 2)
            & (np.abs(wi[1] + d[None, ..., 1]) * smp.dy <= lam / 2))


def fresnel_at_pairs(F, wi, wo, wavelength_nm) -> np.ndarray:
    """F of the pairs (ω_i, ω_o) (..., 3) as :func:`waveoptics.scatter.brdf_from_field` applies it: 1 for None,
    ``F.at(ω_i, ω_o, λ)`` (polarized light, relative weights), else F(cos θ_d, λ) at the half-vector angle."""
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    shape = np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1])
    if F is None:
        return np.ones(shape)
    if hasattr(F, "at"):
        return np.broadcast_to(np.asarray(F.at(wi, wo, wavelength_nm), dtype=float), shape)
    return np.broadcast_to(np.asarray(F(cos_theta_d(wi, wo), wavelength_nm), dtype=float), shape)


def field_first_order_over_fresnel(psd, wi, wo, wavelength_nm, material=None,
                                   polarization: str = "unpolarized") -> np.ndarray:
    """f_RR / F (1/sr) of a height field at paired directions (n, 3): the first-order Rayleigh-Rice lobe whose PSD
    is the field's periodogram *psd* (:class:`waveoptics.surfaces.PeriodogramPSD`), over the Kirchhoff family's
    Fresnel factor F at each pair, as the PSD route's tables hold it
    (:func:`waveoptics.scatter.tangent_blend.first_order_over_fresnel`): the vector Q of a *material* with a complex
    index (and Elson's factor of a stack) divided by its facet reflectance, else the scalar Q = 1 lobe
    (16π²/λ⁴) cosθ_i cosθ_o S(f) that F multiplies as it does the tangent-plane lobe.

    References
    ----------
    .. [1] E. L. Church, H. A. Jenkinson, J. M. Zavada, Opt. Eng. 18(2), 125–136, 1979 (first order with a PSD).
    .. [2] J. M. Elson, J. M. Bennett, Opt. Eng. 18(2), 116–124, 1979 (the vector factor Q).
    """
    lam = float(wavelength_nm)
    Fl = ((lambda a, b: material.F_facet(a, b, lam, polarization)) if uses_vector_first_order(material) else None)
    return first_order_over_fresnel(wi, wo, lam, psd, material, polarization, Fl)


def field_scattered_lobe(surface: HeightField, wi, grid: DirectionGrid, wavelengths_nm, F, *, psd=None,
                         material=None, polarization: str | None = None, solver: str = "fft", device=None,
                         precision: str = "float32", warnings=None, diffraction="kirchhoff") -> np.ndarray:
    """The diffracted lobe (n_λ, n_v, n_u) in 1/sr a height field's facets carry: its Kirchhoff lobe
    (:func:`kirchhoff_scattered_lobe`) handed over to first order towards grazing angles as the PSD route's is,

        f = W f_K + (1 − W) (f_RR / F) F,    W = w(θ_i) w(θ_o)   (:mod:`waveoptics.scatter.tangent_blend`),

    f_RR the Rayleigh-Rice lobe of the field's periodogram *psd* (:func:`field_first_order_over_fresnel`; computed
    from *surface* when None) and F the factor *F* the Kirchhoff lobe carries (:func:`fresnel_at_pairs`). The
    tangent-plane lobe's albedo grows as 1/cosθ_i towards grazing incidence (Al, a generated ABC field σ 8 nm at
    550 nm: 5.1x / 40x the first-order TIS of its periodogram at 88° / 89°), first order holds as kσ cosθ → 0
    (Thorsos & Jackson 1989), and W is symmetric in ω_i and ω_o. From θ_i ≥ 80° (W = 0) the Kirchhoff lobe is not
    computed. Rayleigh-Rice (*diffraction* perturbative) is the Kirchhoff lobe's own route and is returned as it is.

    The PSD route's grid lobe is the same blend (:func:`waveoptics.brdf.nano_lobe`), as are the facet tables and
    the pointwise form's lobe: ensembles of generated fields follow the PSD route direction by direction
    (tests/test_generated_fields.py).

    References
    ----------
    .. [1] E. I. Thorsos, JASA 83(1), 78–92, 1988 (the tangent plane fails towards grazing angles).
    .. [2] E. I. Thorsos, D. R. Jackson, JASA 86(1), 261–277, 1989 (first order holds as kσ cosθ → 0).
    .. [3] E. L. Church, H. A. Jenkinson, J. M. Zavada, Opt. Eng. 18(2), 125–136, 1979 (Rayleigh-Rice with a PSD).
    """
    w = check_wavelengths(wavelengths_nm)
    wi = np.asarray(wi, dtype=float)
    dm = scatter.get_model(diffraction, perturbative=True)
    kw = dict(solver=solver, device=device, precision=precision, warnings=warnings, diffraction=diffraction)
    if dm.perturbative:
        return kirchhoff_scattered_lobe(surface, wi, grid, w, F, **kw)
    wo = grid.directions()
    W = blend_weight(wi, wo)
    far = grid.inside & (W < 1.0)
    grazing = float(tangent_plane_weight(wi[2])) == 0.0
    f_k = (np.zeros((w.size, grid.n_v, grid.n_u)) if grazing
           else np.array(kirchhoff_scattered_lobe(surface, wi, grid, w, F, **kw), dtype=float))
    if not far.any():
        return f_k
    out = f_k.copy()
    if psd is None:
        from ..surfaces import PeriodogramPSD

        psd = PeriodogramPSD(surface)
    pol = polarization or getattr(F, "polarization", "unpolarized")
    wo_f = wo[far]
    wi_f = np.broadcast_to(wi, wo_f.shape)
    for i, lam in enumerate(w):
        rr = field_first_order_over_fresnel(psd, wi_f, wo_f, lam, material, pol) * fresnel_at_pairs(F, wi_f, wo_f,
                                                                                                     lam)
        out[i][far] = W[far] * out[i][far] + (1.0 - W[far]) * rr
    return out


#: facet incidences θ_d (degrees) at which a height field's scattered share E_field is tabulated per wavelength
#: (:meth:`Nano.coherent_fraction`): denser towards grazing, where the tangent-plane lobe's albedo bends
FIELD_THETAS_DEG = np.array([0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 68.0, 75.0, 80.0, 84.0, 87.0, 89.0])
#: cells of the grid that integrates a height field's lobe are λ / (this × L) wide: |U|² varies on the scale
#: λ/(2L) (the window's autocorrelation spans 2L), and 3 is where its integral settles (Gaussian patch at 60°:
#: 1e-3 below at 2, within 2e-4 from 3 to 12; a heavy-tailed ABC C = 2.2 patch, whose speckle reaches the
#: horizon and its 1/cosθ_o obliquity, keeps ±0.5 % of cell-quadrature scatter at any of them)
FIELD_GRID_OVERSAMPLING = 3.0


def field_cell_split(surface: HeightField, grid: DirectionGrid, wavelength_nm: float) -> int:
    """Sub-cells r per axis that make *grid*'s cells at most 2 λ / (:data:`FIELD_GRID_OVERSAMPLING` L) wide (L the
    patch's larger side, *wavelength_nm* in nm): the cells on which a height field's lobe is averaged
    (:func:`field_cell_averages`); 1 where *grid* is that fine already."""
    ext = max(scatter.samples(surface).extent)
    return max(1, int(np.ceil(max(grid.du, grid.dv) * FIELD_GRID_OVERSAMPLING * ext / (2e-9 * float(wavelength_nm)))))


def field_cells_resolve(surface: HeightField, grid: DirectionGrid, wavelength_nm: float) -> bool:
    """Whether the centres of *grid*'s cells sum a height field's lobe at *wavelength_nm* (nm) exactly: cells at
    most λ/L_x by λ/L_y (L the patch's sides; Poisson summation of |Û|², :func:`waveoptics.scatter.sampling_warnings`).
    Coarser cells take :func:`field_cell_averages`."""
    Lx, Ly = scatter.samples(surface).extent
    lam = float(wavelength_nm) * 1e-9
    return grid.du <= lam / Lx * (1 + 1e-9) and grid.dv <= lam / Ly * (1 + 1e-9)


def field_cell_averages(lobe_on, grid: DirectionGrid, r: int) -> np.ndarray:
    """Cell averages (n_λ, n_v, n_u) on *grid* of a lobe ``lobe_on(fine)`` (n_λ, r n_v, r n_u) in 1/sr evaluated on
    the grid r times finer per axis (:func:`field_cell_split`), 0 at cells whose centre lies below the horizon. A
    cell across the rim of the disc holds the light of its part above the horizon (its mean with 0 below), so the
    grid sum is the fine grid's.

    A windowed patch's |U|² varies on the scale λ/(2L) (grating orders, speckle, the narrow streak of long
    scratches); the centres of cells up to λ/L wide sum it exactly (Poisson summation: its transform, the window's
    autocorrelation, spans |x| < L; :func:`field_cells_resolve`), those of coarser cells arbitrarily. Averaged over each cell, the grid
    sum is the fine grid's, the quadrature of :func:`field_scattered_albedo` (the budget the coherent part gives
    up). Measured on the brushed-aluminium scene's scratches (Al, 40°, 380 nm) on 16² cells: point samples held
    1.46 of the incident light against a budget of 0.75 (64 samples, with the replicas :func:`nyquist_band` removes;
    the two-scale energy guard then removed 49 %) and 0.0050 against 0.103 (the scene's 256 samples: the streak
    missed the cell centres, which no guard sees); averaged, 0.130 against 0.130 and 0.098 against 0.103 (the rest
    lies in rim cells below the horizon; tests/test_field_cells.py). The facet-frame route's tables are averaged
    on the same cells (:mod:`waveoptics.brdf.twoscale_frame`).

    References
    ----------
    .. [1] M. Parseval; R. N. Bracewell, *The Fourier Transform and its Applications*, 3rd ed., ch. 6 (the power
       of the field's samples).
    """
    if r <= 1:
        return np.where(grid.inside, lobe_on(grid), 0.0)
    fine = DirectionGrid(grid.n_u * r, grid.n_v * r, tuple(grid.u_range), tuple(grid.v_range))
    f = np.where(fine.inside, lobe_on(fine), 0.0)
    g = f.reshape(f.shape[0], grid.n_v, r, grid.n_u, r).mean(axis=(2, 4))
    return np.where(grid.inside, g, 0.0)


def field_scattered_albedo(surface: HeightField, theta_deg: float, wavelength_nm: float, diffraction="kirchhoff",
                           material=None, polarization: str = "unpolarized", azimuth_deg: float = 0.0,
                           psd=None) -> float:
    """E_field(θ): the share of the specularly reflected light that a height field's diffracted lobe scatters at
    incidence (θ, φ) (degrees), relative to F(θ) (unitless).

    The lobe is :func:`field_scattered_lobe`: the Kirchhoff lobe :func:`kirchhoff_scattered_lobe` (fft solver,
    exact Kirchhoff to its tolerance; the direct solver agrees to 1e-3) handed over to the first-order lobe of the
    field's periodogram *psd* (computed from *surface* when None) towards grazing angles, where the tangent-plane
    lobe's albedo grows as 1/cosθ_i (Al, ABC field σ 8 nm, 550 nm: E_field 0.10 at 89°, 0.19 at 89.5°, against a
    first-order TIS/R of 0.0025 and 0.0013; handed over, within 0.4 % of it from 75°,
    tests/test_heightfield_grazing.py), with each direction's Fresnel factor relative to the specular one
    (:class:`waveoptics.materials.RelativeFacetFresnel`; 1 without a *material*), integrated over a direction grid
    whose cells are λ/(3L) wide (L the patch's larger side, :data:`FIELD_GRID_OVERSAMPLING`), finer than the scale
    λ/(2L) on which |U|² varies, so that for a lobe inside the disc Σ f du dv is Parseval's sum of
    |U − χ̂ U_flat|², 1 − |χ̂|² when nothing is evanescent (measured 1e-4 on Gaussian patches). What the sum
    misses is the light of surface frequencies outside the propagating band, which does not scatter (the
    relevant roughness: Krywonos, Harvey & Choi 2011); the lobe is that of the band-limited heights
    (:func:`band_limited_field`), so the roughness beyond the band does not damp it either.

    References
    ----------
    .. [1] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness; only the
       propagating band scatters or reduces the specular reflection).
    .. [2] M. Parseval; Bracewell, *The Fourier Transform and its Applications*, 3rd ed., ch. 6 (Rayleigh's
       theorem: the power of a sequence equals that of its DFT samples).
    """
    from ..materials import RelativeFacetFresnel
    from ..units import direction_from_angles

    smp = scatter.samples(surface)
    n = int(np.ceil(FIELD_GRID_OVERSAMPLING * max(smp.extent) / (wavelength_nm * 1e-9)))
    grid = DirectionGrid.hemisphere(n)
    wi = direction_from_angles(theta_deg, azimuth_deg)
    # the lobe's own evaluation says what its sampling misses (held in this thread only: the budget's callers run
    # in a pool of threads, which warnings.catch_warnings would not leave alone)
    with scatter.diffraction_warnings_held([]):
        lobe = field_scattered_lobe(surface, wi, grid, [wavelength_nm], RelativeFacetFresnel(material, polarization),
                                    psd=psd, material=material, polarization=polarization, solver="fft",
                                    diffraction=diffraction)
    return float(integrate(lobe, grid)[0])



def bracketing_nodes(theta_lo: float, theta_hi: float) -> np.ndarray:
    """The :data:`FIELD_THETAS_DEG` nodes that bracket the facet incidences [θ_lo, θ_hi] (degrees)."""
    lo = np.searchsorted(FIELD_THETAS_DEG, theta_lo, side="right") - 1
    hi = np.searchsorted(FIELD_THETAS_DEG, theta_hi, side="left")
    return FIELD_THETAS_DEG[max(lo, 0):hi + 1]



#: generators whose fields are realizations of a statistically isotropic random surface (:mod:`waveoptics.surfaces`)
ISOTROPIC_FIELD_MODELS = ("gaussian", "exponential", "abc", "flat")
#: generators whose fields have a direction (a grating, oriented scratches, square flake cells)
ANISOTROPIC_FIELD_MODELS = ("sinusoid", "scratches", "flakes")
#: azimuth sectors over [0°, 180°) in which :func:`field_anisotropy` sums a field's slope spectrum
ISOTROPY_SECTORS = 4
#: largest ratio of the largest to the smallest sector's slope power of a field taken as isotropic: a random
#: isotropic patch fluctuates by tens of percent per sector (a periodogram is a χ² of 2 degrees of freedom per
#: frequency), a sinusoid or brushed metal by orders of magnitude
ISOTROPY_MAX_RATIO = 2.0


def field_anisotropy(surface: HeightField) -> str | None:
    """None when *surface* is taken as statistically isotropic (its lobe at any azimuth of incidence is the
    azimuth-0 lobe turned), else the reason it is not (a sentence).

    A field generated by a model of :data:`ISOTROPIC_FIELD_MODELS` is isotropic by construction, one of
    :data:`ANISOTROPIC_FIELD_MODELS` is not; any other (measured, a sum) is isotropic when its slope spectrum
    |f|² |ĥ(f)|² summed over :data:`ISOTROPY_SECTORS` azimuth sectors of [0°, 180°) (the periodogram of a real
    field is even) varies by less than :data:`ISOTROPY_MAX_RATIO` from sector to sector.

    References
    ----------
    .. [1] J. A. Ogilvy, *Theory of Wave Scattering from Random Rough Surfaces*, 1991, §2.2 (an isotropic surface's
       spectrum depends on |f| only).
    """
    model = surface.meta.get("model")
    if model in ISOTROPIC_FIELD_MODELS:
        return None
    if model in ANISOTROPIC_FIELD_MODELS:
        return f"the height field (model {model!r}) is anisotropic"
    h = np.asarray(surface.heights, dtype=float)
    h = np.where(surface.mask, h - h[surface.mask].mean(), 0.0) if surface.mask is not None else h - h.mean()
    P = np.abs(np.fft.fft2(h)) ** 2
    fy = np.fft.fftfreq(h.shape[0], surface.dy or surface.dx)
    fx = np.fft.fftfreq(h.shape[1], surface.dx)
    FX, FY = np.meshgrid(fx, fy)
    phi = np.mod(np.arctan2(FY, FX), np.pi)
    sector = np.minimum((phi / np.pi * ISOTROPY_SECTORS).astype(int), ISOTROPY_SECTORS - 1)
    power = np.bincount(sector.ravel(), weights=(P * (FX ** 2 + FY ** 2)).ravel(), minlength=ISOTROPY_SECTORS)
    if power.max() <= 0:
        return None
    ratio = power.max() / max(power.min(), 1e-300 * power.max())
    if ratio < ISOTROPY_MAX_RATIO:
        return None
    return (f"the height field's slope spectrum varies {ratio:.3g}x between azimuth sectors (anisotropic above "
            f"{ISOTROPY_MAX_RATIO:g}x)")


def field_proposal_model(surface: HeightField):
    """A Gaussian :class:`waveoptics.surfaces.PSDModel` of the field's rms height and correlation length (the
    generator's ``corr_length`` or ABC ``B`` when recorded, else the 1/e lag of its autocovariance, else a quarter
    of the patch): only the width of the nano lobe that places quadrature nodes about each half-vector
    (:class:`waveoptics.brdf.facet.NanoRadial`) and picks their count; the lobe itself is the field's.

    References
    ----------
    .. [1] P. Beckmann, A. Spizzichino, 1963, ch. 5 (Gaussian correlation: lobe width λ/(π T)).
    """
    from ..surfaces import PSDModel
    from ..surfaces.statistics import correlation_length, rms_height

    T = surface.meta.get("corr_length") or surface.meta.get("B")
    if not T or not np.isfinite(T) or T <= 0:
        T = correlation_length(surface)
    if not np.isfinite(T) or T <= 0:
        T = 0.25 * max(scatter.samples(surface).extent)
    return PSDModel("gaussian", max(rms_height(surface), 1e-15), T=float(T))
