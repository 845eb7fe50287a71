"""Thin-film stacks: the transfer-matrix code (waveoptics.materials.stack) against closed forms written here (the Airy
formula of one film, the characteristic-matrix product of Born & Wolf §1.6, quarter-wave AR coating and Bragg
mirror), energy conservation, the Stack material and its grammar, the single-index callers' refusals, and the
planner's wavelength nodes with their measured colour error."""
import math

import colour as cs
import numpy as np
import pytest

from waveoptics import colour, planning
from waveoptics.cli import main as cli_main
from waveoptics.errors import FieldError
from waveoptics.materials import (PolarizedFresnel, RelativeFacetFresnel, Stack, fresnel, get_material, stack)
from waveoptics.planning import scene
from waveoptics.scatter import permittivity

COS = np.cos(np.radians([0.0, 10.0, 35.0, 60.0, 80.0, 89.0]))
TOL = 1e-12


# ------------------------------------------------------------------------------------------- references (here)

def _cos_t(n, n0, c):
    """n cos θ in a medium of index n, Im ≥ 0 (the decaying wave)."""
    q = np.sqrt(n * n - (n0 * n0) * (1 - c * c) + 0j)
    return np.where(q.imag < 0, -q, q)


def _fresnel_rt(pol, na, nb, qa, qb):
    """Born & Wolf §1.5.2 in terms of q = n cos θ (p: ratio of electric amplitudes, r_p = (n_b cosθ_a −
    n_a cosθ_b)/(n_b cosθ_a + n_a cosθ_b))."""
    ca, cb = qa / na, qb / nb
    if pol == "s":
        return (qa - qb) / (qa + qb), 2 * qa / (qa + qb)
    return (nb * ca - na * cb) / (nb * ca + na * cb), 2 * na * ca / (nb * ca + na * cb)


def airy(pol, c, lam, n_sub, n_film, d, n0=1.0):
    """One film: r = (r01 + r12 e^{2iβ})/(1 + r01 r12 e^{2iβ}), t = t01 t12 e^{iβ}/(1 + r01 r12 e^{2iβ}),
    β = (2π/λ) n1 d cos θ1 (Born & Wolf §1.6.4, eqs. (57)-(58))."""
    q0, q1, q2 = _cos_t(n0 + 0j, n0, c), _cos_t(n_film, n0, c), _cos_t(n_sub, n0, c)
    r01, t01 = _fresnel_rt(pol, n0, n_film, q0, q1)
    r12, t12 = _fresnel_rt(pol, n_film, n_sub, q1, q2)
    beta = 2 * np.pi / lam * q1 * d
    e = np.exp(2j * beta)
    return (r01 + r12 * e) / (1 + r01 * r12 * e), t01 * t12 * np.exp(1j * beta) / (1 + r01 * r12 * e)


def char_matrix_R(pol, c, lam, n_sub, films_out_to_in, n0=1.0):
    """R from the product of characteristic matrices M_j = [[cos β, −i sin β / p], [−i p sin β, cos β]],
    p = n cos θ (s) or cos θ / n (p) (Born & Wolf §1.6.2-1.6.3, eqs. (1.6.33), (1.6.35)); films listed from the
    incident side (the order of the book)."""
    def p_of(n):
        q = _cos_t(n + 0j, n0, c)
        return q if pol == "s" else q / (n * n)
    M = np.array([[1, 0], [0, 1]], dtype=complex)
    for n, d in films_out_to_in:
        b = 2 * np.pi / lam * _cos_t(n + 0j, n0, c) * d
        pj = p_of(n)
        M = M @ np.array([[np.cos(b), -1j * np.sin(b) / pj], [-1j * pj * np.sin(b), np.cos(b)]])
    p1, pl = p_of(n0), p_of(n_sub)
    r = ((M[0, 0] + M[0, 1] * pl) * p1 - (M[1, 0] + M[1, 1] * pl)) / \
        ((M[0, 0] + M[0, 1] * pl) * p1 + (M[1, 0] + M[1, 1] * pl))
    return abs(r) ** 2


# ----------------------------------------------------------------------------------------------- the math

@pytest.mark.parametrize("pol", ["s", "p"])
@pytest.mark.parametrize("n_sub,n_film,d", [(1.52, 1.38, 100.0),              # lossless glass + MgF2
                                            (1.2 + 7.0j, 1.65, 120.0),        # absorbing substrate (Al-like)
                                            (1.52, 2.0 + 0.3j, 80.0),         # absorbing film
                                            (0.15 + 3.4j, 1.8 + 0.05j, 500.0),  # both absorbing (Ag-like)
                                            (4.0 + 0.05j, 0.5 + 2.0j, 15.0)])  # metal film on silicon-like
def test_one_film_is_the_airy_formula(pol, n_sub, n_film, d):
    lam = np.array([400.0, 550.0, 700.0])[:, None]
    r, t = stack.amplitudes(COS, lam, n_sub, [n_film], [d], pol)
    r_ref, t_ref = airy(pol, COS, lam, n_sub, n_film, d)
    assert r.shape == (3, COS.size)
    np.testing.assert_allclose(r, r_ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(t, t_ref, rtol=0, atol=TOL)
    R = stack.R(COS, lam, n_sub, [n_film], [d], pol)
    np.testing.assert_allclose(R, np.abs(r_ref) ** 2, rtol=0, atol=TOL)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_many_films_are_the_characteristic_matrix_product(pol):
    # substrate outwards: Si-like | SiO2 | absorbing | TiO2 | MgF2
    films = [(1.46, 300.0), (2.2 + 0.2j, 40.0), (2.35, 65.0), (1.38, 99.0)]
    n_sub = 4.1 + 0.03j
    for lam in (420.0, 560.0, 690.0):
        for c in COS:
            R = float(stack.R(c, lam, n_sub, [n for n, _ in films], [d for _, d in films], pol))
            assert R == pytest.approx(char_matrix_R(pol, c, lam, n_sub, films[::-1]), abs=TOL)


@pytest.mark.parametrize("pol", ["s", "p"])
def test_energy_is_conserved(pol):
    lam = np.linspace(380, 780, 9)[:, None]
    # lossless everywhere: R + T = 1 (R from r and T from t, computed apart)
    R = stack.R(COS, lam, 1.52, [2.3, 1.38, 2.3], [60.0, 400.0, 75.0], pol)
    T = stack.T(COS, lam, 1.52, [2.3, 1.38, 2.3], [60.0, 400.0, 75.0], pol)
    np.testing.assert_allclose(R + T, 1.0, rtol=0, atol=TOL)
    # absorbing substrate under lossless films: all light not reflected enters the substrate (A = 0)
    A = stack.A(COS, lam, 1.2 + 7.0j, [1.65, 2.3], [120.0, 55.0], pol)
    np.testing.assert_allclose(A, 0.0, rtol=0, atol=TOL)
    # an absorbing film absorbs: A > 0, and R, T match the Airy closed form (T as the normal Poynting flux)
    n_f, n_s, d = 2.0 + 0.3j, 1.52, 80.0
    r, t = airy(pol, COS, lam, n_s, n_f, d)
    q_s = _cos_t(n_s + 0j, 1.0, COS)
    flux = q_s.real if pol == "s" else (q_s * np.conj(n_s) / n_s).real
    T_ref = np.where(COS > 0, flux / np.maximum(COS, 1e-300) * np.abs(t) ** 2, 0.0)
    A = stack.A(COS, lam, n_s, [n_f], [d], pol)
    np.testing.assert_allclose(A, 1 - np.abs(r) ** 2 - T_ref, rtol=0, atol=TOL)
    assert np.all(A[:, COS > 0.2] > 1e-3)


def test_zero_thickness_film_is_the_bare_substrate():
    lam = np.array([450.0, 650.0])[:, None]
    for n_sub in (1.52, 1.2 + 7.0j):
        for pol in ("s", "p"):
            bare = stack.R(COS, lam, n_sub, [], [], pol)
            film = stack.R(COS, lam, n_sub, [1.9 + 0.2j], [0.0], pol)
            q0, qs = _cos_t(1.0 + 0j, 1.0, COS), _cos_t(n_sub + 0j, 1.0, COS)
            r_ref = _fresnel_rt(pol, 1.0, n_sub, q0, qs)[0]
            np.testing.assert_allclose(bare, np.abs(r_ref) ** 2 + 0 * lam, rtol=0, atol=1e-15)
            np.testing.assert_allclose(film, bare, rtol=0, atol=2e-15)   # a few ulp


def test_quarter_wave_antireflection_coating():
    n_s, lam0 = 1.52, 550.0
    n_f = math.sqrt(n_s)
    d = lam0 / (4 * n_f)
    assert float(stack.R(1.0, lam0, n_s, [n_f], [d])) < 1e-30 + 1e-32
    # and away from λ0 it reflects, less than bare glass
    R_bare = ((n_s - 1) / (n_s + 1)) ** 2
    assert 0 < float(stack.R(1.0, 420.0, n_s, [n_f], [d])) < R_bare


@pytest.mark.parametrize("N", [1, 2, 4, 8])
def test_bragg_mirror_at_the_design_wavelength(N):
    # (LH)^N from the substrate outwards, each a quarter wave at λ0: the admittance is (n_H/n_L)^{2N} n_s and
    # R = ((n0 n_L^{2N} − n_s n_H^{2N}) / (n0 n_L^{2N} + n_s n_H^{2N}))² (Macleod, Thin-Film Optical Filters §6.1)
    n0, n_s, nL, nH, lam0 = 1.0, 1.52, 1.38, 2.35, 600.0
    films = [nL, nH] * N
    d = [lam0 / (4 * n) for n in films]
    a, b = n0 * nL ** (2 * N), n_s * nH ** (2 * N)
    for pol in ("s", "p", "unpolarized"):
        assert float(stack.R(1.0, lam0, n_s, films, d, pol)) == pytest.approx(((a - b) / (a + b)) ** 2, abs=TOL)


def test_s_and_p_agree_at_normal_incidence():
    lam = np.linspace(380, 780, 21)
    args = (lam, 0.2 + 3.0j, [1.46, 2.2 + 0.1j, 1.38], [200.0, 30.0, 95.0])
    np.testing.assert_allclose(stack.R(1.0, *args, "s"), stack.R(1.0, *args, "p"), rtol=0, atol=TOL)
    # on this convention r_p = −r_s there (the p field's sign, Born & Wolf §1.5.2)
    np.testing.assert_allclose(stack.r_p(1.0, *args), -stack.r_s(1.0, *args), rtol=0, atol=TOL)


def test_thick_absorbing_layer_neither_overflows_nor_loses_the_top_interface():
    # 1 mm of an absorbing film: the substrate is invisible; R is the film's own interface (no inf/nan)
    c = COS
    for pol in ("s", "p"):
        R = stack.R(c, 500.0, 1.52, [1.7 + 0.2j, 1.5 + 0.01j], [50.0, 1e6], pol)
        q0, q1 = _cos_t(1.0 + 0j, 1.0, c), _cos_t(1.5 + 0.01j, 1.0, c)
        np.testing.assert_allclose(R, np.abs(_fresnel_rt(pol, 1.0, 1.5 + 0.01j, q0, q1)[0]) ** 2, rtol=0, atol=TOL)
        assert np.all(np.isfinite(stack.T(c, 500.0, 1.52, [1.5 + 0.01j], [1e6], pol)))


def test_grazing_incidence_reflects_totally_and_bad_inputs_are_refused():
    assert stack.R(0.0, 550.0, 1.52, [1.0], [100.0]) == 1.0      # a film of the incident index: 0/0 guarded
    assert stack.T(0.0, 550.0, 1.52, [1.38], [100.0]) == 0.0
    for kw, word in [(dict(n_films=[1.5], d_films_nm=[-1.0]), "thicknesses"),
                     (dict(n_films=[1.5], d_films_nm=[]), "thickness per film"),
                     (dict(n_films=[1.5 - 0.1j], d_films_nm=[5.0]), "film 0 index"),
                     (dict(n_incident=1.0 + 0.1j), "incident medium")]:
        with pytest.raises(ValueError, match=word):
            stack.R(1.0, 550.0, 1.52, **kw)


# --------------------------------------------------------------------------------------- the Stack material

def test_stack_material_is_the_airy_formula_of_its_layers():
    m = get_material("Al|Al2O3:120nm")
    assert isinstance(m, Stack) and m.category == "metal" and m.is_metal and not m.has_index
    assert m.name == "Al|Al2O3:120nm" and "Al2O3" in m.source and "transfer matrix" in m.source
    lam = np.array([400.0, 550.0, 700.0])
    n_al, n_ox = get_material("Al").eta(lam), get_material("Al2O3").eta(lam)
    Rs, Rp = m.F_sp(COS[:, None], lam)
    for pol, Rv in (("s", Rs), ("p", Rp)):
        np.testing.assert_allclose(Rv, np.abs(airy(pol, COS[:, None], lam, n_al, n_ox, 120.0)[0]) ** 2,
                                   rtol=0, atol=TOL)
    np.testing.assert_allclose(m.F(COS[:, None], lam), 0.5 * (Rs + Rp), rtol=0, atol=0)
    np.testing.assert_allclose(m.F0(lam), np.abs(airy("s", 1.0, lam, n_al, n_ox, 120.0)[0]) ** 2, rtol=0, atol=TOL)


def test_stack_facet_reflectance_at_the_mirror_is_the_stack_s_and_p():
    m = get_material("Si|SiO2:100nm|TiO2:50nm")
    th = math.radians(50)
    wi = np.array([math.sin(th), 0.0, math.cos(th)])
    mirror = np.array([-wi[0], 0.0, wi[2]])
    lam = np.array([450.0, 600.0])
    Rs, Rp = m.F_sp(math.cos(th), lam)
    np.testing.assert_allclose(PolarizedFresnel(m, "s").at(wi, mirror[None], lam[:, None])[:, 0], Rs, atol=1e-15)
    np.testing.assert_allclose(PolarizedFresnel(m, "p").at(wi, mirror[None], lam[:, None])[:, 0], Rp, atol=1e-15)
    wo = np.array([[0.3, 0.4, math.sqrt(1 - 0.25)]])
    rel = RelativeFacetFresnel(m, "s").at(wi, wo, lam[:, None])
    assert rel.shape == (2, 1) and np.all(np.isfinite(rel)) and np.all(rel > 0)


def test_plain_material_facet_reflectance_is_unchanged_bit_for_bit():
    rng = np.random.default_rng(7)
    v = rng.normal(size=(50, 3))
    v[:, 2] = np.abs(v[:, 2])
    wo = v / np.linalg.norm(v, axis=-1, keepdims=True)
    wi = np.array([0.5, 0.1, math.sqrt(1 - 0.26)])
    lam = np.array([[430.0], [610.0]])
    for spec in ("Au", "1.5", "0.2+3.1j"):
        m = get_material(spec)
        eta = m.eta(lam)
        for pol in ("s", "p"):
            assert np.array_equal(PolarizedFresnel(m, pol).at(wi, wo, lam), fresnel.F_facet_polarized(wi, wo, eta, pol))
            mirror = wi * np.array([-1.0, -1.0, 1.0])
            ref = fresnel.F_facet_polarized(wi, wo, eta, pol) / fresnel.F_facet_polarized(wi, mirror, eta, pol)
            assert np.array_equal(RelativeFacetFresnel(m, pol).at(wi, wo, lam), ref)


def test_single_index_callers_refuse_a_stack_in_one_line():
    m = get_material("Al|Al2O3:5nm")
    for call in (lambda: m.eta(550.0), lambda: permittivity(m, 550.0)):
        with pytest.raises(FieldError) as e:
            call()
        assert e.value.field == "material" and "\n" not in str(e.value) and "thin-film stack" in str(e.value)


# ------------------------------------------------------------------------------------------------ the grammar

def test_grammar_orders_films_from_the_substrate_outwards_with_units():
    m = get_material("Si|SiO2:100nm|TiO2:0.05um")
    assert m.substrate.name == "Si" and [f.name for f, _ in m.films] == ["fused-silica", "TiO2"]
    assert m.thicknesses_nm == pytest.approx((100.0, 50.0))
    assert get_material("Al|alumina:1.2um").thicknesses_nm == pytest.approx((1200.0,))
    assert get_material(" Al | Al2O3 : 5nm ").thicknesses_nm == pytest.approx((5.0,))
    # any database spec as a layer: PRESET@PAGE, shelf/book/page, n+kj; thickness 0 allowed
    m = get_material("Au@Babar|main/SiO2/Malitson:20nm|1.38:0nm|2.0+0.1j:8nm")
    assert m.substrate.name == "Au@Babar" and len(m.films) == 3 and m.thicknesses_nm[1] == 0.0
    # the order matters: a film on the other side is another stack
    a, b = get_material("BK7|TiO2:60nm|MgF2:90nm"), get_material("BK7|MgF2:90nm|TiO2:60nm")
    assert abs(float(a.F0(550.0)) - float(b.F0(550.0))) > 0.05


@pytest.mark.parametrize("spec,words", [
    ("Al|Al2O3", ["'Al2O3' needs a thickness", "FILM:THICKNESS"]),
    ("Al|Al2O3:120", ["thickness '120'", "unit"]),
    ("Al|Al2O3:-5nm", ["thickness '-5nm'", ">= 0"]),
    ("Al|Al2O3:5parsec", ["'5parsec'", "nm"]),
    ("Al|Unobtainium:5nm", ["film 'Unobtainium'", "unknown material", "allowed"]),
    ("Xx|Al2O3:5nm", ["substrate 'Xx'", "unknown material"]),
    ("Al||Al2O3:5nm", ["empty film", "SUBSTRATE|FILM:THICKNESS"]),
    ("Al|", ["empty film"]),
    ("Al:5nm|SiO2:5nm", ["substrate 'Al:5nm' takes no thickness"]),
    ("f0:0.5|SiO2:5nm", ["substrate 'f0:0.5' gives only F0"]),
    ("Al|f0:0.3:5nm", ["film 'f0:0.3' gives only F0"]),
])
def test_grammar_errors_are_one_line_naming_the_token(spec, words):
    with pytest.raises(FieldError) as e:
        get_material(spec)
    msg = str(e.value)
    assert e.value.field == "material" and "\n" not in msg and msg.startswith(f"material {spec.strip()!r}")
    for w in words:
        assert w in msg


def test_cli_f0_and_microfacet_brdf_take_a_stack(capsys):
    assert cli_main(["f0", "Al|Al2O3:120nm", "--json"]) == 0
    assert "Al|Al2O3:120nm" in capsys.readouterr().out
    assert cli_main(["brdf", "--model", "microfacet", "--material", "Al|Al2O3:120nm", "--alpha", "0.2",
                     "--incident", "30", "--outgoing", "30,180", "--wavelengths", "450,550", "--json"]) == 0
    assert "Al|Al2O3:120nm" in capsys.readouterr().out
    assert cli_main(["brdf", "--model", "microfacet", "--material", "Al|Al2O3:120nm", "--alpha", "0.2",
                     "--incident", "30", "--outgoing", "30,180", "--backend", "opencl"]) == 2
    err = capsys.readouterr().err
    assert "--material 'Al|Al2O3:120nm' is a thin-film stack" in err and "--backend numpy" in err
    assert cli_main(["f0", "Al|Al2O3"]) == 2
    assert "film 'Al2O3' needs a thickness" in capsys.readouterr().err


def test_cli_materials_describes_a_stack(capsys):
    """``waveoptics materials STACK``: the layers with their data sources and thicknesses, F0 at 450/550/650 nm
    against Airy's one-film formula written above (1e-12), and the fringe spacing λ²/(2 n d) at 550 nm."""
    import json

    spec = "BK7|MgF2:100nm"
    assert cli_main(["materials", spec, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [layer["material"] for layer in data["layers"]] == ["BK7", "MgF2"]
    assert data["layers"][1]["thickness_nm"] == 100.0 and "semi" not in json.dumps(data["layers"][1])
    bk7, mgf2 = get_material("BK7"), get_material("MgF2")
    for lam in (450.0, 550.0, 650.0):
        ns, nf = bk7.eta(np.array(lam)), mgf2.eta(np.array(lam))
        R = np.mean([abs(airy(pol, 1.0, lam, ns, nf, 100.0)[0]) ** 2 for pol in "sp"])
        assert data["F0"][f"{lam:g}nm"] == pytest.approx(float(R), rel=1e-12)
    n550 = float(np.real(mgf2.eta(np.array(550.0))))
    assert data["fringe_spacing_nm_550nm"] == pytest.approx(550.0 ** 2 / (2 * n550 * 100.0), rel=1e-9)
    assert cli_main(["materials", spec]) == 0
    text = capsys.readouterr().out
    assert "100 nm" in text and "semi-infinite" in text and "SCHOTT" in text
    assert cli_main(["materials", "BK7|MgF2:0nm", "--json"]) == 0      # the bare substrate: no fringes
    bare = json.loads(capsys.readouterr().out)
    assert bare["fringe_spacing_nm_550nm"] is None and bare["optical_thickness_nm_550nm"] == 0.0
    assert cli_main(["materials", "BK7|MgF2"]) == 2
    assert "needs a thickness" in capsys.readouterr().err


def test_microfacet_brdf_of_a_stack_uses_the_stack_reflectance_at_the_half_angle():
    from waveoptics.brdf import models

    lam = np.array([450.0, 600.0])
    wi = np.array([[math.sin(0.5), 0.0, math.cos(0.5)]])
    wo = np.array([[-math.sin(0.5), 0.0, math.cos(0.5)]])
    kw = dict(wavelengths_nm=lam, alpha=0.2, kd=0.0)
    f_stack = models.microfacet_model(material="Al|Al2O3:300nm", **kw).evaluate(wi, wo)
    f_one = models.microfacet_model(fresnel="one", **kw).evaluate(wi, wo)
    F = get_material("Al|Al2O3:300nm").F(math.cos(0.5), lam)
    np.testing.assert_allclose(f_stack[:, 0, 0], f_one[:, 0, 0] * F, rtol=1e-12)
    from waveoptics.brdf import spectral_brdf
    f = spectral_brdf(wi, wo, lam, "Al|Al2O3:300nm", alpha=0.2, kd=0.0)
    np.testing.assert_allclose(f[:, 0], f_one[:, 0, 0] * F, rtol=1e-12)


# ------------------------------------------------------------------------------------- the planner's nodes

@pytest.fixture
def fixed_costs(monkeypatch):
    """A fixed cost model: the wavelength decision does not depend on it, and timing one (planning.calibration)
    takes half a minute on a busy machine, where its result is not cached."""
    cm = planning.CostModel(**{k: 1e-6 for k in planning.CostModel.__dataclass_fields__})
    monkeypatch.setattr(planning.planner, "calibration", lambda **kw: cm)


def _plan(material):
    d = {"name": "film", "accuracy": {"delta_e": 1.0},
         "materials": [{"name": "film", "material": material, "roughness": 0.05, "ndf": "ggx"}],
         "lights": [{"name": "sun", "spd": "D65", "directions_deg": [[30, 0]]}],
         "view": {"directions_deg": [[0, 0]]},
         "output": {"rgb_images": False, "tables": True, "resolution": 32}}
    return planning.plan_scene(scene.parse(d)).entries[0]


def _dE_vs_1nm(material, grid):
    """ΔE2000 (D65, CIE 1931 2°) of the normal-incidence reflectance colour from *grid* (linear interpolation, the
    simulation's integration) against colour-science's 1 nm integration of the same spectrum."""
    cmfs, d65 = cs.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"], cs.SDS_ILLUMINANTS["D65"]
    w1 = np.arange(360.0, 831.0)
    ref = cs.sd_to_XYZ(cs.SpectralDistribution(dict(zip(w1, material.F0(w1)))), cmfs, d65, method="Integration")
    white = cs.sd_to_XYZ(cs.SpectralDistribution(dict(zip(w1, np.ones_like(w1)))), cmfs, d65, method="Integration")
    xy = cs.XYZ_to_xy(white / 100)
    XYZ = colour.reflectance_to_XYZ(material.F0(grid), grid, "D65")
    return float(cs.delta_E(cs.XYZ_to_Lab(XYZ, xy), cs.XYZ_to_Lab(ref / 100, xy), method="CIE 2000"))


@pytest.mark.parametrize("spec,refined", [("Al|Al2O3:500nm", True), ("Si|SiO2:500nm", True),
                                          ("Al|Al2O3:120nm", False), ("Si|SiO2:120nm", False)])
def test_planner_puts_nodes_on_every_fringe_and_the_colour_stays_within_target(spec, refined, fixed_costs):
    e = _plan(spec)
    m = e.material
    grid = e.colour_wavelengths_nm
    step = grid[1] - grid[0]
    fringe = float(np.min(m.fringe_spacing_nm(grid)))
    assert np.array_equal(e.wavelengths_nm, grid)
    assert fringe / step >= planning.FILM_NODES_PER_FRINGE
    why = next(r for d, _, r in e.decisions if d == "wavelengths")
    assert "thin-film stack" in why and "nodes per fringe" in why
    coarse = colour.spectral_grid("D65", 20.0)
    assert bool(step < 20.0) is refined
    dE_plan, dE_coarse = _dE_vs_1nm(m, grid), _dE_vs_1nm(m, coarse)
    # measured: 500 nm Al2O3/Al 0.046 (10 nm) vs 0.18 (20 nm); 500 nm SiO2/Si 0.095 vs 0.40; 120 nm films ≤ 0.041
    assert dE_plan <= 0.1
    if refined:
        assert dE_plan < dE_coarse / 3
