"""The propagating band and the relevant roughness (docs/physics.md §9; Krywonos, Harvey & Choi 2011): the radial
quadrature of the library against a brute-force 2-D sum written here, the closed form of a Gaussian PSD at normal
incidence, the limits, and a generated height field against its own statistics."""
from __future__ import annotations

import functools
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


# --- the band-limited series and the energy of the two-scale model (issue 13) ----------------------------------

from waveoptics import materials  # noqa: E402
from waveoptics.brdf import twoscale  # noqa: E402
from waveoptics.scatter import band, perturbation  # noqa: E402
from waveoptics.scatter.grid import DirectionGrid, integrate  # noqa: E402
from waveoptics.units import direction_from_angles  # noqa: E402

HEAVY = surfaces.PSDModel("abc", sigma=40e-9, B=3.7e-6, C=2.2)


def test_relevant_variances_on_one_grid_match_the_adaptive_quadrature():
    s = np.array([0.0, 0.3, 0.7, 0.95])
    for m in (HEAVY, surfaces.PSDModel("exponential", sigma=20e-9, T=0.5e-6)):
        ref = np.array([band.relevant_variance(m, 450.0, x) for x in s])
        np.testing.assert_allclose(band.relevant_variances(m, 450.0, s), ref, rtol=5e-4)


def test_band_tables_match_a_2d_fft_of_the_band_limited_surface():
    """H_2^b (the second-order term of the surface band-limited to |f| ≤ 1/λ) and its share B_2 inside the
    off-centre band of θ_i = 30°, against the same surface built on a 2-D frequency grid: c_b = IFFT(S·1[|f| ≤ 1/λ]),
    H_2 = FFT(c_b²) (a different code path: Cartesian FFTs instead of Hankel quadrature)."""
    lam = 550e-9
    bs = band.band_series(HEAVY, 550.0)
    N, L = 1024, 1024 * lam / 6
    f = np.fft.fftfreq(N, L / N)
    FX, FY = np.meshgrid(f, f)
    F = np.hypot(FX, FY)
    df = f[1] - f[0]
    Sb = np.where(F <= 1 / lam, HEAVY.S(F), 0.0)
    C = np.real(np.fft.ifft2(Sb)) * N * N * df * df
    c = C / C[0, 0]
    H2 = np.real(np.fft.fft2(c * c)) / (N * N * df * df)
    for fr in (0.1, 0.5, 1.0, 1.5):
        i = int(round(fr / lam / df))
        got = np.interp(2 * np.pi * f[i], bs.q, bs.H[0])
        assert got == pytest.approx(H2[0, i], rel=2e-2, abs=2e-3 * H2[0, 0])
    s = math.sin(math.radians(30.0))
    inside = np.hypot(FX + s / lam, FY) <= 1 / lam
    B2 = float(H2[inside].sum() * df * df / (H2.sum() * df * df))
    assert float(np.interp(s, bs.sin_nodes, bs.inband[0])) == pytest.approx(B2, abs=5e-3)


def _handover(cos_t):
    """w(θ) of the grazing hand-over, written here: 1 up to 70°, 0 from 80°, 1 − x²(3 − 2x) between."""
    x = np.clip((np.degrees(np.arccos(np.clip(cos_t, -1.0, 1.0))) - 70.0) / 10.0, 0.0, 1.0)
    return 1.0 - x * x * (3.0 - 2.0 * x)


def test_lobe_albedo_on_the_polar_grid_matches_a_fine_direction_grid():
    """The polar quadrature of the lobe's albedo (F = 1) against a 512² direction grid: the lobe the two-scale
    model carries, W f_K + (1 − W) f_RR with W = w(θ_i) w(θ_o) and f_RR the scalar first-order lobe
    (16π²/λ⁴) cosθ_i cosθ_o S(|ω_i + ω_o|_xy / λ) (Q = 1), both written here, within 2e-3 at the albedo nodes
    0, 40, 70, 76 and 78°; between the nodes, where the albedo is read linearly, within 2 % (measured at 76.5°:
    < 2e-3, at 78.5°: +1.5 %, where the hand-over bends the albedo)."""
    grid = DirectionGrid.hemisphere(512)
    wo = grid.directions()
    m = surfaces.PSDModel("abc", sigma=55e-9, B=1e-6, C=4)
    bs = band.band_series(m, 550.0)
    lam = 550e-9
    for th, rel in ((0.0, 2e-3), (40.0, 2e-3), (70.0, 2e-3), (76.0, 2e-3), (78.0, 2e-3), (76.5, 0.02), (78.5, 0.02)):
        wi = direction_from_angles(th, 0.0)
        s = wi + wo
        rr = 16 * np.pi ** 2 / lam ** 4 * wi[2] * wo[..., 2] * m.S(np.hypot(s[..., 0], s[..., 1]) / lam)
        W = _handover(wi[2]) * _handover(wo[..., 2])
        f = np.where(grid.inside, W * scatter.scattered_lobe(wi, wo, 550.0, m) + (1 - W) * rr, 0.0)
        assert float(bs.scattered_albedo(th)) == pytest.approx(integrate(f[None], grid)[0], rel=rel), th


@pytest.mark.parametrize("mat", ["Al", "1.5"])
def test_the_specular_loss_is_the_light_first_order_perturbation_theory_scatters(mat):
    """Small roughness (σ = 5-10 nm at 550 nm): the light the lobe scatters (on a metal the coherent loss 1 − A; on
    glass the lobe's own albedo, since a dielectric's coherent part is the Debye-Waller factor) agrees with the total integrated scatter of first-order Rayleigh-Rice theory with its full polarization factor
    Q (an independent theory, rigorous to that order): within 6 % on a metal up to θ_i = 60°, where exp(−g_rel)
    is off by up to a factor 5 for short correlation lengths; on glass within 25 % (the tangent-plane lobe weighs
    each direction by F(θ_h), Rayleigh-Rice by its Q: they part where the correlation length nears λ, 1.43× at
    B = 0.5 µm and 60°, which is left out)."""
    grid = DirectionGrid.hemisphere(384)
    wo = grid.directions()
    material = materials.get_material(mat)
    for m in (surfaces.PSDModel("abc", sigma=10e-9, B=3e-6, C=2.8), surfaces.PSDModel("abc", sigma=5e-9, B=0.5e-6, C=3),
              surfaces.PSDModel("gaussian", sigma=5e-9, T=1e-6)):
        nano = twoscale.Nano(model=m)
        for th in (0.0, 30.0, 60.0):
            wi = direction_from_angles(th, 0.0)
            rr = np.where(grid.inside, perturbation.rayleigh_rice_brdf(wi, wo, 550.0, m, material.eta(550.0) ** 2), 0)
            tis = integrate(rr[None], grid)[0] / float(material.F(wi[2], 550.0))
            if mat == "1.5":   # a dielectric's specular loss is the Debye-Waller factor's: compare the lobe's own
                # albedo (tests/test_dielectric_energy.py checks its coherent part)
                loss = float(nano.scattered_share(wi[2], 550.0, material=material)) / float(material.F(wi[2], 550.0))
            else:
                loss = 1.0 - float(nano.coherent_fraction(wi[2], 550.0, material=material))
            if m.length_scale < 1e-6 and th > 30.0:
                # correlation length near λ, oblique: the tangent plane's own limit (glass: Kirchhoff 1.43×
                # Rayleigh-Rice, docs/validity; metal: test_tangent_plane_loss_at_a_correlation_length_near_lambda)
                continue
            assert loss == pytest.approx(tis, rel=0.25 if mat == "1.5" else 0.06), (m, th)


@pytest.mark.xfail(strict=True, reason="known: the tangent-plane lobe of a correlation length near λ holds 11 % less "
                                       "light than first order in exits up to 75° (0.899 of TIS at 60°)")
def test_tangent_plane_loss_at_a_correlation_length_near_lambda():
    """Al, ABC σ = 5 nm, B = 0.5 µm, C = 3 (ℓ ≈ λ), 60°: the coherent loss within 6 % of first-order TIS, as for
    the longer correlation lengths above. Measured 0.899: the tangent-plane (Kirchhoff) lobe holds 0.00245 of F in
    exits ≤ 75° where Rayleigh-Rice holds 0.00275, a limit of the tangent plane where ℓ nears λ. Before the grazing
    hand-over to first order (scatter.tangent_blend) it passed (0.945) only because the tangent-plane lobe's excess
    at grazing exit (beyond its validity, and not reciprocal: up to 27 % in the two-scale BRDF) made up that deficit;
    the hand-over gives grazing exits first order's light."""
    grid = DirectionGrid.hemisphere(384)
    wo = grid.directions()
    material = materials.get_material("Al")
    m = surfaces.PSDModel("abc", sigma=5e-9, B=0.5e-6, C=3)
    wi = direction_from_angles(60.0, 0.0)
    rr = np.where(grid.inside, perturbation.rayleigh_rice_brdf(wi, wo, 550.0, m, material.eta(550.0) ** 2), 0)
    tis = integrate(rr[None], grid)[0] / float(material.F(wi[2], 550.0))
    loss = 1.0 - float(twoscale.Nano(model=m).coherent_fraction(wi[2], 550.0, material=material))
    assert loss == pytest.approx(tis, rel=0.06)


ENERGY_CASES = [("gaussian", dict(sigma=55e-9, T=1e-6)), ("exponential", dict(sigma=55e-9, T=1e-6)),
                ("abc", dict(sigma=40e-9, B=3.7e-6, C=2.2)), ("abc", dict(sigma=55e-9, B=2e-6, C=3)),
                ("abc", dict(sigma=55e-9, B=1e-6, C=4))]


@pytest.mark.parametrize("kind,kw", ENERGY_CASES)
def test_two_scale_albedo_is_fresnel_on_the_psd_route_without_capping(kind, kw):
    """Issue 13's energy test: σ up to λ/10, C from 2.2 to 4, micro α = 0, θ_i ≤ 40°: albedo = F(θ_i) within 1e-2
    for a metal, and the capping guard does not act for a metal or a dielectric. (On a dielectric the coherent part
    is R exp(−g_rel) and the scattered light has its own albedo, so the albedo is not F: issue 28,
    tests/test_dielectric_energy.py.)"""
    m = surfaces.PSDModel(kind, **kw)
    grid = DirectionGrid.hemisphere(128)
    for mat in ("1+6j", "1.5"):
        material = materials.get_material(mat)
        for th in (0.0, 20.0, 40.0):
            wi = direction_from_angles(th, 0.0)
            L = twoscale.evaluate(wi, [550.0], material, twoscale.Micro(alpha=0.0, ndf="ggx"), twoscale.Nano(model=m), grid,
                                  kd=0)
            if mat != "1.5":
                assert L.albedo()[0] / float(material.F(wi[2], 550.0)) == pytest.approx(1.0, abs=1e-2), (mat, th)
            assert L.info["diffraction_energy_scale"] == [1.0]


@functools.cache
def _gauss_legendre(n):
    """Gauss-Legendre nodes and weights on [-1, 1] (NumPy's, an eigenvalue problem of 1 s at n = 400: made once)."""
    return np.polynomial.legendre.leggauss(n)


def _ggx_facet_reflectance(theta_deg, alpha, F):
    """∫ F(ω_i·m) G1(ω_i, m) (ω_i·m)⁺ D(m) dm / cos θ_i: the light the micro facets reflect before masking on the
    way out, GGX D and its Smith G1 written here (Walter et al. 2007, eqs. 33-34), by a product rule in
    (tan θ_m, φ_m)."""
    t = math.radians(theta_deg)
    wi = np.array([math.sin(t), 0.0, math.cos(t)])
    x, wx = _gauss_legendre(400)
    u = 0.5 * (x + 1)                                    # tan θ_m = α u / (1 − u) covers [0, ∞)
    tan_m, dtan = alpha * u / (1 - u), 0.5 * wx * alpha / (1 - u) ** 2
    phi = (np.arange(256) + 0.5) * (2 * math.pi / 256)
    T, P = np.meshgrid(tan_m, phi, indexing="ij")
    cm = 1 / np.sqrt(1 + T * T)
    m = np.stack([T * cm * np.cos(P), T * cm * np.sin(P), cm], axis=-1)
    D = alpha ** 2 / (math.pi * cm ** 4 * (alpha ** 2 + T * T) ** 2)
    im = np.clip(m @ wi, 0, None)
    tan_i = math.tan(t)
    G1 = 2 / (1 + math.sqrt(1 + alpha ** 2 * tan_i ** 2))
    dm = cm ** 3 * dtan[:, None] * (2 * math.pi / 256)        # dω_m = sin θ_m dθ_m dφ = cos³θ_m tan θ_m d(tan θ_m) dφ
    return float(np.sum(F(im) * G1 * im * D * T * dm) / wi[2])


def test_micro_rough_two_scale_albedo_is_bounded_by_the_light_the_facets_reflect():
    """With micro α up to 0.3 the two-scale albedo (Au, kd = 0) is at most the light its facets reflect before
    masking on the way out (each facet reflects F, coherent or diffracted), computed in the test
    (:func:`_ggx_facet_reflectance`), and within 20 % of the microfacet albedo. Measured against the microfacet
    albedo: 4.4 % below for the Gaussian σ = 55 nm, T = 1 µm surface that scatters 80 % of its light, carried by
    α = 0.3 facets; 18 % below for ABC C = 4 with B = 1 µm (σ = 55 nm), whose lobe spreads to the horizon
    (docs/two-scale.md); 0.24 % above for ABC C = 2.2 (σ = 40 nm) at 40° on α = 0.3, where the diffracted light,
    handed over to first order towards grazing exit (scatter.tangent_blend), is masked less than the specular
    light of its facets (the pointwise form, a different quadrature, gives the same +0.23 %)."""
    grid = DirectionGrid.hemisphere(128)
    gold = materials.get_material("Au")
    for kind, kw in ENERGY_CASES[::2]:
        nano = twoscale.Nano(model=surfaces.PSDModel(kind, **kw))
        for alpha in (0.1, 0.3):
            for th in (0.0, 40.0):
                L = twoscale.evaluate(direction_from_angles(th, 0.0), [550.0], "Au", twoscale.Micro(alpha=alpha, ndf="ggx"), nano,
                                      grid, kd=0)
                ratio = L.albedo()[0] / L.albedo("microfacet")[0]
                bound = _ggx_facet_reflectance(th, alpha, lambda c: gold.F(c, 550.0))
                assert 0.8 < ratio, (kind, alpha, th, ratio)
                assert L.albedo()[0] <= bound, (kind, alpha, th, L.albedo()[0], bound)
