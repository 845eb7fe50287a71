"""Self-tests of tests/twoscale_reference.py, the independent two-scale reference (written from the papers).

Each check holds the reference against something that is not itself: a closed form (PSD normalization, Fresnel
equations, Davies' small-roughness limit, Walter's microfacet BRDF), a property (reciprocity, Smith's visible-area
identity, 1/√N), or a second algorithm (quadrature against Monte Carlo, one importance technique against another).
"""
import numpy as np
import pytest
from scipy import integrate

import twoscale_reference as R

LAM = 550.0
METAL = (1 + 6j) ** 2
GLASS = 1.5 ** 2
#: tolerances, in one place
TOL = {
    "quad": 1e-6,          # deterministic quadratures of smooth integrands
    "fresnel": 1e-12,      # Q against Fresnel at the specular direction
    "k_se": 4.0,           # Monte Carlo: |mean − expected| ≤ k_se · se + bias allowance
    "narrow_bias": 0.01,   # facet integral with a 0.001-wide nano lobe vs the microfacet BRDF (smoothing of D)
    "alpha0_bias": 0.005,  # facet integral at α = 1e-3 vs f_nano
    "davies": 0.01,        # Rayleigh-Rice TIS vs R (4π σ cos θ / λ)² for a lobe 0.016 wide
}


def _hemisphere_quadrature(n_phi=256):
    """Nodes (K, 3) and solid-angle weights (K,) over the upper hemisphere, Gauss-Legendre panels in θ (fine near
    the pole for narrow NDFs), trapezoid in φ."""
    breaks = np.array([0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 1.2, np.pi / 2])
    x, w = np.polynomial.legendre.leggauss(24)
    a, b = breaks[:-1, None], breaks[1:, None]
    th = (0.5 * (b - a) * x + 0.5 * (a + b)).ravel()
    wth = (0.5 * (b - a) * w).ravel() * np.sin(th)
    ph = 2 * np.pi * np.arange(n_phi) / n_phi
    T, P = np.meshgrid(th, ph, indexing="ij")
    m = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    return m, (wth[:, None] * np.full(n_phi, 2 * np.pi / n_phi)[None, :]).ravel()


# ---------------------------------------------------------------------------------------------------------------
# PSDs
# ---------------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("sigma,B,C", [(10.0, 2000.0, 2.6), (1.0, 500.0, 3.0), (5.0, 10000.0, 2.2), (2.0, 50.0, 6.0)])
def test_abc_psd_integrates_to_sigma_squared(sigma, B, C):
    S = R.abc_psd(sigma, B, C)
    # ∫ S d²f = ∫ 2π f S(f) df; substitute f = x / B to keep quad on an O(1) scale, tail split at x = 1
    g = lambda x: 2 * np.pi * (x / B) * S(x / B) / B  # noqa: E731
    tot = integrate.quad(g, 0, 1, epsabs=0, epsrel=1e-10)[0] + integrate.quad(g, 1, np.inf, epsabs=0,
                                                                               epsrel=1e-10, limit=400)[0]
    assert tot == pytest.approx(sigma ** 2, rel=TOL["quad"])


def test_abc_psd_refuses_C_at_most_2():
    with pytest.raises(ValueError, match="C must exceed 2"):
        R.abc_psd(1.0, 100.0, 2.0)


@pytest.mark.parametrize("sigma,T", [(10.0, 300.0), (1.0, 5000.0)])
def test_gaussian_psd_integrates_to_sigma_squared_and_is_the_transform_of_C(sigma, T):
    S = R.gaussian_psd(sigma, T)
    tot = integrate.quad(lambda f: 2 * np.pi * f * S(f), 0, 10 / T, epsabs=0, epsrel=1e-10)[0]
    assert tot == pytest.approx(sigma ** 2, rel=TOL["quad"])
    # the Hankel transform of C(r) = σ² exp(−r²/T²) at one frequency, S(f) = 2π ∫ C(r) J0(2π f r) r dr
    from scipy.special import j0
    f = 0.7 / T
    hank = integrate.quad(lambda r: 2 * np.pi * sigma ** 2 * np.exp(-(r / T) ** 2) * j0(2 * np.pi * f * r) * r,
                          0, 8 * T, epsabs=0, epsrel=1e-10, limit=200)[0]
    assert S(f) == pytest.approx(hank, rel=1e-8)


# ---------------------------------------------------------------------------------------------------------------
# microfacet pieces
# ---------------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("ndf", R.NDFS)
@pytest.mark.parametrize("alpha", [0.05, 0.3, 1.0])
def test_ndf_normalization_and_smith_visible_area(ndf, alpha):
    m, w = _hemisphere_quadrature()
    D = R.D(m, alpha, ndf)
    assert np.sum(w * D * m[:, 2]) == pytest.approx(1.0, abs=1e-5)
    # Heitz 2014 eq. 46: ∫ G1(v, m) max(0, v·m) D(m) dω_m = v·n (a check of Λ against D)
    for th in (0.0, 30.0, 60.0, 80.0):
        v = R.direction(th)
        lhs = np.sum(w * R.G1(v, m, alpha, ndf) * np.maximum(m @ v, 0) * D)
        assert lhs == pytest.approx(v[2], rel=2e-4), th


def test_lambda_closed_values():
    # GGX at α tanθ = √8: Λ = (−1 + 3)/2 = 1; Beckmann at a = 1/(α tanθ) = 1: (erf 1 − 1)/2 + e^{−1}/(2√π)
    from scipy.special import erf
    th = np.arctan(np.sqrt(8.0) / 0.5)
    assert R.Lambda(R.direction(np.rad2deg(th)), 0.5, "ggx") == pytest.approx(1.0, rel=1e-12)
    th = np.arctan(1.0 / 0.5)
    expect = 0.5 * (erf(1.0) - 1.0) + np.exp(-1.0) / (2 * np.sqrt(np.pi))
    assert R.Lambda(R.direction(np.rad2deg(th)), 0.5, "beckmann") == pytest.approx(expect, rel=1e-12)
    assert R.Lambda(R.direction(0.0), 0.5, "beckmann") == 0.0
    assert R.G2(R.direction(30.0), R.direction(40.0, 180.0), R.direction(-5.0), 0.3) > 0
    assert R.G2(R.direction(30.0), R.direction(40.0, 180.0), R.direction(85.0, 180.0), 0.3) == 0.0  # i·m < 0


@pytest.mark.parametrize("ndf", R.NDFS)
def test_sampler_moments_match_quadrature_of_its_pdf(ndf):
    alpha = 0.4
    rng = np.random.default_rng(7)
    s = R.sample_ndf(alpha, 200_000, rng, ndf)
    m, w = _hemisphere_quadrature()
    p = R.pdf_ndf(m, alpha, ndf)
    assert np.sum(w * p) == pytest.approx(1.0, abs=1e-5)
    for g in (lambda x: x[:, 2] ** 2, lambda x: x[:, 0] ** 2, lambda x: (x[:, 0] > 0.2) * 1.0,
              lambda x: x[:, 0] * x[:, 1]):
        mc, se = g(s).mean(), g(s).std() / np.sqrt(len(s))
        assert abs(mc - np.sum(w * p * g(m))) < TOL["k_se"] * se + 1e-6


def test_facet_frame_is_the_minimal_rotation():
    rng = np.random.default_rng(3)
    m = R._unit(rng.normal(size=(50, 3)))
    m[:, 2] = np.abs(m[:, 2])
    a, b = R._unit(rng.normal(size=(50, 3))), R._unit(rng.normal(size=(50, 3)))
    np.testing.assert_allclose(R.to_facet_frame(m, m), np.tile([0, 0, 1.0], (50, 1)), atol=1e-14)
    np.testing.assert_allclose(np.sum(R.to_facet_frame(a, m) * R.to_facet_frame(b, m), -1), np.sum(a * b, -1),
                               atol=1e-14)
    axis = np.cross(m, [0, 0, 1.0])                                  # the rotation axis stays put
    np.testing.assert_allclose(R.to_facet_frame(axis, m), axis, atol=1e-14)
    # a proper rotation (determinant +1), not a reflection
    E = np.stack([R.to_facet_frame(np.broadcast_to(e, m.shape), m) for e in np.eye(3)], axis=-1)
    np.testing.assert_allclose(np.linalg.det(E), 1.0, atol=1e-12)


# ---------------------------------------------------------------------------------------------------------------
# Fresnel and the Rayleigh-Rice polarization factors
# ---------------------------------------------------------------------------------------------------------------

def _fresnel_born_wolf(theta, n):
    """Born & Wolf §1.5.2 in terms of the refraction angle (a different algebra from the module's)."""
    st = np.sin(theta) / n
    ct = np.sqrt(1 - st * st + 0j)
    ci = np.cos(theta)
    rs = (ci - n * ct) / (ci + n * ct)
    rp = (n * ci - ct) / (n * ci + ct)
    return abs(rs) ** 2, abs(rp) ** 2


@pytest.mark.parametrize("n", [1 + 6j, 1.5, 0.96 + 6.69j])
@pytest.mark.parametrize("theta", [0.0, 20.0, 45.0, 70.0, 85.0])
def test_Q_is_fresnel_at_the_specular_direction(n, theta):
    wi = R.direction(theta, 37.0)
    wo = R.direction(theta, 217.0)                       # mirror of wi
    q = R.rayleigh_rice_Q(wi, wo, n * n)
    Rs, Rp = _fresnel_born_wolf(np.deg2rad(theta), n)
    assert q["ss"] == pytest.approx(Rs, rel=TOL["fresnel"], abs=1e-15)
    assert q["pp"] == pytest.approx(Rp, rel=TOL["fresnel"], abs=1e-15)
    assert q["sp"] < 1e-25 and q["ps"] < 1e-25
    assert R.fresnel_R(np.cos(np.deg2rad(theta)), n * n, "s") == pytest.approx(Rs, rel=1e-12)
    assert R.rayleigh_rice_Q_pol(wi, wo, n * n) == pytest.approx(0.5 * (Rs + Rp), rel=1e-12)


def test_Q_pp_vanishes_at_brewster_for_glass():
    tb = np.rad2deg(np.arctan(1.5))
    q = R.rayleigh_rice_Q(R.direction(tb), R.direction(tb, 180.0), GLASS)
    assert q["pp"] < 1e-30 and q["ss"] > 0.1


@pytest.mark.parametrize("eps", [METAL, GLASS])
def test_rayleigh_rice_is_reciprocal(eps):
    rng = np.random.default_rng(11)
    wi = R.direction(rng.uniform(0, 85, 200), rng.uniform(0, 360, 200))
    wo = R.direction(rng.uniform(0, 85, 200), rng.uniform(0, 360, 200))
    psd = R.abc_psd(10.0, 2000.0, 2.6)
    f = R.rayleigh_rice_brdf(wi, wo, LAM, psd, eps)
    np.testing.assert_allclose(R.rayleigh_rice_brdf(wo, wi, LAM, psd, eps), f, rtol=1e-12)
    q, qt = R.rayleigh_rice_Q(wi, wo, eps), R.rayleigh_rice_Q(wo, wi, eps)
    np.testing.assert_allclose(qt["ps"], q["sp"], rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(qt["pp"], q["pp"], rtol=1e-12, atol=1e-300)
    # rotating both directions about the normal changes nothing (isotropic PSD)
    rot = np.array([[np.cos(1.0), -np.sin(1.0), 0], [np.sin(1.0), np.cos(1.0), 0], [0, 0, 1]])
    np.testing.assert_allclose(R.rayleigh_rice_brdf(wi @ rot.T, wo @ rot.T, LAM, psd, eps), f, rtol=1e-10)


@pytest.mark.parametrize("eps", [METAL, GLASS])
@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0])
def test_rayleigh_rice_tis_and_coherent_loss_meet_davies(eps, theta):
    """A Gaussian PSD 20 λ long scatters into a 0.016-wide lobe: TIS_s,p → R_s,p (4π σ cos θ / λ)², which is also
    the reflectance the coherent beam loses, R − R exp(−g), for σ = 1 nm (Davies 1954; Bennett & Porteus 1961)."""
    psd = R.gaussian_psd(1.0, 20 * LAM)
    c = np.cos(np.deg2rad(theta))
    g = (4 * np.pi * 1.0 * c / LAM) ** 2
    # near Brewster's angle (glass, 60°) R_p ≈ 0.002 varies across the lobe by more than itself: p is left out there
    pols = ("s", "unpolarized") if (eps == GLASS and theta > 50) else ("s", "p", "unpolarized")
    for pol in pols:
        tis, err = R.rayleigh_rice_tis(theta, LAM, psd, eps, pol)
        Rf = R.fresnel_R(c, eps, pol)
        assert err < 1e-3 * tis
        assert tis == pytest.approx(Rf * g, rel=TOL["davies"])
        assert Rf - R.coherent_reflectance(theta, LAM, 1.0, eps, pol) == pytest.approx(tis, rel=TOL["davies"])


# ---------------------------------------------------------------------------------------------------------------
# the facet-frame integral
# ---------------------------------------------------------------------------------------------------------------

WI = R.direction([30.0, 30.0, 60.0, 0.0])
WO = R.direction([45.0, 60.0, 70.0, 20.0], [180.0, 150.0, 180.0, 90.0])


@pytest.mark.parametrize("ndf", R.NDFS)
@pytest.mark.parametrize("alpha", [0.15, 0.4])
def test_narrow_nano_lobe_gives_the_microfacet_brdf(ndf, alpha):
    """A nano lobe of albedo F and width 0.001 is a mirror: the facet integral → F G2 D(h) / (4 cos cos)."""
    fn = R.gaussian_nano(0.8, 0.001)
    mean, se = R.facet_integral(fn, WI, WO, LAM, alpha, ndf, nano_width=0.001, n_samples=20_000, seed=5)
    ref = R.microfacet_brdf(WI, WO, alpha, 0.8, ndf)
    assert np.all(se < 0.02 * ref)
    assert np.all(np.abs(mean - ref) < TOL["k_se"] * se + TOL["narrow_bias"] * ref), (mean / ref, se / ref)


@pytest.mark.parametrize("ndf", R.NDFS)
def test_smooth_micro_surface_gives_the_nano_lobe(ndf):
    """α → 0: every facet is the macro surface, the facet integral → f_nano(i, o) (Rayleigh-Rice lobe of Al-like
    ABC roughness, n = 1 + 6i)."""
    fn = R.rayleigh_rice_nano(R.abc_psd(10.0, 2000.0, 2.6), METAL)
    mean, se = R.facet_integral(fn, WI, WO, LAM, 1e-3, ndf, nano_width=0.3, n_samples=8_000, seed=6)
    ref = fn(WI, WO, LAM)
    assert np.all(np.abs(mean - ref) < TOL["k_se"] * se + TOL["alpha0_bias"] * ref), (mean / ref, se / ref)


@pytest.mark.parametrize("ndf", R.NDFS)
def test_facet_integral_matches_deterministic_quadrature(ndf):
    """Between the limits (α = 0.3, a Rayleigh-Rice lobe about 0.27 wide): the Monte Carlo mixture against a
    Gauss-Legendre × trapezoid quadrature of the same integrand over the hemisphere of micro-normals."""
    fn = R.rayleigh_rice_nano(R.abc_psd(10.0, 2000.0, 2.6), METAL)
    m, w = _hemisphere_quadrature(n_phi=192)
    mm = np.broadcast_to(m, (len(WI),) + m.shape)
    quad = np.sum(w * R.facet_integrand(fn, WI, WO, mm, LAM, 0.3, ndf), axis=1)
    mean, se = R.facet_integral(fn, WI, WO, LAM, 0.3, ndf, nano_width=0.27, n_samples=20_000, seed=15)
    assert np.all(np.abs(mean - quad) < TOL["k_se"] * se + 1e-3 * quad), ((mean - quad) / se)
    assert np.all(se < 0.02 * quad)


def test_half_vector_proposal_density_integrates_to_its_mass_on_the_disc():
    """The technique-(b) density about h = z integrates over the hemisphere to P(r < 1) = 1 − (1 + 1/s²)^(−1/2)
    (the draws beyond the unit disc are the samples that count zero)."""
    m, w = _hemisphere_quadrature()
    for s in (0.05, 0.3):
        p = R._pdf_about(m[None], np.array([[0.0, 0.0, 1.0]]), s)[0]
        assert np.sum(w * p) == pytest.approx(1 - (1 + 1 / s ** 2) ** -0.5, rel=1e-4)


def test_facet_integral_is_reciprocal():
    fn = R.rayleigh_rice_nano(R.abc_psd(10.0, 2000.0, 2.6), METAL)
    a, sa = R.facet_integral(fn, WI, WO, LAM, 0.2, "beckmann", nano_width=0.3, n_samples=20_000, seed=8)
    b, sb = R.facet_integral(fn, WO, WI, LAM, 0.2, "beckmann", nano_width=0.3, n_samples=20_000, seed=9)
    assert np.all(np.abs(a - b) < TOL["k_se"] * np.hypot(sa, sb)), ((a - b) / np.hypot(sa, sb))


def test_the_two_importance_techniques_agree():
    """The NDF sampler alone and the mixture are both unbiased: equal within their errors (broad nano lobe,
    α = 0.3, where either technique alone converges)."""
    fn = R.gaussian_nano(0.7, 0.15)
    a, sa = R.facet_integral(fn, WI, WO, LAM, 0.3, "ggx", nano_width=None, n_samples=20_000, seed=10)
    b, sb = R.facet_integral(fn, WI, WO, LAM, 0.3, "ggx", nano_width=0.15, n_samples=20_000, seed=11)
    c, sc = R.facet_integral(fn, WI, WO, LAM, 0.3, "ggx", nano_width=0.15, n_samples=20_000, seed=12,
                             ndf_fraction=0.1)
    assert np.all(np.abs(a - b) < TOL["k_se"] * np.hypot(sa, sb))
    assert np.all(np.abs(c - b) < TOL["k_se"] * np.hypot(sc, sb))


def test_standard_error_shrinks_as_one_over_root_n():
    fn = R.rayleigh_rice_nano(R.abc_psd(10.0, 2000.0, 2.6), METAL)
    _, s1 = R.facet_integral(fn, WI, WO, LAM, 0.3, "beckmann", nano_width=0.3, n_samples=4_000, seed=13)
    _, s4 = R.facet_integral(fn, WI, WO, LAM, 0.3, "beckmann", nano_width=0.3, n_samples=16_000, seed=14)
    ratio = s1 / s4
    assert np.all((ratio > 1.6) & (ratio < 2.5)), ratio


def test_facet_integral_is_seeded_and_broadcasts():
    fn = R.gaussian_nano(0.7, 0.1)
    a = R.facet_integral(fn, WI, WO, LAM, 0.3, nano_width=0.1, n_samples=2_000, seed=1)
    b = R.facet_integral(fn, WI, WO, LAM, 0.3, nano_width=0.1, n_samples=2_000, seed=1)
    np.testing.assert_array_equal(a[0], b[0])
    one = R.facet_integral(fn, WI[1], WO[1], LAM, 0.3, nano_width=0.1, n_samples=2_000, seed=1)
    assert one[0].shape == (1,) and np.isfinite(one[0]).all()


# ---------------------------------------------------------------------------------------------------------------
# albedo and the coherent part
# ---------------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0.0, 40.0])
def test_albedo_mc_and_quadrature_agree(theta):
    wi = R.direction(theta)
    fn = R.gaussian_nano(0.8, 0.05)
    brdf = lambda a, b: fn(a, b, LAM)  # noqa: E731
    q, qerr = R.albedo_quadrature(brdf, wi)
    assert q == pytest.approx(0.8, rel=1e-6)                      # the Gaussian lies well inside the disc
    m, se = R.albedo_mc(brdf, wi, n_samples=40_000, seed=2, width=0.05)
    assert abs(m[0] - q) < TOL["k_se"] * se[0] and se[0] < 0.01
    rr = lambda a, b: R.rayleigh_rice_brdf(a, b, LAM, R.abc_psd(10.0, 2000.0, 2.6), METAL)  # noqa: E731
    q2, _ = R.albedo_quadrature(rr, wi)
    m2, se2 = R.albedo_mc(rr, wi, n_samples=40_000, seed=3, width=0.3)
    assert abs(m2[0] - q2) < TOL["k_se"] * se2[0]


def test_coherent_part_carries_A_F_on_a_smooth_micro_surface():
    """α = 0.05: the coherent part's albedo is A(cos θi) F(cos θi) times the microfacet albedo with F = 1, close
    to 1 for a smooth surface."""
    A = lambda c: np.exp(-(4 * np.pi * 10.0 * c / LAM) ** 2)  # noqa: E731
    F = lambda c: R.fresnel_R(c, METAL)  # noqa: E731
    wi = R.direction(30.0)
    fc, _ = R.albedo_quadrature(lambda a, b: R.coherent_part(a, b, 0.05, A, F), wi)
    one, _ = R.albedo_quadrature(lambda a, b: R.microfacet_brdf(a, b, 0.05), wi)
    c = np.cos(np.deg2rad(30.0))
    assert one == pytest.approx(1.0, abs=0.01)
    assert fc == pytest.approx(A(c) * F(c) * one, rel=0.01)
