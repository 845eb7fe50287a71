"""An anisotropic micro NDF (α_y) through the request: ``simulate`` (library and command line), ``table`` and the
request's validation. References: the grid evaluation ``brdf.evaluate`` with the anisotropic Micro (another entry
point), and Beckmann's slope law (Beckmann & Spizzichino 1963; Walter et al. 2007 eq. 25): its slopes (p, q) are
Gaussian with variances α_x²/2 and α_y²/2, and at normal incidence the mirror-reflected direction cosines are
(u, v) ≈ −2 (p, q), so the lobe's second moments about the mirror direction stand in the ratio (α_y/α_x)²."""
import json

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import brdf
from waveoptics.errors import FieldError
from waveoptics.request import SimulationRequest
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.simulate import simulate

AX, AY = 0.1, 0.2
NANO = "gaussian:sigma=5nm,corr_length=1um"
KW = dict(material="Au", nano=NANO, wavelengths=[550.0], resolution=32, sphere=False, micro_alpha=AX, ndf="beckmann")


def _dir(theta_deg, phi_deg=0.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def test_simulate_lobes_are_the_grid_evaluation_of_the_anisotropic_micro():
    """``simulate(alpha_y=...)`` gives the lobes ``brdf.evaluate`` gives with Micro(α, α_y) at the same light (to
    1e-12), and they differ from the isotropic request's by far more."""
    sim = simulate(alpha_y=AY, incident=(30.0, 20.0), **KW)
    iso = simulate(incident=(30.0, 20.0), **KW)
    micro = brdf.Micro(alpha=AX, alpha_y=AY, ndf="beckmann")
    from waveoptics.request import make_nano

    ref = brdf.evaluate(_dir(30.0, 20.0), [550.0], "Au", micro, make_nano(NANO, [550.0]),
                        DirectionGrid.hemisphere(32))
    for part in ("coherent", "diffraction", "microfacet"):
        a, b = getattr(sim.lobes, part), getattr(ref, part)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * float(np.abs(b).max()), err_msg=part)
    diff = np.abs(sim.lobes.microfacet - iso.lobes.microfacet).max()
    assert diff > 0.1 * np.abs(iso.lobes.microfacet).max()
    assert sim.params["alpha_y"] == AY and iso.params["alpha_y"] is None
    assert sim.params["micro_alpha_used"] == [AX, AY]


def test_lobe_width_ratio_follows_alpha_y_over_alpha_x():
    """Beckmann at normal incidence: the microfacet lobe's second moments of u and v about the mirror direction
    (0, 0), weighted by f cos θ_o (the grid's projected solid angle du dv), stand in the ratio (α_y/α_x)² = 4 of the
    slope law within 10 % (the small-slope map u ≈ −2p is exact to O(α²))."""
    grid = DirectionGrid.hemisphere(64)
    sim = simulate(alpha_y=AY, incident=(0.0, 0.0), **{**KW, "resolution": 64})
    f = np.where(grid.inside, sim.lobes.microfacet[0], 0.0)
    u, v = np.meshgrid(grid.u, grid.v)
    mu, mv = (f * u**2).sum(), (f * v**2).sum()
    assert mv / mu == pytest.approx((AY / AX) ** 2, rel=0.1)


def test_cli_simulate_summary_carries_alpha_y(tmp_path):
    rc, out, err, _ = run_cli(["simulate", "--alpha-y", str(AY), "--micro-alpha", str(AX), "--resolution", "32",
                               "--wavelengths", "550", "--sphere-size", "16",
                               "--nano", "gaussian:sigma=0nm,corr_length=1um",
                               "-o", str(tmp_path / "o"), "--quiet"])
    assert rc == 0, err
    params = json.loads((tmp_path / "o" / "summary.json").read_text())["parameters"]
    assert params["alpha_y"] == AY and params["micro_alpha"] == AX


@pytest.mark.parametrize("extra", [["--alpha-y", "-0.1"], ["--alpha-y", "nan"], ["--alpha-y", "3"],
                                   ["--alpha-y", "0.2", "--ndf", "abc"],
                                   ["--alpha-y", "0.2", "--micro-surface", "nofile.npy"]])
def test_cli_bad_alpha_y_is_one_line_naming_the_option(tmp_path, extra):
    rc, out, err, _ = run_cli(["simulate", *extra, "--resolution", "16", "-o", str(tmp_path / "o")])
    lines = [x for x in err.splitlines() if x.strip()]
    assert rc == 2 and len(lines) == 1 and "--alpha-y" in lines[0], err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("kw", [dict(alpha_y=-1.0), dict(alpha_y=float("inf")), dict(alpha_y=0.2, ndf="blinn-phong"),
                                dict(alpha_y=0.2, micro_surface="x.npy"),
                                dict(alpha_y=0.2, split=True, surface="x.npy", nano=None)])
def test_request_refuses_alpha_y_naming_the_field(kw):
    with pytest.raises(FieldError) as exc:
        SimulationRequest(**kw)
    assert "alpha_y" in exc.value.fields


def test_anisotropic_case_has_its_own_token():
    """A cached or resumed isotropic result is never taken for an anisotropic one: the table token differs."""
    from waveoptics.distributed import TableSpec

    base = SimulationRequest(wavelengths_nm=(550.0,), resolution=16)
    tokens = {TableSpec(r, thetas_deg=(30.0,)).token() for r in (base, SimulationRequest(
        wavelengths_nm=(550.0,), resolution=16, alpha_y=0.2), SimulationRequest(wavelengths_nm=(550.0,),
                                                                               resolution=16, alpha_y=0.3))}
    assert len(tokens) == 3


def test_cli_table_attrs_carry_alpha_y(tmp_path):
    from waveoptics.distributed import read_table

    out = tmp_path / "t.h5"
    rc, _, err, _ = run_cli(["table", "--nano", "gaussian:sigma=0nm,corr_length=1um", "--alpha-y", "0.25",
                             "--incident-angles", "30", "--wavelengths", "550", "--resolution", "16", "-o", str(out),
                             "--quiet"])
    assert rc == 0, err
    t = read_table(out)
    assert t.params["alpha_y"] == 0.25 and t.params["micro_alpha"] == pytest.approx(0.05)


#: a scene with an anisotropic material, in TOML's inline tables (NDF: its NDF)
SCENE = ('materials = [{name = "brushed", material = "Al", roughness = 0.1, roughness_y = 0.3, ndf = "NDF", '
         'nano = {statistics = "gaussian:sigma=3nm,corr_length=1um"}}]\n'
         'lights = [{name = "sun", spd = "D65", directions_deg = [[30, 0]]}]\noutput = {resolution = 16}\n')


def test_scene_roughness_y_reaches_the_request_and_the_planner(tmp_path):
    from waveoptics.planning import load, plan_scene, request_of

    path = tmp_path / "s.toml"
    path.write_text(SCENE.replace("NDF", "ggx"))
    sc = load(path)
    assert sc.materials[0].roughness_y == 0.3 and sc.materials[0].micro().alpha_y == 0.3
    req = request_of(sc, None, None)
    assert (req.micro_alpha, req.alpha_y) == (0.1, 0.3)
    plan_scene(sc)   # the planner sizes the anisotropic lobe (no crash)
    rc, out, err, _ = run_cli(["plan", str(path)])
    assert rc == 0, err


@pytest.mark.parametrize("text", [SCENE.replace("NDF", "abc"), SCENE.replace("NDF", "ggx").replace("0.3", "-0.3"),
                                  SCENE.replace("NDF", "ggx").replace('ndf = "ggx"', 'micro_surface = "m.npy"')])
def test_scene_refuses_a_bad_roughness_y_naming_the_key(tmp_path, text):
    from waveoptics.planning import load

    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(Exception) as exc:
        load(path)
    assert "roughness_y" in str(exc.value).splitlines()[0]
