"""First-order scatter of a rough thin-film stack into both half-spaces, light from either side
(waveoptics.scatter.rough_film_sides).

References held against the code:
* one interface (no films): waveoptics.scatter.transmission's Rayleigh-Rice BRDF on either side and BTDF across
  (closed-form q factors of another derivation, held against a rigorous grating solve and SCATMECH), on all four
  side combinations, beyond the critical angle too;
* light from the air into the air: waveoptics.scatter.rough_film (today's reflection-only result);
* the limits a stack must reach: a film of zero thickness with conformal roughness, a film of the substrate's own
  index, reciprocity of radiance with the η² factor (Veach 1997, §5.2);
* written here from the paper: the translation identity of conformal roughness (identical roughness on every
  interface = the whole flat stack shifted by h, so at the specular directions the first-order field is
  δt = i (k_oz − k_iz) h t and δr = 2 i k_iz h r) with r and t of the flat stack from a direct solve of the
  boundary conditions of plane waves (a linear system, not characteristic matrices), pointwise at f = 0, and its
  TIS form for a long correlation length (Carniglia 1979's T (2πσ (n_i cosθ_i − n_o cosθ_t)/λ)² and Davies's
  R (4π n_i σ cosθ_i/λ)², Stover 2012).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from waveoptics.errors import FieldError
from waveoptics.materials import get_material
from waveoptics.scatter import (rough_stack_bsdf, rough_stack_bsdf_components, rough_stack_components,
                                rough_stack_tis, rough_stack_tis_sides, rr_bsdf_components)
from waveoptics.surfaces import PSDModel

LAM = 550.0
N_S = 1.52                                           # BK7-like glass
PSD = PSDModel("gaussian", 1e-9, T=0.3e-6)
COMPONENTS = ("ss", "sp", "ps", "pp")
TOL = 1e-10
# MgF2 over a weakly absorbing high-index film on glass (films from the substrate outwards)
TWO = (N_S, [2.3 + 0.01j, 1.38], [61.0, 99.6])


class UnitPSD:
    """S = 1 m⁴ at every frequency: the BSDF per unit PSD."""
    length_scale = 1e-6

    def S(self, f):
        return np.ones_like(np.asarray(f, dtype=float))


def _random_pairs(m, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, m, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return v[0], v[1]


def _assert_components(got, ref, tol):
    big = max(float(np.max(ref[ab])) for ab in COMPONENTS)
    for ab in COMPONENTS:
        nz = ref[ab] > 1e-12 * big                  # cross-polarized terms vanish in the plane of incidence
        np.testing.assert_allclose(got[ab][nz], ref[ab][nz], rtol=tol, atol=0, err_msg=ab)
        assert np.all(np.abs(got[ab][~nz]) <= 1e-10 * big), ab


@pytest.mark.parametrize("n_sub", [N_S, 0.8])
def test_single_interface_is_rayleigh_rice_on_every_side(n_sub):
    """No films: the four components equal transmission's rr_bsdf_components over the sphere (reflection on either
    side, transmission either way), light from inside beyond the critical angle and observers beyond it included."""
    wi, wo = _random_pairs(4000, 7)
    got = rough_stack_bsdf_components(wi, wo, LAM, (n_sub, [], []), PSD)
    ref = rr_bsdf_components(wi, wo, LAM, PSD, 1.0, n_sub)
    # light from the denser side beyond its critical angle
    beyond = np.hypot(wi[:, 0], wi[:, 1]) * max(n_sub, 1.0) > min(n_sub, 1.0)
    dense = -1 if n_sub > 1.0 else 1
    for zi in (1, -1):
        for zo in (1, -1):
            sel = (np.sign(wi[:, 2]) == zi) & (np.sign(wo[:, 2]) == zo)
            assert zi != dense or np.count_nonzero(sel & beyond) > 100
            _assert_components({k: v[sel] for k, v in got.items()}, {k: v[sel] for k, v in ref.items()}, TOL)
    assert np.all(got["ss"][(wi[:, 2] < 0) != (wo[:, 2] < 0)] >= 0)


@pytest.mark.parametrize("pol", ["s", "p", "unpolarized"])
def test_reflection_from_air_is_the_stack_brdf(pol):
    """Light from the air into the air equals rough_film's BRDF of the same stack (glass, and a metal substrate
    over which nothing goes below), correlated and partly correlated."""
    wi, wo = _random_pairs(500, 11)
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    metal = (0.96 + 6.69j, TWO[1], TWO[2])
    for layers in (TWO, metal):
        for corr in ("correlated", 0.4):
            got = rough_stack_bsdf_components(wi, wo, LAM, layers, PSD, corr)
            ref = rough_stack_components(wi, wo, LAM, layers, PSD, corr)
            for ab in COMPONENTS:
                np.testing.assert_allclose(got[ab], ref[ab], rtol=1e-12, atol=1e-14 * float(np.max(ref["ss"])))
    below = wo * np.array([1.0, 1.0, -1.0])
    assert np.all(rough_stack_bsdf(wi, below, LAM, metal, PSD, polarization=pol) == 0.0)
    assert np.all(rough_stack_bsdf(wi, below, LAM, TWO, PSD, polarization=pol) > 0.0)


def _sides_pairs(m, seed):
    """Seeded pairs on all four side combinations (m each)."""
    wi, wo = _random_pairs(4 * m, seed)
    sz = np.repeat(np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]]), m, axis=0)
    wi[:, 2] = np.abs(wi[:, 2]) * sz[:, 0]
    wo[:, 2] = np.abs(wo[:, 2]) * sz[:, 1]
    return wi, wo


def test_zero_thickness_film_with_conformal_roughness_is_the_bare_interface():
    """A 0 nm MgF2 film with identical roughness on both interfaces is the bare air/glass interface on every side;
    uncorrelated it is not (the limit needs the correlation)."""
    wi, wo = _sides_pairs(300, 5)
    ref = rr_bsdf_components(wi, wo, LAM, PSD, 1.0, N_S)
    got = rough_stack_bsdf_components(wi, wo, LAM, (N_S, [1.38], [0.0]), PSD, "correlated")
    _assert_components(got, ref, TOL)
    unc = rough_stack_bsdf_components(wi, wo, LAM, (N_S, [1.38], [0.0]), PSD, "uncorrelated")
    assert np.max(np.abs(unc["ss"] / ref["ss"] - 1.0)) > 1e-2


def test_film_of_the_substrate_index():
    """A 137 nm film of the substrate's index: roughness on its bottom (glass/glass) scatters nothing; roughness on
    its top only is the bare interface (every side)."""
    wi, wo = _sides_pairs(300, 6)
    layers = (N_S, [N_S], [137.0])
    bottom = rough_stack_bsdf_components(wi, wo, LAM, layers, [PSD, None])
    assert all(np.all(bottom[ab] == 0.0) for ab in COMPONENTS)
    top = rough_stack_bsdf_components(wi, wo, LAM, layers, [None, PSD])
    _assert_components(top, rr_bsdf_components(wi, wo, LAM, PSD, 1.0, N_S), TOL)


@pytest.mark.parametrize("corr", ["correlated", "uncorrelated", 0.3])
def test_reciprocity_with_the_eta_squared_factor(corr):
    """f_ab(ω_i, ω_o) / n_o² = f_ba(ω_o, ω_i) / n_i² for a two-film stack (an absorbing film): across (either way)
    and in reflection inside the substrate, beyond the critical angle too."""
    wi, wo = _sides_pairs(200, 9)
    fwd = rough_stack_bsdf_components(wi, wo, LAM, TWO, PSD, corr)
    bwd = rough_stack_bsdf_components(wo, wi, LAM, TWO, PSD, corr)
    n_i = np.where(wi[:, 2] < 0, N_S, 1.0)
    n_o = np.where(wo[:, 2] < 0, N_S, 1.0)
    assert np.count_nonzero(wi[:, 2] * wo[:, 2] < 0) == 400
    _assert_components({ab: fwd[ab] / n_o ** 2 for ab in COMPONENTS},
                       {ab: bwd[ab[::-1]] / n_i ** 2 for ab in COMPONENTS}, TOL)


# --- written here from the paper: the flat stack by a direct solve of its boundary conditions --------------------

def _flat_stack_rt(kappa, lam_nm, n_list, d_list, pol, from_above):
    """(r, t, R, T) of the flat stack for a plane wave of lateral index *kappa* (units of k₀): media *n_list* from
    the substrate up to the air, films' thicknesses *d_list* (nm); r, t the amplitudes of E (s) or of H (p), R, T the
    power shares. In each medium the field (E_y for s, H_y for p) is a e^{i k₀ q z} + b e^{−i k₀ q z} with
    q = √(n² − κ²) (Im ≥ 0); across an interface the field and (1/ε)^γ ∂_z of it are continuous (γ = 0 for s,
    1 for p: Maxwell's boundary conditions on the tangential E and H, Born & Wolf §1.1.3). The unknowns, one
    (a, b) a medium, with the incident amplitude 1 and no wave coming in from the far side, solve one linear
    system."""
    k0 = 2 * np.pi / lam_nm
    eps = [complex(n) ** 2 for n in n_list]
    q = [np.sqrt(e - kappa ** 2 + 0j) for e in eps]
    q = [-x if x.imag < 0 else x for x in q]
    g = [1.0 if pol == "s" else 1.0 / e for e in eps]
    z = np.concatenate([[0.0], np.cumsum(d_list)])          # interface j at z_j
    m = len(eps)
    A = np.zeros((2 * m, 2 * m), dtype=complex)
    rhs = np.zeros(2 * m, dtype=complex)
    for j in range(m - 1):                                  # interface j between media j and j + 1
        for side, sign in ((j, 1.0), (j + 1, -1.0)):
            ph = np.exp(1j * k0 * q[side] * z[j])
            A[2 * j, 2 * side:2 * side + 2] = sign * np.array([ph, 1 / ph])
            A[2 * j + 1, 2 * side:2 * side + 2] = sign * g[side] * q[side] * np.array([ph, -1 / ph])
    # up-going a, down-going b; from above: b_air = 1 and a_sub = 0; from below: a_sub = 1 and b_air = 0
    fixed = [(2 * (m - 1) + 1, 1.0), (0, 0.0)] if from_above else [(0, 1.0), (2 * (m - 1) + 1, 0.0)]
    for row, (col, val) in zip((2 * m - 2, 2 * m - 1), fixed):
        A[row, col] = 1.0
        rhs[row] = val
    x = np.linalg.solve(A, rhs)
    flux = [(g[i] * q[i]).real for i in range(m)]          # power flux per |amplitude|² (common factors dropped)
    if from_above:
        r, t = x[2 * (m - 1)], x[1]
        return r, t, abs(r) ** 2, abs(t) ** 2 * flux[0] / flux[-1]
    r, t = x[1], x[2 * (m - 1)]
    return r, t, abs(r) ** 2, abs(t) ** 2 * flux[-1] / flux[0]


FILMS = ([2.3 + 0.01j, 1.38], [61.0, 99.6])


@pytest.mark.parametrize("from_above, theta", [(True, 0.0), (True, 35.0), (True, 80.0), (False, 0.0),
                                               (False, 30.0), (False, 55.0)])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_conformal_stack_at_the_specular_directions_is_a_shifted_stack(from_above, theta, pol):
    """Identical roughness on every interface of the two-film stack: at the specular reflection and transmission
    directions (f = 0) the first-order scatter is the flat stack shifted by h, f = P (Δk_z)² (n_o/λ)² S(0) with
    P = R, Δk_z = 2 k₀ n_i cosθ_i in reflection and P = T, Δk_z = k₀ (n_i cosθ_i − n_o cosθ_o) across (the phase of
    r and t of a displaced stack; f = dP/dω / (P_i cosθ_o) with d²f = (n_o/λ)² cosθ_o dω). From the glass at 55°
    (beyond its 41° critical angle) nothing crosses and R = 1 − absorption."""
    n_i, n_far = (1.0, N_S) if from_above else (N_S, 1.0)
    t = math.radians(theta)
    kappa = n_i * math.sin(t)
    lam = LAM * 1e-9
    s_z = 1.0 if from_above else -1.0
    wi = np.array([math.sin(t), 0.0, s_z * math.cos(t)])
    r, tt, R, T = _flat_stack_rt(kappa, LAM, [N_S, *FILMS[0], 1.0], FILMS[1], pol, from_above)
    k_iz = 2 * np.pi / lam * n_i * math.cos(t)
    wr = np.array([-wi[0], 0.0, wi[2]])
    f_r = rough_stack_bsdf_components(wi, wr, LAM, (N_S, *FILMS), UnitPSD())
    ref_r = R * (2 * k_iz) ** 2 * (n_i / lam) ** 2
    assert f_r[pol + pol] == pytest.approx(ref_r, rel=TOL)
    assert abs(f_r["sp"]) + abs(f_r["ps"]) < 1e-12 * ref_r
    if kappa < n_far:
        c_o = math.sqrt(1.0 - (kappa / n_far) ** 2)
        wt = np.array([-kappa / n_far, 0.0, -s_z * c_o])
        f_t = rough_stack_bsdf_components(wi, wt, LAM, (N_S, *FILMS), UnitPSD())
        ref_t = T * (2 * np.pi / lam * (n_i * math.cos(t) - n_far * c_o)) ** 2 * (n_far / lam) ** 2
        assert f_t[pol + pol] == pytest.approx(ref_t, rel=TOL)
    else:
        assert T == 0.0 and R < 1.0                       # total internal reflection; the film absorbs a little


@pytest.mark.parametrize("from_above, theta", [(True, 0.0), (True, 40.0), (False, 20.0)])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_tis_of_a_long_correlation_length_is_the_shifted_stack(from_above, theta, pol):
    """For a long correlation length (T = 20 µm, paraxial lobes) the TIS of conformal roughness tends to
    R (2 k₀ n_i σ cosθ_i)² on the incidence side and T (k₀ σ (n_i cosθ_i − n_o cosθ_o))² across (Davies; Carniglia
    1979; Stover 2012), with R, T of the flat two-film stack solved here; a zero-thickness film gives the bare
    interface's smooth-surface limit (Stover's (2πσ(n₂ − n₁)/λ)² T at normal incidence)."""
    sigma = 1e-9
    psd = PSDModel("gaussian", sigma, T=20e-6)
    n_i, n_far = (1.0, N_S) if from_above else (N_S, 1.0)
    t = math.radians(theta)
    kappa = n_i * math.sin(t)
    c_o = math.sqrt(1.0 - (kappa / n_far) ** 2)
    k0 = 2 * np.pi / (LAM * 1e-9)
    for films, d in (FILMS, ([1.38], [0.0])):
        _, _, R, T = _flat_stack_rt(kappa, LAM, [N_S, *films, 1.0], d, pol, from_above)
        tis_r, tis_t = rough_stack_tis_sides(theta, LAM, (N_S, films, d), psd, "correlated", pol, from_above)
        assert tis_r == pytest.approx(R * (2 * k0 * n_i * sigma * math.cos(t)) ** 2, rel=1e-3)
        assert tis_t == pytest.approx(T * (k0 * sigma * (n_i * math.cos(t) - n_far * c_o)) ** 2, rel=1e-3)


def test_tis_quadratures_agree_and_beyond_the_critical_angle():
    """The polar quadrature about each specular direction and the hemisphere quadrature (cut at the critical angle)
    give one TIS for a narrow lobe; from the glass beyond the critical angle there is no specular transmission, but
    the roughness's spatial frequencies that bring the light inside the air's circle of directions do cross: TIS_T
    (over the hemisphere) is > 0, and the polar quadrature, which needs a specular direction, is refused."""
    psd = PSDModel("gaussian", 1e-9, T=1e-6)
    for above, th in ((True, 30.0), (False, 25.0)):
        a = rough_stack_tis_sides(th, LAM, TWO, psd, "correlated", "p", above, method="polar")
        b = rough_stack_tis_sides(th, LAM, TWO, psd, "correlated", "p", above, method="hemisphere")
        # measured 6e-11 and 6e-6 from the air; 3.7e-4 on the glass side from inside, where the √ kink at the
        # critical angle crosses the polar grid (as for one interface, tests/test_rr_transmission.py)
        np.testing.assert_allclose(a, b, rtol=1e-3)
    r, t = rough_stack_tis_sides(60.0, LAM, TWO, PSD, "correlated", "s", from_above=False)
    assert r > 0 and t > 0
    with pytest.raises(FieldError, match="theta_deg .* critical angle"):
        rough_stack_tis_sides(60.0, LAM, TWO, PSD, from_above=False, method="polar")


def test_absorbing_substrate():
    """Over a metal: light from above keeps the reflection-only result (TIS_T = 0); light from below is refused,
    naming the stack."""
    metal = (0.96 + 6.69j, [1.46], [180.0])
    wi = np.array([0.3, 0.0, math.sqrt(0.91)])
    wo = np.array([0.1, 0.2, -math.sqrt(0.95)])
    r, t = rough_stack_tis_sides(20.0, LAM, metal, PSD)
    assert r > 0 and t == 0.0
    r_polar, _ = rough_stack_tis_sides(20.0, LAM, metal, PSD, method="polar")
    assert r_polar == pytest.approx(rough_stack_tis(20.0, LAM, metal, PSD), rel=1e-12)
    with pytest.raises(FieldError, match="stack: light from inside the substrate") as e:
        rough_stack_bsdf_components(wo, wi, LAM, metal, PSD)
    assert e.value.field == "stack"
    with pytest.raises(FieldError, match="stack"):
        rough_stack_tis_sides(20.0, LAM, metal, PSD, from_above=False)
    with pytest.raises(FieldError, match="polarization"):
        rough_stack_bsdf(wi, wo, LAM, TWO, PSD, polarization="x")
    with pytest.raises(FieldError, match="method"):
        rough_stack_tis_sides(20.0, LAM, TWO, PSD, method="grid")


def test_a_catalogued_glass_is_transparent():
    """BK7's catalogued k (~1e-8, absorbed over millimetres) does not make it opaque: the stack material scatters
    on every side as its layers with the substrate's real index."""
    m = get_material("BK7|MgF2:100nm")
    lam = np.array([450.0, 550.0, 650.0])
    ns, nf = m.indices(lam)
    assert np.all(ns.imag > 0)
    wi, wo = _sides_pairs(3, 4)
    for k in range(3):
        f = rough_stack_bsdf(wi, wo, lam[k], m, PSD)
        g = rough_stack_bsdf(wi, wo, lam[k], (ns[k].real, [nf[0][k]], [100.0]), PSD)
        np.testing.assert_allclose(f, g, rtol=1e-12)


@pytest.mark.parametrize("layers", [TWO, "BK7|MgF2:100nm"])
def test_wavelengths_broadcast_against_directions(layers):
    layers = get_material(layers) if isinstance(layers, str) else layers
    wi, wo = _sides_pairs(3, 3)
    lam = np.linspace(450.0, 650.0, len(wi))
    f = rough_stack_bsdf(wi, wo, lam, layers, PSD)
    g = np.array([rough_stack_bsdf(a, b, x, layers, PSD) for a, b, x in zip(wi, wo, lam)])
    np.testing.assert_allclose(f, g, rtol=1e-13)
