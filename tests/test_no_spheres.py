"""``simulate --no-spheres`` (promise 3: simulate only what is asked, and say what was skipped and why): the lobe
outputs and no sphere file, a summary that names the skipped renders and the reason, a text line without a sphere
ΔE, a progress bar whose total is the lobe evaluations the run makes, and --environment refused beside it."""
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
