"""Height-field files: .npz, .npy (+ JSON sidecar), OpenEXR and text grids / xyz point lists, read and written
here; instrument formats (.x3p, .sur, .datx, .sdf, .gwy, .nc, ...) through SurfaceTopography
(:mod:`waveoptics.surfaces.instruments`).
"""
from __future__ import annotations

import io as _io
import json
import re
import zipfile
from pathlib import Path

import numpy as np

from ..errors import FieldError, OutputExistsError, WaveopticsError, unknown
from ..io.files import atomic_path, read_exr, to_json, write_exr
from .generators import length_value
from .heightfield import HeightField
from .metadata import header_length, npz_heights_key, npz_mask, npz_spacing, unit_scale
from . import instruments
from .instruments import INSTRUMENT_EXTS, WRITERS

__all__ = ['TEXT_EXTS', 'FORMATS', 'READ_FORMATS', 'WRITE_FORMATS', 'load', 'save', 'FINGERPRINT_BYTES', 'npy_fingerprint']

# ----------------------------------------------------------------------------------------------------------------
# Files
# ----------------------------------------------------------------------------------------------------------------
# .npz  heights (float64), dx, dy (metres), optional mask, meta (JSON text): self-contained, bit-exact.
# .npy  heights in metres; the spacing comes from the sidecar FILE.npy.json (written by save) or from the
#       `spacing` argument. Masked samples are stored as NaN and flagged in the sidecar.
# .exr  one float32 channel "Z" (heights in `units`, metres when written here); header strings spacing_x,
#       spacing_y (repr of the float, so the spacing survives exactly), units, waveoptics_meta; masked = NaN.
# text  .txt/.dat/.asc (whitespace) and .csv (commas): a matrix (rows = y) with '# dx = ...' header lines or a
#       stated spacing; .xyz (or any text file with '# layout = xyz', or three columns forming a grid):
#       x y z columns on a regular grid (missing points become masked).

# other  instrument formats (INSTRUMENT_EXTS) through SurfaceTopography; .x3p, .gwy and .nc are also written.

TEXT_EXTS = (".txt", ".dat", ".asc", ".csv", ".xyz")
#: formats waveoptics reads and writes itself
FORMATS = (".npy", ".npz", ".exr") + TEXT_EXTS
#: every extension :func:`load` reads (instrument formats need the optional SurfaceTopography)
READ_FORMATS = FORMATS + INSTRUMENT_EXTS
#: every extension :func:`save` writes
WRITE_FORMATS = FORMATS + tuple(WRITERS)

_MAGIC = {b"\x93NUMPY": "a NumPy .npy file", b"PK\x03\x04": "a zip/.npz archive",
          b"\x76\x2f\x31\x01": "an OpenEXR image", b"\x89PNG": "a PNG image", b"\xff\xd8\xff": "a JPEG image",
          b"II*\x00": "a TIFF image", b"MM\x00*": "a TIFF image", b"\x89HDF": "an HDF5 file"}


def _sniff(head: bytes) -> str:
    for magic, what in _MAGIC.items():
        if head.startswith(magic):
            return what
    if b"\x00" in head:
        return "binary data"
    return "text"


def _ext(path, allowed=READ_FORMATS) -> str:

    ext = Path(path).suffix.lower()
    if ext not in allowed:
        more = " and the instrument formats SurfaceTopography reads (.x3p .sur .datx .sdf .gwy .nc ...)" \
            if allowed is READ_FORMATS else f", {', '.join(WRITERS)}"
        raise WaveopticsError(f"height-field file {str(path)!r} has unsupported extension {ext or '(none)'!r}; "
                              f"allowed: {', '.join(FORMATS)}{more}")
    return ext


def _spacing_arg(spacing):
    """(dx, dy) in metres from None, a number (m), a string with unit, or a pair."""
    if spacing is None:
        return None
    if isinstance(spacing, str) and "," in spacing:
        spacing = spacing.split(",")
    if isinstance(spacing, (list, tuple, np.ndarray)):
        if len(spacing) != 2:
            raise WaveopticsError(f"spacing {spacing!r} is not allowed; give D or (DX, DY)")
        return length_value(spacing[0], "spacing dx"), length_value(spacing[1], "spacing dy")
    d = length_value(spacing, "spacing")
    return d, d


def _real_heights(a, what: str) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.kind not in "fiu":
        raise WaveopticsError(f"{what} holds {a.dtype} values; heights must be real numbers (float or int)")
    a = a.astype(np.float64)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.size == 0:
        raise WaveopticsError(f"{what} has shape {a.shape}; heights must be a non-empty 2-D array")
    return a


def _nan_mask(h, allow: bool, what: str):
    """(heights with NaN set to 0, mask or None); NaN is only accepted where the file declares it a mask."""
    bad = ~np.isfinite(h)
    if not bad.any():
        return h, None
    if np.isinf(h).any():
        raise WaveopticsError(f"{what} holds Inf heights; heights must be finite")
    if not allow:
        raise WaveopticsError(f"{what} holds NaN heights; heights must be finite (or pass nan_is_mask=True "
                              "to treat NaN as missing samples)")
    if bad.all():
        raise WaveopticsError(f"{what} holds only NaN heights; no valid sample")
    return np.where(bad, 0.0, h), ~bad


def _json_meta(text, what):

    try:
        meta = json.loads(text)
    except (TypeError, ValueError):
        raise WaveopticsError(f"{what}: metadata is not valid JSON") from None
    return meta if isinstance(meta, dict) else {}


def load(path, spacing=None, *, units=None, layout=None, nan_is_mask=False, channel=None) -> HeightField:
    """Read a height field, choosing the format by extension (see :data:`FORMATS`).

    Parameters
    ----------
    path : str or Path
        .npz, .npy (+ optional sidecar ``path.json``), .exr, a text grid (.txt .dat .asc .csv .xyz), or an
        instrument file SurfaceTopography reads (:data:`~waveoptics.surfaces.instruments.INSTRUMENT_EXTS`: .x3p,
        .sur, .datx, .sdf, .opd, .plu, .gwy, .nc, a binary MetroPro .dat, ...).
    spacing : float or str or (dx, dy), m, optional
        Grid spacing; overrides what the file states. Required for a plain .npy without sidecar, and for a text
        matrix or EXR without spacing in its header.
    units : str, optional
        Unit of the heights (and of x, y and header spacings) in a text file or a foreign EXR/.npy, e.g. 'um'.
        Text files without a '# units = ...' line need it; others default to metres.
    layout : {'matrix', 'xyz'}, optional
        Text layout; by default from a '# layout =' line, the .xyz extension, or three columns forming a grid.
    nan_is_mask : bool
        Treat NaN heights as missing samples (mask) instead of an error. Files written by :func:`save`
        declare this themselves, and so do instrument files (their undefined samples become the mask).
    channel : int or str, optional
        Data channel of an instrument file, by index or name (default: the file's default channel).

    Returns
    -------
    HeightField
        Heights and spacings in metres; ``meta["source"]`` is the path, and an instrument file adds
        ``meta["source_format"]``, ``meta["channel"]``, ``meta["file_unit"]`` and the instrument and
        acquisition time where the file records them.

    Raises
    ------
    WaveopticsError
        One line naming the file and the problem: missing, empty, truncated, not what its extension says,
        wrong dtype or shape, NaN/Inf heights, missing/zero/negative spacing, unknown units.
    """

    p = Path(path)
    ext = _ext(p)
    if not p.is_file():
        raise WaveopticsError(f"height-field file {str(p)!r} does not exist")
    if p.stat().st_size == 0:
        raise WaveopticsError(f"height-field file {str(p)!r} is empty")
    with open(p, "rb") as fh:
        head = fh.read(4096)
    kind = _sniff(head)
    if ext == ".dat" and kind == "binary data":
        ext = ".metropro"   # a binary .dat is a Zygo MetroPro file, not a text grid
    if channel is not None and ext in FORMATS:
        raise FieldError(f"{{channel}} {channel!r} applies to instrument files; {str(p)!r} has one height channel",
                         "channel")
    expect = {".npy": "a NumPy .npy file", ".npz": "a zip/.npz archive", ".exr": "an OpenEXR image"}.get(ext, "text")
    if ext in FORMATS and kind != expect:
        what = f"a {ext} text grid" if expect == "text" else expect
        raise WaveopticsError(f"{str(p)!r} is not {what} (its content looks like {kind})")
    sp = _spacing_arg(spacing)
    if units is not None:
        unit_scale(units)  # refuse an unknown unit even where the file states its own
    try:
        if ext == ".npz":
            hf = _load_npz(p, sp, units, nan_is_mask)
        elif ext == ".npy":
            hf = _load_npy(p, sp, units, nan_is_mask)
        elif ext == ".exr":
            hf = _load_exr(p, sp, units, nan_is_mask)
        elif ext in TEXT_EXTS:
            hf = _load_text(p, sp, units, layout, nan_is_mask)
        else:
            hf = instruments.read(p, sp, units, channel)
    except FieldError as exc:  # keep the field, so that the CLI can name its flag
        prefix = "" if str(p) in str(exc) else f"{str(p)!r}: "
        raise FieldError(prefix + exc.template, *exc.fields) from None
    except WaveopticsError as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise WaveopticsError(msg if str(p) in msg else f"{str(p)!r}: {msg}") from None
    meta = dict(hf.meta, source=str(p))
    return HeightField(hf.heights, hf.dx, hf.dy, hf.mask, meta)


def _finish(h, sp, mask, meta, what):
    if sp is None:
        raise FieldError(f"{what} does not state its grid spacing; pass {{spacing}}, e.g. 50nm", "spacing")
    return HeightField(h, sp[0], sp[1], mask, meta)


def _load_npz(p, sp, units, nan_is_mask):

    try:
        # an open handle of our own: np.load leaks the one it opens when the zip is broken
        with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        raise WaveopticsError(f"is truncated or not a valid .npz archive ({str(exc).splitlines()[0]})") from None
    key = npz_heights_key(data)
    h = _real_heights(data[key], f"array {key!r}")
    u = str(data["units"]) if "units" in data else (units or "m")
    scale = unit_scale(u)
    meta = _json_meta(str(data["meta"]), ".npz") if "meta" in data else {}
    if sp is None:
        sp = npz_spacing(data, p.name, scale)
    mask = None
    if "mask" in data:
        mask = npz_mask(data["mask"], h.shape)
        h = np.where(mask, h, 0.0)
    h, nmask = _nan_mask(h, nan_is_mask, f"array {key!r}")
    mask = nmask if mask is None else (mask if nmask is None else mask & nmask)
    return _finish(h * scale, sp, mask, meta, "the .npz archive")


#: bytes read from each end of a .npy file for its fingerprint (a few ms, whatever the file's size)
FINGERPRINT_BYTES = 1 << 20


def npy_fingerprint(path) -> str:
    """A fingerprint of a .npy file that its sidecar records: SHA-256 of its size and its first and last
    :data:`FINGERPRINT_BYTES` bytes. The pair is renamed into place as two files; a run killed between the two
    renames leaves a new sidecar beside the earlier heights, which this tells apart (unless both arrays have the same
    size and agree in both ends), while copies of the pair keep it (unlike a time stamp)."""
    import hashlib

    p = Path(path)
    size = p.stat().st_size
    h = hashlib.sha256(str(size).encode())
    with open(p, "rb") as fh:
        h.update(fh.read(FINGERPRINT_BYTES))
        if size > FINGERPRINT_BYTES:
            fh.seek(max(size - FINGERPRINT_BYTES, FINGERPRINT_BYTES))
            h.update(fh.read())
    return h.hexdigest()


def npy_parts(p, sp, units, nan_is_mask, *, mmap: bool = False):
    """(array, scale to metres, spacing (dx, dy) m or None, meta, NaN allowed) of a .npy file and its sidecar; the
    array is memory-mapped (nothing read yet) with *mmap*."""
    try:
        a = np.load(p, allow_pickle=False, mmap_mode="r" if mmap else None)
    except (ValueError, OSError, EOFError) as exc:
        raise WaveopticsError(f"is truncated or not a valid .npy file ({str(exc).splitlines()[0]})") from None
    side = p.with_name(p.name + ".json")
    meta, allow_nan = {}, nan_is_mask
    if side.is_file():
        info = _json_meta(side.read_text(errors="replace"), f"sidecar {side.name!r}")
        if "heights_fingerprint" in info and info["heights_fingerprint"] != npy_fingerprint(p):
            raise WaveopticsError(f"sidecar {side.name!r} was written for other heights than {p.name!r} (a write of "
                                  "the pair interrupted between its two renames?); write the field again")
        units = units or info.get("units", "m")
        scale = unit_scale(units)
        meta = info.get("meta", {}) if isinstance(info.get("meta"), dict) else {}
        allow_nan = allow_nan or info.get("mask") == "nan"
        if sp is None and "dx" in info:   # numbers in the heights' units, or lengths with a unit ("50nm")
            sp = (header_length(info["dx"], scale, f"sidecar {side.name!r} spacing dx"),
                  header_length(info.get("dy", info["dx"]), scale, f"sidecar {side.name!r} spacing dy"))
    else:
        scale = unit_scale(units or "m")
    return a, scale, sp, meta, allow_nan


def _load_npy(p, sp, units, nan_is_mask):
    a, scale, sp, meta, allow_nan = npy_parts(p, sp, units, nan_is_mask)
    h = _real_heights(a, "the .npy array")
    h, mask = _nan_mask(h, allow_nan, "the .npy array")
    side = p.with_name(p.name + ".json")
    return _finish(h * scale, sp, mask, meta, f"the .npy file (no sidecar {side.name!r})")


def _load_exr(p, sp, units, nan_is_mask):

    chans, header = read_exr(p)
    if len(chans) == 1:
        name = next(iter(chans))
    elif "Z" in chans:
        name = "Z"
    else:
        raise WaveopticsError(f"has channels {sorted(chans)}; a height field needs one channel (or one named 'Z')")
    h = _real_heights(chans[name], f"EXR channel {name!r}")
    u = units or str(header.get("units", "m"))
    scale = unit_scale(u, "EXR units")
    meta = _json_meta(header["waveoptics_meta"], "EXR header") if "waveoptics_meta" in header else {}
    if sp is None and "spacing_x" in header:
        sp = (header_length(header["spacing_x"], scale, "EXR header spacing_x"),
              header_length(header.get("spacing_y", header["spacing_x"]), scale, "EXR header spacing_y"))
    h, mask = _nan_mask(h, nan_is_mask or header.get("mask") == "nan", f"EXR channel {name!r}")
    return _finish(h * scale, sp, mask, meta, "the EXR header")


def _parse_text(p):
    """(header dict, data rows as list of token lists with their line numbers)."""
    try:
        text = p.read_text(encoding="utf-8-sig")   # a byte-order mark (Windows editors write one) is no data
    except UnicodeDecodeError:
        raise WaveopticsError("is not UTF-8 text") from None
    header, lines = {}, []
    for i, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith(("#", "%", ";")):
            body = s.lstrip("#%; ")
            for sep in ("=", ":"):
                if sep in body:
                    k, v = body.split(sep, 1)
                    header[k.strip().lower()] = v.strip()
                    break
            continue
        lines.append((i, s.split("#", 1)[0].strip()))   # a '#' after the values starts a comment
    decimal_comma = _decimal_comma(lines)
    rows = []
    for i, s in lines:
        if decimal_comma:   # "1,5;2,25" or "1,5 2,25": commas are decimal marks, ';' or blanks separate
            rows.append((i, s.replace(";", " ").replace(",", ".").split()))
        else:
            rows.append((i, s.replace(",", " ").replace(";", " ").split()))
    # one leading line of column names (e.g. "x y z") is allowed
    if rows and all(not _is_number(t) for t in rows[0][1]):
        rows = rows[1:]
    if not rows:
        raise WaveopticsError("holds no data rows")
    return header, rows


_DECIMAL_COMMA = re.compile(r"^[-+]?\d+,\d+(?:[eE][-+]?\d+)?$")


def _decimal_comma(lines) -> bool:
    """Whether the data use decimal commas (as spreadsheets in many locales write them): the first data lines
    separate their values by ';' or blanks and every value holds one comma between digits. Plain comma-separated
    numbers ("1.5,2.25" or "1,2,3") are not decimal commas."""
    for _, s in lines[:5]:
        toks = [t for t in re.split(r"[;\s]+", s) if t]
        if not toks:
            continue
        if any(not (_DECIMAL_COMMA.match(t) or _is_number(t)) for t in toks):
            return False
        if not any(_DECIMAL_COMMA.match(t) for t in toks) or (len(toks) == 1 and ";" not in s):
            return False
    return bool(lines)


def _is_number(t) -> bool:
    try:
        float(t)
        return True
    except ValueError:
        return False


def _text_array(rows) -> np.ndarray:
    n = len(rows[0][1])
    for line, toks in rows:
        if len(toks) != n:
            raise WaveopticsError(f"line {line} has {len(toks)} values, expected {n} (truncated or ragged file)")
    try:
        return np.array([toks for _, toks in rows], dtype=np.float64)
    except ValueError:
        for line, toks in rows:
            for t in toks:
                if not _is_number(t):
                    raise WaveopticsError(f"line {line}: {t!r} is not a number") from None
        raise


def _grid_axis(v, what, origin=None, step=None):
    """(index of each value on a regular grid, spacing) for coordinates *v*; spacing None for a single value.

    *origin* and *step* (the file's first grid coordinate and spacing, when its header states them) keep the
    indices right when whole edge rows or columns are missing.
    """
    u = np.unique(v)
    if u.size == 1 and step is None:
        return np.zeros(v.size, dtype=np.int64), None
    d = float(np.min(np.diff(u))) if step is None else step
    o = u[0] if origin is None else min(origin, u[0])
    idx = np.rint((v - o) / d).astype(np.int64)
    if np.max(np.abs(v - (o + idx * d))) > 1e-3 * d:
        raise WaveopticsError(f"{what} coordinates are not on a regular grid (spacing {d:g})")
    return idx, d


def _float_header(header, key, scale: float):
    """Header value *key* in the file's units (*scale* metres each; a value with its own unit is converted)."""
    if key not in header:
        return None
    return header_length(header[key], scale, f"header {key}") / scale


def _int_header(header, key) -> int:
    try:
        return int(header.get(key, 0))
    except ValueError:
        raise WaveopticsError(f"header {key} = {header[key]!r} is not an integer") from None


def _load_text(p, sp, units, layout, nan_is_mask):
    header, rows = _parse_text(p)
    meta = _json_meta(header["meta"], "header meta") if "meta" in header else {}
    a = _text_array(rows)
    units = units or header.get("units")
    if units is None:
        raise FieldError("does not state its units; pass {units}, e.g. 'um', or add a '# units = um' header line",
                         "units")
    scale = unit_scale(units)
    layout = layout or header.get("layout")
    if layout is None:
        layout = "xyz" if p.suffix.lower() == ".xyz" else "matrix"
        if layout == "matrix" and a.shape[1] == 3 and a.shape[0] > 3:
            try:
                _grid_axis(a[:, 0], "x")
                _grid_axis(a[:, 1], "y")
                layout = "xyz"
            except WaveopticsError:
                pass
    if layout not in ("matrix", "xyz"):
        raise unknown("text layout", layout, ("matrix", "xyz"))
    allow_nan = nan_is_mask or header.get("nan") == "mask"
    if sp is None and "dx" in header:
        sp = (header_length(header["dx"], scale, "header spacing dx"),
              header_length(header.get("dy", header["dx"]), scale, "header spacing dy"))
    if sp is None and "spacing" in header:
        sp = _spacing_arg(header["spacing"])
    if layout == "matrix":
        h, mask = _nan_mask(a, allow_nan, "the grid")
        return _finish(h * scale, sp, mask, meta, "the text matrix (no '# dx = ...' line)")
    if a.shape[1] != 3:
        raise WaveopticsError(f"xyz layout needs 3 columns (x y z), found {a.shape[1]}")
    if not np.all(np.isfinite(a[:, :2])):
        raise WaveopticsError("x/y columns hold NaN or Inf")
    hdr_dx = _float_header(header, "dx", scale)
    ix, dx = _grid_axis(a[:, 0], "x", _float_header(header, "x0", scale), hdr_dx)
    iy, dy = _grid_axis(a[:, 1], "y", _float_header(header, "y0", scale), _float_header(header, "dy", scale) or hdr_dx)
    if dx is None and dy is None and sp is None:
        raise WaveopticsError("holds a single point; no grid")
    nx, ny = int(ix.max()) + 1, int(iy.max()) + 1
    if dx is not None and sp is not None:  # a stated spacing and grid size keep masked edge columns/rows
        nx = max(nx, _int_header(header, "nx"))
    if dy is not None and sp is not None:
        ny = max(ny, _int_header(header, "ny"))
    flat_idx = iy * nx + ix
    if np.unique(flat_idx).size != flat_idx.size:
        raise WaveopticsError("has duplicate (x, y) points")
    z = np.full(ny * nx, np.nan)
    z[flat_idx] = a[:, 2]
    if np.isinf(z).any():
        raise WaveopticsError("holds Inf heights; heights must be finite")
    if np.isnan(a[:, 2]).any() and not allow_nan:
        raise WaveopticsError("holds NaN heights; heights must be finite (or pass nan_is_mask=True)")
    missing = np.isnan(z).reshape(ny, nx)
    mask = ~missing if missing.any() else None
    h = np.where(missing, 0.0, z.reshape(ny, nx))
    if sp is None:
        d1 = dx if dx is not None else dy
        sp = ((dx or d1) * scale, (dy or d1) * scale)
    return HeightField(h * scale, sp[0], sp[1], mask, meta)


def save(hf: HeightField, path, *, overwrite: bool = False):
    """Write *hf* in the format its extension names (see :data:`FORMATS`), atomically.

    Parameters
    ----------
    hf : HeightField
    path : str or Path
        .npz (bit-exact, self-contained), .npy (bit-exact heights plus sidecar ``path.json`` with the spacing),
        .exr (float32 heights in metres, spacing as exact strings in the header), .txt/.dat/.asc/.csv (matrix
        with '# dx = ...' header, 17 significant digits: bit-exact), .xyz (x y z columns), or through
        SurfaceTopography's writers .x3p (ISO 5436-2), .gwy (Gwyddion) and .nc (NetCDF) (heights in metres;
        ``meta["instrument"]`` is kept, other metadata is not).
    overwrite : bool
        Replace an existing file (default: refuse).

    Returns
    -------
    Path
    """


    p = Path(path)
    ext = _ext(p, WRITE_FORMATS)
    if ext in WRITERS:
        with atomic_path(p, overwrite=overwrite) as tmp:
            instruments.write(hf, tmp, ext)
        return p
    meta_json = to_json(hf.meta)
    masked = hf.mask is not None
    h_nan = np.where(hf.valid, hf.heights, np.nan) if masked else hf.heights
    if ext == ".npz":
        arrays = {"heights": hf.heights, "dx": np.float64(hf.dx), "dy": np.float64(hf.dy),
                  "units": np.str_("m"), "meta": np.str_(meta_json)}
        if masked:
            arrays["mask"] = hf.mask
        with atomic_path(p, overwrite=overwrite) as tmp, open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)
    elif ext == ".npy":
        side = p.with_name(p.name + ".json")
        if side.exists() and not overwrite:
            raise OutputExistsError(side)
        info = {"format": "waveoptics height field", "units": "m", "dx": hf.dx, "dy": hf.dy,
                "meta": json.loads(meta_json)}
        if masked:
            info["mask"] = "nan"
        # both files are written to temporary names first and renamed together (sidecar, then heights); the
        # sidecar records the heights' fingerprint, so a kill between the two renames is refused on reading
        with atomic_path(p, overwrite=overwrite) as tmp, atomic_path(side, overwrite=True) as tmp_side:
            with open(tmp, "wb") as fh:
                np.save(fh, h_nan)
            info["heights_fingerprint"] = npy_fingerprint(tmp)
            tmp_side.write_text(to_json(info, indent=2))
    elif ext == ".exr":
        header = {"spacing_x": repr(hf.dx), "spacing_y": repr(hf.dy), "units": "m", "waveoptics_meta": meta_json}
        if masked:
            header["mask"] = "nan"
        write_exr(p, {"Z": h_nan}, header, overwrite=overwrite)
    else:
        lines = ["# waveoptics height field", "# units = m", f"# dx = {hf.dx!r}", f"# dy = {hf.dy!r}",
                 f"# nx = {hf.shape[1]}", f"# ny = {hf.shape[0]}", f"# meta = {meta_json}"]
        if masked:
            lines.append("# nan = mask")
        if ext == ".xyz":
            x, y = hf.coords()
            X, Y = np.broadcast_arrays(x[None, :], y[:, None])
            keep = hf.valid.ravel()
            cols = np.stack([X.ravel()[keep], Y.ravel()[keep], hf.heights.ravel()[keep]], axis=1)
            lines[1:1] = ["# layout = xyz", f"# x0 = {float(x[0])!r}", f"# y0 = {float(y[0])!r}"]
            body = cols
            delim = " "
        else:
            lines.insert(1, "# layout = matrix")
            body = h_nan
            delim = "," if ext == ".csv" else " "

        buf = _io.StringIO()
        np.savetxt(buf, body, fmt="%.17g", delimiter=delim)
        with atomic_path(p, overwrite=overwrite) as tmp:
            tmp.write_text("\n".join(lines) + "\n" + buf.getvalue())
    return p
