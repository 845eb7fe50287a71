"""File output that never leaves a half-written file under a final name, plus JSON and OpenEXR helpers.

Every writer goes through :func:`atomic_path`: the data is written to a temporary name in the same
directory and moved into place with :func:`os.replace` only when complete, so an interrupted or failed
run leaves the previous result (if any) untouched.
"""
from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import OutputExistsError, WaveopticsError


@contextlib.contextmanager
def atomic_path(final, *, overwrite: bool = True):
    """Yield a temporary path next to *final*; on success it is renamed to *final*.

    Parameters
    ----------
    final : str or Path
        The destination file.
    overwrite : bool
        When False and *final* exists, raise :class:`OutputExistsError` before writing anything.
    """
    final = Path(final)
    if final.exists() and not overwrite:
        raise OutputExistsError(f"output {str(final)!r} already exists; pass --overwrite to replace it")
    parent = final.parent if str(final.parent) else Path(".")
    if not parent.is_dir():
        raise WaveopticsError(f"output directory {str(parent)!r} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=f".partial{final.suffix}", dir=parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, final)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def prepare_outdir(path, *, overwrite: bool = False, expected=()) -> Path:
    """Create output directory *path* (with parents) and check it is writable.

    Parameters
    ----------
    expected : iterable of str
        File names the run will write; if any exists and *overwrite* is False, refuse before computing.
    """
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise WaveopticsError(f"output directory {str(p)!r} is a file, not a directory")
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WaveopticsError(f"cannot create output directory {str(p)!r}: {exc.strerror}") from None
    if not os.access(p, os.W_OK | os.X_OK):
        raise WaveopticsError(f"output directory {str(p)!r} is not writable")
    if not overwrite:
        clash = [name for name in expected if (p / name).exists()]
        if clash:
            raise OutputExistsError(f"output {str(p / clash[0])!r} already exists; pass --overwrite to replace it")
    return p


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if np.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def to_json(data, **kw) -> str:
    """JSON text of *data*, converting numpy types; non-finite floats become ``null``."""
    return json.dumps(_jsonable(data), **kw)


def write_json(path, data, *, overwrite: bool = True) -> Path:
    """Write *data* as indented JSON atomically."""
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(to_json(data, indent=2) + "\n")
    return Path(path)


def write_exr(path, channels: dict, header: dict | None = None, *, overwrite: bool = True,
              half: bool = False) -> Path:
    """Write a scanline OpenEXR file atomically.

    Parameters
    ----------
    channels : dict of str -> ndarray (H, W)
        Channel name to pixels; stored as float32 (or float16 with *half*).
    header : dict
        Extra header attributes. Floats that need full precision should be passed as strings,
        because OpenEXR stores Python floats as 32-bit.
    """
    import OpenEXR

    dtype = np.float16 if half else np.float32
    chans = {}
    shape = None
    for name, arr in channels.items():
        a = np.ascontiguousarray(np.asarray(arr, dtype=dtype))
        if a.ndim != 2:
            raise WaveopticsError(f"EXR channel {name!r} must be 2-D, got shape {a.shape}")
        if shape is not None and a.shape != shape:
            raise WaveopticsError(f"EXR channel {name!r} has shape {a.shape}, others {shape}")
        shape = a.shape
        chans[name] = a
    hdr = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    hdr.update(header or {})
    with atomic_path(path, overwrite=overwrite) as tmp:
        OpenEXR.File(hdr, chans).write(str(tmp))
    return Path(path)


def read_exr(path) -> tuple[dict, dict]:
    """Read an OpenEXR file: returns (channels as float arrays, header dict)."""
    import OpenEXR

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"file {str(p)!r} does not exist")
    try:
        f = OpenEXR.File(str(p))
        chans = {name: np.asarray(c.pixels) for name, c in f.channels().items()}
        header = dict(f.header())
    except Exception as exc:  # noqa: BLE001 - the bindings raise plain RuntimeError/Exception
        raise WaveopticsError(f"{str(p)!r} is not a readable OpenEXR file ({exc})") from None
    return chans, header


# ----------------------------------------------------------------------------------------------------------------
# Spectral OpenEXR (Fichet, Pacanowski & Wilkie 2021)
# ----------------------------------------------------------------------------------------------------------------

#: value of the ``spectralLayoutVersion`` header attribute this writer follows
SPECTRAL_LAYOUT_VERSION = "1.0"


def spectral_channel_name(wavelength_nm: float, *, emissive: bool = False) -> str:
    """Channel name of one wavelength in the spectral OpenEXR layout: ``T.550,000000nm`` (reflective) or
    ``S0.550,000000nm`` (emissive, unpolarized Stokes component 0); the decimal separator is a comma.

    References
    ----------
    .. [1] A. Fichet, R. Pacanowski, A. Wilkie, "An OpenEXR Layout for Spectral Images", JCGT 10(3), 2021, §3
       (channel naming ``<component>.<value with comma decimal><unit>``, ``spectralLayoutVersion``).
    """
    w = float(wavelength_nm)
    if not np.isfinite(w) or w <= 0:
        raise WaveopticsError(f"wavelength {wavelength_nm!r} nm is not allowed in a spectral channel name; it must "
                              "be finite and > 0")
    return ("S0." if emissive else "T.") + f"{w:.6f}".replace(".", ",") + "nm"


def write_spectral_exr(path, layers: dict, header: dict | None = None, *, emissive: bool = False,
                       overwrite: bool = True) -> Path:
    """Write per-wavelength images as one spectral OpenEXR file (atomically).

    Parameters
    ----------
    layers : dict of float -> ndarray (H, W)
        Wavelength in nm to image; all images the same shape. Stored as float32 channels named by
        :func:`spectral_channel_name`.
    header : dict, optional
        Extra attributes (pass floats that need full precision as strings).
    emissive : bool
        ``S0.`` channels with ``emissiveUnits`` = W.m^-2.sr^-1 instead of reflective ``T.`` channels.

    References
    ----------
    .. [1] Fichet, Pacanowski & Wilkie, JCGT 10(3), 2021.
    """
    if not layers:
        raise WaveopticsError("a spectral image needs at least one wavelength layer")
    chans = {}
    for wl in sorted(layers, key=float):
        name = spectral_channel_name(wl, emissive=emissive)
        if name in chans:
            raise WaveopticsError(f"wavelength {wl!r} nm appears twice in the spectral layers")
        chans[name] = layers[wl]
    hdr = {"spectralLayoutVersion": SPECTRAL_LAYOUT_VERSION}
    if emissive:
        hdr["emissiveUnits"] = "W.m^-2.sr^-1"
    hdr.update(header or {})
    return write_exr(path, chans, hdr, overwrite=overwrite)


def read_spectral_exr(path) -> tuple[dict, dict]:
    """Read the spectral channels of an OpenEXR file: ({wavelength_nm: image}, header).

    Channel names are parsed with colour-science's pattern for the Fichet et al. 2021 layout; reflective
    ``T.`` channels are returned, or emissive ``S0.`` channels when there are no reflective ones.
    """
    import re

    from colour.io.fichet2021 import PATTERN_FICHET2021, match_groups_to_nm

    chans, header = read_exr(path)
    found = {"T": {}, "S0": {}}
    for name, img in chans.items():
        m = re.fullmatch(rf"(T|S0)\.{PATTERN_FICHET2021}", name)
        if m:
            found[m.group(1)][match_groups_to_nm(m.group(2), m.group(4) or "", m.group(5))] = img
    layers = found["T"] or found["S0"]
    if not layers:
        raise WaveopticsError(f"{str(path)!r} has no spectral channels (T.<wavelength>nm or S0.<wavelength>nm)")
    return dict(sorted(layers.items())), header
