"""Standard observers: the CIE colour-matching functions (colour-science's tables; the CIE 1931 2° observer from
:mod:`waveoptics.colour.cie_tables`, the same numbers without importing colour-science), by name.

References
----------
.. [1] CIE 015:2018, *Colorimetry*, 4th ed. (1931 2° and 1964 10° standard observers).
"""
from __future__ import annotations

import functools

import numpy as np

from ..errors import unknown
from .cie_tables import CIE_1931_2_NAME, cie_1931_2

__all__ = ['DEFAULT_OBSERVER', 'OBSERVERS', 'observer_name', 'cmfs', 'cmf_at']


#: default observer (colour-science's name)
DEFAULT_OBSERVER = "CIE 1931 2 Degree Standard Observer"


#: observers understood, canonical names and short aliases
OBSERVERS = {
    "CIE 1931 2 Degree Standard Observer": ("2", "2deg", "1931", "cie_2_1931", "cie1931"),
    "CIE 1964 10 Degree Standard Observer": ("10", "10deg", "1964", "cie_10_1964", "cie1964"),
    "CIE 2015 2 Degree Standard Observer": ("2015-2", "cie2015-2"),
    "CIE 2015 10 Degree Standard Observer": ("2015-10", "cie2015-10"),
}


def observer_name(observer) -> str:
    """Canonical colour-science name of an observer given by name or alias (``"2"``, ``"10"``, ``"1964"``)."""
    s = str(observer).strip()
    for name, aliases in OBSERVERS.items():
        if s.lower() == name.lower() or s.lower() in aliases:
            return name
    raise unknown("observer", s, [*OBSERVERS, "2", "10"])


@functools.lru_cache(maxsize=8)
def _cmfs(name: str):
    if name == CIE_1931_2_NAME:   # the default observer, without importing colour-science
        return cie_1931_2()
    import colour   # colour-science, imported where used (about 2 s: it imports its plotting)

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
