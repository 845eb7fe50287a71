"""Coated rough glass (issue 33): :class:`waveoptics.brdf.RoughDielectricBSDF` whose facets carry a thin-film stack
(an anti-reflection coating) on the glass, each facet reflecting the stack's R and transmitting its T
(:class:`waveoptics.brdf.CoatedInterface`).

Oracles written here, not taken from the library:

* the Airy formula of one film (Born & Wolf §1.6.4) with tilted admittances η_s = n cos θ, η_p = n / cos θ
  (Macleod §2.2): r = (ρ₀₁ + ρ₁₂ e^{−2iδ})/(1 + ρ₀₁ ρ₁₂ e^{−2iδ}), t = τ₀₁ τ₁₂ e^{−iδ}/(1 + ρ₀₁ ρ₁₂ e^{−2iδ}),
  δ = 2π n₁ d cos θ₁/λ, R = |r|², T = Re(η₂)/η₀ |t|² (the library uses Rouard's recurrence on field amplitudes);
* the quarter-wave coating's closed form R = ((n₀ n_s − n₁²)/(n₀ n_s + n₁²))² at λ₀ (Macleod §4.1);
* the albedo ∫ f |cos θ_o| dω_o by a quadrature over microfacet normals written here (slopes by Gauss-Legendre
  mapped to infinity, midpoint rule in azimuth; each normal's mirror and refracted direction, Walter eqs. 14, 17,
  40), against the library's quadrature;
* the sampler against its pdf by Pearson's χ²; the mean sample weight (Monte Carlo) against the albedo with an
  absorbing film (R + T < 1 per facet: reflection is chosen with R/(R + T));
* reciprocity f(i, o)/η_o² = f(o, i)/η_i² at random pairs, and T₁₂(θ₁) = T₂₁(θ₂) of the stack at Snell pairs.
"""
from __future__ import annotations

import cmath
import json
import math

import numpy as np
import pytest

from cli_helpers import run_cli
from slope_quadrature import quad_albedo, quad_multiple, slope_nodes
from waveoptics import brdf
from waveoptics.brdf import Micro, RoughDielectricBSDF, chi2_test, facet_interface_of
from waveoptics.errors import FieldError
from waveoptics.materials import get_material

LAM = 550.0
N_GLASS, N_FILM, D_FILM = 1.5, 1.38, 100.0
COATED = f"{N_GLASS}|{N_FILM}:{D_FILM:g}nm"


def _dir(theta_deg, side=1.0, phi_deg=0.0):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), side * math.cos(t)])


def airy_RT(cos0, n0, n1, d_nm, n2, lam=LAM):
    """(R, T) unpolarized (arrays of *cos0*, the cosine in the incidence medium) of one film n1 (thickness d_nm)
    between an incidence medium n0 and a medium n2 (module doc: Airy's sum with tilted admittances)."""
    c0 = np.asarray(cos0, dtype=complex)
    s0 = n0 * np.sqrt(1 - c0 * c0)
    cos = [c0] + [np.sqrt(1 - (s0 / n) ** 2 + 0j) for n in (n1, n2)]
    delta = 2 * np.pi * n1 * d_nm * cos[1] / lam
    R = T = 0.0
    for eta in ([n * c for n, c in zip((n0, n1, n2), cos)], [n / c for n, c in zip((n0, n1, n2), cos)]):
        rho01, rho12 = (eta[0] - eta[1]) / (eta[0] + eta[1]), (eta[1] - eta[2]) / (eta[1] + eta[2])
        tau01, tau12 = 2 * eta[0] / (eta[0] + eta[1]), 2 * eta[1] / (eta[1] + eta[2])
        e2 = np.exp(-2j * delta)
        den = 1 + rho01 * rho12 * e2
        r, t = (rho01 + rho12 * e2) / den, tau01 * tau12 * np.exp(-1j * delta) / den
        R = R + 0.5 * np.abs(r) ** 2
        T = T + 0.5 * (eta[2].real / eta[0].real) * np.abs(t) ** 2
    return R, T


# -- the smooth limit: one film's Airy formula -----------------------------------------------------------------------

@pytest.mark.parametrize("theta, side", [(0, 1), (30, 1), (60, 1), (20, -1)])
def test_smooth_limit_is_the_airy_formula_of_one_film(theta, side):
    """α = 0.01: the reflected and transmitted albedos are the film's R and T (Airy, written here) within 2e-3,
    from air and from the glass (the stack reversed: glass, film, air)."""
    b = RoughDielectricBSDF(COATED, Micro(alpha=0.01))
    parts = b.albedo_parts(_dir(theta, side), LAM)
    n0, n2 = (1.0, N_GLASS) if side > 0 else (N_GLASS, 1.0)
    R, T = airy_RT(math.cos(math.radians(theta)), n0, N_FILM, D_FILM, n2)
    print(theta, side, "albedos", float(parts["reflection"]), float(parts["transmission"]), "Airy", R, T)
    assert abs(parts["reflection"] - R) < 2e-3 and abs(parts["transmission"] - T) < 2e-3
    bare = airy_RT(math.cos(math.radians(theta)), n0, N_FILM, 0.0, n2)[0]
    assert abs(R - bare) > 5e-3          # the film matters here: the test can tell it from the bare glass


def test_facet_transmittance_is_reciprocal_at_snell_pairs():
    """T₁₂(θ₁) = T₂₁(θ₂) of the stack for n₁ sin θ₁ = n₂ sin θ₂, lossless and absorbing films (checked, not assumed:
    the η² reciprocity of the BSDF rests on it); R + T = 1 per facet for the lossless film."""
    c_air = np.linspace(0.02, 1.0, 25)
    c_glass = np.sqrt(1 - (1 - c_air ** 2) / N_GLASS ** 2)
    for spec in (COATED, f"{N_GLASS}|{N_FILM}+0.05j:{D_FILM:g}nm|2.3:60nm"):
        iface = facet_interface_of(get_material(spec), LAM)
        R1, T1 = iface.RT(c_air, np.ones(c_air.shape, bool))
        R2, T2 = iface.RT(c_glass, np.zeros(c_air.shape, bool))
        np.testing.assert_allclose(T1, T2, rtol=1e-10, atol=1e-14)
    iface = facet_interface_of(get_material(COATED), LAM)
    for up, c in ((True, c_air), (False, c_glass)):
        R, T = iface.RT(c, np.full(c.shape, up))
        np.testing.assert_allclose(R + T, 1.0, atol=1e-12)


# -- white furnace ---------------------------------------------------------------------------------------------------

def _ggx_G1(v, alpha):
    """Smith G1 of GGX (Walter eq. 34) of directions v (..., 3) on either side (|cos θ_v|)."""
    c = np.abs(v[..., 2])
    tan2 = np.maximum(1 - c * c, 0) / (c * c)
    return 2 / (1 + np.sqrt(1 + alpha * alpha * tan2))


def single_scattering_albedo(theta_deg, alpha):
    """∫ f |cos θ_o| dω_o of coated facets from air, separable Smith GGX: ∫ D_i(m) [R(m) G1(o_r) + T(m) G1(o_t)]
    dω_m with the visible normals D_i(m) = G1(i) ⟨i·m⟩ D(m)/cos θ_i (Heitz 2014 eq. 38), R, T of the film by
    Airy, each outgoing direction on the side of its facet (otherwise masked: 0). 1 − this is the energy that
    single scattering loses to a second bounce."""
    m, w = slope_nodes(alpha)
    i = _dir(theta_deg)
    c = m @ i
    vis = c > 0
    tan2 = (1 - m[:, 2] ** 2) / m[:, 2] ** 2
    D = alpha ** 2 / (np.pi * m[:, 2] ** 4 * (alpha ** 2 + tan2) ** 2)
    Dv = np.where(vis, _ggx_G1(i, alpha) * c * D / i[2], 0)
    R, T = airy_RT(np.clip(c, 1e-9, 1), 1.0, N_FILM, D_FILM, N_GLASS)    # hidden normals (c ≤ 0) weigh 0
    o_r = 2 * c[:, None] * m - i
    e = 1 / N_GLASS
    o_t = (e * c - np.sqrt(np.maximum(1 + e * e * (c * c - 1), 0)))[:, None] * m - e * i
    g_r = np.where(o_r[:, 2] > 0, _ggx_G1(o_r, alpha), 0)
    g_t = np.where(o_t[:, 2] < 0, _ggx_G1(o_t, alpha), 0)
    return float(np.sum(w * Dv * (R * g_r + T * g_t)))


def test_white_furnace_of_a_lossless_coating():
    """Lossless film on glass, α = 0.1 and 0.5, 0-70° from air (separable Smith GGX): the library's albedo R + T
    equals 1 − (single-scattering loss) by :func:`single_scattering_albedo` (written here: visible normals, the
    film by Airy) within 5e-5 (measured: 3e-6), and the quadrature of ``eval`` written here within 5e-5; R + T ≤ 1
    with a loss that grows with α."""
    thetas = (0, 30, 50, 70)
    loss = {}
    for alpha in (0.1, 0.5):
        b = RoughDielectricBSDF(COATED, Micro(alpha=alpha, ndf="ggx", shadowing="smith"))
        lib = b.albedo(np.array([_dir(t) for t in thetas]), LAM)
        ref = np.array([single_scattering_albedo(t, alpha) for t in thetas])
        quad = np.array([sum(quad_albedo(b, _dir(t), alpha, N_GLASS, LAM)) for t in thetas])
        print(alpha, "library", np.round(lib, 6), "reference", np.round(ref, 6), "eval quadrature", np.round(quad, 6))
        np.testing.assert_allclose(lib, ref, atol=5e-5)
        np.testing.assert_allclose(lib, quad, atol=5e-5)
        loss[alpha] = 1 - ref
    assert np.all(loss[0.1] >= 0) and np.all(loss[0.5] >= 0)
    assert np.all(loss[0.5] > loss[0.1] + 1e-3)


@pytest.mark.parametrize("alpha", [0.1, 0.5])
def test_white_furnace_with_multiple_scattering(alpha):
    """Lossless film, the Kulla-Conty compensation built with the stack's R and T (tables per wavelength): R + T +
    R_ms + T_ms = 1 within 2e-3 (the issue asks 1e-2) at 0-70° from air and 0-60° from the glass (total internal
    reflection included), by the quadratures written here; absorbing films are refused in one line naming both
    fields (the lobes would return light the films absorb)."""
    b = RoughDielectricBSDF(COATED, Micro(alpha=alpha, ndf="ggx"), multiple_scattering=True)
    for theta, side in ((0, 1), (30, 1), (50, 1), (70, 1), (0, -1), (30, -1), (45, -1), (60, -1)):
        i = _dir(theta, side)
        single = sum(quad_albedo(b, i, alpha, N_GLASS, LAM))
        total = single + quad_multiple(b, i, LAM)
        print(alpha, theta, side, "single", round(single, 5), "compensated", round(total, 5))
        assert abs(total - 1) < 2e-3, (theta, side, total)       # measured: ≤ 8.4e-4
    lossy = RoughDielectricBSDF(f"{N_GLASS}|{N_FILM}+0.1j:{D_FILM:g}nm", Micro(alpha=alpha), multiple_scattering=True)
    with pytest.raises(FieldError) as err:
        lossy.eval(_dir(30), _dir(20, -1), LAM)
    assert set(err.value.fields) >= {"material", "multiple_scattering"} and "\n" not in str(err.value)


# -- quarter-wave anti-reflection coating ----------------------------------------------------------------------------

def test_quarter_wave_mgf2_on_bk7_is_an_antireflection_coating():
    """MgF2 of λ₀/(4 n) at λ₀ = 550 nm on BK7, α = 0.1: the reflected albedo at 5° is below the bare glass's at
    550 nm, near the closed-form quarter-wave R (within 1e-3), and lowest near 550 nm over 450-650 nm."""
    n_film = float(np.real(get_material("MgF2").eta(np.array([LAM]))[0]))
    n_sub = float(np.real(get_material("BK7").eta(np.array([LAM]))[0]))
    coated = RoughDielectricBSDF(f"BK7|MgF2:{LAM / (4 * n_film):.6f}nm", Micro(alpha=0.1))
    bare = RoughDielectricBSDF("BK7", Micro(alpha=0.1))
    wi = _dir(5)
    lams = np.arange(450.0, 651.0, 25.0)
    R = np.array([float(coated.albedo_parts(wi, lam)["reflection"]) for lam in lams])
    R_bare = float(bare.albedo_parts(wi, LAM)["reflection"])
    R_qw = ((n_sub - n_film ** 2) / (n_sub + n_film ** 2)) ** 2
    print("R(λ) =", np.round(R, 5), "bare", R_bare, "quarter wave", R_qw)
    at = R[lams == LAM][0]
    assert at < R_bare - 0.02
    assert abs(at - R_qw) < 1e-3
    assert abs(lams[np.argmin(R)] - LAM) <= 25.0


# -- sampling and reciprocity ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("theta, side, ms", [(40, 1, False), (30, -1, False), (50, -1, True)])
def test_sampling_chi2_of_coated_glass(theta, side, ms):
    b = RoughDielectricBSDF(COATED, Micro(alpha=0.3, ndf="ggx"), multiple_scattering=ms)
    wi = _dir(theta, side)
    res = chi2_test(lambda u: b.sample(wi, LAM, u).wo, lambda d: b.pdf(wi, d, LAM), sample_count=100_000, res=31,
                    ires=12, seed=5, test_count=3)
    print(res.message)
    assert res.passed, res.message


def test_mean_sample_weight_with_an_absorbing_film_is_the_albedo():
    """An absorbing film (R + T < 1 per facet): the sampler picks reflection with R/(R + T), and the mean weight
    f |cos θ_o| / pdf (seeded Monte Carlo, 4σ) is the quadrature albedo, below the lossless one."""
    b = RoughDielectricBSDF(f"{N_GLASS}|{N_FILM}+0.1j:{D_FILM:g}nm", Micro(alpha=0.4))
    for wi in (_dir(35), _dir(25, -1)):
        s = b.sample(wi, LAM, np.random.default_rng(11).random((100_000, 2)))
        mc, err = float(np.mean(s.weight)), float(np.std(s.weight)) / math.sqrt(len(s.weight))
        E = float(b.albedo(wi, LAM))
        assert abs(mc - E) < 4 * err + 1e-4, (mc, err, E)
        assert E < 0.9


@pytest.mark.parametrize("ms", [False, True])
def test_reciprocity_with_the_eta_squared_factor(ms):
    """f(i, o)/η_o² = f(o, i)/η_i² at random pairs over the sphere (anisotropic GGX, coated facets), with and
    without the compensation lobes (whose split across the interface uses the stack's mean transmittances)."""
    rng = np.random.default_rng(3)
    b = RoughDielectricBSDF(COATED, Micro(alpha=0.25, alpha_y=0.5, ndf="ggx"), multiple_scattering=ms)
    v = rng.normal(size=(4000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v = v[np.abs(v[:, 2]) > 0.02]
    n = len(v) // 2
    wi, wo = v[:n], v[n:2 * n]
    eta_i = np.where(wi[:, 2] > 0, 1.0, N_GLASS)
    eta_o = np.where(wo[:, 2] > 0, 1.0, N_GLASS)
    fwd, back = b.eval(wi, wo, LAM) / eta_o ** 2, b.eval(wo, wi, LAM) / eta_i ** 2
    np.testing.assert_allclose(fwd, back, rtol=1e-9, atol=1e-300)
    assert np.sum((fwd > 0) & (wi[:, 2] * wo[:, 2] < 0)) > 100


# -- model registry and command line ---------------------------------------------------------------------------------

def test_command_line_prints_R_and_T_of_coated_glass():
    """`brdf --model rough-dielectric --material "BK7|MgF2:100nm" --albedo` prints R and T (those of the library
    object), also with --multiple-scattering (R + T = 1 within 1e-2), also with --nano (the coated nano-rough glass:
    tests/test_coated_nano_glass.py)."""
    base = ["brdf", "--model", "rough-dielectric", "--material", "BK7|MgF2:100nm", "--micro-alpha", "0.2",
            "--incident", "30", "--albedo"]
    rc, out, err, _ = run_cli(base)
    assert rc == 0, err
    assert "R=" in out and "T=" in out
    rc, out, err, _ = run_cli(base + ["--json"])
    row = json.loads(out)["albedo"][0]
    want = RoughDielectricBSDF("BK7|MgF2:100nm", Micro(alpha=0.2)).albedo_parts(_dir(30), LAM)
    assert row["reflection"] == pytest.approx(float(want["reflection"]), rel=1e-12)
    assert row["transmission"] == pytest.approx(float(want["transmission"]), rel=1e-12)
    assert row["albedo"] == pytest.approx(row["reflection"] + row["transmission"], rel=1e-14)
    rc, out, err, _ = run_cli(base + ["--json", "--multiple-scattering"])
    assert rc == 0 and json.loads(out)["albedo"][0]["albedo"] == pytest.approx(1.0, abs=1e-2), err
    rc, out, err, _ = run_cli(base + ["--json", "--multiple-scattering", "--nano",
                                      "gaussian:sigma=20nm,corr_length=1um"])
    assert rc == 0, err
    row = json.loads(out)["albedo"][0]
    assert row["albedo"] == pytest.approx(1.0, abs=1e-2)
    model = brdf.BRDF_MODELS["rough-dielectric"](wavelengths_nm=np.array([LAM]), alpha=0.2, material=COATED)
    assert model.albedo(_dir(30)[None])[0, 0] == pytest.approx(1.0, abs=1e-3)
