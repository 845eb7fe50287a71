"""Pixel footprints on a height field: a Gaussian window anywhere on a (possibly huge) surface, and the local patch
it needs.

A pixel of a render sees the part of the surface its footprint covers, weighted by the pixel filter. As in Yan et
al. (2014, 2016, 2018) the footprint is a Gaussian

    G(x) = exp(−½ (x − c)ᵀ Σ⁻¹ (x − c)),   Σ = R(φ) diag(σ_x², σ_y²) R(φ)ᵀ,

centred at c = (x, y) (metres from the first sample: x along the grid's axis 1, y along axis 0, as
:func:`waveoptics.surfaces.crop_region`), with widths σ_x, σ_y (an ellipse for oblique views) turned by φ. The
patch it needs is the box holding the ellipse out to :data:`N_SIGMA` widths (G < exp(−8) ≈ 3e-4 beyond); a
footprint whose box leaves the surface is refused, not clipped (a clipped Gaussian is another window).

:class:`LargeHeightField` keeps a .npy height field memory-mapped, so that a footprint reads its local patch only
(an 8K × 8K float64 field is 512 MB; a 3 µm footprint on a 10 nm grid reads 240² samples); a label map and
plane slopes stored next to it (:mod:`waveoptics.surfaces.regions`) give each sample its region's slopes.

References
----------
.. [1] L.-Q. Yan, M. Hašan, W. Jakob, J. Lawrence, S. Marschner, R. Ramamoorthi, "Rendering glints on
   high-resolution normal-mapped specular surfaces", ACM TOG 33(4), 116, 2014 (Gaussian pixel footprints).
.. [2] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, "Position-normal distributions for efficient rendering of
   specular microstructure", ACM TOG 35(4), 56, 2016.
.. [3] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 75, 2018 (a Gaussian footprint, or coherence area, as the diffraction window).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FieldError, WaveopticsError
from ..units import parse_length
from .heightfield import HeightField
from .regions import npy_regions

__all__ = ["N_SIGMA", "Footprint", "LargeHeightField", "open_large", "footprint_box", "footprint_patch"]

#: half-width of a footprint's patch, in footprint widths
N_SIGMA = 4.0


@dataclass(frozen=True)
class Footprint:
    """A Gaussian footprint (see the module doc): centre *x*, *y* and widths *sigma* (*sigma_y*, default the
    same) in metres, the ellipse turned by *angle_deg* (degrees, counter-clockwise from the x axis)."""

    x: float
    y: float
    sigma: float
    sigma_y: float | None = None
    angle_deg: float = 0.0

    def __post_init__(self):
        for name in ("x", "y", "angle_deg"):
            if not math.isfinite(float(getattr(self, name))):
                raise FieldError(f"footprint {name}={getattr(self, name)!r} is not a finite number", "footprint")
        for name in ("sigma", "sigma_y"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(float(v)) and float(v) > 0):
                raise FieldError(f"footprint {name}={v!r} m is not allowed; a width must be > 0", "footprint")

    @classmethod
    def parse(cls, text: str) -> "Footprint":
        """From ``X,Y,SIGMA[,SIGMA_Y[,ANGLE_DEG]]`` with length units (``10um,12um,1.5um``)."""
        parts = [p.strip() for p in str(text).split(",")]
        if not 3 <= len(parts) <= 5:
            raise FieldError(f"footprint {text!r} is not allowed; give X,Y,SIGMA[,SIGMA_Y[,ANGLE_DEG]] with units, "
                             "e.g. 10um,12um,1.5um", "footprint")
        x, y = (parse_length(p, name="footprint", allow_zero=True, allow_negative=True) for p in parts[:2])
        s = parse_length(parts[2], name="footprint")
        sy = parse_length(parts[3], name="footprint") if len(parts) > 3 else None
        try:
            angle = float(parts[4]) if len(parts) > 4 else 0.0
        except ValueError:
            raise FieldError(f"footprint angle {parts[4]!r} is not a number of degrees", "footprint") from None
        return cls(x, y, s, sy, angle)

    @property
    def covariance(self) -> np.ndarray:
        """Σ (2, 2) in m²."""
        sx, sy = float(self.sigma), float(self.sigma_y if self.sigma_y is not None else self.sigma)
        c, s = math.cos(math.radians(self.angle_deg)), math.sin(math.radians(self.angle_deg))
        R = np.array([[c, -s], [s, c]])
        return R @ np.diag([sx * sx, sy * sy]) @ R.T

    def half_extent(self, n_sigma: float = N_SIGMA) -> tuple[float, float]:
        """Half-widths (m) of the axis-aligned box holding the ellipse out to *n_sigma* widths."""
        C = self.covariance
        return n_sigma * math.sqrt(C[0, 0]), n_sigma * math.sqrt(C[1, 1])

    def weights(self, X, Y) -> np.ndarray:
        """G at positions X, Y (m, broadcast)."""
        Ci = np.linalg.inv(self.covariance)
        dx, dy = np.asarray(X) - self.x, np.asarray(Y) - self.y
        return np.exp(-0.5 * (Ci[0, 0] * dx * dx + 2 * Ci[0, 1] * dx * dy + Ci[1, 1] * dy * dy))


class LargeHeightField:
    """A .npy height field kept memory-mapped: ``region`` reads only the samples it returns.

    Parameters
    ----------
    path : str or Path
        A .npy file (heights; its sidecar ``FILE.npy.json`` gives the spacing and unit, as
        :func:`waveoptics.surfaces.save` writes it).
    spacing : (dx, dy) in m, optional
        Overrides or completes the sidecar.
    units : str, optional
        Unit of the heights when the sidecar does not state it.
    """

    def __init__(self, path, spacing=None, units=None):
        from .formats import npy_parts

        p = Path(path)
        if p.suffix.lower() != ".npy":
            raise FieldError(f"a memory-mapped height field must be a .npy file, not {p.name!r}", "surface")
        if not p.is_file():
            raise WaveopticsError(f"file {str(p)!r} does not exist")
        sp = None if spacing is None else (float(spacing[0]), float(spacing[-1]))
        a, self.scale, sp, self.meta, self.nan_is_mask = npy_parts(p, sp, units, False, mmap=True)
        if a.ndim != 2 or a.dtype.kind not in "fiu" or a.size == 0:
            raise WaveopticsError(f"{str(p)!r} holds a {a.dtype} array of shape {a.shape}; heights must be a "
                                  "non-empty 2-D array of numbers")
        if sp is None:
            raise FieldError(f"{str(p)!r} does not state its grid spacing; pass {{spacing}}, e.g. 50nm", "spacing")
        self.array, self.dx, self.dy, self.path = a, float(sp[0]), float(sp[1]), p
        self._args = (str(p), spacing, units)
        #: the label map and plane slopes stored next to the file (:mod:`waveoptics.surfaces.regions`), or None
        self.planes = npy_regions(p, a.shape)

    @property
    def gives_slopes(self) -> bool:
        """Whether :meth:`region_slopes` gives each sample's own slopes (regions stored with the file)."""
        return self.planes is not None

    def region_slopes(self, i0: int, j0: int, i1: int, j1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(heights, ∂h/∂x, ∂h/∂y) of samples [j0:j1, i0:i1], the slopes from the stored regions."""
        if self.planes is None:
            raise FieldError(f"{str(self.path)!r} stores no regions (label map and plane slopes)", "regions")
        return (self.region(i0, j0, i1, j1).heights, *self.planes.slopes(i0, j0, i1, j1))

    def __reduce__(self):
        # pickled (e.g. sent to a Dask worker) as its file, not its samples: the worker maps the file itself
        return (type(self), self._args)

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.array.shape)

    def region(self, i0: int, j0: int, i1: int, j1: int) -> HeightField:
        """The samples [j0:j1, i0:i1] (rows y, columns x) as a :class:`HeightField` in metres."""
        h = np.asarray(self.array[j0:j1, i0:i1], dtype=np.float64) * self.scale
        bad = ~np.isfinite(h)
        if bad.any() and not self.nan_is_mask:
            raise WaveopticsError(f"{str(self.path)!r} holds non-finite heights in samples [{j0}:{j1}, {i0}:{i1}]")
        meta = dict(self.meta, source=str(self.path), cropped={"from_samples": [self.shape[1], self.shape[0]],
                                                               "origin_samples": [i0, j0]})
        return HeightField(np.where(bad, 0.0, h), self.dx, self.dy, ~bad if bad.any() else None, meta)


def open_large(path, spacing=None, units=None):
    """A height field for footprint queries: a :class:`LargeHeightField` (memory-mapped) for .npy files, else the
    whole field read by :func:`waveoptics.surfaces.load`."""
    if Path(path).suffix.lower() == ".npy":
        return LargeHeightField(path, spacing, units)
    from .formats import load

    return load(path, spacing=spacing, units=units)


def _region(field, i0, j0, i1, j1) -> HeightField:
    if not isinstance(field, HeightField):     # LargeHeightField or any tiled field (waveoptics.surfaces.tiled)
        return field.region(i0, j0, i1, j1)
    sl = (slice(j0, j1), slice(i0, i1))
    meta = {k: v for k, v in field.meta.items() if k != "periodic"}
    meta["cropped"] = {"from_samples": [field.shape[1], field.shape[0]], "origin_samples": [i0, j0]}
    return HeightField(field.heights[sl], field.dx, field.dy, None if field.mask is None else field.mask[sl], meta)


def footprint_box(fp: Footprint, dx: float, dy: float, n_sigma: float = N_SIGMA) -> tuple[int, int, int, int]:
    """Sample box (i0, j0, i1, j1) (columns [i0, i1), rows [j0, j1)) holding footprint *fp* out to *n_sigma*
    widths on a grid of spacing *dx*, *dy* (m) whose first sample is at the origin."""
    hx, hy = fp.half_extent(n_sigma)
    return (int(math.floor((fp.x - hx) / dx)), int(math.floor((fp.y - hy) / dy)),
            int(math.ceil((fp.x + hx) / dx)) + 1, int(math.ceil((fp.y + hy) / dy)) + 1)


def footprint_patch(field, fp: Footprint, n_sigma: float = N_SIGMA) -> tuple[HeightField, np.ndarray]:
    """The local patch of *field* (HeightField or :class:`LargeHeightField`) that footprint *fp* covers, and the
    footprint's weights G on it (ny, nx), zero where the field is masked.

    Raises
    ------
    FieldError
        When the footprint's box (*n_sigma* widths) leaves the field, or holds fewer than 2 × 2 samples.
    """
    ny, nx = field.shape
    hx, hy = fp.half_extent(n_sigma)
    i0, j0, i1, j1 = footprint_box(fp, field.dx, field.dy, n_sigma)
    if i0 < 0 or j0 < 0 or i1 > nx or j1 > ny:
        raise FieldError(
            f"footprint at ({fp.x * 1e6:.6g}, {fp.y * 1e6:.6g}) um with its {n_sigma:g}-width box "
            f"({2 * hx * 1e6:.6g} x {2 * hy * 1e6:.6g} um) leaves the field of {nx * field.dx * 1e6:.6g} x "
            f"{ny * field.dy * 1e6:.6g} um (positions are from the first sample)", "footprint")
    if i1 - i0 < 2 or j1 - j0 < 2:
        raise FieldError(f"footprint width {fp.sigma * 1e9:.4g} nm covers fewer than 2 x 2 samples of spacing "
                         f"{field.dx * 1e9:.4g} nm", "footprint")
    patch = _region(field, i0, j0, i1, j1)
    X = (i0 + np.arange(i1 - i0)) * field.dx
    Y = (j0 + np.arange(j1 - j0)) * field.dy
    w = fp.weights(X[None, :], Y[:, None]) * patch.valid
    return patch, w
