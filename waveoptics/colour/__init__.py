"""Spectra to colour, with colour-science underneath.

Files: observers (CIE colour-matching functions), illuminants (light sources as SPDs), colorimetry (CMFs, tristimulus weights, XYZ, RGB spaces, ΔE2000),
sampling (the wavelength grid for a colour accuracy), metamers (laser metamers of an illuminant), f0 (F0 colours
and categories).
"""
from .observers import *  # noqa: F401,F403
from .illuminants import *  # noqa: F401,F403
from .colorimetry import *  # noqa: F401,F403
from .sampling import *  # noqa: F401,F403
from .metamers import *  # noqa: F401,F403
from .f0 import *  # noqa: F401,F403
from . import observers, illuminants, colorimetry, sampling, metamers, f0  # noqa: F401

__all__ = observers.__all__ + illuminants.__all__ + colorimetry.__all__ + sampling.__all__ + metamers.__all__ + f0.__all__
