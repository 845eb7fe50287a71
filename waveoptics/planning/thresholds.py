"""The planner's thresholds: the numbers each decision compares against (docs/planning.md lists them with the
decisions they drive; :mod:`waveoptics.planning.planner` says why each has its value).
"""
from __future__ import annotations

__all__ = ['ESTIMATE_RESOLUTION', 'ESTIMATE_RESOLUTION_MAX', 'ESTIMATE_STEP_NM', 'ESTIMATE_SPHERE_THETAS', 'ESTIMATE_SHARE', 'PSD_G_MAX',
           'FLAT_SCATTER', 'PLAN_RESOLUTION_RANGE', 'PATCH_SIGMAS', 'F_FLAT_TOL', 'FLOOR_MARGIN', 'KIRCHHOFF_GRAZING_DEG',
           'RAYLEIGH_RICE_G_MAX', 'FILM_NODES_PER_FRINGE']

#: cells per side of the coarse grid on which the colour shift of diffraction is estimated
ESTIMATE_RESOLUTION = 32
#: the finest grid the colour estimate refines to where the energy guard acts on the coarse one
#: (:func:`waveoptics.planning.colour_estimate.resolved_lobes`)
ESTIMATE_RESOLUTION_MAX = 128
#: wavelength step (nm) of the coarse estimate (line sources use their lines)
ESTIMATE_STEP_NM = 40.0
#: extra incidence angles (degrees) probed when a sphere camera sees every incidence
ESTIMATE_SPHERE_THETAS = (0.0, 45.0, 75.0)
#: diffraction runs when the estimated ΔE2000 exceeds this share of the target
ESTIMATE_SHARE = 0.5
#: largest g = (4πσ cosθ/λ)² for which the PSD series is trusted (scatter/series.py: truncation loses energy beyond)
PSD_G_MAX = 30.0
#: scattered fractions below this are "flat" (no estimate is run)
FLAT_SCATTER = 1e-9
#: smallest and largest direction grid (cells per side) the planner picks
PLAN_RESOLUTION_RANGE = (32, 256)
#: view patches span this many lobe standard deviations around each view direction
PATCH_SIGMAS = 3.0
#: relative spread of F over the spectrum below which a material counts as wavelength-independent
F_FLAT_TOL = 1e-9
#: float32 is fine while its noise floor stays below this share of the weakest light the target resolves
FLOOR_MARGIN = 0.1
#: incidence beyond which the tangent-plane factor's excess over the light the coherent lobe gives up is large
#: (measured with the height-field route: the coherent-loss guard trims < 0.2 % below 60°, 40 % at 80°;
#: waveoptics.brdf.twoscale.cap_to_coherent_loss)
KIRCHHOFF_GRAZING_DEG = 75.0
#: largest (4πσ/λ)² (the g of normal incidence and backscatter, the largest over all directions) at which the
#: planner trusts first-order Rayleigh-Rice (its domain is g ≪ 1)
RAYLEIGH_RICE_G_MAX = 0.05
#: wavelength nodes per interference fringe of a thin-film stack (Δλ ≈ λ²/(2 n d)). Measured at normal incidence
#: under D65 against 1 nm sampling (ΔE2000; scripts/docs_thin_films.py): 4-5 nodes per fringe left 0.4 (500 nm SiO2
#: on Si, 20 nm grid) and 3 left 1.0 (500 nm TiO2 on Ti); with 6 the worst of Al2O3/SiO2/TiO2 films of 120 nm to
#: 2 µm on Al, Si, Ti and BK7 was 0.19
FILM_NODES_PER_FRINGE = 6
