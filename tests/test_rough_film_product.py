"""Rough thin films in the product: the Rayleigh-Rice BRDF model, the two-scale nano lobe and the coherent
fraction of a film stack (issue 33), held to Elson's rough-stack BRDF called directly, to the single-interface
model, to the linearity of the cross-PSD in the correlation, and to energy: coherent + diffracted = the flat
stack's reflectance R(θ) from the transfer matrix (materials/stack.py)."""
from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from waveoptics import scatter
from waveoptics.brdf import build_brdf_model
from waveoptics.brdf.roughness_scales import Nano
from waveoptics.cli import main as cli_main
from waveoptics.errors import FieldError
from waveoptics.materials import get_material, stack as stack_tm, with_roughness_correlation
from waveoptics.request import SimulationRequest
from waveoptics.surfaces import PSDModel

LAM = np.array([450.0, 550.0, 650.0])
SPEC = "Al|Al2O3:120nm"
PSD = PSDModel("gaussian", sigma=2e-9, T=1e-6)


def _dirs(theta_deg, phi_deg):
    t, p = np.radians(np.asarray(theta_deg, float)), np.radians(np.asarray(phi_deg, float))
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


WI = _dirs([0.0, 30.0, 60.0], [0.0, 0.0, 0.0])
WO = _dirs([0.0, 20.0, 45.0, 70.0, 35.0], [0.0, 180.0, 90.0, 200.0, 10.0])


@pytest.mark.parametrize("corr", ["correlated", "uncorrelated", 0.3])
def test_model_by_name_equals_rough_stack_brdf(corr):
    m = build_brdf_model("rayleigh-rice", LAM, psd=PSD, material=SPEC, roughness_correlation=corr)
    got = m.evaluate(WI, WO)
    want = scatter.rough_stack_brdf(WI[None, :, None, :], WO[None, None], LAM[:, None, None], get_material(SPEC),
                                    PSD, corr)
    assert got.shape == (3, 3, 5) and np.all(want > 0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)
    parts = m.components(WI, WO)
    direct = scatter.rough_stack_components(WI[None, :, None, :], WO[None, None], LAM[:, None, None],
                                            get_material(SPEC), PSD, corr)
    for k in ("ss", "sp", "ps", "pp"):
        np.testing.assert_allclose(parts[k], direct[k], rtol=1e-12, atol=1e-300)


def test_stack_without_films_is_the_single_interface_model():
    bare = build_brdf_model("rayleigh-rice", LAM, psd=PSD, material="Al").evaluate(WI, WO)
    zero = build_brdf_model("rayleigh-rice", LAM, psd=PSD, material="Al|Al2O3:0nm").evaluate(WI, WO)
    np.testing.assert_allclose(zero, bare, rtol=1e-12)
    nofilm = dataclasses.replace(get_material(SPEC), films=())
    for pol in ("s", "p", "unpolarized"):
        lobe = scatter.rayleigh_rice_lobe(WI[None, :, None, :], WO[None, None], LAM[:, None, None], PSD, nofilm, pol)
        ref = build_brdf_model("rayleigh-rice", LAM, psd=PSD, material="Al", polarization=pol).evaluate(WI, WO)
        np.testing.assert_allclose(lobe, ref, rtol=1e-12)


def test_partial_correlation_is_linear_between_the_two_limits():
    """S_jk = c √(S_j S_k) off the diagonal: f(c) = (1 − c) f_uncorrelated + c f_correlated (Elson, Rahn &
    Bennett 1983), and a film changes the scatter."""
    st = get_material(SPEC)
    f = {c: scatter.rayleigh_rice_lobe(WI[None, :, None, :], WO[None, None], LAM[:, None, None], PSD,
                                       with_roughness_correlation(st, c)) for c in ("correlated", "uncorrelated", 0.25)}
    np.testing.assert_allclose(f[0.25], 0.75 * f["uncorrelated"] + 0.25 * f["correlated"], rtol=1e-12)
    assert np.max(np.abs(f["correlated"] / f["uncorrelated"] - 1)) > 0.05


def _hemisphere_albedo(lobe, theta_i, n=160):
    """∫ f cosθ_o dω_o by the midpoint rule in (θ_o, φ_o), written here (independent of the library's
    quadratures)."""
    t = (np.arange(n) + 0.5) * (np.pi / 2) / n
    p = (np.arange(2 * n) + 0.5) * (2 * np.pi) / (2 * n)
    T, P = np.meshgrid(t, p, indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    wi = _dirs(theta_i, 0.0)
    f = lobe(wi, wo)
    return float(np.sum(f * np.cos(T) * np.sin(T)) * (np.pi / 2 / n) * (2 * np.pi / (2 * n)))


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0])
def test_coherent_plus_diffracted_is_the_stack_reflectance(theta):
    """On a metal substrate no light crosses into a propagating transmitted wave: to first order the light the
    rough stack scatters, TIS(θ), is what its specular beam loses, so A·R + TIS = R with A the coherent fraction
    (1 − TIS/R, mirroring one rough metal interface). R from the transfer matrix of materials/stack.py."""
    lam = 550.0
    psd = PSDModel("gaussian", sigma=3e-9, T=0.4e-6)
    st = get_material(SPEC)
    nano = Nano(model=psd)
    ns, nf = st.indices(lam)
    c = np.cos(np.radians(theta))
    R = 0.5 * (stack_tm.R(c, lam, ns, nf, st.thicknesses_nm, "s") + stack_tm.R(c, lam, ns, nf, st.thicknesses_nm, "p"))
    A = float(nano.coherent_fraction(c, lam, "rayleigh-rice", st))
    tis = _hemisphere_albedo(lambda wi, wo: scatter.rayleigh_rice_lobe(wi, wo, lam, psd, st), theta)
    assert 1e-3 < tis < 0.05 * R          # lightly rough: first order
    assert abs(A * float(R) + tis - float(R)) < 1e-3
    assert abs(A * float(R) + tis - float(R)) < 0.02 * tis   # the loss matches the scatter, not just small


def test_request_field_and_validation():
    rr = dict(material=SPEC, diffraction="rayleigh-rice")
    assert SimulationRequest().roughness_correlation == "correlated"
    assert SimulationRequest(**rr, roughness_correlation="0.5").roughness_correlation == 0.5
    assert SimulationRequest(**rr, roughness_correlation="Uncorrelated").roughness_correlation == "uncorrelated"
    for bad in ("partly", 1.5, -0.1, float("nan"), True):
        with pytest.raises(FieldError) as e:
            SimulationRequest(**rr, roughness_correlation=bad)
        assert e.value.field == "roughness_correlation"
        assert str(e.value).startswith("roughness_correlation")


def test_cli_brdf_rayleigh_rice_of_a_stack(capsys):
    args = ["brdf", "--model", "rayleigh-rice", "--material", SPEC, "--nano", "gaussian:sigma=2nm,corr_length=1um",
            "--incident", "30", "--outgoing", "20,180", "--outgoing", "45,90", "--wavelengths", "450,550,650",
            "--json"]
    for corr in ("correlated", "uncorrelated"):
        assert cli_main(args + ["--roughness-correlation", corr]) == 0
        rows = json.loads(capsys.readouterr().out)["values"]
        wi, wo = _dirs(30.0, 0.0), _dirs([20.0, 45.0], [180.0, 90.0])
        want = scatter.rough_stack_brdf(wi[None, None, :], wo[None], LAM[:, None], get_material(SPEC), PSD, corr)
        got = np.array([[r["brdf"] for r in rows if r["outgoing"] == o] for o in ([20.0, 180.0], [45.0, 90.0])]).T
        np.testing.assert_allclose(got, want, rtol=1e-12)
    assert cli_main(args + ["--roughness-correlation", "sometimes"]) == 2
    assert "--roughness-correlation 'sometimes'" in capsys.readouterr().err


def test_cli_simulate_a_coated_metal_under_rayleigh_rice(tmp_path, capsys):
    out = tmp_path / "s"
    assert cli_main(["simulate", "--material", SPEC, "--diffraction", "rayleigh-rice", "--resolution", "16", "--sphere-size", "32",
                     "--wavelengths", "450,550,650", "--nano", "gaussian:sigma=2nm,corr_length=1um", "--micro-alpha", "0.1",
                     "--roughness-correlation", "uncorrelated", "-o", str(out), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["parameters"]["diffraction"] == "rayleigh-rice"

    def numbers(x):
        if isinstance(x, dict):
            for v in x.values():
                yield from numbers(v)
        elif isinstance(x, list):
            for v in x:
                yield from numbers(v)
        elif isinstance(x, float):
            yield x

    assert all(np.isfinite(v) for v in numbers(res))
    files = [p for p in out.rglob("*") if p.is_file()]
    assert files
    for p in files:
        if p.suffix == ".npz":
            with np.load(p) as z:
                for k in z.files:
                    if z[k].dtype.kind in "fc":
                        assert np.all(np.isfinite(z[k])), (p.name, k)


def test_scene_key_reaches_the_request():
    from pathlib import Path

    from waveoptics.planning import scene

    path = Path(__file__).resolve().parents[1] / "examples" / "scenes" / "coated-aluminium.toml"
    sc = scene.load(path)
    req = scene.request_of(sc)
    assert req.material == SPEC and req.diffraction == "rayleigh-rice" and req.roughness_correlation == "correlated"
    doc = {"materials": [{"name": "m", "material": SPEC, "roughness_correlation": 0.4, "diffraction": "rayleigh-rice",
                          "nano": {"statistics": "gaussian:sigma=2nm,corr_length=1um"}}],
           "lights": [{"name": "l", "spd": "D65"}]}
    assert scene.request_of(scene.parse(doc, name="t")).roughness_correlation == 0.4
    doc["materials"][0]["roughness_correlation"] = "sometimes"
    with pytest.raises(Exception, match=r"materials\[0\]\.roughness_correlation = 'sometimes' is not allowed"):
        scene.parse(doc, name="t")


def test_a_correlation_for_a_material_without_films_is_refused_naming_both_fields():
    """An option the model does not use is refused, not ignored (issue 34): a bare material has one interface."""
    from waveoptics.errors import FieldError
    from waveoptics.request import SimulationRequest

    with pytest.raises(FieldError) as err:
        SimulationRequest(material="Al", roughness_correlation="uncorrelated").resolved()
    assert err.value.field == "roughness_correlation" and "material 'Al' has one interface" in str(err.value)


# --- a correlation the nano lobe does not use is refused (named model) or skipped with a line (planner) ------------

@pytest.mark.parametrize("model", ["kirchhoff", "ghs", "rghs", "ohs", "rohs"])
def test_a_correlation_under_a_kirchhoff_family_lobe_is_refused_naming_both_fields(model):
    """Only Rayleigh-Rice scatters from every interface of the stack; the tangent-plane lobes see the top surface, so
    the option would have no effect: refused, not ignored, naming the field and the model's field."""
    with pytest.raises(FieldError) as err:
        SimulationRequest(material=SPEC, diffraction=model, roughness_correlation="uncorrelated")
    assert err.value.fields == ("roughness_correlation", "diffraction")
    assert str(err.value) == (f"roughness_correlation 'uncorrelated' applies under diffraction 'rayleigh-rice' "
                              f"(first-order scatter from every interface of the stack); the {model} lobe scatters "
                              "from the top surface only and does not use it")
    # the default (a film replicating its substrate) is what every model assumes: taken everywhere
    assert SimulationRequest(material=SPEC, diffraction=model).roughness_correlation == "correlated"


def test_the_command_line_refuses_the_option_under_kirchhoff(tmp_path, capsys):
    out = tmp_path / "s"
    assert cli_main(["simulate", "--material", SPEC, "--roughness-correlation", "uncorrelated", "--resolution",
                     "16", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == ("waveoptics simulate: error: --roughness-correlation 'uncorrelated' applies under --diffraction "
                   "'rayleigh-rice' (first-order scatter from every interface of the stack); the kirchhoff lobe "
                   "scatters from the top surface only and does not use it")
    assert not out.exists()


def test_a_scene_refuses_a_correlation_its_named_model_or_material_does_not_use():
    from waveoptics.planning import scene

    def doc(**mat):
        return {"materials": [{"name": "m", "material": SPEC, "roughness_correlation": "uncorrelated",
                               "nano": {"statistics": "gaussian:sigma=2nm,corr_length=1um"}, **mat}],
                "lights": [{"name": "l", "spd": "D65"}]}

    with pytest.raises(Exception, match=r"materials\[0\]\.roughness_correlation = 'uncorrelated' applies under "
                                        r"diffraction = 'rayleigh-rice'.*the kirchhoff lobe"):
        scene.parse(doc(diffraction="kirchhoff"), name="t")
    with pytest.raises(Exception, match=r"materials\[0\]\.roughness_correlation = 'uncorrelated' applies to a "
                                        r"thin-film stack.*material 'Al' has one interface"):
        scene.parse(doc(material="Al"), name="t")
    assert scene.parse(doc(diffraction="rayleigh-rice"), name="t").materials[0].roughness_correlation == "uncorrelated"
    assert scene.parse(doc(), name="t").materials[0].diffraction == "auto"   # the planner decides


def _plan(directions, diffraction=True):
    """The plan entry of a coated aluminium with an uncorrelated interface roughness and diffraction = "auto" (the
    diffraction decision forced on or off: the colour estimate that would take it costs seconds here)."""
    from waveoptics.planning import plan_scene, scene

    doc = {"materials": [{"name": "m", "material": SPEC, "roughness": 0.02, "roughness_correlation": "uncorrelated",
                          "nano": {"statistics": "gaussian:sigma=5nm,corr_length=1um"}}],
           "lights": [{"name": "l", "spd": "D65", "directions_deg": directions}], "output": {"resolution": 32}}
    return plan_scene(scene.parse(doc, name="t"), force={"diffraction": diffraction}).entries[0]


def test_the_planner_uses_the_correlation_where_it_picks_rayleigh_rice_and_says_when_it_skips_it():
    """diffraction = "auto": at 80° on a smooth surface the planner picks Rayleigh-Rice, whose lobe takes the
    correlation; at 20° it picks Kirchhoff and says in one line that the correlation is skipped; without a nano
    lobe it says so too. The runner's request carries what is used."""
    e = _plan([[80, 0]])
    assert (e.diffraction, e.request.diffraction, e.request.roughness_correlation) == \
        ("rayleigh-rice", "rayleigh-rice", "uncorrelated")
    assert not [d for d in e.decisions if d[0] == "roughness correlation"]
    for directions, diffraction, why in (([[20, 0]], True, "the kirchhoff lobe scatters from the stack's top surface "
                                                             "only"),
                                         ([[80, 0]], False, "no nano lobe is simulated")):
        e = _plan(directions, diffraction)
        lines = [d for d in e.decisions if d[0] == "roughness correlation"]
        assert len(lines) == 1 and lines[0][1] == "skipped", e.decisions
        assert lines[0][2].startswith("roughness_correlation = 'uncorrelated' is not used: " + why)
        assert e.request.roughness_correlation == "correlated" and e.request.diffraction == "kirchhoff"
