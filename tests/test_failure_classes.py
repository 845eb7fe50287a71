"""One regression test per class of failure an adversarial user found (reliability, round two):

Each test names the class: tracebacks, runaway memory, NaN with exit 0, silent nonsense, non-atomic output.
"""
import json
import os
import resource

import numpy as np
import pytest

from waveoptics import io as wio
from waveoptics import units
from waveoptics.brdf import Micro, MicrofacetBRDF, normal_quadrature
from waveoptics.cli import main as cli_main
from waveoptics.errors import WaveopticsError


def _one_line_error(capsys, argv, *needles):
    rc = cli_main(argv)
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for n in needles:
        assert n in err, err
    return err


# --- tracebacks --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, needle", [("550:inf:1", "not a finite number"), ("0:1e400:1", "not a finite"),
                                          ("4nm00", "not a number list"), ("400:700:0.00001", "at most 100000")])
def test_number_lists_refuse_non_finite_stray_and_huge(text, needle):
    with pytest.raises(WaveopticsError, match=needle):
        units.parse_wavelengths(text)


def test_wavelength_units_per_value():
    np.testing.assert_allclose(units.parse_wavelengths("0.45um,550nm,650"), [450.0, 550.0, 650.0])


def test_cli_ranges_and_generators(capsys, tmp_path):
    _one_line_error(capsys, ["compare", "--incident-angles", "0:inf:1"], "--incident-angles", "finite")
    _one_line_error(capsys, ["surface", "generate", "--generator", "scratches", "--count", "5", "--width", "1um",
                             "--depth", "10nm", "--spread", "1e308", "--size", "20um", "--samples", "32", "-o",
                             str(tmp_path / "s.npz")], "spread")
    np.savez(tmp_path / "e.npz", heights=np.zeros((8, 8)), dx=np.array([]))
    _one_line_error(capsys, ["surface", "stats", str(tmp_path / "e.npz")], "dx", "0 values")


# --- NaN with exit 0 ---------------------------------------------------------------------------------------

def test_absurd_indices_and_orders_are_refused(capsys, tmp_path):
    np.savez(tmp_path / "h.npz", heights=np.random.default_rng(0).normal(0, 5e-9, (32, 32)), dx=1e-7, dy=1e-7)
    base = ["scatter", "--surface", str(tmp_path / "h.npz"), "--incident", "30", "--wavelengths", "550",
            "--resolution", "16", "-o", str(tmp_path / "o"), "--overwrite"]
    for m in ("1e-300", "1.5+1e308j"):
        _one_line_error(capsys, base + ["--material", m], "|n+ik|")
    _one_line_error(capsys, base + ["--material", "Au", "--order", "1000"], "order 1000")


def test_every_fft_order_stays_finite(capsys, tmp_path):
    """The Taylor terms are scaled by max |h|: order 60 used to print 'albedo nan' with exit 0."""
    np.savez(tmp_path / "h.npz", heights=np.random.default_rng(0).normal(0, 20e-9, (32, 32)), dx=1e-7, dy=1e-7)
    vals = []
    for order in ("0", "8", "60"):
        assert cli_main(["scatter", "--surface", str(tmp_path / "h.npz"), "--incident", "30", "--wavelengths",
                         "550", "--resolution", "16", "--material", "Au", "--order", order, "--json", "-o",
                         str(tmp_path / f"o{order}")]) == 0
        doc = json.loads(capsys.readouterr().out)
        vals.append(doc["albedo"][0] if isinstance(doc["albedo"], list) else doc["albedo"])
    assert np.all(np.isfinite(vals)) and vals[2] == pytest.approx(vals[1], rel=1e-6)


def test_json_output_refuses_nan_naming_the_result():
    with pytest.raises(WaveopticsError, match=r"rows\[1\]\.albedo is nan"):
        wio.to_json({"rows": [{"albedo": 0.5}, {"albedo": float("nan")}]})
    assert wio.to_json({"x": float("nan")}, strict=False) == '{"x": null}'


# --- runaway memory ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("ax, ay", [(2.0, 0.001), (0.001, 2.0)])
def test_albedo_of_extreme_anisotropy_against_visible_normal_sampling(ax, ay):
    """Ratio 2000: the quadrature (12 million nodes, used in blocks of NODE_BLOCK) against a Monte Carlo estimate
    from the GGX visible-normal sampler (an independent route: weights G2/G1 · F)."""
    b = MicrofacetBRDF("Au", Micro(alpha=ax, alpha_y=ay, ndf="ggx"))
    wi = np.array([0.5, 0.0, np.sqrt(0.75)])
    s = b.sample(wi, 550.0, np.random.default_rng(4).random((400_000, 2)))
    assert float(b.albedo(wi, 550.0)) == pytest.approx(s.weight.mean(),
                                                       abs=4 * s.weight.std() / np.sqrt(s.weight.size))


def test_moderate_anisotropy_nodes_still_cover_the_hemisphere():
    m, w = normal_quadrature(0.5, 0.005)
    assert w.sum() == pytest.approx(2 * np.pi, abs=1e-8)


def test_cli_albedo_of_an_extreme_anisotropy_in_bounded_memory(capsys):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    assert cli_main(["brdf", "--albedo", "--alpha", "2", "--alpha-y", "0.001", "--material", "Au",
                     "--incident", "30", "--json"]) == 0
    E = json.loads(capsys.readouterr().out)["albedo"][0]["albedo"]
    assert 0 < E < 1
    grown_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert grown_kb < 1_000_000   # < 1 GB (was 3.1 GB)


# --- silent nonsense and outputs ---------------------------------------------------------------------------

def test_empty_output_path_is_refused(capsys):
    _one_line_error(capsys, ["simulate", "-o", "", "--resolution", "16"], "output directory ''")


def test_outputs_honour_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        wio.write_exr(tmp_path / "a.exr", {"Y": np.zeros((2, 2))})
        wio.write_json(tmp_path / "b.json", {"x": 1})
    finally:
        os.umask(old)
    for name in ("a.exr", "b.json"):
        assert oct(os.stat(tmp_path / name).st_mode & 0o777) == oct(0o640)


def test_a_failed_json_write_names_the_output(tmp_path, monkeypatch):
    real_replace = os.replace

    def full_disk(src, dst):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(WaveopticsError, match=r"cannot write .*summary\.json.*No space left"):
        wio.write_json(tmp_path / "summary.json", {"x": 1})
    monkeypatch.setattr(os, "replace", real_replace)
    assert list(tmp_path.iterdir()) == []


def test_lambert_albedo_is_exact_on_any_grid():
    """The diffuse term's albedo is its closed form's quadrature, not the grid sum over the projected disc (which
    gave 1.035 for a kd = 1 dielectric at 8² cells): kd (1 − F(θ_i)) for Lambert with the trade-off."""
    from waveoptics.brdf import twoscale
    from waveoptics.materials import get_material
    from waveoptics.scatter.grid import DirectionGrid

    F0 = float(get_material("PMMA").F(1.0, 550.0))
    for res in (8, 16, 64):
        L = twoscale.evaluate(np.array([0.0, 0.0, 1.0]), [550.0], "PMMA", Micro(alpha=0.3, ndf="ggx"), None,
                              DirectionGrid.hemisphere(res), kd=1.0)
        assert float(L.albedo("diffuse")[0]) == pytest.approx(1.0 - F0, rel=1e-6)
        assert float(L.albedo("total")[0]) <= 1.0


@pytest.mark.parametrize("spec", ["nvidia", "99:99"])
def test_a_device_that_does_not_exist_is_refused_by_every_command(capsys, spec):
    pytest.importorskip("pyopencl")
    from waveoptics.runtime import opencl_available
    if not opencl_available():
        pytest.skip("no OpenCL platform")
    _one_line_error(capsys, ["brdf", "--alpha", "0.1", "--material", "Au", "--incident", "30", "--outgoing",
                             "30,180", "--device", spec], "no OpenCL device matches", "available")


def test_a_garbage_device_variable_is_refused(capsys, monkeypatch):
    from waveoptics.runtime import opencl_available
    if not opencl_available():
        pytest.skip("no OpenCL platform")
    monkeypatch.setenv("WAVEOPTICS_DEVICE", "garbage")
    _one_line_error(capsys, ["brdf", "--alpha", "0.1", "--material", "Au", "--incident", "30", "--outgoing",
                             "30,180"], "garbage")


def test_a_request_beyond_the_memory_budget_is_refused_before_any_work(capsys, tmp_path, monkeypatch):
    from waveoptics.brdf import twoscale
    from waveoptics.scatter import solvers

    def no_work(*args, **kwargs):   # any lobe evaluated means the budget was checked too late
        raise AssertionError("work started before the memory check")

    monkeypatch.setattr(twoscale, "evaluate", no_work)
    monkeypatch.setattr(solvers, "scatter", no_work)
    _one_line_error(capsys, ["simulate", "--resolution", "2048", "-o", str(tmp_path / "o")], "GB", "--max-memory",
                    "--resolution")
    assert not (tmp_path / "o").exists()
    monkeypatch.undo()
    _one_line_error(capsys, ["simulate", "--max-memory", "10XB", "-o", str(tmp_path / "o")], "not a size")
    from waveoptics import simulate
    from waveoptics.request import SimulationRequest
    with pytest.raises(WaveopticsError, match="max_memory budget of 0.001 GB"):
        simulate.run(SimulationRequest(resolution=64), max_memory="1MB")


def test_a_sweep_that_would_run_for_days_is_refused(capsys, tmp_path):
    _one_line_error(capsys, ["sweep", "--vary", "sigma_nano=1nm:1000nm:1nm", "--vary",
                             "material=Au,Ag,Cu,Al,Si,Ti,Zn,Ni,Fe,Cr,Pt", "-o", str(tmp_path / "s.csv")],
                    "points", "at most 10000")


def test_warnings_are_one_line_each_and_quiet_silences_them(capsys, tmp_path):
    """A warning the library raises (a retired nano parameter name; the grating on 32² cells this test used
    warned through the energy guard, which no longer acts there) reaches the terminal as one line."""
    argv = ["simulate", "--nano", "gaussian:sigma=20nm,T=1um", "-o", str(tmp_path / "o"), "--overwrite",
            "--resolution", "32", "--no-spheres", "--wavelengths", "550"]
    assert cli_main(argv) == 0
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines and all(ln.startswith("waveoptics simulate: warning: ") for ln in lines), err
    assert len(lines) == len(set(lines)) and "return " not in err   # no repeats, no source lines
    assert cli_main(argv + ["--quiet"]) == 0
    assert capsys.readouterr().err.strip() == ""


def test_an_aliased_grating_and_a_non_hdf5_table_are_refused(capsys, tmp_path):
    _one_line_error(capsys, ["surface", "generate", "--generator", "sinusoid", "--amplitude", "10nm", "--period", "100nm",
                             "--size", "10um", "--samples", "64", "-o", str(tmp_path / "s.npz")], "Nyquist")
    _one_line_error(capsys, ["table", "--incident-angles", "0,30", "-o", str(tmp_path / "t.txt")], "HDF5")
    assert not (tmp_path / "t.txt").exists()


def test_a_run_that_fails_while_writing_leaves_the_earlier_set_whole(capsys, tmp_path, monkeypatch):
    """Outputs are staged and moved into place only when all are whole: a failure half-way through the writing
    (after the EXRs, before the figures) leaves the earlier set byte for byte, and no staging litter."""
    from waveoptics import simulate

    out = tmp_path / "o"
    argv = ["simulate", "-o", str(out), "--resolution", "16", "--sphere-size", "16", "--wavelengths", "550",
            "--overwrite"]
    assert cli_main(argv) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(*a, **k):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(simulate, "_plot_lobes", broken)
    assert cli_main(argv + ["--wavelengths", "450,650"]) == 2
    assert "No space left" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_an_illuminant_file_in_micrometres_is_refused(tmp_path):
    from waveoptics import colour

    p = tmp_path / "um.csv"
    p.write_text("wavelength,lamp\n0.38,1\n0.5,1\n0.78,1\n")
    with pytest.raises(WaveopticsError, match="look like µm"):
        colour.illuminant(str(p))


def test_scatter_and_npy_sidecar_outputs_appear_whole(capsys, tmp_path, monkeypatch):
    from waveoptics import surfaces
    from waveoptics.scatter import output as scatter_output

    np.savez(tmp_path / "h.npz", heights=np.random.default_rng(1).normal(0, 5e-9, (32, 32)), dx=1e-7, dy=1e-7)
    out = tmp_path / "o"
    argv = ["scatter", "--surface", str(tmp_path / "h.npz"), "--incident", "30", "--wavelengths", "550",
            "--resolution", "16", "--material", "Au", "-o", str(out), "--overwrite"]
    assert cli_main(argv) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(scatter_output, "plot_scatter", lambda *a, **k: (_ for _ in ()).throw(OSError(28, "full")))
    argv2 = [a if a != "30" else "40" for a in argv]
    assert cli_main(argv2) == 2
    capsys.readouterr()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # .npy with its sidecar: a failure writing the sidecar leaves the earlier pair
    hf = surfaces.gaussian("5nm", "1um", "8um", 16, seed=1)
    surfaces.save(hf, tmp_path / "s.npy")
    pair = {p.name: p.read_bytes() for p in tmp_path.glob("s.npy*")}
    monkeypatch.setattr(wio.files.Path, "write_text", lambda *a, **k: (_ for _ in ()).throw(OSError(28, "full")))
    with pytest.raises(WaveopticsError):
        surfaces.save(surfaces.gaussian("9nm", "1um", "8um", 16, seed=2), tmp_path / "s.npy", overwrite=True)
    assert {p.name: p.read_bytes() for p in tmp_path.glob("s.npy*")} == pair


# --- issue 19's small defects ------------------------------------------------------------------------------

def test_small_defects_of_issue_19(capsys, tmp_path):
    import warnings

    from waveoptics import surfaces
    from waveoptics.surfaces.statistics import fit_psd

    assert units.parse_direction("30,400", name="incident_deg") == (30.0, 40.0)
    assert units.parse_direction("30,-30", name="incident_deg") == (30.0, -30.0)
    hf = surfaces.HeightField(np.random.default_rng(0).normal(0, 1e-9, (64, 64)), 1e-7, 1e-7)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = fit_psd(hf, "abc")
    assert fit["resolved"] is False and any("below the sample spacing" in str(w.message) for w in caught)
    out = tmp_path / "o"
    assert cli_main(["simulate", "-o", f"{out}/", "--resolution", "16", "--no-spheres", "--wavelengths",
                     "550"]) == 0
    assert "//" not in capsys.readouterr().out


def test_exr_images_put_the_highest_v_on_top(tmp_path):
    """Issue 19: a known asymmetric lobe lands in the expected pixel. Light at φ = 90° (from +y): the mirror
    direction has v = −sin θ_i < 0, so its peak is in the lower half of the image as a viewer shows it."""
    from waveoptics import scatter, surfaces

    hf = surfaces.gaussian("5nm", "2um", "32um", 128, seed=3)
    res = scatter.scatter(hf, (40.0, 90.0), [550.0], "Au", resolution=32)
    paths = scatter.write_scatter(res, tmp_path / "o")
    layers, header = wio.read_spectral_exr(paths["lobes.exr"])
    img = layers[550.0]
    row, col = np.unravel_index(np.argmax(img), img.shape)
    assert row > img.shape[0] / 2 and abs(col - img.shape[1] / 2) <= 1
    assert "row 0 = highest v" in header["parametrization"] and "1/sr" in header["waveoptics_unit"]


def test_simulate_and_scatter_take_units_and_spacing_for_a_bare_text_grid(capsys, tmp_path):
    """Issue 19: a profilometer grid without a units header was refused with 'pass --units', which simulate and
    scatter did not have."""
    h = np.random.default_rng(5).normal(0, 0.01, (48, 48))   # heights in µm, no header
    np.savetxt(tmp_path / "measured.txt", h)
    _one_line_error(capsys, ["scatter", "--surface", str(tmp_path / "measured.txt"), "--material", "Al",
                             "--incident", "30", "--wavelengths", "550", "--resolution", "16", "-o",
                             str(tmp_path / "s0")], "--units")
    assert cli_main(["scatter", "--surface", str(tmp_path / "measured.txt"), "--units", "um", "--spacing", "100nm",
                     "--material", "Al", "--incident", "30", "--wavelengths", "550", "--resolution", "16", "-o",
                     str(tmp_path / "s1"), "--quiet"]) == 0
    assert cli_main(["simulate", "--surface", str(tmp_path / "measured.txt"), "--units", "um", "--spacing",
                     "100nm", "--resolution", "16", "--no-spheres", "--wavelengths", "550", "-o",
                     str(tmp_path / "s2"), "--quiet", "--json"]) == 0
    capsys.readouterr()
    summary = json.loads((tmp_path / "s2" / "summary.json").read_text())
    assert summary["parameters"]["sigma_nano_m"] == pytest.approx(0.01e-6, rel=0.1)


@pytest.mark.parametrize("workers", [None, "2"])
def test_a_task_error_on_dask_workers_is_one_line(capsys, tmp_path, workers):
    """Issue 17: an error raised on the workers printed a 20-line worker log per task before the one-line error."""
    argv = ["table", "--nano", "abc:sigma=500nm,B=2um,C=2.6", "--material", "Au", "--incident-angles", "0,30",
            "--wavelengths", "450,550", "--resolution", "16", "-o", str(tmp_path / "t.h5")]
    _one_line_error(capsys, argv + (["--workers", workers] if workers else []), "too rough")


def test_a_unitless_spacing_in_a_scene_file_is_refused(tmp_path):
    """Issue 17: spacing = 5 in a scene meant 5 m while --spacing 5 on the command line is refused."""
    from waveoptics import surfaces
    from waveoptics.planning import scene

    surfaces.save(surfaces.gaussian("5nm", "1um", "16um", 32, seed=1), tmp_path / "h.npz")
    text = ('name = "t"\n[[materials]]\nname = "m"\nmaterial = "Au"\nroughness = 0.1\nndf = "ggx"\n[materials.nano]\n'
            'file = {path = "h.npz", spacing = SPACING}\n[[lights]]\nname = "sun"\nspd = "D65"\n'
            'directions_deg = [[30, 0]]\n')
    (tmp_path / "bad.toml").write_text(text.replace("SPACING", "5"))
    with pytest.raises(WaveopticsError, match=r"spacing = 5 needs a unit"):
        scene.load(tmp_path / "bad.toml")
    (tmp_path / "good.toml").write_text(text.replace("SPACING", '"5nm"'))
    scene.load(tmp_path / "good.toml")


def test_long_requests_warn_with_their_estimate(tmp_path, monkeypatch):
    """Issue 17: simulate, compare and scatter estimate their time with the cost model before any work and warn in
    one line when it is long (here every request is 'long'); the run goes on, and --quiet silences it."""
    from cli_helpers import run_cli
    from waveoptics import surfaces
    from waveoptics.planning import estimate
    from waveoptics.request import SimulationRequest

    monkeypatch.setattr(estimate, "LONG_REQUEST_S", 0.0)
    base = ["--resolution", "16", "--wavelengths", "550"]
    rc, _, err, _ = run_cli(["simulate", *base, "--no-spheres", "-o", str(tmp_path / "s")])
    lines = [x for x in err.splitlines() if "will take about" in x]
    assert rc == 0 and len(lines) == 1 and "lower --resolution or the number of --wavelengths" in lines[0]
    assert lines[0].startswith("waveoptics simulate: warning: this request will take about ")
    rc, _, err, _ = run_cli(["compare", *base, "--incident-angles", "0,40", "--quiet"])
    assert rc == 0 and "will take about" not in err
    hf = tmp_path / "h.npz"
    surfaces.save(surfaces.generate("gaussian", sigma="5nm", corr_length="1um", size="8um", samples=64, seed=1), hf)
    rc, _, err, _ = run_cli(["scatter", "--surface", str(hf), "--material", "Al", "--incident", "30", *base,
                             "-o", str(tmp_path / "sc")])
    assert rc == 0 and "will take about" in err and "--realizations" in err
    # the estimate grows with the work: more cells, more wavelengths, the sphere table
    small = estimate.simulation_time(SimulationRequest(resolution=32, wavelengths_nm=(550.0,)), sphere=False)
    more_w = estimate.simulation_time(SimulationRequest(resolution=32, wavelengths_nm=(450.0, 550.0, 650.0)),
                                      sphere=False)
    more_cells = estimate.simulation_time(SimulationRequest(resolution=128, wavelengths_nm=(550.0,)), sphere=False)
    sphere = estimate.simulation_time(SimulationRequest(resolution=32, wavelengths_nm=(550.0,)))
    assert 0 < small < min(more_w, more_cells, sphere)
