"""Multiple-scattering compensation (Kulla & Conty 2017; issue 16): the white furnace holds at every incidence."""
import numpy as np
import pytest

from waveoptics.brdf import F_ms, Micro, MicrofacetBRDF, chi2_test


def _dir(theta_deg):
    t = np.radians(theta_deg)
    return np.array([np.sin(t), 0.0, np.cos(t)])


@pytest.mark.parametrize("ndf", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [0.1, 0.5, 1.0, 2.0])
def test_white_furnace_holds_with_compensation(ndf, alpha):
    """F = 1: single scattering loses up to 69 % (GGX α = 1); with the lobe the albedo is 1 to 1e-3 (the E(μ)
    table's interpolation), at θ_i from 0° to 85°."""
    b = MicrofacetBRDF("Au", Micro(alpha=alpha, ndf=ndf), fresnel="one", multiple_scattering=True)
    for th in (0, 30, 60, 75, 85):
        assert float(b.albedo(_dir(th), 550.0)) == pytest.approx(1.0, abs=1e-3), th


def test_fresnel_average_of_multiple_scattering():
    """F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)): 1 for a white surface, F_avg² as E_avg → 1, and below
    F_avg² otherwise (every further bounce multiplies by F_avg < 1)."""
    assert F_ms(1.0, 0.6) == pytest.approx(1.0)
    assert F_ms(0.8, 1.0) == pytest.approx(0.64)
    assert F_ms(0.8, 0.6) == pytest.approx(0.64 * 0.6 / (1 - 0.8 * 0.4)) and F_ms(0.8, 0.6) < 0.64


def test_compensated_albedo_of_a_metal_lies_between_single_scattering_and_F():
    wi = _dir(30)
    for a in (0.3, 1.0):
        single = MicrofacetBRDF("Au", Micro(alpha=a)).albedo(wi, 550.0)
        multi = MicrofacetBRDF("Au", Micro(alpha=a), multiple_scattering=True)
        E = float(multi.albedo(wi, 550.0))
        assert float(single) < E < float(multi.material.F(np.cos(np.radians(30)), 550.0)) + 0.05


def test_reciprocity_and_sampling_with_compensation():
    b = MicrofacetBRDF("PMMA", Micro(alpha=0.8), kd=0.3, multiple_scattering=True)
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    np.testing.assert_allclose(b.eval(wi, wo, 550.0), b.eval(wo, wi, 550.0), rtol=1e-10)
    d = _dir(50)

    def sample(u):
        s = b.sample(d, 550.0, u)
        return np.where((s.weight > 0)[:, None], s.wo, np.nan)
    r = chi2_test(sample, lambda x: b.pdf(d, x, 550.0), sample_count=100_000, res=41, ires=6)
    assert r.passed, r.message


def test_two_scale_models_refuse_the_option_instead_of_ignoring_it():
    from waveoptics.brdf import TwoScaleBRDF
    from waveoptics.request import make_nano

    with pytest.raises(Exception, match="multiple_scattering is not available for the two-scale model"):
        TwoScaleBRDF("Au", Micro(alpha=0.3), nano=make_nano("gaussian:sigma=5nm,T=1um", [550.0]),
                     multiple_scattering=True)


def test_diffuse_and_compensation_sampling_of_a_dielectric_passes_chi2():
    b = MicrofacetBRDF("PMMA", Micro(alpha=1.0, ndf="beckmann"), kd=0.8, multiple_scattering=True)
    d = _dir(70)

    def sample(u):
        s = b.sample(d, 450.0, u)
        return np.where((s.weight > 0)[:, None], s.wo, np.nan)
    r = chi2_test(sample, lambda x: b.pdf(d, x, 450.0), sample_count=100_000, res=41, ires=6)
    assert r.passed, r.message
