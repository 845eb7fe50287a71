"""The CIE tables copied into waveoptics (waveoptics/colour/cie_tables.py) are colour-science's, value for value,
and the default observer and illuminant (the export's luminance weights) no longer import colour-science."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent


def test_the_copied_tables_are_colour_sciences():
    import colour

    from waveoptics.colour import cie_tables

    w, v = cie_tables.cie_1931_2()
    ref = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    assert np.array_equal(w, ref.wavelengths) and np.array_equal(v, ref.values)
    w, v = cie_tables.d65()
    ref = colour.SDS_ILLUMINANTS["D65"]
    assert np.array_equal(w, ref.wavelengths) and np.array_equal(v, ref.values)


def test_luminance_weights_against_hat_functions_on_colour_sciences_data():
    """Y weights of a 20 nm grid: the 1 nm sum Σ_k S(λ_k) ȳ(λ_k) φ_j(λ_k) / Σ_k S ȳ written here with colour-science's
    tables (φ_j the hat functions of the grid, CIE 015 summation)."""
    import colour

    from waveoptics.colour import tristimulus_weights

    grid = np.linspace(360.0, 830.0, 25)
    cmf = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    lam = np.asarray(cmf.wavelengths, dtype=float)
    sy = np.interp(lam, d65.wavelengths, d65.values) * np.asarray(cmf.values)[:, 1]
    hats = np.array([np.interp(lam, grid, np.eye(grid.size)[j]) for j in range(grid.size)])
    ref = hats @ sy / sy.sum()
    np.testing.assert_allclose(tristimulus_weights(grid)[:, 1], ref, rtol=1e-12, atol=1e-15)


def test_the_export_path_does_not_import_colour_science():
    code = ("import sys, numpy as np\n"
            "from waveoptics.renderers import rgl\n"
            "from waveoptics import colour\n"
            "rgl._luminance_weights(np.linspace(360.0, 830.0, 25))\n"
            "colour.tristimulus_weights(np.linspace(380.0, 780.0, 9))\n"
            "print('colour' in sys.modules, 'matplotlib' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["False", "False"]
