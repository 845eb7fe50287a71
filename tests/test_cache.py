"""The per-machine cache of the planner (issue 19): the cost model is timed once per machine and reused, plans
of an unchanged scene are answered from the cache, and anything a plan depends on changes its key."""
import json
import shutil
from pathlib import Path

import pytest

from cli_helpers import run_cli
from waveoptics import cache
from waveoptics.planning import costmodel

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_CACHE_DIR", str(tmp_path / "c"))
    return tmp_path / "c"


def test_calibration_is_timed_once_per_machine(cache_dir, monkeypatch):
    monkeypatch.setattr(costmodel, "machine_busy", lambda: False)
    first = costmodel.calibration()
    assert list(cache_dir.glob("calibration-*.json"))

    def boom():
        raise AssertionError("calibrated again")

    monkeypatch.setattr(costmodel, "calibrate", boom)
    assert costmodel.calibration() == first
    with pytest.raises(AssertionError, match="calibrated again"):
        costmodel.calibration(recalibrate=True)


def test_a_busy_machine_does_not_keep_its_timings(cache_dir, monkeypatch):
    """A cost model timed while more work than CPUs ran serves that process only: a calibration kept from a test
    run once put a 4.8 s scene at 18 s in every later plan."""
    monkeypatch.setattr(costmodel.os, "getloadavg", lambda: (64.0 * (costmodel.os.cpu_count() or 1), 0.0, 0.0))
    assert costmodel.machine_busy()
    cm = costmodel.calibration()
    assert cm.cell_wl >= 0 and not list(cache_dir.glob("calibration-*.json"))
    monkeypatch.setattr(costmodel.os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    assert not costmodel.machine_busy()
    assert costmodel.calibration() == cm          # the same process's timings, now kept
    assert list(cache_dir.glob("calibration-*.json"))


def test_machine_key_follows_what_timings_depend_on(monkeypatch):
    monkeypatch.delenv("WAVEOPTICS_WORKERS", raising=False)   # make test sets it to 1 for its workers
    k = cache.machine_key()
    monkeypatch.setenv("WAVEOPTICS_WORKERS", "1")
    one = cache.machine_key()
    monkeypatch.setenv("WAVEOPTICS_WORKERS", "3")
    assert len({k, one, cache.machine_key()}) == 3


def test_cache_survives_garbage_and_an_unwritable_directory(cache_dir, tmp_path, monkeypatch):
    cache_dir.mkdir(parents=True)
    (cache_dir / f"plans-{cache.machine_key()}.json").write_text("{not json")
    assert cache.get("plans", "x") is None
    cache.put("plans", "x", {"a": 1})
    assert cache.get("plans", "x") == {"a": 1}
    monkeypatch.setenv("WAVEOPTICS_CACHE_DIR", "/proc/waveoptics-cannot-write-here")
    cache.put("plans", "x", {"a": 2})          # skipped without a word
    assert cache.get("plans", "x") is None


def test_plan_answers_from_the_cache_until_the_scene_or_its_files_change(cache_dir, tmp_path):
    scene = tmp_path / "s.toml"
    shutil.copy(SCENES / "smooth-plastic.toml", scene)
    rc, out1, err, _ = run_cli(["plan", str(scene), "--json"])
    assert rc == 0, err
    rc, out2, err, _ = run_cli(["plan", str(scene), "--json"])
    first, second = json.loads(out1), json.loads(out2)
    assert second.pop("from_cache") is True and "from_cache" not in first
    assert second == first
    rc, out3, err, _ = run_cli(["plan", str(scene), "--json", "--recalibrate"])
    assert "from_cache" not in json.loads(out3)
    scene.write_text(scene.read_text() + "\n# edited\n")
    rc, out4, err, _ = run_cli(["plan", str(scene), "--json"])
    assert "from_cache" not in json.loads(out4)
    rc, out5, err, _ = run_cli(["plan", str(scene), "--json", "--force", "diffuse=off"])
    assert "from_cache" not in json.loads(out5)


def test_a_named_file_is_part_of_the_plan_key(cache_dir, tmp_path):
    from waveoptics import surfaces
    from waveoptics.cli import build_parser, command_parser
    from waveoptics.cli.plan import plan_key

    surfaces.save(surfaces.generate("flat", size="3.2um", samples="32"), tmp_path / "h.npz")
    (tmp_path / "s.toml").write_text('materials = [{name = "m", material = "Al", nano = {file = "h.npz"}}]\n')
    args = command_parser(build_parser(), "plan").parse_args([str(tmp_path / "s.toml")])
    k1 = plan_key(args)
    surfaces.save(surfaces.generate("flat", size="6.4um", samples="32"), tmp_path / "h.npz", overwrite=True)
    assert plan_key(args) != k1
