"""Data of docs/scaling.md (docs/data/scaling.json; prose in docs/templates/scaling.md) and
docs/img/scaling_speedup.png: how to run BRDF tables and sweeps on Dask, the table
layout, and the measured cost and speed-up of 1 vs 2 local workers with a projection to larger clusters. Every
number on the page is measured by this script on the machine that runs it."""
from __future__ import annotations

import math
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from waveoptics import distributed as D
from waveoptics.brdf.tabulated_glass import NODE_TOLERANCE
from waveoptics.request import SimulationRequest

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"

#: the benchmark table: gold with ABC nano-roughness, 18 incident angles x 31 wavelengths on a 128^2 grid
BENCH_CASE = SimulationRequest(material="Au", nano="abc:sigma=10nm,B=2um,C=2.6", micro_alpha=0.1,
                    wavelengths_nm=tuple(np.arange(400.0, 701.0, 10.0)), resolution=128)
THETAS = tuple(float(t) for t in np.arange(0.0, 86.0, 5.0))
BATCH = 8
#: assumed network bandwidth for shipping blocks to the client on a real cluster (1 Gbit/s Ethernet)
BANDWIDTH_B_S = 125e6
PROJECT_N = (1, 2, 4, 8, 16, 32, 64, 128)
CPUS = os.cpu_count()


def _busy_cpu_s() -> float:
    """CPU seconds the whole machine has been busy since boot (all cores, from /proc/stat)."""
    with open("/proc/stat") as fh:
        f = [int(x) for x in fh.readline().split()[1:]]
    user, nice, system, idle, iowait, irq, softirq, steal = (f + [0] * 8)[:8]
    return (user + nice + system + irq + softirq + steal) / os.sysconf("SC_CLK_TCK")


def _own_cpu_s() -> float:
    """CPU seconds of this process and its finished children (the worker processes, once the cluster closed)."""
    import resource

    a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime


def _run(spec, workers, tmp: Path, tag: str) -> dict:
    """One table run; also how many cores other processes kept busy meanwhile (``others_cores``)."""
    out = tmp / f"{tag}.h5"
    busy0, own0, t0 = _busy_cpu_s(), _own_cpu_s(), time.perf_counter()
    r = D.run_table(spec, out, workers=workers, overwrite=True)
    wall = time.perf_counter() - t0
    r["others_cores"] = max(_busy_cpu_s() - busy0 - (_own_cpu_s() - own0), 0.0) / wall
    out.unlink()
    return r


def _measure_bench(tmp: Path) -> dict:
    """Run the benchmark table in-process and on 1 and 2 local workers, interleaved (so that the load of other
    processes on this shared machine hits every configuration alike)."""
    spec = D.TableSpec(BENCH_CASE, THETAS, batch=BATCH)
    res = {None: [], 1: [], 2: []}
    for k, workers in enumerate((None, 1, 2, 2, 1, None, 1, 2)):
        res[workers].append(_run(spec, workers, tmp, f"w{workers}_{k}"))
    return res


def _per_task(case, thetas, *, tasks=3, batch=BATCH, realizations=1) -> dict:
    """Median wall and CPU seconds of a few tasks of *case*, run directly in this process after one warm-up."""
    spec = D.TableSpec(case, thetas, batch=batch, realizations=realizations)
    all_tasks = D.table_tasks(spec)
    D.compute_block(spec, all_tasks[0])  # warm-up: imports, caches, generated surface
    pick = all_tasks[1:1 + tasks]
    walls, cpus = [], []
    for t in pick:
        b = D.compute_block(spec, t)
        walls.append(b["cost_s"])
        cpus.append(b["cpu_s"])
    n_l = len(case.wavelengths())
    return {"spec": spec, "n_tasks": len(all_tasks), "wall": statistics.median(walls), "cpu": statistics.median(cpus),
            "block_bytes": 2 * 4 * min(batch, n_l) * case.resolution ** 2}


_MALLOC_PROBE = """
import os, statistics, numpy as np
from waveoptics import distributed as D
from waveoptics.request import SimulationRequest
spec = D.TableSpec(SimulationRequest(**{case}), {thetas}, batch={batch})
tasks = D.table_tasks(spec)
D.compute_block(spec, tasks[0])
t0 = os.times()
cpu = [D.compute_block(spec, t)["cpu_s"] for t in tasks[1:13]]
t1 = os.times()
print(statistics.median(cpu), (t1.user - t0.user) / 12, (t1.system - t0.system) / 12)
"""


def _malloc_effect() -> dict:
    """CPU seconds per benchmark task in a fresh process with and without Dask's default MALLOC_TRIM_THRESHOLD_
    (median task CPU, user and system time per task); alternating runs, best of 2 each."""
    import subprocess
    import sys

    code = _MALLOC_PROBE.format(case=repr(BENCH_CASE.__dict__), thetas=repr(THETAS), batch=BATCH)
    out = {}
    for _ in range(2):
        for label, extra in (("default", {"MALLOC_TRIM_THRESHOLD_": "65536"}), ("unset", {})):
            env = {k: v for k, v in os.environ.items() if k != "MALLOC_TRIM_THRESHOLD_"}
            env.update(extra, PYTHONPATH=str(ROOT))
            r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            vals = [float(x) for x in r.stdout.split()]
            if label not in out or vals[0] < out[label][0]:
                out[label] = vals
    return out


def _median(runs, key):
    return statistics.median(r["timings_s"][key] for r in runs)


def _summary(bench) -> dict:
    n = bench[None][0]["tasks"]
    s = {"n": n}
    for w, runs in bench.items():
        costs = np.concatenate([r["task_costs_s"] for r in runs])
        cpus = np.concatenate([r["task_cpu_s"] for r in runs])
        s[w] = {"wall": statistics.median(r["wall_s"] for r in runs), "start": _median(runs, "start_s"),
                "compute": _median(runs, "compute_s"), "stop": _median(runs, "stop_s"),
                "assemble": _median(runs, "assemble_s"), "store": _median(runs, "store_s") / n,
                "cost_median": float(np.median(costs)), "cost_max": float(costs.max()),
                "cpu_median": float(np.median(cpus)), "cost_sum": float(costs.sum()) / len(runs),
                "computes": [r["timings_s"]["compute_s"] for r in runs], "walls": [r["wall_s"] for r in runs],
                "others": [r["others_cores"] for r in runs],
                # parallel efficiency on the cores other processes left free: CPU the tasks used / (compute phase x
                # the cores they could have had)
                "eff": [sum(r["task_cpu_s"]) / (r["timings_s"]["compute_s"] * max(min(w or 1, CPUS - o), 1e-3))
                        for r, o in ((r, r["others_cores"]) for r in runs)]}
    # client + Dask overhead per task: the in-process worker runs tasks one after another, so the compute phase
    # minus the tasks' own wall time is what the client, the scheduler and the storage add per task
    s["overhead"] = max(statistics.median((r["timings_s"]["compute_s"] - sum(r["task_costs_s"])) / n
                                          for r in bench[None]), 0.0)
    ratios = [a / b for a in s[1]["computes"] for b in s[2]["computes"]]
    s["speedup"] = (s[1]["compute"] / s[2]["compute"], min(ratios), max(ratios))
    s["speedup_total"] = s[1]["wall"] / s[2]["wall"]
    return s


def project(n_tasks, cost_s, overhead_s, n_workers) -> float:
    """Projected compute-phase seconds on *n_workers* free cores: the slower of the workers' share (whole tasks)
    and the client's serial per-task work (receive + store)."""
    return max(math.ceil(n_tasks / n_workers) * cost_s, n_tasks * overhead_s)


def _figure(s, configs) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    N = np.array(PROJECT_N)
    for label, c, style in configs:
        t1 = project(c["n_tasks"], c["wall"], c["overhead"], 1)
        ax.plot(N, [t1 / project(c["n_tasks"], c["wall"], c["overhead"], k) for k in N], style, label=label)
    sp, lo, hi = s["speedup"]
    ax.errorbar([1, 2], [1.0, sp], yerr=[[0, sp - lo], [0, hi - sp]], fmt="ko", ms=6, capsize=3,
                label="measured, this shared 2-core machine (median, range)")
    ax.plot(N, N, ":", color="grey", lw=1, label="ideal")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log", base=2)
    ax.set_xlabel("workers (one core each)")
    ax.set_ylabel("speed-up of the compute phase")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    ax.set_title("BRDF tables on Dask: measured and projected speed-up", fontsize=10)
    name = "scaling_speedup.png"
    from waveoptics.io.figures import save_figure

    save_figure(fig, IMG / name)
    return name


def _runs(s) -> list:
    """The run table's rows: per configuration (in-process, 1 and 2 workers) the phases' medians and each repeat."""
    keys = ("wall", "start", "computes", "others", "eff", "stop", "assemble", "cost_median", "cost_max", "cpu_median",
            "store")
    return [{"workers": w, **{k: s[w][k] for k in keys}} for w in (None, 1, 2)]


def _projection(configs) -> list:
    """Per worker count of PROJECT_N, each configuration's projected compute phase and its speed-up over one."""
    rows = []
    for k in PROJECT_N:
        cells = []
        for c in configs:
            t = project(c["n_tasks"], c["wall"], c["overhead"], k)
            cells.append([t, project(c["n_tasks"], c["wall"], c["overhead"], 1) / t])
        rows.append({"workers": k, "cells": cells})
    return rows


def _measure() -> tuple:
    """Run every measurement: the memory-trim probe, the interleaved benchmark and the per-task costs of the fine
    and the height-field tables (with the load average before and after)."""
    load0 = os.getloadavg()
    malloc = _malloc_effect()
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        bench = _measure_bench(tmp)
        fine = _per_task(SimulationRequest(**{**BENCH_CASE.__dict__,
                                              "wavelengths_nm": tuple(np.arange(400.0, 701.0, 5.0)),
                                              "resolution": 256}), THETAS)
        hf_case = SimulationRequest(material="Au", nano="gaussian:sigma=20nm,corr_length=1um", micro_alpha=0.05, solver="fft",
                                    wavelengths_nm=BENCH_CASE.wavelengths_nm, resolution=128)
        hfield = _per_task(hf_case, THETAS, realizations=8)
    return [load0[0], os.getloadavg()[0]], malloc, bench, fine, hfield


def compute() -> dict:
    """Every number of docs/scaling.md (minutes of benchmarking) and the speed-up figure."""
    IMG.mkdir(parents=True, exist_ok=True)
    load, malloc, bench, fine, hfield = _measure()
    s = _summary(bench)
    n = s["n"]
    bench_bytes = 2 * 4 * len(THETAS) * len(BENCH_CASE.wavelengths_nm) * BENCH_CASE.resolution ** 2
    block_bytes = 2 * 4 * BATCH * BENCH_CASE.resolution ** 2

    def cfg(label, c, n_tasks, block):
        return {"label": label, "n_tasks": n_tasks, "wall": c, "overhead": s["overhead"] + block / BANDWIDTH_B_S}

    # a task's cost on a free core is its CPU time (its wall time here includes waiting for a shared core)
    configs = [
        cfg(f"benchmark: 18 angles × 31 λ × 128², PSD ({n} tasks)", s[None]["cpu_median"], n, block_bytes),
        cfg(f"fine: 18 angles × 61 λ × 256², PSD ({fine['n_tasks']} tasks)", fine["cpu"], fine["n_tasks"],
            fine["block_bytes"]),
        cfg(f"height fields: 18 angles × 31 λ × 128² × 8 realizations, fft ({hfield['n_tasks']} tasks)",
            hfield["cpu"], hfield["n_tasks"], hfield["block_bytes"]),
    ]
    _figure(s, [(c["label"], c, st) for c, st in zip(configs, ("-", "--", "-."))])
    eff = [statistics.median(s[1]["eff"]), statistics.median(s[2]["eff"])]
    return {"layout": [[k, v] for k, v in D.TABLE_LAYOUT.items()],
            "glass_layout": [[k, v] for k, v in D.GLASS_TABLE_LAYOUT.items()],
            "glass_tolerance": NODE_TOLERANCE, "sweep_columns": list(D.SWEEP_COLUMNS),
            "vary": list(D.VARY), "cpus": os.cpu_count(), "load": load,
            "case": {"angles": len(THETAS), "wavelengths": len(BENCH_CASE.wavelengths_nm),
                     "resolution": BENCH_CASE.resolution, "batch": BATCH, "tasks": n, "mb": bench_bytes / 1e6},
            "runs": _runs(s), "overhead_s": s["overhead"], "speedup": s["speedup"], "speedup_total": s["speedup_total"],
            "others_mean_2": statistics.mean(s[2]["others"]), "eff_median": eff,
            "eff_waste": max(0.0, 1 - eff[1] / eff[0]), "eff_predicted_2": 2 * eff[1] / eff[0], "malloc": malloc,
            "configs": [{"label": c["label"], "cost_s": c["wall"]} for c in configs],
            "bandwidth_gbit": BANDWIDTH_B_S * 8 / 1e9, "block_mb": block_bytes / 1e6,
            "cluster_overhead_s": s["overhead"] + block_bytes / BANDWIDTH_B_S,
            "projection": _projection(configs), "limits": [c["wall"] / c["overhead"] for c in configs]}


def main():
    import make_docs

    make_docs.main(["scaling"])


if __name__ == "__main__":
    main()
