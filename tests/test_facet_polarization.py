"""Polarized light on tilted micro facets (issue 28): a facet with normal m sees the macro s or p field split into its
own s and p parts, rotated by the angle η_i between the macro plane of incidence (ω_i, z) and its own (ω_i, m)
(Priest & Germer 2000), so it reflects and scatters cos²η_i X_pol + sin²η_i X_other of its own s and p responses.

Oracles written here: the rotation as the dihedral angle between the two planes of incidence (the projections of z
and m onto the plane normal to ω_i, a different construction from the library's cross products); the Fresnel
equations of a complex index (Born & Wolf §1.5.2, §14.2); the first-order total integrated scatter of s and p light
on glass from the Rayleigh-Rice polarization factors Q_ss + Q_sp and Q_pp + Q_ps (Elson & Bennett 1979; Germer 1997,
eqs. 17–20) by a polar quadrature about the mirror direction; Beckmann facets drawn from their Gaussian slope law
(seeded), weighted by ⟨ω_i·m⟩ / cos θ_m (the facets the light sees).
"""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from waveoptics import materials, surfaces
from waveoptics.brdf import facet_frame_diffraction, twoscale
from waveoptics.materials import cos2_eta_i, facet_sp_mix
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
N_GLASS = 1.5
SIGMA, B, C = 5e-9, 3e-6, 2.8
GLASS = materials.get_material("1.5")
MODEL = surfaces.PSDModel("abc", sigma=SIGMA, B=B, C=C)


def _dir(theta):
    t = math.radians(theta)
    return np.array([math.sin(t), 0.0, math.cos(t)])


def dihedral_cos2(wi, m):
    """cos² of the angle between the planes (ω_i, z) and (ω_i, m): z and m projected onto the plane normal to ω_i."""
    z = np.array([0.0, 0.0, 1.0])
    a = z - (z @ wi) * wi
    b = m - (m @ wi)[..., None] * wi
    return (b @ a) ** 2 / (np.sum(b * b, axis=-1) * (a @ a))


def beckmann_visible_facets(wi, alpha, n, seed):
    """(normals (n, 3), weights (n,)) of Beckmann facets: slopes from the Gaussian of variance α²/2 per axis (the
    slope law of the Beckmann NDF, D(m) cos θ_m dm = P(x̃, ỹ) dx̃ dỹ), weighted by ⟨ω_i·m⟩ / cos θ_m so that the
    weighted mean is the average over the facets the light sees (Walter et al. 2007, eq. 2 and §5.3)."""
    rng = np.random.default_rng(seed)
    s = rng.normal(0.0, alpha / math.sqrt(2.0), size=(n, 2))
    m = np.concatenate([-s, np.ones((n, 1))], axis=1)
    m /= np.linalg.norm(m, axis=1, keepdims=True)
    return m, np.maximum(m @ wi, 0.0) / m[:, 2]


def fresnel_rs_rp(cos_i, eta):
    """R_s, R_p of an interface air → η = n + iκ (Born & Wolf §1.5.2, §14.2)."""
    cos_i = np.asarray(cos_i, dtype=float)
    g = np.sqrt(eta ** 2 - (1 - cos_i ** 2) + 0j)
    return (np.abs((cos_i - g) / (cos_i + g)) ** 2, np.abs((eta ** 2 * cos_i - g) / (eta ** 2 * cos_i + g)) ** 2)


def abc_psd(f):
    """ABC PSD S(f) = A / (1 + (B f)²)^{C/2}, A from σ² = 2π A / (B² (C − 2)) (m⁴)."""
    A = SIGMA ** 2 * B ** 2 * (C - 2) / (2 * math.pi)
    return A / (1 + (B * np.asarray(f)) ** 2) ** (C / 2)


def tis_s_p(theta, n=N_GLASS):
    """First-order TIS of s and p light on a substrate of permittivity ε = n²: ∫ (16π²/λ⁴) cosθ_i cosθ_o Q S(f)
    du dv over the disc of direction cosines, Q_s = q_ss² + q_sp², Q_p = q_pp² + q_ps² (Germer 1997, eqs. 17–20;
    φ measured from the specular side), in polar coordinates (ρ, ψ) about the mirror point: 64 Gauss-Legendre
    azimuths, 256 radii ρ = ρ_max t³ (t Gauss-Legendre on [0, 1]) that gather about the mirror, where S peaks."""
    lam = LAM * 1e-9
    e = n * n
    ti = math.radians(theta)
    si, ci = math.sin(ti), math.cos(ti)
    x, w = np.polynomial.legendre.leggauss(64)
    psi, w_psi = math.pi * (x + 1), math.pi * w
    t, w_t = np.polynomial.legendre.leggauss(256)
    t, w_t = 0.5 * (t + 1), 0.5 * w_t
    dx, dy = np.cos(psi)[:, None], np.sin(psi)[:, None]
    b = -si * dx
    rho_max = -b + np.sqrt(b * b + ci * ci)            # |m + ρ d| = 1, m = (−sinθ_i, 0)
    rho, d_rho = rho_max * t ** 3, 3 * rho_max * t ** 2 * w_t
    u, v = -si + rho * dx, rho * dy
    so = np.hypot(u, v)
    co = np.sqrt(np.maximum(1 - so * so, 0.0))
    cphi = np.where(so > 0, -u / np.where(so > 0, so, 1), 1.0)
    sphi = np.where(so > 0, -v / np.where(so > 0, so, 1), 0.0)
    ri, ro = math.sqrt(e - si * si), np.sqrt(e - so * so)
    q_ss = (e - 1) * cphi / ((ci + ri) * (co + ro))
    q_sp = (e - 1) * ro * sphi / ((ci + ri) * (e * co + ro))
    q_pp = (e - 1) * (e * si * so - ri * ro * cphi) / ((e * ci + ri) * (e * co + ro))
    q_ps = -(e - 1) * ri * sphi / ((e * ci + ri) * (co + ro))
    base = 16 * math.pi ** 2 / lam ** 4 * ci * co * abc_psd(rho / lam) * rho * d_rho * w_psi[:, None]
    return float(np.sum(base * (q_ss ** 2 + q_sp ** 2))), float(np.sum(base * (q_pp ** 2 + q_ps ** 2)))


def _evaluate(theta, pol, alpha, diffraction, n=64, ndf="beckmann"):
    with warnings.catch_warnings():
        warnings.simplefilter("error")        # the energy guard warns when it acts: it must not
        return twoscale.evaluate(_dir(theta), [LAM], GLASS, twoscale.Micro(alpha=alpha, ndf=ndf),
                                 twoscale.Nano(model=MODEL), DirectionGrid.hemisphere(n), kd=0, polarization=pol,
                                 diffraction=diffraction, facet="frame")


def test_the_rotation_is_the_angle_between_the_planes_of_incidence():
    """cos²η_i against the dihedral angle of the two planes (seeded directions); 1 for facets tilted in the macro
    plane, 0 at normal incidence for a facet tilted across it; s and p mixes average to unpolarized light."""
    rng = np.random.default_rng(28)
    for _ in range(20):
        wi = rng.normal(size=3)
        wi[2] = abs(wi[2]) + 0.1
        wi /= np.linalg.norm(wi)
        m = rng.normal(size=(50, 3)) * [0.4, 0.4, 1.0]
        m[:, 2] = np.abs(m[:, 2]) + 0.2
        m /= np.linalg.norm(m, axis=1, keepdims=True)
        np.testing.assert_allclose(cos2_eta_i(wi, m), dihedral_cos2(wi, m), rtol=1e-9, atol=1e-12)
    wi = _dir(60.0)
    in_plane = np.array([[math.sin(a), 0.0, math.cos(a)] for a in (-0.3, 0.1, 0.5)])
    np.testing.assert_allclose(cos2_eta_i(wi, in_plane), 1.0, atol=1e-12)
    assert float(cos2_eta_i(np.array([0.0, 0.0, 1.0]), np.array([0.0, math.sin(0.2), math.cos(0.2)]))) < 1e-12
    c2 = rng.uniform(size=10)
    Xs, Xp = rng.uniform(size=10), rng.uniform(size=10)
    np.testing.assert_allclose(0.5 * (facet_sp_mix(Xs, Xp, c2, "s") + facet_sp_mix(Xs, Xp, c2, "p")),
                               facet_sp_mix(Xs, Xp, c2, "unpolarized"), rtol=1e-12)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_facets_reflect_the_rotated_mix_of_their_fresnel_reflectances(pol):
    """Glass at Brewster's angle, Beckmann α = 0.3: the light the facets reflect (:func:`facet_frame_diffraction`'s
    *reflected*, before masking) is the Monte-Carlo average over the facets the light sees of cos²η_i R_pol(θ_m) +
    sin²η_i R_other(θ_m) (Fresnel equations and the dihedral angle written here), within 2 % (64 quadrature normals
    against 40 000 seeded facets; measured s −0.01 %, p +0.9 %); each facet's own R_pol alone is 5.6 % (s) and
    36 % (p) off."""
    wi, alpha = _dir(math.degrees(math.atan(N_GLASS))), 0.3
    grid = DirectionGrid.hemisphere(24)
    F = materials.fresnel_function(GLASS, pol)
    _, _, reflected = facet_frame_diffraction(wi, [LAM], GLASS, twoscale.Micro(alpha=alpha, ndf="beckmann"),
                                              twoscale.Nano(model=MODEL), grid, F, polarization=pol)
    m, w = beckmann_visible_facets(wi, alpha, 40_000, seed=7)
    Rs, Rp = fresnel_rs_rp(np.clip(m @ wi, 0.0, 1.0), complex(GLASS.eta(LAM)))
    c2 = dihedral_cos2(wi, m)
    own, other = (Rs, Rp) if pol == "s" else (Rp, Rs)
    expected = float(np.sum(w * (c2 * own + (1 - c2) * other)) / np.sum(w))
    unrotated = float(np.sum(w * own) / np.sum(w))
    assert float(reflected[0]) == pytest.approx(expected, rel=2e-2)
    assert abs(unrotated / expected - 1) > (0.3 if pol == "p" else 0.04)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_glass_facets_scatter_the_rotated_mix_of_their_tis(pol):
    """Rayleigh-Rice nano lobe on glass carried by Beckmann facets (α = 0.3, 50°), facet frame: the light the code
    says the facets scatter (the diffracted albedo plus what is masked or sent below the horizon) is the
    Monte-Carlo average over the facets the light sees of cos²η_i TIS_pol(θ_m) + sin²η_i TIS_other(θ_m), the TIS
    from Q written here, within 2 % (measured: s +0.04 %, p −0.4 %); each facet's own TIS_pol alone is 5.2 % (s) and
    13 % (p) off. The lobe holds at most that light (measured 0.98 and 0.97 of it), and no guard acts."""
    wi, alpha, theta = _dir(50.0), 0.3, 50.0
    L = _evaluate(theta, pol, alpha, "rayleigh-rice")
    claimed = float(L.albedo("diffraction")[0]) + L.info["diffraction_beyond_horizon"][0]
    nodes = np.array([0.0, 10, 20, 30, 40, 50, 55, 60, 65, 70, 75, 80, 85, 89])
    tis = np.array([tis_s_p(t) for t in nodes])           # (n, 2): s, p
    m, w = beckmann_visible_facets(wi, alpha, 40_000, seed=11)
    th_m = np.degrees(np.arccos(np.clip(m @ wi, 0.0, 1.0)))
    T = {"s": np.interp(th_m, nodes, tis[:, 0]), "p": np.interp(th_m, nodes, tis[:, 1])}
    c2 = dihedral_cos2(wi, m)
    other = "p" if pol == "s" else "s"
    expected = float(np.sum(w * (c2 * T[pol] + (1 - c2) * T[other])) / np.sum(w))
    unrotated = float(np.sum(w * T[pol]) / np.sum(w))
    assert claimed == pytest.approx(expected, rel=2e-2)
    assert abs(unrotated / expected - 1) > (0.1 if pol == "p" else 0.04)
    assert L.info["diffraction_energy_scale"] == [1.0]
    assert 0.7 * claimed < float(L.albedo("diffraction")[0]) <= claimed


@pytest.mark.parametrize("diffraction", ["kirchhoff", "rayleigh-rice"])
def test_s_and_p_lobes_on_tilted_facets_lose_what_unpolarized_light_loses(diffraction):
    """GGX α = 0.1 at 20° on glass: the facets' lobes lose little to masking and the horizon, so the share of the
    facets' scattered light that the diffracted lobe holds is the same for s, p and unpolarized light within 1 %
    (measured, Kirchhoff: 0.984, 0.977, 0.981); the budget of each facet's own s or p albedo made it 0.953 and
    1.019, a p lobe holding more than the facets scatter. s and p average to unpolarized light (lobe and budget,
    1e-3)."""
    L = {p: _evaluate(20.0, p, 0.1, diffraction, ndf="ggx") for p in ("s", "p", "unpolarized")}
    held = {}
    for p, lobes in L.items():
        lobe = float(lobes.albedo("diffraction")[0])
        held[p] = lobe / (lobe + lobes.info["diffraction_beyond_horizon"][0])
        assert lobes.info["diffraction_energy_scale"] == [1.0]
    assert held["s"] == pytest.approx(held["unpolarized"], abs=1e-2)
    assert held["p"] == pytest.approx(held["unpolarized"], abs=1e-2)
    for part in ("diffraction", "coherent"):
        avg = 0.5 * (L["s"].albedo(part)[0] + L["p"].albedo(part)[0])
        assert avg == pytest.approx(float(L["unpolarized"].albedo(part)[0]), rel=1e-3), part
    budget = {p: float(L[p].albedo("diffraction")[0]) + L[p].info["diffraction_beyond_horizon"][0] for p in L}
    assert 0.5 * (budget["s"] + budget["p"]) == pytest.approx(budget["unpolarized"], rel=1e-3)


def test_a_metal_s_and_p_coherent_parts_average_to_unpolarized_on_tilted_facets():
    """Al, ABC σ = 10 nm, B = 1 µm (a wide lobe: its s and p shares differ), GGX α = 0.3 at 60°: each facet keeps
    (cos²η_i R_pol A_pol + sin²η_i R_other A_other) of its mixed reflectance coherently, so the s and p coherent
    albedos average to the unpolarized one, (R_s A_s + R_p A_p)/2 = R A facet by facet, within 2e-6 (measured
    4e-7, the grazing continuation's share; the facet's own A_pol left 5.3e-6); the Fresnel factor of each
    polarization at the mirror facet is the rotated one (the microfacet lobes average exactly, 1e-12)."""
    al = materials.get_material("Al")
    nano = twoscale.Nano(model=surfaces.PSDModel("abc", sigma=10e-9, B=1e-6, C=2.8))
    grid = DirectionGrid.hemisphere(48)
    L = {p: twoscale.evaluate(_dir(60.0), [LAM], al, twoscale.Micro(alpha=0.3, ndf="ggx"), nano, grid, kd=0,
                              polarization=p, facet="frame") for p in ("s", "p", "unpolarized")}
    for part, tol in (("coherent", 2e-6), ("microfacet", 1e-12)):
        avg = 0.5 * (L["s"].albedo(part)[0] + L["p"].albedo(part)[0])
        assert avg == pytest.approx(float(L["unpolarized"].albedo(part)[0]), rel=tol), part
    assert all(L[p].info["diffraction_energy_scale"] == [1.0] for p in L)
