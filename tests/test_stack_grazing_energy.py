"""Rough film stacks at grazing light in the two-scale BRDF (issues 28/33): the energy guard must not act, the
coherent part is the stack's reflectance quadrature, and with no micro facets the coherent and diffracted parts add
up to the flat stack's reflectance.

Independent references written here: the stack's reflectance by Airy's single-film formula (Born & Wolf §1.6.4,
Heavens ch. 4), the GGX NDF with height-correlated Smith masking (Walter et al. 2007; Heitz 2014) integrated over
half-vectors on a fine (θ_h, φ_h) grid, and the first-order TIS as the library's rough-film lobe integrated by a
polar midpoint rule over the hemisphere (not the library's polar quadrature).
"""
import warnings

import numpy as np
import pytest

from waveoptics.brdf import Micro, twoscale
from waveoptics.materials import get_material
from waveoptics.request import make_nano
from waveoptics.scatter import rayleigh_rice_lobe
from waveoptics.scatter.grid import DirectionGrid, integrate
from waveoptics.units import direction_from_angles

STACK = "Al|Al2O3:300nm"
NANO = "abc:sigma=15nm,B=2um,C=2.6"
LAM = 560.0
ALPHA = 0.05


@pytest.fixture(scope="module")
def setup():
    return get_material(STACK), make_nano(NANO, [LAM])


def airy_R(mat, cos_t, lam):
    """Unpolarized reflectance of one film on a substrate, from air (Airy summation; Born & Wolf §1.6.4)."""
    n2 = complex(np.ravel(mat.substrate.eta(lam))[0])
    film, d = mat.films[0]
    n1 = complex(np.ravel(film.eta(lam))[0])
    s2 = 1.0 - np.asarray(cos_t, dtype=float) ** 2
    q0 = np.sqrt(1.0 - s2 + 0j)
    q1, q2 = np.sqrt(n1 * n1 - s2 + 0j), np.sqrt(n2 * n2 - s2 + 0j)
    q1 = np.where(q1.imag < 0, -q1, q1)
    q2 = np.where(q2.imag < 0, -q2, q2)
    ph = np.exp(2j * (2 * np.pi / (lam * 1e-9)) * d * 1e-9 * q1)
    out = 0.0
    for rab in (lambda na, qa, nb, qb: (qa - qb) / (qa + qb),
                lambda na, qa, nb, qb: (nb * nb * qa - na * na * qb) / (nb * nb * qa + na * na * qb)):
        r01, r12 = rab(1.0, q0, n1, q1), rab(n1, q1, n2, q2)
        out = out + 0.5 * np.abs((r01 + r12 * ph) / (1 + r01 * r12 * ph)) ** 2
    return out


def ggx_reflectance(mat, theta_deg, lam):
    """∫ R(θ_d) G2 D (ω_i·h) / cos θ_i dω_h: the GGX microfacet lobe's albedo with the stack's R (Walter 2007
    eq. 20 with dω_o = 4 (ω_i·h) dω_h), GGX D and height-correlated Smith G2 = 1 / (1 + Λ_i + Λ_o)
    (Heitz 2014)."""
    t = np.radians(theta_deg)
    wi = np.array([np.sin(t), 0.0, np.cos(t)])
    x = np.concatenate([np.linspace(0, 12, 1200, endpoint=False), np.geomspace(12, 2e3, 300)])
    th = np.arctan(ALPHA * x)
    phi = (np.arange(360) + 0.5) * 2 * np.pi / 360
    TH, PH = np.meshgrid(th, phi, indexing="ij")
    h = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], axis=-1)
    ih = h @ wi
    wo = 2 * ih[..., None] * h - wi
    c = np.cos(TH)
    D = ALPHA ** 2 / (np.pi * c ** 4 * (ALPHA ** 2 + np.tan(TH) ** 2) ** 2)

    def lam_(z):
        z = np.clip(z, 1e-12, 1.0)
        return 0.5 * (-1 + np.sqrt(1 + ALPHA ** 2 * (1 - z * z) / (z * z)))
    ok = (ih > 0) & (wo[..., 2] > 0)
    G = np.where(ok, 1.0 / (1.0 + lam_(wi[2]) + lam_(wo[..., 2])), 0.0)
    f = airy_R(mat, np.clip(ih, 0, 1), lam) * G * D * np.clip(ih, 0, None) / wi[2] * np.sin(TH)
    # dω_h = sinθ dθ dφ on the nonuniform θ nodes (trapezoid in θ, midpoint in φ)
    return float(np.sum(np.trapezoid(f, th, axis=0)) * (2 * np.pi / phi.size))


def tis_reference(nano, mat, theta_deg, lam):
    """∫ f_RR cos θ_o dω_o over the hemisphere by the polar midpoint rule (φ symmetric about the plane)."""
    t = np.radians(theta_deg)
    wi = np.array([np.sin(t), 0.0, np.cos(t)])
    n_t, n_p = 360, 360
    tho = (np.arange(n_t) + 0.5) * (np.pi / 2) / n_t
    pho = (np.arange(n_p) + 0.5) * np.pi / n_p
    TH, PH = np.meshgrid(tho, pho, indexing="ij")
    wo = np.stack([np.sin(TH) * np.cos(PH), np.sin(TH) * np.sin(PH), np.cos(TH)], axis=-1)
    f = rayleigh_rice_lobe(wi, wo, lam, nano.model, mat)
    return float(2 * np.sum(f * np.cos(TH) * np.sin(TH)) * (np.pi / 2 / n_t) * (np.pi / n_p))


def _evaluate(theta, mat, nano, micro, res):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        L = twoscale.evaluate(direction_from_angles(theta, 0.0), [LAM], mat, micro, nano,
                              DirectionGrid.hemisphere(res), diffraction="rayleigh-rice")
    return L, [str(w.message) for w in caught if "energy guard" in str(w.message)]


def test_airy_reference_matches_stack(setup):
    mat, _ = setup
    c = np.cos(np.radians([0.0, 60.0, 80.0, 86.0, 89.0]))
    assert np.allclose(mat.F(c, LAM), airy_R(mat, c, LAM), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("res", [32, 64])
def test_guard_does_not_act_on_stack_at_grazing(setup, res):
    """Before: at 89° the budget was 0.0045 against a lobe of 0.021 (78 % removed): the coherent part read the
    stack's R(θ) at cell centres (0.673 against 0.610 on 32²), and facets beyond 88° carried the 88° lobe."""
    mat, nano = setup
    for theta in (80.0, 86.0, 89.0):
        L, warned = _evaluate(theta, mat, nano, Micro(alpha=ALPHA, ndf="ggx"), res)
        assert L.info["facet_integration"] == "frame"
        assert L.info["diffraction_energy_scale"] == [1.0], (theta, res, warned)
        assert not warned


@pytest.mark.parametrize("theta", [86.0, 89.0])
def test_stack_coherent_part_against_ggx_quadrature(setup, theta):
    """The plain microfacet lobe of the stack on 32² cells against the half-vector quadrature with Airy's R
    (measured 0.8 % at 89°; it was 10 % above, 0.692 against 0.630, with R read at the cell centres), and the
    coherent part below it by at most the facets' first-order scatter (their local incidences spread a few degrees
    below θ_i, where the stack's TIS is larger: 0.0152 at 89°, 0.022 at 86°)."""
    mat, nano = setup
    L, _ = _evaluate(theta, mat, nano, Micro(alpha=ALPHA, ndf="ggx"), 32)
    ref = ggx_reflectance(mat, theta, LAM)
    assert L.albedo("microfacet")[0] == pytest.approx(ref, rel=0.015)
    loss = L.albedo("microfacet")[0] - L.albedo("coherent")[0]
    assert 0.0 < loss < 1.05 * max(tis_reference(nano, mat, t, LAM) for t in (theta - 4, theta - 2, theta))


@pytest.mark.parametrize("theta", [80.0, 86.0, 89.0])
def test_no_facets_stack_coherent_plus_diffracted(setup, theta):
    """α = 0: coherent + diffracted against the flat stack's R (Airy) and the diffracted part against the TIS of
    the rough-film lobe integrated here, each within 2 %."""
    mat, nano = setup
    L, warned = _evaluate(theta, mat, nano, Micro(alpha=0.0), 32)
    R = float(airy_R(mat, np.cos(np.radians(theta)), LAM))
    tis = tis_reference(nano, mat, theta, LAM)
    coh, diff = L.albedo("coherent")[0], L.albedo("diffraction")[0]
    assert L.info["diffraction_energy_scale"] == [1.0] and not warned
    assert diff == pytest.approx(tis, rel=0.02)
    assert coh == pytest.approx(R - tis, rel=0.02)
    assert coh + diff == pytest.approx(R, rel=0.02)


@pytest.mark.parametrize("spec", ["Al|Al2O3:120nm", "1.5|TiO2:60nm"])
def test_beyond_the_tangent_plane_a_stacks_facet_lobe_is_elsons_first_order(spec):
    """From 80° of incidence the facet's nano lobe is handed over in full to first order: for a stack, Elson's
    rough-stack lobe (the nano PSD on every interface, correlated), whose TIS is written here as that lobe integrated
    by a midpoint rule in (θ_o, φ_o) over the hemisphere (not the library's polar quadrature). The blended lobe's
    albedo equals it within 2.5 % at 80, 85 and 88° (measured ≤ 1.2 %; the scalar Q = 1 lobe times the stack's F it
    took before held 0.31-0.50 of it). Known: at 75°, in the hand-over, the Kirchhoff lobe with the stack's F is 2×
    Elson's TIS on Al|Al2O3:120nm (1.07× on bare Al), so the blend there is 1.33-1.41×."""
    from waveoptics.scatter import band

    material = get_material(spec)
    m = make_nano("abc:sigma=5nm,B=3um,C=2.8", [550.0]).model
    bs = band.band_series(m, 550.0)
    n_t, n_p = 720, 360
    t = (np.arange(n_t) + 0.5) * (np.pi / 2 / n_t)
    p = (np.arange(n_p) + 0.5) * (2 * np.pi / n_p)
    T, P = np.meshgrid(t, p, indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    for th in (80.0, 85.0, 88.0):
        wi = np.broadcast_to(direction_from_angles(th, 0.0), wo.shape)
        f = rayleigh_rice_lobe(wi, wo, 550.0, m, material).reshape(n_t, n_p)
        tis = float(np.sum(f * (np.cos(T) * np.sin(T))) * (np.pi / 2 / n_t) * (2 * np.pi / n_p))
        got = float(bs.scattered_albedo(th, "kirchhoff", material=material, absolute=True))
        assert got == pytest.approx(tis, rel=0.025), (th, got / tis)
