"""Height fields from instrument formats through SurfaceTopography (issue 19): every format SurfaceTopography
writes is read back through the library and the command line with its units, axes and mask; files that lack
metadata take --units/--spacing; every surface-taking command has the same metadata options."""
import json

import numpy as np
import pytest

pytest.importorskip("SurfaceTopography")

from SurfaceTopography import Topography  # noqa: E402
from SurfaceTopography.IO import readers  # noqa: E402

from cli_helpers import run_cli  # noqa: E402
from waveoptics import surfaces  # noqa: E402
from waveoptics.cli import build_parser, command_parser  # noqa: E402
from waveoptics.surfaces.formats import FORMATS  # noqa: E402
from waveoptics.surfaces.instruments import INSTRUMENT_EXTS, WRITERS  # noqa: E402


def _ramp(nx=24, ny=16, lx_um=4.8, ly_um=2.4):
    """SurfaceTopography's layout h[ix, iy] in µm: a ramp along x plus a bump at (ix, iy) = (3, 11), so that a
    transposed or flipped read is seen."""
    h = np.add.outer(np.arange(nx) * 0.01, np.zeros(ny))
    h[3, 11] = 0.5
    return h, (lx_um, ly_um)


def test_instrument_extensions_are_what_surfacetopography_reads():
    """The literal list the CLI checks file names against equals SurfaceTopography's readers' extensions less
    the formats waveoptics reads itself (a binary .dat goes to the MetroPro reader by content)."""
    theirs = {"." + e.lower() for r in readers for e in r._file_extensions}
    assert set(INSTRUMENT_EXTS) == theirs - set(FORMATS)


@pytest.mark.parametrize("ext", sorted(WRITERS))
def test_surfacetopography_file_reads_with_units_and_axes(tmp_path, ext):
    h, sizes = _ramp()
    path = tmp_path / f"ramp{ext}"
    getattr(Topography(h, sizes, unit="µm"), WRITERS[ext])(str(path))
    hf = surfaces.load(path)
    assert hf.shape == (16, 24)                                  # (ny, nx)
    np.testing.assert_allclose([hf.dx, hf.dy], [0.2e-6, 0.15e-6], rtol=1e-6)   # NetCDF stores float32 sizes
    np.testing.assert_allclose(hf.heights, h.T * 1e-6, rtol=1e-6, atol=1e-15)
    assert np.unravel_index(np.argmax(hf.heights), hf.shape) == (11, 3)
    assert hf.meta["source_format"] == ext[1:]
    assert hf.meta["file_unit"] in ("m", "µm")


@pytest.mark.parametrize("ext", sorted(WRITERS))
def test_save_load_round_trip_with_mask(tmp_path, ext):
    hf0 = surfaces.generate("gaussian", size="3.2um", samples="32", sigma="8nm", corr_length="0.4um", seed=7)
    mask = np.ones(hf0.shape, bool)
    mask[5, 9] = mask[20, 2] = False
    hf = surfaces.HeightField(hf0.heights[:24], hf0.dx, 1.5 * hf0.dy, mask[:24], {})
    path = surfaces.save(hf, tmp_path / f"s{ext}")
    back = surfaces.load(path)
    assert back.shape == hf.shape
    np.testing.assert_allclose([back.dx, back.dy], [hf.dx, hf.dy], rtol=1e-6)
    np.testing.assert_array_equal(back.valid, hf.valid)
    np.testing.assert_allclose(back.heights[hf.valid], hf.heights[hf.valid], rtol=1e-6, atol=1e-16)
    with pytest.raises(Exception, match="exists"):
        surfaces.save(hf, path)                                   # never replaced without overwrite


def test_file_without_units_or_spacing_needs_them(tmp_path):
    import scipy.io

    h = np.random.default_rng(3).normal(size=(20, 30)) * 0.01
    Topography(h, (2.0, 3.0)).to_netcdf(str(tmp_path / "nounit.nc"))         # sizes, no unit
    scipy.io.savemat(tmp_path / "m.mat", {"data": h})                        # neither
    with pytest.raises(ValueError, match="units"):
        surfaces.load(tmp_path / "nounit.nc")
    hf = surfaces.load(tmp_path / "nounit.nc", units="um")
    np.testing.assert_allclose([hf.dx, hf.dy], [0.1e-6, 0.1e-6])
    np.testing.assert_allclose(hf.heights, h.T * 1e-6)
    with pytest.raises(ValueError, match="spacing"):
        surfaces.load(tmp_path / "m.mat", units="nm")
    hf = surfaces.load(tmp_path / "m.mat", units="nm", spacing="100nm,50nm")
    assert hf.shape == (30, 20) and (hf.dx, hf.dy) == pytest.approx((1e-7, 5e-8))
    np.testing.assert_allclose(hf.heights, h.T * 1e-9)


def test_units_contradicting_the_file_are_refused(tmp_path):
    h, sizes = _ramp()
    Topography(h, sizes, unit="µm").to_x3p(str(tmp_path / "a.x3p"))
    assert surfaces.load(tmp_path / "a.x3p", units="m").shape == (16, 24)   # x3p stores metres: agrees
    with pytest.raises(ValueError, match="contradicts"):
        surfaces.load(tmp_path / "a.x3p", units="nm")


@pytest.mark.parametrize("ext", sorted(WRITERS))
def test_cli_reads_instrument_formats(tmp_path, ext):
    h, sizes = _ramp()
    path = tmp_path / f"ramp{ext}"
    getattr(Topography(h, sizes, unit="µm"), WRITERS[ext])(str(path))
    rc, out, err, _ = run_cli(["surface", "stats", str(path), "--json"])
    assert rc == 0, err
    st = json.loads(out)
    assert st["samples"] == [24, 16]
    assert st["spacing_m"] == pytest.approx([0.2e-6, 0.15e-6], rel=1e-6)
    assert st["surface_info"]["source_format"] == ext[1:]


def test_cli_metadata_options_and_errors(tmp_path):
    h = np.random.default_rng(3).normal(size=(20, 30)) * 0.01
    Topography(h, (2.0, 3.0)).to_netcdf(str(tmp_path / "n.nc"))
    rc, out, err, _ = run_cli(["surface", "stats", str(tmp_path / "n.nc")])
    assert rc == 2 and err.count("\n") == 1 and "--units" in err
    rc, out, err, _ = run_cli(["surface", "stats", str(tmp_path / "n.nc"), "--units", "um", "--json"])
    assert rc == 0 and json.loads(out)["surface_info"]["file_unit"] == "um"
    rc, out, err, _ = run_cli(["surface", "stats", str(tmp_path / "n.nc"), "--channel", "4"])
    assert rc == 2 and "--channel 4 is not a channel" in err and "0: " in err
    rc, out, err, _ = run_cli(["scatter", "--units", "um", "--material", "Al", "-o", str(tmp_path / "o")])
    assert rc == 2


def test_corrupt_instrument_files_are_one_line_errors(tmp_path):
    (tmp_path / "bad.x3p").write_bytes(b"PK\x03\x04 not really a zip" * 10)
    (tmp_path / "bad.sur").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "metropro.dat").write_bytes(b"\x00\x01garbage" * 50)     # binary .dat: MetroPro, not text
    for name in ("bad.x3p", "bad.sur", "metropro.dat"):
        rc, out, err, _ = run_cli(["surface", "stats", str(tmp_path / name)])
        assert rc == 2 and err.count("\n") == 1 and name in err and "Traceback" not in err, err


def _surface_parsers():
    parser = build_parser()
    for words in ("brdf", "cost", "scatter", "simulate", "compare", "surface stats"):
        yield words, command_parser(parser, words)


@pytest.mark.parametrize("words,p", list(_surface_parsers()), ids=lambda x: x if isinstance(x, str) else "")
def test_every_surface_command_has_the_metadata_options(words, p):
    """--spacing, --units and --channel exist wherever a height-field file is taken, with one help text each."""
    helps = {o: a.help for a in p._actions for o in a.option_strings}
    ref = {o: a.help for a in command_parser(build_parser(), "scatter")._actions for o in a.option_strings}
    for flag in ("--spacing", "--units", "--channel"):
        assert helps.get(flag) == ref[flag], (words, flag)


def test_cli_commands_take_a_headerless_text_grid_with_units_and_spacing(tmp_path):
    """A profilometer matrix without header lines goes through each quick surface command with --units and
    --spacing, and the result matches the same surface saved with its metadata."""
    rng = np.random.default_rng(5)
    h_um = rng.normal(size=(48, 48)) * 0.01
    np.savetxt(tmp_path / "plain.txt", h_um)
    surfaces.save(surfaces.HeightField(h_um * 1e-6, 1e-7), tmp_path / "ref.npz")
    common = ["--material", "Al", "--incident", "10", "--json"]
    rc, out, err, _ = run_cli(["brdf", "--model", "kirchhoff", "--surface", str(tmp_path / "plain.txt"),
                               "--units", "um", "--spacing", "100nm", "--wavelengths", "550",
                               "--outgoing", "12,180", *common])
    assert rc == 0, err
    rc2, out2, err2, _ = run_cli(["brdf", "--model", "kirchhoff", "--surface", str(tmp_path / "ref.npz"),
                                  "--wavelengths", "550", "--outgoing", "12,180", *common])
    assert rc2 == 0, err2
    (a,), (b,) = json.loads(out)["values"], json.loads(out2)["values"]
    assert a["brdf"] == pytest.approx(b["brdf"], rel=1e-12) and a["brdf"] > 0
    rc, out, err, _ = run_cli(["scatter", "--surface", str(tmp_path / "plain.txt"), "--units", "um", "--spacing",
                               "100nm", "--wavelengths", "550nm", "--resolution", "32", "-o",
                               str(tmp_path / "sc"), *common])
    assert rc == 0, err
    summary = json.loads((tmp_path / "sc" / "summary.json").read_text())
    assert summary["surface_info"]["spacing_m"] == pytest.approx([1e-7, 1e-7], rel=1e-12)
    rc, out, err, _ = run_cli(["brdf", "--model", "kirchhoff", "--surface", str(tmp_path / "plain.txt"),
                               "--wavelengths", "550", "--outgoing", "12,180", *common])
    assert rc == 2 and "--units" in err


def test_crop_region_takes_the_named_samples_and_refuses_outside():
    h = np.arange(12 * 20, dtype=float).reshape(12, 20) * 1e-9
    hf = surfaces.HeightField(h, 0.1e-6, 0.2e-6)
    c = surfaces.crop_region(hf, 0.3e-6, 0.4e-6, 0.5e-6, 1.0e-6)     # x samples 3..7, y samples 2..6
    np.testing.assert_array_equal(c.heights, h[2:7, 3:8])
    assert c.meta["cropped"] == {"from_samples": [20, 12], "origin_samples": [3, 2]}
    assert surfaces.parse_region("0um,0.4um,0.5um,1um") == pytest.approx((0.0, 0.4e-6, 0.5e-6, 1e-6))
    with pytest.raises(ValueError, match="beyond"):
        surfaces.crop_region(hf, 1.8e-6, 0.0, 0.5e-6, 1e-6)
    with pytest.raises(ValueError, match="X,Y,WIDTH,HEIGHT"):
        surfaces.parse_region("1um,2um")


def test_level_removes_a_tilt_exactly_over_the_valid_samples():
    rng = np.random.default_rng(9)
    ny, nx = 30, 40
    x = np.arange(nx) * 1e-7
    y = np.arange(ny) * 2e-7
    plane = 3e-9 + 0.02 * x[None, :] - 0.01 * y[:, None]
    mask = rng.random((ny, nx)) > 0.1
    hf = surfaces.HeightField(plane + 50.0 * np.where(mask, 0, 1) * 1e-9, 1e-7, 2e-7, mask)  # junk where masked
    lev = surfaces.level(hf, "plane")
    np.testing.assert_allclose(lev.heights[mask], 0.0, atol=1e-18)
    assert lev.meta["levelled"] == "plane"
    assert surfaces.level(hf, "none") is hf
    prof = surfaces.HeightField((0.01 * x)[None, :], 1e-7)        # a profile: tilt along x only
    np.testing.assert_allclose(surfaces.level(prof, "plane").heights, 0.0, atol=1e-18)


def test_cli_prepare_keeps_provenance(tmp_path):
    h, sizes = _ramp(40, 30, 8.0, 6.0)
    Topography(h, sizes, unit="µm").to_x3p(str(tmp_path / "raw.x3p"))
    rc, out, err, _ = run_cli(["surface", "prepare", str(tmp_path / "raw.x3p"), "--crop", "0um,0um,4um,3um", "-o",
                               str(tmp_path / "p.npz"), "--json"])
    assert rc == 0, err
    back = surfaces.load(tmp_path / "p.npz")
    assert back.shape == (15, 20)
    info = back.provenance()
    assert info["source_format"] == "x3p" and info["levelled"] == "plane"
    assert info["prepared_from"].endswith("raw.x3p")
    rc, out, err, _ = run_cli(["surface", "prepare", str(tmp_path / "raw.x3p"), "-o", str(tmp_path / "p.npz")])
    assert rc == 2 and "exists" in err                           # never replaced without --overwrite


def test_docs_sample_is_a_readable_x3p():
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "docs" / "data" / "brushed_aluminium.x3p"
    hf = surfaces.load(path)
    assert hf.shape == (256, 256) and hf.dx == pytest.approx(90e-9, rel=1e-6)
    assert 0.99 < hf.valid.mean() < 1.0
    assert hf.meta["source_format"] == "x3p"


def test_transform_stretch_is_exact_and_scales_slopes():
    hf = surfaces.generate("gaussian", size="12.8um", samples="128", sigma="10nm", corr_length="0.8um", seed=3)
    st = surfaces.stats(hf)
    t = surfaces.transform(hf, stretch=(2.0, 0.5), height_scale=3.0)
    np.testing.assert_array_equal(t.heights, 3.0 * hf.heights)
    assert (t.dx, t.dy) == (2 * hf.dx, 0.5 * hf.dy)
    st2 = surfaces.stats(t)
    assert st2["rms_slope_x"] == pytest.approx(st["rms_slope_x"] * 3 / 2, rel=1e-12)
    assert st2["rms_slope_y"] == pytest.approx(st["rms_slope_y"] * 3 / 0.5, rel=1e-12)
    with pytest.raises(ValueError, match="along x"):
        surfaces.transform(hf, stretch=(0.0, 1.0))


def test_transform_rotation_turns_features_counter_clockwise():
    """A bump on +x lands on +y after 90°; a grating's slope moves from x to y in proportion cos φ, sin φ; what the
    turned patch does not cover is masked; 90° on a square patch loses nothing."""
    n, dx = 65, 1e-7
    x = (np.arange(n) - (n - 1) / 2) * dx
    X, Y = np.meshgrid(x, x)
    bump = np.exp(-((X - 20 * dx) ** 2 + Y ** 2) / (3 * dx) ** 2) * 1e-8
    r = surfaces.transform(surfaces.HeightField(bump, dx), rotate_deg=90.0)
    iy, ix = np.unravel_index(np.argmax(r.heights), r.shape)
    assert (ix, iy) == ((n - 1) // 2, (n - 1) // 2 + 20)
    assert r.mask is None
    gr = surfaces.generate("sinusoid", amplitude="20nm", period="2um", size="25.6um", samples=256)
    s0 = surfaces.stats(gr)["rms_slope_x"]
    for phi in (30.0, 60.0):
        rr = surfaces.transform(gr, rotate_deg=phi)
        st = surfaces.stats(rr)
        assert st["rms_slope_x"] == pytest.approx(s0 * np.cos(np.radians(phi)), rel=0.02)
        assert st["rms_slope_y"] == pytest.approx(s0 * np.sin(np.radians(phi)), rel=0.02)
        assert 0.6 < rr.valid.mean() < 1.0 and rr.meta["periodic"] is False


def test_cli_transform(tmp_path):
    import json

    surfaces.save(surfaces.generate("gaussian", size="6.4um", samples="64", sigma="5nm", corr_length="0.5um",
                                    seed=1), tmp_path / "g.npz")
    rc, out, err, _ = run_cli(["surface", "transform", str(tmp_path / "g.npz"), "--stretch", "1.5", "--rotate", "0",
                               "-o", str(tmp_path / "t.x3p"), "--json"])
    assert rc == 0, err
    d = json.loads(out)
    assert d["after"]["rms_slope_x"] == pytest.approx(d["before"]["rms_slope_x"] / 1.5, rel=1e-6)
    assert surfaces.load(tmp_path / "t.x3p").dx == pytest.approx(1.5e-7, rel=1e-6)
    rc, out, err, _ = run_cli(["surface", "transform", str(tmp_path / "g.npz"), "--stretch", "1,2,3", "-o",
                               str(tmp_path / "u.npz")])
    assert rc == 2 and "--stretch" in err
