"""Files and figures: writes that never leave a half-written file, JSON, OpenEXR (plain and spectral), and the
figure helpers every picture uses.

Files: files (atomic writes, JSON, EXR), spectral_exr (Fichet 2021 spectral EXR), figures (tone mapping, PNG,
matplotlib output, sphere panels).
"""
from .files import (NonFiniteOutputError, atomic_path, staged_outputs, recover_staged, prepare_outdir, to_json,
    write_json, write_exr, write_rgb_exr, gamut_note, read_exr)
from .spectral_exr import (SPECTRAL_LAYOUT_VERSION, spectral_channel_name, write_spectral_exr, read_spectral_exr)
from .figures import (pyplot, save_png, save_figure)
from . import files, spectral_exr, figures  # noqa: F401

__all__ = files.__all__ + spectral_exr.__all__ + figures.__all__
