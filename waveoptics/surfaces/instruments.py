"""Height fields from instrument files (profilometers, white-light interferometers, confocal microscopes, AFMs),
read and written through SurfaceTopography, the surface-metrology community's library of instrument formats [1]_.

waveoptics keeps its own readers only for what SurfaceTopography lacks (the .npy sidecar, the .exr height
channel, text grids with '# dx = ...' headers, masked .npz); every other extension goes to SurfaceTopography.
SurfaceTopography is an optional dependency: ``pip install 'waveoptics[instruments]'``.

Axes: SurfaceTopography indexes heights ``h[ix, iy]`` with ``physical_sizes = (Lx, Ly)``; waveoptics indexes
``h[iy, ix]`` (:class:`~waveoptics.surfaces.heightfield.HeightField`), so the array is transposed on the way in
and out. Heights and spacings become metres; samples the file marks as undefined become the height field's mask.

References
----------
.. [1] L. Pastewka, A. Sanner, M. Röttger, et al., SurfaceTopography: "Read and analyze surface topographies",
   https://github.com/ComputationalMechanics/SurfaceTopography (readers of ISO 25178-71 SDF, ISO 5436-2 X3P,
   Digital Surf SUR, Zygo DATX/MetroPro, Wyko OPD, Sensofar PLU, Gwyddion GWY, NetCDF, ... formats).
"""
from __future__ import annotations

import json
import math
import warnings

import numpy as np

from ..errors import FieldError, WaveopticsError
from ..units import LENGTH_UNITS
from .heightfield import HeightField

__all__ = ['INSTRUMENT_EXTS', 'WRITERS', 'read', 'write', 'channels', 'metres_per']

#: extensions read through SurfaceTopography (its readers' extensions, less those waveoptics reads itself:
#: .npy .npz .txt .asc .dat(text) .csv .xyz; a binary .dat is Zygo MetroPro and goes to SurfaceTopography too).
#: Kept as a literal so that the command line does not import SurfaceTopography to check a file name; a test
#: holds it equal to what the installed SurfaceTopography reads.
INSTRUMENT_EXTS = (
    ".001", ".002", ".003", ".004", ".005", ".al3d", ".apx", ".bcr", ".bcrf", ".cur", ".datx", ".ezd",
    ".frt", ".gwy", ".h5", ".hfm", ".hgt", ".ibw", ".jpk", ".lext", ".mat", ".mdt", ".mi", ".mnt", ".nc",
    ".nid", ".nms", ".oir", ".opd", ".opdx", ".os3d", ".plu", ".plux", ".poir", ".qep", ".sdf", ".spm", ".stp",
    ".sur", ".tif", ".tiff", ".tmd", ".tom", ".top", ".vk3", ".vk4", ".vk6", ".vk7", ".x3p", ".xlsx", ".zip",
    ".zmg", ".zon",
)

#: extensions SurfaceTopography writes → its writer (a method of a uniform topography)
WRITERS = {".x3p": "to_x3p", ".gwy": "to_gwy", ".nc": "to_netcdf"}

#: SurfaceTopography's spellings of length units that :data:`waveoptics.units.LENGTH_UNITS` spells otherwise
_UNIT_ALIASES = {"Å": "A", "Angstrom": "A", "micrometer": "um", "nanometer": "nm", "millimeter": "mm", "meter": "m"}


def _library():
    try:
        import SurfaceTopography.IO as stio
    except ImportError:
        raise WaveopticsError("reading and writing instrument formats needs SurfaceTopography; install it with "
                              "pip install 'waveoptics[instruments]'") from None
    return stio


def metres_per(unit, what: str = "units") -> float:
    """Metres per *unit*, for a unit spelled as waveoptics or SurfaceTopography spell it ('um', 'µm', 'Å')."""
    u = _UNIT_ALIASES.get(str(unit), str(unit))
    if u not in LENGTH_UNITS:
        raise FieldError(f"{{{what}}} {unit!r} is not a length unit waveoptics knows; allowed: "
                         f"{', '.join(LENGTH_UNITS)}", what)
    return LENGTH_UNITS[u]


def _open(path):
    stio = _library()
    try:
        return stio.open_topography(str(path))
    except (stio.UnknownFileFormat, stio.CannotDetectFileFormat):
        raise WaveopticsError("is not in an instrument format SurfaceTopography can read (or its content does not "
                              "match its extension)") from None
    except Exception as exc:   # readers of 42 formats raise anything on a corrupt file: say so in one line
        raise WaveopticsError(f"could not be read as {path.suffix} ({_first_line(exc)})") from None


def _first_line(exc) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def channels(path) -> list[dict]:
    """The data channels of an instrument file: index, name, dimension (1 profile, 2 map), grid points, unit and
    physical sizes as the file states them (None where it does not)."""
    reader = _open(path)
    out = []
    for ch in reader.channels:
        out.append({"index": ch.index, "name": ch.name, "dim": ch.dim, "nb_grid_pts": list(ch.nb_grid_pts),
                    "unit": ch.unit, "physical_sizes": None if ch.physical_sizes is None
                    else [float(s) for s in ch.physical_sizes]})
    return out


def _channel(reader, channel):
    chans = reader.channels
    if channel is None:
        return reader.default_channel
    names = [c.name for c in chans]
    if isinstance(channel, str) and not channel.strip().lstrip("-").isdigit():
        if channel in names:
            return chans[names.index(channel)]
        raise FieldError(f"{{channel}} {channel!r} is not a channel of this file; it has "
                         f"{', '.join(f'{c.index}: {c.name}' for c in chans)}", "channel")
    i = int(channel)
    if not 0 <= i < len(chans):
        raise FieldError(f"{{channel}} {i} is not a channel of this file; it has "
                         f"{', '.join(f'{c.index}: {c.name}' for c in chans)}", "channel")
    return chans[i]


def _jsonable(value):
    """*value* as plain JSON data (instrument metadata holds dates, NumPy scalars and nested dicts)."""
    return json.loads(json.dumps(value, default=lambda v: v.item() if hasattr(v, "item") else str(v)))


def read(path, spacing=None, units=None, channel=None) -> HeightField:
    """A height field from an instrument file, in metres (see :func:`_read`)."""
    with warnings.catch_warnings():   # SciPy's NetCDF reader notes that it cannot close a memory map early
        warnings.filterwarnings("ignore", message="Cannot close a netcdf_file", category=RuntimeWarning)
        return _read(path, spacing, units, channel)


def _read(path, spacing=None, units=None, channel=None) -> HeightField:
    """A height field from an instrument file, in metres.

    Parameters
    ----------
    path : Path
        A file in any format SurfaceTopography reads (:data:`INSTRUMENT_EXTS`).
    spacing : (dx, dy), m, optional
        Grid spacing; needed only when the file does not state its physical size (then it is given to
        SurfaceTopography as the size), and it overrides the file's spacing otherwise (as for every format).
    units : str, optional
        Unit of heights and lengths for a file that does not state it ('um', 'nm', ...). A unit that contradicts
        the file's own is refused.
    channel : int or str, optional
        Channel index or name (default: the file's default channel, normally the height).

    Returns
    -------
    HeightField
        ``meta`` holds the provenance: ``source_format`` (SurfaceTopography's format name), ``channel``,
        ``file_unit``, and ``instrument`` / ``acquisition_time`` where the file records them.
    """
    reader = _open(path)
    ch = _channel(reader, channel)
    kwargs = {}
    unit = ch.unit
    if unit is None:
        if units is None:
            raise FieldError("does not state its units; pass {units}, e.g. 'um'", "units")
        kwargs["unit"] = unit = units
    elif units is not None and not math.isclose(metres_per(units), metres_per(unit, "file unit")):
        raise FieldError(f"states its lengths in {unit}; {{units}} {units!r} contradicts it (pass {{units}} only "
                         "for files that do not state theirs)", "units")
    scale = metres_per(unit)
    if ch.physical_sizes is None:
        if spacing is None:
            raise FieldError("does not state its grid spacing; pass {spacing}, e.g. 50nm", "spacing")
        n = tuple(ch.nb_grid_pts)
        kwargs["physical_sizes"] = tuple(k * d / scale for k, d in zip(n, spacing))[:len(n)]
        spacing = None
    try:
        topo = ch.topography(**kwargs)
        h = np.ma.masked_invalid(np.ma.array(topo.heights(), dtype=np.float64, copy=True))
    except Exception as exc:
        raise WaveopticsError(f"channel {ch.name!r} could not be read ({_first_line(exc)})") from None
    if not topo.is_uniform:
        raise WaveopticsError("holds a non-uniform line scan (samples at irregular positions); waveoptics needs "
                              "heights on a regular grid")
    if np.isinf(np.ma.getdata(h)[~np.ma.getmaskarray(h)]).any():
        raise WaveopticsError("holds Inf heights; heights must be finite")
    mask = ~np.ma.getmaskarray(h)
    heights = np.where(mask, np.ma.getdata(h), 0.0) * scale
    pixel = [float(p) * scale for p in np.atleast_1d(topo.pixel_size)]
    if topo.dim == 1:
        heights, mask, pixel = heights[None, :], mask[None, :], pixel * 2
    else:
        heights, mask = heights.T, mask.T
    if spacing is not None:
        pixel = list(spacing)
    if not mask.any():
        raise WaveopticsError(f"channel {ch.name!r} holds no defined height")
    info = {k: v for k, v in (topo.info or {}).items() if k != "raw_metadata"}
    meta = {"source_format": reader.format() if callable(getattr(reader, "format", None)) else None,
            "channel": ch.name, "file_unit": str(unit), **_jsonable(info)}
    return HeightField(heights, pixel[0], pixel[1], None if mask.all() else mask, meta)


def write(hf: HeightField, tmp_path, ext: str) -> None:
    """Write *hf* to *tmp_path* with SurfaceTopography's writer for *ext* (:data:`WRITERS`), heights in metres.

    The caller renames the file into place (:func:`waveoptics.io.files.atomic_path`). Masked samples are written
    as undefined data where the format has them.
    """
    _library()
    from SurfaceTopography import Topography

    h = hf.heights.T
    if hf.mask is not None:
        h = np.ma.masked_array(h, mask=~hf.mask.T)
    info = {}
    if "instrument" in hf.meta and isinstance(hf.meta["instrument"], dict):
        info["instrument"] = hf.meta["instrument"]
    topo = Topography(h, (hf.shape[1] * hf.dx, hf.shape[0] * hf.dy), unit="m", info=info,
                      periodic=bool(hf.meta.get("periodic", False)))
    try:
        getattr(topo, WRITERS[ext])(str(tmp_path))
    except Exception as exc:
        raise WaveopticsError(f"SurfaceTopography could not write {ext} ({_first_line(exc)})") from None
