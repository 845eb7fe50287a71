"""Random and deterministic height-field generators: flat, Gaussian, exponential and ABC (spectral synthesis),
sinusoid, scratches and sums.

References
----------
.. [1] J. A. Ogilvy, *Theory of Wave Scattering from Random Rough Surfaces*, IOP 1991, §2 (spectral synthesis).
.. [2] E. L. Church, P. Z. Takacs, Proc. SPIE 1530, 1991 (ABC PSD).
"""
from __future__ import annotations

import inspect
import math

import numpy as np

from ..errors import WaveopticsError, unknown
from ..units import parse_length
from .heightfield import HeightField
from .psd import PSD_MODELS, S1_abc, S_abc, abc_A, abc_sigma

__all__ = ['flat', 'gaussian', 'exponential', 'abc', 'sinusoid', 'MAX_SCRATCHES', 'GROOVE_REACH', 'scratches', 'flakes', 'GENERATORS', 'generate']

# ----------------------------------------------------------------------------------------------------------------
# Generators
# ----------------------------------------------------------------------------------------------------------------

def length_value(value, name: str, *, allow_zero: bool = False) -> float:
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


def _number(value, name: str, *, lo=None, lo_open=False, hi=None) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise WaveopticsError(f"{name} {value!r} is not a number") from None
    if (not math.isfinite(v) or (lo is not None and (v <= lo if lo_open else v < lo))
            or (hi is not None and v > hi)):
        bound = "" if lo is None else f" and {'>' if lo_open else '>='} {lo:g}"
        bound += "" if hi is None else f" and <= {hi:g}"
        raise WaveopticsError(f"{name}={value!r} is not allowed; it must be finite{bound}")
    return v


#: peak bytes per sample while generating a field (see :func:`_grid`)
SAMPLE_BYTES = 90.0


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
    from ..runtime import check_memory
    # a generated field peaks at about 84 bytes per sample (complex FFT of the noise and its filter; GNU time,
    # 4096² samples: 1.6 GB): refuse, before any work, a field the memory budget cannot hold
    check_memory(SAMPLE_BYTES * nx * ny, f"a {nx}x{ny} surface", "lower {samples}", fields=("samples",))
    if isinstance(size, str) and "," in size:
        size = size.split(",")
    if isinstance(size, (list, tuple, np.ndarray)):
        if len(size) != 2:
            raise WaveopticsError(f"size {size!r} is not allowed; give L or (Lx, Ly)")
        dx = length_value(size[0], "size Lx") / nx
        dy = length_value(size[1], "size Ly") / ny
    else:
        dx = dy = length_value(size, "size") / max(nx, ny)
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


def _rect_integral(psd, half_widths) -> float:
    """∫ S(|f|) over the rectangle |f_x| < a, |f_y| < b (*half_widths* (a, b), 1/m), or ∫ S over |f| < a for a
    profile (*half_widths* (a,)).

    A radial S integrates over a rectangle as ∫ S(f) ℓ(f) df with ℓ(f) the length of the circle of radius f
    inside it: 2πf up to min(a, b), 4f (π/2 − arccos(a/f) − arccos(b/f)) beyond (arccos of a ratio above 1 is 0),
    0 beyond the corner (adaptive Gauss-Kronrod, scipy.integrate.quad, with the corners as break points).
    """
    from scipy.integrate import quad

    if len(half_widths) == 1:
        a = half_widths[0]
        return 2.0 * quad(lambda f: float(psd(np.array([f]))[0]), 0.0, a, limit=200, epsabs=0.0,
                          epsrel=1e-10)[0]
    a, b = sorted(half_widths)
    corner = math.hypot(a, b)

    def integrand(f):
        arcs = math.pi / 2 - math.acos(min(1.0, a / f)) - math.acos(min(1.0, b / f)) if f > 0 else math.pi / 2
        # guard: at the corner the two arcs meet; rounding must not make the length negative
        return float(psd(np.array([f]))[0]) * 4.0 * f * max(arcs, 0.0)

    return sum(quad(integrand, lo, hi, limit=200, epsabs=0.0, epsrel=1e-10)[0]
               for lo, hi in ((0.0, a), (a, b), (b, corner)) if hi > lo)


def _spectral(psd2d, psd1d, nx, ny, dx, dy, rng, sigma, *, renormalize: bool, exact_rms: bool):
    """Gaussian random field with PSD *psd2d* (or *psd1d* for a single row/column) on a periodic grid.

    Real white noise w (unit variance) is filtered in Fourier space by a_k = √(S(f_k) / (dx dy)), which makes
    the periodogram's expectation E[|ĥ_k|² dx dy / (nx ny)] = S(f_k) at every grid frequency f_k ≠ 0 and
    E[h²] = Σ_k S(f_k) Δfx Δfy, the grid's share of σ² (the mean, k = 0, is set to zero). No global rescale:
    the variance the grid cannot hold (wavelengths longer than the patch, frequencies above Nyquist, where most
    of it lies and where it could not scatter) is left out, not moved into the resolved band. A 1×N or N×1 grid
    is a straight profile of the 2-D surface and uses the profile PSD ∫ S dfy instead.

    Returns
    -------
    h : ndarray (ny, nx), m
    band : dict
        ``psd_variance_fraction`` Σ_k S Δf² / σ², the part of σ² the grid resolves;
        ``variance_below_grid_share`` ∫ S over the zero-frequency cell / σ² (wavelengths longer than the patch);
        ``variance_above_nyquist_share`` 1 − ∫ S over the Nyquist square / σ² (frequencies beyond the grid).
        The three add up to 1 up to the midpoint-rule error of the grid's sum.

    References
    ----------
    .. [1] Ogilvy 1991, §2 (spectral synthesis); D. B. Percival, A. T. Walden, *Spectral Analysis for Physical
       Applications*, Cambridge 1993, §6.3 (periodogram of a periodic Gaussian series).
    """
    if nx * ny < 2:
        raise WaveopticsError("a random surface needs at least 2 samples")
    if ny == 1 or nx == 1:
        n, d = (nx, dx) if ny == 1 else (ny, dy)
        S = psd1d(np.abs(np.fft.fftfreq(n, d)))
        S[0] = 0.0
        var = S.sum() / (n * d)
        below = _rect_integral(psd1d, (0.5 / (n * d),))
        grid_band = _rect_integral(psd1d, (0.5 / d,))
        amp = np.sqrt(psd1d(np.fft.rfftfreq(n, d)) / d)
        amp[0] = 0.0
        h = np.fft.irfft(np.fft.rfft(rng.standard_normal(n)) * amp, n)
        h = h.reshape(ny, nx)
    else:
        fy = np.fft.fftfreq(ny, dy)[:, None]
        S = psd2d(np.hypot(fy, np.fft.fftfreq(nx, dx)[None, :]))
        S[0, 0] = 0.0
        var = S.sum() / (nx * dx * ny * dy)
        below = _rect_integral(psd2d, (0.5 / (nx * dx), 0.5 / (ny * dy)))
        grid_band = _rect_integral(psd2d, (0.5 / dx, 0.5 / dy))
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
    band = {"psd_variance_fraction": float(fraction), "variance_below_grid_share": float(below / sigma**2),
            # guard: quad's relative error (~1e-10) on a spectrum the grid holds entirely leaves no negative share
            "variance_above_nyquist_share": max(0.0, float(1.0 - grid_band / sigma**2))}
    return h, band


def _random_meta(model, params, seed, band, renormalize, exact_rms):
    return {"model": model, **params, "seed": seed, "periodic": True, **band,
            "renormalize": renormalize, "exact_rms": exact_rms, "units": "m"}


def _correlated(model, sigma, corr_length, size, samples, seed, renormalize, exact_rms) -> HeightField:
    """A random surface of a PSD family with rms height σ and correlation length T (:data:`PSD_MODELS`)."""
    sigma = length_value(sigma, "sigma")
    T = length_value(corr_length, "corr_length")
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    family = PSD_MODELS[model]
    h, band = _spectral(lambda f: family.S(f, sigma, T), lambda f: family.S1(f, sigma, T),
                        nx, ny, dx, dy, rng, sigma, renormalize=renormalize, exact_rms=exact_rms)
    meta = _random_meta(model, {"sigma": sigma, "corr_length": T}, seed, band, renormalize, exact_rms)
    return HeightField(h, dx, dy, meta=meta)


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


def gaussian(sigma, corr_length, size, samples, seed=None, *, renormalize=False, exact_rms=False) -> HeightField:
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
        False (default) keeps S(f) exactly where the grid resolves it: the periodogram's expectation is S(f_k)
        at every grid frequency and the ensemble rms is σ·√fraction, fraction = ``meta["psd_variance_fraction"]``
        (the share of σ² the grid resolves; ``meta["variance_below_grid_share"]`` and
        ``meta["variance_above_nyquist_share"]`` say where the rest lies). True scales the spectrum so that the
        ensemble mean square on this grid is σ²: that puts the variance the grid cannot hold (mostly above
        Nyquist, where it could not scatter) into the resolved frequencies, which scatter it, so the field then
        scatters more than the surface asked for (ABC C = 2.2: 2.4× the in-band variance); for controlled
        comparisons only.
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
    return _correlated("gaussian", sigma, corr_length, size, samples, seed, renormalize, exact_rms)


def exponential(sigma, corr_length, size, samples, seed=None, *, renormalize=False,
                exact_rms=False) -> HeightField:
    """Gaussian random surface with exponential correlation C(r) = σ² exp(−r/T).

    Parameters are those of :func:`gaussian`. The slope variance of this surface diverges logarithmically
    with the highest resolved frequency, so its rms slope depends on the spacing (there is no finite α).

    References
    ----------
    .. [1] Ogilvy 1991, §2.2; Church & Takacs 1991.
    """
    return _correlated("exponential", sigma, corr_length, size, samples, seed, renormalize, exact_rms)


def abc(B, C, size, samples, seed=None, *, A=None, sigma=None, renormalize=False, exact_rms=False) -> HeightField:
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
    B = length_value(B, "B")
    C = _number(C, "C", lo=2, lo_open=True)
    if (A is None) == (sigma is None):
        raise WaveopticsError("ABC surface: give exactly one of A (m^4) and sigma (m)")
    if sigma is not None:
        sigma = length_value(sigma, "sigma")
        A = abc_A(sigma, B, C)
    else:
        A = _number(A, "A", lo=0, lo_open=True)
        sigma = abc_sigma(A, B, C)
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    h, band = _spectral(lambda f: S_abc(f, sigma, B, C), lambda f: S1_abc(f, sigma, B, C),
                        nx, ny, dx, dy, rng, sigma, renormalize=renormalize, exact_rms=exact_rms)
    meta = _random_meta("abc", {"A": A, "B": B, "C": C, "sigma": sigma}, seed, band, renormalize, exact_rms)
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
    diffraction orders are at sin θ_m = sin θ_i + m λ/Λ (docs/physics.md §5).
    """
    a = length_value(amplitude, "amplitude", allow_zero=True)
    P = length_value(period, "period")
    phi = math.radians(_number(orientation_deg, "orientation_deg"))
    ph0 = math.radians(_number(phase_deg, "phase_deg"))
    nx, ny, dx, dy = _grid(size, samples)
    # Nyquist: the grating's period along each axis must span more than two samples, else the sampled field is
    # another (aliased) grating
    px = abs(P / math.cos(phi)) if abs(math.cos(phi)) > 1e-12 else math.inf
    py = abs(P / math.sin(phi)) if abs(math.sin(phi)) > 1e-12 else math.inf
    if px <= 2 * dx or py <= 2 * dy:
        raise WaveopticsError(f"period {P * 1e9:.4g} nm is not allowed with samples {dx * 1e9:.4g} x {dy * 1e9:.4g} nm "
                              "apart: a grating needs more than two samples per period along each axis (Nyquist), "
                              "else it is generated aliased; use more samples or a smaller size")
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


#: distance from a groove's axis, in widths w, beyond which :func:`scratches` leaves the surface alone: there the
#: groove exp(−4 ln2 s² / w²) is shallower than 1e-18 of its depth (below float64's resolution of any height it
#: meets), so the band |s| < GROOVE_REACH w holds the whole groove
GROOVE_REACH = math.sqrt(18 * math.log(10) / (4 * math.log(2)))


def _cut_groove(h, x, y, p, th, w, d, ln):
    """Cut one groove of :func:`scratches` into *h* (ny, nx) in place: axis through *p* = (px, py) at angle *th*
    (rad), full width at half depth *w*, depth *d*, length *ln* (None: across the patch), where it is deeper than
    *h*. Only the cells within :data:`GROOVE_REACH` w of the axis are visited: per column for an axis closer to x,
    per row otherwise (a 1024² patch and 0.5 µm grooves on 50 nm cells: 87 of 1024 cells per column)."""
    c, s = math.cos(th), math.sin(th)
    along_x = abs(c) >= abs(s)
    a, b = (x, y) if along_x else (y, x)                 # the axis's direction runs along a; the band is across, in b
    pa, pb = (p[0], p[1]) if along_x else (p[1], p[0])
    slope, lead = (s / c, abs(c)) if along_x else (c / s, abs(s))
    db = b[1] - b[0] if b.size > 1 else 1.0
    half = GROOVE_REACH * w / lead                      # |across| < reach ⇔ |b − b_axis(a)| < reach / |cos|
    k = int(math.ceil(half / db))
    centre = np.rint((pb + (a - pa) * slope - b[0]) / db).astype(int)
    jb = centre[:, None] + np.arange(-k, k + 1)[None, :]   # (len(a), 2k + 1)
    ja = np.broadcast_to(np.arange(a.size)[:, None], jb.shape)
    inside = (jb >= 0) & (jb < b.size)
    ja, jb = ja[inside], jb[inside]
    iy, ix = (jb, ja) if along_x else (ja, jb)
    X, Y = x[ix] - p[0], y[iy] - p[1]
    across = -X * s + Y * c
    if ln is not None:
        across = np.hypot(across, np.maximum(np.abs(X * c + Y * s) - ln / 2, 0.0))
    h[iy, ix] = np.minimum(h[iy, ix], -d * np.exp(-4 * math.log(2) * across ** 2 / w ** 2))


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
    w = length_value(width, "width")
    d = length_value(depth, "depth", allow_zero=True)
    th0 = _number(orientation_deg, "orientation_deg")
    spread = _number(spread_deg, "spread_deg", lo=0, hi=180)
    ln = None if length is None else length_value(length, "length")
    v = _number(variation, "variation", lo=0)
    if v >= 1:
        raise WaveopticsError(f"variation={variation!r} is not allowed; it must be in [0, 1)")
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    hf0 = HeightField(np.zeros((ny, nx)), dx, dy)
    x, y = hf0.coords()
    Lx, Ly = hf0.extent
    h = np.zeros((ny, nx))
    for _ in range(n):
        px, py = rng.uniform(-Lx / 2, Lx / 2), rng.uniform(-Ly / 2, Ly / 2)
        th = math.radians(th0 + rng.uniform(-spread, spread))
        wi = w * rng.uniform(1 - v, 1 + v)
        di = d * rng.uniform(1 - v, 1 + v)
        _cut_groove(h, x, y, (px, py), th, wi, di, ln)
    meta = {"model": "scratches", "count": n, "width": w, "depth": d, "orientation_deg": th0,
            "spread_deg": spread, "length": ln, "variation": v, "seed": seed, "periodic": False, "units": "m"}
    return HeightField(h, dx, dy, meta=meta)


def flakes(size_flake, tilt, size, samples, seed=None) -> HeightField:
    """Metallic-paint flakes: a Voronoi mosaic of flat facets, each tilted at random.

    Flake centres are uniform over the patch, one per *size_flake*² on average; every sample belongs to the
    nearest centre (a Voronoi cell) and lies on that flake's plane h = s_x (x − c_x) + s_y (y − c_y), with the
    slopes (s_x, s_y) of each flake drawn from an isotropic Gaussian of rms tan(*tilt*) per axis. Adjacent flakes
    meet in steps, as flakes in a binder do; each flake mirrors light into its own direction, which is what makes
    the glitter of a metallic paint (Yan et al. 2016 render such surfaces).

    Parameters
    ----------
    size_flake : float or str, m
        Mean flake diameter (the mean cell area is size_flake²).
    tilt : float, degrees
        rms tilt of the flakes (per axis, as an angle).
    size, samples, seed
        As in :func:`gaussian`.

    References
    ----------
    .. [1] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, ACM TOG 35(4), 56, 2016 (metallic flakes).
    """
    from scipy.spatial import cKDTree

    d = length_value(size_flake, "size_flake")
    t = _number(tilt, "tilt", lo=0, hi=60)
    nx, ny, dx, dy = _grid(size, samples)
    rng, seed = _rng_seed(seed)
    hf0 = HeightField(np.zeros((ny, nx)), dx, dy)
    x, y = hf0.coords()
    Lx, Ly = hf0.extent
    n = max(1, int(round(Lx * Ly / d ** 2)))
    if n > 200_000:
        raise WaveopticsError(f"size_flake={size_flake!r} gives {n} flakes on this patch; at most 200000")
    centres = np.column_stack([rng.uniform(-Lx / 2, Lx / 2, n), rng.uniform(-Ly / 2, Ly / 2, n)])
    slopes = rng.normal(0.0, math.tan(math.radians(t)), (n, 2))
    X, Y = np.meshgrid(x, y)
    _, idx = cKDTree(centres).query(np.column_stack([X.ravel(), Y.ravel()]))
    idx = idx.reshape(X.shape)
    h = slopes[idx, 0] * (X - centres[idx, 0]) + slopes[idx, 1] * (Y - centres[idx, 1])
    meta = {"model": "flakes", "size_flake": d, "tilt_deg": t, "flakes": n, "seed": seed, "periodic": False,
            "units": "m"}
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
    "flakes": flakes,
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
