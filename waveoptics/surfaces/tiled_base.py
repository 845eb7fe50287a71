"""The base of the fields of :mod:`waveoptics.surfaces.tiled`: the :class:`TiledField` protocol (a height field read
by patches), :class:`TiledBase` (bounds checking, ``region`` → ``patch`` → ``_read``; the slopes stored with a field,
:mod:`waveoptics.surfaces.regions`) and the grid's checks.

References
----------
.. [1] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 75, 2018 (millimetre fields at sub-µm spacing, read by footprint).
"""
from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import FieldError
from .heightfield import HeightField

__all__ = ["TiledField", "TiledBase", "shape_spacing"]


@runtime_checkable
class TiledField(Protocol):
    """A height field read by patches (see the module doc): ``shape`` (ny, nx), spacing ``dx``, ``dy`` (m)."""

    shape: tuple
    dx: float
    dy: float

    def patch(self, i0: int, j0: int, nx: int, ny: int) -> HeightField: ...

    def region(self, i0: int, j0: int, i1: int, j1: int) -> HeightField: ...


class TiledBase:
    """Shared bounds checking: ``region`` → ``patch`` → ``_read`` (float64 heights in m)."""

    shape: tuple
    dx: float
    dy: float
    #: the label map and plane slopes stored with a field on disk (:class:`waveoptics.surfaces.regions.RegionPlanes`)
    planes = None

    @property
    def gives_slopes(self) -> bool:
        """Whether :meth:`region_slopes` gives each sample's own slopes (else slopes are finite differences)."""
        return self.planes is not None

    def region_slopes(self, i0: int, j0: int, i1: int, j1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(heights, ∂h/∂x, ∂h/∂y) of samples [j0:j1, i0:i1], the slopes from the regions stored with the field
        (:mod:`waveoptics.surfaces.regions`)."""
        if self.planes is None:
            raise FieldError(f"{self.describe()} stores no regions (label map and plane slopes)", "regions")
        h = self.region_heights(i0, j0, i1, j1)
        return (h, *self.planes.slopes(int(i0), int(j0), int(i1), int(j1)))

    def patch(self, i0: int, j0: int, nx: int, ny: int) -> HeightField:
        """Samples [j0:j0+ny, i0:i0+nx] as a HeightField in metres (refused when they leave the field)."""
        i0, j0, nx, ny = self._check(i0, j0, nx, ny)
        h = np.asarray(self._read(i0, j0, nx, ny), dtype=np.float64)
        return HeightField(h, self.dx, self.dy, None, {"source": self.describe(), "cropped": {
            "from_samples": [self.shape[1], self.shape[0]], "origin_samples": [i0, j0]}})

    def region(self, i0: int, j0: int, i1: int, j1: int) -> HeightField:
        return self.patch(i0, j0, i1 - i0, j1 - j0)

    def region_heights(self, i0: int, j0: int, i1: int, j1: int) -> np.ndarray:
        """Heights (m, float64) of samples [j0:j1, i0:i1], refused as :meth:`patch` when they leave the field; the
        array alone, without a HeightField's checks of every sample (what a render's footprint sums read)."""
        i0, j0, nx, ny = self._check(i0, j0, int(i1) - int(i0), int(j1) - int(j0))
        return np.asarray(self._read(i0, j0, nx, ny), dtype=np.float64)

    def _check(self, i0, j0, nx, ny):
        """(i0, j0, nx, ny) as ints, refused when the patch leaves the field."""
        i0, j0, nx, ny = int(i0), int(j0), int(nx), int(ny)
        if nx < 1 or ny < 1 or i0 < 0 or j0 < 0 or i0 + nx > self.shape[1] or j0 + ny > self.shape[0]:
            raise FieldError(f"patch [{j0}:{j0 + ny}, {i0}:{i0 + nx}] leaves the field of {self.shape[0]} x "
                             f"{self.shape[1]} samples", "patch")
        return i0, j0, nx, ny

    def describe(self) -> str:
        return type(self).__name__

    @property
    def extent(self) -> tuple[float, float]:
        """(Lx, Ly) in m."""
        return self.shape[1] * self.dx, self.shape[0] * self.dy


def shape_spacing(ny, nx, dx, dy):
    """(ny, nx, dx, dy) of a grid checked: at least 2 × 2 samples, spacings finite and > 0 (dy None: dx)."""
    ny, nx = int(ny), int(nx)
    dx = float(dx)
    dy = dx if dy is None else float(dy)
    if ny < 2 or nx < 2:
        raise FieldError(f"a field of {ny} x {nx} samples is not allowed; give at least 2 x 2", "shape")
    if not (math.isfinite(dx) and dx > 0 and math.isfinite(dy) and dy > 0):
        raise FieldError(f"spacing ({dx!r}, {dy!r}) m is not allowed; it must be > 0", "spacing")
    return ny, nx, dx, dy
