"""Geometric-optics and two-scale BRDFs.

Files: roughness (α from perceptual roughness and Blinn-Phong exponents), directions (half-vector, mirror direction),
smith (Smith masking; Λ by radial quadrature), anisotropy (stretched NDFs), ndf_closed (GGX, Beckmann, Blinn-Phong),
ndf_shaped (ABC, EPD, SGD), ndf (the NDF registry: D, Λ, G1 by name), shadowing (G terms), fresnel_terms (exact, Schlick or unit F; mean F), diffuse (Lambert, Oren-Nayar, trade-off),
microfacet (the Cook-Torrance specular term and the full BRDF), quadrature (directional albedo), opencl (kernel
twins), facet_frame_cl (the facet-frame quadrature's per-cell sum as an OpenCL kernel), twoscale (micro facets carrying nano-roughness: coherent lobe plus diffracted lobe on a direction grid),
facet_polarization (macro s/p light on tilted facets: each facet's own s/p mix),
sampling (microfacet normal samplers), protocol (the BRDF as a function: eval / pdf / sample / albedo; the
microfacet model), pointwise (the two-scale model as a function), tabulated (the same from diffracted lobes tabulated over
incidence, any nano-roughness), measured_ndf (an NDF tabulated from a height field's slopes), chi2 (goodness-of-fit test of samplers), multiscatter (Kulla-Conty energy compensation), facet_interface (what one facet of rough glass reflects and transmits: bare, or coated by thin films), nano_interface (what one nano-rough interface of a glass scatters and keeps coherent: bare, or coated by rough thin films), btdf (the rough dielectric: reflection and transmission over the sphere, with its energy compensation), nano_dielectric (nano-rough glass: the rough dielectric with first-order Rayleigh-Rice scatter into both half-spaces), twoscale_dielectric (two-scale rough glass: micro facets carrying the nano-rough glass, reflection and transmission), spectral (a BRDF known at wavelength nodes, evaluated at any λ and in RGB), ndf_fit (the α of any NDF that matches a surface's slopes), models (the BRDF models by name, from keyword arguments:
BRDF_MODELS, their parameters BRDF_MODEL_PARAMETERS, build_brdf_model).
"""
from .measured_ndf import (SlopeTable, slope_table, slope_law_table, footprint_ndf, D_tabulated, Lambda_tabulated)
from .roughness import (alpha_from_roughness, roughness_from_alpha, blinn_phong_exponent, alpha_from_blinn_phong)
from .directions import (half_vector, reflect)
from .smith import (LAMBDA_GL_ORDER, Lambda_radial)
from .anisotropy import (stretch_factors, D_stretched, Lambda_stretched, STRETCH_EXPONENT)
from .ndf_closed import (D_ggx, Lambda_ggx, D_beckmann, Lambda_beckmann, D_blinn_phong, Lambda_blinn_phong)
from .ndf_shaped import (ABC_C_DEFAULT, abc_normalization, D_abc, Lambda_abc, EPD_P_DEFAULT, epd_normalization,
    D_epd, Lambda_epd, SGD_P_DEFAULT, gamma_upper, sgd_normalization, D_sgd, Lambda_sgd)
from .ndf import (ALPHA_MIN, ALPHA_MAX, COS_MIN, SHAPE_RANGE, NDF, NDFS, D, Lambda, G1)
from .shadowing import (G_smith, G_smith_correlated, G_cook_torrance, G_implicit, SHADOWINGS, G, sided_lambda,
    sided_G2)
from .fresnel_terms import (FRESNELS, F_mean, MaterialFresnel)
from .diffuse import (lambert, oren_nayar, burley, diffuse_tradeoff, DIFFUSES, diffuse_parameter, sigma_renamed)
from .microfacet import (specular, brdf, fresnel_inputs, spectral_brdf)
from .quadrature import (NODE_BLOCK, TABLE_GL_ORDER, normal_quadrature, table_nodes, directional_albedo, albedo,
                         slope_table_of)
from .opencl import (D_cl, Lambda_cl, brdf_cl, ndf_shape_parameter)
from .field_lobe import (BAND_MARGIN_BINS, band_limited_field, kirchhoff_scattered_lobe, lobe_sampling_warnings, nyquist_band, fresnel_at_pairs,
    field_first_order_over_fresnel, field_scattered_lobe, FIELD_THETAS_DEG,
    FIELD_GRID_OVERSAMPLING, field_cell_split, field_cells_resolve, field_cell_averages, field_scattered_albedo, bracketing_nodes, ISOTROPIC_FIELD_MODELS, ANISOTROPIC_FIELD_MODELS,
    ISOTROPY_SECTORS, ISOTROPY_MAX_RATIO, field_anisotropy, field_proposal_model)
from .roughness_scales import (SERIES_MIN_CAPTURED, check_series, Micro, Nano, isotropic)
from .scale_split import (SPLIT_PERIODS_OF_LAMBDA, split_scales)
from .twoscale_grid import (mirror_direction, fresnel_at_mirror, mirror_cell, sharp_micro_lobe, azimuth_deg,
    FACET_TAIL_SHARE, significant_cells)
from .nano_grid import (NARROW_CELLS, nano_lobe, CORE_CELLS, CORE_SUBSAMPLE_STEP, CORE_MAX_SUBSAMPLES)
from .facet_polarization import (facet_scattered_share, facet_coherent_fraction)
from .twoscale_paraxial import (micro_kernel, kernel_cos_theta_d, kernel_half_vectors, facet_scatter_weights, facet_incidences_deg,
    field_albedo_evaluations, PARAXIAL_SHARE_RATIO, carried_share_warning, paraxial_diffraction)
from .facet_energy import FACET_BUDGET_NODES, FACET_BUDGET_NODES_FIELD, facet_budget
from .facet_field_tables import (ANISOTROPIC_THETAS_DEG, ANISOTROPIC_AZIMUTHS, field_facet_table, anisotropic_field,
    anisotropic_field_stack, field_frame, anisotropic_field_read, ANISOTROPIC_NODE_SEED, cell_shifted_nodes, FACET_NODES_ANISOTROPIC_FIELD, obliquity)
from .twoscale_frame import (FACET_THETAS_DEG, FACET_THETAS_PSD_DEG, facet_thetas, FACET_TABLE_MAX_CELLS, facet_table_grid, equal_area, from_equal_area, FACET_NODES_NARROW, FACET_NODES_WIDE, FACET_NODES_FIELD, FACET_NODE_SPLIT,
    FACET_REFERENCE_NM, FACET_GRAZING_DEG, grazing_cells, FACET_ROUTES, facet_route, paraxial_reason, nano_statistics, facet_nodes, RIM_RADIUS, facet_frame_diffraction)
from .twoscale_coherent import (coherent_lobe, STACK_SUBCELL, COHERENT_CELLS_PER_WIDTH, SUBCELLS_MAX, LOBE_CELLS_REACH,
                                micro_lobe_width, lobe_cells, coarse_micro_lobe, SubCells)
from .twoscale import (Lobes, CAP_TOLERANCE, diffracted_lobe, diffuse_lobe, multiple_scattering_lobe, evaluate)
from .sampling import (NormalSampler, NORMAL_SAMPLERS, sample_normal, pdf_normal, pdf_reflected, sample_reflected, sample_normal_dcos)
from .protocol import (BRDFSample, BRDF, SphereBSDF, MicrofacetBRDF, TwoScaleParts, sample_cosine, pdf_cosine, lobe_choice,
    check_uniform)
from .pointwise import (QUADRATURE_NODES, QUADRATURE_NODES_WIDE, QUADRATURE_WIDE_ALPHA, wide_micro_lobe, RADIAL_BINS, COS_LEVELS, TwoScaleBRDF, unit_nodes, NanoRadial, facet_basis,
    to_facet, from_facet)
from .tabulated import (THETA_NODES_DEG, PHI_NODES_ANISOTROPIC, PHI_NODES_ANISOTROPIC_NDF, light_azimuth_nodes,
    reads_by_half_vector, TabulatedTwoScaleBRDF)
from .spectral import (SpectralNodes)
from .tabulated_glass import (GLASS_SIDES, GLASS_HEMISPHERES, SUBCELL_SIZE, SUBCELLS_RIM_FACTOR, SUBCELLS_MAX, LOBE_REACH,
    incident_direction, specular_exit, exit_lobe_width, cell_subdivisions, DISC_SUBCELLS, disc_fraction, cells_light,
    cell_averages, glass_cells, NODE_TOLERANCE,
    NODE_MIN_STEP_DEG, refined_incidence_nodes, TabulatedGlassBSDF, tabulate_glass)
from .ndf_fit import (slope_magnitude_cdf, alpha_for_median_slope, GGX_AXIS_MEDIAN)
from .chi2 import (Chi2Result, chi2_test, reflected_samples)
from .multiscatter import (MS_NODES, AlbedoTable, albedo_table, f_ms, F_ms)
from .incidence_quadrature import (INCIDENCE_NODES, INCIDENCE_ALPHA_MIN, incidence_panels, incidence_normal_quadrature)
from .facet_interface import (BareInterface, CoatedInterface, FACET_INTERFACES, facet_interface_of, bulk_medium,
                              as_interface)
from .btdf import (DIELECTRIC_SHADOWINGS, DIELECTRIC_MS_NODES, UNIFORM_DIGITS, pack_third_uniform, refract, half_vector_refraction,
    albedo_single, DielectricTables, dielectric_tables, albedo_multiple, RoughDielectricBSDF)
from .mu_pieces import (critical_cosine, albedo_cuts, table_pieces, split_pieces, piece_variable, piece_cosine, read_pieces)
from .nano_interface import (BareNano, CoatedNano, NANO_INTERFACES, nano_interface_of, coherent_shares,
                             check_film_psd)
from .nano_dielectric import (check_perturbative, NANO_MU_NODES, NanoTables,
                              coherent_split, nano_tables, NanoRoughDielectricBSDF)
from .twoscale_dielectric import (TWOSCALE_DIELECTRIC_NODES, ALBEDO_MU_NODES, ALBEDO_PHI_NODES, pair_half_vector,
    coherent_transmission_share, TwoScaleDielectricBSDF, NANO_FRAME_BSDFS, nano_rough_glass)
from .models import (ModelEvaluation, function_evaluation, microfacet_model, kirchhoff_model, rayleigh_rice_model,
    twoscale_model, rough_dielectric_model, table_model, BRDF_MODELS, BRDF_MODEL_PARAMETERS, BRDF_MODEL_HELP,
    build_brdf_model)
from . import measured_ndf, roughness, directions, smith, anisotropy, ndf_closed, ndf_shaped, ndf, shadowing, fresnel_terms, diffuse, microfacet, quadrature, opencl, field_lobe, roughness_scales, scale_split, twoscale_grid, nano_grid, facet_polarization, facet_energy, facet_field_tables, twoscale_paraxial, twoscale_frame, twoscale_coherent, twoscale, sampling, protocol, pointwise, tabulated, chi2, multiscatter, facet_interface, nano_interface, btdf, nano_dielectric, twoscale_dielectric, spectral, tabulated_glass, ndf_fit, models  # noqa: F401

__all__ = measured_ndf.__all__ + roughness.__all__ + directions.__all__ + smith.__all__ + anisotropy.__all__ + ndf_closed.__all__ + ndf_shaped.__all__ + ndf.__all__ + shadowing.__all__ + fresnel_terms.__all__ + diffuse.__all__ + microfacet.__all__ + quadrature.__all__ + opencl.__all__ + field_lobe.__all__ + roughness_scales.__all__ + scale_split.__all__ + twoscale_grid.__all__ + nano_grid.__all__ + facet_polarization.__all__ + facet_energy.__all__ + facet_field_tables.__all__ + twoscale_paraxial.__all__ + twoscale_frame.__all__ + twoscale_coherent.__all__ + twoscale.__all__ + sampling.__all__ + protocol.__all__ + pointwise.__all__ + tabulated.__all__ + chi2.__all__ + multiscatter.__all__ + facet_interface.__all__ + nano_interface.__all__ + btdf.__all__ + nano_dielectric.__all__ + twoscale_dielectric.__all__ + spectral.__all__ + tabulated_glass.__all__ + ndf_fit.__all__ + models.__all__
