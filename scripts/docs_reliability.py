"""Write docs/reliability.md: the hard cases and bad inputs of issue 7, with counts, from the test catalogue.

Runs the catalogue in ``tests/hard_cases.py`` exactly as ``tests/test_hard_cases.py`` and ``tests/test_bad_input.py``
judge it (same functions), the hypothesis properties with the tests' settings, and the "nothing lost" tests of
``tests/test_bad_input.py`` through pytest; then writes the tables. Nothing in the page is typed by hand.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "reliability.md"
sys.path.insert(0, str(ROOT / "tests"))

import hard_cases as H  # noqa: E402

#: tests of tests/test_bad_input.py that are not catalogue entries (nothing lost, console script, --debug)
LOST_TESTS = "not test_api_raises_one_clear_line and not test_cli_exit_2_one_line"


def _runtime():
    from waveoptics import runtime

    return runtime.get_runtime() if runtime.opencl_available() else None


def run_hard_cases(rt):
    rows = []
    for case in H.CASES:
        t = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            out = H.run_case(case, H.Env(Path(tmp), rt))
        rows.append((case, out, time.perf_counter() - t))
    return rows


def run_properties():
    from hypothesis import HealthCheck, given, settings

    rows = []
    for prop in H.PROPERTIES:
        n = [0]

        @settings(max_examples=prop.max_examples, deadline=None, derandomize=True, database=None,
                  suppress_health_check=[HealthCheck.too_slow])
        @given(prop.strategy())
        def holds(example):
            n[0] += 1
            prop.check(example)

        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                holds()
                msg = ""
            except AssertionError as exc:
                msg = str(exc).splitlines()[0][:200]
        rows.append((prop, n[0], msg, time.perf_counter() - t))
    return rows


def run_bad_inputs():
    rows = []
    for bad in H.BAD_INPUTS:
        with tempfile.TemporaryDirectory() as tmp:
            a, c = Path(tmp) / "api", Path(tmp) / "cli"
            a.mkdir()
            c.mkdir()
            api_p, api_msg = H.judge_api(bad, a) if bad.api else (None, "")
            cli_p, cli_err = H.judge_cli(bad, c, api_msg if bad.same else "") if bad.argv else (None, "")
        rows.append((bad, api_p, api_msg, cli_p, cli_err))
    return rows


#: the round-two tests of issue 17: regressions per class, whole output sets under SIGKILL, the CLI fuzz test
ROUND_TWO = ("test_failure_classes.py", "test_output_sets.py", "test_cli_fuzz.py")


def run_lost_tests(files=("test_bad_input.py",), k=LOST_TESTS):
    """(test name, outcome, skip reason) of tests in *files* (by default the nothing-lost / console-script / --debug
    tests), run by pytest."""
    with tempfile.TemporaryDirectory() as tmp:
        xml = Path(tmp) / "r.xml"
        subprocess.run([sys.executable, "-m", "pytest", *(str(ROOT / "tests" / f) for f in files), "-q",
                        "-p", "no:cacheprovider", *(("-k", k) if k else ()), f"--junitxml={xml}"], cwd=ROOT,
                       capture_output=True, text=True, timeout=1800)
        out = []
        for tc in ET.parse(xml).getroot().iter("testcase"):
            kinds = {child.tag: child for child in tc}
            outcome = "failed" if kinds.keys() & {"failure", "error"} else "skipped" if "skipped" in kinds else "passed"
            why = kinds["skipped"].get("message", "") if outcome == "skipped" else ""
            out.append((tc.get("name"), outcome, why))
    return out


def _esc(text) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _status(out) -> str:
    return {"ok": "finite, ≥ 0, check holds", "refused": "refused (policy)", "skipped": "skipped: " + out.message
            }.get(out.status, f"**FAIL** {out.status}: {_esc(out.message)}")


def render(cases, props, bads, lost, device, round_two=()) -> str:
    n_run = sum(1 for _, o, _ in cases if o.status != "skipped")
    nonfinite_now = sum(o.nonfinite for _, o, _ in cases)
    negative_now = sum(o.negative for _, o, _ in cases)
    failing = [(c, o) for c, o, _ in cases if not o.passed or (c.refuse and o.status == "ok")]
    refused = sum(1 for _, o, _ in cases if o.status == "refused")
    fixed_cases = [c for c, _, _ in cases if c.fixed]
    examples = sum(n for _, n, _, _ in props)
    prop_fail = [p for p, _, m, _ in props if m]
    api_n = sum(1 for b, p, *_ in bads if p is not None)
    api_ok = sum(1 for b, p, *_ in bads if p == [])
    cli_n = sum(1 for b, _, _, p, _ in bads if p is not None)
    cli_ok = sum(1 for b, _, _, p, _ in bads if p == [])
    tracebacks = sum(1 for *_, p, e in bads if p and any("traceback" in x for x in p))
    fixed_bad = [b for b, *_ in bads if b.fixed]
    lost_ok = sum(1 for _, o, _ in lost if o == "passed")
    lost_skip = sum(1 for _, o, _ in lost if o == "skipped")

    L = ["# Reliability: hard cases and bad input", "",
         "*Generated by `scripts/docs_reliability.py` from the catalogue in `tests/hard_cases.py` (the same data and "
         "judging functions as `tests/test_hard_cases.py` and `tests/test_bad_input.py`) — do not edit by hand.*",
         "", f"Device for the OpenCL cases: {device}.", "",
         "## Counts", "",
         "| | count |", "|---|---|",
         f"| hard cases | {len(cases)} ({n_run} run, {len(cases) - n_run} skipped) |",
         f"| hard cases passing now | {sum(1 for _, o, _ in cases if o.status in ('ok', 'refused'))} |",
         f"| NaN/Inf values found now | {nonfinite_now} |",
         f"| negative values found now | {negative_now} |",
         f"| hard cases refused with a clear error, as the documented policy says | {refused} |",
         f"| hard cases that were broken before this catalogue (NaN/Inf, energy, silent loss) and are fixed | "
         f"{len(fixed_cases)} |",
         f"| property tests (hypothesis, derandomized) / examples run / failing | {len(props)} / {examples} / "
         f"{len(prop_fail)} |",
         f"| bad inputs | {len(bads)} |",
         f"| … rejected by the Python API with one clear ValueError/TypeError line | {api_ok} of {api_n} |",
         f"| … rejected by the CLI: exit code 2, one stderr line, same message, no traceback, no file touched | "
         f"{cli_ok} of {cli_n} |",
         f"| tracebacks found now | {tracebacks} |",
         f"| bad inputs that were mishandled before this catalogue and are fixed | {len(fixed_bad)} |",
         f"| nothing-lost, console-script and `--debug` tests passing | {lost_ok} of {len(lost)}"
         + (f" ({lost_skip} skipped, see below)" if lost_skip else "") + " |", ""]
    if failing or prop_fail:
        L += ["**Failing now:** " + ", ".join([c.id for c, _ in failing] + [p.id for p in prop_fail]), ""]

    L += ["## Policies", "",
          "* **Grazing angles.** Directions at or below the horizon give exactly 0. The Kirchhoff (tangent-plane) "
          "obliquity factor grows as 1/cos θ_i, so near grazing incidence the Kirchhoff lobe alone does not conserve "
          "energy: `scatter.scatter` says so in a warning (`energy not conserved`), and the two-scale model caps "
          "the diffracted light at the light its coherent lobe lost, which keeps the sum within F (physics.md §7).",
          "* **Roughness.** α ∈ [0, 2] (0 means the sharpest representable lobe, α = 1e-4); larger α is refused. "
          "The PSD (Kirchhoff-series) route refuses nano-roughness whose series would hold less than 99 % of the "
          "scattered light in any direction (σ ≳ λ/2); use a height field (fft/direct solvers) or the micro NDF.",
          "* **Materials.** Outside a data set's range the index is clamped to the edge value (never extrapolated), "
          "the clamped wavelengths are reported (`Material.out_of_range`, `clamped_wavelengths_nm` in simulate's "
          "summary), and wavelengths more than 100 nm beyond the data are refused.",
          "* **Precision.** float32 is the default on the device; its field error on a 10⁴ λ patch is bounded below "
          "(next section). Below ~1e-10 of the lobe peak float32 |U|² is noise: use `--precision float64` for deeper "
          "dynamic range.",
          "* **Files.** Every output goes through a temporary name in the same directory and `os.replace`; "
          "existing outputs are refused without `--overwrite`. Sets of files (simulate, scatter, compare, render, "
          "scene runs) are staged whole and moved under a journal, their manifest (summary.json, plan.json, "
          "compare.json) last (`waveoptics.io.staged_outputs`).", ""]

    L += ["## float32 against float64 (direct Kirchhoff kernel)", "",
          "| case | quantity | value |", "|---|---|---|"]
    for c, o, _ in cases:
        for k, v in o.numbers.items():
            L.append(f"| `{c.id}` | {_esc(k)} | {v:.3g} |")
    L.append("")

    L += ["## Hard cases", ""]
    for cat in H.CATEGORIES:
        sel = [(c, o, t) for c, o, t in cases if c.category == cat]
        L += [f"### {cat} ({len(sel)})", "", "| case | what | result | time (s) |", "|---|---|---|---|"]
        for c, o, t in sel:
            L.append(f"| `{c.id}` | {_esc(c.what)} | {_status(o)} | {t:.2f} |")
        L.append("")

    L += ["## Property tests", "", "| property | what | examples | result |", "|---|---|---|---|"]
    for p, n, msg, _ in props:
        L.append(f"| `{p.id}` | {_esc(p.what)} | {n} | {'holds' if not msg else '**FAIL** ' + _esc(msg)} |")
    L.append("")

    L += ["## Bad inputs", "", "Each is tried through the Python API and/or the CLI (in-process); the message is the "
          "CLI's stderr line (the API raises the same text where both are given).", ""]
    for cat in H.BAD_CATEGORIES:
        sel = [r for r in bads if r[0].category == cat]
        L += [f"### {cat} ({len(sel)})", "", "| input | API | CLI | message |", "|---|---|---|---|"]
        for b, ap, am, cp, ce in sel:
            def mark(p):
                return "—" if p is None else ("ok" if not p else "**FAIL** " + _esc("; ".join(p)))
            msg = ce or am
            L.append(f"| {_esc(b.what)} | {mark(ap)} | {mark(cp)} | `{_esc(msg[:160])}` |")
        L.append("")

    L += ["## Nothing lost", "", "From `tests/test_bad_input.py` (run by pytest from this script): a write that fails "
          "(disk full), is interrupted (Ctrl-C) or is killed (SIGKILL) half-way leaves the earlier result intact "
          "and nothing under the final name; the real console script answers like the in-process CLI; `--debug` "
          "shows the traceback.", "", "| test | result |", "|---|---|"]
    for name, outcome, why in lost:
        L.append(f"| `{name}` | {outcome}{': ' + _esc(why) if why else ''} |")
    L.append("")

    import test_cli_fuzz as fuzz

    FUZZ_EXAMPLES = fuzz.EXAMPLES
    draws = len(fuzz.BASE) * FUZZ_EXAMPLES
    L += ["## Round two: every class of failure, whole output sets, a fuzzed CLI", "",
          "From `tests/test_failure_classes.py` (one regression test per class of failure found by an adversarial "
          "user), `tests/test_output_sets.py` (a child process kills itself with SIGKILL while staging and before "
          "each move of the commit; what is left is the whole earlier set, or a directory without its manifest "
          "whose journal the next run replays, never a mix) and `tests/test_cli_fuzz.py` (hypothesis, derandomized: "
          f"{FUZZ_EXAMPLES} draws of up to four options with valid, edge and junk values for each of "
          f"{len(fuzz.BASE)} commands, {draws} invocations: exit 0 or 2, one stderr line on 2, no traceback, "
          "every printed or written number finite, memory within the budget).", "",
          f"Passing: {sum(1 for _, o, _ in round_two if o == 'passed')} of {len(round_two)}.", "",
          "| test | result |", "|---|---|"]
    for name, outcome, why in round_two:
        L.append(f"| `{name}` | {outcome}{': ' + _esc(why) if why else ''} |")
    L.append("")

    L += ["## Found and fixed", "", "| case | what was wrong, and the fix |", "|---|---|"]
    for c in fixed_cases:
        L.append(f"| `{c.id}` | {_esc(c.fixed)} |")
    for b in fixed_bad:
        L.append(f"| `{b.id}` | {_esc(b.fixed)} |")
    for p in H.PROPERTIES:
        if p.fixed:
            L.append(f"| `{p.id}` | {_esc(p.fixed)} |")
    L.append("")

    L += ["## Not covered", "",
          "* GPU devices: the float32 numbers above come from the device named at the top; other OpenCL "
          "implementations of `sinpi`/`cospi` may differ (the tests run on any device chosen by WAVEOPTICS_DEVICE).",
          "* The Kirchhoff model itself is not made energy-conserving near grazing incidence (it is a warning); only "
          "the two-scale model caps it.",
          "* Correlation lengths far below λ are outside the tangent-plane model: the result stays finite and "
          "bounded (scattered light is lost, never created), but it is not physical.",
          "* Memory is estimated before any work for simulate, compare, scatter, table and generated surfaces "
          "(`--max-memory`, default half the machine's memory); time is estimated for scenes (`plan`) and sweeps "
          "only, so a request that fits in memory may still run long.", ""]
    return "\n".join(L)


def main():
    rt = _runtime()
    device = "none (OpenCL cases skipped)" if rt is None else f"{rt.name} (fp64: {'yes' if rt.fp64 else 'no'})"
    cases = run_hard_cases(rt)
    props = run_properties()
    bads = run_bad_inputs()
    lost = run_lost_tests()
    round_two = run_lost_tests(ROUND_TWO, k=None)
    from waveoptics.io.files import atomic_path

    with atomic_path(DOC) as tmp:
        tmp.write_text(render(cases, props, bads, lost, device, round_two) + "\n")
    counts = Counter(o.status for _, o, _ in cases)
    print(f"wrote {DOC}: {len(cases)} hard cases {dict(counts)}, {len(bads)} bad inputs, {len(props)} properties")


if __name__ == "__main__":
    main()
