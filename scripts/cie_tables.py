"""Write waveoptics/colour/cie_tables.py: colour-science's CIE 1931 2° colour-matching functions and CIE
illuminant D65, copied value for value, so that the default observer and illuminant need no import of
colour-science (about 2 s: it imports matplotlib and its plotting on import).

Run ``python scripts/cie_tables.py`` after a colour-science upgrade; tests/test_cie_tables.py checks the copy.
"""
from __future__ import annotations

from pathlib import Path

import colour
import numpy as np

OUT = Path(__file__).resolve().parent.parent / "waveoptics" / "colour" / "cie_tables.py"
OBSERVER = "CIE 1931 2 Degree Standard Observer"


def _floats(values, per_line: int, indent: str = "    ") -> str:
    v = [repr(float(x)) for x in np.ravel(values)]
    return "\n".join(indent + ", ".join(v[i:i + per_line]) + "," for i in range(0, len(v), per_line))


def main() -> None:
    c = colour.MSDS_CMFS[OBSERVER]
    d = colour.SDS_ILLUMINANTS["D65"]
    w, v = np.asarray(c.wavelengths, dtype=float), np.asarray(c.values, dtype=float)
    dw, dv = np.asarray(d.wavelengths, dtype=float), np.asarray(d.values, dtype=float)
    assert np.array_equal(w, np.arange(w[0], w[-1] + 1)) and np.array_equal(dw, np.arange(dw[0], dw[-1] + 1, 5))
    text = f'''"""The CIE 1931 2° standard observer's colour-matching functions (1 nm) and CIE standard illuminant D65
(5 nm), as colour-science {colour.__version__} tabulates them (copied value for value by scripts/cie_tables.py;
tests/test_cie_tables.py compares them): the default observer and illuminant of :mod:`waveoptics.colour` without
importing colour-science, which takes about 2 s (it imports matplotlib and its plotting on import).

References
----------
.. [1] CIE 015:2018, *Colorimetry*, 4th ed., Tables 1 and 2 (1931 2° observer; illuminant D65).
.. [2] T. Mansencal et al., colour-science, https://www.colour-science.org (``MSDS_CMFS``, ``SDS_ILLUMINANTS``).
"""
from __future__ import annotations

import numpy as np

__all__ = ["CIE_1931_2_NAME", "cie_1931_2", "d65"]

#: colour-science's name of the observer tabulated here
CIE_1931_2_NAME = "{OBSERVER}"

_CMF_START_NM, _CMF_END_NM = {w[0]!r}, {w[-1]!r}
_CMF = (  # x̄, ȳ, z̄ per nm from _CMF_START_NM
{_floats(v, 6)}
)

_D65_START_NM, _D65_END_NM, _D65_STEP_NM = {dw[0]!r}, {dw[-1]!r}, 5.0
_D65 = (  # relative spectral power per nm from _D65_START_NM
{_floats(dv, 8)}
)


def _frozen(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def cie_1931_2() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths (n,) nm, x̄ȳz̄ (n, 3)) of the CIE 1931 2° observer at 1 nm (read-only)."""
    w = np.arange(_CMF_START_NM, _CMF_END_NM + 1.0)
    return _frozen(w), _frozen(np.array(_CMF, dtype=float).reshape(w.size, 3))


def d65() -> tuple[np.ndarray, np.ndarray]:
    """(wavelengths (n,) nm, relative spectral power per nm (n,)) of CIE illuminant D65 at 5 nm (read-only)."""
    w = np.arange(_D65_START_NM, _D65_END_NM + _D65_STEP_NM, _D65_STEP_NM)
    return _frozen(w), _frozen(np.array(_D65, dtype=float))
'''
    OUT.write_text(text)
    print(f"wrote {OUT} ({len(text.splitlines())} lines)")


if __name__ == "__main__":
    main()
