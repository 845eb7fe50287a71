"""Multiple-scattering compensation (Kulla & Conty 2017; issue 16): the white furnace holds at every incidence."""
import numpy as np
import pytest

from waveoptics.brdf import F_ms, Micro, MicrofacetBRDF, chi2_test, reflected_samples


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
        single = MicrofacetBRDF("Au", Micro(alpha=a, ndf="ggx")).albedo(wi, 550.0)
        multi = MicrofacetBRDF("Au", Micro(alpha=a, ndf="ggx"), multiple_scattering=True)
        E = float(multi.albedo(wi, 550.0))
        assert float(single) < E < float(multi.material.F(np.cos(np.radians(30)), 550.0)) + 0.05


def test_reciprocity_and_sampling_with_compensation():
    b = MicrofacetBRDF("PMMA", Micro(alpha=0.8, ndf="ggx"), kd=0.3, multiple_scattering=True)
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    np.testing.assert_allclose(b.eval(wi, wo, 550.0), b.eval(wo, wi, 550.0), rtol=1e-10)
    d = _dir(50)

    sample = reflected_samples(b, d, 550.0)
    r = chi2_test(sample, lambda x: b.pdf(d, x, 550.0), sample_count=100_000, res=41, ires=6)
    assert r.passed, r.message


def test_two_scale_functions_take_the_option():
    """Both two-scale BRDF functions carry the compensation lobe (it was refused before issue 16 was finished)."""
    from waveoptics.brdf import TabulatedTwoScaleBRDF, TwoScaleBRDF
    from waveoptics.request import make_nano

    nano = make_nano("gaussian:sigma=5nm,corr_length=1um", [550.0])
    wi, wo = _dir(30), _dir(50) * np.array([-1.0, 1.0, 1.0])
    table = dict(wavelengths_nm=(550.0,), resolution=32, thetas_deg=(20.0, 40.0))   # θ_i = 30° between two nodes
    for cls, kw in ((TwoScaleBRDF, {}), (TabulatedTwoScaleBRDF, table)):
        on = cls("Au", Micro(alpha=0.5, ndf="ggx"), nano=nano, multiple_scattering=True, **kw)
        off = cls("Au", Micro(alpha=0.5, ndf="ggx"), nano=nano, **kw)
        assert on.eval(wi, wo, 550.0) > off.eval(wi, wo, 550.0)


def test_diffuse_and_compensation_sampling_of_a_dielectric_passes_chi2():
    b = MicrofacetBRDF("PMMA", Micro(alpha=1.0, ndf="beckmann"), kd=0.8, multiple_scattering=True)
    d = _dir(70)

    sample = reflected_samples(b, d, 450.0)
    r = chi2_test(sample, lambda x: b.pdf(d, x, 450.0), sample_count=100_000, res=41, ires=6)
    assert r.passed, r.message


def test_cli_multiple_scattering_white_furnace_and_values():
    """brdf --multiple-scattering: the white furnace (F = 1) holds to ≥ 0.99 for α up to 1 at several incidences,
    the values are those of MicrofacetBRDF(multiple_scattering=True), the option is stated in the output, and it is
    refused where it does not apply."""
    import json

    from cli_helpers import run_cli

    for alpha in ("0.1", "0.5", "1.0"):
        rc, out, err, _ = run_cli(["brdf", "--model", "microfacet", "--fresnel", "one", "--alpha", alpha,
                                   "--incident", "0", "--incident", "45", "--incident", "75", "--albedo",
                                   "--multiple-scattering", "--json"])
        assert rc == 0, err
        d = json.loads(out)
        assert d["parameters"]["multiple_scattering"] is True
        assert all(0.99 <= r["albedo"] <= 1.0 + 1e-3 for r in d["albedo"]), (alpha, d["albedo"])
    rc, out, err, _ = run_cli(["brdf", "--model", "microfacet", "--material", "Au", "--alpha", "0.6",
                               "--incident", "30", "--outgoing", "50,180", "--wavelengths", "450,650",
                               "--multiple-scattering", "--json"])
    assert rc == 0, err
    b = MicrofacetBRDF("Au", Micro(alpha=0.6), multiple_scattering=True)
    wi = np.array([np.sin(np.radians(30)), 0, np.cos(np.radians(30))])
    wo = np.array([-np.sin(np.radians(50)), 0, np.cos(np.radians(50))])
    for row in json.loads(out)["values"]:
        assert row["brdf"] == pytest.approx(float(b.eval(wi, wo, row["wavelength_nm"])), rel=1e-9)
    rc, out, err, _ = run_cli(["brdf", "--model", "microfacet", "--material", "Au", "--alpha", "0.6",
                               "--incident", "30", "--outgoing", "50,180", "--multiple-scattering",
                               "--backend", "opencl"])
    assert rc == 2 and "NumPy" in err


def test_cli_disney_diffuse_is_burley():
    import json

    from cli_helpers import run_cli

    base = ["brdf", "--model", "microfacet", "--ior", "1.5", "--alpha", "0.3", "--incident", "30", "--outgoing",
            "40,180", "--kd", "0.5", "--diffuse-roughness", "0.7", "--json"]
    rc1, out1, _, _ = run_cli([*base, "--diffuse", "disney"])
    rc2, out2, _, _ = run_cli([*base, "--diffuse", "burley"])
    assert rc1 == rc2 == 0 and json.loads(out1)["values"] == json.loads(out2)["values"]


@pytest.mark.parametrize("alpha", [0.3, 0.6, 1.0])
def test_two_scale_white_furnace_with_multiple_scattering(alpha):
    """Issue 16: the two-scale BRDF with the compensation lobe (F = 1, Gaussian nano PSD in the propagating band)
    reflects at least 0.99 (the issue's bound) at θ_i ≤ 75° (single scattering alone: 0.31-0.88 here), never more
    than 1 + 1e-3; what is missing is the single-scattering two-scale lobe's own shortfall against the microfacet
    lobe: the wider diffracted lobe loses more to the horizon and to masking (measured 0.994-0.995 at 75°, where
    the nano-roughness scatters most, tests/test_twoscale.py)."""
    from waveoptics import brdf, surfaces

    nano = brdf.Nano(model=surfaces.PSDModel("gaussian", sigma=15e-9, T=1.5e-6))
    b = brdf.TwoScaleBRDF(material="1.5", micro=brdf.Micro(alpha=alpha, ndf="ggx"), nano=nano, fresnel="one",
                          multiple_scattering=True, nodes=64)
    for th in (0.0, 30.0, 60.0, 75.0):
        wi = np.array([np.sin(np.radians(th)), 0.0, np.cos(np.radians(th))])
        E = float(b.albedo(wi, 550.0))
        assert 0.99 < E < 1.001, (th, E)
    parts = b.eval_parts(np.array([0.3, 0.0, 0.954]), np.array([-0.5, 0.2, 0.843]), 550.0)
    assert parts["multiple"] > 0 and parts["coherent"] > 0 and parts["diffraction"] > 0


def test_two_scale_multiple_scattering_sampling_passes_chi2():
    from waveoptics import brdf, surfaces

    nano = brdf.Nano(model=surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6))
    b = brdf.TwoScaleBRDF(material="gold", micro=brdf.Micro(alpha=0.7, ndf="ggx"), nano=nano, multiple_scattering=True,
                          nodes=64)
    wi = np.array([np.sin(0.6), 0.0, np.cos(0.6)])
    sample = reflected_samples(b, wi, 550.0)
    res = brdf.chi2_test(sample, lambda d: b.pdf(wi, d, 550.0), sample_count=100_000, seed=3)
    assert res.passed, res.message


def test_cli_two_scale_multiple_scattering():
    import json

    from cli_helpers import run_cli

    argv = ["brdf", "--model", "twoscale", "--material", "Au", "--micro-alpha", "0.8", "--nano",
            "abc:sigma=10nm,B=2um,C=2.6", "--incident", "40", "--albedo", "--wavelengths", "550", "--json"]
    rc0, out0, err0, _ = run_cli(argv)
    rc1, out1, err1, _ = run_cli(argv + ["--multiple-scattering"])
    assert rc0 == 0 and rc1 == 0, err0 + err1
    d0, d1 = json.loads(out0), json.loads(out1)
    assert d1["parameters"]["multiple_scattering"] is True
    a0, a1 = (d["albedo"][0]["albedo"] for d in (d0, d1))
    assert a1 > a0 * 1.05
