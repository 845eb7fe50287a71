"""Bad input gets one clear error and nothing is lost (issue 7).

Every user mistake of the catalogue in ``tests/hard_cases.py`` is tried through the Python API (ValueError or
TypeError naming the value, one line) and through the CLI in-process (exit code 2, exactly one stderr line with the
same message, no traceback); neither may create or change a file. Two run the real console script in a subprocess.
Then the "nothing lost" promise: a write that fails, is interrupted or is killed half-way never leaves a partial file
under the final name and never destroys an earlier result.
"""
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import hard_cases as H
from waveoptics import io as wio
from waveoptics.cli import build_parser
from waveoptics.cli import main as cli_main
from waveoptics.errors import WaveopticsError

API = [b for b in H.BAD_INPUTS if b.api is not None]
CLI = [b for b in H.BAD_INPUTS if b.argv is not None]


def _dirs(tmp_path, *names):
    out = []
    for n in names:
        (tmp_path / n).mkdir()
        out.append(tmp_path / n)
    return out


@pytest.mark.parametrize("bad", API, ids=lambda b: b.id)
def test_api_raises_one_clear_line(bad, tmp_path):
    problems, _ = H.judge_api(bad, tmp_path)
    assert not problems, problems


@pytest.mark.parametrize("bad", CLI, ids=lambda b: b.id)
def test_cli_exit_2_one_line(bad, tmp_path):
    a, c = _dirs(tmp_path, "api", "cli")
    api_message = H.judge_api(bad, a)[1] if (bad.same and bad.api) else ""
    problems, _ = H.judge_cli(bad, c, api_message)
    assert not problems, problems


def test_judge_catches_a_traceback_and_a_wrong_exit_code(tmp_path):
    """The CLI judge can fail: a command that succeeds (exit 0, nothing on stderr) is reported."""
    ok = H.BadInput("x", "name", "x", "anything", argv=lambda tmp: ["materials", "gold", "--json"])
    problems, _ = H.judge_cli(ok, tmp_path)
    assert any("exit code 0" in p for p in problems)


def _console_script():
    exe = Path(sys.executable).with_name("waveoptics")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "waveoptics"]


@pytest.mark.parametrize("argv, message", [
    (["brdf", "--incident", "95", "--outgoing", "40,180", "--alpha", "0.1", "--ior", "1.5"],
     "θ=95.0° is outside the allowed range [0, 90] degrees"),
    (["surface", "stats", "{tmp}/missing.npz"], "does not exist"),
])
def test_console_script_behaves_the_same(argv, message, tmp_path):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    r = subprocess.run(_console_script() + argv, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "PYTHONWARNINGS": "default"})
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and message in r.stderr and "Traceback" not in r.stderr
    assert r.stdout == ""


def test_debug_shows_the_traceback():
    with pytest.raises(WaveopticsError, match="θ=95.0°"):
        cli_main(["brdf", "--incident", "95", "--outgoing", "40,180", "--alpha", "0.1", "--ior", "1.5", "--debug"])


def test_every_command_has_debug():
    import argparse

    def leaves(parser, name):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            yield name, {o for a in parser._actions for o in a.option_strings}
            return
        for n, sp in subs[0].choices.items():
            yield from leaves(sp, f"{name} {n}")

    missing = [name for name, opts in leaves(build_parser(), "waveoptics") if "--debug" not in opts]
    assert not missing


# ---------------------------------------------------------------------------------------------- nothing lost

def _patch_exr_write(monkeypatch, fail):
    """Make OpenEXR writes put half a file at the temporary name, then call *fail*."""
    import OpenEXR

    def write(self, path):
        Path(path).write_bytes(b"\x76\x2f\x31\x01" + b"half-written" * 8)
        fail()

    monkeypatch.setattr(OpenEXR.File, "write", write)


def _raise(exc):
    def f():
        raise exc
    return f


def test_failed_exr_write_keeps_the_earlier_file(tmp_path, monkeypatch):
    final = tmp_path / "lobes.exr"
    wio.write_exr(final, {"Y": np.ones((4, 4))})
    before = final.read_bytes()
    # a full disk as the OS reports it, and as the OpenEXR bindings report it: one line naming the output
    for failure in (OSError(28, "No space left on device"), RuntimeError("Failed to write pixel data")):
        _patch_exr_write(monkeypatch, _raise(failure))
        with pytest.raises(WaveopticsError, match=r"cannot write .*lobes\.exr"):
            wio.write_exr(final, {"Y": np.zeros((4, 4))})
        assert final.read_bytes() == before
        assert sorted(p.name for p in tmp_path.iterdir()) == ["lobes.exr"]   # the partial file is gone too
        with pytest.raises(WaveopticsError, match="new.exr"):
            wio.write_exr(tmp_path / "new.exr", {"Y": np.zeros((4, 4))})
        assert not (tmp_path / "new.exr").exists()


@pytest.mark.parametrize("failure, rc", [(OSError(28, "No space left on device"), 2), (KeyboardInterrupt(), 130)])
def test_cli_run_that_fails_while_writing_loses_nothing(tmp_path, monkeypatch, capsys, failure, rc):
    """scatter --overwrite over an earlier result: the write fails (disk full) or is interrupted (Ctrl-C) half-way;
    the earlier lobes.exr is intact, no partial file is left, and a clean rerun then replaces it."""
    surface = H._good_surface(tmp_path)
    out = tmp_path / "out"
    argv = ["scatter", "--surface", str(surface), "--material", "Al", "--incident", "30", "--resolution", "16",
            "--wavelengths", "550", "-o", str(out), "--overwrite"]
    assert cli_main(argv) == 0
    earlier = {p.name: p.read_bytes() for p in out.iterdir()}
    capsys.readouterr()
    _patch_exr_write(monkeypatch, _raise(failure))
    assert cli_main(argv) == rc
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == earlier
    monkeypatch.undo()
    assert cli_main(argv) == 0
    chans, _ = wio.read_exr(out / "lobes.exr")
    assert chans and all(np.all(np.isfinite(c)) for c in chans.values())


def test_killed_writer_never_leaves_a_partial_file_under_the_final_name(tmp_path):
    """A process killed (SIGKILL, no clean-up at all) in the middle of writing an EXR: the final name still holds
    the earlier result; the half-written bytes sit only under the hidden temporary name."""
    final = tmp_path / "lobes.exr"
    wio.write_exr(final, {"Y": np.ones((8, 8))})
    before = final.read_bytes()
    script = textwrap.dedent(f"""
        import os, signal
        from pathlib import Path
        import numpy as np
        import OpenEXR
        from waveoptics import io

        def write(self, path):
            Path(path).write_bytes(b"\\x76\\x2f\\x31\\x01" + b"half" * 100)
            os.kill(os.getpid(), signal.SIGKILL)

        OpenEXR.File.write = write
        io.write_exr({str(final)!r}, {{"Y": np.zeros((8, 8))}})
    """)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=120)
    assert r.returncode == -9
    assert final.read_bytes() == before
    left = [p.name for p in tmp_path.iterdir() if p.name != "lobes.exr"]
    assert left and all(n.startswith(".lobes.exr.") and ".partial" in n for n in left)
    chans, _ = wio.read_exr(final)
    np.testing.assert_array_equal(chans["Y"], 1.0)


def test_existing_outputs_are_replaced_only_with_overwrite(tmp_path, capsys):
    out = tmp_path / "g.npz"
    argv = ["surface", "generate", "--generator", "flat", "--samples", "8", "-o", str(out)]
    assert cli_main(argv) == 0
    before = out.read_bytes()
    assert cli_main(argv) == 2 and out.read_bytes() == before
    assert "already exists; pass --overwrite" in capsys.readouterr().err
    assert cli_main(argv + ["--overwrite", "--size", "2um"]) == 0 and out.read_bytes() != before


@pytest.mark.skipif(os.geteuid() == 0 if hasattr(os, "geteuid") else True,
                    reason="root may write into a read-only directory")
def test_read_only_output_directory(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        rc = cli_main(["surface", "generate", "--generator", "flat", "--samples", "8", "-o", str(ro / "g.npz")])
        err = capsys.readouterr().err
        assert rc == 2 and err.count("\n") == 1 and "Traceback" not in err
        assert not any(ro.iterdir())
    finally:
        ro.chmod(0o700)
        shutil.rmtree(ro)


def test_out_of_memory_is_one_line(tmp_path, monkeypatch, capsys):
    """A request too large for memory (numpy raises MemoryError) is one line and exit code 2, not a traceback."""
    from waveoptics import surfaces

    def huge(*a, **kw):
        raise MemoryError("Unable to allocate 646. GiB for an array")

    monkeypatch.setattr(surfaces, "load", huge)
    rc = cli_main(["surface", "stats", str(H._good_surface(tmp_path))])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and "not enough memory" in err and "Traceback" not in err
    with pytest.raises(MemoryError):
        cli_main(["surface", "stats", str(tmp_path / "ok.npz"), "--debug"])
