"""Which wavelengths a simulation needs: the spectral grid that reaches a requested colour accuracy (ΔE2000)
for an illuminant, measured on a set of smooth test reflectances.

References
----------
.. [1] M. R. Luo, G. Cui, B. Rigg, "The development of the CIE 2000 colour-difference formula: CIEDE2000",
   Color Res. Appl. 26(5), 2001.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import WaveopticsError
from .colorimetry import DEFAULT_OBSERVER, VISIBLE_NM, delta_e2000_XYZ, spd_tristimulus, cmf_at, reflectance_to_XYZ, white_XYZ
from .illuminants import as_spd

__all__ = ['STEPS_NM', 'spectral_grid', 'reference_reflectances', 'step_errors', 'simulation_wavelengths']

#: candidate grid steps (nm), coarsest first, tried by :func:`simulation_wavelengths`
STEPS_NM = (40.0, 20.0, 10.0, 5.0, 2.0, 1.0)


# ----------------------------------------------------------------------------------- simulation grids

def spectral_grid(illuminant, step_nm: float = 5.0, observer=DEFAULT_OBSERVER) -> np.ndarray:
    """Wavelengths (nm) at which spectra must be computed under a light source.

    Line SPD: its visible lines (x̄ȳz̄ not all zero). Continuous SPD: a uniform grid of *step_nm* on multiples of
    the step from 380 nm, covering where S·(x̄+ȳ+z̄) exceeds 1e-4 of its peak within 380–780 nm.
    """
    spd = as_spd(illuminant)
    if spd.lines:
        c = cmf_at(spd.wavelengths_nm, observer)
        keep = (c.sum(axis=-1) > 0) & (spd.values > 0)
        if not keep.any():
            raise WaveopticsError(f"illuminant {spd.name!r} has no visible line")
        return spd.wavelengths_nm[keep].copy()
    step = float(step_nm)
    if not (math.isfinite(step) and step > 0):
        raise WaveopticsError(f"wavelength step {step_nm!r} nm is not allowed; it must be > 0")
    lam, m, c = spd_tristimulus(spd, observer)
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
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

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
    spd = as_spd(illuminant)
    w_ref, R_ref = reflectances if reflectances is not None else reference_reflectances()
    w_ref, R_ref = np.asarray(w_ref, float), np.atleast_2d(np.asarray(R_ref, float))
    XYZ_ref = reflectance_to_XYZ(R_ref, w_ref, spd, observer)
    white = white_XYZ(spd, observer)
    out = {}
    for step in steps_nm:
        grid = spectral_grid(spd, step, observer)
        R = np.stack([np.interp(grid, w_ref, r) for r in R_ref])
        dE = delta_e2000_XYZ(reflectance_to_XYZ(R, grid, spd, observer, method), XYZ_ref, white)
        out[float(step)] = (float(np.max(dE)), int(grid.size))
    return out


def simulation_wavelengths(illuminant, delta_e: float = 0.5, observer=DEFAULT_OBSERVER,
                           reflectances=None, method: str = "linear") -> np.ndarray:
    """The wavelengths (nm) a simulation must compute to reach a colour accuracy under a light source.

    Line SPDs: exactly their visible lines (accuracy is then exact). Continuous SPDs: the coarsest uniform grid
    among :data:`STEPS_NM` whose worst ΔE2000 over the test reflectances (see :func:`step_errors`) stays
    ≤ *delta_e* against 1 nm sampling (falls back to 1 nm), when the simulated spectra are integrated
    with the same *method* (see :func:`tristimulus_weights`).

    Notes
    -----
    The default test set is smooth (ColorChecker patches and metal absorption edges). Iridescent spectra with
    peaks narrower than the chosen step are under-sampled: pass representative *reflectances* for those.
    """
    spd = as_spd(illuminant)
    if spd.lines:
        return spectral_grid(spd, observer=observer)
    if not (math.isfinite(delta_e) and delta_e > 0):
        raise WaveopticsError(f"colour accuracy {delta_e!r} ΔE is not allowed; it must be > 0")
    errors = step_errors(spd, STEPS_NM[:-1], observer, reflectances, method)
    for step, (dE, _) in errors.items():
        if dE <= delta_e:
            return spectral_grid(spd, step, observer)
    return spectral_grid(spd, 1.0, observer)
