"""``simulate --no-spheres`` (promise 3: simulate only what is asked, and say what was skipped and why): the lobe
outputs and no sphere file, a summary that names the skipped renders and the reason, a text line without a sphere
ΔE, a progress bar whose total is the lobe evaluations the run makes, and --environment refused beside it.

``sweep --no-spheres`` / ``--sphere-size 0``: its ΔE2000 columns over sphere renders are "not computed" (an empty
CSV cell, JSON null), never 0 (which reads as "no colour difference"), and its outputs say what was skipped and why.
The memory refusal offers ``--no-spheres`` where the command has it, in one line."""
import csv
import json

import pytest

from cli_helpers import run_cli
from waveoptics.cli import simulate as cli_simulate

ARGS = ["--resolution", "16", "--wavelengths", "450,650"]
#: what a run without spheres writes, spelt out here (not taken from the library's own file lists)
LOBE_FILES = {"brdf_spectral.exr", "brdf_rgb.exr", "brdf.png", "lobes.png", "summary.json"}


class _Bar:
    """Stands for the tqdm bar: records the total it was given and the steps the run reports."""

    def __init__(self, total):
        self.total, self.steps = total, 0

    def update(self, n=1):
        self.steps += n

    def close(self):
        pass


def test_no_spheres_writes_the_lobes_and_says_it_skipped_the_spheres(tmp_path, monkeypatch):
    bars = []
    monkeypatch.setattr(cli_simulate, "progress", lambda total=None, **kw: bars.append(_Bar(total)) or bars[-1])
    out = tmp_path / "run"
    rc, stdout, stderr, _ = run_cli(["simulate", "-o", str(out), *ARGS, "--no-spheres"])
    assert rc == 0, stderr
    assert {p.name for p in out.iterdir()} == LOBE_FILES   # no sphere_* file, no staging litter
    summary = json.loads((out / "summary.json").read_text())
    assert summary["skipped"] == {"sphere renders": "not asked: --no-spheres"}
    assert summary["delta_e2000"] is None and set(summary["files"]) == LOBE_FILES
    assert summary["parameters"]["sphere_render"]["diffraction_table"] is None
    assert len(summary["albedo"]) == 2 and all(0 < a < 1 for a in summary["albedo"])
    assert "ΔE" not in stdout and "spheres skipped (not asked: --no-spheres)" in stdout
    # one lobe evaluation at the light, no table over incidence: the bar's total is what the run reported
    assert [(b.total, b.steps) for b in bars] == [(1, 1)]
    pytest.importorskip("jsonschema")
    from waveoptics.schemas import validate

    validate(summary, "simulate_summary")


def test_no_spheres_with_an_environment_is_refused_in_one_line(tmp_path):
    out = tmp_path / "run"
    rc, stdout, stderr, _ = run_cli(["simulate", "-o", str(out), *ARGS, "--no-spheres", "--environment", "sky"])
    assert rc == 2 and stdout == ""
    assert len(stderr.strip().splitlines()) == 1 and "--environment" in stderr and "--no-spheres" in stderr
    assert not out.exists()   # refused before the output directory is made


# ------------------------------------------------------------------------------------------------ sweep

#: the smallest sweep: the coarsest grid, one wavelength, the PSD solver (no height field), two points
SWEEP = ["sweep", "--nano", "abc:sigma=8nm,B=2um,C=2.6", "--vary", "material=Au,Cu", "--wavelengths", "550",
         "--resolution", "8"]
SPHERE_COLUMNS = ("dE_sphere_mean", "dE_sphere_max")


def _csv_rows(path):
    """The table as the csv module reads it (not the library's reader): every cell as its text."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("flags, reason", [(["--no-spheres"], "not asked: --no-spheres"),
                                           (["--sphere-size", "0"], "not asked: --sphere-size 0")])
def test_sweep_without_spheres_writes_no_value_and_says_why(tmp_path, flags, reason):
    from waveoptics.distributed import read_sweep

    out_csv, out_json = tmp_path / "s.csv", tmp_path / "s.json"
    rc, stdout, stderr, _ = run_cli([*SWEEP, *flags, "-o", str(out_csv)])
    assert rc == 0, stderr
    rows = _csv_rows(out_csv)
    assert len(rows) == 2
    for r in rows:   # an empty cell ("not computed"), not "0"
        assert [r[c] for c in SPHERE_COLUMNS] == ["", ""], r
        assert r["skipped"] == f"sphere renders: {reason}"
        assert 0 < float(r["albedo_R"]) < 1   # the columns that were computed are there
    assert f"spheres skipped ({reason})" in stdout and "sphere mean" not in stdout
    back = read_sweep(out_csv)   # the library's reader gives None for the empty cell and the entry JSON holds
    assert all(r["dE_sphere_mean"] is None and r["skipped"] == {"sphere renders": reason} for r in back)

    rc, stdout, stderr, _ = run_cli([*SWEEP, *flags, "-o", str(out_json), "--json"])
    assert rc == 0, stderr
    for rows in (json.loads(out_json.read_text()), json.loads(stdout)["rows"]):
        assert all(r[c] is None for r in rows for c in SPHERE_COLUMNS)
        assert all(r["skipped"] == {"sphere renders": reason} for r in rows)


def test_sweep_with_spheres_writes_their_delta_e_and_skips_nothing(tmp_path):
    out = tmp_path / "s.csv"
    rc, stdout, stderr, _ = run_cli([*SWEEP, "--sphere-size", "16", "-o", str(out)])
    assert rc == 0, stderr
    rows = _csv_rows(out)
    assert "skipped" not in rows[0] and "skipped" not in stdout and "sphere mean" in stdout
    # a nano-rough metal against its microfacet model: a colour difference that is there (> 0) and finite
    assert all(0 < float(r[c]) < 100 for r in rows for c in SPHERE_COLUMNS)


# ------------------------------------------------------------------------------------------------ memory refusal

#: at 16² directions and one wavelength the lobes alone take 12 float64 arrays (24.6 kB), the sphere renders' table
#: over incidence adds ~180 kB: a 100 kB budget refuses the run with spheres, not the one without them
SMALL = ["--resolution", "16", "--wavelengths", "550", "--nano", "abc:sigma=8nm,B=2um,C=2.6"]


def test_memory_refusal_offers_no_spheres_in_one_line(tmp_path):
    out = tmp_path / "run"
    rc, stdout, stderr, _ = run_cli(["simulate", "-o", str(out), *SMALL, "--max-memory", "100kB"])
    assert rc == 2 and stdout == "" and not out.exists()
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and "--max-memory" in lines[0] and "drop the sphere renders (--no-spheres)" in lines[0]
    assert "sphere=False" not in lines[0]
    # without spheres the same budget suffices; a smaller one is refused without offering what is already off
    rc, _, stderr, _ = run_cli(["simulate", "-o", str(out), *SMALL, "--no-spheres", "--max-memory", "10kB"])
    assert rc == 2 and "--no-spheres" not in stderr and "--resolution" in stderr
    # compare needs the sphere renders' BRDF functions: it does not offer to drop them
    rc, _, stderr, _ = run_cli(["compare", *SMALL, "--max-memory", "100kB"])
    assert rc == 2 and len(stderr.strip().splitlines()) == 1 and "sphere" not in stderr


def test_sweep_memory_refusal_offers_no_spheres(tmp_path, monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_MAX_MEMORY", "100kB")   # sweep has no --max-memory: the budget of every task
    rc, stdout, stderr, _ = run_cli(["sweep", "--vary", "material=Au", *SMALL, "-o", str(tmp_path / "s.csv")])
    assert rc == 2 and len(stderr.strip().splitlines()) == 1 and "(--no-spheres)" in stderr, stderr


def test_the_library_names_its_keyword_not_the_flag():
    from waveoptics import simulate
    from waveoptics.errors import FieldError
    from waveoptics.request import SimulationRequest

    req = SimulationRequest(resolution=16, wavelengths_nm=(550.0,), nano="abc:sigma=8nm,B=2um,C=2.6")
    with pytest.raises(FieldError) as e:
        simulate.check_request_memory(req, max_memory="100kB")
    assert str(e.value).endswith("or drop the sphere renders (sphere=False)") and "--" not in str(e.value)
