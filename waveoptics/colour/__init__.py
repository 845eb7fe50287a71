"""Spectra to colour, with colour-science underneath (imported only by the functions that need it; the default
observer and illuminant come from cie_tables without it).

Files: observers (CIE colour-matching functions), illuminants (light sources as SPDs), colorimetry (CMFs, tristimulus weights, XYZ, RGB spaces, ΔE2000),
sampling (the wavelength grid for a colour accuracy), metamers (laser metamers of an illuminant), f0 (F0 colours
and categories).
"""
from .observers import (DEFAULT_OBSERVER, OBSERVERS, observer_name, cmfs, cmf_at)
from .illuminants import (ILLUMINANT_NAMES, SPD, laser, blackbody, standard_illuminant, spd_from_csv, illuminant)
from .colorimetry import (SPACES, CAT, VISIBLE_NM, spd_to_XYZ, TRISTIMULUS_METHODS, tristimulus_weights,
    reflectance_to_XYZ, white_XYZ, space_name, XYZ_to_rgb, reflectance_to_rgb, reflectance_to_rgb_matrix,
    rgb_to_srgb8, delta_e2000, luminance)
from .sampling import (STEPS_NM, spectral_grid, reference_reflectances, step_errors, simulation_wavelengths)
from .metamers import (metamer_laser_weights, metamer_summary, plot_metamers, RGB_LASER_NM, rgb_laser_projector)
from .f0 import (classify_f0, f0_colour)
from . import observers, illuminants, colorimetry, sampling, metamers, f0  # noqa: F401

__all__ = observers.__all__ + illuminants.__all__ + colorimetry.__all__ + sampling.__all__ + metamers.__all__ + f0.__all__
