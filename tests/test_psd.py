"""PSD-based (statistical) scattering against closed forms: Beckmann-Spizzichino series, TIS, Rayleigh-Rice."""
import numpy as np
import pytest
from scipy import integrate, special

from waveoptics import scatter, surfaces
from waveoptics.errors import WaveopticsError
from waveoptics.units import direction_from_angles


def _disc(n=801):
    u = np.linspace(-1, 1, n)
    U, V = np.meshgrid(u, u)
    r2 = U ** 2 + V ** 2
    wo = np.stack([U, V, np.sqrt(np.clip(1 - r2, 0, 1))], -1)
    return wo, r2 < 1, (u[1] - u[0]) ** 2


@pytest.mark.parametrize("kind, kw", [("gaussian", {"T": 1e-6}), ("exponential", {"T": 0.5e-6}),
                                      ("abc", {"B": 5e-6, "C": 3.0})])
def test_psd_integrates_to_sigma_squared(kind, kw):
    m = surfaces.PSDModel(kind, sigma=3e-9, **kw)
    val, _ = integrate.quad(lambda f: 2 * np.pi * f * m.S(f), 0, np.inf, limit=400)
    assert val == pytest.approx(m.sigma ** 2, rel=1e-6)


@pytest.mark.parametrize("kind, kw", [("gaussian", {"T": 1e-6}), ("exponential", {"T": 0.5e-6}),
                                      ("abc", {"B": 5e-6, "C": 3.5})])
def test_correlation_is_hankel_transform_of_psd(kind, kw):
    """c(r) σ² = 2π ∫ S(f) J0(2π f r) f df (Wiener-Khinchin), checked at a few lags."""
    m = surfaces.PSDModel(kind, sigma=1.0, **kw)
    for r in [0.0, 0.3 * m.length_scale, m.length_scale, 2.5 * m.length_scale]:
        top = (50 if kind == "gaussian" else 5000) / m.length_scale  # heavy f^-3 tails need a long range
        val, _ = integrate.quad(lambda f: 2 * np.pi * f * m.S(f) * special.j0(2 * np.pi * f * r), 0, top,
                                limit=20000)
        assert val == pytest.approx(float(m.c(r)), abs=2e-3)


def test_series_tables_match_closed_form_gaussian():
    """For c = exp(−r²/T²): H_m(q) = π T²/m · exp(−q²T²/(4m)) (docs/physics.md §3)."""
    m = surfaces.PSDModel("gaussian", sigma=10e-9, T=2e-6)
    tab = scatter.series_tables(m, q_max=3e7, m_max=20)
    for mm in (1, 2, 5, 20):
        exact = np.pi * m.T ** 2 / mm * np.exp(-tab.q ** 2 * m.T ** 2 / (4 * mm))
        assert np.max(np.abs(tab.H[mm - 1] - exact)) < 1e-3 * exact[0]


@pytest.mark.parametrize("sigma_nm, lam", [(5, 550), (20, 500), (40, 450), (60, 650)])
def test_scattered_energy_equals_one_minus_exp_minus_g_at_normal_incidence(sigma_nm, lam):
    """Paraxial energy: ∫ f_s cosθ dω = 1 − e^{−g} (docs/physics.md §3) when T ≫ λ (narrow lobe)."""
    m = surfaces.PSDModel("gaussian", sigma=sigma_nm * 1e-9, T=8e-6)
    wo, ins, dA = _disc(1201)
    f = scatter.scattered_lobe(np.array([0, 0, 1.0]), wo, lam, m)
    g = (4 * np.pi * m.sigma / (lam * 1e-9)) ** 2
    assert np.sum(f[ins]) * dA == pytest.approx(-np.expm1(-g), rel=0.01)


def test_first_term_is_rayleigh_rice_for_smooth_surfaces():
    """σ ≪ λ: the series reduces to Rayleigh-Rice with Q = 1 near the specular direction (docs/physics.md §4)."""
    m = surfaces.PSDModel("abc", sigma=1e-9, B=20e-6, C=3.2)
    wi = direction_from_angles(0.0, 0.0)
    wo = direction_from_angles(np.linspace(0.5, 20, 30), 0.0)
    a = scatter.scattered_lobe(wi, wo, 550.0, m)
    b = scatter.rayleigh_rice(wi, wo, 550.0, m)
    np.testing.assert_allclose(a, b, rtol=0.08)  # obliquity differs by (1+cosθ_o)²/4cosθ_o... within 20°: < 8 %


def test_truncation_is_reported_for_very_rough_surfaces():
    m = surfaces.PSDModel("gaussian", sigma=400e-9, T=5e-6)
    _, cap = scatter.scattered_lobe(np.array([0, 0, 1.0]), np.array([0.01, 0, 0.99995]), 400.0, m, m_max=48,
                                return_captured=True)
    assert cap < 0.5  # g ≈ 1600: 48 terms hold almost nothing, and the function says so


def test_debye_waller_formula():
    assert scatter.debye_waller(1.0, 500.0, 0.0) == 1.0
    g = (4 * np.pi * 10e-9 * 0.5 / 500e-9) ** 2
    assert scatter.debye_waller(0.5, 500.0, 10e-9) == pytest.approx(np.exp(-g))


def test_below_surface_and_grazing_give_zero_not_nan():
    m = surfaces.PSDModel("exponential", sigma=5e-9, T=1e-6)
    wi = direction_from_angles(30.0, 0.0)
    wo = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.6, 0.0, 0.8]])
    f = scatter.scattered_lobe(wi, wo, 500.0, m)
    assert np.all(np.isfinite(f)) and f[0] == 0 and f[1] == 0 and f[2] > 0


def test_bad_parameters_rejected():
    with pytest.raises(WaveopticsError, match="sigma"):
        surfaces.PSDModel("gaussian", sigma=-1e-9, T=1e-6)
    with pytest.raises(WaveopticsError, match="C=2.0"):
        surfaces.PSDModel("abc", sigma=1e-9, B=1e-6, C=2.0)
    with pytest.raises(WaveopticsError, match="did you mean 'gaussian'"):
        surfaces.PSDModel("gausian", sigma=1e-9, T=1e-6)
