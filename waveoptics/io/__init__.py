"""Files and figures: writes that never leave a half-written file, JSON, OpenEXR (plain and spectral), and the
figure helpers every picture uses.

Files: files (atomic writes, JSON, EXR), spectral_exr (Fichet 2021 spectral EXR), figures (tone mapping, PNG,
matplotlib output, sphere panels).
"""
from .files import *  # noqa: F401,F403
from .spectral_exr import *  # noqa: F401,F403
from .figures import *  # noqa: F401,F403
from . import files, spectral_exr, figures  # noqa: F401

__all__ = files.__all__ + spectral_exr.__all__ + figures.__all__
