"""Renders that report their noise floor (issue 31, part 4): ``waveoptics render`` renders the wave-optics model a
second time with seeds of its own and reports the CIEDE2000 between its two renders (the Monte Carlo noise floor)
beside the model-vs-reference ΔE2000; ``--target-noise`` doubles the samples per pixel until the floor is below
it. The reference for the floor's fall is the Monte Carlo standard error ∝ 1/√N (Veach 1997, §2.4): a fit of
log(floor) against log(spp) has slope −1/2."""
import json
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from cli_helpers import run_cli  # noqa: E402

pytest.importorskip("mitsuba")

from waveoptics.renderers import scene  # noqa: E402
from waveoptics.renderers import mitsuba as wm  # noqa: E402

HAVE_LLVM = (wm.llvm_library()[1] or 0) >= wm.LLVM_MIN or bool(os.environ.get("DRJIT_LIBLLVM_PATH"))
needs_llvm = pytest.mark.skipif(not HAVE_LLVM, reason="no libLLVM >= 17 for Mitsuba's JIT")

SIZE = 32


def _scenes(mi, settings):
    from waveoptics.renderers import lighting

    env = lighting.procedural_environment("studio", height=64)
    metal = {"type": "roughconductor", "material": "Cu", "alpha": 0.3}
    return {k: scene.scene_dict(mi, metal, env.radiance, settings) for k in ("wave", "reference")}


@pytest.fixture(scope="module")
def mi():
    return wm.register("scalar_rgb")


def test_noise_floor_falls_as_one_over_sqrt_spp(mi):
    settings = scene.RenderSettings(size=SIZE, spp=16, variant="scalar_rgb", ground=False, passes=2)
    mask = scene.sphere_mask(SIZE)
    # a target no render reaches: the rounds run to the most samples per pixel and say so
    c = scene.render_comparison(mi, _scenes(mi, settings), settings, mask, target_noise=1e-6, max_spp=256)
    spp, floor = np.array(c.history).T
    assert list(spp) == [16, 32, 64, 128, 256] and c.spp == 256
    assert "most samples per pixel" in c.stop and len(c.stop.splitlines()) == 1
    slope = np.polyfit(np.log(spp), np.log(floor), 1)[0]
    assert abs(slope + 0.5) < 0.08, (slope, floor)
    # the floor is a property of the noise, not of the images: two identical BSDFs here, so the model difference
    # (common random numbers: the reference shares the first render's seeds) is zero
    assert np.array_equal(c.images["wave"], c.images["reference"])
    assert not np.array_equal(c.images["wave"], c.images["wave_repeat"])
    assert np.isclose(float(np.mean(c.noise_floor[mask])), floor[-1])


def test_target_noise_stops_when_reached(mi):
    settings = scene.RenderSettings(size=SIZE, spp=4, variant="scalar_rgb", ground=False, passes=1)
    mask = scene.sphere_mask(SIZE)
    c = scene.render_comparison(mi, _scenes(mi, settings), settings, mask, target_noise=6.0, max_spp=1024)
    floors = [f for _, f in c.history]
    assert floors[-1] < 6.0 <= floors[-2], c.history      # stopped at the first round below the target
    assert c.spp == 4 * 2 ** (len(floors) - 1) < 1024
    assert "below the target" in c.stop
    # without a target: one round
    one = scene.render_comparison(mi, _scenes(mi, settings), settings, mask)
    assert one.spp == 4 and len(one.history) == 1 and one.stop == ""


def test_the_time_budget_stops_the_doubling(mi):
    settings = scene.RenderSettings(size=16, spp=4, variant="scalar_rgb", ground=False, passes=1)
    c = scene.render_comparison(mi, _scenes(mi, settings), settings, scene.sphere_mask(16), target_noise=1e-6,
                                budget_s=1e-6)
    assert c.spp == 4 and "time budget" in c.stop


def test_bad_noise_settings_name_their_fields(mi):
    from waveoptics.errors import FieldError

    settings = scene.RenderSettings(size=16, spp=4, variant="scalar_rgb", ground=False)
    for kw, field in ((dict(target_noise=0.0), "target_noise"), (dict(max_spp=2), "max_spp"),
                      (dict(budget_s=-1.0), "budget")):
        with pytest.raises(FieldError, match=field):
            scene.render_comparison(mi, _scenes(mi, settings), settings, scene.sphere_mask(16), **kw)


@needs_llvm
def test_render_summary_holds_the_model_difference_beside_the_noise_floor(tmp_path):
    out = tmp_path / "r"
    rc, stdout, err, _ = run_cli(["render", "--material", "copper", "--micro-alpha", "0.3", "--nano", "none",
                                  "--wavelength-step", "94nm", "--sphere-size", "16", "--spp", "4", "--no-ground",
                                  "--environment", "studio", "--target-noise", "1e-6", "--max-spp", "8",
                                  "-o", str(out), "--json"])
    assert rc == 0, err
    s = json.loads(stdout)
    assert s == json.loads((out / "summary.json").read_text())
    de, floor = s["delta_e2000"], s["noise_floor_delta_e2000"]
    assert de["mean"] >= 0 and floor["mean"] > 0 and "CIEDE2000" in de["meaning"] and "seeds" in floor["meaning"]
    assert s["model_to_noise"] == pytest.approx(de["mean"] / floor["mean"])
    assert s["spp"] == 8 and [n for n, _ in s["noise_history"]] == [4, 8] and "most samples" in s["stop"]


def test_render_noise_options_are_refused_in_one_line(tmp_path):
    for argv, text in ((["--target-noise", "0"], "--target-noise"), (["--max-spp", "2", "--spp", "4"], "--max-spp"),
                       (["--budget", "soon"], "--budget")):
        rc, _, err, _ = run_cli(["render", "--nano", "none", *argv, "-o", str(tmp_path / "x")])
        assert rc == 2 and text in err and len(err.strip().splitlines()) == 1, err
    rc, _, err, _ = run_cli(["render", "--glints", "--surface", "x.npy", "--target-noise", "1",
                             "-o", str(tmp_path / "g")])
    assert rc == 2 and "--target-noise belongs to the sphere render" in err, err
