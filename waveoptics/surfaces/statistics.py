"""Height-field statistics: rms height and slopes, radial autocorrelation, correlation length, radial PSD and
PSD fits.

References
----------
.. [1] J. M. Bennett, L. Mattsson, *Introduction to Surface Roughness and Scattering*, OSA 1999.
.. [2] T. D. B. Jacobs, T. Junge, L. Pastewka, "Quantitative characterization of surface topography using
   spectral analysis", Surf. Topogr.: Metrol. Prop. 5 013001, 2017.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.interpolate import RegularGridInterpolator
from scipy.fft import next_fast_len
from scipy.ndimage import uniform_filter1d
from scipy.optimize import least_squares
from scipy.special import digamma, polygamma

from ..errors import WaveopticsError, unknown
from ..vocabulary import DETRENDS
from .heightfield import HeightField
from .psd import PSD_MODELS, abc_A

__all__ = ['PeriodogramPSD', 'DETRENDS', 'detrended', 'rms_height', 'rms_slopes', 'rms_slope', 'autocorrelation_radial', 'correlation_length', 'psd_radial', 'fit_psd', 'stats']

# ----------------------------------------------------------------------------------------------------------------
# Statistics
# ----------------------------------------------------------------------------------------------------------------


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
        axes = [c for c in (X, Y) if np.ptp(c[valid]) > 0]   # a profile has no tilt across it
        cols = [np.ones(valid.sum())] + [c[valid] for c in axes]
        coef, *_ = np.linalg.lstsq(np.stack(cols, axis=1), hf.heights[valid], rcond=None)
        fit = coef[0] + sum(c * k for c, k in zip(axes, coef[1:]))
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
        from scipy.signal.windows import hann   # scipy.signal costs ~0.4 s to import: only where it is used

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


class PeriodogramPSD:
    """The two-sided PSD of a height field from its windowed periodogram, S(f_x, f_y) in m⁴, normalized so that
    Σ S Δf_x Δf_y equals the window-weighted height variance (Jacobs, Junge & Pastewka 2017).

    It stands where a :class:`~waveoptics.surfaces.PSDModel` does for first-order scattering
    (:func:`waveoptics.scatter.rayleigh_rice_brdf`): ``S_xy`` interpolates the 2-D periodogram bilinearly (so an
    anisotropic surface keeps its orientation), ``S`` is its radial average. A single periodogram scatters by
    100 % per bin (χ²₂ statistics); average realizations or smooth before reading fine structure into it.
    """

    def __init__(self, hf: HeightField, window="hann", detrend: str = "mean"):
        h = detrended(hf, detrend)
        ny, nx = hf.shape
        w = hf.valid.astype(float)
        if window == "hann":
            from scipy.signal.windows import hann   # ~0.4 s to import: only where it is used

            w = w * np.outer(hann(ny, sym=False) if ny > 1 else [1.0], hann(nx, sym=False) if nx > 1 else [1.0])
        elif window not in (None, "none"):
            raise unknown("PSD window", window, ("hann", "none"))
        P = np.abs(np.fft.fft2(w * h)) ** 2 * hf.dx * hf.dy / float(np.sum(w ** 2))
        self.fx = np.fft.fftshift(np.fft.fftfreq(nx, hf.dx))
        self.fy = np.fft.fftshift(np.fft.fftfreq(ny, hf.dy))
        self.P = np.fft.fftshift(P)
        self._radial = _psd(hf, window or None, detrend)[:2] if min(nx, ny) > 1 else None
        self.sigma = float(np.sqrt(np.sum(P) / (nx * hf.dx * ny * hf.dy)))
        self.length_scale = max(hf.extent) / 8   # no correlation model: a scale for quadrature hints only

    def S_xy(self, fx, fy):
        """S at (f_x, f_y) (1/m), bilinear in the periodogram grid; 0 beyond its Nyquist range."""
        fx, fy = np.broadcast_arrays(np.asarray(fx, dtype=float), np.asarray(fy, dtype=float))
        interp = RegularGridInterpolator((self.fy, self.fx), self.P, bounds_error=False, fill_value=0.0)
        return interp(np.stack([fy.ravel(), fx.ravel()], axis=-1)).reshape(fx.shape)

    def S(self, f):
        """Radially averaged S at |f| (1/m)."""
        fr, Sr = self._radial
        return np.interp(np.asarray(f, dtype=float), fr, Sr, left=Sr[0], right=0.0)


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
        = 2σ/T); for abc ``A_m4``, ``B_m``, ``C``; ``f_range_per_m`` (fitted band), ``rms_log_residual``,
        ``resolved`` (the fitted length is above the sample spacing) and ``at_bound`` (parameters the fit left on
        their bounds, e.g. C = 40 when the ABC model does not fit; a warning says so).

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

    if model not in PSD_MODELS:
        raise unknown("PSD model", model, PSD_MODELS)
    f, S, n = _psd(hf, window, detrend)
    profile = 1 in hf.shape
    family = PSD_MODELS[model]
    names = ("sigma",) + family.shape
    fn = family.S1 if profile else family.S
    # the band ends where a running mean of S (over ~11 bins) first falls below floor·max: choosing bins by
    # their own noisy values would keep only the upward fluctuations in the tail and bias the fit

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
        x0 = [math.log(s0), math.log(2 * np.pi * T0), 3.0]
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
        sigma, B, C = pars
        out.update(A_m4=float(abc_A(sigma, B, C)), B_m=float(B), C=float(C), sigma_m=float(sigma))
        length = float(B)
    else:
        out.update(sigma_m=float(pars[0]), corr_length_m=float(pars[1]))
        if model == "gaussian":
            out["beckmann_alpha"] = 2 * pars[0] / pars[1]
        length = float(pars[1])
    # a fitted length below the sample spacing is not resolved by the data (e.g. white noise): say so
    ny, nx = hf.shape
    spacing = hf.dx if ny == 1 else hf.dy if nx == 1 else min(hf.dx, hf.dy)
    if length < spacing:
        out["resolved"] = False
        warnings.warn(f"the fitted {model} length {length * 1e9:.3g} nm is below the sample spacing "
                      f"{spacing * 1e9:.3g} nm: this height field does not resolve it (noise-like heights), so the "
                      "fit's length and exponent are not measured", stacklevel=2)
    else:
        out["resolved"] = True
    # an exponent that ends on its bound was not found by the fit: the model does not describe this PSD (e.g. an
    # ABC fit to a Gaussian spectrum runs C up to its cap); report it rather than hand back the cap as a value
    out["at_bound"] = [n for n, v, a, b in zip(names, sol.x, lo, hi) if np.isfinite(b) and abs(v - b) < 1e-6 * abs(b)
                       or np.isfinite(a) and abs(v - a) < 1e-6 * max(abs(a), 1.0)]
    if out["at_bound"]:
        warnings.warn(f"the {model} fit ended at the bound of {', '.join(out['at_bound'])} (rms log residual "
                      f"{out['rms_log_residual']:.3g}): the {model} model does not describe this PSD, so those "
                      "parameters are not measured", stacklevel=2)
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
    .. [1] Beckmann & Spizzichino 1963, ch. 5; docs/physics.md §1.
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
        # undefined (None) for a flat field: its autocovariance is 0 everywhere and has no 1/e point
        "corr_length_m": T if np.isfinite(T) else None,
        "beckmann_alpha": 2 * sigma / T if np.isfinite(T) and T > 0 else None,
        "profile": bool(ny == 1 or nx == 1),
        "detrend": detrend,
    }
