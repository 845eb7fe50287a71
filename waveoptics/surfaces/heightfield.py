"""Height fields: surface nanogeometry on a regular grid — type, generators, file formats and statistics.

Heights and spacings are in metres. Arrays are indexed ``h[iy, ix]`` with x along axis 1 (spacing ``dx``) and
y along axis 0 (spacing ``dy``). A patch of ``nx`` samples at spacing ``dx`` is ``Lx = nx dx`` long.

Random surfaces are synthesized spectrally: real white Gaussian noise is Fourier transformed, filtered by the
square root of the two-sided power spectral density (PSD) and transformed back, so each generated field is one
period of a periodic, stationary, Gaussian surface [1]_ [2]_. PSD conventions (``∫ S d²f = σ²``, f in cycles/m):

============  ==============================  ===========================================
model         correlation C(r)                PSD S(f)
============  ==============================  ===========================================
gaussian      σ² exp(−r²/T²)                  π σ² T² exp(−π² T² f²)
exponential   σ² exp(−r/T)                    2π σ² T² / (1 + (2π T f)²)^{3/2}
abc           K-correlation (Bessel K)        A / (1 + (B f)²)^{C/2},  σ² = 2πA / (B²(C−2))
============  ==============================  ===========================================

For Gaussian heights with Gaussian correlation the rms of |∇h| is 2σ/T, the Beckmann roughness α that the
geometric-optics limit of Kirchhoff scattering predicts [3]_; the rms slope along one axis is √2 σ/T.

References
----------
.. [1] J. A. Ogilvy, *Theory of Wave Scattering from Random Rough Surfaces*, Adam Hilger, 1991, §2.2 (correlation
   functions) and §4.2 (spectral synthesis).
.. [2] E. L. Church, P. Z. Takacs, "The optimal estimation of finish parameters", Proc. SPIE 1530, 71–85, 1991
   (ABC / K-correlation PSD); and E. L. Church, P. Z. Takacs, T. A. Leonard, "The prediction of BRDFs from
   surface profile measurements", Proc. SPIE 1165, 136–150, 1989 (two-sided PSD normalization, profile PSDs).
.. [3] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon,
   1963, ch. 5 (Gaussian surface, slope variance 2σ²/T² per axis).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import WaveopticsError

__all__ = ['HeightField']

#: largest |height| (m) a height field may hold, offsets included: a kilometre is far beyond any surface of wave
#: optics (a metre-high offset over nanometre relief is a hard case that must still work), while heights near
#: float64's range overflow every slope, phase and variance computed from them
HEIGHT_MAX_M = 1e3


@dataclass(frozen=True, eq=False)
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
        Free-form provenance (generator, parameters, seed, source file). ``meta["periodic"]`` is True when the
        field is one period of a periodic surface (spectral generators), which the statistics use to skip
        the leakage window.

    Notes
    -----
    Height fields on the same grid add (``hf1 + hf2``: e.g. a micro-scale band plus a nano-scale band) and scale
    by a real number (``0.5 * hf``). The sum's mask is the intersection of the masks.
    """

    heights: np.ndarray
    dx: float
    dy: float | None = None
    mask: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        h = np.asarray(self.heights)
        if h.dtype.kind not in "fiu":
            raise WaveopticsError(f"height field dtype {h.dtype} is not allowed; heights must be real numbers")
        h = np.asarray(h, dtype=np.float64)
        if h.ndim == 1:
            h = h[None, :]
        if h.ndim != 2 or h.size == 0:
            raise WaveopticsError(f"height field must be a non-empty 2-D grid, got shape {np.shape(self.heights)}")
        if not np.all(np.isfinite(h)):
            raise WaveopticsError("height field holds NaN or Inf values; heights must be finite (use a mask)")
        top = float(np.max(np.abs(h)))
        if top > HEIGHT_MAX_M:   # slopes, phases and variances of such heights overflow (and no optics is left)
            raise WaveopticsError(f"height field reaches {top:.3g} m; heights beyond {HEIGHT_MAX_M:g} m are not a "
                                  "surface this tool models (were they in another unit?)")
        dy = self.dx if self.dy is None else self.dy
        for name, v in (("dx", self.dx), ("dy", dy)):
            try:
                ok = np.isfinite(v) and v > 0
            except TypeError:
                ok = False
            if not ok:
                raise WaveopticsError(f"height-field spacing {name}={v!r} m is not allowed; it must be finite and > 0")
        object.__setattr__(self, "heights", h)
        object.__setattr__(self, "dx", float(self.dx))
        object.__setattr__(self, "dy", float(dy))
        if self.mask is not None:
            m = np.asarray(self.mask)
            if m.shape != h.shape:
                raise WaveopticsError(f"mask shape {m.shape} differs from heights shape {h.shape}")
            object.__setattr__(self, "mask", m.astype(bool))
        object.__setattr__(self, "meta", dict(self.meta or {}))

    @property
    def shape(self) -> tuple[int, int]:
        """(ny, nx)"""
        return self.heights.shape

    @property
    def extent(self) -> tuple[float, float]:
        """Patch size (Lx, Ly) in metres."""
        ny, nx = self.shape
        return nx * self.dx, ny * self.dy

    @property
    def valid(self) -> np.ndarray:
        """Boolean (ny, nx): the mask, or all True when there is none."""
        return np.ones(self.shape, bool) if self.mask is None else self.mask

    #: meta keys that say where a height field came from (file, instrument, channel, unit of the file)
    PROVENANCE_KEYS = ("source", "source_format", "channel", "file_unit", "instrument", "acquisition_time",
                       "model", "seed", "cropped_from", "cropped", "levelled", "transformed", "prepared_from", "split_cutoff_period_m")

    def provenance(self) -> dict:
        """Where this height field came from and its grid: ``samples`` [nx, ny], ``spacing_m`` [dx, dy] (m), and
        the :attr:`PROVENANCE_KEYS` its ``meta`` holds (an instrument file's format, channel, unit, instrument and
        acquisition time; a generator's model and seed). Written into outputs that used the field."""
        out = {"samples": [self.shape[1], self.shape[0]], "spacing_m": [self.dx, self.dy],
               "valid_fraction": float(self.valid.mean())}
        out.update({k: self.meta[k] for k in self.PROVENANCE_KEYS if k in self.meta})
        return out

    def coords(self) -> tuple[np.ndarray, np.ndarray]:
        """Sample positions x (nx,) and y (ny,) in metres, centred on the patch."""
        ny, nx = self.shape
        return (np.arange(nx) - (nx - 1) / 2) * self.dx, (np.arange(ny) - (ny - 1) / 2) * self.dy

    def same_grid(self, other: "HeightField") -> bool:
        """True when *other* has the same shape and spacings (to 1e-9 relative)."""
        return (self.shape == other.shape and math.isclose(self.dx, other.dx, rel_tol=1e-9)
                and math.isclose(self.dy, other.dy, rel_tol=1e-9))

    def __add__(self, other):
        if isinstance(other, (int, float)) and other == 0:  # lets sum() start from 0
            return self
        if not isinstance(other, HeightField):
            return NotImplemented
        if not self.same_grid(other):
            raise WaveopticsError(f"cannot add height fields on different grids: {self.shape} at "
                                  f"({self.dx:g}, {self.dy:g}) m vs {other.shape} at ({other.dx:g}, {other.dy:g}) m")
        if self.mask is None and other.mask is None:
            mask = None
        else:
            mask = self.valid & other.valid
        meta = {"model": "sum", "components": [self.meta, other.meta],
                "periodic": bool(self.meta.get("periodic") and other.meta.get("periodic"))}
        return HeightField(self.heights + other.heights, self.dx, self.dy, mask, meta)

    __radd__ = __add__

    def __mul__(self, factor):
        if not isinstance(factor, (int, float, np.integer, np.floating)) or not np.isfinite(factor):
            return NotImplemented
        meta = {"model": "scaled", "factor": float(factor), "component": self.meta,
                "periodic": bool(self.meta.get("periodic"))}
        return HeightField(self.heights * float(factor), self.dx, self.dy, self.mask, meta)

    __rmul__ = __mul__
