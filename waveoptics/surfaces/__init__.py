"""Height fields and their statistics.

Files: heightfield (the :class:`HeightField` type), psd (PSD models in σ/length vocabulary, :class:`PSDModel`),, generators (random and deterministic surfaces),
statistics (rms height and slope, autocorrelation, radial PSD, fits), preparation (levelling, cropping),
formats (reading and writing files; instrument formats in instruments), footprint (Gaussian pixel footprints and
memory-mapped large fields), regions (label maps and plane slopes stored with a field on disk), tiled_base and
tiled (fields of real size read by patches: memory-mapped .npy, chunked HDF5, procedural), plots, examples (example fields for glint renders).
"""
from .heightfield import (HeightField)
from .psd import (S_gaussian, S1_gaussian, c_gaussian, S_exponential, S1_exponential, c_exponential, abc_A,
    abc_sigma, S_abc, S1_abc, c_abc, PSDModel, PSDFamily, PSD_MODELS)
from .generators import (flat, gaussian, exponential, abc, sinusoid, MAX_SCRATCHES, GROOVE_REACH, scratches, flakes, GENERATORS,
    generate)
from .statistics import (PeriodogramPSD, DETRENDS, detrended, rms_height, rms_slopes, rms_slope,
    autocorrelation_radial, correlation_length, psd_radial, fit_psd, stats)
from .preparation import (level, crop_region, parse_region, transform)
from .formats import (TEXT_EXTS, FORMATS, READ_FORMATS, WRITE_FORMATS, load, save, FINGERPRINT_BYTES,
    npy_fingerprint)
from .footprint import (N_SIGMA, Footprint, LargeHeightField, open_large, footprint_box, footprint_patch)
from .regions import (REGION_DATASETS, RegionPlanes, npy_region_paths, npy_regions, hdf5_regions, write_regions)
from .tiled import (TiledField, NpyField, HDF5Field, create_npy, create_hdf5, write_tiles, PSDField,
    ScratchField, FlakeField, PROCEDURAL, procedural)
from .plots import (plot)
from .examples import (Example, EXAMPLES, example)
from . import heightfield, psd, generators, statistics, preparation, formats, footprint, regions, tiled_base, tiled, instruments, plots, examples  # noqa: F401

__all__ = heightfield.__all__ + psd.__all__ + generators.__all__ + statistics.__all__ + preparation.__all__ + formats.__all__ + footprint.__all__ + regions.__all__ + tiled.__all__ + plots.__all__ + examples.__all__
