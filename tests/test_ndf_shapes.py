"""The EPD (Holzschuch & Pacanowski 2017) and SGD (Bagher, Soler & Holzschuch 2012) NDFs (issue 16): their D
against the papers' formulas written here, normalization, the Smith identity, the Beckmann limit of the EPD,
the incomplete gamma function behind the SGD, sampling (χ²), reciprocity and the command line."""
import functools
import math

import numpy as np
import pytest
from scipy import integrate

from cli_helpers import run_cli
from waveoptics import brdf
from waveoptics.brdf import Micro, MicrofacetBRDF, chi2_test, reflected_samples
from waveoptics.brdf.ndf_shaped import gamma_upper


def _dir(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t) * np.ones_like(p)], axis=-1)


@functools.cache
def _gamma_upper_quad(a, y):
    """Γ(a, y) by quadrature of its integral (made once per (a, y): the slope laws below call it per point)."""
    return integrate.quad(lambda t: t ** (a - 1) * math.exp(-t), y, np.inf, limit=200)[0]


def epd_paper(theta, alpha, p):
    """EPD: slope law exp(−(tan²θ/α²)^p) normalized over the slope plane; D = P22 / cos⁴θ."""
    norm = p / (math.pi * alpha ** 2 * math.gamma(1 / p))
    return norm * np.exp(-(np.tan(theta) ** 2 / alpha ** 2) ** p) / np.cos(theta) ** 4


def sgd_paper(theta, alpha, p):
    """SGD: P22(x) = α^{p−1} e^{−(α²+x)/α} / (Γ(1−p, α) (α²+x)^p), x = tan²θ; D = P22 / (π cos⁴θ)."""
    x = np.tan(theta) ** 2
    K = alpha ** (p - 1) / _gamma_upper_quad(1 - p, alpha)
    return K * np.exp(-(alpha ** 2 + x) / alpha) / (alpha ** 2 + x) ** p / (math.pi * np.cos(theta) ** 4)


#: three shapes of EPD, two of SGD (its evaluation is the slow one: the incomplete gamma), spanning α and p
CASES = [("epd", 0.2, 0.5), ("epd", 0.3, 1.0), ("epd", 0.1, 2.5), ("sgd", 0.05, 0.4), ("sgd", 0.3, 1.8)]
PAPER = {"epd": epd_paper, "sgd": sgd_paper}


@pytest.mark.parametrize("a", [0.7, 0.3, 1e-3, 0.0, -0.4, -1.0, -1.6, -3.2])
def test_gamma_upper_against_quadrature(a):
    for y in (0.01, 0.3, 2.0, 9.0):
        assert gamma_upper(a, y) == pytest.approx(_gamma_upper_quad(a, y), rel=1e-9)


@pytest.mark.parametrize("ndf,alpha,p", CASES)
def test_D_is_the_papers_formula_and_normalized(ndf, alpha, p):
    t = np.radians(np.linspace(0, 88, 45))
    np.testing.assert_allclose(brdf.D(_dir(np.degrees(t)), alpha, ndf=ndf, ndf_shape=p),
                               PAPER[ndf](t, alpha, p), rtol=1e-10, atol=1e-300)
    total = integrate.quad(lambda th: PAPER[ndf](th, alpha, p) * math.cos(th) * math.sin(th) * 2 * math.pi,
                           0, math.pi / 2, limit=400, points=[0.01, 0.05, 0.2])[0]
    assert total == pytest.approx(1.0, abs=1e-8)


def test_epd_with_p_one_is_beckmann():
    w = _dir(np.linspace(0, 89.5, 60), 20.0)
    for alpha in (0.01, 0.3, 1.0):
        np.testing.assert_allclose(brdf.D(w, alpha, ndf="epd", ndf_shape=1.0), brdf.D(w, alpha, ndf="beckmann"),
                                   rtol=1e-12, atol=1e-300)
        np.testing.assert_allclose(brdf.G1(w, np.array([0, 0, 1.0]), alpha, ndf="epd", ndf_shape=1.0),
                                   brdf.G1(w, np.array([0, 0, 1.0]), alpha, ndf="beckmann"), rtol=0, atol=1e-8)


@pytest.mark.parametrize("ndf,alpha,p", CASES)
def test_smith_identity_projected_area(ndf, alpha, p):
    """∫ G1(ω_o, m) ⟨ω_o·m⟩ D(m) dω_m = cos θ_o (Heitz 2014, eq. 23): Λ is consistent with D."""
    for theta_o in (40.0, 75.0):   # (0° is the normalization, tested above)
        wo = _dir(theta_o)
        lam = float(brdf.Lambda(wo, alpha, ndf=ndf, ndf_shape=p))

        def azimuthal(th):
            """∫₀^{2π} ⟨m·ω_o⟩ dφ in closed form: m·ω_o = a cos φ + b with a = sinθ sinθ_o, b = cosθ cosθ_o,
            positive for |φ| < φ₀ = arccos(−b/a) (all φ when b ≥ a)."""
            a, b = math.sin(th) * wo[0], math.cos(th) * wo[2]
            if b >= a:
                return 2 * math.pi * b
            phi0 = math.acos(-b / a)
            return 2 * (b * phi0 + a * math.sin(phi0))
        kink = math.pi / 2 - math.radians(theta_o)   # where the facets start to turn away from ω_o
        val = integrate.quad(lambda th: azimuthal(th) * PAPER[ndf](th, alpha, p) * math.sin(th), 0, math.pi / 2,
                             epsabs=1e-12, epsrel=1e-10, limit=400, points=[0.01, 0.05, 0.2, kink])[0]
        assert val / (1 + lam) == pytest.approx(math.cos(math.radians(theta_o)), rel=2e-5), theta_o


@pytest.mark.parametrize("ndf,alpha,p", CASES)
def test_sampling_passes_chi2(ndf, alpha, p):
    b = MicrofacetBRDF("PMMA", Micro(alpha=max(alpha, 0.05), ndf=ndf), kd=0.3, ndf_shape=p)
    for theta in (30.0, 75.0):
        wi = _dir(theta)

        sample = reflected_samples(b, wi, 550.0)
        r = chi2_test(sample, lambda d: b.pdf(wi, d, 550.0), sample_count=100_000, res=41, ires=6,
                      test_count=2 * len(CASES))
        assert r.passed, (theta, r.message)


@pytest.mark.parametrize("ndf,alpha,p", CASES)
def test_sampled_slopes_follow_the_slope_law(ndf, alpha, p):
    """The normal sampler draws tan²θ with the CDF of the slope law (Kolmogorov–Smirnov against the CDF
    integrated here from the papers' formulas)."""
    from scipy import stats

    from waveoptics.brdf.sampling import sample_normal

    u = np.random.default_rng(3).random((20_000, 2))
    m = sample_normal(np.array([0, 0, 1.0]), u, ndf=ndf, ax=alpha, ay=alpha, c=p)
    theta = np.arccos(m[:, 2])

    def cdf(t):
        return integrate.quad(lambda th: PAPER[ndf](th, alpha, p) * math.cos(th) * math.sin(th) * 2 * math.pi,
                              0, t, limit=200)[0]
    grid = np.linspace(0, theta.max() * 1.01, 400)
    table = np.array([cdf(t) for t in grid])
    ks = stats.kstest(theta, lambda t: np.interp(t, grid, table))
    assert ks.pvalue > 1e-3, ks


@pytest.mark.parametrize("ndf,alpha,p", CASES[:4:3])
def test_reciprocity(ndf, alpha, p):
    rng = np.random.default_rng(8)
    wi = rng.normal(size=(200, 3))
    wo = rng.normal(size=(200, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    b = MicrofacetBRDF("Au", Micro(alpha=alpha, ndf=ndf), ndf_shape=p)
    np.testing.assert_allclose(b.eval(wi, wo, 550.0), b.eval(wo, wi, 550.0), rtol=1e-12, atol=1e-300)


def test_shape_parameter_is_checked():
    m = _dir(10.0)
    with pytest.raises(ValueError, match="no shape parameter"):
        brdf.D(m, 0.2, ndf="ggx", ndf_shape=1.5)
    with pytest.raises(ValueError, match=r"sgd; its p must be in \(0, 5\]"):
        brdf.D(m, 0.2, ndf="sgd", ndf_shape=7.0)
    with pytest.raises(ValueError, match="epd; its p"):
        brdf.D(m, 0.2, ndf="epd", ndf_shape=0.0)


def test_cli(tmp_path):
    base = ["brdf", "--model", "microfacet", "--material", "Au", "--alpha", "0.2", "--incident", "30",
            "--outgoing", "30,180", "--json"]
    rc, out, err, _ = run_cli([*base, "--ndf", "sgd", "--ndf-shape", "1.5"])
    assert rc == 0, err
    import json

    d = json.loads(out)
    assert d["parameters"]["ndf_shape"] == 1.5
    f = MicrofacetBRDF("Au", Micro(alpha=0.2, ndf="sgd"), ndf_shape=1.5, kd=0.0).eval(_dir(30.0), _dir(30.0, 180.0),
                                                                                    550.0)
    assert d["values"][0]["brdf"] == pytest.approx(float(f), rel=1e-9)
    rc, out, err, _ = run_cli([*base, "--ndf", "epd", "--backend", "opencl"])
    assert rc == 2 and "no OpenCL kernel" in err
    rc, out, err, _ = run_cli([*base, "--ndf", "ggx", "--ndf-shape", "2"])
    assert rc == 2 and "no shape parameter" in err
    rc, out, err, _ = run_cli([*base, "--ndf", "abc", "--abc-c", "3"])
    assert rc == 0 and "--abc-c is deprecated" in err


def test_two_scale_route_and_scene_files_carry_the_shape(tmp_path):
    """The shape parameter reaches the micro NDF of the two-scale model from the request and from a scene file,
    and a scene refuses it for an NDF without one."""
    from waveoptics.planning import scene
    from waveoptics.request import SimulationRequest

    req = SimulationRequest("Au", nano="abc:sigma=8nm,B=2um,C=2.6", micro_alpha=0.1, ndf="sgd", ndf_shape=1.4)
    assert req.micro().kw()["ndf_shape"] == 1.4
    with pytest.raises(ValueError, match="ndf_shape"):
        SimulationRequest("Au", ndf="ggx", ndf_shape=1.4)
    path = tmp_path / "s.toml"
    path.write_text('[[materials]]\nname = "m"\nmaterial = "Au"\nndf = "epd"\nndf_shape = 0.6\n'
                    '[[lights]]\nname = "sun"\nspd = "D65"\n')
    assert scene.load(path).materials[0].ndf_shape == 0.6
    path.write_text('[[materials]]\nname = "m"\nmaterial = "Au"\nndf = "ggx"\nndf_shape = 0.6\n'
                    '[[lights]]\nname = "sun"\nspd = "D65"\n')
    with pytest.raises(ValueError, match="ndf_shape applies to NDFs with a shape parameter"):
        scene.load(path)


# -- anisotropy (Heitz 2014 §5.3 stretching), against slope laws written here ----------------------------------

ANISO = [("epd", 0.12, 0.35, 0.6), ("epd", 0.3, 0.1, 2.0), ("sgd", 0.05, 0.2, 0.5), ("sgd", 0.2, 0.08, 1.4)]


def _aniso_slope_law(ndf, ax, ay, p, x, y):
    """P22(x̃, ỹ) of the stretched law, from the papers' isotropic laws: EPD N exp(−((x/α_x)² + (y/α_y)²)^p) /
    (α_x α_y) with N the α = 1 constant; SGD of ᾱ = √(α_x α_y) with slopes stretched by √(α/ᾱ)."""
    if ndf == "epd":
        r2 = (x / ax) ** 2 + (y / ay) ** 2
        return p / (math.pi * math.gamma(1 / p)) * np.exp(-r2 ** p) / (ax * ay)
    a = math.sqrt(ax * ay)
    kx, ky = math.sqrt(ax / a), math.sqrt(ay / a)
    t2 = (x / kx) ** 2 + (y / ky) ** 2
    K = a ** (p - 1) / _gamma_upper_quad(1 - p, a)
    return K * np.exp(-(a * a + t2) / a) / (a * a + t2) ** p / math.pi / (kx * ky)


@pytest.mark.parametrize("ndf,ax,ay,p", ANISO)
def test_anisotropic_D_is_the_stretched_slope_law_and_normalized(ndf, ax, ay, p):
    rng = np.random.default_rng(11)
    x, y = rng.normal(scale=3 * max(ax, ay) ** (1 if ndf == "epd" else 0.5), size=(2, 400))
    m = np.stack([-x, -y, np.ones_like(x)], axis=-1)
    m /= np.linalg.norm(m, axis=-1, keepdims=True)
    np.testing.assert_allclose(brdf.D(m, ax, ay, ndf=ndf, ndf_shape=p) * m[:, 2] ** 4,
                               _aniso_slope_law(ndf, ax, ay, p, x, y), rtol=1e-10, atol=1e-300)
    # ∫ D cos θ dω = ∫ P22 d²slope = 1 (polar slope coordinates, the law's own scale along each axis)
    total = integrate.dblquad(lambda r, phi: r * _aniso_slope_law(ndf, ax, ay, p, r * math.cos(phi),
                                                                  r * math.sin(phi)),
                              0, 2 * math.pi, 0, np.inf, epsabs=1e-11)[0]
    assert total == pytest.approx(1.0, abs=1e-7)


def test_anisotropic_epd_with_p_one_is_anisotropic_beckmann():
    w = _dir(np.linspace(0, 89.5, 60)[:, None], np.linspace(0, 180, 7)[None, :]).reshape(-1, 3)
    for ax, ay in ((0.05, 0.4), (0.6, 0.2)):
        np.testing.assert_allclose(brdf.D(w, ax, ay, ndf="epd", ndf_shape=1.0), brdf.D(w, ax, ay, ndf="beckmann"),
                                   rtol=1e-11, atol=1e-300)
        np.testing.assert_allclose(brdf.Lambda(w, ax, ay, ndf="epd", ndf_shape=1.0),
                                   brdf.Lambda(w, ax, ay, ndf="beckmann"), rtol=1e-7, atol=1e-8)


@pytest.mark.parametrize("ndf,ax,ay,p", ANISO)
def test_anisotropic_smith_identity(ndf, ax, ay, p):
    """∫ ⟨ω·m⟩ D dω_m / (1 + Λ(ω)) = cos θ at azimuths between the axes: Λ of the stretch matches D."""
    for theta, phi in ((50.0, 30.0), (78.0, 115.0)):
        w = _dir(theta, phi)
        lam = float(brdf.Lambda(w, ax, ay, ndf=ndf, ndf_shape=p))

        def integrand(r, ang):   # over slopes: ⟨ω·m⟩ D dω_m = max(0, −x w_x − y w_y + w_z) P22 d²slope
            x, y = r * math.cos(ang), r * math.sin(ang)
            return r * max(-x * w[0] - y * w[1] + w[2], 0.0) * _aniso_slope_law(ndf, ax, ay, p, x, y)
        val = integrate.dblquad(integrand, 0, 2 * math.pi, 0, np.inf, epsabs=1e-10)[0]
        assert val / (1 + lam) == pytest.approx(w[2], rel=2e-5), (theta, phi)


@pytest.mark.parametrize("ndf,ax,ay,p", ANISO)
def test_anisotropic_sampling_passes_chi2(ndf, ax, ay, p):
    b = MicrofacetBRDF("Au", Micro(alpha=max(ax, 0.05), alpha_y=max(ay, 0.05), ndf=ndf), ndf_shape=p)
    for theta, phi in ((30.0, 0.0), (60.0, 70.0)):
        wi = _dir(theta, phi)

        sample = reflected_samples(b, wi, 550.0)
        r = chi2_test(sample, lambda d: b.pdf(wi, d, 550.0), sample_count=100_000, res=41, ires=6,
                      test_count=2 * len(ANISO))
        assert r.passed, (theta, phi, r.message)


def test_anisotropic_white_furnace_and_reciprocity():
    rng = np.random.default_rng(5)
    wi, wo = rng.normal(size=(2, 200, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for ndf, p in (("epd", 0.7), ("sgd", 1.2)):
        b = MicrofacetBRDF("Au", Micro(alpha=0.1, alpha_y=0.3, ndf=ndf), ndf_shape=p)
        np.testing.assert_allclose(b.eval(wi, wo, 550.0), b.eval(wo, wi, 550.0), rtol=1e-12, atol=1e-300)
        one = MicrofacetBRDF("Au", Micro(alpha=0.1, alpha_y=0.3, ndf=ndf), ndf_shape=p, fresnel="one")
        a = float(np.ravel(one.albedo(_dir(20.0, 40.0), 550.0))[0])
        assert 0.97 < a <= 1.0 + 1e-3, (ndf, a)   # single scattering at α ≤ 0.3 loses a few % at most
