"""Issue 28's speed bullet: this tree against 08faf07 ("today" in the issue), by the same measures on both.

Runs ``waveoptics/bench/model_speed.py`` of THIS tree (its :func:`brdf_eval_rates` and :func:`simulate_times`,
written in public names only) in fresh processes, each with one tree on ``PYTHONPATH``, alternating the trees,
``--repeats`` times (default 3); keeps the best of each measure per tree and records the ratios and the issue's
bounds: pointwise ``TwoScaleBRDF.eval`` at most 2× slower; the tabulated form at least 1e6 evaluations/s;
``simulate()`` at its defaults within 1.5× (fresh process: the first call, which pays the one-off costs; and warm:
the best later call in the same process). Every child runs with ``WAVEOPTICS_WORKERS=1`` (CPU time then is the
computation's own, less sensitive to the machine's load than the wall clock) and its own empty cache directory.

``--write`` stores the result as ``vs_08faf07`` in docs/data/performance.json and re-renders docs/performance.md
(its section "Against 08faf07"); ``scripts/docs_performance.py`` keeps that entry when it recomputes the rest.
``--from-data`` measures nothing and summarizes the kept runs again.

Usage::

    PYTHONPATH=$PWD python scripts/bench_vs_08faf07.py [--old /tmp/audit28/old] [--repeats 3] [--write] [--from-data]

``--old``: an unpacked copy of commit 08faf07 (``git archive 08faf07 | tar -x -C DIR``).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
MODEL_SPEED = ROOT / "waveoptics" / "bench" / "model_speed.py"

#: what a child process runs: the measure *what* from model_speed.py, with the tree on PYTHONPATH
CHILD = """
import json, os, runpy, sys
import waveoptics
ns = runpy.run_path(sys.argv[1])
res = ns["brdf_eval_rates"]() if sys.argv[2] == "eval" else ns["simulate_times"](repeat=1)
print("RESULT " + json.dumps({"tree": waveoptics.__file__, "load": os.getloadavg()[0], "result": res}))
"""

#: (key, label, unit, how to read it from a child's results, bound, "max" or "min": the bound is on this tree's
#: value over 08faf07's ("max", a slowdown) or on this tree's value alone ("min"))
MEASURES = (
    ("pointwise", "pointwise TwoScaleBRDF.eval, own ω_i per pair", "evaluations/s",
     lambda r: _row(r["eval"], "quadrature")["own_wi_per_s"], 2.0, "slowdown"),
    ("tabulated", "TabulatedTwoScaleBRDF.eval (128²), own ω_i per pair", "evaluations/s",
     lambda r: _row(r["eval"], "tabulated")["own_wi_per_s"], 1e6, "floor"),
    ("microfacet", "MicrofacetBRDF.eval, own ω_i per pair (no bound; its code changed since 08faf07 too)",
     "evaluations/s", lambda r: _row(r["eval"], "microfacet")["own_wi_per_s"], None, "slowdown"),
    ("simulate_first_cpu", "simulate() default, first call of a fresh process, CPU", "s",
     lambda r: r["simulate"]["first"]["cpu_s"], 1.5, "time"),
    ("simulate_first_wall", "simulate() default, first call of a fresh process, wall", "s",
     lambda r: r["simulate"]["first"]["wall_s"], 1.5, "time"),
    ("simulate_warm_cpu", "simulate() default, second call in the same process, CPU", "s",
     lambda r: r["simulate"]["default"]["cpu_s"], 1.5, "time"),
    ("simulate_warm_wall", "simulate() default, second call in the same process, wall", "s",
     lambda r: r["simulate"]["default"]["wall_s"], 1.5, "time"),
    ("no_spheres_warm_cpu", "simulate --no-spheres (lobe at the light only), warm, CPU", "s",
     lambda r: r["simulate"]["no_spheres"]["cpu_s"], None, "time"),
    ("no_spheres_warm_wall", "simulate --no-spheres (lobe at the light only), warm, wall", "s",
     lambda r: r["simulate"]["no_spheres"]["wall_s"], None, "time"),
)


def _row(res: dict, word: str) -> dict:
    return next(r for r in res["rows"] if word in r["model"])


def child(tree: Path, what: str, cache: Path) -> dict:
    """One fresh process with *tree* first on PYTHONPATH running the measure *what* ('eval' or 'simulate')."""
    env = dict(os.environ, PYTHONPATH=str(tree), WAVEOPTICS_WORKERS="1", WAVEOPTICS_CACHE_DIR=str(cache))
    with tempfile.TemporaryDirectory() as cwd:   # not the repository root: '' on sys.path would shadow PYTHONPATH
        p = subprocess.run([sys.executable, "-c", CHILD, str(MODEL_SPEED), what], env=env, cwd=cwd,
                           capture_output=True, text=True, check=False)
    line = next((ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")), None)
    if p.returncode or line is None:
        return {"error": (p.stderr.strip().splitlines() or ["no output"])[-1][:300]}
    out = json.loads(line[len("RESULT "):])
    if not out["tree"].startswith(str(tree)):
        return {"error": f"imported {out['tree']}, not the tree {tree}"}
    return out


def best(values: list, kind: str):
    """The best of the repeats: the highest rate, the lowest time; None when no run gave one."""
    vals = [v for v in values if v is not None]
    return None if not vals else (max(vals) if kind in ("slowdown", "floor") else min(vals))


def _value(fn, run: dict):
    try:
        return float(fn(run))
    except (KeyError, StopIteration, TypeError):
        return None


def summarize(runs: dict, names: dict) -> list[dict]:
    """One row per measure: the best value per tree, the ratio (this tree's cost over 08faf07's: time ratio, or
    rate of 08faf07 over this tree's) and whether the issue's bound holds."""
    rows = []
    for key, label, unit, fn, bound, kind in MEASURES:
        this_runs, old_runs = ([_value(fn, r) for r in runs[t]] for t in ("this", "08faf07"))
        new, old = best(this_runs, kind), best(old_runs, kind)
        if new is None or old is None:
            ratio = None
        else:
            ratio = old / new if kind in ("slowdown", "floor") else new / old
        if bound is None:
            holds = None
        elif kind == "floor":
            holds = new is not None and new >= bound
        else:
            holds = None if ratio is None else ratio <= bound
        rows.append({"key": key, "measure": label, "unit": unit, "this": new, "old": old,
                     "cost_ratio": ratio, "bound": bound, "bound_kind": "at least" if kind == "floor" else "at most ×",
                     "holds": holds, "old_error": names.get(key), "this_runs": this_runs, "old_runs": old_runs})
    return rows


def measure(old: Path, repeats: int, whats=("eval", "simulate")) -> dict:
    """Alternate the trees, *repeats* fresh processes per tree and measure *whats*; every child's result kept."""
    runs = {"this": [], "08faf07": []}
    errors = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(repeats):
            for name, tree in (("this", ROOT), ("08faf07", old)):
                run = {}
                for what in whats:
                    out = child(tree, what, Path(tmp) / f"{name}-{i}-{what}")
                    if "error" in out:
                        errors.setdefault(name, {})[what] = out["error"]
                    else:
                        run[what] = out["result"]
                        run.setdefault("load", []).append(out["load"])
                runs[name].append(run)
                print(f"bench_vs_08faf07: {name} run {i + 1}/{repeats} done", file=sys.stderr)
    return {"runs": runs, "errors": errors}


def merged(new: dict, kept: dict | None, whats) -> dict:
    """*new* runs of the measures *whats* put into the *kept* result's runs (same number of repeats), the kept
    measures' runs and loads staying; each run's ``loads`` lists the load average per measure."""
    if kept is None or kept["repeats"] != new["repeats"]:
        raise SystemExit("bench_vs_08faf07: --what needs kept runs of the same --repeats (run both measures first)")
    out = dict(kept, runs={t: [dict(r) for r in rs] for t, rs in kept["runs"].items()})
    for tree, runs in new["runs"].items():
        for old_run, run in zip(out["runs"][tree], runs):
            old_run.update({w: run[w] for w in whats if w in run})
            old_run.setdefault("loads", {}).update({w: l for w, l in zip(whats, run.get("load", []))})
    out["errors"] = {t: {**kept["errors"].get(t, {}), **new["errors"].get(t, {})}
                     for t in set(kept["errors"]) | set(new["errors"])}
    out["remeasured"] = {"what": list(whats), "load_average_1min_before": new["load_average_1min_before"],
                         "load_average_1min_after": new["load_average_1min_after"], "this_commit": new["this_commit"]}
    return out


def commit_of(tree: Path) -> str | None:
    p = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                       check=False)
    return p.stdout.strip() or None if p.returncode == 0 else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", default="/tmp/audit28/old", help="an unpacked copy of 08faf07")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--write", action="store_true", help="store in docs/data/performance.json and re-render")
    ap.add_argument("--what", nargs="+", choices=("eval", "simulate"), default=["eval", "simulate"],
                    help="measure only these; with --write the others' kept runs stay")
    ap.add_argument("--from-data", action="store_true",
                    help="measure nothing: summarize the runs kept in docs/data/performance.json again")
    args = ap.parse_args(argv)
    import docs_render
    from waveoptics.bench import machine

    if args.from_data:
        out = docs_render.load_data("performance")["vs_08faf07"]
    else:
        load0 = os.getloadavg()[0]
        got = measure(Path(args.old).resolve(), args.repeats, args.what)
        out = {"machine": machine(), "load_average_1min_after": os.getloadavg()[0],
               "load_average_1min_before": load0, "repeats": args.repeats, "workers": 1,
               "this_commit": commit_of(ROOT), "old_commit": "08faf07", "errors": got["errors"], "runs": got["runs"]}
        if len(args.what) < 2:
            out = merged(out, docs_render.load_data("performance").get("vs_08faf07"), args.what)
    old_errors = {key: out["errors"].get("08faf07", {}).get("simulate" if key.startswith(("simulate", "no_"))
                                                               else "eval") for key, *_ in MEASURES}
    out["rows"] = summarize(out["runs"], old_errors)
    for r in out["rows"]:
        print(f"{r['measure']}: this {r['this']}, 08faf07 {r['old']}, cost ratio {r['cost_ratio']}, "
              f"bound {r['bound_kind']} {r['bound']}: {r['holds']}")
    if args.write:
        data = docs_render.load_data("performance")
        data["vs_08faf07"] = out
        docs_render.write_data("performance", data)
        print(f"wrote {docs_render.write('performance').relative_to(ROOT)}")
    else:
        print(json.dumps(out["rows"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
