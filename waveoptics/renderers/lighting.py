"""Environment light: an equirectangular radiance map (a user's EXR, or a procedural sky or studio built here),
importance-sampled by its luminance, for sphere renders with multiple importance sampling (:mod:`waveoptics.renderers.sphere`).

Conventions (world space of the renders: camera looking down −z, x right, y up): the map's rows run from the
zenith (+y, row 0) to the nadir (−y), its columns over the azimuth φ measured about +y from −z (column 0, the
direction the camera looks) towards +x; so a direction is

    d = (sin θ sin φ, cos θ, −sin θ cos φ),   θ = π (row + ½) / H,   φ = 2π (col + ½) / W.

Values are linear sRGB radiance (D65 white). The sampling density of a pixel is proportional to its luminance
times sin θ (its solid angle), and the density over directions is p_pixel / (Δθ Δφ sin θ) (Pharr et al., §12.5).

The procedural maps are illustrations, not measured skies: ``sky`` is a zenith-to-horizon gradient with a warm
sun disc 5° across at (θ = 45°, φ = 30°) and a grey ground; ``studio`` is a dim room with two large softboxes.

References
----------
.. [1] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 2023, §12.5 (image infinite
   lights and their sampling).
.. [2] E. Veach, L. Guibas, "Optimally combining sampling techniques for Monte Carlo rendering", SIGGRAPH 1995
   (multiple importance sampling, balance heuristic).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import colour, io
from ..errors import FieldError

__all__ = ['PROCEDURAL', 'Environment', 'procedural_environment', 'load_environment', 'environment']

#: procedural maps built by :func:`procedural_environment`
PROCEDURAL = ("sky", "studio", "constant")


def _angles(h, w):
    theta = np.pi * (np.arange(h) + 0.5) / h
    phi = 2 * np.pi * (np.arange(w) + 0.5) / w
    return theta, phi


def _direction(theta, phi):
    return np.stack(np.broadcast_arrays(np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)),
                    axis=-1)


@dataclass(frozen=True, eq=False)
class Environment:
    """An equirectangular radiance map (H, W, 3) of linear sRGB with its sampling tables (see the module doc)."""

    radiance: np.ndarray
    name: str = "map"
    _tables: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        L = np.asarray(self.radiance, dtype=float)
        if L.ndim != 3 or L.shape[2] != 3 or L.shape[0] < 2 or L.shape[1] < 2:
            raise FieldError(f"an environment map must be (rows, columns, 3) RGB, got shape {L.shape}", "environment")
        if not np.all(np.isfinite(L)) or np.any(L < 0):
            raise FieldError("an environment map must hold finite radiance >= 0", "environment")
        object.__setattr__(self, "radiance", L)
        h, w = L.shape[:2]
        theta, _ = _angles(h, w)
        weight = np.maximum(colour.luminance(L), 0.0) * np.sin(theta)[:, None]
        total = weight.sum()
        if total <= 0:
            raise FieldError("an environment map must hold some light (its luminance is 0 everywhere)",
                             "environment")
        self._tables.update(p=(weight / total).ravel(), cdf=np.cumsum(weight.ravel()) / total, theta=theta)

    @property
    def shape(self):
        return self.radiance.shape[:2]

    def _pixel(self, d):
        d = np.asarray(d, dtype=float)
        h, w = self.shape
        theta = np.arccos(np.clip(d[..., 1], -1.0, 1.0))
        phi = np.mod(np.arctan2(d[..., 0], -d[..., 2]), 2 * np.pi)
        row = np.clip((theta / np.pi * h).astype(int), 0, h - 1)
        col = np.clip((phi / (2 * np.pi) * w).astype(int), 0, w - 1)
        return row, col

    def eval(self, d):
        """Radiance (..., 3) arriving from world directions *d* (..., 3) (nearest pixel)."""
        row, col = self._pixel(d)
        return self.radiance[row, col]

    def pdf(self, d):
        """Density (1/sr) of :meth:`sample` at world directions *d*."""
        row, col = self._pixel(d)
        h, w = self.shape
        sin_t = np.sqrt(np.maximum(1.0 - np.asarray(d, dtype=float)[..., 1] ** 2, 0.0))
        dens = self._tables["p"][row * w + col] / ((np.pi / h) * (2 * np.pi / w))
        return np.where(sin_t > 0, dens / np.where(sin_t > 0, sin_t, 1.0), 0.0)

    def sample(self, u):
        """World directions (..., 3) drawn with density :meth:`pdf` from uniform *u* (..., 2): a pixel by its
        luminance × solid angle, then uniformly in (θ, φ) inside it (density p_pixel / (Δθ Δφ sin θ))."""
        u = np.asarray(u, dtype=float)
        h, w = self.shape
        cdf = self._tables["cdf"]
        idx = np.minimum(np.searchsorted(cdf, u[..., 0] * cdf[-1], side="right"), cdf.size - 1)
        row, col = np.divmod(idx, w)
        lo = np.where(idx > 0, cdf[np.maximum(idx - 1, 0)], 0.0)
        frac = np.clip((u[..., 0] * cdf[-1] - lo) / np.maximum(cdf[idx] - lo, 1e-300), 0.0, 1.0)
        theta = np.pi * (row + frac) / h
        phi = 2 * np.pi * (col + u[..., 1]) / w
        return _direction(theta, phi)


def procedural_environment(kind: str = "sky", *, height: int = 128) -> Environment:
    """A procedural map (:data:`PROCEDURAL`; see the module doc) of *height* rows and 2 × height columns."""
    if kind not in PROCEDURAL:
        raise FieldError(f"environment {kind!r} is not allowed; use one of {', '.join(PROCEDURAL)} or an .exr file",
                         "environment")
    h, w = int(height), 2 * int(height)
    theta, phi = _angles(h, w)
    T, P = np.meshgrid(theta, phi, indexing="ij")
    d = _direction(T, P)
    if kind == "constant":
        return Environment(np.ones((h, w, 3)), "constant")
    if kind == "sky":
        up = np.clip(d[..., 1], 0.0, 1.0)[..., None]
        zenith, horizon = np.array([0.25, 0.45, 1.0]), np.array([0.9, 0.95, 1.0])
        L = np.where(d[..., 1:2] > 0, horizon + (zenith - horizon) * up ** 0.5, np.array([0.25, 0.23, 0.2]))
        sun = _direction(np.radians(45.0), np.radians(30.0))
        L = L + np.where((d @ sun > np.cos(np.radians(2.5)))[..., None], np.array([400.0, 380.0, 330.0]), 0.0)
        return Environment(L, "sky")
    L = np.full((h, w, 3), 0.03)
    for centre in (_direction(np.radians(60.0), np.radians(-50.0)), _direction(np.radians(70.0), np.radians(60.0))):
        L = L + np.where((d @ centre > np.cos(np.radians(18.0)))[..., None], 8.0, 0.0)
    return Environment(L, "studio")


def load_environment(path) -> Environment:
    """An equirectangular OpenEXR map with R, G, B channels (linear radiance) in the module's orientation."""
    p = Path(path)
    if p.suffix.lower() != ".exr":
        raise FieldError(f"environment file {str(p)!r} is not allowed; give an OpenEXR (.exr) equirectangular map",
                         "environment")
    if not p.is_file():
        raise FieldError(f"environment file {str(p)!r} does not exist", "environment")
    channels, _ = io.read_exr(p)
    if all(c in channels for c in "RGB"):
        rgb = np.stack([np.asarray(channels[c], dtype=float) for c in "RGB"], axis=-1)
    else:   # the OpenEXR bindings group R, G, B (and A) into one (H, W, 3 or 4) channel
        grouped = channels.get("RGB", channels.get("RGBA"))
        if grouped is None:
            raise FieldError(f"environment file {str(p)!r} has no R, G, B channels (it has "
                             f"{', '.join(sorted(channels))})", "environment")
        rgb = np.asarray(grouped, dtype=float)[..., :3]
    return Environment(rgb, p.name)


def environment(spec) -> Environment:
    """An :class:`Environment` from a name in :data:`PROCEDURAL`, an .exr path, or an Environment."""
    if isinstance(spec, Environment):
        return spec
    if str(spec) in PROCEDURAL:
        return procedural_environment(str(spec))
    return load_environment(spec)
