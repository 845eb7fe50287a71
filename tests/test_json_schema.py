"""JSON outputs are valid against the shipped JSON Schemas (issue 19), and the schemas reject what they should."""
import json

import pytest

jsonschema = pytest.importorskip("jsonschema")

from cli_helpers import run_cli  # noqa: E402
from waveoptics import surfaces  # noqa: E402
from waveoptics.schemas import SCHEMAS, schema, validate  # noqa: E402


@pytest.mark.parametrize("name", sorted(SCHEMAS))
def test_schemas_are_valid_schemas(name):
    jsonschema.Draft202012Validator.check_schema(schema(name))


@pytest.fixture(scope="module")
def surface_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("s") / "g.npz"
    surfaces.save(surfaces.generate("gaussian", size="6.4um", samples="64", sigma="15nm", corr_length="0.5um",
                                    seed=2), path)
    return path


def _json(argv):
    rc, out, err, _ = run_cli([*argv, "--json"])
    assert rc == 0, err
    return json.loads(out)


def test_brdf_values_and_albedo(surface_file):
    base = ["brdf", "--model", "microfacet", "--ior", "1.5", "--micro-alpha", "0.2", "--incident", "30"]
    validate(_json(base + ["--outgoing", "30,180", "--wavelengths", "450,650"]), "brdf")
    validate(_json(base + ["--albedo"]), "brdf")
    validate(_json(["brdf", "--model", "rayleigh-rice", "--nano", "abc:sigma=3nm,B=5um,C=3", "--ior", "1+6j",
                    "--incident", "30", "--outgoing", "60,180"]), "brdf")
    glass = _json(["brdf", "--model", "rough-dielectric", "--material", "BK7|MgF2:100nm", "--micro-alpha", "0.2",
                   "--incident", "30", "--albedo"])
    validate(glass, "brdf")
    row = glass["albedo"][0]
    assert glass["units"]["reflection"] == glass["units"]["transmission"] == "1"
    assert row["reflection"] + row["transmission"] == pytest.approx(row["albedo"], rel=1e-12)


def test_surface_stats(surface_file):
    validate(_json(["surface", "stats", str(surface_file), "--fit", "gaussian"]), "surface_stats")


def test_scatter_summary_file_and_stdout(surface_file, tmp_path):
    out = _json(["scatter", "--surface", str(surface_file), "--material", "Al", "--incident", "20",
                 "--wavelengths", "500,600", "--resolution", "32", "-o", str(tmp_path / "sc")])
    validate(out, "scatter_summary")
    validate(json.loads((tmp_path / "sc" / "summary.json").read_text()), "scatter_summary")


@pytest.mark.slow
def test_simulate_and_compare(surface_file, tmp_path):
    common = ["--nano", "gaussian:sigma=5nm,corr_length=1um", "--wavelengths", "450,550,650", "--resolution", "32"]
    _json(["simulate", *common, "--sphere-size", "32", "-o", str(tmp_path / "sim")])
    validate(json.loads((tmp_path / "sim" / "summary.json").read_text()), "simulate_summary")
    validate(_json(["compare", *common, "--incident-angles", "0,40"]), "compare")


def test_cost():
    validate(_json(["cost", "--generator", "sinusoid:amplitude=30nm,period=0.8um", "--size", "3.2um", "--samples",
                    "32", "--resolutions", "8,16", "--delta-e", "4", "--solvers", "fft0,fft"]), "cost")


def test_schemas_reject_what_they_should():
    good = {"model": "microfacet", "parameters": {}, "units": {"brdf": "1/sr"},
            "values": [{"incident": [30, 0], "outgoing": [30, 180], "wavelength_nm": 550, "brdf": 0.1}]}
    validate(good, "brdf")
    for bad in ({k: v for k, v in good.items() if k != "units"},               # no units
                {**good, "values": [{**good["values"][0], "brdf": -1.0}]},      # a negative BRDF
                {**good, "extra": 1},                                         # an undocumented key
                {**good, "values": [{**good["values"][0], "incident": [30]}]}):  # a direction without φ
        with pytest.raises(jsonschema.ValidationError):
            validate(bad, "brdf")


def _numbers_without_unit(data):
    """Top-level keys holding numbers (or lists of numbers) whose name does not end in a unit."""
    out = []
    for k, v in data.items():
        vals = v if isinstance(v, list) else [v]
        if vals and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in vals) \
                and not k.endswith(("_nm", "_m", "_deg", "_s")) and k != "realizations":
            out.append(k)
    return out


def test_numeric_outputs_carry_units(surface_file, tmp_path):
    """Every number in scatter's summary is named with its unit or listed in its units map."""
    out = _json(["scatter", "--surface", str(surface_file), "--material", "Al", "--incident", "20",
                 "--wavelengths", "550", "--resolution", "32", "-o", str(tmp_path / "sc")])
    missing = [k for k in _numbers_without_unit(out) if k not in out["units"]]
    assert not missing, missing

