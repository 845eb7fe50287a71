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

import inspect
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import gammaln

from . import psd as _psdlib
from .errors import OutputExistsError, WaveopticsError, unknown
from .units import parse_length


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


# ----------------------------------------------------------------------------------------------------------------
# Power spectral densities (two-sided, ∫ S d²f = σ²) and their profile (1-D marginal) forms ∫ S(fx, fy) dfy.
# ----------------------------------------------------------------------------------------------------------------

#: Gaussian-correlation PSD π σ² T² exp(−π² T² f²) (f in 1/m, σ and T in m): the one in :mod:`waveoptics.psd`
psd_gaussian = _psdlib.S_gaussian


def psd_gaussian_profile(f, sigma, T):
    """1-D PSD of a straight profile through a Gaussian-correlated surface: √π σ² T exp(−π² T² f²), m³.

    It is ∫ S(fx, fy) dfy of :func:`psd_gaussian`, with ∫ S₁ df = σ² (Church, Takacs & Leonard 1989).
    """
    f = np.asarray(f, dtype=float)
    return math.sqrt(math.pi) * sigma**2 * T * np.exp(-(np.pi * T * f) ** 2)


#: Exponential-correlation PSD 2π σ² T² / (1 + (2π T f)²)^{3/2}: the one in :mod:`waveoptics.psd`; it is the
#: ABC PSD with A = 2πσ²T², B = 2πT, C = 3
psd_exponential = _psdlib.S_exponential


def psd_exponential_profile(f, sigma, T):
    """1-D PSD of a profile through an exponentially correlated surface: 2 σ² T / (1 + (2π T f)²), m³."""
    f = np.asarray(f, dtype=float)
    return 2 * sigma**2 * T / (1 + (2 * np.pi * T * f) ** 2)


def psd_abc(f, A, B, C):
    """ABC (K-correlation) PSD S(f) = A / (1 + (B f)²)^{C/2}.

    Parameters
    ----------
    f : array_like, 1/m
        Radial spatial frequency.
    A : float, m⁴
        Low-frequency plateau S(0).
    B : float, m
        Knee: the PSD bends over near f = 1/B.
    C : float
        Fall-off exponent (> 2 for a finite rms height); at high f, S ∝ f^(−C).

    Returns
    -------
    ndarray, m⁴

    References
    ----------
    .. [1] E. L. Church, P. Z. Takacs, Proc. SPIE 1530, 1991; σ² = 2πA / (B² (C − 2)).
    """
    f = np.asarray(f, dtype=float)
    return A / (1 + (B * f) ** 2) ** (C / 2)


def psd_abc_profile(f, A, B, C):
    """1-D profile PSD of the ABC surface: A √π Γ((C−1)/2) / (B Γ(C/2)) · (1 + (B f)²)^{(1−C)/2}, m³.

    From ∫ (1 + B²(fx² + fy²))^{−C/2} dfy; it integrates to the same σ² as :func:`psd_abc`.
    """
    f = np.asarray(f, dtype=float)
    pref = A * math.sqrt(math.pi) / B * math.exp(gammaln((C - 1) / 2) - gammaln(C / 2))
    return pref * (1 + (B * f) ** 2) ** ((1 - C) / 2)


def abc_sigma(A, B, C) -> float:
    """rms height σ (m) of the ABC PSD: σ² = 2π A / (B² (C − 2)), C > 2 (Church & Takacs 1991)."""
    if not C > 2:
        raise WaveopticsError(f"ABC exponent C={C!r} is not allowed; it must be > 2 for a finite rms height")
    return math.sqrt(2 * math.pi * A / (B**2 * (C - 2)))


def abc_A(sigma, B, C) -> float:
    """ABC plateau A (m⁴) giving rms height σ: A = σ² B² (C − 2) / (2π)."""
    if not C > 2:
        raise WaveopticsError(f"ABC exponent C={C!r} is not allowed; it must be > 2 for a finite rms height")
    return _psdlib.abc_A(sigma, B, C)


# ----------------------------------------------------------------------------------------------------------------
# Generators
# ----------------------------------------------------------------------------------------------------------------

def _length(value, name: str, *, allow_zero: bool = False) -> float:
    """A length in metres from a number (m) or a string with a unit ('5nm')."""
    if isinstance(value, str):
        return parse_length(value, name=name, allow_zero=allow_zero)
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise WaveopticsError(f"{name} {value!r} is not a length in metres") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        raise WaveopticsError(f"{name}={value!r} m is not allowed; it must be finite and "
                              f"{'>= 0' if allow_zero else '> 0'}")
    return v


def _number(value, name: str, *, lo=None, lo_open=False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise WaveopticsError(f"{name} {value!r} is not a number") from None
    if not math.isfinite(v) or (lo is not None and (v <= lo if lo_open else v < lo)):
        bound = "" if lo is None else f" and {'>' if lo_open else '>='} {lo:g}"
        raise WaveopticsError(f"{name}={value!r} is not allowed; it must be finite{bound}")
    return v


def _grid(size, samples) -> tuple[int, int, float, float]:
    """(nx, ny, dx, dy) from *size* (L or (Lx, Ly), m) and *samples* (n or (nx, ny)).

    A scalar size is the longer side with square pixels: dx = dy = size / max(nx, ny).
    """
    if isinstance(samples, str):
        parts = samples.lower().replace("x", ",").split(",")
        samples = parts[0] if len(parts) == 1 else parts
    ns = np.atleast_1d(samples)
    if ns.ndim != 1 or len(ns) not in (1, 2):
        raise WaveopticsError(f"samples {samples!r} is not allowed; give N or (NX, NY)")
    try:
        nsf = [float(n) for n in ns]
    except (TypeError, ValueError):
        raise WaveopticsError(f"samples {samples!r} is not an integer count") from None
    if any(not math.isfinite(n) or n != int(n) or n < 1 for n in nsf):
        raise WaveopticsError(f"samples {samples!r} is not allowed; counts must be integers >= 1")
    nx, ny = (int(nsf[0]), int(nsf[0])) if len(nsf) == 1 else (int(nsf[0]), int(nsf[1]))
    if nx * ny > 2**27:
        raise WaveopticsError(f"samples {nx}x{ny} is too many; at most 2^27 samples per field")
    if isinstance(size, str) and "," in size:
        size = size.split(",")
    if isinstance(size, (list, tuple, np.ndarray)):
        if len(size) != 2:
            raise WaveopticsError(f"size {size!r} is not allowed; give L or (Lx, Ly)")
        dx = _length(size[0], "size Lx") / nx
        dy = _length(size[1], "size Ly") / ny
    else:
        dx = dy = _length(size, "size") / max(nx, ny)
    return nx, ny, dx, dy


def _rng_seed(seed):
    """(Generator, seed actually used): a fresh seed is drawn and recorded when *seed* is None."""
    if seed is None:
        seed = int(np.random.SeedSequence().entropy % (2**63))
    try:
        seed = int(seed)
    except (TypeError, ValueError):
        raise WaveopticsError(f"seed {seed!r} is not an integer") from None
    if seed < 0:
        raise WaveopticsError(f"seed {seed!r} is not allowed; it must be >= 0")
    return np.random.default_rng(seed), seed


def _spectral(psd2d, psd1d, nx, ny, dx, dy, rng, sigma, *, renormalize: bool, exact_rms: bool):
    """Gaussian random field with PSD *psd2d* (or *psd1d* for a single row/column) on a periodic grid.

    Real white noise w (unit variance) is filtered in Fourier space by a_k = √(S(f_k) / (dx dy)), which makes
    E[h²] = Σ_k S(f_k) Δfx Δfy, the grid's share of σ² (the mean, k = 0, is set to zero). A 1×N or N×1 grid is
    a straight profile of the 2-D surface and uses the profile PSD ∫ S dfy instead.

    Returns
    -------
    h : ndarray (ny, nx), m
    fraction : float
        Σ_k S Δf² / σ²: the part of the variance the grid resolves (below 1 when L is not ≫ T or dx not ≪ T).
    """
    if nx * ny < 2:
        raise WaveopticsError("a random surface needs at least 2 samples")
    if ny == 1 or nx == 1:
        n, d = (nx, dx) if ny == 1 else (ny, dy)
        S = psd1d(np.abs(np.fft.fftfreq(n, d)))
        S[0] = 0.0
        var = S.sum() / (n * d)
        amp = np.sqrt(psd1d(np.fft.rfftfreq(n, d)) / d)
        amp[0] = 0.0
        h = np.fft.irfft(np.fft.rfft(rng.standard_normal(n)) * amp, n)
        h = h.reshape(ny, nx)
    else:
        fy = np.fft.fftfreq(ny, dy)[:, None]
        S = psd2d(np.hypot(fy, np.fft.fftfreq(nx, dx)[None, :]))
        S[0, 0] = 0.0
        var = S.sum() / (nx * dx * ny * dy)
        del S
        amp = np.sqrt(psd2d(np.hypot(fy, np.fft.rfftfreq(nx, dx)[None, :])) / (dx * dy))
        amp[0, 0] = 0.0
        h = np.fft.irfft2(np.fft.rfft2(rng.standard_normal((ny, nx))) * amp, s=(ny, nx))
    fraction = var / sigma**2
    if not fraction > 1e-12:
        raise WaveopticsError(f"the grid (spacing {dx:g} x {dy:g} m, {nx}x{ny} samples) resolves none of the "
                              "surface's spectrum; make the patch larger than, and the spacing finer than, "
                              "the correlation length")
    if exact_rms:
        rms = float(np.sqrt(np.mean(h**2)))
        if rms > 0:
            h *= sigma / rms
    elif renormalize:
        h *= 1.0 / math.sqrt(fraction)
    return h, fraction


def _random_meta(model, params, seed, fraction, renormalize, exact_rms):
    return {"model": model, **params, "seed": seed, "periodic": True, "psd_variance_fraction": fraction,
            "renormalize": renormalize, "exact_rms": exact_rms, "units": "m"}


def flat(size, samples) -> HeightField:
    """A flat surface h = 0.

    Parameters
    ----------
    size : float or str or (Lx, Ly), m
        Patch size; a scalar is the longer side with square pixels.
    samples : int or (nx, ny)
        Grid samples.
    """
    nx, ny, dx, dy = _grid(size, samples)
    return HeightField(np.zeros((ny, nx)), dx, dy, meta={"model": "flat", "periodic": True, "units": "m"})


def gaussian(sigma, corr_length, size, samples, seed=None, *, renormalize=True, exact_rms=False) -> HeightField:
    """Gaussian random surface with Gaussian correlation C(r) = σ² exp(−r²/T²).

    Parameters
    ----------
    sigma : float or str, m
        rms height σ.
    corr_length : float or str, m
        Correlation length T (C(T) = σ²/e). The rms of |∇h| is α = 2σ/T; per axis √2 σ/T.
    size : float or str or (Lx, Ly), m
        Patch size; a scalar is the longer side with square pixels.
    samples : int or (nx, ny)
        Grid samples; a 1×N grid is a straight profile of the 2-D surface.
    seed : int, optional
        Seed for ``numpy.random.default_rng``; drawn and recorded in ``meta["seed"]`` when None.
    renormalize : bool
        Scale the spectrum so that the *ensemble* mean square on this grid is σ² (default). The fraction of σ²
        the grid resolves before that scaling is ``meta["psd_variance_fraction"]``; when it is well below 1
        (patch not ≫ T or spacing not ≪ T) the surface is a band-limited version of the one asked for.
        False keeps S(f) exactly as specified (ensemble rms σ·√fraction).
    exact_rms : bool
        Rescale this realization so its own rms is exactly σ (not physical for an ensemble; off by default).

    Returns
    -------
    HeightField
        One period of a periodic surface (``meta["periodic"] = True``); each realization has zero mean.

    References
    ----------
    .. [1] Ogilvy 1991, §2.2, §4.2; Beckmann & Spizzichino 1963, ch. 5.
    """
    sigma = _length(sigma, "sigma")
    T = _length(corr_length, "corr_length")
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    h, frac = _spectral(lambda f: psd_gaussian(f, sigma, T), lambda f: psd_gaussian_profile(f, sigma, T),
                        nx, ny, dx, dy, rng, sigma, renormalize=renormalize, exact_rms=exact_rms)
    meta = _random_meta("gaussian", {"sigma": sigma, "corr_length": T}, seed, frac, renormalize, exact_rms)
    return HeightField(h, dx, dy, meta=meta)


def exponential(sigma, corr_length, size, samples, seed=None, *, renormalize=True,
                exact_rms=False) -> HeightField:
    """Gaussian random surface with exponential correlation C(r) = σ² exp(−r/T).

    Parameters are those of :func:`gaussian`. The slope variance of this surface diverges logarithmically
    with the highest resolved frequency, so its rms slope depends on the spacing (there is no finite α).

    References
    ----------
    .. [1] Ogilvy 1991, §2.2; Church & Takacs 1991.
    """
    sigma = _length(sigma, "sigma")
    T = _length(corr_length, "corr_length")
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    h, frac = _spectral(lambda f: psd_exponential(f, sigma, T), lambda f: psd_exponential_profile(f, sigma, T),
                        nx, ny, dx, dy, rng, sigma, renormalize=renormalize, exact_rms=exact_rms)
    meta = _random_meta("exponential", {"sigma": sigma, "corr_length": T}, seed, frac, renormalize, exact_rms)
    return HeightField(h, dx, dy, meta=meta)


def abc(B, C, size, samples, seed=None, *, A=None, sigma=None, renormalize=True, exact_rms=False) -> HeightField:
    """Gaussian random surface with the ABC (K-correlation, fractal-like) PSD A / (1 + (B f)²)^{C/2}.

    Parameters
    ----------
    B : float or str, m
        Knee length (the PSD bends at f ≈ 1/B).
    C : float
        Fall-off exponent, > 2.
    size, samples, seed, renormalize, exact_rms
        As in :func:`gaussian`.
    A : float, m⁴, optional
        Plateau. Give exactly one of *A* and *sigma*.
    sigma : float or str, m, optional
        rms height; A = σ² B² (C − 2) / (2π).

    References
    ----------
    .. [1] Church & Takacs, Proc. SPIE 1530, 1991; Holzschuch & Pacanowski, ACM TOG 36(4), 2017 (use in rendering).
    """
    B = _length(B, "B")
    C = _number(C, "C", lo=2, lo_open=True)
    if (A is None) == (sigma is None):
        raise WaveopticsError("ABC surface: give exactly one of A (m^4) and sigma (m)")
    if sigma is not None:
        sigma = _length(sigma, "sigma")
        A = abc_A(sigma, B, C)
    else:
        A = _number(A, "A", lo=0, lo_open=True)
        sigma = abc_sigma(A, B, C)
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    h, frac = _spectral(lambda f: psd_abc(f, A, B, C), lambda f: psd_abc_profile(f, A, B, C),
                        nx, ny, dx, dy, rng, sigma, renormalize=renormalize, exact_rms=exact_rms)
    meta = _random_meta("abc", {"A": A, "B": B, "C": C, "sigma": sigma}, seed, frac, renormalize, exact_rms)
    return HeightField(h, dx, dy, meta=meta)


def sinusoid(amplitude, period, size, samples, orientation_deg=0.0, phase_deg=0.0) -> HeightField:
    """Sinusoidal grating h = a sin(2π (x cos φ + y sin φ) / Λ + φ₀).

    Parameters
    ----------
    amplitude : float or str, m
        Amplitude a (rms height a/√2 over whole periods; rms of |∇h| = √2 π a / Λ).
    period : float or str, m
        Period Λ.
    size, samples
        As in :func:`gaussian`.
    orientation_deg : float, degrees
        Direction φ of the grating vector from the x axis (grooves run perpendicular to it).
    phase_deg : float, degrees
        Phase φ₀ at the patch centre.

    Notes
    -----
    ``meta["periodic"]`` is True only when the patch holds a whole number of periods along both axes; the
    diffraction orders are at sin θ_m = sin θ_i + m λ/Λ (physics.md §5).
    """
    a = _length(amplitude, "amplitude", allow_zero=True)
    P = _length(period, "period")
    phi = math.radians(_number(orientation_deg, "orientation_deg"))
    ph0 = math.radians(_number(phase_deg, "phase_deg"))
    nx, ny, dx, dy = _grid(size, samples)
    hf0 = HeightField(np.zeros((ny, nx)), dx, dy)
    x, y = hf0.coords()
    u = x[None, :] * math.cos(phi) + y[:, None] * math.sin(phi)
    h = a * np.sin(2 * np.pi * u / P + ph0)
    kx, ky = nx * dx * math.cos(phi) / P, ny * dy * math.sin(phi) / P
    periodic = bool(abs(kx - round(kx)) < 1e-9 and abs(ky - round(ky)) < 1e-9)
    meta = {"model": "sinusoid", "amplitude": a, "period": P, "orientation_deg": math.degrees(phi),
            "phase_deg": math.degrees(ph0), "periodic": periodic, "units": "m"}
    return HeightField(h, dx, dy, meta=meta)


#: most scratches :func:`scratches` draws (a billion would run for days, one grid pass each)
MAX_SCRATCHES = 10000


def scratches(count, width, depth, size, samples, orientation_deg=0.0, spread_deg=0.0, length=None,
              variation=0.0, seed=None) -> HeightField:
    """Random straight scratches (grooves) on a flat surface at h = 0.

    Each scratch is a groove of Gaussian cross-section, −d exp(−4 ln2 s² / w²) at distance s from its axis
    (w is the full width at half depth), through a uniformly random point of the patch. Where grooves overlap
    the deeper one wins (material removed once).

    Parameters
    ----------
    count : int
        Number of scratches, >= 0.
    width : float or str, m
        Full width at half depth w.
    depth : float or str, m
        Depth d (the groove bottom is at −d).
    size, samples
        As in :func:`gaussian`.
    orientation_deg : float, degrees
        Mean direction of the scratches from the x axis.
    spread_deg : float, degrees
        Directions are uniform in [orientation − spread, orientation + spread].
    length : float or str, m, optional
        Scratch length (rounded ends); None: they cross the whole patch.
    variation : float
        Relative spread of each scratch's width and depth: uniform in [1 − v, 1 + v], 0 <= v < 1.
    seed : int, optional
        RNG seed (recorded in ``meta["seed"]``).

    Notes
    -----
    The result is not periodic; scattering solvers see the patch edges as edges of the grooves.
    """
    n = _number(count, "count", lo=0)
    if n != int(n) or n > MAX_SCRATCHES:
        raise WaveopticsError(f"count={count!r} is not allowed; it must be a whole number in 0..{MAX_SCRATCHES} "
                              "(each scratch costs a pass over the grid)")
    n = int(n)
    w = _length(width, "width")
    d = _length(depth, "depth", allow_zero=True)
    th0 = _number(orientation_deg, "orientation_deg")
    spread = _number(spread_deg, "spread_deg", lo=0)
    ln = None if length is None else _length(length, "length")
    v = _number(variation, "variation", lo=0)
    if v >= 1:
        raise WaveopticsError(f"variation={variation!r} is not allowed; it must be in [0, 1)")
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    hf0 = HeightField(np.zeros((ny, nx)), dx, dy)
    x, y = hf0.coords()
    Lx, Ly = hf0.extent
    X, Y = x[None, :], y[:, None]
    h = np.zeros((ny, nx))
    for _ in range(n):
        px, py = rng.uniform(-Lx / 2, Lx / 2), rng.uniform(-Ly / 2, Ly / 2)
        th = math.radians(th0 + rng.uniform(-spread, spread))
        wi = w * rng.uniform(1 - v, 1 + v)
        di = d * rng.uniform(1 - v, 1 + v)
        s = -(X - px) * math.sin(th) + (Y - py) * math.cos(th)   # across the groove
        if ln is not None:
            t = (X - px) * math.cos(th) + (Y - py) * math.sin(th)  # along the groove
            s = np.hypot(s, np.maximum(np.abs(t) - ln / 2, 0.0))
        np.minimum(h, -di * np.exp(-4 * math.log(2) * s**2 / wi**2), out=h)
    meta = {"model": "scratches", "count": n, "width": w, "depth": d, "orientation_deg": th0,
            "spread_deg": spread, "length": ln, "variation": v, "seed": seed, "periodic": False, "units": "m"}
    return HeightField(h, dx, dy, meta=meta)


def _sum(components, size, samples, seed=None) -> HeightField:
    """Sum of several models on one grid (e.g. a micro-scale band plus a nano-scale band).

    Parameters
    ----------
    components : list of dict
        Each ``{"model": name, **params}`` without size/samples; random components get independent seeds
        spawned from *seed* unless they give their own.
    """
    if not isinstance(components, (list, tuple)) or not components:
        raise WaveopticsError("sum: components must be a non-empty list of {'model': ..., params} dicts")
    _, seed = _rng_seed(seed)
    children = np.random.SeedSequence(seed).spawn(len(components))
    total = None
    for comp, child in zip(components, children):
        if not isinstance(comp, dict) or "model" not in comp:
            raise WaveopticsError(f"sum: component {comp!r} is not a dict with a 'model' key")
        params = {k: v for k, v in comp.items() if k != "model"}
        if "seed" in inspect.signature(GENERATORS.get(comp["model"], flat)).parameters:
            params.setdefault("seed", int(child.generate_state(1, np.uint64)[0] >> np.uint64(1)))
        hf = generate(comp["model"], size=size, samples=samples, **params)
        total = hf if total is None else total + hf
    meta = dict(total.meta, model="sum", seed=seed)
    return HeightField(total.heights, total.dx, total.dy, total.mask, meta)


#: model name -> generator; every generator takes ``size`` and ``samples``
GENERATORS = {
    "flat": flat,
    "gaussian": gaussian,
    "exponential": exponential,
    "abc": abc,
    "sinusoid": sinusoid,
    "scratches": scratches,
    "sum": _sum,
}


def generate(model: str, **params) -> HeightField:
    """Generate a height field by model name (the registry :data:`GENERATORS`), as the CLI and scene files do.

    Parameters
    ----------
    model : str
        One of :data:`GENERATORS`.
    **params
        The generator's parameters; lengths may be strings with units ('5nm', '1.2um').

    Raises
    ------
    WaveopticsError
        Unknown model, unknown or missing parameter, or a bad value.
    """
    if model not in GENERATORS:
        raise unknown("surface model", model, GENERATORS)
    fn = GENERATORS[model]
    sig = inspect.signature(fn)
    bad = [k for k in params if k not in sig.parameters]
    if bad:
        raise WaveopticsError(f"surface model {model!r} has no parameter {bad[0]!r}; allowed: "
                              f"{', '.join(sig.parameters)}")
    missing = [k for k, p in sig.parameters.items() if p.default is inspect.Parameter.empty and k not in params]
    if missing:
        raise WaveopticsError(f"surface model {model!r} needs parameter {missing[0]!r}")
    return fn(**params)


# ----------------------------------------------------------------------------------------------------------------
# Statistics
# ----------------------------------------------------------------------------------------------------------------

DETRENDS = ("mean", "plane", "none")


def detrended(hf: HeightField, detrend: str = "mean") -> np.ndarray:
    """Heights with the mean (or least-squares plane) of the valid samples removed; invalid samples set to 0.

    Parameters
    ----------
    detrend : {'mean', 'plane', 'none'}
        'plane' also removes a tilt (levelling, as profilometer software does).

    Returns
    -------
    ndarray (ny, nx), m
    """
    if detrend not in DETRENDS:
        raise unknown("detrend", detrend, DETRENDS)
    valid = hf.valid
    if not valid.any():
        raise WaveopticsError("height field has no valid samples (mask is all False)")
    h = np.where(valid, hf.heights, 0.0)
    if detrend == "mean":
        h = h - h[valid].mean()
    elif detrend == "plane":
        x, y = hf.coords()
        X, Y = np.broadcast_arrays(x[None, :], y[:, None])
        cols = [np.ones(valid.sum())] + [c[valid] for c in (X, Y) if np.ptp(c[valid]) > 0]
        coef, *_ = np.linalg.lstsq(np.stack(cols, axis=1), hf.heights[valid], rcond=None)
        fit = coef[0] + sum(c * k for c, k in zip((X, Y)[: len(cols) - 1], coef[1:]))
        h = hf.heights - fit
    return np.where(valid, h, 0.0)


def rms_height(hf: HeightField, detrend: str = "mean") -> float:
    """rms height (m) of the valid samples about their mean (or plane)."""
    h = detrended(hf, detrend)
    return float(np.sqrt(np.mean(h[hf.valid] ** 2)))


def rms_slopes(hf: HeightField) -> tuple[float | None, float | None]:
    """Per-axis rms slopes (dimensionless) from forward differences between adjacent valid samples.

    Periodic fields (``meta["periodic"]``, no mask) include the difference across the wrap-around.

    Returns
    -------
    (s_x, s_y) : float or None
        None along an axis with a single sample.

    Notes
    -----
    A forward difference is the slope of the facet between two samples; for a spectrum resolved by the grid
    it underestimates the slope variance by about E[k⁴] dx² / (12 E[k²]) (0.05 % for T = 10 dx, Gaussian).
    """
    h, v = hf.heights, hf.valid
    periodic = hf.meta.get("periodic") and hf.mask is None
    out = []
    for axis, d in ((1, hf.dx), (0, hf.dy)):
        if h.shape[axis] < 2:
            out.append(None)
            continue
        if periodic:  # one period of a periodic surface: the last sample's neighbour is the first
            g = (np.roll(h, -1, axis=axis) - h) / d
            ok = v
        else:
            g = np.diff(h, axis=axis) / d
            ok = v[:, 1:] & v[:, :-1] if axis == 1 else v[1:, :] & v[:-1, :]
        out.append(float(np.sqrt(np.mean(g[ok] ** 2))) if ok.any() else None)
    return out[0], out[1]


def rms_slope(hf: HeightField) -> float:
    """rms of |∇h| (dimensionless), i.e. √(s_x² + s_y²); for Gaussian correlation it is α = 2σ/T.

    A single-row (or column) field is taken as the profile it is (h constant across it), so this is the rms
    of dh/dx along it. For a profile cut through an *isotropic* surface the 2-D rms of |∇h| is √2 times that.
    """
    sx, sy = rms_slopes(hf)
    if sx is None and sy is None:
        raise WaveopticsError("rms slope needs at least 2 samples along one axis")
    if sx is None or sy is None:
        return sx if sy is None else sy
    return math.hypot(sx, sy)


def _radial_bins(r, values, weights, width, r_max):
    """Mean of *values* (weighted) in bins of *width* of *r* up to *r_max*: (r_mean, value_mean, count)."""
    k = np.rint(r / width).astype(np.int64).ravel()
    keep = (r.ravel() <= r_max) & (weights.ravel() > 0)
    k, rv, vv, wv = k[keep], r.ravel()[keep], values.ravel()[keep], weights.ravel()[keep]
    n = np.bincount(k)
    wsum = np.bincount(k, wv)
    good = wsum > 0
    rm = np.bincount(k, rv * wv)[good] / wsum[good]
    vm = np.bincount(k, vv * wv)[good] / wsum[good]
    return rm, vm, n[good]


def autocorrelation_radial(hf: HeightField, detrend: str = "mean") -> tuple[np.ndarray, np.ndarray]:
    """Radially averaged autocovariance C(r) of the heights.

    Parameters
    ----------
    hf : HeightField
    detrend : {'mean', 'plane', 'none'}

    Returns
    -------
    r : ndarray, m
        Lag radii, from 0 to half the shorter patch side (bins of the finer spacing).
    C : ndarray, m²
        Autocovariance, C(0) = rms height².

    Notes
    -----
    Periodic fields without a mask (the spectral generators) use the circular estimator, exact on the torus.
    Others use the zero-padded estimator divided by the number of overlapping valid pairs at each lag
    (unbiased; masks are honoured by correlating the mask too) [1]_.

    References
    ----------
    .. [1] J. S. Bendat, A. G. Piersol, *Random Data*, 4th ed., Wiley 2010, §11.4 (FFT correlation estimates).
    """
    h = detrended(hf, detrend)
    ny, nx = hf.shape
    if hf.meta.get("periodic") and hf.mask is None:
        num = np.fft.irfft2(np.abs(np.fft.rfft2(h)) ** 2, s=(ny, nx))
        cnt = np.full((ny, nx), float(nx * ny))
        sy, sx = ny, nx
    else:
        from scipy.fft import next_fast_len
        sy, sx = (1 if ny == 1 else next_fast_len(2 * ny)), (1 if nx == 1 else next_fast_len(2 * nx))
        m = hf.valid.astype(float)
        num = np.fft.irfft2(np.abs(np.fft.rfft2(h, s=(sy, sx))) ** 2, s=(sy, sx))
        cnt = np.rint(np.fft.irfft2(np.abs(np.fft.rfft2(m, s=(sy, sx))) ** 2, s=(sy, sx)))
    lx = np.fft.fftfreq(sx, 1.0 / sx) * hf.dx
    ly = np.fft.fftfreq(sy, 1.0 / sy) * hf.dy
    r = np.hypot(ly[:, None], lx[None, :])
    with np.errstate(invalid="ignore", divide="ignore"):
        C = np.where(cnt > 0.5, num / np.maximum(cnt, 1.0), 0.0)
    sides = [L for L, n in zip(hf.extent, (nx, ny)) if n > 1]
    d = min(dd for dd, n in zip((hf.dx, hf.dy), (nx, ny)) if n > 1) if sides else hf.dx
    r_max = 0.5 * min(sides) if sides else 0.0
    rm, Cm, _ = _radial_bins(r, C, (cnt > 0.5).astype(float), d, r_max)
    return rm, Cm


def correlation_length(hf: HeightField, detrend: str = "mean") -> float:
    """Correlation length T (m): the first lag where the radial autocovariance falls to C(0)/e.

    This is the T of C(r) = σ² exp(−r²/T²) (and of σ² exp(−r/T)), found by linear interpolation between the
    bins of :func:`autocorrelation_radial`. Returns NaN when C never falls that far within half the patch.
    """
    r, C = autocorrelation_radial(hf, detrend)
    if C.size < 2 or C[0] <= 0:
        return float("nan")
    c = C / C[0]
    below = np.nonzero(c < 1 / math.e)[0]
    if below.size == 0:
        return float("nan")
    i = below[0]
    # linear interpolation between bins i-1 (above 1/e) and i (below)
    t = (c[i - 1] - 1 / math.e) / (c[i - 1] - c[i])
    return float(r[i - 1] + t * (r[i] - r[i - 1]))


def _psd(hf: HeightField, window="auto", detrend: str = "mean"):
    """Radially averaged periodogram: (f, S, count); profile PSD for single-row/column fields."""
    if window == "auto":
        window = None if (hf.meta.get("periodic") and hf.mask is None) else "hann"
    if window not in (None, "hann"):
        raise unknown("PSD window", window, ("auto", "hann", "none"))
    h = detrended(hf, detrend)
    ny, nx = hf.shape
    w = hf.valid.astype(float)
    if window == "hann":
        from scipy.signal.windows import hann
        w = w * np.outer(hann(ny, sym=False) if ny > 1 else [1.0], hann(nx, sym=False) if nx > 1 else [1.0])
    wsum2 = float(np.sum(w**2))
    if wsum2 <= 0:
        raise WaveopticsError("height field has no valid samples for a PSD")
    if ny == 1 or nx == 1:  # profile: 1-D two-sided PSD, ∫ S₁ df = σ²
        n, d = (nx, hf.dx) if ny == 1 else (ny, hf.dy)
        P = np.abs(np.fft.fft((w * h).ravel())) ** 2 * d / wsum2
        f = np.abs(np.fft.fftfreq(n, d))
        fr, S, cnt = _radial_bins(f, P, np.ones_like(f), 1.0 / (n * d), 0.5 / d)
        return fr[1:], S[1:], cnt[1:]
    P = np.abs(np.fft.fft2(w * h)) ** 2 * hf.dx * hf.dy / wsum2
    f = np.hypot(np.fft.fftfreq(ny, hf.dy)[:, None], np.fft.fftfreq(nx, hf.dx)[None, :])
    df = max(1.0 / (nx * hf.dx), 1.0 / (ny * hf.dy))
    fr, S, n = _radial_bins(f, P, np.ones_like(f), df, 0.5 / max(hf.dx, hf.dy))
    return fr[1:], S[1:], n[1:]


def psd_radial(hf: HeightField, window="auto", detrend: str = "mean") -> tuple[np.ndarray, np.ndarray]:
    """Radially averaged two-sided power spectral density of the heights.

    Parameters
    ----------
    hf : HeightField
    window : {'auto', 'hann', None}
        Leakage window (separable Hann). 'auto': none for periodic fields without a mask (spectral generators),
        Hann otherwise.
    detrend : {'mean', 'plane', 'none'}

    Returns
    -------
    f : ndarray, 1/m
        Mean radial frequency of each annulus (width max(1/Lx, 1/Ly)), from the first non-zero annulus up to
        the lower Nyquist frequency.
    S : ndarray, m⁴ (m³ for a single-row profile)
        Periodogram |FFT(w h)|² dx dy / Σw² averaged over each annulus, normalized so that ∫ S d²f ≈ ∫ 2π f S df
        equals the mean square of the windowed heights (σ²). For a single-row field it is the profile PSD
        with ∫ S df = σ² over −∞..∞.

    References
    ----------
    .. [1] Church, Takacs & Leonard, Proc. SPIE 1165, 1989 (two-sided PSD estimation from profiles);
       P. D. Welch, IEEE Trans. Audio Electroacoust. 15(2), 1967 (window normalization by Σw²).
    """
    f, S, _ = _psd(hf, window, detrend)
    return f, S


#: PSD models for :func:`fit_psd`: (2-D PSD, profile PSD, parameter names)
PSD_MODELS = {
    "gaussian": (psd_gaussian, psd_gaussian_profile, ("sigma", "T")),
    "exponential": (psd_exponential, psd_exponential_profile, ("sigma", "T")),
    "abc": (psd_abc, psd_abc_profile, ("A", "B", "C")),
}


def fit_psd(hf: HeightField, model: str = "gaussian", *, window="auto", detrend: str = "mean",
            floor: float = 1e-8) -> dict:
    """Fit a PSD model to the radial PSD of *hf* by weighted least squares on log S.

    Parameters
    ----------
    hf : HeightField
    model : {'gaussian', 'exponential', 'abc'}
    window, detrend
        As in :func:`psd_radial`.
    floor : float
        The fitted band stops where the PSD (smoothed over ~11 annuli) first falls below ``floor · max(S)``;
        window leakage and round-off live beyond.

    Returns
    -------
    dict
        ``model``; ``sigma_m``; for gaussian/exponential ``corr_length_m`` (and for gaussian ``beckmann_alpha``
        = 2σ/T); for abc ``A_m4``, ``B_m``, ``C``; ``f_range_per_m`` (fitted band) and ``rms_log_residual``.

    Notes
    -----
    Each periodogram value is S(f) times an exponential (χ²₂/2) variable; an annulus averages m independent ones
    (half its coefficients, since P(f) = P(−f) for real heights). Its log is biased by ψ(m) − ln m (−0.58 for a
    single value, as in every bin of a profile) with variance ψ′(m); the fit removes that bias and weights the
    residuals by 1/√ψ′(m) [2]_. Single-row fields are fitted with the profile PSD of the model.

    References
    ----------
    .. [1] Church & Takacs, Proc. SPIE 1530, 1991 (fitting finish parameters to measured PSDs).
    .. [2] M. Vaughan, "A simple test for periodic signals in red noise", A&A 431, 391–403, 2005, §3
       (bias ψ(m) − ln m and variance ψ′(m) of the log of an averaged periodogram).
    """
    from scipy.optimize import least_squares
    from scipy.special import digamma, polygamma

    if model not in PSD_MODELS:
        raise unknown("PSD model", model, PSD_MODELS)
    f, S, n = _psd(hf, window, detrend)
    profile = 1 in hf.shape
    psd2, psd1, names = PSD_MODELS[model]
    fn = psd1 if profile else psd2
    # the band ends where a running mean of S (over ~11 bins) first falls below floor·max: choosing bins by
    # their own noisy values would keep only the upward fluctuations in the tail and bias the fit
    from scipy.ndimage import uniform_filter1d

    smooth = uniform_filter1d(S, size=min(11, max(1, S.size)), mode="nearest") if S.size else S
    below = np.nonzero(smooth < floor * smooth.max())[0] if S.size else []
    stop = below[0] if len(below) else S.size
    keep = np.arange(S.size) < stop
    f, S, n = f[keep], S[keep], n[keep]
    if f.size < len(names) + 1:
        raise WaveopticsError(f"PSD fit '{model}': only {f.size} usable frequency bins; use a larger grid")
    # a real field has P(f) = P(−f): an annulus of n coefficients holds m = n/2 independent χ²₂ values, whose
    # mean has E[log] = log S + ψ(m) − log m and Var[log] = ψ′(m) (Gamma distribution)
    m = np.maximum(n / 2.0, 1.0)
    logS = np.log(S) - (digamma(m) - np.log(m))
    sw = 1.0 / np.sqrt(polygamma(1, m))
    var = float(np.sum(S * (2.0 if profile else 2 * np.pi * f)) * np.median(np.diff(f)))
    T0 = correlation_length(hf, detrend)
    if not np.isfinite(T0):
        T0 = 1.0 / f[len(f) // 2]
    s0 = math.sqrt(max(var, 1e-300))
    if model in ("gaussian", "exponential"):
        x0 = [math.log(s0), math.log(T0)]
        unpack = lambda p: (math.exp(p[0]), math.exp(p[1]))  # noqa: E731
    else:
        x0 = [math.log(S[0]), math.log(2 * np.pi * T0), 3.0]
        unpack = lambda p: (math.exp(p[0]), math.exp(p[1]), p[2])  # noqa: E731
    lo = [-np.inf] * len(x0)
    hi = [np.inf] * len(x0)
    if model == "abc":
        lo[2], hi[2] = 2.0 + 1e-6, 40.0

    def resid(p):
        with np.errstate(over="ignore", under="ignore"):
            m = fn(f, *unpack(p))
        return sw * (logS - np.log(np.maximum(m, 1e-300)))

    sol = least_squares(resid, x0, bounds=(lo, hi), x_scale="jac")
    pars = unpack(sol.x)
    out = {"model": model, "profile": profile, "f_range_per_m": [float(f[0]), float(f[-1])],
           "rms_log_residual": float(np.sqrt(np.mean(sol.fun**2)))}
    if model == "abc":
        A, B, C = pars
        out.update(A_m4=float(A), B_m=float(B), C=float(C), sigma_m=abc_sigma(A, B, C))
    else:
        out.update(sigma_m=float(pars[0]), corr_length_m=float(pars[1]))
        if model == "gaussian":
            out["beckmann_alpha"] = 2 * pars[0] / pars[1]
    return out


def stats(hf: HeightField, detrend: str = "mean") -> dict:
    """Summary statistics of a height field (the keys of ``waveoptics surface stats --json``).

    Returns
    -------
    dict
        ``samples`` [nx, ny]; ``spacing_m`` [dx, dy]; ``extent_m`` [Lx, Ly]; ``valid_fraction``;
        ``mean_height_m``; ``rms_height_m`` σ (about the mean or plane); ``rms_slope`` (rms of |∇h|, see
        :func:`rms_slope`); ``rms_slope_x``, ``rms_slope_y`` (None along an axis of one sample);
        ``corr_length_m`` T (1/e point of the autocovariance, :func:`correlation_length`);
        ``beckmann_alpha`` = 2σ/T, the Beckmann roughness that the geometric-optics limit predicts for a
        Gaussian-correlated surface (compare with ``rms_slope``: they agree only for that correlation);
        ``profile`` (True for a single row or column: ``rms_slope`` is then the profile's rms dh/dx, which is
        1/√2 of the 2-D rms |∇h| of an isotropic surface, while ``beckmann_alpha`` stays the 2-D value 2σ/T).

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963, ch. 5; physics.md §1.
    """
    ny, nx = hf.shape
    valid = hf.valid
    sigma = rms_height(hf, detrend)
    T = correlation_length(hf, detrend)
    sx, sy = rms_slopes(hf)
    return {
        "samples": [nx, ny],
        "spacing_m": [hf.dx, hf.dy],
        "extent_m": list(hf.extent),
        "valid_fraction": float(valid.mean()),
        "mean_height_m": float(hf.heights[valid].mean()),
        "rms_height_m": sigma,
        "rms_slope": rms_slope(hf) if (sx is not None or sy is not None) else None,
        "rms_slope_x": sx,
        "rms_slope_y": sy,
        "corr_length_m": T,
        "beckmann_alpha": 2 * sigma / T if np.isfinite(T) and T > 0 else None,
        "profile": bool(ny == 1 or nx == 1),
        "detrend": detrend,
    }


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

TEXT_EXTS = (".txt", ".dat", ".asc", ".csv", ".xyz")
FORMATS = (".npy", ".npz", ".exr") + TEXT_EXTS

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


def _ext(path) -> str:
    from pathlib import Path

    ext = Path(path).suffix.lower()
    if ext not in FORMATS:
        raise WaveopticsError(f"height-field file {str(path)!r} has unsupported extension {ext or '(none)'!r}; "
                              f"allowed: {', '.join(FORMATS)}")
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
        return _length(spacing[0], "spacing dx"), _length(spacing[1], "spacing dy")
    d = _length(spacing, "spacing")
    return d, d


def _unit_scale(units, what="units") -> float:
    from .units import LENGTH_UNITS

    if units not in LENGTH_UNITS:
        raise unknown(what, units, LENGTH_UNITS)
    return LENGTH_UNITS[units]


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
    import json

    try:
        meta = json.loads(text)
    except (TypeError, ValueError):
        raise WaveopticsError(f"{what}: metadata is not valid JSON") from None
    return meta if isinstance(meta, dict) else {}


def load(path, spacing=None, *, units=None, layout=None, nan_is_mask=False) -> HeightField:
    """Read a height field, choosing the format by extension (see :data:`FORMATS`).

    Parameters
    ----------
    path : str or Path
        .npz, .npy (+ optional sidecar ``path.json``), .exr, or a text grid (.txt .dat .asc .csv .xyz).
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
        declare this themselves.

    Returns
    -------
    HeightField
        Heights and spacings in metres; ``meta["source"]`` is the path.

    Raises
    ------
    WaveopticsError
        One line naming the file and the problem: missing, empty, truncated, not what its extension says,
        wrong dtype or shape, NaN/Inf heights, missing/zero/negative spacing, unknown units.
    """
    from pathlib import Path

    p = Path(path)
    ext = _ext(p)
    if not p.is_file():
        raise WaveopticsError(f"height-field file {str(p)!r} does not exist")
    if p.stat().st_size == 0:
        raise WaveopticsError(f"height-field file {str(p)!r} is empty")
    with open(p, "rb") as fh:
        head = fh.read(4096)
    kind = _sniff(head)
    expect = {".npy": "a NumPy .npy file", ".npz": "a zip/.npz archive", ".exr": "an OpenEXR image"}.get(ext, "text")
    if kind != expect:
        what = f"a {ext} text grid" if expect == "text" else expect
        raise WaveopticsError(f"{str(p)!r} is not {what} (its content looks like {kind})")
    sp = _spacing_arg(spacing)
    if units is not None:
        _unit_scale(units)  # refuse an unknown unit even where the file states its own
    try:
        if ext == ".npz":
            hf = _load_npz(p, sp, units, nan_is_mask)
        elif ext == ".npy":
            hf = _load_npy(p, sp, units, nan_is_mask)
        elif ext == ".exr":
            hf = _load_exr(p, sp, units, nan_is_mask)
        else:
            hf = _load_text(p, sp, units, layout, nan_is_mask)
    except WaveopticsError as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise WaveopticsError(msg if str(p) in msg else f"{str(p)!r}: {msg}") from None
    meta = dict(hf.meta, source=str(p))
    return HeightField(hf.heights, hf.dx, hf.dy, hf.mask, meta)


def _finish(h, sp, mask, meta, what):
    if sp is None:
        raise WaveopticsError(f"{what} does not state its grid spacing; pass spacing (CLI --spacing), e.g. 50nm")
    return HeightField(h, sp[0], sp[1], mask, meta)


def _load_npz(p, sp, units, nan_is_mask):
    import zipfile

    try:
        # an open handle of our own: np.load leaks the one it opens when the zip is broken
        with open(p, "rb") as fh, np.load(fh, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
        raise WaveopticsError(f"is truncated or not a valid .npz archive ({str(exc).splitlines()[0]})") from None
    if "heights" in data:
        key = "heights"
    elif len(data) == 1:
        key = next(iter(data))
    else:
        raise WaveopticsError(f"has arrays {sorted(data)} but no 'heights'")
    h = _real_heights(data[key], f"array {key!r}")
    u = str(data["units"]) if "units" in data else (units or "m")
    scale = _unit_scale(u)
    meta = _json_meta(str(data["meta"]), ".npz") if "meta" in data else {}
    if sp is None and "dx" in data:
        dx = float(np.asarray(data["dx"], dtype=float).ravel()[0])
        dy = float(np.asarray(data.get("dy", dx), dtype=float).ravel()[0])
        sp = (dx * scale, dy * scale)
    mask = None
    if "mask" in data:
        mask = np.asarray(data["mask"])
        if mask.dtype != bool or mask.shape != h.shape:
            raise WaveopticsError(f"mask is {mask.dtype} {mask.shape}; it must be bool with the heights' shape {h.shape}")
        h = np.where(mask, h, 0.0)
    h, nmask = _nan_mask(h, nan_is_mask, f"array {key!r}")
    mask = nmask if mask is None else (mask if nmask is None else mask & nmask)
    return _finish(h * scale, sp, mask, meta, "the .npz archive")


def _load_npy(p, sp, units, nan_is_mask):
    try:
        a = np.load(p, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise WaveopticsError(f"is truncated or not a valid .npy file ({str(exc).splitlines()[0]})") from None
    h = _real_heights(a, "the .npy array")
    side = p.with_name(p.name + ".json")
    meta, allow_nan = {}, nan_is_mask
    if side.is_file():
        info = _json_meta(side.read_text(errors="replace"), f"sidecar {side.name!r}")
        units = units or info.get("units", "m")
        scale = _unit_scale(units)
        meta = info.get("meta", {}) if isinstance(info.get("meta"), dict) else {}
        allow_nan = allow_nan or info.get("mask") == "nan"
        if sp is None and "dx" in info:
            try:
                sp = (float(info["dx"]) * scale, float(info.get("dy", info["dx"])) * scale)
            except (TypeError, ValueError):
                raise WaveopticsError(f"sidecar {side.name!r} spacing {info['dx']!r} is not a number") from None
    else:
        scale = _unit_scale(units or "m")
    h, mask = _nan_mask(h, allow_nan, "the .npy array")
    return _finish(h * scale, sp, mask, meta, f"the .npy file (no sidecar {side.name!r})")


def _load_exr(p, sp, units, nan_is_mask):
    from .io import read_exr

    chans, header = read_exr(p)
    if len(chans) == 1:
        name = next(iter(chans))
    elif "Z" in chans:
        name = "Z"
    else:
        raise WaveopticsError(f"has channels {sorted(chans)}; a height field needs one channel (or one named 'Z')")
    h = _real_heights(chans[name], f"EXR channel {name!r}")
    u = units or str(header.get("units", "m"))
    scale = _unit_scale(u, "EXR units")
    meta = _json_meta(header["waveoptics_meta"], "EXR header") if "waveoptics_meta" in header else {}
    if sp is None and "spacing_x" in header:
        try:
            dx = float(header["spacing_x"])
            dy = float(header.get("spacing_y", header["spacing_x"]))
        except (TypeError, ValueError):
            raise WaveopticsError(f"EXR header spacing_x={header['spacing_x']!r} is not a number") from None
        sp = (dx * scale, dy * scale)
    h, mask = _nan_mask(h, nan_is_mask or header.get("mask") == "nan", f"EXR channel {name!r}")
    return _finish(h * scale, sp, mask, meta, "the EXR header")


def _parse_text(p):
    """(header dict, data rows as list of token lists with their line numbers)."""
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise WaveopticsError("is not UTF-8 text") from None
    header, rows = {}, []
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
        rows.append((i, s.replace(",", " ").replace(";", " ").split()))
    # one leading line of column names (e.g. "x y z") is allowed
    if rows and all(not _is_number(t) for t in rows[0][1]):
        rows = rows[1:]
    if not rows:
        raise WaveopticsError("holds no data rows")
    return header, rows


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


def _float_header(header, key):
    if key not in header:
        return None
    try:
        return float(header[key])
    except ValueError:
        raise WaveopticsError(f"header {key} = {header[key]!r} is not a number") from None


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
        raise WaveopticsError("does not state its units; pass units (CLI --units), e.g. 'um', "
                              "or add a '# units = um' header line")
    scale = _unit_scale(units)
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
        try:
            sp = (float(header["dx"]) * scale, float(header.get("dy", header["dx"])) * scale)
        except ValueError:
            raise WaveopticsError(f"header spacing dx = {header['dx']!r} is not a number") from None
    if sp is None and "spacing" in header:
        sp = _spacing_arg(header["spacing"])
    if layout == "matrix":
        h, mask = _nan_mask(a, allow_nan, "the grid")
        return _finish(h * scale, sp, mask, meta, "the text matrix (no '# dx = ...' line)")
    if a.shape[1] != 3:
        raise WaveopticsError(f"xyz layout needs 3 columns (x y z), found {a.shape[1]}")
    if not np.all(np.isfinite(a[:, :2])):
        raise WaveopticsError("x/y columns hold NaN or Inf")
    hdr_dx = _float_header(header, "dx")
    ix, dx = _grid_axis(a[:, 0], "x", _float_header(header, "x0"), hdr_dx)
    iy, dy = _grid_axis(a[:, 1], "y", _float_header(header, "y0"), _float_header(header, "dy") or hdr_dx)
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
        with '# dx = ...' header, 17 significant digits: bit-exact) or .xyz (x y z columns).
    overwrite : bool
        Replace an existing file (default: refuse).

    Returns
    -------
    Path
    """
    import json
    from pathlib import Path

    from .io import atomic_path, to_json, write_exr, write_json

    p = Path(path)
    ext = _ext(p)
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
            raise OutputExistsError(f"output {str(side)!r} already exists; pass --overwrite to replace it")
        with atomic_path(p, overwrite=overwrite) as tmp, open(tmp, "wb") as fh:
            np.save(fh, h_nan)
        info = {"format": "waveoptics height field", "units": "m", "dx": hf.dx, "dy": hf.dy,
                "meta": json.loads(meta_json)}
        if masked:
            info["mask"] = "nan"
        write_json(side, info, overwrite=True)
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
        import io as _io

        buf = _io.StringIO()
        np.savetxt(buf, body, fmt="%.17g", delimiter=delim)
        with atomic_path(p, overwrite=overwrite) as tmp:
            tmp.write_text("\n".join(lines) + "\n" + buf.getvalue())
    return p


def plot(hf: HeightField, path, *, fits=(), overwrite: bool = False):
    """PNG with the height map (nm) and the radial PSD with fitted models, written atomically.

    Parameters
    ----------
    hf : HeightField
    path : str or Path
        Output .png.
    fits : iterable of dict
        Results of :func:`fit_psd` to overlay.
    overwrite : bool
        Replace an existing file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .io import atomic_path

    f, S = psd_radial(hf)
    profile = 1 in hf.shape
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.5))
    x, y = hf.coords()
    h_nm = np.where(hf.valid, hf.heights, np.nan) * 1e9
    if profile:
        ax0.plot((x if hf.shape[0] == 1 else y) * 1e6, h_nm.ravel(), lw=0.8)
        ax0.set(xlabel="position (µm)", ylabel="height (nm)")
    else:
        im = ax0.imshow(h_nm, origin="lower", cmap="viridis",
                        extent=[x[0] * 1e6, x[-1] * 1e6, y[0] * 1e6, y[-1] * 1e6])
        fig.colorbar(im, ax=ax0, label="height (nm)")
        ax0.set(xlabel="x (µm)", ylabel="y (µm)")
    ax0.set_title(str(hf.meta.get("model", hf.meta.get("source", "height field"))))
    ax1.loglog(f * 1e-6, S, ".", ms=3, label="radial periodogram")
    for fit in fits:
        fn = PSD_MODELS[fit["model"]][1 if profile else 0]
        args = ((fit["A_m4"], fit["B_m"], fit["C"]) if fit["model"] == "abc"
                else (fit["sigma_m"], fit["corr_length_m"]))
        ax1.loglog(f * 1e-6, fn(f, *args), lw=1.2, label=f"{fit['model']} fit")
    ax1.set(xlabel="spatial frequency |f| (1/µm)", ylabel="PSD (m³)" if profile else "PSD (m⁴)",
            ylim=(max(S.min(), S.max() * 1e-12), S.max() * 10))
    ax1.legend()
    fig.tight_layout()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
