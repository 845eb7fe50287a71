"""The coherent part of the two-scale BRDF on a direction grid: the microfacet specular lobe with F, times the
coherent fraction A(λ, θ_d) of each facet (:meth:`waveoptics.brdf.Nano.coherent_fraction`; docs/physics.md §7, §9).

A micro lobe narrower than a cell (α ≲ du) cannot be sampled: its energy F·A·ρ_mf is deposited in the mirror cell as a
spike of height E/(du dv), which keeps albedo and colour exact on the grid.

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (coherent part of the two-scale model).
.. [2] H. Davies, Proc. IEE 101, 209 (1954) (coherent fraction).
"""
from __future__ import annotations

import numpy as np

from ..materials import cos2_eta_i
from ..scatter.grid import DirectionGrid
from .facet_polarization import facet_coherent_fraction
from .microfacet import specular
from .quadrature import albedo
from .roughness_scales import Micro, Nano
from .twoscale_grid import azimuth_deg, fresnel_at_mirror, mirror_cell, sharp_micro_lobe, significant_cells

__all__ = ['coherent_lobe']


def coherent_lobe(wi, wavelengths_nm, F, micro: Micro, nano: Nano | None, grid: DirectionGrid, diffraction,
                  material, polarization: str = "unpolarized", reference_grid: DirectionGrid | None = None):
    """(microfacet lobe f_mf with F, the same lobe with F = 1, coherent part A f_mf), each (n_λ, n_v, n_u) in 1/sr.

    The F = 1 lobe is all the light the facets receive (a dielectric's diffracted budget). Its cell quadrature is
    scaled to the accurate quadrature albedo ρ_mf (:func:`waveoptics.brdf.albedo`; of *reference_grid* when *grid* is
    a patch of it): near grazing a narrow lobe is squeezed against the rim of the (u, v) disc and the cell
    quadrature over- or under-counts it. A is evaluated per cell at the facet's local incidence θ_d = ∠(ω_i, h);
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
    grid_rho = float(f1.sum()) * grid.du * grid.dv
    if reference_grid is not None:  # a patch: the quadrature of the whole grid it belongs to
        ref = reference_grid
        f_ref = specular(wi, ref.directions(), fresnel="one", **micro.kw())
        grid_rho = float(np.sum(np.where(ref.inside, f_ref, 0.0))) * ref.du * ref.dv
    rho = float(albedo(wi, fresnel="one", **micro.kw()))
    if grid_rho > 0:
        f1 = f1 * (rho / grid_rho)
    used = inside if nano is None or nano.surface is None else inside & significant_cells(np.where(inside, f1, 0))
    for i, lam in enumerate(w):
        mf[i] = f1 * (F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam))
        A = np.ones(cos_d.shape)
        if sigma_nano > 0:
            A[:] = nano.coherent_fraction(wi[2], lam, diffraction, material, polarization, phi)
            if used.any():
                A[used] = facet_coherent_fraction(nano, cos_d[used], c2[used], lam, diffraction, material,
                                                  polarization, phi)
        coherent[i] = mf[i] * A
    return (np.where(inside, mf, 0.0), np.broadcast_to(np.where(inside, f1, 0.0), shape),
            np.where(inside, coherent, 0.0))
