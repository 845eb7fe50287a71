"""Colour of a material's normal-incidence reflectance F0 under an illuminant, and its category.

References
----------
.. [1] N. Hoffman, "Physics and Math of Shading", SIGGRAPH 2015 Physically Based Shading course notes.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import WaveopticsError
from ..materials.database import category_from_f0
from .colorimetry import DEFAULT_OBSERVER, XYZ_to_rgb, reflectance_to_XYZ, rgb_to_srgb8, white_XYZ
from .illuminants import as_spd
from .sampling import spectral_grid

__all__ = ['classify_f0', 'f0_colour']

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
    spd = as_spd(illuminant)
    grid = spectral_grid(spd, step_nm, observer)
    F0 = np.asarray(material.F0(grid), dtype=float)
    XYZ = reflectance_to_XYZ(F0, grid, spd, observer)
    rgb = XYZ_to_rgb(XYZ, "sRGB", white_XYZ(spd, observer))
    category, forbidden = classify_f0(min(float(XYZ[1]), 1.0))
    return {"material": material.name, "f0_linear": [float(v) for v in rgb],
            "f0_srgb8": [int(v) for v in rgb_to_srgb8(rgb)], "category": category, "source": material.source,
            "Y": float(XYZ[1]), "forbidden_zone": forbidden}
