"""Spectral pipeline: light sources, spectra → CIE XYZ → linear RGB, metamers, F0 colours.

Everything colorimetric (colour-matching functions, CIE illuminants, Planck's law, RGB colour spaces, chromatic
adaptation, CIELAB and ΔE2000, the sRGB transfer function, CSV spectra, ASTM E2022 weights) comes from
colour-science (imported by the functions that need it: it takes about 2 s to import; the default observer and
illuminant, CIE 1931 2° and D65, come from :mod:`waveoptics.colour.cie_tables`, the same numbers); this module
only arranges it for waveoptics' needs:

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

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import WaveopticsError, unknown
from ..units import check_wavelengths
from .illuminants import SPD, as_spd
from .observers import DEFAULT_OBSERVER, cmf_at, cmfs, observer_name

__all__ = ['SPACES', 'CAT', 'VISIBLE_NM', 'spd_to_XYZ', 'TRISTIMULUS_METHODS', 'tristimulus_weights', 'reflectance_to_XYZ', 'white_XYZ', 'space_name', 'XYZ_to_rgb', 'reflectance_to_rgb', 'reflectance_to_rgb_matrix', 'rgb_to_srgb8', 'delta_e2000', 'luminance']


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


# ------------------------------------------------------------------------------------------- observers


def spd_tristimulus(spd: SPD, observer) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
    spd = as_spd(spd)
    _, m, c = spd_tristimulus(spd, observer)
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
    lam, m, c = spd_tristimulus(spd, observer)
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

    lam, m, c = spd_tristimulus(spd, observer)
    mc = m[:, None] * c
    if grid.size == 1:
        return mc.sum(axis=0, keepdims=True)
    Phi = CubicSpline(grid, np.eye(grid.size), axis=0)(np.clip(lam, grid[0], grid[-1]))  # (k, n)
    return Phi.T @ mc


def _weights_astm_e2022(grid: np.ndarray, spd: SPD, observer) -> np.ndarray:
    """colour-science's ASTM E2022 weights for a uniform integer-step grid aligned with the CMF start."""
    from colour.colorimetry import (
        adjust_tristimulus_weighting_factors_ASTME308,
        tristimulus_weighting_factors_ASTME2022,
    )
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

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
    spd = as_spd(illuminant)
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
    XYZ = spd_to_XYZ(as_spd(illuminant), observer)
    if not XYZ[1] > 0:
        raise WaveopticsError(f"illuminant {as_spd(illuminant).name!r} has no visible power")
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
    import colour   # colour-science (module doc)

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


def reflectance_to_rgb_matrix(wavelengths_nm, illuminant="D65", space="sRGB") -> np.ndarray:
    """The linear map M (n, 3) from a reflectance sampled at *wavelengths_nm* to linear RGB, rgb = R @ M:
    :func:`reflectance_to_rgb` is linear in R, so row j is the RGB of unit reflectance at wavelength j alone (a
    white reflector gives (1, 1, 1))."""
    w = np.asarray(wavelengths_nm, dtype=float)
    return reflectance_to_rgb(np.eye(w.size), w, illuminant, space=space)


def luminance(rgb, space="sRGB") -> np.ndarray:
    """Relative luminance Y of linear RGB (..., 3) in *space*: the Y row of the space's RGB → XYZ matrix
    (colour-science's; for sRGB the Rec. 709 weights 0.2126, 0.7152, 0.0722, IEC 61966-2-1)."""
    import colour   # colour-science (module doc)

    weights = np.asarray(colour.RGB_COLOURSPACES[space_name(space)].matrix_RGB_to_XYZ)[1]
    return np.asarray(rgb, dtype=float) @ weights


def rgb_to_srgb8(rgb) -> np.ndarray:
    """8-bit sRGB-encoded integers from linear sRGB: clipped to [0, 1], IEC 61966-2-1 curve, rounded."""
    import colour   # colour-science (module doc)

    rgb = np.asarray(rgb, dtype=float)
    if not np.all(np.isfinite(rgb)):
        raise WaveopticsError("RGB contains NaN or Inf")
    enc = colour.cctf_encoding(np.clip(rgb, 0.0, 1.0), function="sRGB")
    return np.rint(np.asarray(enc) * 255.0).astype(int)


def delta_e2000_XYZ(XYZ1, XYZ2, white) -> np.ndarray:
    import colour   # colour-science (module doc)

    xy = colour.XYZ_to_xy(np.asarray(white, dtype=float))
    return colour.delta_E(colour.XYZ_to_Lab(XYZ1, xy), colour.XYZ_to_Lab(XYZ2, xy), method="CIE 2000")


def delta_e2000(rgb1, rgb2, colourspace="sRGB") -> np.ndarray:
    """CIEDE2000 colour difference between linear RGB colours (..., 3) of *colourspace*, white Y = 1.

    References
    ----------
    .. [1] Luo, Cui, Rigg, Color Res. Appl. 26(5), 2001; colour-science ``delta_E(method='CIE 2000')``.
    """
    import colour   # colour-science (module doc)

    cs = colour.RGB_COLOURSPACES[space_name(colourspace)]
    to_XYZ = functools.partial(colour.RGB_to_XYZ, colourspace=cs, illuminant=cs.whitepoint,
                               chromatic_adaptation_transform=None)
    white = colour.xy_to_XYZ(cs.whitepoint)
    return delta_e2000_XYZ(to_XYZ(np.asarray(rgb1, float)), to_XYZ(np.asarray(rgb2, float)), white)
