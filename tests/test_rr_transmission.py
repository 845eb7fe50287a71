"""First-order scatter into transmission of a slightly rough interface (waveoptics.scatter.transmission, issue 33).

References held against the code:
* a rigorous plane-wave solve of a shallow sinusoidal grating (tests/rr_grating.py, the Rayleigh method with Bessel
  harmonics, written from Maxwell's boundary conditions): its ±1 reflected and transmitted efficiencies, s and p
  analyzed, in conical mounts, from air into glass, from glass into air (also beyond the critical angle) and
  between two dielectrics, against the library's BSDF with a delta PSD; and its specular loss (the second-order
  reduction of R + T) against the library's first-order scatter into both half-spaces (optical theorem);
* the same specular loss integrated over a Gaussian PSD (grating solves on a polar grid of spatial frequencies)
  against the library's TIS_R + TIS_T of the random surface;
* T. A. Germer's SCATMECH (NIST) Microroughness_BRDF_Model in transmission (after Elson 1995), its Jones matrix
  transcribed into the test: equal to 1e-11 from air and from inside;
* reciprocity with the η² factor of radiance (Veach 1997, §5.2), the n₂ → n₁ limit, and the smooth-surface
  transmitted TIS at normal incidence, (2π σ (n₂ − n₁) / λ)² T (Stover 2012; Duparré et al. 2002), and at oblique
  incidence T (2π σ (n_i cosθ_i − n_o cosθ_t) / λ)² (Carniglia 1979), written here.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from rr_grating import grating_solve, integrated_losses
from waveoptics.errors import FieldError
from waveoptics.scatter.transmission import (hemisphere_albedo, q_transmission, rr_brdf_components, rr_bsdf, rr_btdf_components,
                                             rr_tis_reflection, rr_tis_transmission)
from waveoptics.surfaces import PSDModel

LAM_NM = 500.0
LAM = LAM_NM * 1e-9
KA = 1e-3              # grating amplitude × the larger wave number, k₀ n_max a
TOL_ORDER = 2e-6       # first order vs rigorous at KA (the error is O((k a)²): measured ≤ 1.1e-6)
TOL_LOSS = 1e-5        # first-order scatter vs the rigorous specular loss at KA (measured ≤ 4e-7)
TOL_QUAD = 1e-8       # the two TIS quadratures against each other where the integrand is smooth (measured ≤ 8e-10)
TOL_QUAD_KINK = 1e-3  # ... where a √ kink crosses the polar grid (measured 1.1e-4 to 7.0e-4: Gauss-Legendre panels
                      # converge slowly across it; method='auto' integrates such wide lobes over the hemisphere)
TOL_TIS = 1e-5         # TIS of a random surface vs the integrated grating loss (measured ≤ 9e-7)
TOL_TIS_TIR = 1e-3     # the same beyond the critical angle (the reference's grid, measured 4.7e-4)


class UnitPSD:
    """S = 1 m⁴ everywhere: f / S of the library, the BSDF per unit PSD."""
    length_scale = 1e-6

    def S(self, f):
        return np.ones_like(np.asarray(f, dtype=float))


# (n_incident, n_other, θ_i deg, azimuth of the incidence deg, K / k₀, light from above in the library's frame)
CASES = [
    (1.0, 1.5, 30.0, 17.0, 0.7, True),      # air → glass, conical
    (1.0, 1.5, 0.5, 60.0, 1.3, True),       # near-normal, orders at ±1.3/1.5
    (1.0, 1.5, 70.0, 0.0, 0.9, True),       # classical mount (in plane: sp = ps = 0)
    (1.5, 1.0, 25.0, 30.0, 0.6, False),     # glass → air (library: air above, glass below, light from below)
    (1.5, 1.0, 60.0, 10.0, 1.2, False),     # glass → air beyond the critical angle: specular T = 0, orders cross
    (1.33, 1.7, 40.0, 45.0, 1.1, True),     # water → dense glass
]


def _setup(case):
    n_i, n_o, th, az, K, above = case
    t, p = math.radians(th), math.radians(az)
    wi = np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])   # in the solver's frame
    a = KA / max(n_i, n_o)
    lib = (n_i, n_o) if above else (n_o, n_i)             # the library's (n1 above, n2 below)
    flip = np.array([1.0, 1.0, 1.0 if above else -1.0])   # solver frame → library frame
    return n_i, n_o, wi, a, K, lib, flip


def _order_efficiencies(case, pol):
    """[(kind, order, analyzed b, rigorous, library)] of the propagating ±1 orders."""
    n_i, n_o, wi, a, K, (n1, n2), flip = _setup(case)
    res = grating_solve(n_i, n_o, -n_i * wi[0], -n_i * wi[1], K, a, pol)
    a_m = a * LAM / (2 * np.pi)
    out = []
    for j in np.flatnonzero(np.abs(res["orders"]) == 1):
        for kind, kv, nn, fn in (("R", res["kr"][j], n_i, rr_brdf_components),
                                 ("T", res["kt"][j], n_o, rr_btdf_components)):
            if abs(kv[2].imag) > 1e-12:
                continue
            wo = kv.real / nn
            f = fn(wi * flip, wo * flip, LAM_NM, UnitPSD(), n1, n2)
            for b in "sp":
                out.append((kind, res["orders"][j], b, res[kind][b][j], (LAM / nn) ** 2 * a_m ** 2 / 4 * f[pol + b]))
    return res, out


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("pol", ["s", "p"])
def test_orders_match_rigorous_grating(case, pol):
    """Every propagating ±1 order, reflected and transmitted, s and p analyzed: the library's first-order BSDF with
    a delta PSD equals the rigorous efficiency to O((k a)²)."""
    res, rows = _order_efficiencies(case, pol)
    tot = res["R"]["total"].sum() + res["T"]["total"].sum()
    assert abs(tot - 1.0) < 1e-12                     # the solver conserves energy (lossless media)
    assert any(r[0] == "T" for r in rows)
    big = max(r[3] for r in rows)
    for kind, m, b, rig, lib in rows:
        # cross-polarized in-plane orders vanish in both (0 = 0): compared against the largest order instead
        assert abs(lib - rig) <= TOL_ORDER * max(rig, 1e-6 * big), (kind, m, b, rig, lib)


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("pol", ["s", "p"])
def test_first_order_scatter_is_the_specular_loss(case, pol):
    """Optical theorem to second order: the rigorous grating's specular R₀ + T₀ falls below the flat interface's
    (= 1, lossless) by exactly the first-order scatter into both half-spaces."""
    res, rows = _order_efficiencies(case, pol)
    loss = 1.0 - res["R"]["total"][res["orders"] == 0][0] - res["T"]["total"][res["orders"] == 0][0]
    scatter = sum(r[4] for r in rows)
    assert abs(scatter / loss - 1.0) < TOL_LOSS, (scatter, loss)


@pytest.mark.parametrize("n_i, n_o, th, pol, tol", [(1.0, 1.5, 30.0, "s", TOL_TIS), (1.0, 1.5, 30.0, "p", TOL_TIS),
                                                    (1.5, 1.0, 20.0, "p", TOL_TIS),
                                                    (1.5, 1.0, 50.0, "s", TOL_TIS_TIR)])
def test_random_surface_tis_is_the_integrated_specular_loss(n_i, n_o, th, pol, tol):
    """Gaussian PSD (σ = 1 nm, T = 1 µm): TIS_R + TIS_T of the library equals ∫ S(f) L(f) d²f over a half plane of
    spatial frequencies, with L the rigorous specular loss of a grating of frequency f per a²/4 (each grating
    scatters into +f and −f)."""
    psd = PSDModel("gaussian", 1e-9, T=1e-6)
    t = math.radians(th)
    wi = np.array([math.sin(t), 0.0, math.cos(t)])
    ref = sum(integrated_losses(n_i, n_o, wi, psd.S, psd.T, LAM, pol))
    above = n_i == 1.0
    n1, n2 = (n_i, n_o) if above else (n_o, n_i)
    tis = (rr_tis_reflection(th, LAM_NM, psd, n1, n2, pol, from_above=above)
           + rr_tis_transmission(th, LAM_NM, psd, n1, n2, pol, from_above=above))
    assert abs(tis / ref - 1.0) < tol, (tis, ref)


@pytest.mark.parametrize("th, corr", [(0.0, 1e-6), (30.0, 0.3e-6), (60.0, 0.15e-6)])
def test_tis_quadratures_agree(th, corr):
    """The polar quadrature about the specular direction and the hemisphere quadrature (cut at the critical angle)
    give one TIS, transmitted and reflected, air → glass and glass → air; the hemisphere quadrature is converged
    (doubling its nodes changes it by < 1e-9 relative). Where the integrand has a √ kink inside the disc (the circle
    where a first-order factor's normal wave number turns imaginary: transmission into glass, reflection inside
    glass) and the lobe is wide enough to reach it, the polar quadrature's panels do not follow it."""
    psd = PSDModel("gaussian", 1e-9, T=corr)
    for n1, n2, above in ((1.0, 1.5, True), (1.0, 1.5, False)):
        tt = th if above else th * 0.6            # below the critical angle from inside
        for fn in (rr_tis_transmission, rr_tis_reflection):
            a = fn(tt, LAM_NM, psd, n1, n2, "p", from_above=above, method="polar")
            b = fn(tt, LAM_NM, psd, n1, n2, "p", from_above=above, method="hemisphere")
            kink = (fn is rr_tis_transmission) == above and corr < 1e-6
            assert a == pytest.approx(b, rel=TOL_QUAD_KINK if kink else TOL_QUAD), (fn.__name__, above)
    wi = np.array([math.sin(math.radians(th)), 0.0, math.cos(math.radians(th))])

    def lobe(wo):
        f = rr_btdf_components(np.broadcast_to(wi, wo.shape), wo * [1, 1, -1], LAM_NM, psd, 1.0, 1.5)
        return 0.5 * (f["ss"] + f["sp"] + f["pp"] + f["ps"])

    crit = [math.asin(1 / 1.5)]
    assert hemisphere_albedo(lobe, crit, 64, 257) == pytest.approx(hemisphere_albedo(lobe, crit, 128, 513),
                                                                    rel=1e-9)


def _scatmech_btdf(thi, ths, phs, n, lam_m, S_of_f, backward):
    """The first-order BTDF of one rough interface as T. A. Germer's SCATMECH Microroughness_BRDF_Model gives it
    (Jones matrix of the transmission case, after Elson 1995, code/urough.cpp; BRDF_Model type 1, light from above,
    or type 3, from inside: ε → 1/ε, λ → λ/n), written here in its variables: q0 of the incident wave, q1 of the
    scattered one, [0] in the substrate, [1] in the ambient. Returns {ab: |J_ab|²} (1/sr), first index incident."""
    eps = n * n
    lam = lam_m
    if backward:
        eps, lam = 1.0 / eps, lam_m / n
    index = np.sqrt(eps + 0j)
    k = np.sin(ths) * index
    k0 = np.sin(thi)
    q0 = (np.sqrt(eps - k0 * k0 + 0j), np.sqrt(1.0 - k0 * k0 + 0j))
    q1 = (np.sqrt(eps - k * k + 0j), np.sqrt(1.0 - k * k + 0j))
    f = np.hypot(np.sin(ths) * np.cos(phs) * index.real - np.sin(thi), np.sin(ths) * np.sin(phs) * index.real) / lam
    J = {"pp": index * (k * k0 + np.cos(phs) * q0[0] * q1[1]) / (q0[0] + eps * q0[1]) / (q1[0] + eps * q1[1]),
         "ss": np.cos(phs) / (q0[0] + q0[1]) / (q1[0] + q1[1]),
         "sp": index * q1[1] * np.sin(phs) / (q0[0] + q0[1]) / (q1[0] + eps * q1[1]),
         "ps": -q0[0] * np.sin(phs) / (q0[0] + eps * q0[1]) / (q1[0] + q1[1])}
    common = 4 * np.pi * (1 - eps) * index * np.sqrt(q1[0] * q0[1] * S_of_f(f)) / lam ** 2
    return {ab: np.abs(v * common) ** 2 for ab, v in J.items()}


@pytest.mark.parametrize("backward", [False, True])
def test_btdf_equals_scatmech_transmission(backward):
    """SCATMECH's transmission Jones matrix (another program's formula, transcribed into the test) squared equals
    the library's four polarized BTDFs at seeded random geometries (incidence from air, type 1, and from inside the
    glass below the critical angle, type 3): the same Q_t, prefactor n₁ n₂³ and radiance convention."""
    rng = np.random.default_rng(1995)
    n = 1.52
    psd = PSDModel("gaussian", 2e-9, T=0.4e-6)
    m = 40
    # from air, scattering angles in the glass up to 69° (beyond its 41° critical angle the reciprocal wave is
    # evanescent in air); from inside, incidence below the critical angle
    thi = rng.uniform(0.0, math.asin(1 / n) if backward else 1.5, m)
    ths = rng.uniform(0.0, 1.5 if backward else 1.2, m)
    phs = rng.uniform(-np.pi, np.pi, m)
    ref = _scatmech_btdf(thi, ths, phs, n, LAM, psd.S, backward)
    zi, zo = (-1.0, 1.0) if backward else (1.0, -1.0)
    wi = np.stack([np.sin(thi), np.zeros(m), zi * np.cos(thi)], axis=-1)
    wo = np.stack([-np.sin(ths) * np.cos(phs), -np.sin(ths) * np.sin(phs), zo * np.cos(ths)], axis=-1)
    got = rr_btdf_components(wi, wo, LAM_NM, psd, 1.0, n)
    for ab in ("ss", "sp", "ps", "pp"):
        np.testing.assert_allclose(got[ab], ref[ab], rtol=1e-11, atol=1e-14 * float(np.max(ref[ab])))


def test_brdf_inside_equals_scatmech_type_2():
    """Reflection inside the glass (SCATMECH BRDF_Model type 2: Germer's q factors with ε → 1/ε and λ → λ/n, from
    code/urough.cpp, transcribed here) equals the library's BRDF from below, also beyond the critical angle."""
    rng = np.random.default_rng(2)
    n, m = 1.52, 40
    psd = PSDModel("gaussian", 2e-9, T=0.4e-6)
    thi, ths, phs = rng.uniform(0.0, 1.5, m), rng.uniform(0.0, 1.5, m), rng.uniform(-np.pi, np.pi, m)
    e, lam = 1.0 / n ** 2, LAM / n
    ri, rs = np.sqrt(e - np.sin(thi) ** 2 + 0j), np.sqrt(e - np.sin(ths) ** 2 + 0j)
    q = {"pp": (e - 1) * (e * np.sin(thi) * np.sin(ths) - rs * ri * np.cos(phs)) / (e * np.cos(thi) + ri)
         / (e * np.cos(ths) + rs),
         "ss": (e - 1) * np.cos(phs) / (np.cos(thi) + ri) / (np.cos(ths) + rs),
         "ps": -(e - 1) * ri * np.sin(phs) / (e * np.cos(thi) + ri) / (np.cos(ths) + rs),
         "sp": -(e - 1) * rs * np.sin(phs) / (np.cos(thi) + ri) / (e * np.cos(ths) + rs)}
    f = np.hypot(np.sin(ths) * np.cos(phs) - np.sin(thi), np.sin(ths) * np.sin(phs)) / lam
    pre = 16 * np.pi ** 2 / lam ** 4 * np.cos(thi) * np.cos(ths) * psd.S(f)
    wi = np.stack([np.sin(thi), np.zeros(m), -np.cos(thi)], axis=-1)
    wo = np.stack([-np.sin(ths) * np.cos(phs), -np.sin(ths) * np.sin(phs), -np.cos(ths)], axis=-1)
    got = rr_brdf_components(wi, wo, LAM_NM, psd, 1.0, n)
    for ab in ("ss", "sp", "ps", "pp"):
        np.testing.assert_allclose(got[ab], pre * np.abs(q[ab]) ** 2, rtol=1e-11, atol=0)


def test_reciprocity_with_the_eta_squared_factor():
    """f^{ab}(ω_i → ω_o) / n_o² = f^{ba}(ω_o → ω_i) / n_i² for the BTDF (light either way) and the BRDF inside the
    glass, at seeded random directions."""
    rng = np.random.default_rng(33)
    psd = PSDModel("gaussian", 2e-9, T=0.3e-6)
    n1, n2 = 1.0, 1.52
    v = rng.normal(size=(2, 64, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    wi = v[0].copy()
    wi[:, 2] = np.abs(v[0][:, 2])                     # above
    wo = v[1].copy()
    wo[:, 2] = -np.abs(v[1][:, 2])                    # below
    fwd = rr_btdf_components(wi, wo, LAM_NM, psd, n1, n2)
    bwd = rr_btdf_components(wo, wi, LAM_NM, psd, n1, n2)
    assert np.all(fwd["ss"] > 0)
    for ab in ("ss", "sp", "ps", "pp"):
        np.testing.assert_allclose(fwd[ab] / n2 ** 2, bwd[ab[::-1]] / n1 ** 2, rtol=1e-12, atol=0)
    wr = wo.copy()
    wr[:, 0] *= -1
    r1 = rr_brdf_components(wo, wr, LAM_NM, psd, n1, n2)
    r2 = rr_brdf_components(wr, wo, LAM_NM, psd, n1, n2)
    for ab in ("ss", "sp", "ps", "pp"):
        np.testing.assert_allclose(r1[ab], r2[ab[::-1]], rtol=1e-12, atol=0)


def test_no_interface_no_scatter():
    """n₂ → n₁: the BSDF vanishes as (n₂ − n₁)² (no index step, nothing to scatter)."""
    psd = PSDModel("gaussian", 2e-9, T=0.3e-6)
    wi = np.array([0.5, 0.0, math.sqrt(0.75)])
    wo = np.array([-0.2, 0.3, -math.sqrt(1 - 0.13)])
    wr = np.array([-0.2, 0.3, math.sqrt(1 - 0.13)])
    f = {d: rr_bsdf(wi, w, LAM_NM, psd, 1.4, 1.4 + d) for d in (1e-3, 1e-4) for w in (wo,)}
    assert rr_bsdf(wi, wo, LAM_NM, psd, 1.4, 1.4) == 0.0
    assert rr_bsdf(wi, wr, LAM_NM, psd, 1.4, 1.4) == 0.0
    assert f[1e-4] / f[1e-3] == pytest.approx(1e-2, rel=2e-3)


@pytest.mark.parametrize("n1, n2", [(1.0, 1.5), (1.0, 2.4), (1.5, 1.0)])
def test_normal_incidence_tis_closed_form(n1, n2):
    """Smooth-surface transmitted TIS at normal incidence, (2π σ (n₂ − n₁) / λ)² T with T = 4 n₁ n₂ / (n₁ + n₂)²,
    and the reflected (4π n₁ σ / λ)² R (Stover 2012; Duparré et al., Appl. Opt. 41(1), 154–171, 2002, eqs. 2–3),
    for a long correlation length (paraxial lobe, corrections O((λ / π T)²))."""
    sigma = 2e-9
    psd = PSDModel("gaussian", sigma, T=20e-6)
    T = 4 * n1 * n2 / (n1 + n2) ** 2
    R = 1 - T
    tis_t = rr_tis_transmission(0.0, LAM_NM, psd, n1, n2)
    tis_r = rr_tis_reflection(0.0, LAM_NM, psd, n1, n2)
    assert tis_t == pytest.approx((2 * np.pi * sigma * (n2 - n1) / LAM) ** 2 * T, rel=1e-3)
    assert tis_r == pytest.approx((4 * np.pi * n1 * sigma / LAM) ** 2 * R, rel=1e-3)


@pytest.mark.parametrize("n_i, n_o, th", [(1.0, 1.5, 30.0), (1.0, 1.5, 60.0), (1.5, 1.0, 20.0), (1.5, 1.0, 35.0)])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_oblique_paraxial_tis_closed_form(n_i, n_o, th, pol):
    """For a long correlation length the transmitted TIS at oblique incidence is the scalar smooth-surface
    T (2π σ (n_i cosθ_i − n_o cosθ_t) / λ)² (C. K. Carniglia, Opt. Eng. 18(2), 104–115, 1979; Stover 2012), with
    T = 1 − R of the polarization (Fresnel, Born & Wolf §1.5.2), written here."""
    sigma = 2e-9
    psd = PSDModel("gaussian", sigma, T=20e-6)
    t = math.radians(th)
    ci, st = math.cos(t), n_i * math.sin(t) / n_o
    ct = math.sqrt(1 - st * st)
    if pol == "s":
        r = (n_i * ci - n_o * ct) / (n_i * ci + n_o * ct)
    else:
        r = (n_o * ci - n_i * ct) / (n_o * ci + n_i * ct)
    T = 1 - r * r
    above = n_i == 1.0
    n1, n2 = (n_i, n_o) if above else (n_o, n_i)
    got = rr_tis_transmission(th, LAM_NM, psd, n1, n2, pol, from_above=above)
    assert got == pytest.approx(T * (2 * np.pi * sigma * (n_i * ci - n_o * ct) / LAM) ** 2, rel=1e-3)


def test_q_transmission_normal_incidence():
    """At normal incidence and normal exit q_ss and q_pp are both (ε₂ − ε₁) / (n₁ + n₂)² (the step of the index
    times the two Fresnel transmission amplitudes over 4 n₁ n₂), written here."""
    q = q_transmission(np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), 1.2, 1.9)
    ref = (1.9 ** 2 - 1.2 ** 2) / (1.2 + 1.9) ** 2
    assert abs(q["ss"]) == pytest.approx(ref, rel=1e-14)
    assert abs(q["pp"]) == pytest.approx(ref, rel=1e-14)
    assert abs(q["sp"]) < 1e-15 and abs(q["ps"]) < 1e-15


def test_bad_indices_are_refused():
    psd = PSDModel("gaussian", 1e-9, T=1e-6)
    wi, wo = np.array([0.0, 0.0, 1.0]), np.array([0.1, 0.0, -math.sqrt(0.99)])
    with pytest.raises(FieldError, match="n2 .* transparent"):
        rr_btdf_components(wi, wo, LAM_NM, psd, 1.0, 1.5 + 0.1j)
    with pytest.raises(FieldError, match="n1"):
        rr_btdf_components(wi, wo, LAM_NM, psd, -1.0, 1.5)
    with pytest.raises(FieldError, match="theta_deg .* critical angle"):
        rr_tis_transmission(50.0, LAM_NM, psd, 1.0, 1.5, from_above=False, method="polar")
    with pytest.raises(FieldError, match="method"):
        rr_tis_transmission(50.0, LAM_NM, psd, 1.0, 1.5, method="grid")
    # an absorbing substrate still has a reflected first order (Rayleigh-Rice in air)
    assert rr_bsdf(wi, np.array([0.1, 0.0, math.sqrt(0.99)]), LAM_NM, psd, 1.0, 0.5 + 3j) > 0
