"""Data of docs/reliability.md (docs/data/reliability.json; prose in docs/templates/reliability.md): the hard cases
and bad inputs of issue 7, with counts, from the test catalogue.

Runs the catalogue in ``tests/hard_cases.py`` exactly as ``tests/test_hard_cases.py`` and ``tests/test_bad_input.py``
judge it (same functions), the hypothesis properties with the tests' settings, and the "nothing lost" tests of
``tests/test_bad_input.py`` through pytest. No result in the page is typed by hand.
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
import time
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
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


def counts(cases, props, bads, lost) -> dict:
    """The numbers of the page's count table, from the raw results of the four runs."""
    n_run = sum(1 for _, o, _ in cases if o.status != "skipped")
    return {"cases": len(cases), "run": n_run, "skipped": len(cases) - n_run,
            "passing": sum(1 for _, o, _ in cases if o.status in ("ok", "refused")),
            "nonfinite": sum(o.nonfinite for _, o, _ in cases), "negative": sum(o.negative for _, o, _ in cases),
            "refused": sum(1 for _, o, _ in cases if o.status == "refused"),
            "fixed_cases": sum(1 for c, _, _ in cases if c.fixed),
            "properties": len(props), "examples": sum(n for _, n, _, _ in props),
            "properties_failing": sum(1 for _, _, m, _ in props if m), "bad_inputs": len(bads),
            "api": [sum(1 for b, p, *_ in bads if p == []), sum(1 for b, p, *_ in bads if p is not None)],
            "cli": [sum(1 for b, _, _, p, _ in bads if p == []), sum(1 for b, _, _, p, _ in bads if p is not None)],
            "tracebacks": sum(1 for *_, p, e in bads if p and any("traceback" in x for x in p)),
            "fixed_bad": sum(1 for b, *_ in bads if b.fixed),
            "lost": [sum(1 for _, o, _ in lost if o == "passed"), len(lost)],
            "lost_skipped": sum(1 for _, o, _ in lost if o == "skipped")}


def _tests(rows) -> list:
    return [{"name": n, "outcome": o, "why": w} for n, o, w in rows]


def data(cases, props, bads, lost, device, round_two) -> dict:
    """The page's data from the runs' results: counts, one row per case, property, bad input and test."""
    import test_cli_fuzz as fuzz

    failing = [c.id for c, o, _ in cases if not o.passed or (c.refuse and o.status == "ok")]
    return {
        "device": device, "counts": counts(cases, props, bads, lost),
        "failing": failing + [p.id for p, _, m, _ in props if m],
        "categories": list(H.CATEGORIES), "bad_categories": list(H.BAD_CATEGORIES),
        "precision": [[c.id, k, v] for c, o, _ in cases for k, v in o.numbers.items()],
        "cases": [{"id": c.id, "category": c.category, "what": c.what, "status": o.status, "message": o.message,
                   "seconds": t} for c, o, t in cases],
        "properties": [{"id": p.id, "what": p.what, "examples": n, "failure": m} for p, n, m, _ in props],
        "bad_inputs": [{"category": b.category, "what": b.what, "api": ap, "cli": cp, "message": (ce or am)[:160]}
                       for b, ap, am, cp, ce in bads],
        "lost": _tests(lost), "round_two": _tests(round_two),
        "fuzz": {"examples": fuzz.EXAMPLES, "commands": len(fuzz.BASE)},
        "found_fixed": [[c.id, c.fixed] for c, _, _ in cases if c.fixed]
        + [[b.id, b.fixed] for b, *_ in bads if b.fixed] + [[p.id, p.fixed] for p in H.PROPERTIES if p.fixed]}


def compute() -> dict:
    """Run the catalogue, the properties, the bad inputs and the pytest-run tests (minutes)."""
    rt = _runtime()
    device = "none (OpenCL cases skipped)" if rt is None else f"{rt.name} (fp64: {'yes' if rt.fp64 else 'no'})"
    return data(run_hard_cases(rt), run_properties(), run_bad_inputs(), run_lost_tests(), device,
                run_lost_tests(ROUND_TWO, k=None))


def main():
    import make_docs

    make_docs.main(["reliability"])


if __name__ == "__main__":
    main()
