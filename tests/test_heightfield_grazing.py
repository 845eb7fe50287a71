"""Height fields at grazing light (issue 28, point 5): a nano height field's Kirchhoff lobe hands over to the
first-order (Rayleigh-Rice) lobe of its periodogram towards grazing angles, as the PSD route's lobe does.

Before, the field's tangent-plane lobe kept its obliquity factor, whose albedo grows as 1/cosθ_i: on Al at 550 nm
a generated ABC field (σ 8.2 nm realized) scattered 5.1x / 40x / 156x its first-order TIS at 88 / 89 / 89.5°, its
coherent fraction fell to 0.95 / 0.90 / 0.81 (first order: 0.995 / 0.998 / 0.999), and the two-scale energy guard
cut the diffracted part by 84-87 % at 89-89.5° (F = 1, micro α 0.1, paraxial route).

Oracles written here: the field's periodogram (Hann window, |FFT|² dx dy / Σw²; Welch 1967) summed bin by bin over
the propagating disc with first-order Rayleigh-Rice's BRDF (16π²/λ⁴) cosθ_i cosθ_o Q S(f) (Church, Jenkinson &
Zavada 1979), Q of Al from Elson & Bennett 1979 (Germer 1997, eqs. 17–20) and Q = 1 for F = 1 (the scalar
Dirichlet problem, Thorsos & Jackson 1989); the Debye-Waller factor exp(−(2kσ_band cosθ)²) of the periodogram's
propagating band (Davies 1954); the white furnace from the grid's albedos with F = 1.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.signal.windows import hann

from waveoptics import materials, scatter
from waveoptics.brdf import roughness_scales, twoscale
from waveoptics.request import make_nano
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
AL = materials.get_material("Al")
GRAZING = (75.0, 80.0, 85.0, 88.0, 89.0)


@pytest.fixture(scope="module")
def nano():
    """A generated ABC field (128², λ/4 spacing, 17.6 µm; σ 10 nm asked, 8.2 nm in the grid's band ≤ λ/50)."""
    n = make_nano("abc:sigma=10nm,B=2um,C=2.6", [LAM], solver="fft", seed=1)
    assert n.sigma <= LAM * 1e-9 / 50
    return n


def _dir(theta):
    t = math.radians(theta)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def _periodogram(hf):
    """(P (m⁴), f_x, f_y (1/m), bin area (1/m²)): the Hann-windowed periodogram of the field, Σ P Δf² = the
    window-weighted variance."""
    h = hf.heights - hf.heights.mean()
    ny, nx = h.shape
    w = np.outer(hann(ny, sym=False), hann(nx, sym=False))
    P = np.abs(np.fft.fft2(w * h)) ** 2 * hf.dx * hf.dy / np.sum(w ** 2)
    return P, np.fft.fftfreq(nx, hf.dx)[None, :], np.fft.fftfreq(ny, hf.dy)[:, None], 1 / (nx * hf.dx * ny * hf.dy)


def _q_al(ti, u, v):
    """Unpolarized Q = (|q_ss|² + |q_sp|² + |q_ps|² + |q_pp|²)/2 of Al at exit (u, v) (Germer 1997,
    eqs. 17–20)."""
    eps = complex(AL.eta(LAM)) ** 2
    si, ci = math.sin(ti), math.cos(ti)
    s2 = u * u + v * v
    so, co = np.sqrt(s2), np.sqrt(np.clip(1 - s2, 0, 1))
    cphi = np.where(so > 0, -u / np.where(so > 0, so, 1), 1.0)
    sphi = np.where(so > 0, -v / np.where(so > 0, so, 1), 0.0)
    ri, ro = np.sqrt(eps - si * si + 0j), np.sqrt(eps - s2 + 0j)
    ss = (eps - 1) * cphi / ((ci + ri) * (co + ro))
    sp = -(eps - 1) * ro * sphi / ((ci + ri) * (eps * co + ro))
    ps = -(eps - 1) * ri * sphi / ((eps * ci + ri) * (co + ro))
    pp = (eps - 1) * (eps * si * so - ri * ro * cphi) / ((eps * ci + ri) * (eps * co + ro))
    return 0.5 * (abs(ss) ** 2 + abs(sp) ** 2 + abs(ps) ** 2 + abs(pp) ** 2)


def tis_first_order(hf, theta, vector=True):
    """First-order TIS at incidence θ (degrees), the periodogram's bins summed over the propagating disc:
    Σ (16π²/λ²) cosθ_i cosθ_o Q P Δf² (f du dv = f cosθ_o dω_o, du dv = λ² Δf²); Q of Al or 1."""
    P, fx, fy, df = _periodogram(hf)
    lam = LAM * 1e-9
    ti = math.radians(theta)
    u, v = -math.sin(ti) + lam * fx + 0 * fy, lam * fy + 0 * fx
    ok = u * u + v * v < 1
    co = np.sqrt(np.clip(1 - u * u - v * v, 0, 1))
    Q = _q_al(ti, u, v) if vector else 1.0
    return float(np.sum(np.where(ok, 16 * math.pi ** 2 / lam ** 2 * math.cos(ti) * co * Q * P, 0.0)) * df)


def debye_waller(hf, theta):
    """exp(−(2kσ_band cosθ)²), σ_band² the periodogram summed over the frequencies that scatter into the disc."""
    P, fx, fy, df = _periodogram(hf)
    lam = LAM * 1e-9
    ti = math.radians(theta)
    band = np.hypot(-math.sin(ti) + lam * fx, lam * fy) < 1
    return math.exp(-(4 * math.pi / lam * math.cos(ti)) ** 2 * float(np.sum(P[band]) * df))


def _R_al(theta):
    return float(AL.F(math.cos(math.radians(theta)), LAM))


def test_coherent_fraction_is_first_order_at_grazing_incidence(nano):
    """σ ≤ λ/50, θ_i 75–89°: A within 2 % of first order's 1 − TIS/R (Al, vector Q; F = 1, Q = 1) and of the
    Debye-Waller factor of the band. Measured within 2e-4 of 1 − TIS/R; before 0.947 / 0.900 at 88 / 89° (Al)."""
    hf = nano.surface
    for theta in GRAZING:
        c = math.cos(math.radians(theta))
        A = float(nano.coherent_fraction(c, LAM, "kirchhoff", AL))
        A_rr = 1 - tis_first_order(hf, theta) / _R_al(theta)
        assert A == pytest.approx(A_rr, rel=2e-2), (theta, A, A_rr)
        assert A == pytest.approx(debye_waller(hf, theta), rel=2e-2), (theta, A)
        A1 = float(nano.coherent_fraction(c, LAM, "kirchhoff", None))
        assert A1 == pytest.approx(1 - tis_first_order(hf, theta, vector=False), rel=2e-2), (theta, A1)


def test_diffracted_albedo_is_the_periodogram_tis(nano):
    """Mirror-like micro surface on Al (the nano lobe itself, grid route, 96² cells), 85–89°: the diffracted
    albedo within 2 % of the first-order TIS of the field's periodogram summed here (measured ≤ 0.2 %; before
    2.6x / 11x / 41x at 85 / 88 / 89°, the field's tangent-plane lobe)."""
    grid = DirectionGrid.hemisphere(96)
    for theta in (85.0, 88.0, 89.0):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            L = twoscale.evaluate(_dir(theta), [LAM], AL, twoscale.Micro(alpha=0.0), nano, grid, kd=0)
        ref = tis_first_order(nano.surface, theta)
        assert float(L.albedo("diffraction")[0]) == pytest.approx(ref, rel=2e-2), (theta, ref)


#: how far the whole BRDF may fall below the microfacet albedo less the light sent beyond the horizon, per facet
#: route: the frame route's facets balance (measured 3.3e-4 / 3.8e-4 at 89 / 89.5°); the paraxial route's
#: diffracted part falls 0.36 % / 0.42 % of the incident light short of what the coherent part gives up: on 64²
#: cells the grid's micro lobe at 89° lies on cells whose facets see θ_d ≤ 84.8° (no cell centre lies within a
#: cell of the rim), the micro kernel's, centred on the mirror direction, mostly on θ_d = 89°, and the field's
#: 1 − A(θ_d) varies 180x between 89° and 80° (Σ (1 − A) over the grid's lobe 4.4e-3, over the kernel 8.5e-4). A
#: known gap of the paraxial route, not hidden by any rescale; the frame route is the default for such a field
SHORTFALL = {"frame": 2e-3, "paraxial": 5e-3}


@pytest.mark.parametrize("facet", ["frame", "paraxial"])
def test_white_furnace_at_grazing_incidence(nano, facet):
    """F = 1, GGX α = 0.1, 64² cells, θ_i 89 and 89.5°: the whole two-scale BRDF reflects ≤ 1.01 and no less than
    the single-scattering microfacet albedo minus the diffracted light sent beyond the horizon (within
    :data:`SHORTFALL`); neither the energy guard nor the coherent fraction's clip acts (each would warn). Before,
    the guard removed 7-9 % (frame) and 84-87 % (paraxial) of the diffracted light there."""
    one = materials.get_material("f0:1")
    grid = DirectionGrid.hemisphere(64)
    for theta in (89.0, 89.5):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            L = twoscale.evaluate(_dir(theta), [LAM], one, twoscale.Micro(alpha=0.1, ndf="ggx"), nano, grid, kd=0,
                                  facet=facet)
        total, mf = float(L.albedo("total")[0]), float(L.albedo("microfacet")[0])
        beyond = L.info["diffraction_beyond_horizon"][0]
        assert L.info["facet_integration"] == facet
        assert L.info["diffraction_energy_scale"] == [1.0]
        assert total <= 1.01, (theta, total)
        assert total >= mf - beyond - SHORTFALL[facet], (theta, total, mf, beyond)


def test_coherent_fraction_clip_warns_when_it_acts():
    """The guard on A = 1 − E warns with the light it removed (so that the tests above can see it act)."""
    with pytest.warns(scatter.DiffractionWarning, match="removed 0.2"):
        A = roughness_scales._complement_of_albedo(np.array([0.5, 1.2]), LAM)
    assert A.tolist() == [0.5, 0.0]
