"""Wave-optics scattering from a surface's nanogeometry.

Files: grid (the direction-cosine grid), patch (window and detrend of a height-field patch), models (the
diffraction models: Kirchhoff, GHS, RGHS, OHS, ROHS), kirchhoff (the Kirchhoff
factor and BRDF of a field), direct (the direct sum, NumPy and OpenCL), fft (the chirp-z solver), series (the
Beckmann-Spizzichino series from a PSD), band (the propagating band and the relevant roughness), angles (the angles of a scattering geometry), band_energy
(the band lobe's albedo and coherent fraction),
perturbation (Rayleigh-Rice
with the polarization factor Q), transmission (Rayleigh-Rice into both half-spaces of an interface between two
media: the BTDF with Q_t), spm2 (the second-order mean field of a rough interface: the coherent
reflection and transmission losses), spm2_stack (the same for a thin-film stack with rough interfaces, light
from either side), rough_film (first-order scatter of a film stack with rough interfaces, Elson), rough_film_sides (the same
stack's first-order BSDF over the whole sphere, light from either side), mom (the rigorous method-of-moments reference for 1-D rough surfaces), models1d (Kirchhoff and
Rayleigh-Rice for 1-D Gaussian surfaces), solvers (the :data:`SOLVERS` registry, :func:`brdf`,
:func:`scatter`), footprint (the BRDF of a pixel footprint on a large field), pixel (per-pixel
footprint BRDFs at one direction pair, OpenCL), gabor (one footprint by Yan et al. 2018's Gabor kernels, an
independent check of pixel), output (the files of a scatter run).
"""
from .grid import (HORIZON_SIN, DirectionGrid, integrate, COS_I_MIN)
from .patch import (DEFAULT_WINDOW, window, window_area, Samples, samples)
from .models import (DiffractionModel, DIFFRACTION_MODELS, get_model, K_kirchhoff, K_harvey_shack, K_symmetric)
from .kirchhoff import (cos_theta_d, brdf_from_field, coherent_amplitude)
from .direct import (VECTOR_WIDTH, TERMS_PER_LAUNCH, PhaseCoefficients, phase_coefficients, kirchhoff_phase,
    kirchhoff_U, PAIRS_PER_ITEM, SINCOS_TERMS, sincos_poly, sincos_2pi, kirchhoff_phase_cl, sincos_2pi_cl,
    launch_pairs, exact_phase_args, kirchhoff_U_cl)
from .fft import (FFT_TOL, FFT_BAND_X, FFT_MAX_ORDER, fft_plan, field_fft)
from .series import (M_MAX, SeriesTables, series_tables, SeriesSum, series_sum, poisson_weights, roughness_g,
    series_terms, debye_waller, obliquity, rayleigh_rice)
from .polar import (N_PSI, N_PANELS, N_PANEL_NODES, N_RIM, polar_nodes, polar_albedo)
from .angles import (scattering_angles)
from .band_energy import (TANGENT_PLANE_MAX_DEG, is_conductor, ALBEDO_THETAS_DEG, RR_THETAS_DEG, rr_interp,
    BandAlbedos)
from .band import (band_arc, relevant_variance, relevant_variance_of_field, beyond_band_fraction, SIN_NODES,
    relevant_variances, relevant_sigma2, band_correlation, BandSeries, band_series, band_series_built, scattered_lobe,
    series_arrays)
from .perturbation import (POLARIZATIONS, COMPONENTS, PEC_PERMITTIVITY, q_factors, Q,
    rayleigh_rice_components, rayleigh_rice_brdf, permittivity, rayleigh_rice_lobe, rayleigh_rice_albedo,
    rayleigh_rice_tis, periodogram_bin_sum, is_stack, stack_correlation)
from .transmission import (q_transmission, rr_psd, rr_btdf_components, rr_brdf_components, rr_bsdf_components,
    rr_bsdf, TIS_METHODS, WIDE_LOBE, hemisphere_albedo, rr_tis_transmission, rr_tis_reflection,
    incident_polarization)
from .spm2 import (match_flat, spm2_kernel, PSD_TAIL_EXPONENTS, tail_exponent, radial_moment, first_moment,
    loss_quadrature, coherent_losses, SPM2_NODES, K_LIMIT, CHUNK_NODES)
from .spm2_stack import (GUIDED_SAMPLES, MAX_HALF_WAVES, stack_media, flat_stack, stack_response, stack_amplitudes,
    stack_loss_kernels, node_scale, guided_modes, stack_coherent_losses)
from .rough_film import (CORRELATIONS, stack_layers, interface_fields, interface_amplitudes, cross_psd_weights,
    rough_stack_components, rough_stack_brdf, rough_stack_tis, direction_fields, bragg_psd, interface_psd_list,
    interface_spectra, cross_psd_pairs, correlated_sum)
from .rough_film_sides import (TRANSPARENT_K, substrate_is_transparent, rough_stack_bsdf_components, rough_stack_bsdf,
    rough_stack_tis_sides)
from .mom import (MIN_TAPER_PARAMETER, MomRequest, MomResult, ProfileSolution, gaussian_profile, mom_scatter,
    solve_profile, thorsos_beam, thorsos_incident_power)
from .models1d import (fresnel_amplitude_1d, kirchhoff_1d, spm1_1d)
from .solvers import (ENERGY_TOL, DiffractionWarning, diffraction_warnings_held, Solver, SOLVERS, BACKENDS, get_solver, tile_layout, split_patch,
    sampling_warnings, brdf, ScatterResult, memory_estimate, check_request_memory, scatter)
from .footprint import (footprint_scatter, coherence_centres, incoherent_sum)
from .pixel import (PIXEL_BACKENDS, MAX_REGION_SAMPLES, PixelBRDF, footprint_sums, footprint_sums_numpy,
    pixel_brdf, footprint_brdf, SUM_N_SIGMA, Q_MAX, ellipse_samples)
from .gabor import (KERNEL_SIGMA, GaborKernels, gabor_kernels, gabor_footprint_field, gabor_footprint_brdf)
from .output import (plot_scatter, SCATTER_FILES, write_scatter, brdf_exr_header)
from . import grid, patch, models, kirchhoff, direct, fft, series, polar, angles, band_energy, band, perturbation, transmission, rough_film, rough_film_sides, mom, models1d, solvers, footprint, pixel, gabor, output  # noqa: F401

__all__ = grid.__all__ + patch.__all__ + models.__all__ + kirchhoff.__all__ + direct.__all__ + fft.__all__ + series.__all__ + polar.__all__ + angles.__all__ + band_energy.__all__ + band.__all__ + perturbation.__all__ + transmission.__all__ + rough_film.__all__ + rough_film_sides.__all__ + mom.__all__ + models1d.__all__ + solvers.__all__ + footprint.__all__ + pixel.__all__ + gabor.__all__ + output.__all__
