"""Spectral pipeline: light sources, spectra → CIE XYZ → linear RGB, metamers, F0 colours.

Everything colorimetric (colour-matching functions, CIE illuminants, Planck's law, RGB colour spaces, chromatic
adaptation, CIELAB and ΔE2000, the sRGB transfer function, CSV spectra, ASTM E2022 weights) comes from
colour-science; this module only arranges it for waveoptics' needs:

* spectra sampled on *any* wavelength grid with the wavelength axis **last** and any leading shape (images,
  direction sets), so a simulation hands over its per-wavelength output as is;
* line spectra (lasers) as a first-class source, so a simulation computes only the wavelengths that carry light;
* a choice of simulation grid from a requested colour accuracy (:func:`simulation_wavelengths`).

Light sources are :class:`SPD` objects (see :func:`illuminant` for the names understood). Continuous SPDs are
relative spectral power per nm (CIE illuminants as tabulated, 100 at 560 nm for the synthetic ones); line SPDs
hold the power of each line (units of the continuous ones × 1 nm).

Tristimulus integration
-----------------------
A continuous SPD ``S`` and the colour-matching functions (CMFs) are used at their 1 nm tabulation
(360–830 nm; ``S`` linearly interpolated to 1 nm and held constant beyond its table, the CIE 015 practice),
while the reflectance ``R`` is known only on the caller's grid ``λ_j``. The default ``"linear"`` method
interpolates ``R`` linearly between the ``λ_j`` (constant beyond the first/last sample) and integrates exactly
at 1 nm, which gives weighting factors

    W_j = Σ_k S(λ_k) x̄ȳz̄(λ_k) φ_j(λ_k) Δλ / Σ_k S(λ_k) ȳ(λ_k) Δλ,      XYZ = Σ_j W_j R_j,

with ``φ_j`` the piecewise-linear "hat" functions of the grid (Σ_j φ_j ≡ 1). Hence ``R ≡ 1`` gives the
illuminant's white with ``Y = 1`` *exactly* on every grid (uniform or not, any step), the weights are
non-negative (XYZ of a non-negative spectrum is a physical colour) and narrow illuminant peaks (fluorescent
lamps) are integrated at 1 nm however coarse ``R`` is sampled. For a line SPD the sums over ``k`` run over
the lines with their powers (a discrete sum, no quadrature). The ``"spline"`` method uses the cardinal
functions of a cubic spline instead of the hats (same exactness for R ≡ 1, several times more accurate for smooth
spectra at 20 nm, but weights can be slightly negative); ``"ASTM E2022"`` uses colour-science's cubic-Lagrange
weighting factors (uniform integer steps aligned with 360 nm only) and serves as the standard reference.

Chromatic adaptation
--------------------
Reflectance colours are reported as seen by an observer adapted to the illuminant: the illuminant's white
(the perfect reflector's XYZ) is mapped to the RGB space's white with the CAT02 von Kries transform
(CIE 159:2004), so a perfect white reflector is RGB (1, 1, 1) under any illuminant, like a white-balanced
camera. Under D65 with the 2° observer and sRGB / Display P3 this is the identity up to 1e-4 (the spaces'
white is D65). Pass ``adapt=False`` to keep the illuminant's own colour (e.g. illuminant A looks orange).
The RGB spaces' matrices are defined for the 2° observer; with the 10° observer the adaptation still maps the
white exactly, but other colours carry the (small) inconsistency every 10°-observer RGB pipeline has.

Where this breaks
-----------------
Linear interpolation of ``R`` assumes the spectrum is smooth on the grid scale: iridescent (diffraction)
spectra with peaks narrower than the grid step need a finer grid than :func:`simulation_wavelengths` picks
from its smooth default test set (pass your own test reflectances). Linear RGB is not clipped (gold's red F0
is > 1 in sRGB); only :func:`rgb_to_srgb8` clips.

References
----------
.. [1] CIE 015:2018, *Colorimetry*, 4th ed., §7 (tristimulus values, normalization k = 100 / Σ S ȳ Δλ).
.. [2] ASTM E308-15 / E2022-11, tristimulus weighting factors; colour-science
   ``tristimulus_weighting_factors_ASTME2022``.
.. [3] CIE 159:2004, *A colour appearance model for colour management systems: CIECAM02* (CAT02).
.. [4] IEC 61966-2-1:1999 (sRGB); SMPTE S-2014-004 (ACEScg); SMPTE EG 432-1 (Display P3).
.. [5] M. R. Luo, G. Cui, B. Rigg, "The development of the CIE 2000 colour-difference formula: CIEDE2000",
   Color Res. Appl. 26(5), 2001.
.. [6] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 Physically Based Shading course notes.
.. [7] ITU-R BT.2020-2 (2015): monochromatic primaries at 630, 532 and 467 nm, D65 white.
.. [8] T. Mansencal et al., colour-science, https://www.colour-science.org (CMFs, illuminants, conversions).
"""
from __future__ import annotations

import functools
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import WaveopticsError, unknown
from .units import check_wavelengths

#: default observer (colour-science's name)
DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"

#: observers understood, canonical names and short aliases
OBSERVERS = {
    "CIE 1931 2 Degree Standard Observer": ("2", "2deg", "1931", "cie_2_1931", "cie1931"),
    "CIE 1964 10 Degree Standard Observer": ("10", "10deg", "1964", "cie_10_1964", "cie1964"),
    "CIE 2015 2 Degree Standard Observer": ("2015-2", "cie2015-2"),
    "CIE 2015 10 Degree Standard Observer": ("2015-10", "cie2015-10"),
}

#: RGB working spaces (colour-science names) and their aliases
SPACES = {
    "sRGB": ("srgb", "rec709", "bt709"),
    "ACEScg": ("acescg", "ap1"),
    "Display P3": ("display p3", "display-p3", "displayp3", "p3", "p3-d65"),
}

#: chromatic adaptation transform used to map the illuminant white to the RGB space white
CAT = "CAT02"

#: visible range (nm) used for simulation grids (ȳ < 1e-4 of its peak outside it); R is held constant beyond it
VISIBLE_NM = (380.0, 780.0)

#: BT.2020 monochromatic primaries (nm): wavelengths of the "rgb-laser" projector [7]_
RGB_LASER_NM = (467.0, 532.0, 630.0)

#: candidate grid steps (nm), coarsest first, tried by :func:`simulation_wavelengths`
STEPS_NM = (40.0, 20.0, 10.0, 5.0, 2.0, 1.0)

_STANDARD_ALIASES = {f"F{i}": f"FL{i}" for i in range(1, 13)}
#: illuminant names offered in error messages (any colour-science illuminant name is accepted too)
ILLUMINANT_NAMES = ("A", "D50", "D55", "D65", "D75", "E", *(f"F{i}" for i in range(1, 13)), "rgb-laser",
                    "blackbody:<T>K", "laser:<nm>[,<nm>...]", "<file>.csv")


# ----------------------------------------------------------------------------------------------- sources

@dataclass(frozen=True, eq=False)
class SPD:
    """A spectral power distribution: continuous (per nm) or a set of lines.

    Attributes
    ----------
    name : str
        Display name (``"D65"``, ``"laser 465,532,638 nm"``).
    wavelengths_nm : numpy.ndarray
        Increasing wavelengths, nm.
    values : numpy.ndarray
        Continuous: relative spectral power per nm at ``wavelengths_nm`` (linearly interpolated between them,
        constant beyond). Lines: power of each line (continuous units × nm).
    lines : bool
        True for a line spectrum (lasers): only these wavelengths carry light.
    """

    name: str
    wavelengths_nm: np.ndarray
    values: np.ndarray
    lines: bool = False

    def __post_init__(self):
        w = check_wavelengths(self.wavelengths_nm, name=f"SPD {self.name!r} wavelength")
        v = np.asarray(self.values, dtype=float).reshape(-1)
        if v.shape != w.shape:
            raise WaveopticsError(f"SPD {self.name!r}: {v.size} values for {w.size} wavelengths")
        if not np.all(np.isfinite(v)) or np.any(v < 0):
            raise WaveopticsError(f"SPD {self.name!r}: spectral power must be finite and >= 0")
        order = np.argsort(w, kind="stable")
        w, v = w[order], v[order]
        if np.any(np.diff(w) <= 0):
            raise WaveopticsError(f"SPD {self.name!r}: wavelengths must be distinct")
        if not np.any(v > 0):
            raise WaveopticsError(f"SPD {self.name!r} has no power")
        w.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "wavelengths_nm", w)
        object.__setattr__(self, "values", v)

    def __call__(self, wavelength_nm) -> np.ndarray:
        """Spectral power per nm at *wavelength_nm* (nm) of a continuous SPD (linear, constant beyond)."""
        if self.lines:
            raise WaveopticsError(f"SPD {self.name!r} is a line spectrum; it has no value per nm")
        return np.interp(np.asarray(wavelength_nm, dtype=float), self.wavelengths_nm, self.values)


def laser(lines_nm, powers=None, *, name: str | None = None) -> SPD:
    """A line spectrum: lasers at *lines_nm* (nm) with *powers* (equal when omitted)."""
    w = check_wavelengths(lines_nm, name="laser line")
    p = np.ones_like(w) if powers is None else np.asarray(powers, dtype=float).reshape(-1)
    label = ",".join(f"{x:g}" for x in w)
    return SPD(name or f"laser {label} nm", w, p, lines=True)


def blackbody(temperature_K: float) -> SPD:
    """Planckian radiator at *temperature_K* (K), 360–830 nm at 1 nm, normalized to 100 at 560 nm.

    References
    ----------
    .. [1] CIE 015:2018, §B.1 (Planck's law with c2 = 1.4388e-2 m·K); colour-science ``sd_blackbody``.
    """
    import colour

    T = float(temperature_K)
    if not (math.isfinite(T) and 100.0 <= T <= 1e7):
        raise WaveopticsError(f"blackbody temperature {temperature_K!r} K is not allowed; use 100 to 1e7 K")
    sd = colour.sd_blackbody(T, colour.SpectralShape(360, 830, 1))
    return SPD(f"blackbody {T:g} K", sd.wavelengths, 100.0 * sd.values / sd[560])


def standard_illuminant(name: str) -> SPD:
    """A CIE (or other colour-science) illuminant by name: ``"D65"``, ``"A"``, ``"F2"`` (= ``"FL2"``), ``"E"``."""
    import colour

    key = _STANDARD_ALIASES.get(name.upper(), name)
    table = {k.lower(): k for k in colour.SDS_ILLUMINANTS}
    if key.lower() not in table:
        raise unknown("illuminant", name, ILLUMINANT_NAMES)
    key = table[key.lower()]
    sd = colour.SDS_ILLUMINANTS[key]
    return SPD(name.upper() if name.upper() in _STANDARD_ALIASES else key, sd.wavelengths, sd.values)


def spd_from_csv(path, column: str | None = None) -> SPD:
    """A continuous SPD from a CSV file: first column wavelength (nm), then one column per spectrum.

    Parameters
    ----------
    path : str or Path
        CSV file with a header row (colour-science ``read_sds_from_csv_file`` format).
    column : str, optional
        Column to use; required when the file has more than one spectrum.
    """
    import colour

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"SPD file {str(p)!r} does not exist")
    try:
        sds = colour.io.read_sds_from_csv_file(str(p))
    except Exception as exc:  # noqa: BLE001 - colour raises assorted errors for malformed CSV
        raise WaveopticsError(f"SPD file {str(p)!r} is not a CSV of wavelength,value columns ({exc})") from None
    if not sds:
        raise WaveopticsError(f"SPD file {str(p)!r} has no spectrum column")
    if column is None:
        if len(sds) > 1:
            raise WaveopticsError(f"SPD file {str(p)!r} has {len(sds)} spectra ({', '.join(sds)}); "
                                  f"pick one with {p.name}:COLUMN")
        column = next(iter(sds))
    if column not in sds:
        raise unknown(f"column of {p.name}", column, list(sds))
    sd = sds[column]
    values = np.asarray(sd.values, dtype=float)
    if not np.all(np.isfinite(values)):
        raise WaveopticsError(f"SPD file {str(p)!r} column {column!r} has missing or non-numeric values")
    return SPD(f"{p.name}:{column}" if len(sds) > 1 else p.name, sd.wavelengths, values)


def rgb_laser_projector(lines_nm=RGB_LASER_NM, white="D65", observer=DEFAULT_OBSERVER) -> SPD:
    """A three-laser RGB projector whose full-white mix is a metamer of *white* (same XYZ).

    Parameters
    ----------
    lines_nm : sequence of 3 float, nm
        Laser wavelengths; default the BT.2020 primaries 467, 532, 630 nm [1]_.
    white : str or SPD
        The white the projector is calibrated to.

    References
    ----------
    .. [1] ITU-R BT.2020-2 (2015), Table 3 (primaries on the spectral locus, D65 white).
    """
    target = _as_spd(white)
    powers = metamer_laser_weights(target, lines_nm, observer=observer)
    label = ",".join(f"{x:g}" for x in np.asarray(lines_nm, dtype=float))
    return laser(lines_nm, powers, name=f"rgb-laser {label} nm ({target.name} white)")


_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def illuminant(spec) -> SPD:
    """Parse a light-source specification into an :class:`SPD`.

    Parameters
    ----------
    spec : str or SPD
        ``"D65"``, ``"D50"``, ``"A"``, ``"F1"``..``"F12"`` (or ``"FL1"``..), ``"E"`` (equal energy), any other
        colour-science illuminant name (``"LED-B1"``, ``"FL3.1"``); ``"blackbody:5500K"``;
        ``"laser:532nm"`` or ``"laser:465,532,638"`` (equal line powers); ``"rgb-laser"`` (BT.2020 lasers
        mixed to a D65 metamer) or ``"rgb-laser:465,532,638"``; a CSV file path (``"lamp.csv"`` or
        ``"lamps.csv:COLUMN"``).

    Returns
    -------
    SPD

    Raises
    ------
    WaveopticsError
        Unknown names (with a did-you-mean suggestion), bad numbers, missing files.
    """
    if isinstance(spec, SPD):
        return spec
    if not isinstance(spec, (str, Path)):
        raise TypeError(f"illuminant must be a name or an SPD, got {type(spec).__name__}")
    s = str(spec).strip()
    low = s.lower()
    if low.startswith("blackbody:"):
        m = re.fullmatch(rf"\s*({_NUM})\s*k?\s*", low.split(":", 1)[1])
        if not m:
            raise WaveopticsError(f"illuminant {s!r}: write blackbody:TEMPERATUREK, e.g. blackbody:5500K")
        return blackbody(float(m.group(1)))
    if low.startswith("laser:") or low.startswith("rgb-laser:"):
        text = s.split(":", 1)[1].replace("nm", "")
        try:
            lines = [float(x) for x in text.split(",") if x.strip()]
        except ValueError:
            raise WaveopticsError(f"illuminant {s!r}: write laser:NM[,NM...], e.g. laser:465,532,638") from None
        if low.startswith("rgb-laser:"):
            return rgb_laser_projector(lines)
        return laser(lines)
    if low == "rgb-laser":
        return rgb_laser_projector()
    path, _, column = s.partition(".csv:")
    if column or low.endswith(".csv"):
        return spd_from_csv(path + ".csv" if column else s, column or None)
    return standard_illuminant(s)


_as_spd = illuminant  # for functions whose parameter is called 'illuminant'


# ------------------------------------------------------------------------------------------- observers

def observer_name(observer) -> str:
    """Canonical colour-science name of an observer given by name or alias (``"2"``, ``"10"``, ``"1964"``)."""
    s = str(observer).strip()
    for name, aliases in OBSERVERS.items():
        if s.lower() == name.lower() or s.lower() in aliases:
            return name
    raise unknown("observer", s, [*OBSERVERS, "2", "10"])


@functools.lru_cache(maxsize=8)
def _cmfs(name: str):
    import colour

    c = colour.MSDS_CMFS[name]
    w, v = np.array(c.wavelengths, dtype=float), np.array(c.values, dtype=float)
    w.setflags(write=False)
    v.setflags(write=False)
    return w, v


def cmfs(observer=DEFAULT_OBSERVER) -> tuple[np.ndarray, np.ndarray]:
    """Colour-matching functions: (wavelengths_nm (n,), x̄ȳz̄ (n, 3)) at their 1 nm tabulation (read-only)."""
    return _cmfs(observer_name(observer))


def cmf_at(wavelength_nm, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """x̄ȳz̄ at arbitrary wavelengths (nm), linearly interpolated, zero outside the tabulation; shape (..., 3)."""
    w, v = cmfs(observer)
    x = np.asarray(wavelength_nm, dtype=float)
    return np.stack([np.interp(x, w, v[:, i], left=0.0, right=0.0) for i in range(3)], axis=-1)


def _measure(spd: SPD, observer) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The illuminant as a discrete measure: wavelengths λ_k (nm), weights m_k (power), x̄ȳz̄(λ_k) (k, 3).

    Continuous: the CMF's 1 nm grid with m_k = S(λ_k)·1 nm (CIE 015 summation). Lines: the lines and their powers.
    """
    if spd.lines:
        return spd.wavelengths_nm, spd.values, cmf_at(spd.wavelengths_nm, observer)
    w, v = cmfs(observer)
    step = np.gradient(w)  # 1 nm for the CIE tables; kept general for other tabulations
    return w, spd(w) * step, v


def spd_to_XYZ(spd, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """Absolute (un-normalized) tristimulus values Σ S x̄ȳz̄ Δλ of a light source, in its power units × nm."""
    spd = _as_spd(spd)
    _, m, c = _measure(spd, observer)
    return m @ c


# ---------------------------------------------------------------------------------- tristimulus weights

def _check_grid(wavelengths_nm) -> np.ndarray:
    w = check_wavelengths(wavelengths_nm, name="wavelength grid")
    if w.ndim != 1:
        raise WaveopticsError(f"wavelength grid must be 1-D, got shape {w.shape}")
    if np.unique(w).size != w.size:
        raise WaveopticsError("wavelength grid has repeated wavelengths")
    return w


def _weights_linear(grid: np.ndarray, spd: SPD, observer) -> np.ndarray:
    """Weights Σ_k m_k x̄ȳz̄_k φ_j(λ_k) for R linearly interpolated on *grid* (sorted), constant beyond."""
    lam, m, c = _measure(spd, observer)
    mc = m[:, None] * c
    n = grid.size
    W = np.zeros((n, 3))
    if n == 1:
        W[0] = mc.sum(axis=0)
        return W
    # interval index i with grid[i] <= λ < grid[i+1]; clamped so ends extrapolate constantly (t in [0, 1])
    i = np.clip(np.searchsorted(grid, lam, side="right") - 1, 0, n - 2)
    t = np.clip((lam - grid[i]) / (grid[i + 1] - grid[i]), 0.0, 1.0)
    for ch in range(3):
        W[:, ch] = (np.bincount(i, (1.0 - t) * mc[:, ch], minlength=n)
                    + np.bincount(i + 1, t * mc[:, ch], minlength=n))
    return W


def _weights_spline(grid: np.ndarray, spd: SPD, observer) -> np.ndarray:
    """Weights Σ_k m_k x̄ȳz̄_k φ_j(λ_k) with φ_j the cardinal functions of a not-a-knot cubic spline on *grid*
    (scipy ``CubicSpline`` through the unit vectors), R held constant beyond the ends."""
    from scipy.interpolate import CubicSpline

    lam, m, c = _measure(spd, observer)
    mc = m[:, None] * c
    if grid.size == 1:
        return mc.sum(axis=0, keepdims=True)
    Phi = CubicSpline(grid, np.eye(grid.size), axis=0)(np.clip(lam, grid[0], grid[-1]))  # (k, n)
    return Phi.T @ mc


def _weights_astm_e2022(grid: np.ndarray, spd: SPD, observer) -> np.ndarray:
    """colour-science's ASTM E2022 weights for a uniform integer-step grid aligned with the CMF start."""
    import colour
    from colour.colorimetry import (adjust_tristimulus_weighting_factors_ASTME308,
                                    tristimulus_weighting_factors_ASTME2022)

    if spd.lines:
        raise WaveopticsError("method 'ASTM E2022' needs a continuous illuminant; use method='linear' for lasers")
    w_cmf, _ = cmfs(observer)
    start, end = float(w_cmf[0]), float(w_cmf[-1])
    steps = np.diff(grid)
    step = float(steps[0]) if steps.size else 0.0
    if (steps.size == 0 or not np.allclose(steps, step) or step != round(step)
            or (grid[0] - start) % step != 0 or grid[0] < start or grid[-1] > end):
        raise WaveopticsError(f"method 'ASTM E2022' needs a uniform integer-nm grid starting at {start:g} + "
                              f"k·step inside {start:g}-{end:g} nm; got {grid[0]:g}..{grid[-1]:g} nm")
    cm = colour.MSDS_CMFS[observer_name(observer)]
    S = colour.SpectralDistribution(spd(w_cmf), w_cmf)
    W = tristimulus_weighting_factors_ASTME2022(cm, S, colour.SpectralShape(start, end, step), k=1)
    last = start + step * (W.shape[0] - 1)
    return adjust_tristimulus_weighting_factors_ASTME308(
        W, colour.SpectralShape(start, last, step), colour.SpectralShape(grid[0], grid[-1], step))


#: tristimulus weighting methods (registry, see ``method=`` of :func:`tristimulus_weights`)
TRISTIMULUS_METHODS = {"linear": _weights_linear, "spline": _weights_spline, "ASTM E2022": _weights_astm_e2022}


def tristimulus_weights(wavelengths_nm, illuminant="D65", observer=DEFAULT_OBSERVER,
                        method: str = "linear") -> np.ndarray:
    """Weighting factors W (n, 3) with XYZ = Σ_j W_j R_j for a reflectance sampled at *wavelengths_nm*.

    Normalized so that R ≡ 1 gives Y = 1 (Σ_j W_jy = 1) on any grid.

    Parameters
    ----------
    wavelengths_nm : array_like (n,), nm
        Sample wavelengths of the reflectance (any order, distinct).
    illuminant : str or SPD
        Light source (see :func:`illuminant`).
    observer : str
        Observer name or alias.
    method : {"linear", "spline", "ASTM E2022"}
        ``"linear"``: R linearly interpolated between samples, exact 1 nm integration (any grid, lines);
        weights are non-negative. ``"spline"``: R interpolated by a cubic spline (any grid): 3-7x smaller
        errors at 20 nm for smooth spectra, but weights can be slightly negative and narrow peaks ring.
        ``"ASTM E2022"``: colour-science's cubic-Lagrange weights (uniform integer steps aligned with
        the CMF start only).

    References
    ----------
    .. [1] CIE 015:2018 §7.1; ASTM E2022-11; ASTM E308-15 §7.
    """
    grid = _check_grid(wavelengths_nm)
    spd = _as_spd(illuminant)
    if method not in TRISTIMULUS_METHODS:
        raise unknown("tristimulus method", method, TRISTIMULUS_METHODS)
    order = np.argsort(grid)
    W_sorted = TRISTIMULUS_METHODS[method](grid[order], spd, observer)
    norm = W_sorted[:, 1].sum()
    if not norm > 0:
        raise WaveopticsError(f"illuminant {spd.name!r} has no visible power for the {observer_name(observer)}")
    W = np.empty_like(W_sorted)
    W[order] = W_sorted / norm
    return W


def reflectance_to_XYZ(R, wavelengths_nm, illuminant="D65", observer=DEFAULT_OBSERVER,
                       method: str = "linear") -> np.ndarray:
    """CIE XYZ of a reflectance (or any spectral factor) lit by an illuminant; R ≡ 1 gives Y = 1.

    XYZ = Σ S R x̄ȳz̄ Δλ / Σ S ȳ Δλ (CIE 015), evaluated with :func:`tristimulus_weights`.

    Parameters
    ----------
    R : array_like (..., n)
        Reflectance factors (dimensionless) with the wavelength axis LAST and any leading shape.
    wavelengths_nm : array_like (n,), nm
        Wavelengths of the last axis of *R*.
    illuminant : str or SPD
        Light source; for a line SPD *R* is needed only at the lines (pass the lines as the grid).
    observer : str
        ``"CIE 1931 2 Degree Standard Observer"`` (default), ``"CIE 1964 10 Degree Standard Observer"``, ...

    Returns
    -------
    numpy.ndarray (..., 3)
        X, Y, Z (Y = 1 for the perfect white reflector).

    References
    ----------
    .. [1] CIE 015:2018, *Colorimetry*, eq. 7.1–7.3.
    """
    R = np.asarray(R, dtype=float)
    W = tristimulus_weights(wavelengths_nm, illuminant, observer, method)
    if R.ndim == 0 or R.shape[-1] != W.shape[0]:
        raise WaveopticsError(f"reflectance has shape {R.shape}; its last axis must have one value per "
                              f"wavelength ({W.shape[0]})")
    if not np.all(np.isfinite(R)):
        raise WaveopticsError("reflectance contains NaN or Inf")
    return R @ W


def white_XYZ(illuminant="D65", observer=DEFAULT_OBSERVER) -> np.ndarray:
    """XYZ of the perfect white reflector under the illuminant (Y = 1): the adaptation white."""
    XYZ = spd_to_XYZ(_as_spd(illuminant), observer)
    if not XYZ[1] > 0:
        raise WaveopticsError(f"illuminant {_as_spd(illuminant).name!r} has no visible power")
    return XYZ / XYZ[1]


# ------------------------------------------------------------------------------------------ RGB spaces

def space_name(space) -> str:
    """Canonical colour-science name of an RGB space: ``"sRGB"``, ``"ACEScg"`` or ``"Display P3"``."""
    s = str(space).strip()
    for name, aliases in SPACES.items():
        if s == name or s.lower() in aliases:
            return name
    raise unknown("RGB space", s, SPACES)


def XYZ_to_rgb(XYZ, space="sRGB", white=None, *, cat: str = CAT) -> np.ndarray:
    """Linear (unclipped) RGB in *space* from XYZ.

    Parameters
    ----------
    XYZ : array_like (..., 3)
        Tristimulus values, white Y = 1.
    space : {"sRGB", "ACEScg", "Display P3"}
    white : array_like (3,) or None
        XYZ of the adapted white (e.g. :func:`white_XYZ` of the illuminant); it is mapped to the space's white
        with *cat*. None: XYZ are already relative to the space's white (no adaptation).
    cat : str
        colour-science chromatic adaptation transform (default CAT02, CIE 159:2004).

    Returns
    -------
    numpy.ndarray (..., 3)
        Linear RGB; values outside [0, 1] are kept (out-of-gamut colours such as gold's red F0).
    """
    import colour

    cs = colour.RGB_COLOURSPACES[space_name(space)]
    XYZ = np.asarray(XYZ, dtype=float)
    if white is None:
        return colour.XYZ_to_RGB(XYZ, cs, illuminant=cs.whitepoint, chromatic_adaptation_transform=None)
    xy_white = colour.XYZ_to_xy(np.asarray(white, dtype=float))
    return colour.XYZ_to_RGB(XYZ, cs, illuminant=xy_white, chromatic_adaptation_transform=cat)


def reflectance_to_rgb(R, wavelengths_nm, illuminant="D65", observer=DEFAULT_OBSERVER, space="sRGB",
                       *, adapt: bool = True, method: str = "linear") -> np.ndarray:
    """Linear RGB (..., 3) of reflectances R (..., n): :func:`reflectance_to_XYZ` then :func:`XYZ_to_rgb`.

    With *adapt* (default) the illuminant white maps to the space white (white reflector → (1, 1, 1)).
    """
    XYZ = reflectance_to_XYZ(R, wavelengths_nm, illuminant, observer, method)
    white = white_XYZ(illuminant, observer) if adapt else None
    return XYZ_to_rgb(XYZ, space, white)


def rgb_to_srgb8(rgb) -> np.ndarray:
    """8-bit sRGB-encoded integers from linear sRGB: clipped to [0, 1], IEC 61966-2-1 curve, rounded."""
    import colour

    rgb = np.asarray(rgb, dtype=float)
    if not np.all(np.isfinite(rgb)):
        raise WaveopticsError("RGB contains NaN or Inf")
    enc = colour.cctf_encoding(np.clip(rgb, 0.0, 1.0), function="sRGB")
    return np.rint(np.asarray(enc) * 255.0).astype(int)


def _delta_e2000_XYZ(XYZ1, XYZ2, white) -> np.ndarray:
    import colour

    xy = colour.XYZ_to_xy(np.asarray(white, dtype=float))
    return colour.delta_E(colour.XYZ_to_Lab(XYZ1, xy), colour.XYZ_to_Lab(XYZ2, xy), method="CIE 2000")


def delta_e2000(rgb1, rgb2, colourspace="sRGB") -> np.ndarray:
    """CIEDE2000 colour difference between linear RGB colours (..., 3) of *colourspace*, white Y = 1.

    References
    ----------
    .. [1] Luo, Cui, Rigg, Color Res. Appl. 26(5), 2001; colour-science ``delta_E(method='CIE 2000')``.
    """
    import colour

    cs = colour.RGB_COLOURSPACES[space_name(colourspace)]
    to_XYZ = functools.partial(colour.RGB_to_XYZ, colourspace=cs, illuminant=cs.whitepoint,
                               chromatic_adaptation_transform=None)
    white = colour.xy_to_XYZ(cs.whitepoint)
    return _delta_e2000_XYZ(to_XYZ(np.asarray(rgb1, float)), to_XYZ(np.asarray(rgb2, float)), white)


# ----------------------------------------------------------------------------------- simulation grids

def spectral_grid(illuminant, step_nm: float = 5.0, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """Wavelengths (nm) at which spectra must be computed under a light source.

    Line SPD: its visible lines (x̄ȳz̄ not all zero). Continuous SPD: a uniform grid of *step_nm* on multiples of
    the step from 380 nm, covering where S·(x̄+ȳ+z̄) exceeds 1e-4 of its peak within 380–780 nm.
    """
    spd = _as_spd(illuminant)
    if spd.lines:
        c = cmf_at(spd.wavelengths_nm, observer)
        keep = (c.sum(axis=-1) > 0) & (spd.values > 0)
        if not keep.any():
            raise WaveopticsError(f"illuminant {spd.name!r} has no visible line")
        return spd.wavelengths_nm[keep].copy()
    step = float(step_nm)
    if not (math.isfinite(step) and step > 0):
        raise WaveopticsError(f"wavelength step {step_nm!r} nm is not allowed; it must be > 0")
    lam, m, c = _measure(spd, observer)
    lo, hi = VISIBLE_NM
    sig = m * c.sum(axis=1)
    inside = (lam >= lo) & (lam <= hi)
    on = np.nonzero(inside & (sig > 1e-4 * sig[inside].max()))[0]
    if on.size == 0:
        raise WaveopticsError(f"illuminant {spd.name!r} has no visible power in {lo:g}-{hi:g} nm")
    a = lo + math.floor((lam[on[0]] - lo) / step + 1e-9) * step
    b = min(lo + math.ceil((lam[on[-1]] - lo) / step - 1e-9) * step, hi + 1e-9)
    return a + step * np.arange(int(round((b - a) / step)) + 1)


@functools.lru_cache(maxsize=1)
def reference_reflectances() -> tuple[np.ndarray, np.ndarray]:
    """Smooth test reflectances at 1 nm over 360–830 nm: the 24 ColorChecker patches (Ohta, Sprague-
    interpolated) and four metal-like absorption edges 0.05 + 0.9/(1 + exp(-(λ-λ0)/15 nm)), λ0 = 450..600 nm."""
    import colour

    w = np.arange(360.0, 831.0)
    shape = colour.SpectralShape(380, 780, 1)
    rows = []
    for sd in colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"].values():
        s = sd.copy().interpolate(shape)
        rows.append(np.interp(w, s.wavelengths, s.values))
    for lam0 in (450.0, 500.0, 550.0, 600.0):
        rows.append(0.05 + 0.9 / (1.0 + np.exp(-(w - lam0) / 15.0)))
    R = np.clip(np.array(rows), 0.0, None)
    R.setflags(write=False)
    return w, R


def step_errors(illuminant, steps_nm=STEPS_NM, observer=DEFAULT_OBSERVER, reflectances=None,
                method: str = "linear") -> dict:
    """Largest ΔE2000 of test reflectances sampled on :func:`spectral_grid` of each step vs their 1 nm colour.

    Parameters
    ----------
    reflectances : (wavelengths_nm (m,), R (k, m)) or None
        Finely sampled test spectra; default :func:`reference_reflectances` (ColorChecker + metal edges).
    method : str
        Tristimulus method used on the coarse grids (see :func:`tristimulus_weights`).

    Returns
    -------
    dict
        step_nm -> (max ΔE2000, number of wavelengths).
    """
    spd = _as_spd(illuminant)
    w_ref, R_ref = reflectances if reflectances is not None else reference_reflectances()
    w_ref, R_ref = np.asarray(w_ref, float), np.atleast_2d(np.asarray(R_ref, float))
    XYZ_ref = reflectance_to_XYZ(R_ref, w_ref, spd, observer)
    white = white_XYZ(spd, observer)
    out = {}
    for step in steps_nm:
        grid = spectral_grid(spd, step, observer)
        R = np.stack([np.interp(grid, w_ref, r) for r in R_ref])
        dE = _delta_e2000_XYZ(reflectance_to_XYZ(R, grid, spd, observer, method), XYZ_ref, white)
        out[float(step)] = (float(np.max(dE)), int(grid.size))
    return out


def simulation_wavelengths(illuminant, accuracy_dE: float = 0.5, observer=DEFAULT_OBSERVER,
                           reflectances=None, method: str = "linear") -> np.ndarray:
    """The wavelengths (nm) a simulation must compute to reach a colour accuracy under a light source.

    Line SPDs: exactly their visible lines (accuracy is then exact). Continuous SPDs: the coarsest uniform grid
    among :data:`STEPS_NM` whose worst ΔE2000 over the test reflectances (see :func:`step_errors`) stays
    ≤ *accuracy_dE* against 1 nm sampling (falls back to 1 nm), when the simulated spectra are integrated
    with the same *method* (see :func:`tristimulus_weights`).

    Notes
    -----
    The default test set is smooth (ColorChecker patches and metal absorption edges). Iridescent spectra with
    peaks narrower than the chosen step are under-sampled: pass representative *reflectances* for those.
    """
    spd = _as_spd(illuminant)
    if spd.lines:
        return spectral_grid(spd, observer=observer)
    if not (math.isfinite(accuracy_dE) and accuracy_dE > 0):
        raise WaveopticsError(f"colour accuracy {accuracy_dE!r} ΔE is not allowed; it must be > 0")
    errors = step_errors(spd, STEPS_NM[:-1], observer, reflectances, method)
    for step, (dE, _) in errors.items():
        if dE <= accuracy_dE:
            return spectral_grid(spd, step, observer)
    return spectral_grid(spd, 1.0, observer)


# ------------------------------------------------------------------------------------------- metamers

def metamer_laser_weights(target_spd, lines_nm, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """Powers of three laser lines whose mix has the same XYZ as *target_spd*.

    Solves Σ_l P_l x̄ȳz̄(λ_l) = ∫ S x̄ȳz̄ dλ (a 3×3 linear system).

    Parameters
    ----------
    target_spd : str or SPD
        The light to match (e.g. ``"D65"``).
    lines_nm : sequence of 3 float, nm
        Laser wavelengths.

    Returns
    -------
    numpy.ndarray (3,)
        Line powers, in the target's units × nm (so the mix has the target's absolute XYZ).

    Raises
    ------
    WaveopticsError
        Not three distinct visible lines, or a match needs negative power (the target lies outside the
        lines' chromaticity triangle).
    """
    target = _as_spd(target_spd)
    lines = check_wavelengths(lines_nm, name="laser line")
    if lines.size != 3 or np.unique(lines).size != 3:
        raise WaveopticsError(f"metamer needs exactly 3 distinct laser lines, got {lines.tolist()} nm")
    M = cmf_at(lines, observer).T  # columns: XYZ of a unit-power line
    if np.linalg.cond(M) > 1e8:
        raise WaveopticsError(f"laser lines {lines.tolist()} nm are (nearly) colour-collinear or invisible; "
                              "choose a blue, a green and a red line")
    P = np.linalg.solve(M, spd_to_XYZ(target, observer))
    if np.any(P < 0):
        bad = int(np.argmin(P))
        raise WaveopticsError(f"{target.name} cannot be matched by lines {lines.tolist()} nm: line "
                              f"{lines[bad]:g} nm would need negative power; choose lines around its "
                              "chromaticity (blue, green, red)")
    return P


def metamer_summary(target_spd, lines_nm, observer=DEFAULT_OBSERVER) -> dict:
    """The laser metamer of a light as plain data (for the CLI and docs).

    Returns
    -------
    dict
        ``target``, ``observer``, ``lines_nm``, ``powers`` (target units × nm, see
        :func:`metamer_laser_weights`), ``power_fractions`` (sum 1), ``XYZ_target`` and ``XYZ_mix`` (scaled so the
        target's Y = 1) and ``xy`` (chromaticity of the target).
    """
    import colour

    target = _as_spd(target_spd)
    lines = check_wavelengths(lines_nm, name="laser line")
    P = metamer_laser_weights(target, lines, observer)
    XYZ_t = spd_to_XYZ(target, observer)
    XYZ_m = spd_to_XYZ(laser(lines, P), observer)
    return {"target": target.name, "observer": observer_name(observer), "lines_nm": lines.tolist(),
            "powers": P.tolist(), "power_fractions": (P / P.sum()).tolist(),
            "XYZ_target": (XYZ_t / XYZ_t[1]).tolist(), "XYZ_mix": (XYZ_m / XYZ_t[1]).tolist(),
            "xy": colour.XYZ_to_xy(XYZ_t).tolist()}


def plot_metamers(target_spd, lines_nm, powers, path, *, observer=DEFAULT_OBSERVER,
                  overwrite: bool = False) -> Path:
    """PNG plot of a continuous SPD and its laser-line metamer (stems), with both chromaticities.

    Parameters
    ----------
    target_spd : str or SPD
    lines_nm, powers : sequences of float
        Laser wavelengths (nm) and powers (target units × nm), e.g. from :func:`metamer_laser_weights`.
    path : str or Path
        PNG file (written atomically; refused if it exists unless *overwrite*).
    """
    import colour
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .io import atomic_path

    target = _as_spd(target_spd)
    mix = laser(lines_nm, powers)
    xy_t = colour.XYZ_to_xy(spd_to_XYZ(target, observer))
    xy_m = colour.XYZ_to_xy(spd_to_XYZ(mix, observer))
    w_cmf, c = cmfs(observer)
    fig = Figure(figsize=(7.5, 4.2), dpi=120)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    if target.lines:
        ax.stem(target.wavelengths_nm, target.values, linefmt="k-", markerfmt="ko", basefmt=" ",
                label=target.name)
    else:
        wt = w_cmf[(w_cmf >= 360) & (w_cmf <= 780)]
        ax.plot(wt, target(wt), "k-", lw=1.5, label=f"{target.name} (per nm)")
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("relative spectral power per nm")
    ax.set_xlim(360, 780)
    ax.set_ylim(bottom=0)
    ax2 = ax.twinx()
    for lam, p, col in zip(mix.wavelengths_nm, mix.values, _line_colours(mix.wavelengths_nm, observer)):
        ax2.vlines(lam, 0, p, color=col, lw=3)
        ax2.annotate(f"{lam:g} nm", (lam, p), textcoords="offset points", xytext=(0, 4), ha="center", fontsize=8)
    ax2.set_ylabel("laser line power (× 1 nm)")
    ax2.set_ylim(0, 1.15 * mix.values.max())
    for i in range(3):
        ax.plot(w_cmf, c[:, i] / c.max() * ax.get_ylim()[1] * 0.5, ":", lw=0.8, color="grey",
                label="CMFs (scaled)" if i == 0 else None)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"Metamers: {target.name} xy=({xy_t[0]:.4f}, {xy_t[1]:.4f}) vs lasers "
                 f"xy=({xy_m[0]:.4f}, {xy_m[1]:.4f})", fontsize=9)
    fig.tight_layout()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format="png")
    return Path(path)


def _line_colours(lines_nm, observer):
    """Display sRGB (0-1) of monochromatic lines, scaled into gamut (for plotting only)."""
    rgb = XYZ_to_rgb(cmf_at(lines_nm, observer), "sRGB")
    rgb = np.clip(rgb, 0.0, None)
    rgb = rgb / np.maximum(rgb.max(axis=-1, keepdims=True), 1e-12)
    return [tuple(r) for r in np.clip(rgb, 0.0, 1.0)]


# ------------------------------------------------------------------------------------------- F0 colours

def classify_f0(luminance_F0: float) -> tuple[str, bool]:
    """Category of a surface from the luminance Y of its linear F0, and whether it lies in the forbidden zone.

    Ranges (Hoffman 2015 [1]_): dielectrics ~0.02–0.05 (gems up to ~0.17), metals ≥ ~0.5, and the
    0.2–0.45 "forbidden zone" which real production surfaces avoid and which only semiconductors occupy.
    The thresholds live in :func:`waveoptics.materials.category_from_f0`.

    Returns
    -------
    (category, forbidden_zone) : (str, bool)
        ``"metal"``, ``"dielectric"`` or ``"semiconductor"``; True for 0.2 ≤ Y < 0.45.

    References
    ----------
    .. [1] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 PBS course notes.
    """
    from .materials import category_from_f0

    y = float(luminance_F0)
    if not (math.isfinite(y) and 0.0 <= y <= 1.0 + 1e-9):
        raise WaveopticsError(f"F0 luminance {luminance_F0!r} is not allowed; it must be in [0, 1]")
    category = category_from_f0(y)
    return category, category == "semiconductor"


def f0_colour(material, illuminant="D65", observer=DEFAULT_OBSERVER, *, step_nm: float = 5.0) -> dict:
    """Characteristic specular colour F0 = F(0°) of a material, computed spectrally.

    F0(λ) is weighted by the illuminant and the CMFs to XYZ (white reflector Y = 1), adapted to the sRGB white
    (see module notes), converted to linear sRGB (not clipped) and to 8-bit sRGB (clipped).

    Parameters
    ----------
    material : object with ``F0(wavelength_nm)``, ``name``, ``source``
        A :class:`waveoptics.materials.Material`.
    illuminant : str or SPD
    observer : str
    step_nm : float, nm
        Grid step for continuous illuminants (line illuminants use their lines).

    Returns
    -------
    dict
        ``material``, ``f0_linear`` [r, g, b], ``f0_srgb8`` [r, g, b], ``category``, ``source``, plus
        ``Y`` (luminance of F0) and ``forbidden_zone``.

    References
    ----------
    .. [1] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 PBS course notes (F0 table computed
       the same way from measured optical constants).
    """
    spd = _as_spd(illuminant)
    grid = spectral_grid(spd, step_nm, observer)
    F0 = np.asarray(material.F0(grid), dtype=float)
    XYZ = reflectance_to_XYZ(F0, grid, spd, observer)
    rgb = XYZ_to_rgb(XYZ, "sRGB", white_XYZ(spd, observer))
    category, forbidden = classify_f0(min(float(XYZ[1]), 1.0))
    return {"material": material.name, "f0_linear": [float(v) for v in rgb],
            "f0_srgb8": [int(v) for v in rgb_to_srgb8(rgb)], "category": category, "source": material.source,
            "Y": float(XYZ[1]), "forbidden_zone": forbidden}
