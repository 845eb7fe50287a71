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

from .errors import WaveopticsError, unknown
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

def psd_gaussian(f, sigma, T):
    """Two-sided 2-D PSD of a Gaussian-correlated surface, C(r) = σ² exp(−r²/T²).

    Parameters
    ----------
    f : array_like, 1/m
        Radial spatial frequency |f| (cycles per metre).
    sigma : float, m
        rms height σ.
    T : float, m
        Correlation length (C(T) = σ²/e).

    Returns
    -------
    ndarray, m⁴
        S(f) = π σ² T² exp(−π² T² f²), with ∫ S d²f = σ².

    References
    ----------
    .. [1] Ogilvy 1991, §2.2; Church, Takacs & Leonard 1989 (two-sided normalization).
    """
    f = np.asarray(f, dtype=float)
    return np.pi * sigma**2 * T**2 * np.exp(-(np.pi * T * f) ** 2)


def psd_gaussian_profile(f, sigma, T):
    """1-D PSD of a straight profile through a Gaussian-correlated surface: √π σ² T exp(−π² T² f²), m³.

    It is ∫ S(fx, fy) dfy of :func:`psd_gaussian`, with ∫ S₁ df = σ² (Church, Takacs & Leonard 1989).
    """
    f = np.asarray(f, dtype=float)
    return math.sqrt(math.pi) * sigma**2 * T * np.exp(-(np.pi * T * f) ** 2)


def psd_exponential(f, sigma, T):
    """Two-sided 2-D PSD of an exponentially correlated surface, C(r) = σ² exp(−r/T).

    Parameters
    ----------
    f : array_like, 1/m
        Radial spatial frequency.
    sigma, T : float, m
        rms height and correlation length (C(T) = σ²/e).

    Returns
    -------
    ndarray, m⁴
        S(f) = 2π σ² T² / (1 + (2π T f)²)^{3/2}; it is the ABC PSD with A = 2πσ²T², B = 2πT, C = 3.

    References
    ----------
    .. [1] Ogilvy 1991, §2.2; Church & Takacs 1991 (K-correlation family, C = 3).
    """
    f = np.asarray(f, dtype=float)
    return 2 * np.pi * sigma**2 * T**2 / (1 + (2 * np.pi * T * f) ** 2) ** 1.5


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
    return sigma**2 * B**2 * (C - 2) / (2 * math.pi)


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
    if n != int(n):
        raise WaveopticsError(f"count={count!r} is not allowed; it must be a whole number >= 0")
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
    out = []
    for axis, d in ((1, hf.dx), (0, hf.dy)):
        if h.shape[axis] < 2:
            out.append(None)
            continue
        g = np.diff(h, axis=axis) / d
        ok = v[:, 1:] & v[:, :-1] if axis == 1 else v[1:, :] & v[:-1, :]
        out.append(float(np.sqrt(np.mean(g[ok] ** 2))) if ok.any() else None)
    return out[0], out[1]


def rms_slope(hf: HeightField) -> float:
    """rms of |∇h| (dimensionless), i.e. √(s_x² + s_y²); for Gaussian correlation it is α = 2σ/T.

    For a single-row (or column) profile the surface is assumed isotropic: √2 times the profile's rms slope.
    """
    sx, sy = rms_slopes(hf)
    if sx is None and sy is None:
        raise WaveopticsError("rms slope needs at least 2 samples along one axis")
    if sx is None or sy is None:
        return math.sqrt(2) * (sx if sy is None else sy)
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
        return _radial_bins(f, P, np.ones_like(f), 1.0 / (n * d), 0.5 / d)
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
        Annuli with S below ``floor · max(S)`` are left out (window leakage and round-off live there).

    Returns
    -------
    dict
        ``model``; ``sigma_m``; for gaussian/exponential ``corr_length_m`` (and for gaussian ``beckmann_alpha``
        = 2σ/T); for abc ``A_m4``, ``B_m``, ``C``; ``f_range_per_m`` (fitted band) and ``rms_log_residual``.

    Notes
    -----
    Each annulus's periodogram mean has a relative variance of 1/count (χ² with 2 degrees of freedom per
    Fourier coefficient), so the log residuals are weighted by √count. Single-row fields are fitted with the
    profile PSD of the model.

    References
    ----------
    .. [1] Church & Takacs, Proc. SPIE 1530, 1991 (fitting finish parameters to measured PSDs).
    """
    from scipy.optimize import least_squares

    if model not in PSD_MODELS:
        raise unknown("PSD model", model, PSD_MODELS)
    f, S, n = _psd(hf, window, detrend)
    profile = 1 in hf.shape
    psd2, psd1, names = PSD_MODELS[model]
    fn = psd1 if profile else psd2
    keep = S > floor * S.max() if S.size else S > 0
    f, S, n = f[keep], S[keep], n[keep]
    if f.size < len(names) + 1:
        raise WaveopticsError(f"PSD fit '{model}': only {f.size} usable frequency bins; use a larger grid")
    logS, sw = np.log(S), np.sqrt(n)
    var = float(np.sum(S * (2 * f if profile else 2 * np.pi * f)) * np.median(np.diff(f)))
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
           "rms_log_residual": float(np.sqrt(np.sum(sol.fun**2) / np.sum(n)))}
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
        ``profile`` (True for a single row or column: the slope assumes isotropy).

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
