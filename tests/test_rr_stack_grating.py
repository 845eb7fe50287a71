"""The Rayleigh method for gratings on the interfaces of a thin-film stack (tests/rr_stack_grating.py), and the
library's first-order scatter of a rough stack (waveoptics.scatter.rough_film.rough_stack_components, Elson) held
against it.

References held against the solver (written here): the Airy one-film reflection and transmission amplitudes with the
Fresnel coefficients (Born & Wolf §1.6.4, §1.5.2), oblique and conical, transparent and absorbing film, metal
substrate; the two-media Rayleigh solve of tests/rr_grating.py (no films); energy conservation of a lossless stack;
convergence in the number of orders; an index-matched film (a grating on a non-interface scatters nothing); an
opaque metal film against the metal substrate (bounded exponentials).

Against the library: every propagating reflected ±1 order, s and p incident, s and p analyzed, for a rough top
interface, a rough bottom interface, both (correlated: same amplitude and phase) and both with a phase shift φ
(the mean of ±φ is the partially correlated stack, c = cos φ), for MgF₂ on BK7, TiO₂ on glass and an oxide on a
metal; TiO₂/MgF₂ on BK7 (three interfaces); stack_order_bsdf at seeded random directions (also the library's
single-interface BTDF without films). The mapping of the first-order BRDF with a delta PSD to an order's efficiency is that of
tests/test_rr_transmission.py: a profile a cos(2π f₀·x) has the two-sided PSD (a²/4)[δ(f − f₀) + δ(f + f₀)], and
d²f = (n/λ)² cosθ_o dΩ_o, so ∫ f_r cosθ_o dΩ_o over order +1 is (λ/n)² (a²/4) f_r|_{S=1}; for an interface of a
stack the profile and its PSD enter the same way.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from rr_grating import grating_solve
from rr_stack_grating import stack_grating_solve, stack_integrated_losses, stack_order_bsdf, stack_specular_losses
from waveoptics.scatter.rough_film import rough_stack_components
from waveoptics.scatter.transmission import rr_brdf_components, rr_btdf_components

LAM_NM = 550.0
LAM = LAM_NM * 1e-9
KA = 1e-3              # grating amplitude × the largest |n| k₀
TOL_AIRY = 1e-12       # measured ≤ 8e-16 on the amplitudes
TOL_TWO_MEDIA = 1e-10
TOL_ORDER = 5e-6       # first order vs rigorous at KA, O((k a)²): measured ≤ 1.9e-6 (1.9e-8 at KA = 1e-4)
KA_FINE = 1e-4         # seeded random directions: the O((k a)²) term reaches 1.5e-5 at KA (1.5e-7 here)
TOL_FINE = 5e-7


def _fresnel(e_i, e_j, g_i, g_j, pol):
    """(r_ij, t_ij) of one interface, Born & Wolf §1.5.2 with γ = n cosθ (complex allowed): s, and p (∥)."""
    if pol == "s":
        return (g_i - g_j) / (g_i + g_j), 2 * g_i / (g_i + g_j)
    den = e_j * g_i + e_i * g_j
    return (e_j * g_i - e_i * g_j) / den, 2 * np.sqrt(e_i) * np.sqrt(e_j) * g_i / den


def _airy(n0, n1, d, n2, kx, pol):
    """(r, t) of one film (index n1, thickness d in 1/k₀) between n0 (light) and n2, lateral wave number kx (units
    of k₀): r = (r₀₁ + r₁₂ e^{2iβ}) / (1 + r₀₁ r₁₂ e^{2iβ}), t = t₀₁ t₁₂ e^{iβ} / (1 + r₀₁ r₁₂ e^{2iβ}), β = γ₁ d
    (Born & Wolf §1.6.4, eqs. 57–58)."""
    e = [complex(n) ** 2 for n in (n0, n1, n2)]
    g = [np.sqrt(x - kx * kx) for x in e]
    g = [-x if x.imag < 0 else x for x in g]
    r01, t01 = _fresnel(e[0], e[1], g[0], g[1], pol)
    r12, t12 = _fresnel(e[1], e[2], g[1], g[2], pol)
    ph = np.exp(1j * g[1] * d)
    den = 1 + r01 * r12 * ph * ph
    return (r01 + r12 * ph * ph) / den, t01 * t12 * ph / den, g


@pytest.mark.parametrize("n0, n1, n2", [(1.0, 1.38, 1.5168), (1.0, 2.0 + 0.3j, 1.5168), (1.0, 1.65, 1.2 + 7j),
                                        (1.5168, 1.38, 1.0)])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_flat_film_is_airy(n0, n1, n2, pol):
    """a = 0: the specular amplitudes (r at the top, t at the film's lower face) and R, T equal Airy's one-film
    sums, oblique and conical (the s/p basis follows the plane of incidence), transparent, absorbing film, metal,
    and from the glass side (the reversed stack; at 62° beyond the critical angle, T = 0)."""
    d = 2 * np.pi * 130.0 / LAM_NM
    for th, az in ((0.0, 0.0), (35.0, 0.0), (62.0, 40.0)):
        kx = n0 * math.sin(math.radians(th))
        res = stack_grating_solve(n0, [(n1, d)], n2, kx * math.cos(math.radians(az)),
                                  kx * math.sin(math.radians(az)), 0.8, 0.0, pol, M=2)
        r, t, g = _airy(n0, n1, d, n2, kx, pol)
        assert abs(res["r0"][pol] - r) < TOL_AIRY
        assert abs(res["r"][2, "ps".index(pol)]) < TOL_AIRY                 # no cross-polarized specular
        assert abs(res["R"]["total"][2] - abs(r) ** 2) < TOL_AIRY
        transparent = complex(n2).imag == 0
        T = g[2].real / g[0].real * abs(t) ** 2 if transparent else 0.0
        assert abs(res["T"]["total"][2] - T) < TOL_AIRY
        if transparent:
            assert abs(res["t0"][pol] - t) < TOL_AIRY
        assert all(res["R"]["total"][j] == 0 and res["T"]["total"][j] == 0 for j in (0, 1, 3, 4))


@pytest.mark.parametrize("n_i, n_o, alpha0, beta0, K, a", [(1.0, 1.5, 0.3, 0.2, 0.7, 0.02),
                                                           (1.5, 1.0, 1.1, 0.4, 1.2, 0.03),
                                                           (1.33, 1.7, 0.05, 0.0, 0.5, 0.05)])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_no_films_is_the_two_media_solve(n_i, n_o, alpha0, beta0, K, a, pol):
    """Without films the stack solver is tests/rr_grating.py's grating_solve: every order, s and p analyzed."""
    ref = grating_solve(n_i, n_o, alpha0, beta0, K, a, pol, M=3)
    got = stack_grating_solve(n_i, [], n_o, alpha0, beta0, K, a, pol, M=3)
    for X in ("R", "T"):
        for b in "sp":
            np.testing.assert_allclose(got[X][b], ref[X][b], rtol=0, atol=TOL_TWO_MEDIA)
    np.testing.assert_allclose(got["kr"], ref["kr"], rtol=0, atol=1e-15)


STACK2 = [(2.4, 2 * np.pi * 60.0 / LAM_NM), (1.38, 2 * np.pi * 100.0 / LAM_NM)]    # TiO₂ / MgF₂ on glass


def test_lossless_stack_conserves_energy_and_converges():
    """Two films, three gratings of different amplitudes and phases (k a up to 0.05 in TiO₂), conical: Σ R + Σ T
    = 1 at M = 3 (the truncation's own imbalance: 2e-12 at M = 2, 1e-15 at M = 3); the propagating ±1 orders of
    M = 2 and M = 3 agree (measured ≤ 7e-8 relative)."""
    a, phi = [0.02, 0.013, 0.017], [0.0, 1.0, 2.5]
    for pol in "sp":
        res = {M: stack_grating_solve(1.0, STACK2, 1.5168, 0.2, 0.3, 0.6, a, pol, M=M, phi=phi) for M in (2, 3)}
        assert abs(res[3]["R"]["total"].sum() + res[3]["T"]["total"].sum() - 1.0) < 1e-12
        for X in ("R", "T"):
            e2, e3 = res[2][X]["total"][[1, 3]], res[3][X]["total"][[2, 4]]
            assert np.all(e3 > 1e-6), (pol, X, e3)
            assert np.max(np.abs(e2 / e3 - 1)) < 1e-6, (pol, X, e2, e3)


def test_opaque_metal_film_is_a_metal_substrate():
    """A 2 µm metal film (n = 1.2 + 7i, attenuation e^{−160} across it) over glass reflects every order as the
    semi-infinite metal does, and transmits nothing: the layer-referenced exponentials stay bounded (a formulation
    with e^{+|γ| d} would overflow or lose the reflected orders to rounding)."""
    oxide = (1.65, 2 * np.pi * 50.0 / LAM_NM)
    for pol in "sp":
        film = stack_grating_solve(1.0, [oxide, (1.2 + 7j, 2 * np.pi * 2000.0 / LAM_NM)], 1.5168, 0.3, 0.2, 0.7,
                                   [0.01, 0.01, 0.01], pol, M=3)
        bulk = stack_grating_solve(1.0, [oxide], 1.2 + 7j, 0.3, 0.2, 0.7, [0.01, 0.01], pol, M=3)
        np.testing.assert_allclose(film["r"], bulk["r"], rtol=0, atol=1e-14)       # measured 8e-16
        assert film["T"]["total"].max() < 1e-100
        assert film["R"]["total"][2] > 1e-6                                        # order −1 propagates


def test_index_matched_film_does_not_scatter():
    """A film with the index of the substrate and a grating only on its lower face (no index step there): the ±1
    orders vanish, against the same grating under a film of another index."""
    d = 2 * np.pi * 90.0 / LAM_NM
    for pol in "sp":
        on = stack_grating_solve(1.0, [(1.5168, d)], 1.5168, 0.3, 0.1, 0.5, [0.0, 0.01], pol, M=2)
        ref = stack_grating_solve(1.0, [(1.9, d)], 1.5168, 0.3, 0.1, 0.5, [0.0, 0.01], pol, M=2)
        for X in ("R", "T"):
            scale = ref[X]["total"][[1, 3]].min()
            assert scale > 1e-7
            assert on[X]["total"][[1, 3]].max() < 1e-20 * scale, (pol, X)


class UnitPSD:
    """S = 1 m⁴ everywhere: f / S of the library, the BRDF per unit PSD."""
    length_scale = 1e-6

    def S(self, f):
        return np.ones_like(np.asarray(f, dtype=float))


STACKS = {"MgF2 on BK7": (1.5168, 1.38, 100.0), "TiO2 on glass": (1.5168, 2.4, 120.0),
          "oxide on metal": (1.2 + 7j, 1.65, 50.0)}
ROUGH = {"top": (1.0, 0.0), "bottom": (0.0, 1.0), "both": (1.0, 1.0)}
# (θ_i deg, azimuth of the incidence deg, K / k₀): conical, near-normal, in plane (grazing), backward
MOUNTS = [(30.0, 17.0, 0.7), (0.5, 60.0, 0.8), (70.0, 0.0, 0.9), (50.0, 120.0, 0.4)]


def _wi(th, az):
    t, p = math.radians(th), math.radians(az)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def _order_rows(stack, mount, rough, pol, phi=0.0, correlation="correlated"):
    """[(order, analyzed b, rigorous, library, largest efficiency of the order)] of the propagating reflected ±1
    orders; the rigorous efficiency is the mean over the bottom profile's phase ±φ (φ = 0: one solve)."""
    ns, nf, d = stack
    wi = _wi(*mount[:2])
    a = KA / max(abs(ns), nf)
    sols = [stack_grating_solve(1.0, [(nf, 2 * np.pi * d / LAM_NM)], ns, -wi[0], -wi[1], mount[2],
                                [a * rough[0], a * rough[1]], pol, M=3, phi=[0.0, s * phi])
            for s in ((1, -1) if phi else (1,))]
    psds = [UnitPSD() if rough[1] else None, UnitPSD() if rough[0] else None]     # the library: substrate first
    a_m = a * LAM / (2 * np.pi)
    out = []
    for j in np.flatnonzero(np.abs(sols[0]["orders"]) == 1):
        kv = sols[0]["kr"][j]
        if abs(kv[2].imag) > 1e-12:
            continue
        f = rough_stack_components(wi, kv.real, LAM_NM, (ns, [nf], [d]), psds, correlation)
        for b in "sp":
            rig = np.mean([s["R"][b][j] for s in sols])
            out.append((sols[0]["orders"][j], b, rig, LAM ** 2 * a_m ** 2 / 4 * f[pol + b],
                        max(s["R"]["total"][j] for s in sols)))
    return out


def _assert_orders(rows, label):
    assert rows, label
    for m, b, rig, lib, big in rows:
        # cross-polarized in-plane orders vanish in both (0 = 0): compared against the order's total instead
        assert abs(lib - rig) <= TOL_ORDER * max(rig, 1e-6 * big), (label, m, b, rig, lib, lib / rig)


@pytest.mark.parametrize("stack", STACKS)
@pytest.mark.parametrize("rough", ROUGH)
@pytest.mark.parametrize("pol", ["s", "p"])
def test_rough_stack_orders_match_rigorous_grating(stack, rough, pol):
    """Every propagating reflected ±1 order, s and p analyzed, in four mounts: the library's first-order BRDF of
    the stack with a delta PSD equals the rigorous efficiency to O((k a)²)."""
    for mount in MOUNTS:
        _assert_orders(_order_rows(STACKS[stack], mount, ROUGH[rough], pol), (stack, rough, pol, mount))


@pytest.mark.parametrize("stack", ["TiO2 on glass", "oxide on metal"])
@pytest.mark.parametrize("phi", [1.1, np.pi / 2])
def test_partly_correlated_interfaces(stack, phi):
    """Both interfaces rough, the lower profile shifted by ±φ: the mean of the two rigorous efficiencies is the
    library's stack with cross-correlation c = cos φ (π/2: 'uncorrelated')."""
    c = "uncorrelated" if phi == np.pi / 2 else math.cos(phi)
    for pol in "sp":
        _assert_orders(_order_rows(STACKS[stack], MOUNTS[0], (1.0, 1.0), pol, phi=phi, correlation=c),
                       (stack, phi, pol))


class ScaledUnitPSD(UnitPSD):
    """S = r² m⁴ everywhere: an interface whose profile is r times the common one."""

    def __init__(self, r):
        self.r = r

    def S(self, f):
        return self.r ** 2 * super().S(f)


@pytest.mark.parametrize("rough", [(1.0, 1.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0),
                                   (1.0, 0.5, 0.7)])
def test_two_film_stack_orders_match_rigorous_grating(rough):
    """TiO₂ 60 nm over MgF₂ 100 nm on BK7 (three interfaces, top first here, the library's substrate first), one
    interface rough at a time, all three correlated, and correlated with amplitudes 1, 0.5, 0.7 (the library's
    S_j = r_j² S): every propagating reflected ±1 order, s and p in and analyzed, four mounts (measured ≤ 1.4e-6)."""
    films = [(2.4, 60.0), (1.38, 100.0)]
    a = KA / 2.4
    a_m = a * LAM / (2 * np.pi)
    layers = (1.5168, [n for n, _ in films][::-1], [d for _, d in films][::-1])
    psds = [ScaledUnitPSD(r) if r else None for r in rough[::-1]]
    for mount in MOUNTS:
        wi = _wi(*mount[:2])
        for pol in "sp":
            res = stack_grating_solve(1.0, [(n, 2 * np.pi * d / LAM_NM) for n, d in films], 1.5168, -wi[0],
                                      -wi[1], mount[2], a * np.array(rough), pol, M=3)
            rows = []
            for j in np.flatnonzero((np.abs(res["orders"]) == 1) & (np.abs(res["kr"][:, 2].imag) < 1e-12)):
                f = rough_stack_components(wi, res["kr"][j].real, LAM_NM, layers, psds, "correlated")
                rows += [(res["orders"][j], b, res["R"][b][j], LAM ** 2 * a_m ** 2 / 4 * f[pol + b],
                          res["R"]["total"][j]) for b in "sp"]
            _assert_orders(rows, (rough, mount, pol))


def test_order_bsdf_at_seeded_directions():
    """stack_order_bsdf (the grating chosen from ω_i, ω_o) at seeded random directions: without films it is the
    library's single-interface Rayleigh-Rice BRDF and BTDF (air → glass, into both half-spaces); with a TiO₂ film
    on glass, rough top, bottom or both, the library's rough_stack_components (at k a = 1e-4: measured ≤ 1.5e-7; at
    1e-3 the same geometries give ≤ 1.5e-5, the O((k a)²) of the rigorous solve)."""
    rng = np.random.default_rng(1983)
    for _ in range(6):
        th, az = rng.uniform(0.0, 80.0, 2), rng.uniform(0.0, 360.0, 2)
        wi, wo = _wi(th[0], az[0]), _wi(th[1], az[1])
        for z in (1.0, -1.0):
            w = wo * [1.0, 1.0, z]
            got = stack_order_bsdf(1.0, [], 1.5, wi, w, LAM, ka=KA_FINE)
            ref = (rr_brdf_components if z > 0 else rr_btdf_components)(wi, w, LAM_NM, UnitPSD(), 1.0, 1.5)
            for ab in got:
                assert abs(got[ab] / ref[ab] - 1) < TOL_FINE, (wi, w, ab, got[ab], ref[ab])
        for rough in ROUGH.values():
            got = stack_order_bsdf(1.0, [(2.4, 120e-9)], 1.5168, wi, wo, LAM, rough=rough, ka=KA_FINE)
            psds = [UnitPSD() if rough[1] else None, UnitPSD() if rough[0] else None]
            ref = rough_stack_components(wi, wo, LAM_NM, (1.5168, [2.4], [120.0]), psds)
            for ab in got:
                assert abs(got[ab] / ref[ab] - 1) < TOL_FINE, (wi, wo, rough, ab, got[ab], ref[ab])


def test_specular_losses_of_a_stack():
    """The helpers' second-order specular losses: without films they are tests/rr_grating.py's (the same solve);
    for a lossless coated glass ΔR₀ + ΔT₀ per a²/4 equals the first-order scatter of the ±1 orders (reflected
    and transmitted) per a²/4, both from the same rigorous solve (optical theorem to second order)."""
    from rr_grating import specular_losses

    wi = _wi(30.0, 0.0)
    got = stack_specular_losses(1.0, [], 1.5, wi, 0.6e6, 0.8e6, LAM, "p")
    ref = specular_losses(1.0, 1.5, wi, 0.6e6, 0.8e6, LAM, "p")
    np.testing.assert_allclose(got, ref, rtol=1e-8)    # (1 − R₀ − T₀) / a²: rounding ~1e-9
    films = [(2.4, 60e-9), (1.38, 100e-9)]
    dR, dT = stack_specular_losses(1.0, films, 1.5168, wi, 0.6e6, 0.8e6, LAM, "s", rough=[1.0, 0.5, 0.7])
    k0 = 2 * np.pi / LAM
    kap, c, s = 1e6 * LAM, 0.6, 0.8
    a = 2e-3 / 2.4
    res = stack_grating_solve(1.0, [(n, k0 * d) for n, d in films], 1.5168, -c * wi[0], s * wi[0], kap,
                              a * np.array([1.0, 0.5, 0.7]), "s", M=1)
    scatter = res["R"]["total"][[0, 2]].sum() + res["T"]["total"][[0, 2]].sum()
    assert abs((dR + dT) / (scatter / ((a / k0) ** 2 / 4)) - 1) < 1e-6       # measured 2.5e-8
    assert dR != 0 and dT != 0


def test_integrated_losses():
    """stack_integrated_losses: without films it is tests/rr_grating.py's integrated_losses (same quadrature);
    'uncorrelated' is the sum of the single rough interfaces; 'correlated' (one profile on both) differs from it."""
    from rr_grating import integrated_losses

    def psd(f):
        return 1e-18 * 1e-12 * np.exp(-(np.pi * f * 1e-6) ** 2)     # Gaussian-like S (m⁴), T = 1 µm
    wi = _wi(20.0, 0.0)
    kw = dict(n_rho=6, n_psi=4)
    np.testing.assert_allclose(stack_integrated_losses(1.0, [], 1.5, wi, psd, 1e-6, LAM, "p", **kw),
                               integrated_losses(1.0, 1.5, wi, psd, 1e-6, LAM, "p", **kw), rtol=1e-8)
    films = [(1.38, 100e-9)]
    one = [stack_integrated_losses(1.0, films, 1.5168, wi, psd, 1e-6, LAM, "s", rough=r, **kw)
           for r in ([1.0, 0.0], [0.0, 1.0])]
    both = stack_integrated_losses(1.0, films, 1.5168, wi, psd, 1e-6, LAM, "s", correlation="uncorrelated", **kw)
    corr = stack_integrated_losses(1.0, films, 1.5168, wi, psd, 1e-6, LAM, "s", **kw)
    np.testing.assert_allclose(both, np.add(*one), rtol=1e-12)
    assert abs(corr[0] / both[0] - 1) > 1e-3


# a coated glass on every side: TiO₂ (60 nm) under MgF₂ (100 nm) on BK7, films listed from the substrate outwards
_COATED = (1.5168, [2.4, 1.38], [60.0, 100.0])
# which of the three interfaces (substrate, middle, air) are rough: each alone, and all three correlated
_ROUGH3 = {"substrate": (1.0, 0.0, 0.0), "middle": (0.0, 1.0, 0.0), "air": (0.0, 0.0, 1.0),
           "all": (1.0, 0.5, 0.7)}


@pytest.mark.parametrize("rough", sorted(_ROUGH3))
def test_rough_stack_bsdf_into_both_half_spaces_from_either_side(rough):
    """The library's full-sphere first-order BSDF of a rough stack (waveoptics.scatter.rough_stack_bsdf_components)
    against the rigorous solve at seeded directions: light from the air and from inside the BK7, reflected and
    transmitted, s and p in, s and p analyzed (the solver lit from the glass is the stack turned over: the layers
    reversed, the profile −h, which a first-order power does not see). k a = 1e-4: the O((k a)²) of the solve is
    ~1e-7."""
    from waveoptics.scatter import rough_stack_bsdf_components

    n_sub, n_f, d_f = _COATED
    r_lib = _ROUGH3[rough]                               # substrate interface first
    psds = [UnitPSD() if r else None for r in r_lib]
    scale = [r if r else 1.0 for r in r_lib]             # the library's PSD of interface j is r_j² S
    rng = np.random.default_rng(2002)
    flip = np.array([1.0, 1.0, -1.0])
    for _ in range(3):
        th, az = rng.uniform(0.0, 80.0, 2), rng.uniform(0.0, 360.0, 2)
        wi, wo = _wi(th[0], az[0]), _wi(th[1], az[1])
        for above in (True, False):
            if above:                                    # the solver's layers top-down: air, MgF₂, TiO₂, BK7
                top, films, bot, rs = 1.0, [(1.38, 100e-9), (2.4, 60e-9)], n_sub, r_lib[::-1]
            else:                                        # lit from the glass: BK7, TiO₂, MgF₂, air
                top, films, bot, rs = n_sub, [(2.4, 60e-9), (1.38, 100e-9)], 1.0, r_lib
            for z in (1.0, -1.0):
                w_s = wo * [1.0, 1.0, z]                 # the solver's frame: the light's medium on top
                got = stack_order_bsdf(top, films, bot, wi, w_s, LAM, rough=np.array(rs), ka=KA_FINE)
                wi_l, wo_l = (wi, w_s) if above else (wi * flip, w_s * flip)
                lib = rough_stack_bsdf_components(wi_l, wo_l, LAM_NM, (n_sub, n_f, d_f),
                                                  [None if p is None else _Scaled(s) for p, s in zip(psds, scale)])
                big = max(abs(v) for v in got.values())
                for ab in got:
                    assert abs(lib[ab] - got[ab]) <= TOL_FINE * max(abs(got[ab]), 1e-6 * big), (
                        rough, above, z, wi, wo, ab, got[ab], lib[ab])


class _Scaled(UnitPSD):
    """S = r² m⁴ everywhere (interface j's relative rms r)."""

    def __init__(self, r):
        self.r = r

    def S(self, f):
        return self.r ** 2 * np.ones_like(np.asarray(f, dtype=float))
