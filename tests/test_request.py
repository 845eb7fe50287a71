"""The simulation request owns its defaults and its validation (issue 30): every front end (the command line's
options, scene files, the Python API) reads the defaults of :class:`waveoptics.request.SimulationRequest`'s fields
instead of restating them, one default NDF and material hold everywhere, bad values are FieldErrors naming the
field, and a quantity's old command-line names are refused with a hint naming the new one."""
import argparse
import dataclasses
import textwrap

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import vocabulary
from waveoptics.cli import build_parser, command_parser
from waveoptics.errors import FieldError
from waveoptics.request import SimulationRequest, request_default

#: the defaults the docs and the demo (``waveoptics simulate`` with no options) promise, written out here
DOCUMENTED = {"material": "Al", "micro_alpha": 0.05, "alpha_y": None, "ndf": "beckmann",
              "shadowing": "smith-correlated", "incident_deg": (30.0, 0.0), "illuminant": "D65", "delta_e": 1.0,
              "resolution": 128, "solver": "auto", "kd": 0.5, "precision": "float32", "seed": 0,
              "diffraction": "kirchhoff", "polarization": "unpolarized", "nano": "abc:sigma=10nm,B=2um,C=2.6",
              "split": False, "multiple_scattering": False, "ndf_shape": None, "micro_surface": None, "surface": None,
              "wavelengths_nm": None, "roughness_correlation": "correlated"}

FIELDS = {f.name: f.default for f in dataclasses.fields(SimulationRequest)}

#: option dest → request field, where the two are spelled differently
DEST_FIELD = {"incident": "incident_deg", "wavelengths": "wavelengths_nm"}


def test_the_fields_hold_the_documented_defaults():
    assert FIELDS == DOCUMENTED
    assert {k: request_default(k) for k in FIELDS} == DOCUMENTED


def test_request_default_names_an_unknown_field():
    with pytest.raises(ValueError, match="unknown request field 'micro_alfa'.*did you mean 'micro_alpha'"):
        request_default("micro_alfa")


def test_one_default_ndf_and_material_everywhere():
    from waveoptics import brdf
    from waveoptics.materials import get_material
    from waveoptics.planning import scene

    assert vocabulary.DEFAULT_NDF == FIELDS["ndf"] == brdf.Micro().ndf == scene.MaterialSpec("m", "Au").ndf
    assert vocabulary.DEFAULT_MATERIAL == FIELDS["material"]
    assert get_material(brdf.MicrofacetBRDF().material.name).name == get_material(FIELDS["material"]).name


def _cli_defaults(command):
    """dest → default of every visible option of *command* that carries a request field."""
    out = {}
    for a in command_parser(build_parser(), command)._actions:
        if a.help == argparse.SUPPRESS or not a.option_strings:
            continue
        field = DEST_FIELD.get(a.dest, a.dest)
        if field in FIELDS:
            out[field] = (a.default, a.help)
    return out


@pytest.mark.parametrize("command", ["simulate", "compare"])
def test_each_option_default_is_the_field_default(command):
    """An option's default is the field's (parsed as the option is), or None with the field's default in its help
    (options that must tell "not given" apart)."""
    from waveoptics.units import parse_direction

    seen = _cli_defaults(command)
    assert set(seen) >= set(FIELDS) - {"shadowing", "wavelengths_nm", "ndf_shape", "micro_surface", "surface"}
    for field, (default, help_) in seen.items():
        if field == "incident_deg":
            assert tuple(parse_direction(default)) == FIELDS[field]
        elif default is None and FIELDS[field] is not None:
            assert f"default {FIELDS[field]:g}" in help_ if isinstance(FIELDS[field], float) \
                else f"default {FIELDS[field]}" in help_, (field, help_)
        else:
            assert default == FIELDS[field], (command, field, default)


@pytest.mark.parametrize("command, resolution", [("table", 128), ("sweep", 64)])
def test_case_options_state_the_field_defaults(command, resolution):
    """table and sweep keep None for "not given" (a scene file's value wins): their help states the field's
    default, and the few they fill in equal it."""
    seen = _cli_defaults(command)
    for field in ("material", "ndf", "illuminant", "delta_e", "kd", "seed", "nano"):
        default, help_ = seen[field]
        assert default is None and f"default {FIELDS[field]}" in help_, (field, help_)
    for field in ("solver", "diffraction", "precision"):
        assert seen[field][0] == FIELDS[field], field
    assert f"default {resolution}" in seen["resolution"][1]


def test_simulate_with_no_options_is_the_default_request():
    from waveoptics.cli.simulate import request_from_args

    args = command_parser(build_parser(), "simulate").parse_args(["-o", "unused"])
    assert request_from_args(args) == SimulationRequest()


def test_table_with_no_options_is_the_default_request():
    from waveoptics.cli.table import case_from_args

    args = command_parser(build_parser(), "table").parse_args(["-o", "unused.h5"])
    case, hf = case_from_args(args)
    assert hf is None and case == SimulationRequest(resolution=128)


BAD = [
    ("micro_alpha", -1.0, "micro_alpha -1.0 is not allowed"),
    ("micro_alpha", float("nan"), "micro_alpha nan is not finite"),
    ("resolution", 4, "resolution 4 is not allowed; use 8..2048"),
    ("kd", 1.5, "kd 1.5 is not allowed"),
    ("delta_e", 0.0, r"delta_e 0.0 is not allowed; use a ΔE2000 in \(0, 100\)"),
    ("delta_e", 100.0, "delta_e 100.0 is not allowed"),
    ("solver", "ftt", "unknown solver 'ftt'"),
    ("ndf", "gxx", "unknown ndf 'gxx'.*did you mean 'ggx'"),
    ("ndf", "tabulated", "unknown ndf 'tabulated'"),
    ("shadowing", "smithy", "unknown shadowing 'smithy'"),
    ("diffraction", "kirchoff", "unknown diffraction 'kirchoff'"),
    ("polarization", "circular", "unknown polarization 'circular'"),
    ("precision", "float16", "unknown precision 'float16'"),
    ("seed", -1, "seed -1 is not allowed"),
    ("seed", 1.5, "seed 1.5 is not allowed"),
    ("incident_deg", (90.0, 0.0), "incident_deg θ=90° is not allowed"),
    ("incident_deg", (10.0, 0.0, 0.0), "incident_deg .* is not"),
    ("nano", "gaussian:sigma=5nm", "nano 'gaussian:sigma=5nm' lacks corr_length"),
    ("nano", "fractal:sigma=5nm", "unknown nano model 'fractal'"),
    ("multiple_scattering", "yes", "multiple_scattering 'yes' is not allowed"),
    ("ndf_shape", 50.0, r"ndf_shape is not allowed for epd; its p must be in \(0, 20\]"),
    ("ndf_shape", 1.5, "ndf_shape is not allowed for NDF 'ggx', which has no shape parameter"),
]


@pytest.mark.parametrize("field, value, message", BAD, ids=[f"{f}={v!r}" for f, v, _ in BAD])
def test_a_bad_value_is_a_field_error_naming_the_field(field, value, message):
    kw = {"ndf": "epd" if value == 50.0 else "ggx"} if field == "ndf_shape" else {}
    with pytest.raises(FieldError, match=message) as info:
        SimulationRequest(**{field: value}, **kw)
    assert info.value.field == field
    assert "--" not in str(info.value)   # the library names fields, never flags


def test_the_command_line_writes_the_field_as_its_flag(tmp_path):
    rc, out, err, _ = run_cli(["simulate", "--delta-e", "0", "-o", str(tmp_path / "x")])
    assert rc == 2 and err.strip() == ("waveoptics simulate: error: --delta-e 0.0 is not allowed; use a ΔE2000 in "
                                       "(0, 100)")
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("argv, old, want", [
    (["simulate", "--accuracy", "2", "-o", "x"], "--accuracy", 2.0),
    (["compare", "--accuracy", "2"], "--accuracy", 2.0),
    (["table", "--accuracy", "2", "-o", "x.h5"], "--accuracy", 2.0),
    (["sweep", "--vary", "kd=0,1", "--accuracy", "2", "-o", "s.csv"], "--accuracy", 2.0),
    (["cost", "--colour-accuracy", "4,1", "-o", "c"], "--colour-accuracy", [4.0, 1.0]),
])
def test_a_renamed_colour_accuracy_still_works_with_one_deprecation_line(argv, old, want):
    """One name per quantity (--delta-e) while the old spellings keep working for one release, as every rename."""
    from waveoptics.cli import deprecations, shared_parser

    args = shared_parser().parse_args(argv)
    assert list(np.atleast_1d(args.delta_e)) == list(np.atleast_1d(want))
    notes = list(deprecations(args))
    assert len(notes) == 1 and old in notes[0] and "use --delta-e" in notes[0], notes


def test_the_python_keyword_accuracy_names_its_new_name():
    """Python keywords are renamed outright (only the command line's old flags keep working until 0.3): the old
    keyword is refused in one line naming delta_e, before any work."""
    from waveoptics.simulate import simulate

    with pytest.raises(TypeError, match=r"^simulate\(\) got an unexpected keyword argument 'accuracy': it was renamed; "
                                        r"use delta_e= \(the colour accuracy, ΔE2000\)$"):
        simulate("Al", accuracy=2.0)


def _scene(tmp_path, material_table):
    p = tmp_path / "s.toml"
    p.write_text(textwrap.dedent("""
        seed = 3
        [accuracy]
        delta_e = 2.5
        [[materials]]
        """) + textwrap.dedent(material_table) + textwrap.dedent("""
        [[lights]]
        name = "lamp"
        spd = "A"
        directions_deg = [[20, 45]]
        """))
    return p


def test_a_scene_file_is_a_request(tmp_path):
    from waveoptics.distributed import case_from_scene
    from waveoptics.planning import scene

    path = _scene(tmp_path, """
        name = "gold"
        material = "Au"
        roughness = 0.2
        ndf = "ggx"
        diffuse_albedo = 0.1
        [materials.nano]
        statistics = "gaussian:sigma=4nm,corr_length=1.5um"
        """)
    req, hf = case_from_scene(scene.load(path))
    assert hf is None
    assert req == SimulationRequest(material="Au", micro_alpha=0.2, ndf="ggx", kd=0.1, illuminant="A",
                                    incident_deg=(20.0, 45.0), delta_e=2.5, seed=3,
                                    nano="gaussian:sigma=4nm,corr_length=1.5um")


def test_a_scene_material_without_keys_takes_the_request_defaults(tmp_path):
    from waveoptics.distributed import case_from_scene
    from waveoptics.planning import scene

    path = _scene(tmp_path, """
        name = "plain"
        material = "Al"
        """)
    sc = scene.load(path)
    req, _ = case_from_scene(sc)
    for field in ("micro_alpha", "ndf", "shadowing", "kd", "multiple_scattering", "resolution"):
        assert getattr(req, field) == DOCUMENTED[field], field
    assert (sc.materials[0].roughness, sc.materials[0].ndf, sc.materials[0].diffuse_albedo) == (0.05, "beckmann", 0.5)


def test_the_planner_hands_the_runner_the_scene_request(tmp_path):
    """A plan entry carries the scene's request with the planner's decisions applied; the runner evaluates it."""
    from waveoptics.planning import plan_scene, scene

    path = _scene(tmp_path, """
        name = "gold"
        material = "Au"
        roughness = 0.2
        ndf = "ggx"
        """)
    e = plan_scene(scene.load(path)).entries[0]
    req = e.request
    assert (req.material, req.micro_alpha, req.ndf, req.illuminant, req.incident_deg, req.delta_e, req.seed) == \
        ("Au", 0.2, "ggx", "A", (20.0, 45.0), 2.5, 3)
    assert (req.kd, req.resolution, req.precision, req.diffraction) == (e.kd, e.resolution, e.precision,
                                                                        e.diffraction)
    simulated = e.wavelengths_nm if e.wavelengths_nm.size else e.colour_wavelengths_nm
    assert req.wavelengths_nm == tuple(simulated)


# --- scatter's request (waveoptics.scatter_job.ScatterRequest) ----------------------------------------------------

#: the defaults of ``waveoptics scatter`` as docs/cli.md states them, written out here
SCATTER_DOCUMENTED = {"spacing": None, "units": None, "channel": None, "wavelengths_nm": "400:700:10",
                      "diffraction": "kirchhoff", "polarization": "unpolarized", "solver": "fft", "resolution": 256,
                      "max_memory": None, "realizations": 1, "order": "auto", "window": "hann", "footprint": None,
                      "coherence": None, "detrend": "mean", "precision": "float32", "backend": "opencl",
                      "device": None}


def _scatter_fields():
    from waveoptics.scatter_job import ScatterRequest

    return {f.name: f.default for f in dataclasses.fields(ScatterRequest)}


def test_the_scatter_fields_hold_the_documented_defaults():
    from waveoptics import scatter, surfaces
    from waveoptics.scatter_job import scatter_default

    fields = _scatter_fields()
    assert [k for k, v in fields.items() if v is dataclasses.MISSING] == ["surface", "material", "incident_deg"]
    assert {k: v for k, v in fields.items() if v is not dataclasses.MISSING} == SCATTER_DOCUMENTED
    assert {k: scatter_default(k) for k in SCATTER_DOCUMENTED} == SCATTER_DOCUMENTED
    # the names the request takes are the registries' (the CLI's choices come from the same vocabulary)
    assert fields["window"] == scatter.DEFAULT_WINDOW
    assert set(vocabulary.FIELD_SOLVERS) == set(scatter.SOLVERS)
    assert set(vocabulary.FIELD_BACKENDS) == set(scatter.BACKENDS)
    assert set(vocabulary.DETRENDS) == set(surfaces.DETRENDS)
    with pytest.raises(ValueError, match="unknown scatter request field 'resolutoin'.*did you mean 'resolution'"):
        scatter_default("resolutoin")


def test_each_scatter_option_default_is_the_field_default():
    """Every field of the request is an option of ``waveoptics scatter`` whose default is the field's (the three
    without a default are required options); the parser reads them from the request (no default restated)."""
    from waveoptics.cli.scatter import DEST_FIELD

    fields = _scatter_fields()
    seen = {}
    for a in command_parser(build_parser(), "scatter")._actions:
        field = DEST_FIELD.get(a.dest, a.dest)
        if a.option_strings and field in fields:
            seen[field] = a
    assert set(seen) == set(fields)
    for field, a in seen.items():
        if fields[field] is dataclasses.MISSING:
            assert a.required, field
        else:
            assert a.default == fields[field] and not a.required, (field, a.default)
    assert set(seen["solver"].choices) == set(vocabulary.FIELD_SOLVERS)
    assert set(seen["detrend"].choices) == set(vocabulary.DETRENDS)


def test_scatter_with_only_the_required_options_is_the_default_request():
    from waveoptics.cli.scatter import request_from_args
    from waveoptics.scatter_job import ScatterRequest

    args = command_parser(build_parser(), "scatter").parse_args(
        ["--surface", "h.npz", "--material", "Au", "--incident", "30", "-o", "unused"])
    req = request_from_args(args)
    assert req == ScatterRequest(surface="h.npz", material="Au", incident_deg=(30.0, 0.0))
    assert req.wavelengths_nm == tuple(float(x) for x in range(400, 701, 10)) and req.order == "auto"


SCATTER_BAD = [
    ({"order": "2.5"}, "order", r"order '2\.5' is not allowed; use 'auto' or an integer >= 0"),
    ({"order": True}, "order", "order True is not allowed"),
    ({"coherence": "1um"}, "coherence", "coherence is the coherence area inside a footprint; give one"),
    ({"footprint": "20um,20um,2um", "realizations": 2}, "realizations", "footprint is one patch; drop realizations"),
    ({"footprint": "20um,20um,2um", "window": "boxcar"}, "window",
     r"footprint sets the window \(its Gaussian\); drop window"),
    ({"footprint": "20um,20um,2um", "coherence": "1 furlong"}, "coherence", "coherence '1 furlong' has unknown unit"),
    ({"solver": "ftt"}, "solver", "unknown solver 'ftt' .*did you mean 'fft'"),
    ({"backend": "cuda"}, "backend", "unknown backend 'cuda'"),
    ({"detrend": "linear"}, "detrend", "unknown detrend 'linear'"),
    ({"precision": "float16"}, "precision", "unknown precision 'float16'"),
    ({"diffraction": "kirchoff"}, "diffraction", "unknown diffraction 'kirchoff'"),
    ({"polarization": "circular"}, "polarization", "unknown polarization 'circular'"),
    ({"incident_deg": (95.0, 0.0)}, "incident_deg", "incident_deg θ=95.0° is outside the allowed range"),
    ({"incident_deg": "abc"}, "incident_deg", "incident_deg 'abc' is not THETA"),
    ({"wavelengths_nm": "700:400:10"}, "wavelengths_nm", "STEP > 0 and STOP >= START"),
    ({"wavelengths_nm": (0.0,)}, "wavelengths_nm", "wavelengths_nm 0.0 nm is not allowed"),
    ({"surface": None}, "surface", "a scatter request needs a height field: surface"),
    ({"material": None}, "material", "a scatter request needs a material"),
]


@pytest.mark.parametrize("change, field, message", SCATTER_BAD, ids=[repr(c) for c, _, _ in SCATTER_BAD])
def test_a_bad_scatter_value_is_a_field_error_naming_the_field(change, field, message):
    from waveoptics.scatter_job import ScatterRequest

    with pytest.raises(FieldError, match=message) as info:
        ScatterRequest(**{"surface": "h.npz", "material": "Au", "incident_deg": 30, **change})
    assert info.value.field == field
    assert "--" not in str(info.value)   # the library names fields, never flags


def test_file_metadata_of_a_height_field_object_is_refused():
    from waveoptics import surfaces
    from waveoptics.scatter_job import ScatterRequest

    hf = surfaces.HeightField(np.zeros((8, 8)), 1e-7, 1e-7)
    with pytest.raises(FieldError, match="spacing describes a surface file, not a height field") as info:
        ScatterRequest(surface=hf, material="Au", incident_deg=30, spacing="50nm")
    assert info.value.field == "spacing"


def test_the_scatter_command_writes_the_request_fields_as_its_flags(tmp_path):
    out = tmp_path / "x"
    rc, _, err, _ = run_cli(["scatter", "--surface", "h.npz", "--material", "Al", "--incident", "30", "--order",
                             "2.5", "-o", str(out)])
    assert rc == 2 and err.strip() == ("waveoptics scatter: error: --order '2.5' is not allowed; use 'auto' or an "
                                       "integer >= 0")
    rc, _, err, _ = run_cli(["scatter", "--surface", "h.npz", "--material", "Al", "--incident", "30",
                             "--footprint", "20um,20um,2um", "--window", "boxcar", "-o", str(out)])
    assert rc == 2 and err.strip() == ("waveoptics scatter: error: --footprint sets the window (its Gaussian); drop "
                                       "--window")
    assert not out.exists()


def test_the_scatter_job_of_a_height_field_object(tmp_path):
    """Python callers pass the field itself: the outputs name it, and the job's coherent fraction of a lightly rough
    patch is the Davies / Bennett-Porteus exp(−g), g = (4π σ cos θ_i / λ)², written here from the patch's rms
    height (F = 1)."""
    import json

    from waveoptics import surfaces
    from waveoptics.scatter_job import ScatterRequest, scatter_job

    hf = surfaces.gaussian(2e-9, 1e-6, 12e-6, 96, seed=3)
    wl = np.array([450.0, 550.0, 650.0])
    run = scatter_job(ScatterRequest(surface=hf, material="one", incident_deg=30, wavelengths_nm=tuple(wl),
                                     resolution=32), tmp_path / "o")
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["surface"] == run.summary()["surface"] == "height field" and summary["material"] == "one"
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["lobes.exr", "lobes.png", "summary.json"]
    sigma = float(np.std(hf.heights))
    g = (4 * np.pi * sigma * np.cos(np.radians(30.0)) / (wl * 1e-9)) ** 2
    np.testing.assert_allclose(summary["coherent_specular_fraction"], np.exp(-g), atol=2e-4)


def test_a_refused_scatter_job_creates_nothing(tmp_path):
    from waveoptics import surfaces
    from waveoptics.errors import WaveopticsError
    from waveoptics.scatter_job import ScatterRequest, scatter_job

    hf = surfaces.HeightField(np.zeros((8, 8)), 1e-7, 1e-7)
    with pytest.raises(WaveopticsError, match="unobtainium"):
        scatter_job(ScatterRequest(surface=hf, material="unobtainium", incident_deg=30), tmp_path / "o")
    with pytest.raises(WaveopticsError, match="cannot split a 8x8 patch into 64 tiles"):
        scatter_job(ScatterRequest(surface=hf, material="Al", incident_deg=30, realizations=64), tmp_path / "o")
    assert not (tmp_path / "o").exists()
