"""What height-field files state about their heights besides the heights: units, grid spacing (as numbers in the
file's units or as lengths with a unit), the array names and the mask of a .npz archive. Shared by the readers of
:mod:`waveoptics.surfaces.formats`.
"""
from __future__ import annotations

import numpy as np

from ..errors import FieldError, WaveopticsError, unknown
from ..units import LENGTH_UNITS, length_unit, parse_length

__all__ = ['unit_scale', 'header_length', 'npz_spacing', 'npz_lengths', 'npz_coordinate_spacing', 'NPZ_METADATA',
           'npz_heights_key', 'npz_mask']


def unit_scale(units, what="units") -> float:
    """Metres per unit of heights: a symbol or name :func:`waveoptics.units.length_unit` knows (``um``, ``µm``,
    ``micron``, ``NM``, ``Å``)."""
    scale = length_unit(units) if isinstance(units, str) else None
    if scale is None:
        raise unknown(what, units, LENGTH_UNITS)
    return scale


def header_length(value, scale: float, what: str) -> float:
    """A spacing stated in a file's metadata, in metres: a bare number is in the file's height units (*scale*
    metres each), a number with a unit (``50 nm``, ``0.05um``) in that unit."""
    try:
        return float(value) * scale
    except (TypeError, ValueError):
        pass
    try:
        return parse_length(str(value), name="spacing")
    except FieldError:
        raise WaveopticsError(f"{what} = {value!r} is not a number or a length with a unit (e.g. 50nm)") from None


def npz_spacing(data: dict, name: str, scale: float):
    """(dx, dy) in metres stated by a .npz archive, or None: ``dx`` (and ``dy``, default dx), or a ``spacing`` /
    ``dx`` array of one value (square cells) or two (dx, dy), as numpy users write a grid's spacing."""
    key = "dx" if "dx" in data else ("spacing" if "spacing" in data else None)
    if key is None:
        return npz_coordinate_spacing(data, name, scale)
    v = npz_lengths(data[key], key, name, scale)
    if key == "dx" and "dy" in data:
        dy = npz_lengths(data["dy"], "dy", name, scale)
        if v.size != 1 or dy.size != 1:
            bad, n = ("dx", v.size) if v.size != 1 else ("dy", dy.size)
            raise WaveopticsError(f"{bad} in {name!r} holds {n} values; with both dx and dy each must be one "
                                  "spacing in metres")
        v = np.concatenate([v, dy])
    if v.size not in (1, 2):
        raise WaveopticsError(f"{key} in {name!r} holds {v.size} values; it must be one spacing in metres or two "
                              "(dx, dy)")
    return float(v[0]), float(v[-1])


def npz_lengths(value, key: str, name: str, scale: float) -> np.ndarray:
    """The spacing array *key* of a .npz archive in metres: numbers in the archive's units, or text with a unit
    (``"50nm"``, ``["50nm", "60nm"]``)."""
    a = np.asarray(value)
    if a.dtype.kind in "US":
        return np.array([header_length(str(t), scale, f"{key} in {name!r}") for t in a.ravel()])
    if a.dtype.kind not in "fiu":
        raise WaveopticsError(f"{key} in {name!r} holds {a.dtype} values; it must be numbers (in the archive's "
                              "units) or lengths with a unit")
    return a.astype(float).ravel() * scale


def npz_coordinate_spacing(data: dict, name: str, scale: float):
    """(dx, dy) in metres from 1-D coordinate arrays ``x`` and ``y`` of a .npz archive (as ``np.meshgrid`` users
    save them), or None without them; coordinates must be equally spaced."""
    if "x" not in data or "y" not in data:
        return None
    out = []
    for k in ("x", "y"):
        c = np.asarray(data[k], dtype=float)
        d = np.diff(c) if c.ndim == 1 and c.size > 1 else np.array([np.nan])
        if not (np.all(np.isfinite(d)) and d[0] > 0 and np.allclose(d, d[0], rtol=1e-6, atol=0)):
            raise WaveopticsError(f"coordinates {k!r} in {name!r} are not a 1-D increasing regular grid; give "
                                  "dx (and dy) instead")
        out.append(float(d[0]) * scale)
    return out[0], out[1]


#: arrays of a .npz archive that describe the heights rather than hold them
NPZ_METADATA = ("dx", "dy", "spacing", "units", "meta", "mask", "x", "y")


def npz_heights_key(data: dict) -> str:
    """The array holding the heights: ``heights``, or else the only array that is no metadata
    (:data:`NPZ_METADATA`), e.g. ``z`` or ``height`` beside ``dx``."""
    if "heights" in data:
        return "heights"
    rest = [k for k in data if k not in NPZ_METADATA]
    if len(rest) == 1:
        return rest[0]
    if len(data) == 1:
        return next(iter(data))
    raise WaveopticsError(f"has arrays {sorted(data)} but no 'heights' (and {len(rest)} arrays besides the "
                          f"metadata {', '.join(NPZ_METADATA)}, so none is the heights)")


def npz_mask(value, shape) -> np.ndarray:
    """A .npz mask (True = valid sample) as bool: bool, or integers holding only 0 and 1."""
    mask = np.asarray(value)
    if mask.dtype.kind in "iu" and mask.shape == shape and np.all((mask == 0) | (mask == 1)):
        mask = mask.astype(bool)
    if mask.dtype != bool or mask.shape != shape:
        raise WaveopticsError(f"mask is {mask.dtype} {mask.shape}; it must be bool (or 0/1 integers) with the "
                              f"heights' shape {shape}")
    return mask
