"""polar_albedo over an array of incidences (one quadrature for all of them, as the band series' albedo tables use
it) against a closed form: a Gaussian lobe about the mirror point in direction cosines, cut by the rim of the
disc, whose albedo reduces to a one-dimensional integral over the azimuth about the mirror point."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from waveoptics.scatter import polar_albedo

K = 2 * math.pi / 500e-9          # wave number (1/m)
S = 0.1                           # lobe width in direction cosines
THETAS_DEG = np.array([0.0, 30.0, 60.0, 80.0, 88.0])


def gaussian_lobe(wi, wo, q):
    """exp(−ρ²/2s²) / (2π s²), ρ = q/k the distance from the mirror point in direction cosines (1/sr)."""
    rho = q / K
    return np.exp(-rho ** 2 / (2 * S ** 2)) / (2 * math.pi * S ** 2) + 0.0 * wo[..., 2]


def closed_form(theta_deg):
    """∫ f du dv over the unit disc: in polar coordinates (ρ, ψ) about the mirror point (−a, 0) the radial integral
    is 1 − exp(−t²/2s²) up to the rim, t(ψ) = a cos ψ + √(1 − a² sin² ψ); the azimuth by adaptive quadrature."""
    a = math.sin(math.radians(theta_deg))

    def radial(psi):
        t = a * math.cos(psi) + math.sqrt(1.0 - (a * math.sin(psi)) ** 2)
        return -math.expm1(-t * t / (2 * S ** 2)) / (2 * math.pi)
    val, _ = integrate.quad(radial, 0.0, 2 * math.pi, epsabs=0.0, epsrel=1e-12, limit=200)
    return val


def test_an_array_of_incidences_matches_the_closed_form_and_one_call_each():
    got = polar_albedo(np.radians(THETAS_DEG), K, 1e-6, gaussian_lobe)
    assert got.shape == THETAS_DEG.shape
    ref = np.array([closed_form(t) for t in THETAS_DEG])
    assert ref[-1] < 0.6            # at 88° the rim cuts the lobe
    # measured: ≤ 1.3e-9 relative up to 60°, 2.9e-5 at 80°; 4.1e-3 at 88°, where the rim crosses the lobe and the
    # 24 azimuths resolve its cut coarsely
    np.testing.assert_array_less(np.abs(got / ref - 1.0), [1e-8, 1e-8, 1e-8, 1e-4, 6e-3])
    one = np.array([polar_albedo(math.radians(t), K, 1e-6, gaussian_lobe) for t in THETAS_DEG])
    np.testing.assert_allclose(got, one, rtol=1e-12, atol=0.0)


def test_a_scalar_incidence_gives_a_float():
    assert isinstance(polar_albedo(0.3, K, 1e-6, gaussian_lobe), float)
    assert polar_albedo(0.3, K, 1e-6, gaussian_lobe) == pytest.approx(closed_form(math.degrees(0.3)), rel=1e-8)


@pytest.mark.parametrize("theta_deg", [0.0, 30.0, 60.0, 80.0, 88.0, 89.9])
def test_a_constant_and_a_one_over_cosine_lobe_fill_the_disc_and_the_hemisphere(theta_deg):
    """f = 1: ∫ du dv over the unit disc = π, whatever the incidence (the nodes cover the disc once); f = 1/cosθ_o:
    ∫ f cosθ_o dω_o = ∫ dω = 2π, which tests the substitution q = q_rim − τ² at the horizon, where the integrand
    grows as 1/√(q_rim − q) (measured: ≤ 1.2e-11 up to 60°, 1.8e-6 at 80°, 4.1e-4 at 88°, 7.1e-4 at 89.9°)."""
    t = math.radians(theta_deg)
    assert polar_albedo(t, K, 1e-6, lambda wi, wo, q: 1.0 + 0.0 * q) == pytest.approx(math.pi, rel=1e-12)
    tol = 1e-10 if theta_deg <= 60 else 1e-5 if theta_deg <= 80 else 1.5e-3
    assert polar_albedo(t, K, 1e-6, lambda wi, wo, q: 1.0 / wo[..., 2]) == pytest.approx(2 * math.pi, rel=tol)


def _fresnel_unpolarized(cos_i, n):
    """(R_s + R_p)/2 of an interface of complex index n (Born & Wolf §1.5.2, §14.2), written here."""
    sin2 = 1.0 - cos_i ** 2
    cos_t = np.sqrt(1.0 - sin2 / n ** 2 + 0j)
    rs = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    rp = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (np.abs(rs) ** 2 + np.abs(rp) ** 2)


def test_relative_facet_fresnel_of_a_broadcast_incidence():
    """The weight of the band lobe's albedo, F(θ_h)/F(θ_i), with ω_i broadcast over the directions (its specular
    reflectance taken once per incidence) against the Fresnel formula."""
    from waveoptics.materials import RelativeFacetFresnel, get_material

    al = get_material("Al")
    n = complex(al.eta(550.0))
    rng = np.random.default_rng(3)
    th = np.radians([10.0, 45.0, 75.0])
    wi = np.stack([np.sin(th), 0.0 * th, np.cos(th)], axis=-1)[:, None, :]          # (3, 1, 3)
    wo = rng.normal(size=(3, 50, 3))
    wo[..., 2] = np.abs(wo[..., 2])
    wo /= np.linalg.norm(wo, axis=-1, keepdims=True)
    wi_b = np.broadcast_to(wi, wo.shape)
    got = RelativeFacetFresnel(al, "unpolarized").at(wi_b, wo, 550.0)
    h = wi_b + wo
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    ref = _fresnel_unpolarized(np.sum(h * wi_b, axis=-1), n) / _fresnel_unpolarized(wi_b[..., 2], n)
    assert got.shape == (3, 50)
    np.testing.assert_allclose(got, ref, rtol=1e-12)
