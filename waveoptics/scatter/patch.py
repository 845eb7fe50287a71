"""A height field prepared for the Kirchhoff sum: window, detrend and sample coordinates.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, WaveopticsError, unknown
from ..surfaces.heightfield import HeightField
from ..surfaces.statistics import DETRENDS

__all__ = ['DEFAULT_WINDOW', 'window', 'window_area', 'Samples', 'samples']

#: default smooth window (scipy.signal.windows name, symmetric form), applied separably along x and y
DEFAULT_WINDOW = "hann"


# ----------------------------------------------------------------------------------------------------------------
# Window, samples, Fresnel
# ----------------------------------------------------------------------------------------------------------------

def window(hf: HeightField, name=DEFAULT_WINDOW) -> np.ndarray:
    """Smooth window w(x, y) = w_x(x) w_y(y) over the patch, zero where the mask is False.

    Parameters
    ----------
    hf : HeightField
    name : str, tuple or ndarray
        A :func:`scipy.signal.windows.get_window` name (symmetric form), e.g. ``"hann"`` (default),
        ``"blackmanharris"``, ``("tukey", 0.5)``, or ``"boxcar"`` (no taper: edge ringing, for comparison);
        ``"gaussian:SIGMA"`` with a length (``"gaussian:1.5um"``: a Gaussian of that width in metres centred on
        the patch, a pixel footprint, :mod:`waveoptics.surfaces.footprint`); or explicit weights (ny, nx) ≥ 0.

    Returns
    -------
    ndarray (ny, nx)
        Weights in [0, 1]. The normalization of the BRDF uses A_w = Σ w² dx dy (:func:`window_area`).

    Notes
    -----
    A hard-edged patch diffracts like a rectangular aperture: sinc² side lobes that fall off as 1/q² and, after
    the 1/cos θ_o of the BRDF, spread light towards the horizon. The Hann taper's side lobes fall off as 1/q⁶
    (Harris 1978) at the cost of a main lobe twice as wide.

    References
    ----------
    .. [1] F. J. Harris, "On the use of windows for harmonic analysis with the discrete Fourier transform",
       Proc. IEEE 66(1), 1978.
    """

    ny, nx = hf.shape
    if isinstance(name, np.ndarray):
        w = np.asarray(name, dtype=float)
        if w.shape != hf.shape or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise FieldError(f"explicit window weights must be finite, >= 0 and of the patch's shape {hf.shape}, "
                             f"got shape {w.shape}", "window")
        w = w * hf.valid
        if not np.any(w > 0):
            raise WaveopticsError("the window leaves no sample with positive weight (mask empty or patch too small)")
        return w
    if isinstance(name, str) and name.lower().startswith("gaussian:"):
        from ..units import parse_length

        sigma = parse_length(name.split(":", 1)[1], name="window")
        name = ("gaussian", sigma / hf.dx)
        name_y = ("gaussian", sigma / hf.dy)
    else:
        name_y = name
    from scipy.signal.windows import get_window   # scipy.signal costs ~0.4 s to import: only where it is used

    try:
        wx = get_window(name, nx, fftbins=False) if nx > 1 else np.ones(1)
        wy = get_window(name_y, ny, fftbins=False) if ny > 1 else np.ones(1)
    except (ValueError, TypeError) as exc:
        raise WaveopticsError(f"window {name!r} is not allowed ({exc}); use a scipy.signal.windows name "
                              "such as 'hann', 'blackmanharris', ('tukey', 0.5) or 'boxcar'") from None
    w = np.outer(wy, wx) * hf.valid
    if not np.any(w > 0):
        raise WaveopticsError("the window leaves no sample with positive weight (mask empty or patch too small)")
    return w


def window_area(w, dx: float, dy: float) -> float:
    """A_w = Σ w² dx dy (m²), the normalization area of docs/physics.md §1."""
    return float(np.sum(np.asarray(w) ** 2) * dx * dy)


@dataclass(frozen=True)
class Samples:
    """The patch as a list of samples with positive window weight, as the kernels take it.

    Attributes
    ----------
    ix, iy : ndarray of int32
        Grid indices (column, row).
    h : ndarray of float64, m
        Heights with the w²-weighted mean (or plane) removed, see :func:`samples`.
    w : ndarray of float64
        Window weights.
    dx, dy : float, m
    nx, ny : int
    area : float, m²
        A_w = Σ w² dx dy.
    """

    ix: np.ndarray
    iy: np.ndarray
    h: np.ndarray
    w: np.ndarray
    dx: float
    dy: float
    nx: int
    ny: int
    area: float

    @property
    def size(self) -> int:
        return int(self.w.size)

    @property
    def extent(self) -> tuple[float, float]:
        return self.nx * self.dx, self.ny * self.dy

    def grid_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(h, w) back on the (ny, nx) grid (zeros where no sample)."""
        h = np.zeros((self.ny, self.nx))
        w = np.zeros((self.ny, self.nx))
        h[self.iy, self.ix] = self.h
        w[self.iy, self.ix] = self.w
        return h, w


def samples(hf: HeightField, window_name=DEFAULT_WINDOW, detrend: str = "mean") -> Samples:
    """Window the height field and list the samples with w > 0 (see :class:`Samples`).

    Parameters
    ----------
    detrend : {'mean', 'plane', 'none'}
        'plane' also removes the patch's tilt (least squares weighted by w², the weight of each sample in |U|²).
        A finite patch of a random surface has a mean slope; the Kirchhoff model reflects it like a tilted
        mirror, whose albedo differs from the untilted one by about tan θ_i times that slope. The (weighted)
        mean is removed in every case, 'none' included — it changes only the phase of U, but float32 rounding
        of h v_z grows with |h| (a 1 m offset changes nothing: ``tests/hard_cases.py``, offset cases).
    """

    if not isinstance(hf, HeightField):
        raise WaveopticsError(f"surface must be a HeightField, got {type(hf).__name__}")
    if detrend not in DETRENDS:
        raise unknown("detrend", detrend, DETRENDS)
    w = window(hf, window_name)
    iy, ix = np.nonzero(w > 0)
    ww = w[iy, ix]
    hh = hf.heights[iy, ix]
    w2 = ww**2
    # least squares weighted by w² (the weight each sample has in |U|²): mean, or mean and tilt
    cols = [np.ones_like(hh)]
    if detrend == "plane":
        cols += [c - np.sum(w2 * c) / np.sum(w2) for c in (ix * hf.dx, iy * hf.dy) if np.ptp(c) > 0]
    X = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(X * ww[:, None], hh * ww, rcond=None)
    hh = hh - X @ coef
    ny, nx = hf.shape
    if max(nx, ny) > 2**30:
        raise WaveopticsError(f"patch {nx}x{ny} is too large; at most 2^30 samples per side")
    return Samples(ix.astype(np.int32), iy.astype(np.int32), hh, ww, hf.dx, hf.dy, nx, ny,
                   window_area(ww, hf.dx, hf.dy))
