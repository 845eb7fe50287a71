"""The propagating band and the relevant roughness (docs/physics.md §9; Krywonos, Harvey & Choi 2011): the radial
quadrature of the library against a brute-force 2-D sum written here, the closed form of a Gaussian PSD at normal
incidence, the limits, and a generated height field against its own statistics."""
from __future__ import annotations

import math

import numpy as np
import pytest

from waveoptics import scatter, surfaces


def brute_force_band(model, lam_nm, sin_i, n=2001):
    """Σ S(f) df² over the offset disc |f + (sinθ_i/λ, 0)| ≤ 1/λ on an n × n grid (midpoint rule)."""
    R = 1 / (lam_nm * 1e-9)
    c = sin_i * R
    x = -c + np.linspace(-R, R, n, endpoint=False) + R / n
    y = np.linspace(-R, R, n, endpoint=False) + R / n
    fx, fy = np.meshgrid(x, y)
    inside = np.hypot(fx + c, fy) <= R
    return float(np.sum(model.S(np.hypot(fx, fy))[inside])) * (2 * R / n) ** 2


@pytest.mark.parametrize("model", [surfaces.PSDModel("gaussian", sigma=5e-9, T=0.6e-6),
                                   surfaces.PSDModel("exponential", sigma=5e-9, T=0.8e-6),
                                   surfaces.PSDModel("abc", sigma=39e-9, B=3.7e-6, C=2.34)],
                         ids=["gaussian", "exponential", "abc-heavy-tail"])
@pytest.mark.parametrize("theta", [0.0, 30.0, 75.0])
def test_relevant_variance_matches_a_brute_force_sum(model, theta):
    got = scatter.relevant_variance(model, 550.0, math.sin(math.radians(theta)))
    ref = brute_force_band(model, 550.0, math.sin(math.radians(theta)))
    assert got == pytest.approx(ref, rel=5e-3)


def test_gaussian_at_normal_incidence_is_closed_form():
    """S = πσ²T² exp(−π²T²f²) over |f| ≤ 1/λ: σ_rel² = σ²(1 − exp(−π²T²/λ²))."""
    m = surfaces.PSDModel("gaussian", sigma=10e-9, T=0.3e-6)
    lam = 550.0
    ref = m.sigma ** 2 * (1 - math.exp(-(math.pi * m.T / (lam * 1e-9)) ** 2))
    assert scatter.relevant_variance(m, lam, 0.0) == pytest.approx(ref, rel=1e-8)


def test_limits():
    m = surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6)
    # a wavelength far below every surface frequency: everything scatters
    assert scatter.relevant_variance(m, 1e-3, 0.3) == pytest.approx(m.sigma ** 2, rel=1e-3)
    # the default surface (ABC, C = 2.6: a heavy tail) keeps only ~60 % of its variance in the band at 380 nm and
    # θ_i = 30°; using the full σ in exp(−g) then withholds ~3 % of the light from the lobe, the loss the issue
    # measured on the two-scale model
    s2 = scatter.relevant_variance(m, 380.0, 0.5)
    frac = scatter.beyond_band_fraction(m.sigma ** 2, s2)
    assert 0.35 < frac < 0.45
    k = 4 * math.pi * math.cos(math.radians(30.0)) / 380e-9
    lost = math.exp(-k * k * s2) - math.exp(-k * k * m.sigma ** 2)
    assert lost == pytest.approx(0.03, abs=0.006)
    # grazing incidence shifts the band: at sinθ_i → 1 it still holds the low frequencies
    assert 0 < scatter.relevant_variance(m, 550.0, 1.0) < m.sigma ** 2


def test_band_arc_edges():
    lam = 500.0
    R = 1 / (lam * 1e-9)
    assert scatter.band_arc(0.5 * R, 0.3, lam) == pytest.approx(2 * np.pi)
    assert scatter.band_arc(1.5 * R, 0.3, lam) == 0.0
    # on the circle through the band's centre the arc is 2 arccos(s / (2R))
    s = 0.3 * R
    assert scatter.band_arc(R, 0.3, lam) == pytest.approx(2 * math.acos(s / (2 * R)))


def test_height_field_band_matches_its_psd_model():
    """A periodic Gaussian surface (exact spectral synthesis, no window): its periodogram's band share equals the
    model's within the sampling scatter (3 %)."""
    m = surfaces.PSDModel("gaussian", sigma=5e-9, T=0.5e-6)
    fr = []
    for seed in range(4):
        hf = surfaces.gaussian(m.sigma, m.T, 256 * 0.1e-6, 256, seed)
        fr.append(scatter.relevant_variance_of_field(hf, 550.0, 0.5) / float(np.var(hf.heights)))
    assert np.mean(fr) == pytest.approx(scatter.relevant_variance(m, 550.0, 0.5) / m.sigma ** 2, rel=3e-2)
