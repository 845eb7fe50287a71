"""Output sets appear whole or not at all, even under SIGKILL (issue 17).

A child process writes a set through :func:`waveoptics.io.staged_outputs` (or runs a real command) and kills
itself with SIGKILL at every possible point: while staging, and before each move of the commit. The parent then
checks what a user would see: the whole earlier set, or a directory without its manifest (summary.json), never a
manifest beside a mix; and after the next run into that directory (which replays a journalled commit or clears the
litter) a whole set with no staging directory left.
"""
from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from waveoptics.io import files

NAMES = ["a.exr", "b.exr", "c.png", "summary.json"]

# the child patches os.replace so that the k-th move into the output directory (not the journal's own rename in the
# staging directory) kills the process before it happens; k = -1 kills it while the set is still being staged
CHILD = textwrap.dedent("""
    import os, signal, sys
    from pathlib import Path
    out, k = Path(sys.argv[1]), int(sys.argv[2])
    real = os.replace
    moves = [0]
    def replace(a, b):
        if Path(b).parent.resolve() == out.resolve():
            if moves[0] == k:
                os.kill(os.getpid(), signal.SIGKILL)
            moves[0] += 1
        return real(a, b)
    os.replace = replace
    {body}
""")


def _child(out: Path, k: int, body: str):
    code = CHILD.replace("{body}", textwrap.dedent(body))
    return subprocess.run([sys.executable, "-c", code, str(out), str(k)], capture_output=True, text=True,
                          timeout=300)


STAGE_BODY = """
from waveoptics.io import files
names = ["a.exr", "b.exr", "c.png", "summary.json"]
with files.staged_outputs(out, names, last="summary.json") as st:
    for n in names[:2]:
        (st / n).write_text("new " + n)
    if k == -1:
        os.kill(os.getpid(), signal.SIGKILL)
    for n in names[2:]:
        (st / n).write_text("new " + n)
"""


def _contents(d: Path) -> dict:
    return {p.name: p.read_text() for p in d.iterdir() if not p.name.startswith(".")}


@pytest.mark.parametrize("k", [-1, 0, 1, 2, 3])
def test_a_kill_at_any_point_leaves_the_old_set_or_no_manifest_and_the_next_run_lands_a_whole_set(tmp_path, k):
    out = tmp_path / "o"
    out.mkdir()
    old = {n: "old " + n for n in NAMES}
    for n, text in old.items():
        (out / n).write_text(text)
    r = _child(out, k, STAGE_BODY)
    assert r.returncode == -9, r.stderr
    seen = _contents(out)
    if "summary.json" in seen:        # a manifest is there: it must be the old whole set
        assert seen == old
    else:                             # mid-commit: no manifest, and the journalled stage is still there
        assert k >= 0 and any((s / files.JOURNAL).is_file() for s in out.glob(".staging.*.partial"))
    # what the next run into the directory does first
    files.recover_staged(out)
    after = _contents(out)
    new = {n: "new " + n for n in NAMES}
    assert after == (old if k == -1 else new)
    assert not list(out.glob(".staging.*"))


SMALLER_BODY = """
from waveoptics.io import files
names = ["a.exr", "summary.json"]     # this run skips b.exr and c.png (e.g. simulate --no-spheres)
with files.staged_outputs(out, names, last="summary.json", members=["a.exr", "b.exr", "c.png", "summary.json"]) as st:
    for n in names:
        (st / n).write_text("new " + n)
"""


@pytest.mark.parametrize("k", [0, 1])
def test_a_smaller_set_removes_the_earlier_sets_members_it_does_not_hold_also_after_a_kill(tmp_path, k):
    """A set that leaves out optional members (a run without sphere renders over one with them) removes the earlier
    set's files of those names when it lands, so no file of another run sits beside the new manifest; killed
    mid-commit, the replay removes them too. A file that is no member of the set is kept."""
    out = tmp_path / "o"
    out.mkdir()
    for n in NAMES + ["mine.txt"]:
        (out / n).write_text("old " + n)
    r = _child(out, k, SMALLER_BODY)
    assert r.returncode == -9, r.stderr
    files.recover_staged(out)
    assert _contents(out) == {"a.exr": "new a.exr", "summary.json": "new summary.json", "mine.txt": "old mine.txt"}
    r = _child(out, 99, SMALLER_BODY)           # uninterrupted, over the new set: nothing else goes
    assert r.returncode == 0, r.stderr
    assert _contents(out) == {"a.exr": "new a.exr", "summary.json": "new summary.json", "mine.txt": "old mine.txt"}


def test_a_live_run_s_staging_directory_is_left_alone(tmp_path):
    """Two runs into one directory: recovery by the second never clears the first's staging directory."""
    with files.staged_outputs(tmp_path, ["x.txt"], last="x.txt") as st:
        (st / "x.txt").write_text("first")
        assert files.recover_staged(tmp_path) == []
        assert st.is_dir()
        with files.staged_outputs(tmp_path, ["y.txt"], last="y.txt") as st2:
            (st2 / "y.txt").write_text("second")
        assert st.is_dir()
    assert (tmp_path / "x.txt").read_text() == "first" and (tmp_path / "y.txt").read_text() == "second"
    assert not list(tmp_path.glob(".staging.*"))


@pytest.mark.parametrize("k", [0, 3])
def test_simulate_killed_while_moving_its_set_into_place(tmp_path, k):
    """The real command: ``simulate --overwrite`` killed before the 1st and the 4th move of its commit. The earlier
    summary.json is gone at once (the set is marked incomplete), and the next ``simulate`` into the directory
    (which refuses to overwrite without --overwrite) finds the new set completed: every file from the killed run,
    its summary last, none from the earlier one."""
    out = tmp_path / "o"
    base = ["simulate", "-o", str(out), "--resolution", "16", "--sphere-size", "16", "--overwrite"]
    from waveoptics.cli import main
    assert main(base + ["--wavelengths", "550"]) == 0
    old = {p.name: p.read_bytes() for p in out.iterdir()}
    body = f"""
    from waveoptics.cli import main
    main({base + ["--wavelengths", "450,650"]!r})
    """
    r = _child(out, k, body)
    assert r.returncode == -9, r.stderr
    assert "summary.json" not in {p.name for p in out.iterdir()}
    # the next run into the directory, without --overwrite: it completes the set first, then refuses to replace it
    assert main(["simulate", "-o", str(out), "--resolution", "16", "--wavelengths", "550"]) == 2
    new = {p.name: p.read_bytes() for p in out.iterdir()}
    assert set(new) == set(old) and not list(out.glob(".staging.*"))
    assert json.loads(new["summary.json"])["wavelengths_nm"] == [450.0, 650.0]
    assert all(new[n] != old[n] for n in new if n.endswith(".exr"))


def test_npy_pair_interrupted_between_its_two_renames_is_refused(tmp_path):
    """Issue 17: a .npy height field and its sidecar are renamed as two files; a kill between the renames would
    leave a new sidecar beside the earlier heights. The sidecar records the heights' fingerprint, so that mix is
    refused in one line, while the pair itself (and a copy of it) loads."""
    import shutil

    from waveoptics import surfaces
    from waveoptics.errors import WaveopticsError

    a = surfaces.generate("gaussian", sigma="5nm", corr_length="1um", size="8um", samples=64, seed=1)
    b = surfaces.generate("gaussian", sigma="9nm", corr_length="1um", size="16um", samples=64, seed=2)
    p = tmp_path / "h.npy"
    surfaces.save(a, p)
    surfaces.save(b, tmp_path / "new.npy")
    np.testing.assert_array_equal(surfaces.load(p).heights, a.heights)
    copy = tmp_path / "copy"
    copy.mkdir()
    shutil.copy(p, copy / "h.npy")
    shutil.copy(tmp_path / "h.npy.json", copy / "h.npy.json")
    assert surfaces.load(copy / "h.npy").dx == a.dx
    # the new sidecar landed, the heights' rename did not
    shutil.copy(tmp_path / "new.npy.json", tmp_path / "h.npy.json")
    with pytest.raises(WaveopticsError, match="was written for other heights than 'h.npy'"):
        surfaces.load(p)
    with pytest.raises(WaveopticsError, match="was written for other heights"):
        surfaces.open_large(p)
