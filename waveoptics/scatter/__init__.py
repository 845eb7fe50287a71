"""Wave-optics scattering from a surface's nanogeometry.

Files: grid (the direction-cosine grid), patch (window and detrend of a height-field patch), models (the
diffraction models: Kirchhoff, GHS, RGHS, OHS, ROHS), kirchhoff (the Kirchhoff
factor and BRDF of a field), direct (the direct sum, NumPy and OpenCL), fft (the chirp-z solver), series (the
Beckmann-Spizzichino series from a PSD), band (the propagating band and the relevant roughness),
perturbation (Rayleigh-Rice
with the polarization factor Q), mom (the rigorous method-of-moments reference for 1-D rough surfaces), models1d (Kirchhoff and
Rayleigh-Rice for 1-D Gaussian surfaces), solvers (the :data:`SOLVERS` registry, :func:`brdf`,
:func:`scatter`), footprint (the BRDF of a pixel footprint on a large field), output (the files of a scatter run).
"""
from .grid import *  # noqa: F401,F403
from .patch import *  # noqa: F401,F403
from .models import *  # noqa: F401,F403
from .kirchhoff import *  # noqa: F401,F403
from .direct import *  # noqa: F401,F403
from .fft import *  # noqa: F401,F403
from .series import *  # noqa: F401,F403
from .band import *  # noqa: F401,F403
from .perturbation import *  # noqa: F401,F403
from .mom import *  # noqa: F401,F403
from .models1d import *  # noqa: F401,F403
from .solvers import *  # noqa: F401,F403
from .footprint import *  # noqa: F401,F403
from .output import *  # noqa: F401,F403
from . import grid, patch, models, kirchhoff, direct, fft, series, band, perturbation, mom, models1d, solvers, footprint, output  # noqa: F401

__all__ = grid.__all__ + patch.__all__ + models.__all__ + kirchhoff.__all__ + direct.__all__ + fft.__all__ + series.__all__ + band.__all__ + perturbation.__all__ + mom.__all__ + models1d.__all__ + solvers.__all__ + footprint.__all__ + output.__all__
