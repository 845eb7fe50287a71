"""Grazing incidence (issue 28, point 5): the tangent-plane lobe's albedo grows as 1/cosθ_i, so 1 − E dimmed grazing
highlights by up to 42 % and the pointwise two-scale function reflected 1.149 of the light at 89° with F = 1.

Oracles written here: first-order Rayleigh-Rice TIS (Elson & Bennett 1979; Germer 1997 eqs. 17–20) of Al, and of
the scalar modulus-1 (Dirichlet) problem with Q = 1 (Thorsos & Jackson 1989) for F = 1, integrated over the
hemisphere by adaptive quadrature; the white furnace (F = 1) of the whole two-scale BRDF by a quadrature about the
mirror direction written here, against the single-scattering microfacet albedo by the same quadrature.
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import integrate as spi

from waveoptics import brdf, materials, surfaces
from waveoptics.brdf import twoscale
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
AL = materials.get_material("Al")
SMOOTH = surfaces.PSDModel("abc", sigma=LAM * 1e-9 / 50, B=3e-6, C=2.6)   # σ = λ/50 = 11 nm


def _dir(theta):
    t = math.radians(theta)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def abc_psd(f, sigma=SMOOTH.sigma, B=3e-6, C=2.6):
    A = sigma ** 2 * B ** 2 * (C - 2) / (2 * math.pi)
    return A / (1 + (B * f) ** 2) ** (C / 2)


def Q_unpolarized(theta_i, wo, eps):
    """(|q_ss|² + |q_sp|² + |q_pp|² + |q_ps|²)/2 for a substrate of permittivity ε (Germer 1997, eqs. 17–20)."""
    ti = math.radians(theta_i)
    si, ci = math.sin(ti), math.cos(ti)
    u, v, co = wo
    so = math.hypot(u, v)
    cphi, sphi = (-u / so, -v / so) if so > 0 else (1.0, 0.0)
    ri, ro = np.sqrt(eps - si * si + 0j), np.sqrt(eps - so * so + 0j)
    ss = (eps - 1) * cphi / ((ci + ri) * (co + ro))
    sp = -(eps - 1) * ro * sphi / ((ci + ri) * (eps * co + ro))
    ps = -(eps - 1) * ri * sphi / ((eps * ci + ri) * (co + ro))
    pp = (eps - 1) * (eps * si * so - ri * ro * cphi) / ((eps * ci + ri) * (eps * co + ro))
    return 0.5 * (abs(ss) ** 2 + abs(sp) ** 2 + abs(pp) ** 2 + abs(ps) ** 2)


def tis(theta, Q):
    """∫ (16π²/λ⁴) cosθ_i cosθ_o Q S(f) du dv over the disc, polar (ρ, ψ) about the mirror point, ψ by 64-point
    Gauss-Legendre, ρ adaptively to the rim."""
    lam = LAM * 1e-9
    ti = math.radians(theta)
    m = np.array([-math.sin(ti), 0.0])
    xs, ws = np.polynomial.legendre.leggauss(64)
    total = 0.0
    for x, w in zip(xs, ws):
        p = math.pi * (x + 1)
        d = np.array([math.cos(p), math.sin(p)])
        b = m @ d
        rho_max = -b + math.sqrt(max(b * b - (m @ m - 1), 0.0))

        def integrand(rho):
            uv = m + rho * d
            co = math.sqrt(max(1 - uv @ uv, 0.0))
            return 16 * math.pi ** 2 / lam ** 4 * math.cos(ti) * co * Q(theta, (uv[0], uv[1], co)) \
                * abc_psd(rho / lam) * rho
        val, _ = spi.quad(integrand, 0.0, rho_max, points=[p_ for p_ in (lam / 3e-6, 10 * lam / 3e-6)
                                                            if p_ < rho_max] or None, limit=200, epsrel=1e-7)
        total += w * math.pi * val
    return total


def test_grazing_coherent_fraction_follows_first_order_rayleigh_rice():
    """σ = λ/50 on Al and with F = 1, θ_i 75–89°: the coherent fraction is within 2 % of 1 − TIS/R of first-order
    perturbation theory (Al: the vector Q; F = 1: the scalar Q = 1). Before: 0.89 / 0.78 / 0.58 at 85 / 88 / 89°
    for σ = 20 nm, where Rayleigh-Rice gives 0.96 / 0.98 / 0.99."""
    nano = twoscale.Nano(model=SMOOTH)
    eps = complex(AL.eta(LAM)) ** 2
    n = complex(AL.eta(LAM))
    for theta in (75.0, 80.0, 85.0, 88.0, 89.0):
        ci, si = math.cos(math.radians(theta)), math.sin(math.radians(theta))
        g = np.sqrt(n * n - si * si)
        R = 0.5 * (abs((ci - g) / (ci + g)) ** 2 + abs((n * n * ci - g) / (n * n * ci + g)) ** 2)
        A_rr = 1 - tis(theta, lambda t, wo: Q_unpolarized(t, wo, eps)) / R
        A = float(nano.coherent_fraction(ci, LAM, "kirchhoff", AL))
        assert A == pytest.approx(A_rr, rel=2e-2), (theta, A, A_rr)
        A1 = float(nano.coherent_fraction(ci, LAM, "kirchhoff", None))
        assert A1 == pytest.approx(1 - tis(theta, lambda t, wo: 1.0), rel=2e-2), (theta, A1)


def _albedo_about_mirror(f, theta, n_gamma=90, n_psi=64):
    """∫ f cosθ_o dω_o over the upper hemisphere in spherical coordinates (γ, ψ) about the mirror direction:
    γ geometric from 1e-5 to π (trapezoid), ψ midpoints; directions below the horizon contribute 0."""
    r = _dir(theta) * np.array([-1.0, 1.0, 1.0])          # mirror direction
    e1 = np.cross(r, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(r, e1)
    gam = np.concatenate([[0.0], np.geomspace(1e-5, math.pi, n_gamma)])
    psi = (np.arange(n_psi) + 0.5) * 2 * math.pi / n_psi
    G, P = np.meshgrid(gam, psi, indexing="ij")
    wo = (np.cos(G)[..., None] * r + np.sin(G)[..., None] * (np.cos(P)[..., None] * e1 + np.sin(P)[..., None] * e2))
    up = wo[..., 2] > 0
    wo_up = np.where(up[..., None], wo, [0.0, 0.0, 1.0])
    val = np.where(up, f(np.broadcast_to(_dir(theta), wo.shape).reshape(-1, 3), wo_up.reshape(-1, 3))
                   .reshape(up.shape) * wo[..., 2], 0.0)
    ring = val.mean(axis=1) * 2 * math.pi * np.sin(gam)
    return float(spi.trapezoid(ring, gam))


@pytest.mark.parametrize("model", [surfaces.PSDModel("gaussian", sigma=100e-9, T=1e-6),
                                   surfaces.PSDModel("abc", sigma=20e-9, B=3e-6, C=2.6)],
                         ids=["gaussian-100nm", "abc-20nm"])
def test_pointwise_white_furnace_up_to_grazing(model):
    """F = 1, micro α = 0.05: the pointwise two-scale function reflects at most 1.01 of the light and no less than
    the single-scattering microfacet albedo minus the diffracted light its facets shift (paraxially) beyond the
    horizon, θ_i 75–89.5° (the issue's Gaussian case reflected 1.149 at 89°). Measured shortfall: 1.4 % at 85° for
    the Gaussian σ = λ/5 lobe, ≤ 0.7 % for the ABC one; the facet convolution's geometry, not the energy split."""
    b = brdf.TwoScaleBRDF(material="Al", micro=twoscale.Micro(alpha=0.05, ndf="ggx"), nano=twoscale.Nano(model=model),
                          fresnel="one")
    mf = brdf.MicrofacetBRDF("Al", twoscale.Micro(alpha=0.05, ndf="ggx"), fresnel="one")
    for theta in (75.0, 85.0, 89.0, 89.5):
        a = _albedo_about_mirror(lambda wi, wo: b.eval(wi, wo, 500.0), theta)
        a_mf = _albedo_about_mirror(lambda wi, wo: mf.eval(wi, wo, 500.0), theta)
        assert a <= 1.01, (theta, a)
        assert a >= a_mf - 0.015, (theta, a, a_mf)


def test_grid_white_furnace_up_to_grazing():
    """F = 1 on the grid (twoscale.evaluate), mirror-like micro surface: coherent + diffracted = 1 within 1e-3 at
    every incidence up to 89.5°, and the energy guard does not act (it would warn)."""
    one = materials.get_material("f0:1")
    grid = DirectionGrid.hemisphere(96)
    for model in (surfaces.PSDModel("gaussian", sigma=40e-9, T=1e-6), surfaces.PSDModel("abc", sigma=20e-9, B=3e-6,
                                                                                          C=2.6)):
        for theta in (0.0, 60.0, 80.0, 85.0, 89.0, 89.5):
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                L = twoscale.evaluate(_dir(theta), [500.0], one, twoscale.Micro(alpha=0.0, ndf="ggx"),
                                      twoscale.Nano(model=model), grid, kd=0)
            total = float(np.sum(L.total[0][grid.inside])) * grid.du * grid.dv
            assert total == pytest.approx(1.0, abs=2e-3), (model.kind, theta, total)
            assert L.info["diffraction_energy_scale"] == [1.0]


def _scene(sigma, theta=None):
    d = {"name": "t", "materials": [{"name": "m", "material": "Al", "roughness": 0.05, "ndf": "ggx",
                                     "nano": {"statistics": f"abc:sigma={sigma},B=3um,C=2.8"}}],
         "lights": [{"name": "l", "spd": "D65", "directions_deg": [[theta if theta is not None else 30, 0]]}]}
    if theta is None:   # a sphere shows every incidence
        d.update(view={"camera": "sphere"}, output={"rgb_images": True})
    else:
        d.update(view={"directions_deg": [[theta, 180]]}, output={"rgb_images": False, "tables": True})
    return d


def test_planner_chooses_the_model_by_the_g_of_each_incidence():
    """σ = 10 nm: (4πσ/λ_min)² exceeds first-order theory's bound 0.05, but a light at 85° sees only
    g = (kσ_rel(cosθ_i + 1))² (a quarter of it and less): Rayleigh-Rice for that light, Kirchhoff for a sphere, whose
    facets see normal incidence too. (One Rayleigh number refused both.)"""
    from waveoptics.planning import parse, plan_scene

    grazing = plan_scene(parse(_scene("10nm", theta=85)), force={"diffraction": True}).entries[0]
    assert grazing.diffraction == "rayleigh-rice"
    assert plan_scene(parse(_scene("10nm")), force={"diffraction": True}).entries[0].diffraction == "kirchhoff"


def _rr_scalar(wi, wo):
    """The scalar first-order (Q = 1) lobe (16π²/λ⁴) cosθ_i cosθ_o S(|ω_i + ω_o|_xy / λ) of SMOOTH, written here."""
    lam = LAM * 1e-9
    s = wi + wo
    return 16 * math.pi ** 2 / lam ** 4 * wi[2] * wo[2] * abc_psd(math.hypot(s[0], s[1]) / lam)


@pytest.mark.parametrize("fresnel", ["one", "exact"])
def test_nano_lobe_hands_over_to_first_order_and_stays_reciprocal(fresnel):
    """A facet's nano lobe (TwoScaleBRDF.facet_nano_brdf, in the facet's frame) is the first-order Rayleigh-Rice lobe
    where either end is beyond 80° (F = 1: the scalar Q = 1 lobe; Al: the vector Q of Germer 1997, both written
    here) within 1e-9, and f(ω_i, ω_o) = f(ω_o, ω_i) to rounding at pairs inside the hand-over (70-80°), where
    the tangent-plane lobe's grazing scaling by its incidence alone was not reciprocal (issue 28)."""
    b = brdf.TwoScaleBRDF(material="Al", micro=twoscale.Micro(alpha=0.05, ndf="ggx"),
                          nano=twoscale.Nano(model=SMOOTH), fresnel=fresnel)
    eps = complex(AL.eta(LAM)) ** 2

    def wo_at(theta, phi):
        t, p = math.radians(theta), math.radians(phi)
        return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])

    for ti, to, phi in ((85.0, 30.0, 180.0), (82.0, 60.0, 120.0), (30.0, 84.0, 150.0), (89.0, 89.0, 170.0)):
        wi, wo = _dir(ti), wo_at(to, phi)
        ref = _rr_scalar(wi, wo)
        if fresnel == "exact":
            ref *= Q_unpolarized(ti, wo, eps)
        got = float(b.facet_nano_brdf(wi[None], wo[None], LAM)[0])
        assert got == pytest.approx(ref, rel=1e-9), (ti, to, phi, got, ref)
    for ti, to, phi in ((72.0, 40.0, 180.0), (75.0, 78.0, 100.0), (60.0, 79.0, 140.0), (71.0, 71.0, 170.0)):
        wi, wo = _dir(ti), wo_at(to, phi)
        a = float(b.facet_nano_brdf(wi[None], wo[None], LAM)[0])
        c = float(b.facet_nano_brdf(wo[None], wi[None], LAM)[0])
        assert a > 0 and a == pytest.approx(c, rel=1e-12), (ti, to, phi, a, c)
