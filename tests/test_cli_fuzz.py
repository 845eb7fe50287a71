"""A seeded fuzz test over the CLI's option grammar (issue 17).

For every command (but the slow renderers and benchmarks), hypothesis draws a few of its options and a value for
each from pools of valid values, edge values and junk (empty, NaN, infinities, huge and tiny numbers, missing
units, misplaced separators). Whatever it draws, the promise is the same:

* the exit code is 0 or 2, never a crash;
* on 2, exactly one line on stderr, naming the command, and no traceback;
* every number printed or written (stdout, ``--json``, JSON files) is finite;
* no EXR or JSON file written holds a negative or non-finite BRDF or radiance, and an RGB image with colours
  outside its gamut says so (tests/output_scan.py; issue 34);
* the process stays within its memory budget (``WAVEOPTICS_MAX_MEMORY``).

Each command starts from a small valid invocation (so that valid draws finish in seconds); the drawn options come
after it and override it. derandomize=True: the same draws every run.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from waveoptics.cli import build_parser, command_parser
from waveoptics.cli import main as cli_main

from output_scan import scan_outputs

SCENE = str(Path(__file__).resolve().parents[1] / "examples" / "scenes" / "smooth-plastic.toml")

#: commands and the small valid invocation each starts from ({out} a fresh directory, {surface} a small field)
BASE = {
    "brdf": ["brdf", "--incident", "30", "--outgoing", "40,180"],
    "compare": ["compare", "--resolution", "16", "--incident-angles", "0,40", "--wavelengths", "550"],
    "f0": ["f0", "Au"],
    "info": ["info"],
    "materials": ["materials"],
    "metamer": ["metamer"],
    "plan": ["plan", SCENE],
    "run": ["run", SCENE, "-o", "{out}/run"],
    "scatter": ["scatter", "--surface", "{surface}", "--material", "Au", "--incident", "30", "-o", "{out}/s",
                "--resolution", "16", "--wavelengths", "550"],
    "simulate": ["simulate", "-o", "{out}/sim", "--resolution", "16", "--sphere-size", "16", "--wavelengths",
                 "450,650"],
    "surface generate": ["surface", "generate", "-o", "{out}/h.npz", "--samples", "32", "--size", "8um"],
    "surface stats": ["surface", "stats", "{surface}"],
    "surface prepare": ["surface", "prepare", "{surface}", "-o", "{out}/p.npz"],
    "surface transform": ["surface", "transform", "{surface}", "-o", "{out}/t.npz"],
    "sweep": ["sweep", "--vary", "micro_alpha=0.1,0.2", "-o", "{out}/s.csv", "--resolution", "16",
              "--wavelengths", "550"],
    "table": ["table", "-o", "{out}/t.h5", "--resolution", "16", "--incident-angles", "0,30", "--wavelengths",
              "550"],
}

#: options not drawn: help, tracebacks, and those that start worker processes or clusters (covered elsewhere)
SKIP = {"-h", "--help", "--debug", "--workers", "--scheduler", "--version"}

#: the grammars of issue 34's legal inputs (units by name and case, angle suffixes, complex-index notations, stacks)
#: are in VALUES beside their refused neighbours, so the draws meet both sides of each rule
JUNK = ["", " ", "nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-308", "abc", ",", ":", "1,,2",
        "0:inf:1", "550:400:10", "4nm00", "5", "1+6j", "1.5+1e308j", "99:99", "1e9", "-0", "☃", "10 nm",
        "--", "%s", "1_000"]

#: valid and edge values of options that take a value, by flag (others get JUNK and the generic numbers)
VALUES = {
    "--wavelengths": ["550", "450,650", "500:600:50", "0.55um", "380", "830", "200", "100000", "550nm", "550,,650",
                      "1e300", "450, 650", "0.45μm,550NM", "5500Å", "550;650"],
    "--incident": ["30", "30,45", "0", "89.9", "90", "-10", "30,400", "45,nan", "30°", "30deg,45deg", "0.5rad"],
    "--outgoing": ["40,180", "0", "89,0", "95,0"],
    "--incident-angles": ["0,40", "0:80:40", "89.99", "90", "0:80:0.00001", "0°:60°:30°", "0deg,40deg"],
    "--resolution": ["8", "16", "32", "7", "0", "100000"],
    "--material": ["Au", "Al", "1.5", "1+6j", "f0:0.9", "f0:1.5", "nosuch", "1e-300", "Au@Babar", "(1.5+0.01j)",
                   "1.5 + 0.01i", "Fused Silica", "Al|Al2O3:120nm", "Al|Al2O3:120", "1.5-0.01j"],
    "--nano": ["gaussian:sigma=5nm,corr_length=1um", "abc:sigma=10nm,B=2um,C=2.6", "abc:sigma=10nm,B=2um,C=1.5",
               "gaussian:sigma=-5nm,corr_length=1um", "gaussian:sigma=5,corr_length=1um",
               "exponential:sigma=1um,corr_length=1um", "sinusoid:amplitude=40nm,period=2um", "gaussian:sigma=5nm",
               "Gaussian:sigma=5nm,corr_length=1um", "gaussian: sigma=5nm, corr_length=1um",
               "gaussian:sigma=5nm,T=1um"],
    "--micro-alpha": ["0", "0.1", "2", "3", "-1"],
    "--alpha": ["0", "0.1", "2", "3", "-1"],
    "--alpha-y": ["0.001", "0.5", "2"],
    "--kd": ["0", "0.5", "1", "1.5"],
    "--sphere-size": ["16", "24", "15", "5000"],
    "--spp": ["1", "4", "0"],
    "--samples": ["16", "32", "32x16", "1", "100000"],
    "--size": ["8um", "8um,4um", "8", "0um", "1km", "8 microns", "8UM", "0.008mm"],
    "--spacing": ["50nm", "50nm,80nm", "50", "0nm", "500Å", "50 nanometres"],
    "--seed": ["1", "-1", "2**70"],
    "--illuminant": ["D65", "A", "blackbody:5500K", "laser:532", "blackbody:-5K", "F13", "laser:532NM",
                     "laser:0.638um", "laser:532:600:1"],
    "--delta-e": ["1", "0.1", "0", "-1"],
    "--ndf-shape": ["2.5", "1.5", "0.5"],
    "--max-memory": ["1GB", "1kB", "0", "lots"],
    "--realizations": ["1", "2", "0"],
    "--window": ["hann", "boxcar", "gaussian:1um", "gaussian:-1um", "nosuch"],
    "--footprint": ["2um,2um,0.5um", "0,0,1um", "1um,1um,-1um", "100um,100um,1um"],
    "--coherence": ["0.5um", "-1um"],
    "--light-radius": ["0.5", "0.5deg", "0.01rad", "-1", "45"],
    "--order": ["0", "3", "auto", "1000"],
    "--units": ["nm", "um", "furlong"],
    "--vary": ["micro_alpha=0.1,0.2", "sigma_nano=1nm:1000000nm:1nm", "nosuch=1,2", "micro_alpha=0:1:0.5",
               "theta=30,30"],
    "--force": ["diffraction=on", "diffraction=off", "diffuse", "solver=fft"],
    "--tail": ["10", "0", "90"],
    "--phi": ["0", "45", "nan"],
    "--batch": ["1", "0"],
    "--device": ["cpu", "99:99", "nvidia", "", " "],
    "--output": ["{out}/x", ""],
    "-o": ["{out}/x", ""],
    "--generator": ["gaussian", "sinusoid", "scratches", "flakes"],
    "--amplitude": ["40nm", "-1nm"],
    "--period": ["2um", "10nm"],
    "--sigma": ["5nm", "0nm", "5"],
    "--corr-length": ["1um", "0um"],
    "--tilt": ["8", "100"],
    "--flake-size": ["2um", "0um"],
    "--environment": ["constant", "sky", "nosuch.exr"],
}


def _leaf_commands():
    parser = build_parser()
    return parser, {name: command_parser(parser, name) for name in BASE}


PARSER, PARSERS = _leaf_commands()


def _drawable(parser: argparse.ArgumentParser):
    return [a for a in parser._actions if a.option_strings and not (set(a.option_strings) & SKIP)]


@st.composite
def invocations(draw, command: str):
    """argv for *command*: its base invocation plus up to four drawn options."""
    actions = _drawable(PARSERS[command])
    chosen = draw(st.lists(st.sampled_from(actions), max_size=4, unique_by=lambda a: a.dest)) if actions else []
    argv = list(BASE[command])
    for a in chosen:
        flag = a.option_strings[-1]
        if a.nargs == 0:                                  # a switch
            argv.append(flag)
            continue
        pool = list(a.choices) + ["nosuch"] if a.choices else VALUES.get(flag, []) + JUNK
        argv += [flag, draw(st.sampled_from(pool))]
    return argv


def _finite_json(text: str, where: str):
    def bad(token):
        raise AssertionError(f"{where}: non-finite number {token!r}")
    data = json.loads(text, parse_constant=bad)

    def walk(x):
        if isinstance(x, float):
            assert math.isfinite(x), where
        elif isinstance(x, dict):
            for v in x.values():
                walk(v)
        elif isinstance(x, list):
            for v in x:
                walk(v)
    walk(data)


NON_FINITE = re.compile(r"(?<![\w.-])[-+]?(nan|inf|infinity)(?![\w])", re.IGNORECASE)


def _run(argv, capsys):
    work = Path(tempfile.mkdtemp(prefix="wo-fuzz-"))
    here = os.getcwd()
    os.chdir(work)           # junk output names ('-o %s') land in the scratch directory
    try:
        surface = work / "h.npz"
        rng = np.random.default_rng(7)
        np.savez(surface, heights=rng.normal(0.0, 5e-9, (32, 32)), dx=1e-7, dy=1e-7)
        argv = [a.replace("{out}", str(work)).replace("{surface}", str(surface)) for a in argv]
        capsys.readouterr()
        try:
            rc = cli_main(argv)
        except SystemExit as exc:           # argparse's own refusals (exit 2, one line: cli._Parser.error)
            rc = exc.code
        out, err = capsys.readouterr()
        shown = " ".join(repr(a) for a in argv)
        assert rc in (0, 2), f"exit {rc}: {shown}\n{err[-2000:]}"
        assert "Traceback" not in err, f"{shown}\n{err[-2000:]}"
        if rc == 2:
            lines = [ln for ln in err.splitlines() if ln.strip()]
            assert len(lines) == 1 and lines[0].startswith("waveoptics"), f"{shown}\n{err}"
        else:
            if "--json" in argv:
                _finite_json(out, shown)
            else:   # the user's own words echoed back (a file named 'nan') are not numbers
                text = out
                for a in sorted(argv, key=len, reverse=True):
                    if len(a) >= 3 or a.lower() in ("nan", "inf"):
                        text = text.replace(a, "")
                assert not NON_FINITE.search(text), f"{shown}\n{out[-2000:]}"
            for p in work.rglob("*.json"):
                if not p.name.startswith("."):
                    _finite_json(p.read_text(), f"{shown}: {p.name}")
            problems = scan_outputs(work)
            assert not problems, f"{shown}: {problems}"
    finally:
        os.chdir(here)
        shutil.rmtree(work, ignore_errors=True)


#: hypothesis draws per command (20; 60 once spent 5 minutes of the suite on one legal, CPU-heavy compare draw, and
#: 30 cost the suite ~25 s more when it ran at the 10-minute limit)
EXAMPLES = 20

#: fewer draws for the commands whose base invocation alone runs a whole scene or sweep (~1 s a draw on 2 cores);
#: run and plan have 7 and 6 drawable options (7 and 10 draws of up to four reach each at least once), sweep 27
HEAVY_EXAMPLES = {"run": 7, "sweep": 10, "plan": 10}


#: the memory budget every draw runs under: legal but huge requests (``--resolution 1_000``: 1.6 GB) are refused by
#: the same check that guards a user's machine, instead of running for minutes
BUDGET = "256MB"


@pytest.fixture(autouse=True)
def _budget(monkeypatch):
    monkeypatch.setenv("WAVEOPTICS_MAX_MEMORY", BUDGET)


@pytest.mark.parametrize("command", sorted(BASE))
def test_any_option_draw_exits_0_or_2_with_one_line_and_finite_numbers(command, capsys):
    @settings(max_examples=HEAVY_EXAMPLES.get(command, EXAMPLES), derandomize=True, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(invocations(command))
    def check(argv):
        _run(argv, capsys)

    check()
    # the budget held: the test process (which ran every draw) never grew past it plus the interpreter's own
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    # (the worker process also ran other tests before this one, so the bound is the budget plus 3.5 GB of headroom)
    assert peak < 0.256e9 + 4.25e9, f"peak resident memory {peak / 1e9:.3g} GB"
