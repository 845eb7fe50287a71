"""Data of docs/cost-defaults.md (docs/data/cost_defaults.json; prose in docs/templates/cost_defaults.md):
`waveoptics cost` with its defaults (fft reference, ladder budget) against the full study (direct-sum reference,
every rung), both run here as a user runs them, with their times and recommendations side by side."""
from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

RUNS = (("defaults", []), ("full study", ["--reference", "direct", "--budget", "none"]))


def _run(extra):
    t = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "waveoptics", "cost", "--json", *extra], check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out), time.perf_counter() - t


def _summary(name, extra, data, wall) -> dict:
    ref = data["reference"]
    rec = data["recommendation"] or {}
    return {"name": name, "command": " ".join(["waveoptics", "cost", *extra]), "wall_s": wall,
            "reference": {"solver": ref["solver"], "precision": ref["precision"], "time_s": ref["time_s"]},
            "rungs_run": sum(1 for r in data["settings"] if not r["skipped"]),
            "rungs_skipped": sum(1 for r in data["settings"] if r["skipped"]),
            "recommended": rec.get("setting"), "recommended_words": rec.get("in_words", rec.get("reason", ""))}


def compute() -> dict:
    """Run both commands; keep what the page shows of each, and how far their errors agree."""
    from waveoptics.bench import machine
    from waveoptics.study.accuracy_cost import DEFAULT_BUDGET_S, DEFAULT_TARGET_ERROR

    res = [(name, extra, *_run(extra)) for name, extra in RUNS]
    (_, _, d, _), (_, _, f, _) = res
    common = [i for i, (a, b) in enumerate(zip(d["settings"], f["settings"])) if not a["skipped"] and not b["skipped"]
              and a["error_rel_l2"] is not None and b["error_rel_l2"] is not None and not a["same_as_reference"]
              and not b["same_as_reference"]]
    diffs = [abs(d["settings"][i]["error_rel_l2"] - f["settings"][i]["error_rel_l2"]) for i in common]
    m = machine()
    return {"budget_s": DEFAULT_BUDGET_S, "target_error": DEFAULT_TARGET_ERROR,
            "runs": [_summary(*r) for r in res],
            "same_recommendation": (d["recommendation"] or {}).get("setting")
            == (f["recommendation"] or {}).get("setting"),
            "common_rungs": len(common), "max_error_difference": max(diffs),
            "machine": {"cpu": m["cpu"], "cores": m["cores"]}}


def main() -> None:
    import make_docs

    make_docs.main(["cost_defaults"])


if __name__ == "__main__":
    main()
