"""Preparing a measured height field for simulation, as surface-metrology software does before analysis:
levelling (removing the mean or the least-squares plane, ISO 25178-2's F-operation of form removal in its
simplest form [1]_) and cropping a region of interest.

References
----------
.. [1] ISO 25178-2:2012, "Geometrical product specifications (GPS) — Surface texture: Areal — Part 2: Terms,
   definitions and surface texture parameters", §3.1 (F-operation: removal of form, here a plane).
"""
from __future__ import annotations

import numpy as np

from ..errors import FieldError
from ..units import parse_length
from .heightfield import HeightField
from .statistics import detrended

__all__ = ['level', 'crop_region', 'parse_region']


def level(hf: HeightField, detrend: str = "plane") -> HeightField:
    """*hf* with its mean ('mean') or least-squares plane ('plane', the tilt of the mounted sample) removed over
    the valid samples; 'none' returns it unchanged. ``meta["levelled"]`` records the operation."""
    if detrend == "none":
        return hf
    return HeightField(detrended(hf, detrend), hf.dx, hf.dy, hf.mask, {**hf.meta, "levelled": detrend})


def parse_region(text) -> tuple[float, float, float, float]:
    """``"X,Y,WIDTH,HEIGHT"`` (lengths with units, e.g. ``"0um,0um,40um,40um"``) → (x, y, w, h) in metres."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 4:
        raise FieldError(f"{{crop}} {text!r} is not allowed; give X,Y,WIDTH,HEIGHT with units, e.g. "
                         "0um,0um,40um,40um", "crop")
    x, y = (parse_length(p, name="crop", allow_zero=True) for p in parts[:2])
    w, h = (parse_length(p, name="crop") for p in parts[2:])
    return x, y, w, h


def crop_region(hf: HeightField, x: float, y: float, width: float, height: float) -> HeightField:
    """The samples of *hf* inside the rectangle [x, x + width) × [y, y + height), in metres from the first
    sample (x along axis 1, y along axis 0, as the file's grid). A region reaching outside the field is refused,
    not clipped. ``meta["cropped"]`` records the region and the original grid."""
    ny, nx = hf.shape
    if not (width > 0 and height > 0) or x < 0 or y < 0:
        raise FieldError(f"{{crop}} region at ({x:g}, {y:g}) m of {width:g} x {height:g} m is not allowed; the "
                         "origin must be >= 0 and the size > 0", "crop")
    i0, j0 = int(np.floor(x / hf.dx + 1e-9)), int(np.floor(y / hf.dy + 1e-9))
    i1, j1 = int(np.ceil((x + width) / hf.dx - 1e-9)), int(np.ceil((y + height) / hf.dy - 1e-9))
    if i1 > nx or j1 > ny:
        raise FieldError(f"{{crop}} region reaches {(x + width) * 1e6:.6g} x {(y + height) * 1e6:.6g} um, beyond "
                         f"the field's {nx * hf.dx * 1e6:.6g} x {ny * hf.dy * 1e6:.6g} um", "crop")
    if i1 - i0 < 2 or j1 - j0 < 1:
        raise FieldError("{crop} region holds fewer than 2 samples along x", "crop")
    sl = (slice(j0, j1), slice(i0, i1))
    meta = {k: v for k, v in hf.meta.items() if k != "periodic"}   # a part of a periodic field is not periodic
    meta["cropped"] = {"from_samples": [nx, ny], "origin_samples": [i0, j0]}
    return HeightField(hf.heights[sl], hf.dx, hf.dy, None if hf.mask is None else hf.mask[sl], meta)
