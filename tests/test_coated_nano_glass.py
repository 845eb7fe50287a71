"""Coated nano-rough glass (issue 33): an anti-reflection coating on a nano-rough glass, every interface of the
films rough (waveoptics.brdf.nano_interface.CoatedNano inside NanoRoughDielectricBSDF and TwoScaleDielectricBSDF).

References held against the code, each a different algorithm or a different theory than the one under test:
* the optical theorem: the second-order loss of the coherent light of a lossless coated glass (the stack's SPM2 mean
  field, waveoptics.scatter.stack_coherent_losses) equals the first-order light it scatters into both half-spaces
  (Elson's rough-stack scatter integrated over each hemisphere, waveoptics.scatter.rough_stack_tis_sides): two
  theories that share no code;
* the rigorous Rayleigh-method solve of a grating on every interface of the stack (tests/rr_stack_grating.py),
  integrated over the PSD, for the coherent losses' split between R and T;
* reciprocity of the mean field (the coherent transmittance from the air at θ₁ equals that from the glass at θ₂,
  n₁ sin θ₁ = n₂ sin θ₂), which the stack's losses compute by two different sweeps of the stack;
* the white furnace R + T = 1 of a lossless coated glass by Monte Carlo over the BSDF's own sampler (weights
  f |cos θ_o| / pdf: eval integrated by a different algorithm than the tables' quadratures);
* reciprocity f(i, o)/η_o² = f(o, i)/η_i² of the whole BSDF in both frames of the nano lobes.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from rr_stack_grating import stack_integrated_losses
from waveoptics.brdf import Micro, NanoRoughDielectricBSDF, TwoScaleDielectricBSDF
from waveoptics.materials import get_material
from waveoptics.scatter import rough_stack_tis_sides, stack_coherent_losses
from waveoptics.surfaces import PSDModel

LAM_NM = 550.0
N_BK7 = 1.5168
AR = (N_BK7, [1.38], [100.0])                           # MgF₂ 100 nm on BK7 (substrate first)
TWO = (N_BK7, [2.4, 1.38], [10.0, 100.0])               # a thin TiO₂ (below the TE₀ cut-off) under MgF₂
PSD = PSDModel("gaussian", 2e-9, T=1e-6)
COATED = "BK7|MgF2:100nm"


def _unpolarized(d):
    return d["s"] + d["p"]


@pytest.mark.parametrize("stack", [AR, TWO], ids=["MgF2", "TiO2-MgF2"])
@pytest.mark.parametrize("theta, above", [(0.0, True), (45.0, True), (75.0, True), (20.0, False), (60.0, False)])
def test_optical_theorem_of_a_lossless_coated_rough_glass(stack, theta, above):
    """ΔR + ΔT of each polarization (second order, the mean field) = TIS_R + TIS_T (first order, scattered light)
    for a lossless stack, from the air and from the glass (60°: beyond the critical angle, no coherent T)."""
    for corr in ("correlated", "uncorrelated"):
        c = stack_coherent_losses(math.cos(math.radians(theta)), above, stack, PSD, corr, LAM_NM)
        for pol in ("s", "p"):
            r, t = rough_stack_tis_sides(theta, LAM_NM, stack, PSD, corr, pol, from_above=above)
            loss = c["dR"][pol] + c["dT"][pol]
            assert loss == pytest.approx(r + t, rel=1e-6), (corr, pol, loss, r, t)   # measured ≤ 2.8e-8


@pytest.mark.parametrize("theta", [20.0, 35.0])
def test_coherent_transmission_of_a_coated_rough_glass_is_reciprocal(theta):
    """T₀ − ΔT from the air at θ₁ equals T₀ − ΔT from the glass at the Snell angle θ₂, per polarization (the mean
    field obeys reciprocity), for correlated and uncorrelated films."""
    t1 = math.radians(theta)
    t2 = math.asin(math.sin(t1) / N_BK7)
    for corr in ("correlated", "uncorrelated"):
        up = stack_coherent_losses(math.cos(t1), True, TWO, PSD, corr, LAM_NM)
        down = stack_coherent_losses(math.cos(t2), False, TWO, PSD, corr, LAM_NM)
        for pol in ("s", "p"):
            a, b = up["T0"][pol] - up["dT"][pol], down["T0"][pol] - down["dT"][pol]
            assert a == pytest.approx(b, rel=1e-6), (corr, pol)
            assert up["dT"][pol] != 0.0


@pytest.mark.parametrize("theta, pol", [(30.0, "s"), (30.0, "p"), (70.0, "p")])
def test_coherent_losses_of_a_coated_glass_against_the_rigorous_grating(theta, pol):
    """ΔR and ΔT of MgF₂ on BK7, both interfaces rough and correlated, against the rigorous Rayleigh-method solve of
    a grating on both interfaces integrated over the Gaussian PSD (28 × 20 nodes; measured within 1e-6 at 30°, 7e-4
    at 70°, where the reference's own quadrature limits it)."""
    t = math.radians(theta)
    wi = np.array([math.sin(t), 0.0, math.cos(t)])
    films = [(1.38, 100e-9)]
    dR, dT = stack_integrated_losses(1.0, films, N_BK7, wi, PSD.S, PSD.T, LAM_NM * 1e-9, pol, rough=1.0,
                                     correlation="correlated")
    c = stack_coherent_losses(math.cos(t), True, AR, PSD, "correlated", LAM_NM)
    assert c["dR"][pol] == pytest.approx(dR, rel=2e-3)
    assert c["dT"][pol] == pytest.approx(dT, rel=2e-3)


@pytest.fixture(scope="module")
def coated():
    """σ = 20 nm, T = 1 µm on MgF₂-coated BK7, α = 0.02: a few % of the light goes to the nano lobes."""
    psd = PSDModel("gaussian", 20e-9, T=1e-6)
    return NanoRoughDielectricBSDF(COATED, Micro(alpha=0.02, ndf="ggx", shadowing="smith-correlated"), psd=psd)


@pytest.mark.parametrize("theta, side", [(0.0, 1), (60.0, 1), (60.0, -1)])
def test_white_furnace_of_a_coated_nano_rough_glass(coated, theta, side):
    """∫ f |cos θ_o| dω_o over the sphere = 1 within 1e-2 by importance sampling (seeded); the nano lobes carry
    more than 1 % of the light, and the coating reflects less than the bare glass does (its purpose)."""
    t = math.radians(theta)
    wi = np.array([math.sin(t), 0.0, side * math.cos(t)])
    n = 40000
    u = np.random.default_rng(int(theta) + 7 * side).random((n, 2))
    s = coated.sample(wi, LAM_NM, u)
    assert s.weight.std() / math.sqrt(n) < 3e-3
    assert s.weight.mean() == pytest.approx(1.0, abs=1e-2)
    parts = coated.albedo_parts(wi, LAM_NM)
    assert float(parts["nano_reflection"] + parts["nano_transmission"]) > 0.01
    if side > 0 and theta == 0.0:
        bare = NanoRoughDielectricBSDF("BK7", coated.micro, psd=coated.psd).albedo_parts(wi, LAM_NM)
        assert float(parts["reflection"]) < 0.5 * float(bare["reflection"])


def _pairs(seed, n=6):
    rng = np.random.default_rng(seed)
    th, ph = np.radians(rng.uniform(5, 80, (n, 2))), np.radians(rng.uniform(0, 360, (n, 2)))
    wi = np.stack([np.sin(th[:, 0]) * np.cos(ph[:, 0]), np.sin(th[:, 0]) * np.sin(ph[:, 0]), np.cos(th[:, 0])], -1)
    wo = np.stack([np.sin(th[:, 1]) * np.cos(ph[:, 1]), np.sin(th[:, 1]) * np.sin(ph[:, 1]), -np.cos(th[:, 1])], -1)
    return wi, wo


@pytest.mark.parametrize("frame", ["macro", "facet"])
def test_coated_nano_rough_glass_is_reciprocal_with_the_eta_squared_factor(frame):
    """f(i, o)/η_o² = f(o, i)/η_i² across the coated interface: the nano part in the macro and in the facet frame
    of the nano lobes (the facet frame: each micro facet a rough coated interface), and the coherent transmission
    in the facet frame, whose A_T is read at the Snell pair's air-side cosine (the macro frame reads it at μ_i, the
    α → 0 form: 3e-4 off at α = 0.15, as for the bare glass)."""
    cls = {"macro": NanoRoughDielectricBSDF, "facet": TwoScaleDielectricBSDF}[frame]
    psd = PSDModel("gaussian", 10e-9, T=0.8e-6)
    b = cls(COATED, Micro(alpha=0.15, ndf="beckmann", shadowing="smith-correlated"), psd=psd)
    wi, wo = _pairs(33)
    eta = float(np.real(get_material(COATED).substrate.eta(LAM_NM)))
    fwd, back = b.eval_parts(wi, wo, LAM_NM), b.eval_parts(wo, wi, LAM_NM)
    for key in ("nano", "transmission") if frame == "facet" else ("nano",):
        np.testing.assert_allclose(fwd[key] / eta ** 2, back[key], rtol=1e-6, err_msg=key)
    assert np.all(fwd["nano"] > 0)


@pytest.mark.parametrize("psd", [PSDModel("abc", 5e-9, B=2e-6, C=2.6), PSDModel("exponential", 5e-9, T=1e-6)])
def test_a_psd_tail_the_films_cannot_take_is_refused_when_the_bsdf_is_made(psd):
    """S ∝ |f|^−C with C ≤ 3 (∫ S |f| d²f diverges: the films' coherent split is not finite to second order) is
    refused by the coated glass at construction, naming the field (one line on the command line, exit 2), not in
    a renderer's first lookup; the bare glass takes it."""
    from cli_helpers import run_cli
    from waveoptics.errors import FieldError

    with pytest.raises(FieldError) as e:
        NanoRoughDielectricBSDF(COATED, Micro(alpha=0.1), psd=psd)
    assert e.value.fields == ("psd",) and "C > 3" in str(e.value)
    NanoRoughDielectricBSDF("BK7", Micro(alpha=0.1), psd=psd)
    spec = "abc:sigma=5nm,B=2um,C=2.6" if psd.kind == "abc" else "exponential:sigma=5nm,corr_length=1um"
    rc, _, err, _ = run_cli(["brdf", "--model", "rough-dielectric", "--alpha", "0.1", "--material", COATED,
                             "--nano", spec, "--incident", "30", "--wavelengths", "550", "--albedo"])
    assert rc == 2 and "--nano" in err and len(err.strip().splitlines()) == 1, err


def test_brdf_command_rayleigh_rice_scatters_into_a_transparent_substrate():
    """`brdf --model rayleigh-rice` takes directions below a transparent material (bare BK7 and MgF₂-coated BK7),
    and light from inside it:
    the value at the specular transmission direction and off it equals the rigorous grating solve times the PSD at
    the grating equation's frequency (computed here); `--albedo` prints R and T, T equal to a brute-force
    quadrature of the command's own BTDF over the lower hemisphere; below a metal the command refuses in one line."""
    import json

    from cli_helpers import run_cli
    from rr_stack_grating import stack_order_bsdf

    psd = PSDModel("gaussian", 5e-9, T=0.4e-6)
    nano = "gaussian:sigma=5nm,corr_length=0.4um"
    t_i = math.radians(30.0)
    wi = np.array([math.sin(t_i), 0.0, math.cos(t_i)])
    n_sub, (n_mgf2,) = get_material(COATED).indices(np.array([LAM_NM]))     # the data sets' indices at 550 nm
    n_sub, n_mgf2 = float(np.real(n_sub[0])), complex(n_mgf2[0])
    for material, films in (("BK7", []), (COATED, [(n_mgf2, 100e-9)])):
        outs = [(160.8, 180.0), (140.0, 150.0)]
        args = ["brdf", "--model", "rayleigh-rice", "--material", material, "--nano", nano, "--incident", "30",
                "--wavelengths", "550", "--json"]
        rc, out, err, _ = run_cli(args + sum((["--outgoing", f"{t},{p}"] for t, p in outs), []))
        assert rc == 0, err
        for row, (t, p) in zip(json.loads(out)["values"], outs):
            th, ph = math.radians(t), math.radians(p)
            wo = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
            rig = stack_order_bsdf(1.0, films, n_sub, wi, wo, LAM_NM * 1e-9, ka=1e-4)
            f = (wi[:2] + n_sub * wo[:2]) / (LAM_NM * 1e-9)
            want = 0.5 * sum(rig.values()) * float(psd.S(np.hypot(*f)))
            assert row["brdf"] == pytest.approx(want, rel=1e-5), (material, t, p)
        rc, out, err, _ = run_cli(args[:-1] + ["--albedo", "--json"])
        row = json.loads(out)["albedo"][0]
        # T by brute force: Gauss-Legendre in cos θ_o and the midpoint rule in φ_o over the lower hemisphere
        x, w = np.polynomial.legendre.leggauss(48)
        mu, wmu = 0.5 * (x + 1), 0.5 * w
        phi = (np.arange(96) + 0.5) * 2 * np.pi / 96
        dirs = [f"{math.degrees(math.acos(-m)):.12g},{math.degrees(p):.12g}" for m in mu for p in phi]
        rc, out, err, _ = run_cli(args + sum((["--outgoing", d] for d in dirs), []))
        f = np.array([v["brdf"] for v in json.loads(out)["values"]]).reshape(mu.size, phi.size)
        T = float(np.sum(wmu[:, None] * mu[:, None] * f) * 2 * np.pi / phi.size)
        assert row["transmission"] == pytest.approx(T, rel=2e-3), (material, row, T)
        assert row["albedo"] == pytest.approx(row["reflection"] + row["transmission"], rel=1e-12)
    # light from inside the coated glass (θ_i 160°: 20° in the BK7) out into the air, against the solver lit from
    # the glass (the stack turned over)
    rc, out, err, _ = run_cli(["brdf", "--model", "rayleigh-rice", "--material", COATED, "--nano", nano,
                               "--incident", "160", "--outgoing", "40,170", "--wavelengths", "550", "--json"])
    assert rc == 0, err
    t_i, t_o, p_o = math.radians(20.0), math.radians(40.0), math.radians(170.0)
    wi_s = np.array([math.sin(t_i), 0.0, math.cos(t_i)])                     # the solver's frame: glass on top
    wo_s = np.array([math.sin(t_o) * math.cos(p_o), math.sin(t_o) * math.sin(p_o), -math.cos(t_o)])
    rig = stack_order_bsdf(n_sub, [(n_mgf2, 100e-9)], 1.0, wi_s, wo_s, LAM_NM * 1e-9, ka=1e-4)
    f = (n_sub * wi_s[:2] + wo_s[:2]) / (LAM_NM * 1e-9)
    want = 0.5 * sum(rig.values()) * float(psd.S(np.hypot(*f)))
    assert json.loads(out)["values"][0]["brdf"] == pytest.approx(want, rel=1e-5)
    # the rough dielectric lit from inside the coated glass: lossless, R + T = 1 with multiple scattering
    rc, out, err, _ = run_cli(["brdf", "--model", "rough-dielectric", "--alpha", "0.1", "--material", COATED,
                               "--nano", nano, "--incident", "160", "--albedo", "--multiple-scattering",
                               "--wavelengths", "550", "--json"])
    assert rc == 0 and json.loads(out)["albedo"][0]["albedo"] == pytest.approx(1.0, abs=1e-2), err
    rc, _, err, _ = run_cli(["brdf", "--model", "rayleigh-rice", "--material", "Al", "--nano", nano,
                             "--incident", "30", "--outgoing", "150,0", "--wavelengths", "550"])
    assert rc == 2 and "--outgoing" in err and len(err.strip().splitlines()) == 1, err
