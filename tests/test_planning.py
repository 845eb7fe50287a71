"""Scene files and the effect planner: validation, decisions from physics, forcing, and what runs.

Runs use small direction grids (32-48 cells per side) so that the file stays well under a minute.
"""
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.special import jv

from waveoptics import colour, scatter
from waveoptics import io, planning
from waveoptics.planning import scene
from waveoptics.brdf import twoscale
from waveoptics.errors import WaveopticsError

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
RES = 40  # direction grid of the runs


def plastic(**over):
    """The smooth-plastic example as a dict (small grid), with overrides."""
    d = {"name": "plastic", "accuracy": {"delta_e": 1.0},
         "materials": [{"name": "plastic", "ior": 1.5, "roughness": 0.05, "ndf": "ggx", "diffuse_albedo": 0.5,
                        "nano": {"statistics": "gaussian:sigma=0.5nm,corr_length=1um"}}],
         "lights": [{"name": "sun", "spd": "D65", "directions_deg": [[30, 0]]}],
         "view": {"directions_deg": [[0, 0], [30, 180], [60, 180]]},
         "output": {"rgb_images": False, "tables": True, "resolution": RES}}
    d.update(over)
    return scene.parse(d)


def run(sc, tmp_path, name, max_resolution=None, **force):
    plan = planning.plan_scene(sc, force=force, max_resolution=max_resolution)
    data = planning.execute(plan, tmp_path / name)
    res = json.loads((tmp_path / name / "results.json").read_text())
    return plan, data, res


def view_rgb(res):
    return np.array([v["rgb"] for m in res["materials"] for v in m["views"]])


# ------------------------------------------------------------------------------------------------ scene files

@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_example_scenes_load_and_plan(path):
    sc = scene.load(path)
    plan = planning.plan_scene(sc, max_resolution=64)
    assert plan.entries and all(e.reasons for e in plan.entries)
    for e in plan.entries:
        decided = {d for d, _, _ in e.decisions}
        assert {"diffuse", "diffraction", "wavelengths", "solver", "resolution", "directions",
                "precision"} <= decided
        assert e.estimated_time_s > 0
    text = plan.table()
    assert sc.name in text and "estimated" in text


def test_diffraction_model_is_the_scenes_or_kirchhoff_with_its_reason(tmp_path):
    """A scene may name the diffraction model of a material; otherwise the planner picks Kirchhoff and says why,
    and the run uses the model the plan names."""
    mat = {"name": "plastic", "ior": 1.5, "roughness": 0.05, "ndf": "ggx", "diffuse_albedo": 0.5,
           "nano": {"statistics": "gaussian:sigma=20nm,corr_length=1um"}}
    auto = planning.plan_scene(plastic(materials=[mat]))
    e = auto.entries[0]
    assert e.diffraction == "kirchhoff" and e.effects["diffraction"]
    assert any(d == "diffraction model" and "Kirchhoff" in r for d, _, r in e.decisions)
    plan = planning.plan_scene(plastic(materials=[dict(mat, diffraction="rghs")]))
    e = plan.entries[0]
    assert e.diffraction == "rghs" and ("diffraction model", "rghs", "set by the scene") in e.decisions
    res = planning.run_entry(e)
    L = next(iter(res.lobes.values()))
    L = L[0] if isinstance(L, list) else L
    assert L.info["diffraction_model"] == "rghs"


@pytest.mark.parametrize("data, key, allowed", [
    ({"bogus": 1}, "bogus", "allowed: name"),
    ({"materials": [{"name": "a", "material": "Au", "roughnes": 0.1}]}, "materials[0].roughnes",
     "did you mean 'roughness'"),
    ({"materials": [{"name": "a", "material": "Au", "roughness": -0.1}]}, "materials[0].roughness",
     "in [0, 2]"),
    ({"materials": [{"name": "a"}]}, "materials[0]", "exactly one of material"),
    ({"materials": [{"name": "a", "material": "unobtainium"}]}, "materials[0].material", "unknown material"),
    ({"materials": [{"name": "a", "ior": 1.5, "nano": {"statistics": "abc:sigma=1nm,B=1um,C=3",
                                                       "file": "x.npz"}}]}, "materials[0].nano", "exactly one"),
    ({"materials": [{"name": "a", "ior": 1.5, "nano": {"statistics": "sinusoid:amplitude=1nm,period=1um"}}]},
     "materials[0].nano.statistics", "use generator"),
    ({"materials": [{"name": "a", "ior": 1.5, "nano": {"generator": {"model": "sinusoid", "amplitude": "1nm",
                                                                     "period": "1um"}}}]},
     "materials[0].nano.generator", "lacks size"),
    ({"lights": [{"name": "l", "spd": "D65", "directions_deg": [[95, 0]]}]}, "lights[0].directions_deg[0]",
     "0 <= theta"),
    ({"lights": [{"name": "l", "spd": "D66"}]}, "lights[0].spd", "unknown illuminant"),
    ({"view": {"camera": "fisheye"}}, "view.camera", "allowed: sphere"),
    ({"output": {"tables": True, "rgb_images": False}}, "output.tables", "needs view.directions_deg"),
    ({"accuracy": {"delta_e": 0}}, "accuracy.delta_e", "> 0"),
    ({"materials": [{"name": "a", "material": "Au", "diffraction": "hs"}]}, "materials[0].diffraction",
     "ghs"),
])
def test_scene_errors_are_one_line_naming_the_key(data, key, allowed):
    base = {"materials": [{"name": "a", "material": "Au"}], "lights": [{"name": "l", "spd": "D65"}]}
    base.update(data)
    with pytest.raises(WaveopticsError) as exc:
        scene.parse(base, where="s.toml")
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"s.toml: {key}") and allowed in msg, msg


def test_scene_file_errors(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("name = [unclosed\n")
    with pytest.raises(WaveopticsError, match="not valid TOML"):
        scene.load(p)
    with pytest.raises(WaveopticsError, match="does not exist"):
        scene.load(tmp_path / "missing.toml")


# ------------------------------------------------------------------------------------- decisions from physics

def test_g_factor_is_the_davies_exponent():
    """g at the mirror direction is Davies' (4πσ cosθ_i / λ)² (written here from the paper), and the coherent
    fraction is exp(−g); the planner and the series share this one g."""
    sigma, lam, c = 5e-9, 450.0, 0.8
    davies = (4 * np.pi * sigma * c / (lam * 1e-9)) ** 2
    assert float(scatter.roughness_g(sigma, 2 * c, lam)) == pytest.approx(davies, rel=1e-12)
    assert float(scatter.debye_waller(c, lam, sigma)) == pytest.approx(np.exp(-davies), rel=1e-12)


@pytest.mark.parametrize("width, dE", [(0.02, 1.0), (0.1, 0.5), (0.05, 3.0)])
def test_grid_step_bounds_interpolation_error(width, dE):
    """Linear interpolation of a Gaussian lobe at grid_step(s, ΔE) errs by ≤ ΔE / DE_PER_RELATIVE_Y of its peak."""
    h = planning.grid_step(width, dE)
    x = np.linspace(-5 * width, 5 * width, 20001)
    nodes = np.arange(-6 * width - 0.37 * h, 6 * width, h)   # an arbitrary offset of the grid
    f = np.exp(-0.5 * (x / width) ** 2)
    interp = np.interp(x, nodes, np.exp(-0.5 * (nodes / width) ** 2))
    err = np.max(np.abs(interp - f))
    assert err <= dE / planning.DE_PER_RELATIVE_Y * 1.0001
    assert err >= 0.5 * dE / planning.DE_PER_RELATIVE_Y          # and the bound is not loose


def test_grating_orders_follow_bessel_efficiencies():
    a, period, lam = 40e-9, 1.6e-6, 400.0
    x = 4 * np.pi * a / (lam * 1e-9)
    m = planning.grating_orders(a, period, lam)
    assert jv(m, x) ** 2 >= planning.ORDER_EFFICIENCY_MIN > jv(m + 1, x) ** 2
    assert m == 3


def test_float64_for_large_patches_only():
    """The float32 floor grows with the samples while the weakest visible level falls as (λ/L)²."""
    lam, dE = 400.0, 1.0
    for L, want64 in ((24e-6, False), (2e-3, True)):
        n = int((4 * L / (lam * 1e-9)) ** 2)       # dx = λ/4
        floor = planning.float32_floor(n, 50e-9, lam)
        assert (floor > planning.FLOOR_MARGIN * planning.weakest_level(dE, L, lam)) is want64


def test_smooth_plastic_plans_no_diffraction_and_no_wavelengths():
    e = planning.plan_scene(scene.load(SCENES / "smooth-plastic.toml")).entries[0]
    assert e.effects["diffraction"] is False and e.solver == "none"
    assert e.effects["diffuse"] is True
    # constant index, no diffraction: the BRDF is the same at every λ, so nothing is simulated per wavelength
    assert e.wavelengths_nm.size == 0 and e.effects["spectral"] is False
    assert e.metrics["estimated_delta_e"] < planning.ESTIMATE_SHARE * 1.0
    w = np.array([420.0, 560.0, 690.0])
    L = twoscale.evaluate(np.array([0.5, 0, math.sqrt(0.75)]), w, e.material, e.micro, None,
                          scatter.DirectionGrid.hemisphere(24), kd=e.kd)
    assert np.array_equal(L.total[0], L.total[1]) and np.array_equal(L.total[0], L.total[2])


def test_polished_metal_keeps_diffraction_on_the_psd_route():
    e = planning.plan_scene(scene.load(SCENES / "polished-aluminium-haze.toml"), max_resolution=48).entries[0]
    assert e.effects["diffraction"] and e.solver == "psd"
    assert e.metrics["estimated_delta_e"] > 1.0
    assert e.wavelengths_nm.size > 1


def test_metal_has_no_diffuse_term(tmp_path):
    sc = scene.load(SCENES / "gold-sphere-daylight.toml")
    plan = planning.plan_scene(sc, max_resolution=32)
    e = plan.entries[0]
    assert e.effects["diffuse"] is False and e.kd == 0
    assert any("metal" in r for r in e.reasons)
    res = planning.run_entry(e)
    assert not np.any(res.lobes[(30.0, 0.0)].diffuse)
    with pytest.raises(WaveopticsError, match="metal"):
        planning.plan_scene(sc, force={"diffuse": True})


def test_laser_scene_simulates_only_the_laser_lines(tmp_path):
    lines = [465.0, 532.0, 638.0]
    sc = plastic(materials=[{"name": "glass", "material": "BK7", "roughness": 0.05, "ndf": "ggx", "diffuse_albedo": 0.3,
                             "nano": {"statistics": "abc:sigma=5nm,B=2um,C=2.6"}}],
                 lights=[{"name": "rgb", "spd": "laser:465,532,638", "directions_deg": [[30, 0]]}],
                 output={"spectral_brdf": True, "rgb_images": False, "resolution": 32})
    plan, data, res = run(sc, tmp_path, "laser", diffraction=True)
    e = plan.entries[0]
    assert e.wavelengths_nm.tolist() == lines and np.asarray(data["materials"][0]["wavelengths_nm"]).tolist() == lines
    assert res["materials"][0]["wavelengths_nm"] == lines
    layers, _ = io.read_spectral_exr(tmp_path / "laser" / "glass_i30_0_brdf_spectral.exr")
    assert sorted(layers) == lines
    grating = planning.plan_scene(scene.load(SCENES / "grating-laser.toml")).entries[0]
    assert grating.wavelengths_nm.tolist() == [532.0] and grating.effects["diffraction"]


def test_plastic_skips_diffraction_with_the_same_result_as_forcing_it(tmp_path):
    """The planner leaves diffraction out of the smooth-plastic scene and loses nothing: the forced run agrees within
    the scene's ΔE target (how much time that saves is measured by docs/planning.md's estimated-vs-measured table,
    not asserted here: a timing ratio fails on a loaded machine)."""
    sc = scene.load(SCENES / "smooth-plastic.toml")          # sphere camera, images, tables at three views
    plan, data, res = run(sc, tmp_path, "planned", max_resolution=RES)
    plan_f, data_f, res_f = run(sc, tmp_path, "forced", max_resolution=RES, diffraction=True)
    assert not plan.entries[0].effects["diffraction"] and plan_f.entries[0].effects["diffraction"]
    assert data["measured_time_s"] > 0 and data_f["measured_time_s"] > 0
    # the same result within the accuracy target: at the view directions, on the sphere, in the albedo
    dE = colour.delta_e2000(view_rgb(res), view_rgb(res_f))
    assert np.max(dE) <= sc.delta_e
    a, a_f = (np.array(r["materials"][0]["albedo"]["i30_0"]["rgb"]) for r in (res, res_f))
    assert colour.delta_e2000(a, a_f) <= sc.delta_e
    assert res_f["materials"][0]["sphere"]["delta_e2000_vs_microfacet"]["max"] <= sc.delta_e
    # plan.json holds the measured time beside the estimate
    saved = json.loads((tmp_path / "planned" / "plan.json").read_text())
    m = saved["materials"][0]
    assert m["measured_time_s"] > 0 and m["estimated_time_s"] > 0 and m["effects"]["diffraction"] is False


def test_forcing_diffraction_off_removes_the_haze(tmp_path):
    """A polished metal whose haze the planner keeps: forcing diffraction off changes its colour by > target."""
    d = {"name": "haze", "materials": [{"name": "al", "material": "Al", "roughness": 0.02, "ndf": "ggx",
                                        "nano": {"statistics": "abc:sigma=5nm,B=5um,C=2.5"}}],
         "lights": [{"name": "sun", "spd": "D65", "directions_deg": [[30, 0]]}],
         "view": {"directions_deg": [[25, 180], [40, 180]]},
         "output": {"rgb_images": False, "tables": True, "resolution": 32}}
    sc = scene.parse(d)
    plan, _, res = run(sc, tmp_path, "on")
    plan_off, _, res_off = run(sc, tmp_path, "off", diffraction=False)
    assert plan.entries[0].effects["diffraction"] and not plan_off.entries[0].effects["diffraction"]
    assert plan_off.entries[0].decisions[1][2].startswith("forced")
    dE = colour.delta_e2000(view_rgb(res), view_rgb(res_off))
    assert np.max(dE) > sc.delta_e


def test_forcing_diffuse_off_removes_the_diffuse_albedo(tmp_path):
    sc = plastic(output={"rgb_images": True, "resolution": 32})
    _, _, on = run(sc, tmp_path, "on")
    _, _, off = run(sc, tmp_path, "off", diffuse=False)
    a_on = on["materials"][0]["albedo"]["i30_0"]["albedo"][0]
    a_off = off["materials"][0]["albedo"]["i30_0"]["albedo"][0]
    # n = 1.5: specular albedo ≈ F ≈ 0.04-0.05; the substrate adds kd (1 − F)-ish
    assert a_off < 0.08 and a_on - a_off > 0.35


def test_view_patches_equal_the_hemisphere_at_the_view_directions():
    sc = plastic(materials=[{"name": "al", "material": "Al", "roughness": 0.05, "ndf": "ggx",
                             "nano": {"statistics": "abc:sigma=5nm,B=5um,C=2.5"}}],
                 lights=[{"name": "l", "spd": "laser:532", "directions_deg": [[30, 0]]}])
    vals = {}
    for d in ("views", "hemisphere"):
        e = planning.plan_scene(sc, force={"diffraction": True, "directions": d}).entries[0]
        assert e.directions == d
        vals[d] = np.array([r["brdf"] for r in planning.view_values(planning.run_entry(e))])
    np.testing.assert_allclose(vals["views"], vals["hemisphere"], rtol=1e-3)


def test_force_validation():
    assert planning.parse_force(["diffraction", "diffuse=off", "solver=fft"]) == \
        {"diffraction": True, "diffuse": False, "solver": "fft"}
    with pytest.raises(WaveopticsError, match="did you mean 'diffraction'"):
        planning.parse_force(["difraction"])
    with pytest.raises(WaveopticsError, match="solver takes psd, fft, direct"):
        planning.parse_force(["solver=magic"])
    sc = plastic(materials=[{"name": "bare", "ior": 1.5}])
    with pytest.raises(WaveopticsError, match="no nano surface"):
        planning.plan_scene(sc, force={"diffraction": True})
    with pytest.raises(WaveopticsError, match="directions=views"):
        planning.plan_scene(plastic(output={"rgb_images": True}), force={"directions": "views"})


def test_estimate_tracks_measured_time(tmp_path, monkeypatch):
    """The calibrated cost model (timed here, not the tests' seeded one) is within an order of magnitude of the
    measured run (a broken model is not)."""
    cm = planning.costmodel.calibration(recalibrate=True)
    monkeypatch.setattr(planning.planner, "calibration", lambda **kw: cm)
    sc = plastic(output={"rgb_images": False, "tables": True, "resolution": 48})
    _, data, _ = run(sc, tmp_path, "t", diffraction=True)
    m = data["materials"][0]
    assert 0.1 < m["measured_time_s"] / m["estimated_time_s"] < 10


# ------------------------------------------------------------------------------------------------------- CLI

def _cli(capsys, *args):
    """Run the CLI dispatcher in this process: (exit code, stdout, stderr)."""
    from waveoptics.cli import main

    rc = main([str(a) for a in args])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_cli_plan_json_and_errors(tmp_path, capsys):
    rc, out, err = _cli(capsys, "plan", SCENES / "gold-sphere-daylight.toml", "--json", "--max-resolution", "32")
    assert rc == 0, err
    d = json.loads(out)
    m = d["materials"][0]
    assert {"name", "effects", "solver", "wavelengths_nm", "precision", "estimated_time_s", "reasons"} <= set(m)
    assert m["name"] == "gold" and m["effects"]["diffuse"] is False and m["solver"] == "none"
    bad = tmp_path / "bad.toml"
    bad.write_text('[[materials]]\nname = "x"\nmaterial = "Au"\nroughness = "rough"\n'
                   '[[lights]]\nname = "l"\n')
    rc, _, err = _cli(capsys, "plan", bad)
    assert rc == 2 and err.count("\n") == 1 and "materials[0].roughness" in err
    rc, _, err = _cli(capsys, "plan", bad.with_name("none.toml"))
    assert rc == 2 and "does not exist" in err


def test_cli_run_writes_outputs_and_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "out"
    rc, text, err = _cli(capsys, "run", SCENES / "smooth-plastic.toml", "-o", out, "--max-resolution", "32")
    assert rc == 0, err
    assert "estimated" in text and "measured" in text
    for f in ("plan.json", "results.json", "plastic_sphere.png", "plastic_table.csv", "plastic_i30_0_brdf.png"):
        assert (out / f).is_file(), f
    plan = json.loads((out / "plan.json").read_text())
    assert plan["materials"][0]["measured_time_s"] > 0
    rc, _, err = _cli(capsys, "run", SCENES / "smooth-plastic.toml", "-o", out, "--max-resolution", "32")
    assert rc == 2 and "already exists" in err and err.count("\n") == 1


def test_cli_is_a_console_command():
    r = subprocess.run([sys.executable, "-m", "waveoptics", "plan", "--help"], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0 and "--force" in r.stdout


def test_height_field_file_fft_and_direct_agree_at_the_views(tmp_path, rt):
    """A grating given as a file: diffraction on, a Kirchhoff solver; fft and direct give the same orders."""
    from waveoptics import surfaces

    hf = surfaces.generate("sinusoid", amplitude="40nm", period="1.6um", size="12um", samples=128)
    surfaces.save(hf, tmp_path / "grating.npz")
    (tmp_path / "g.toml").write_text(
        '[[materials]]\nname = "grating"\nmaterial = "Al"\nroughness = 0.005\nndf = "ggx"\n'
        '[materials.nano]\nfile = "grating.npz"\n'
        '[[lights]]\nname = "laser"\nspd = "laser:532"\ndirections_deg = [[20, 0]]\n'
        '[view]\ndirections_deg = [[20, 180], [0.545, 180], [18.85, 0]]\n'
        '[output]\nrgb_images = false\ntables = true\nresolution = 128\n')
    sc = scene.load(tmp_path / "g.toml")
    vals = {}
    for solver in ("fft", "direct"):
        e = planning.plan_scene(sc, force={"solver": solver, "directions": "views"}).entries[0]
        assert e.effects["diffraction"] and e.solver == solver and e.directions == "views"
        assert e.wavelengths_nm.tolist() == [532.0]
        if solver == "direct":
            assert e.precision == "float32" and any("noise floor" in r for r in e.reasons)
        vals[solver] = np.array([r["brdf"] for r in planning.view_values(planning.run_entry(e))]).ravel()
    np.testing.assert_allclose(vals["direct"], vals["fft"], rtol=1e-4)
    # orders 1 and 2 at the same incidence: their ratio follows the Raman-Nath efficiencies within a factor 2
    x = 4 * np.pi * 40e-9 / 532e-9 * math.cos(math.radians(20))
    assert 0.5 < (vals["fft"][1] / vals["fft"][2]) / (jv(1, x) ** 2 / jv(2, x) ** 2) < 2
    auto = planning.plan_scene(sc).entries[0]
    assert auto.solver in ("fft", "direct") and any("both exact Kirchhoff" in r for r in auto.reasons)


def test_grating_under_daylight_samples_wavelengths_finer_than_one_cell_per_order():
    """Grating equation: order m moves by m Δλ/Λ in direction cosine, so Δλ ≤ Λ du / m keeps the rainbow whole."""
    sc = plastic(materials=[{"name": "g", "material": "Al", "roughness": 0.005, "ndf": "ggx",
                             "nano": {"generator": {"model": "sinusoid", "amplitude": "40nm", "period": "1.6um",
                                                    "size": "12um", "samples": 128}}}],
                 output={"rgb_images": True})
    e = planning.plan_scene(sc, max_resolution=64).entries[0]
    du = 2.0 / e.resolution
    m = planning.grating_orders(40e-9, 1.6e-6, float(e.wavelengths_nm.min()))
    step = float(np.diff(e.wavelengths_nm)[0])
    assert step <= 1.6e-6 * du / m * 1e9 and step < 20.0
    assert any("periodic nano surface" in r for r in e.reasons)
