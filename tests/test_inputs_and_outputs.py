"""One regression test per class of broken promise an adversarial corpus found (issue 34, reliability round three):
negative radiance in outputs, a hang, multi-line errors, meaningless inputs silently accepted, legal inputs refused.

The corpus itself stays outside the project; these tests hold the mechanisms (and tests/test_cli_fuzz.py draws the
same grammars), not its cases.
"""
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from cli_helpers import run_cli
from output_scan import count_outputs, scan_outputs
from waveoptics import io as wio
from waveoptics.errors import WaveopticsError

SCENES = Path(__file__).resolve().parents[1] / "examples" / "scenes"


def _one_line(argv, *needles):
    rc, out, err, _ = run_cli(argv)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert rc == 2 and len(lines) == 1 and "Traceback" not in err, (argv, err)
    assert lines[0].startswith("waveoptics "), err
    for n in needles:
        assert n in lines[0], (n, lines[0])
    return lines[0]


def _field(tmp_path, name="h.npz", sigma=5e-9, n=32):
    np.savez(tmp_path / name, heights=np.random.default_rng(7).normal(0.0, sigma, (n, n)), dx=1e-7, dy=1e-7)
    return tmp_path / name


# --- negative radiance in outputs --------------------------------------------------------------------------------

#: CIE 1931 2° colour-matching functions at 520 nm (CIE 015:2018 table) and the XYZ → linear sRGB matrix of
#: IEC 61966-2-1: a monochromatic 520 nm light lies outside the sRGB triangle, so its R is negative
CMF_520 = np.array([0.06327, 0.71000, 0.07825])
XYZ_TO_SRGB = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])


def test_an_out_of_gamut_colour_is_kept_and_stated_in_the_file(tmp_path):
    green = XYZ_TO_SRGB @ CMF_520
    assert green[0] < 0   # the reference itself: a non-negative spectrum, a negative sRGB component
    img = np.full((4, 5, 3), 0.18)
    img[1, 2] = green
    note = wio.write_rgb_exr(tmp_path / "g.exr", img)
    chans, hdr = wio.read_exr(tmp_path / "g.exr")
    rgb = chans["RGB"] if "RGB" in chans else np.stack([chans[c] for c in "RGB"], axis=-1)
    assert rgb[1, 2, 0] == np.float32(green[0])                   # kept, not clipped
    assert note == {"pixels": 1, "of": 20, "min": pytest.approx(green[0], rel=1e-6), "space": "sRGB"}
    assert hdr["waveoptics_out_of_gamut"].startswith("1 of 20 pixels lie outside the linear sRGB gamut")
    assert wio.write_rgb_exr(tmp_path / "grey.exr", np.full((2, 2, 3), 0.5)) is None
    assert "waveoptics_out_of_gamut" not in wio.read_exr(tmp_path / "grey.exr")[1]
    img[0, 0, 1] = np.nan
    with pytest.raises(wio.NonFiniteOutputError, match="n.exr"):
        wio.write_rgb_exr(tmp_path / "n.exr", img)
    assert not (tmp_path / "n.exr").exists()


def test_a_spectral_exr_refuses_a_negative_or_non_finite_value(tmp_path):
    for bad in (-1e-25, np.inf):
        layer = np.ones((3, 3))
        layer[1, 1] = bad
        with pytest.raises(wio.NonFiniteOutputError, match="550 nm"):
            wio.write_spectral_exr(tmp_path / "s.exr", {450.0: np.ones((3, 3)), 550.0: layer})
        assert not (tmp_path / "s.exr").exists()


def test_the_fft_solver_s_point_values_never_leave_the_range_of_their_cells(tmp_path):
    """The fft solver evaluates f at given directions from its hemisphere grid: bilinear between the four nearest
    cell centres (a convex combination), held at the edge cells. Linear extrapolation beyond the outermost centres
    gave f < 0 towards the horizon (down to -1.0 1/sr for this field: σ = 50 nm, θ_i = 45°, 16² cells). Reference: the
    grid's own cell values (bounds of any convex combination)."""
    from waveoptics import surfaces
    from waveoptics.scatter.grid import DirectionGrid
    from waveoptics.scatter.solvers import lobe_at_fft
    from waveoptics.scatter.patch import samples

    hf = surfaces.HeightField(np.random.default_rng(3).normal(0, 50e-9, (32, 32)), 1e-7, 1e-7)
    wi = np.array([np.sin(np.radians(45)), 0.0, np.cos(np.radians(45))])
    th = np.radians(np.r_[0.0, 45.0, 80.0, 88.0, 89.9])
    ph = np.radians(np.linspace(0, 360, 24, endpoint=False))
    T, P = np.meshgrid(th, ph)
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    f = lobe_at_fft(samples(hf, "hann", "mean"), wi, wo, np.array([550.0]), lambda *a: 1.0, resolution=16)
    assert np.all(np.isfinite(f)) and f.min() >= 0.0
    assert DirectionGrid.hemisphere(16).interpolate(np.ones((16, 16)), wo[:, 0], wo[:, 1]).min() == 1.0


def _tour(tmp_path):
    """The README tour's commands that write EXR and JSON files, at their smallest settings."""
    base = ["--resolution", "16", "--sphere-size", "16", "--quiet"]
    from waveoptics import surfaces

    two_scale = tmp_path / "two.npz"   # both scales: 100 nm of height over 3 µm, 5 nm over 0.2 µm (isotropic)
    h = (surfaces.gaussian("100nm", "3um", "12.8um", 128, seed=11).heights
         + surfaces.gaussian("5nm", "0.2um", "12.8um", 128, seed=12).heights)
    np.savez(two_scale, heights=h, dx=100e-9, dy=100e-9)
    nano = _field(tmp_path, "nano.npz")
    return [
        ["simulate", "--surface", str(two_scale), "--split", "--wavelengths", "450,550,650", *base,
         "-o", str(tmp_path / "split")],
        ["simulate", "--nano", "abc:sigma=10nm,B=2um,C=2.6", "--illuminant", "laser:450,532,635", "--material",
         "Au", *base, "-o", str(tmp_path / "laser")],
        ["simulate", "--diffraction", "rayleigh-rice", "--nano", "abc:sigma=4nm,B=3um,C=2.8", "--incident", "80",
         "--wavelengths", "450,650", *base, "-o", str(tmp_path / "rr")],
        ["simulate", "--nano", "Gaussian: sigma=5nm, corr_length=1um", "--wavelengths", "450,650", *base,
         "-o", str(tmp_path / "upper")],
        ["scatter", "--surface", str(nano), "--material", "Al", "--incident", "30", "--wavelengths", "400,700",
         "--resolution", "16", "-o", str(tmp_path / "scat"), "--quiet"],
        ["brdf", "--model", "kirchhoff", "--surface", str(nano), "--solver", "fft", "--resolution", "16",
         "--material", "Al", "--incident", "60", "--outgoing", "89.9,0", "--outgoing", "89.9,90", "--json"],
    ]


def test_no_output_of_the_readme_tour_holds_a_negative_or_non_finite_brdf_or_radiance(tmp_path):
    for argv in _tour(tmp_path):
        rc, out, err, _ = run_cli(argv)
        assert rc == 0, (argv, err)
        if "--json" in argv:
            (tmp_path / "brdf.json").write_text(out)
    assert count_outputs(tmp_path) >= 14
    assert scan_outputs(tmp_path) == []
    summary = json.loads((tmp_path / "split" / "summary.json").read_text())
    assert set(summary["out_of_gamut"]) <= {"brdf_rgb.exr", "sphere_wave.exr", "sphere_microfacet.exr"}


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_no_output_of_an_example_scene_holds_a_negative_or_non_finite_value(path, tmp_path):
    from waveoptics import planning
    from waveoptics.planning import scene

    d = tomllib.loads(path.read_text())
    d.setdefault("output", {})["sphere_size"] = 16
    d.setdefault("accuracy", {})["delta_e"] = 10.0   # the coarsest wavelength grid the planner picks
    for m in d.get("materials", []):   # the smallest generated fields (a file keeps its own)
        gen = m.get("nano", {}).get("generator")
        if gen:
            gen["samples"] = min(int(gen.get("samples", 64)), 64)
    sc = scene.parse(d, base=path.parent, name=path.stem)
    plan = planning.plan_scene(sc, max_resolution=16)
    planning.execute(plan, tmp_path / "o")
    assert count_outputs(tmp_path / "o") >= 2
    assert scan_outputs(tmp_path / "o") == []


# --- a hang ------------------------------------------------------------------------------------------------------

def test_the_cost_model_and_the_memory_check_see_every_nano_kind(monkeypatch):
    from waveoptics import simulate
    from waveoptics.planning.estimate import simulation_time
    from waveoptics.request import SimulationRequest

    req = lambda nano, **kw: SimulationRequest(nano=nano, resolution=16, wavelengths_nm=(550.0,), **kw)  # noqa: E731
    psd = simulate.memory_estimate(req("gaussian:sigma=5nm,corr_length=1um"))
    for nano in ("sinusoid:amplitude=40nm,period=2um", "scratches:count=20,width=200nm,depth=30nm"):
        assert simulate.memory_estimate(req(nano)) >= psd + 10 * 16 * 512 ** 2
    assert simulate.memory_estimate(req("gaussian:sigma=5nm,corr_length=1um", solver="fft")) > psd
    # the fft solver's expansion grows with the heights: 1 mm of amplitude is orders of magnitude dearer
    low = simulation_time(req("sinusoid:amplitude=40nm,period=2um"), sphere=False)
    high = simulation_time(req("sinusoid:amplitude=1mm,period=2um"), sphere=False)
    assert high > 100 * low


def test_a_request_beyond_the_time_budget_is_refused_before_any_output(tmp_path, monkeypatch):
    from waveoptics.brdf import twoscale

    def no_work(*a, **k):
        raise AssertionError("work started before the time check")

    monkeypatch.setenv("WAVEOPTICS_MAX_TIME", "0.001")
    monkeypatch.setattr(twoscale, "evaluate", no_work)
    _one_line(["simulate", "--resolution", "16", "--wavelengths", "550", "-o", str(tmp_path / "o")],
              "time budget", "WAVEOPTICS_MAX_TIME", "--resolution")
    assert not (tmp_path / "o").exists()
    monkeypatch.setenv("WAVEOPTICS_MAX_TIME", "soon")
    _one_line(["simulate", "--resolution", "16", "-o", str(tmp_path / "o")], "'soon'", "90min")


# --- multi-line errors -------------------------------------------------------------------------------------------

def test_every_refusal_is_one_line_naming_the_value(tmp_path):
    empty, huge = tmp_path / "empty.csv", tmp_path / "huge.csv"
    empty.write_text("wavelength,lamp\n")
    huge.write_text("wavelength,lamp\n" + "".join(f"{380 + i * 0.001:.3f},1\n" for i in range(100_001)))
    for argv, needles in [
        (["cost", "--budget", "-1"], ["'-1'", "> 0"]), (["cost", "--budget", "nan"], ["'nan'"]),
        (["cost", "--target-error", "nan"], ["nan", "> 0"]),
        (["cost", "--resolutions", "7,16"], ["7", "divide"]),
        (["f0", "Au", "--illuminant", str(empty)], ["empty.csv", "no data rows"]),
        (["f0", "Au", "--illuminant", str(huge)], ["huge.csv", "at most 100000"]),
        (["scatter", "--surface", str(_field(tmp_path)), "--material", "Au", "--incident", "30", "--resolution",
          "16", "--wavelengths", "550", "-o", str(tmp_path / "s"), "--realizations", "1000000"],
         ["1000000", "1..256"]),
    ]:
        _one_line(argv, *needles)
    assert not (tmp_path / "s").exists()


# --- meaningless inputs silently accepted ------------------------------------------------------------------------

def test_meaningless_or_contradictory_inputs_are_refused(tmp_path):
    h = str(_field(tmp_path))
    sim = ["simulate", "--resolution", "16", "--sphere-size", "16", "-o", str(tmp_path / "o")]
    brdf = ["brdf", "--model", "microfacet", "--alpha", "0.1", "--material", "Au", "--incident", "30", "--outgoing",
            "40,180"]
    for argv, needles in [
        (sim + ["--device", ""], ["--device ''", "names no device"]),
        (["info", "--device", " "], ["--device ' '"]),
        (sim + ["--wavelengths", "550,,650"], ["'550,,650'", "empty item"]),
        (sim + ["--wavelengths", "1e300"], ["1e+300", "100..1e+06 nm"]),
        (sim + ["--wavelengths", "5"], ["5 nm", "X-rays", "scalar theory"]),
        (sim + ["--seed=-1"], ["--seed -1", "0..2**63-1"]),
        (brdf + ["--surface", h], ["--surface is not used by --model microfacet", "kirchhoff"]),
        (brdf + ["--solver", "fft"], ["--solver is not used by --model microfacet"]),
        (["table", "--resume", "--overwrite", "-o", str(tmp_path / "t.h5")], ["--resume", "--overwrite"]),
        (["cost", "--precisions", "float16"], ["'float16'", "float32, float64"]),
        (["run", str(SCENES / "smooth-plastic.toml"), "-o", str(tmp_path / "r"), "--force", "diffraction=on",
          "--force", "diffraction=off"], ["diffraction twice", "on and off"]),
        (["sweep", "--vary", "theta=30,30", "-o", str(tmp_path / "s.csv")], ["theta=30,30", "twice"]),
    ]:
        _one_line(argv, *needles)
    assert not any((tmp_path / n).exists() for n in ("o", "t.h5", "r", "s.csv"))


def test_a_brdf_model_takes_its_own_options():
    from waveoptics.cli.brdf import MODELS

    rc, out, err, _ = run_cli(["brdf", "--model", "microfacet", "--alpha", "0.1", "--material", "Au", "--incident",
                               "30", "--outgoing", "40,180", "--json"])
    assert rc == 0 and json.loads(out)["values"][0]["brdf"] > 0
    assert all(set(m.uses) for m in MODELS.values())


# --- legal inputs refused ----------------------------------------------------------------------------------------

def test_inputs_the_formats_allow_are_accepted(tmp_path):
    from waveoptics import colour, surfaces

    one = tmp_path / "laser.csv"
    one.write_text("wavelength,power\n532,1\n")
    spd = colour.illuminant(str(one))
    assert spd.lines and spd.wavelengths_nm.tolist() == [532.0]
    rc, out, err, _ = run_cli(["f0", "Au", "--illuminant", str(one), "--json"])
    assert rc == 0, err
    heights = np.random.default_rng(2).normal(0, 3.0, (8, 8))
    (tmp_path / "bom.txt").write_text("\n".join(" ".join(f"{v:.6f}" for v in r) for r in heights),
                                      encoding="utf-8-sig")
    hf = surfaces.load(tmp_path / "bom.txt", spacing="100nm", units="nm")
    np.testing.assert_allclose(hf.heights, heights * 1e-9, atol=1e-15)
    for key, value in (("spacing", [1e-7, 2e-7]), ("dx", [1e-7, 2e-7]), ("spacing", 1e-7)):
        np.savez(tmp_path / "s.npz", heights=heights, **{key: np.array(value)})
        hf = surfaces.load(tmp_path / "s.npz")
        assert (hf.dx, hf.dy) == ((1e-7, 2e-7) if np.size(value) == 2 else (1e-7, 1e-7))
    np.savez(tmp_path / "s3.npz", heights=heights, spacing=np.array([1e-7, 2e-7, 3e-7]))
    with pytest.raises(WaveopticsError, match="3 values"):
        surfaces.load(tmp_path / "s3.npz")
    rc, out, err, _ = run_cli(["materials", "*", "--limit", "2", "--json"])
    assert rc == 0 and json.loads(out)["total_matches"] > 1000
    rc, out, err, _ = run_cli(["materials", "Au*", "--json", "--limit", "500"])
    assert rc == 0 and all(m["spec"].lower().startswith("main/au") or "au" in m["book"].lower()
                           or m["name"].lower().startswith("au") for m in json.loads(out)["matches"])
