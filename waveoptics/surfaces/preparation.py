"""Preparing a measured height field for simulation, as surface-metrology software does before analysis:
levelling (removing the mean or the least-squares plane, ISO 25178-2's F-operation of form removal in its
simplest form [1]_), cropping a region of interest, and deforming it (stretch, rotation, height scale).

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

__all__ = ['level', 'crop_region', 'parse_region', 'transform']


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


def transform(hf: HeightField, *, stretch=(1.0, 1.0), rotate_deg: float = 0.0, height_scale: float = 1.0,
              order: int = 3) -> HeightField:
    """A deformed copy of *hf*: stretched laterally, rotated about the patch centre, heights scaled.

    Stretching by (s_x, s_y) multiplies the spacings (the samples stay, so it is exact): slopes along x scale by
    h_s / s_x and along y by h_s / s_y, and an NDF's α_x, α_y with them — the skin-deformation model of Nagano
    et al. [1]_ in its simplest, affine form. Rotation by φ resamples the heights on the same grid turned by φ
    (cubic splines, ``order`` 3, SciPy's ``map_coordinates``); output samples whose source lies outside the patch
    become masked (no wrapping: a turned period does not tile the same rectangle). The mask follows the samples.

    Parameters
    ----------
    stretch : float or (float, float)
        Lateral stretch factors (s_x, s_y) > 0 (one number: both).
    rotate_deg : float, degrees
        Counter-clockwise rotation of the surface about the patch centre.
    height_scale : float
        Factor on the heights (≥ 0); 0 flattens.
    order : int
        Spline order of the rotation's interpolation (1 linear … 5).

    References
    ----------
    .. [1] K. Nagano, G. Fyffe, O. Alexander, J. Barbič, H. Li, A. Ghosh, P. Debevec, "Skin microstructure
       deformation with displacement map convolution", ACM TOG 34(4):109, 2015, §4 (stretch and compression of
       the microgeometry change its slope distribution).
    """
    from scipy import ndimage

    sx, sy = (stretch, stretch) if np.ndim(stretch) == 0 else tuple(stretch)
    for axis, v in (("x", sx), ("y", sy)):
        if not (np.isfinite(v) and v > 0):
            raise FieldError(f"{{stretch}} factor {v!r} along {axis} is not allowed; it must be > 0", "stretch")
    if not (np.isfinite(height_scale) and height_scale >= 0):
        raise FieldError(f"{{height_scale}} {height_scale!r} is not allowed; it must be >= 0", "height_scale")
    if not np.isfinite(rotate_deg):
        raise FieldError(f"{{rotate_deg}} {rotate_deg!r} is not allowed; it must be finite", "rotate_deg")
    h, mask = hf.heights * float(height_scale), hf.mask
    dx, dy = hf.dx * float(sx), hf.dy * float(sy)
    meta = dict(hf.meta, transformed={"stretch": [float(sx), float(sy)], "rotate_deg": float(rotate_deg),
                                      "height_scale": float(height_scale)})
    if rotate_deg % 360.0:
        ny, nx = h.shape
        c, s = np.cos(np.radians(rotate_deg)), np.sin(np.radians(rotate_deg))
        x = (np.arange(nx) - (nx - 1) / 2) * dx
        y = (np.arange(ny) - (ny - 1) / 2) * dy
        X, Y = np.meshgrid(x, y)
        xs, ys = c * X + s * Y, -s * X + c * Y                        # the source point of each output sample
        cols = xs / dx + (nx - 1) / 2
        rows = ys / dy + (ny - 1) / 2
        # no wrapping, even for a periodic field: a turned period does not tile the same rectangle, and the
        # seams would add slopes that are not on the surface; what the turned patch does not cover is masked
        tol = 1e-9
        inside = (cols >= -tol) & (cols <= nx - 1 + tol) & (rows >= -tol) & (rows <= ny - 1 + tol)
        h = ndimage.map_coordinates(h, [rows, cols], order=order, mode="nearest")
        if mask is not None:   # a sample is valid where its source neighbourhood was
            inside &= ndimage.map_coordinates(mask.astype(float), [rows, cols], order=1, mode="nearest") > 0.999
        mask = None if inside.all() else inside
        h = np.where(inside, h, 0.0)
        meta["periodic"] = False
    return HeightField(h, dx, dy, mask, meta)
