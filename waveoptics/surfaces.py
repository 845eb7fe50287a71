"""Height fields: surface nanogeometry on a regular grid.

Heights and spacings are in metres. Arrays are indexed ``h[iy, ix]`` with x along axis 1.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import WaveopticsError


@dataclass(frozen=True)
class HeightField:
    """Surface heights on a regular grid.

    Parameters
    ----------
    heights : ndarray (ny, nx), m
        Surface height h(x, y) in metres, finite.
    dx, dy : float, m
        Grid spacing along x (axis 1) and y (axis 0), > 0.
    mask : ndarray of bool (ny, nx), optional
        True where the height is valid (measured); invalid samples are excluded from statistics and
        from the scattering aperture.
    meta : dict
        Free-form provenance (generator, parameters, seed, source file).
    """

    heights: np.ndarray
    dx: float
    dy: float | None = None
    mask: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        h = np.asarray(self.heights, dtype=np.float64)
        if h.ndim == 1:
            h = h[None, :]
        if h.ndim != 2 or h.size == 0:
            raise WaveopticsError(f"height field must be a non-empty 2-D grid, got shape {np.shape(self.heights)}")
        if not np.all(np.isfinite(h)):
            raise WaveopticsError("height field holds NaN or Inf values; heights must be finite (use a mask)")
        dy = self.dx if self.dy is None else self.dy
        for name, v in (("dx", self.dx), ("dy", dy)):
            if not np.isfinite(v) or v <= 0:
                raise WaveopticsError(f"height-field spacing {name}={v!r} m is not allowed; it must be finite and > 0")
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "dx", float(self.dx))
        object.__setattr__(self, "dy", float(dy))
        if self.mask is not None:
            m = np.asarray(self.mask, dtype=bool)
            if m.shape != h.shape:
                raise WaveopticsError(f"mask shape {m.shape} differs from heights shape {h.shape}")
            object.__setattr__(self, "mask", m)

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx)"""
        return self.heights.shape

    @property
    def extent(self) -> tuple[float, float]:
        """Patch size (Lx, Ly) in metres."""
        ny, nx = self.shape
        return nx * self.dx, ny * self.dy

    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        """Sample positions x (nx,) and y (ny,) in metres, centred on the patch."""
        ny, nx = self.shape
        return (np.arange(nx) - (nx - 1) / 2) * self.dx, (np.arange(ny) - (ny - 1) / 2) * self.dy
