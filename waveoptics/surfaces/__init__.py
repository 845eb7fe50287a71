"""Height fields and their statistics.

Files: heightfield (the :class:`HeightField` type), psd (PSD models in σ/length vocabulary, :class:`PSDModel`),, generators (random and deterministic surfaces),
statistics (rms height and slope, autocorrelation, radial PSD, fits), preparation (levelling, cropping),
formats (reading and writing files; instrument formats in instruments), footprint (Gaussian pixel footprints and
memory-mapped large fields), plots, examples (example fields for glint renders).
"""
from .heightfield import *  # noqa: F401,F403
from .psd import *  # noqa: F401,F403
from .generators import *  # noqa: F401,F403
from .statistics import *  # noqa: F401,F403
from .preparation import *  # noqa: F401,F403
from .formats import *  # noqa: F401,F403
from .footprint import *  # noqa: F401,F403
from .plots import *  # noqa: F401,F403
from .examples import *  # noqa: F401,F403
from . import heightfield, psd, generators, statistics, preparation, formats, footprint, instruments, plots, examples  # noqa: F401

__all__ = heightfield.__all__ + psd.__all__ + generators.__all__ + statistics.__all__ + preparation.__all__ + formats.__all__ + footprint.__all__ + plots.__all__ + examples.__all__
