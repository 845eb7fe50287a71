"""Shortcuts taken by the tables of the default model (issue 31: export and demo time) give the numbers of the plain
computation they replace, to float rounding: the band series' H_m in one matrix product (against the per-term
trapezoid Hankel sum written here), the RGL table's projected area of an isotropic NDF on one row, the memo of η at
single wavelengths, and `info` without colour-science's import."""
import math

import numpy as np
from scipy import special

from waveoptics import scatter, surfaces
from waveoptics.scatter.band import sigma2_nodes, band_correlation, series_arrays

MODEL = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)


def _band_hankel(lam, m, q, n_r):
    """H_m^b(q) = 2π Σ_r c_b(r)^m J0(q r) r w_r + 2π dr²/12 (trapezoid on *n_r* nodes of r ≤ max(12 ℓ, 60 λ), the
    r = 0 end corrected; Bracewell ch. 12), one sum per q, as written from the formula."""
    r_max = max(12.0 * MODEL.length_scale, 60.0 * lam * 1e-9)
    r = np.linspace(0.0, r_max, n_r)
    dr = r[1] - r[0]
    cm = band_correlation(MODEL, lam, r) ** m * 2 * math.pi * r
    out = np.empty(q.size)
    for i, qi in enumerate(q):
        y = cm * special.j0(qi * r)
        out[i] = max(dr * (y.sum() - 0.5 * (y[0] + y[-1])) + 2 * math.pi * dr ** 2 / 12, 0.0)
    return out


def test_band_series_terms_equal_the_per_term_hankel_sums():
    """The band series' table of H_m^b (one matrix product over all terms) equals the per-term trapezoid sums on
    the same radial grid (steps min(λ/16, ℓ/40)) to rounding (1e-12 of the peak)."""
    lam = 830.0
    nodes = np.linspace(0.0, 1.0, scatter.band.SIN_NODES)
    tab = series_arrays(MODEL, lam, nodes, sigma2_nodes(MODEL, lam), None, 256)
    L = MODEL.length_scale
    r_max = max(12.0 * L, 60.0 * lam * 1e-9)
    n_r = int(min(max(r_max / (lam * 1e-9 / 16.0), r_max / (L / 40.0), 400), 12000))
    assert tab["H"].shape[0] >= 2
    for j in range(tab["H"].shape[0]):
        same = _band_hankel(lam, j + 2, tab["q"], n_r)
        np.testing.assert_allclose(tab["H"][j], same, rtol=0, atol=1e-12 * same.max())
    assert tab["H"].flags.c_contiguous


def test_isotropic_sigma_row_matches_full_grid_and_closed_form():
    """The RGL projected area σ(θ_i) of an isotropic Beckmann NDF table (α = 0.1): the one computed row repeated
    over φ_i is within 2e-4 of the midpoint rule at every (φ_i, θ_i) vertex (measured 1.2e-4), and relative to
    normal incidence within 2e-3 of the closed form cos θ_i (1 + Λ(θ_i)) up to 85° (Heitz 2014 eq. 2; Beckmann
    Λ = (erf(a) − 1)/2 + e^{−a²}/(2a√π), a = 1/(α tan θ_i)): measured 5.4e-4, the full grid 5.5e-4."""
    import pytest
    pytest.importorskip("mitsuba")
    from waveoptics.renderers import rgl

    mi = rgl._mitsuba()
    nn, a = 64, 0.1
    th = rgl.u2theta(np.linspace(0.0, 1.0, nn))
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        D = np.where(th < np.pi / 2 - 1e-9, np.exp(-np.tan(th) ** 2 / a ** 2) / (np.pi * a * a * np.cos(th) ** 4),
                     0.0)
    warp = mi.MarginalContinuous2D0(np.repeat(D[None, :], nn, axis=0).astype(np.float32), normalize=False,
                                    enable_sampling=False)
    row = rgl.sigma_table(warp.eval, mi, nn, True)
    full = rgl.sigma_table(warp.eval, mi, nn, False)
    assert row.shape == full.shape == (nn, nn)
    np.testing.assert_array_equal(row, np.repeat(row[:1], nn, axis=0))
    np.testing.assert_allclose(row, full, rtol=2e-4)
    ok = (th > 0) & (th <= np.radians(85.0))
    x = 1.0 / (a * np.tan(th[ok]))
    lam = (special.erf(x) - 1.0) / 2.0 + np.exp(-x * x) / (2.0 * x * math.sqrt(math.pi))
    # relative to normal incidence, σ(0) = ∫ D cos θ_m dm: the interpolated table holds 1 + 3.7e-3 of it
    np.testing.assert_allclose(row[0, 0], 1.0, rtol=5e-3)
    np.testing.assert_allclose(row[0, ok] / row[0, 0], np.cos(th[ok]) * (1.0 + lam), rtol=2e-3)


def test_series_tables_equal_the_per_term_hankel_sums():
    """The classical series' H_m(q) = 2π Σ_r c(r)^m J0(q r) r w_r + 2π dr²/12 (trapezoid, the r = 0 end corrected;
    values below 1e-12 of H_m(0) are 0), one sum per term as written from the formula, against the table's single
    product over all 48 terms: equal to rounding (1e-12 of each term's peak)."""
    from waveoptics.scatter import series

    model = surfaces.PSDModel("gaussian", sigma=5e-9, T=1e-6)
    q_max = 2.0 ** 24
    tab = series.series_tables(model, q_max, 48, 128)
    L = model.length_scale
    r_probe = L * np.logspace(-3, 4, 2000)
    idx = np.nonzero(model.c(r_probe) ** 2 < 1e-10)[0]
    r_max = r_probe[idx[0]] if idx.size else r_probe[-1]
    n_r = int(min(max(r_max / min(L / 40, 2 * np.pi / q_max / 12), 400), 20000))
    r = np.linspace(0.0, r_max, n_r)
    dr = r[1] - r[0]
    c = model.c(r)
    J = special.j0(np.outer(tab.q, r)) * 2 * math.pi * r
    for m in (1, 2, 7, 48):
        y = J * c ** m
        expect = dr * (y.sum(axis=1) - 0.5 * (y[:, 0] + y[:, -1])) + 2 * math.pi * dr ** 2 / 12
        expect = np.where(expect > 1e-12 * expect[0], expect, 0.0)
        np.testing.assert_allclose(tab.H[m - 1], expect, rtol=0, atol=1e-12 * expect.max())


def test_scalar_eta_memo_returns_the_array_path_values():
    """η at one wavelength is kept per material: repeated and interleaved asks give the values of the array path
    (which is not kept), a caller's write into the returned array does not reach the memo, a replaced copy starts
    empty, and the memo stays bounded."""
    import dataclasses

    from waveoptics.materials import get_material
    from waveoptics.materials.database import ETA_MEMO_SIZE

    m = get_material("Au")
    w = np.array([380.0, 550.0, 701.5])
    ref = m.eta(w)
    for _ in range(2):
        for lam, e in zip(w, ref):
            got = m.eta(float(lam))
            assert np.ndim(got) == 0 and got == e
    got = m.eta(550.0)
    got[...] = 0.0
    assert m.eta(550.0) == ref[1]
    assert dataclasses.replace(m, name="copy")._eta_memo == {}
    for lam in np.linspace(400.0, 700.0, ETA_MEMO_SIZE + 10):
        m.eta(float(lam))
    assert len(m._eta_memo) <= ETA_MEMO_SIZE
    assert m.eta(701.5) == ref[2]


def test_info_reports_colours_version_without_importing_it():
    """``waveoptics info`` reads colour-science's version from its metadata: the version the package itself
    states, and the command leaves colour (its plotting, matplotlib, pandas: ~2 s) unimported."""
    import json
    import subprocess
    import sys

    code = ("import json, sys; from waveoptics.cli.info import gather; d = gather(); "
            "print(json.dumps([d['colour'], 'colour' in sys.modules, 'matplotlib' in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    version, imported_colour, imported_mpl = json.loads(out.stdout.strip().splitlines()[-1])
    import colour
    assert version == colour.__version__
    assert not imported_colour and not imported_mpl
