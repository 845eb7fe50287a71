"""First-order scatter of a thin-film stack with rough interfaces (waveoptics.scatter.rough_film, issue 33).

References held against the code: today's single-interface Rayleigh-Rice (Germer's q factors, a different formula)
in every single-interface limit; the translation identity of conformal roughness at the mirror direction
(identical displacement of every interface = a shift of the whole stack, δr = 2ik cosθ h r, with r from the
Rouard recurrence of waveoptics.materials.stack, a different algorithm); the closed-form period λ/(2 n cosθ_f)
of the film's interference; the Davies/Bennett-Porteus TIS R (4πσ/λ)² of a long-correlation surface; and a
second implementation written here for one film, from plane waves and Airy multiple-beam sums (Elson 1976's
single overlayer) rather than characteristic matrices.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from waveoptics.errors import WaveopticsError
from waveoptics.materials import get_material, stack
from waveoptics.scatter import rayleigh_rice_brdf, rayleigh_rice_components, rough_stack_brdf
from waveoptics.scatter.rough_film import rough_stack_components, rough_stack_tis
from waveoptics.surfaces import PSDModel

TOL_LIMIT = 1e-10          # single-interface limits (the brief's 1e-10 relative)
LAM = 550.0
PSD = PSDModel("gaussian", 1e-9, T=1e-6)
SUBSTRATES = {"glass": 1.52 + 0j, "metal": 0.96 + 6.69j}
POLS = ("s", "p", "unpolarized")


def _dir(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


# several (θi, θo, φo): in plane forward/back, out of plane, normal incidence, normal exit, grazing-ish
WI = _dir(np.array([30.0, 10.0, 0.0, 60.0, 45.0, 75.0]), np.zeros(6))
WO = _dir(np.array([40.0, 70.0, 20.0, 5.0, 0.0, 80.0]), np.array([140.0, 20.0, 90.0, 250.0, 0.0, 180.0]))


def _rr(n, pol):
    return rayleigh_rice_brdf(WI, WO, LAM, PSD, n * n, pol)


def _rel(a, b):
    return np.max(np.abs(a / b - 1.0))


@pytest.mark.parametrize("name", SUBSTRATES)
@pytest.mark.parametrize("pol", POLS)
def test_bare_substrate_is_rayleigh_rice(name, pol):
    n = SUBSTRATES[name]
    f = rough_stack_brdf(WI, WO, LAM, (n, [], []), PSD, polarization_in=pol)
    assert _rel(f, _rr(n, pol)) < TOL_LIMIT


@pytest.mark.parametrize("name", SUBSTRATES)
def test_analyzed_components_are_rayleigh_rice(name):
    n = SUBSTRATES[name]
    ref = rayleigh_rice_components(WI, WO, LAM, PSD, n * n)
    for a in "sp":
        for b in "sp":
            f = rough_stack_brdf(WI, WO, LAM, (n, [], []), PSD, polarization_in=a, polarization_out=b)
            nz = ref[a + b] > 1e-30 * ref["ss"].max()          # sp, ps vanish in the plane of incidence
            np.testing.assert_allclose(f[nz], ref[a + b][nz], rtol=TOL_LIMIT)
            assert np.all(np.abs(f[~nz]) < 1e-12 * ref["ss"].max())


@pytest.mark.parametrize("name", SUBSTRATES)
@pytest.mark.parametrize("pol", POLS)
def test_film_of_air_with_smooth_top_is_the_bare_substrate(name, pol):
    """(b) a 137 nm film of index 1 (the ambient's) whose top is smooth: only air/substrate scatters."""
    n = SUBSTRATES[name]
    f = rough_stack_brdf(WI, WO, LAM, (n, [1.0], [137.0]), [PSD, None], polarization_in=pol)
    assert _rel(f, _rr(n, pol)) < TOL_LIMIT


@pytest.mark.parametrize("name", SUBSTRATES)
@pytest.mark.parametrize("pol", POLS)
def test_film_of_substrate_with_smooth_bottom_is_the_bare_substrate(name, pol):
    """(c) a 137 nm film of the substrate's index, bottom smooth: only the top (air/substrate) scatters."""
    n = SUBSTRATES[name]
    f = rough_stack_brdf(WI, WO, LAM, (n, [n], [137.0]), [None, PSD], polarization_in=pol)
    assert _rel(f, _rr(n, pol)) < TOL_LIMIT


@pytest.mark.parametrize("name", SUBSTRATES)
@pytest.mark.parametrize("pol", POLS)
def test_vanishing_film_with_correlated_roughness_is_one_interface(name, pol):
    """(d) MgF2-like film (1.38) of thickness 0 and 1e-3 nm, identical roughness on both interfaces."""
    n = SUBSTRATES[name]
    ref = _rr(n, pol)
    f0 = rough_stack_brdf(WI, WO, LAM, (n, [1.38], [0.0]), PSD, "correlated", pol)
    assert _rel(f0, ref) < TOL_LIMIT
    f1 = rough_stack_brdf(WI, WO, LAM, (n, [1.38], [1e-3]), PSD, "correlated", pol)
    assert _rel(f1, ref) < 1e-4                  # O(k d) away from the limit
    funcorr = rough_stack_brdf(WI, WO, LAM, (n, [1.38], [0.0]), PSD, "uncorrelated", pol)
    assert _rel(funcorr, ref) > 1e-2             # the limit needs the correlation: not a trivial identity


FILM = (0.96 + 6.69j, [1.46], [180.0])          # silica on a metal


@pytest.mark.parametrize("pol", POLS)
def test_uncorrelated_is_the_sum_of_single_interfaces(pol):
    psd2 = PSDModel("exponential", 0.7e-9, T=0.3e-6)
    f = rough_stack_brdf(WI, WO, LAM, FILM, [PSD, psd2], "uncorrelated", pol)
    f0 = rough_stack_brdf(WI, WO, LAM, FILM, [PSD, None], "correlated", pol)
    f1 = rough_stack_brdf(WI, WO, LAM, FILM, [None, psd2], "correlated", pol)
    np.testing.assert_allclose(f, f0 + f1, rtol=1e-12)
    # partial correlation c: uncorrelated + c × the cross terms
    fc = rough_stack_brdf(WI, WO, LAM, FILM, [PSD, psd2], "correlated", pol)
    fh = rough_stack_brdf(WI, WO, LAM, FILM, [PSD, psd2], 0.5, pol)
    np.testing.assert_allclose(fh, f + 0.5 * (fc - f), rtol=1e-12, atol=1e-12 * np.max(fc))
    assert np.max(np.abs(fc - f) / f) > 1e-2     # the cross terms are not negligible here


@pytest.mark.parametrize("theta", [0.0, 40.0])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_cross_terms_oscillate_with_the_film_period(theta, pol):
    """correlated − uncorrelated at the mirror direction, swept over the film thickness: its maxima are spaced
    by λ / (2 n_f cosθ_f) (the closed form of the film's interference)."""
    n_f, n_s = 1.46, 0.96 + 6.69j
    wi = _dir(theta, 0.0)
    wo = np.array([-wi[0], -wi[1], wi[2]])
    cos_f = np.sqrt(1.0 - (np.sin(np.radians(theta)) / n_f) ** 2)
    period = LAM / (2.0 * n_f * cos_f)

    def cross(d):
        layers = (n_s, [n_f], [d])
        return float(rough_stack_brdf(wi, wo, LAM, layers, PSD, "correlated", pol)
                     - rough_stack_brdf(wi, wo, LAM, layers, PSD, "uncorrelated", pol))

    d = np.linspace(0.0, 4.2 * period, 841)
    c = np.array([cross(x) for x in d])
    assert c.max() - c.min() > 0.1 * np.abs(c).max()   # it oscillates (not always through zero: p on a metal)
    peaks = [i for i in range(1, len(d) - 1) if c[i] > c[i - 1] and c[i] >= c[i + 1]]
    assert len(peaks) >= 3
    step = d[1] - d[0]
    refined = [minimize_scalar(lambda x: -cross(x), bounds=(d[i] - step, d[i] + step), method="bounded",
                               options={"xatol": 1e-9}).x for i in peaks]
    spacing = np.diff(refined)
    np.testing.assert_allclose(spacing, period, rtol=1e-6)


MULTI = (0.96 + 6.69j, [1.46, 2.35, 1.46, 2.35 + 0.02j], [95.0, 61.0, 120.0, 40.0])


@pytest.mark.parametrize("theta", [0.0, 35.0, 70.0])
@pytest.mark.parametrize("pol", ["s", "p"])
def test_conformal_stack_at_the_mirror_direction_is_a_shifted_stack(theta, pol):
    """Identical roughness on every interface = the whole stack displaced by h: at the mirror direction (f = 0)
    the first-order field is δr = 2ik cosθ h r, so f = (16π²/λ⁴) cos²θ |r_stack|² S(0), with r from the Rouard
    recurrence (a different algorithm), for a four-film stack with an absorbing film on a metal."""
    wi = _dir(theta, 0.0)
    wo = np.array([-wi[0], -wi[1], wi[2]])
    f = rough_stack_brdf(wi, wo, LAM, MULTI, PSD, "correlated", pol, pol)
    r, _ = stack.amplitudes(np.cos(np.radians(theta)), LAM, MULTI[0], MULTI[1], MULTI[2], pol)
    lam = LAM * 1e-9
    ref = 16 * np.pi ** 2 / lam ** 4 * np.cos(np.radians(theta)) ** 2 * abs(r) ** 2 * PSD.S(0.0)
    np.testing.assert_allclose(f, ref, rtol=1e-10)
    cross = rough_stack_brdf(wi, wo, LAM, MULTI, PSD, "correlated", pol, "p" if pol == "s" else "s")
    assert abs(cross) < 1e-12 * ref


def test_stack_material_is_its_layers():
    m = get_material("Al|Al2O3:120nm")
    ns, nf = m.indices(LAM)
    f = rough_stack_brdf(WI, WO, LAM, m, PSD, "uncorrelated")
    g = rough_stack_brdf(WI, WO, LAM, (ns, nf, [120.0]), PSD, "uncorrelated")
    np.testing.assert_allclose(f, g, rtol=1e-13)


def test_below_the_horizon_is_zero():
    wi = _dir(30.0, 0.0)
    wo = np.array([0.3, 0.0, -0.95])
    assert rough_stack_brdf(wi, wo, LAM, FILM, PSD) == 0.0
    grazing = np.array([-1.0, 0.0, 0.0])               # the limit at the horizon is 0 (r = −1), not 0/0
    assert rough_stack_brdf(wi, grazing, LAM, FILM, PSD) == 0.0
    assert rough_stack_brdf(grazing, wi, LAM, FILM, PSD, polarization_in="p") == 0.0


def test_bad_inputs_name_their_fields():
    with pytest.raises(WaveopticsError, match="correlation.*'partial'"):
        rough_stack_brdf(WI, WO, LAM, FILM, PSD, "partial")
    with pytest.raises(WaveopticsError, match=r"correlation 1.5 is not allowed"):
        rough_stack_brdf(WI, WO, LAM, FILM, PSD, 1.5)
    with pytest.raises(WaveopticsError, match="interface_psds: 3 PSDs for a stack of 2 interfaces"):
        rough_stack_brdf(WI, WO, LAM, FILM, [PSD, PSD, PSD])
    with pytest.raises(WaveopticsError, match="polarization_in"):
        rough_stack_brdf(WI, WO, LAM, FILM, PSD, polarization_in="x")
    with pytest.raises(WaveopticsError, match="stack: 1 film indices but 2 thicknesses"):
        rough_stack_brdf(WI, WO, LAM, (1.5, [1.38], [1.0, 2.0]), PSD)


def test_total_integrated_scatter_of_a_quarter_wave_antireflection_coating():
    """TIS at normal incidence, 550 nm, σ = 1 nm on every interface: bare glass (1.52) against a quarter-wave MgF2
    (1.38) coating. With a long correlation length (T = 5 µm, every frequency scatters near the mirror) the bare
    TIS tends to Davies' R (4πσ/λ)² and the conformal coating's to R_AR (4πσ/λ)² (the shifted-stack argument):
    comparable, not zero, as R_AR = 1.26 % is not 0. Measured (printed with -s): T = 5 µm: bare 2.2232e-5,
    correlated 6.579e-6, uncorrelated 1.885e-5; T = 0.2 µm: bare 1.568e-5, correlated 4.838e-6, uncorrelated
    1.339e-5; an ideal coating (n = √1.52) at T = 0.2 µm: correlated 3.56e-7, uncorrelated 1.266e-5."""
    lam, ng, nf = 550.0, 1.52, 1.38
    ar = (ng, [nf], [lam / (4 * nf)])
    g = (4 * np.pi * 1.0 / lam) ** 2
    R_bare = ((ng - 1) / (ng + 1)) ** 2
    R_ar = ((ng - nf * nf) / (ng + nf * nf)) ** 2          # quarter wave: admittance nf²/ng (Macleod ch. 4)
    for T in (5e-6, 0.2e-6):
        psd = PSDModel("gaussian", 1e-9, T=T)
        bare = rough_stack_tis(0.0, lam, (ng, [], []), psd)
        corr = rough_stack_tis(0.0, lam, ar, psd, "correlated")
        unc = rough_stack_tis(0.0, lam, ar, psd, "uncorrelated")
        print(f"T = {T * 1e6:g} um: TIS bare {bare:.4e}, AR correlated {corr:.4e}, AR uncorrelated {unc:.4e}, "
              f"ratio correlated/bare {corr / bare:.3f}")
        assert 0 < corr < bare and 0 < unc < bare
        if T == 5e-6:
            assert abs(bare / (R_bare * g) - 1) < 1e-3
            assert abs(corr / (R_ar * g) - 1) < 1e-3
    nf_ideal = np.sqrt(ng)
    ideal = (ng, [nf_ideal], [lam / (4 * nf_ideal)])
    psd = PSDModel("gaussian", 1e-9, T=0.2e-6)
    corr = rough_stack_tis(0.0, lam, ideal, psd, "correlated")
    unc = rough_stack_tis(0.0, lam, ideal, psd, "uncorrelated")
    print(f"ideal AR (n = {nf_ideal:.4f}), T = 0.2 um: TIS correlated {corr:.4e}, uncorrelated {unc:.4e}")
    assert 0 < corr < unc


# --- a second implementation, for one film, written here: plane waves with 3-D polarization vectors in every
# medium, the four boundary conditions (tangential E and H at both interfaces) solved as one 4 × 4 linear system
# per wave, and Elson's induced-dipole sheet (Elson 1976, single overlayer) radiating by reciprocity. No
# characteristic matrix, no (û, ŝ) scalar bookkeeping.

def _waves(kappa_vec, n, pol):
    """(E, H) unit-amplitude vectors (Z₀ = 1) of the down (σ = −1) and up (σ = +1) waves of lateral index vector
    *kappa_vec* in medium n, and their normal index q."""
    kap = np.hypot(*kappa_vec)
    u = np.array([*kappa_vec, 0.0]) / kap if kap > 0 else np.array([1.0, 0.0, 0.0])
    z = np.array([0.0, 0.0, 1.0])
    s = np.cross(z, u)
    q = np.sqrt(n * n - kap * kap + 0j)
    q = -q if q.imag < 0 else q
    out = {}
    for sig in (-1, 1):
        kv = kap * u + sig * q * z                        # k / k₀
        E = s.astype(complex) if pol == "s" else np.cross(s, kv) / n
        out[sig] = (E, np.cross(kv, E))
    return out, q


def _film_fields(kappa_vec, lam, n2, n1, d, pol):
    """E and D/ε₀ (3-D) at the bottom (z = −d) and top (z = 0) interfaces of film n1 on substrate n2, for a unit
    wave from air along lateral index *kappa_vec*."""
    k0 = 2 * np.pi / lam
    w0, q0 = _waves(kappa_vec, 1.0, pol)
    w1, q1 = _waves(kappa_vec, n1, pol)
    w2, q2 = _waves(kappa_vec, n2, pol)
    # unknowns: r (air, up), a (film, down), b (film, up), t (substrate, down); phases e^{i σ k₀ q z}
    M = np.zeros((4, 4), complex)
    rhs = np.zeros(4, complex)
    tang = [lambda v: v[0], lambda v: v[1]]               # the x and y components are the tangential ones

    def rows(z, cols):                                    # continuity of (E_t, H_t) projected on x and y
        eqs = []
        for which in (0, 1):                              # E, H
            for comp in tang:
                eqs.append([sum(c * comp(w[which]) * np.exp(1j * sig * k0 * q * z) for c, w, sig, q in col)
                            for col in cols])
        return eqs

    # top interface z = 0: air (incident + r) = film (a, b); bottom z = −d: film (a, b) = substrate t
    top = rows(0.0, [[(1, w0[1], 1, q0)], [(-1, w1[-1], -1, q1)], [(-1, w1[1], 1, q1)], []])
    inc = rows(0.0, [[(1, w0[-1], -1, q0)]])
    bot = rows(-d, [[], [(1, w1[-1], -1, q1)], [(1, w1[1], 1, q1)], [(-1, w2[-1], -1, q2)]])
    eqs = [row + [b[0]] for row, b in zip(top, inc)] + [row + [0j] for row in bot]
    # 8 projections (x, y of E_t and H_t at two interfaces) of 4 conditions: a consistent system, least squares
    eqs = np.array(eqs)
    A, y = eqs[:, :4], -eqs[:, 4]
    sol = np.linalg.lstsq(A, y, rcond=None)[0]
    r, a, b, t = sol
    E_top = w0[-1][0] + r * w0[1][0]
    E_bot = t * w2[-1][0] * np.exp(-1j * k0 * q2 * (-d))
    D_top = E_top[2] * 1.0
    D_bot = E_bot[2] * n2 * n2
    return (E_bot, D_bot), (E_top, D_top)


def _film_brdf(wi, wo, lam_nm, n2, n1, d, psd, pol_in, pol_out):
    """f (1/sr) of a film with identical (correlated) roughness on both interfaces, from the fields above."""
    lam = lam_nm * 1e-9
    fi = _film_fields(-wi[:2], lam_nm, n2, n1, d, pol_in)      # incident wave travels along −ω_i
    fo = _film_fields(-wo[:2], lam_nm, n2, n1, d, pol_out)     # reciprocal wave travels along −ω_o
    eps = [n2 * n2, n1 * n1, 1.0]
    G = 0j
    for j in range(2):
        (E, D), (E2, D2) = fi[j], fo[j]
        below, above = eps[j], eps[j + 1]
        G += (below - above) * (E[:2] @ E2[:2] + D * D2 / (above * below))
    k = 2 * np.pi / lam
    S = psd.S(np.hypot(*(wi[:2] + wo[:2])) / lam)
    return k ** 4 / (16 * np.pi ** 2 * wi[2] * wo[2]) * abs(G) ** 2 * S


@pytest.mark.parametrize("n2", [1.52 + 0j, 0.96 + 6.69j])
def test_single_film_against_a_plane_wave_implementation(n2):
    n1, d = 1.46 + 0.01j, 180.0
    for wi, wo in zip(WI, WO):
        for a in "sp":
            for b in "sp":
                f = rough_stack_brdf(wi, wo, LAM, (n2, [n1], [d]), PSD, "correlated", a, b)
                ref = _film_brdf(wi, wo, LAM, n2, n1, d, PSD, a, b)
                # measured: within 1e-14 (glass), 2e-10 (metal) relative; the issue asks 1e-3
                assert abs(f - ref) <= 1e-8 * abs(ref) + 1e-16, (a, b, f, ref)


def test_wavelengths_broadcast_against_directions():
    m = get_material("Al|Al2O3:120nm")
    lams = np.array([450.0, 550.0, 650.0])
    wi, wo = WI[:1], WO[:1]
    f = rough_stack_brdf(wi, wo, lams, m, PSD, "correlated", "p")
    one = [float(rough_stack_brdf(wi[0], wo[0], x, m, PSD, "correlated", "p")) for x in lams]
    np.testing.assert_allclose(f, one, rtol=1e-13)
