"""Data of docs/performance.md (docs/data/performance.json; prose in docs/templates/performance.md) from the
benchmark's own output (``waveoptics.bench.run_all``): the raw results, the tables of ``waveoptics bench``, the
numbers the conclusions quote (FFT choice, speed-ups), and the scaling figure. The entry ``vs_08faf07`` (this tree
against issue 28's "today") is written by ``scripts/bench_vs_08faf07.py --write`` and kept here."""
from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from waveoptics import bench

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
IMG = ROOT / "docs" / "img" / "performance_scaling.png"

def figure(res):
    s = res["direct_scaling"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), constrained_layout=True)
    for ax, key, xk, xl in ((axes[0], "by_samples", "samples", "samples (directions fixed)"),
                            (axes[1], "by_directions", "directions", "directions (samples fixed)")):
        rows = s[key]
        x = [r[xk] for r in rows]
        for col, lab, mk in (("opencl_float32_s", "kernel float32", "o-"), ("opencl_float64_s", "kernel float64", "s-"),
                             ("naive_float32_s", "naive native_sin float32", "^--"), ("numpy_s", "NumPy direct sum", "x:")):
            pts = [(xi, r[col]) for xi, r in zip(x, rows) if r.get(col)]
            if pts:
                ax.loglog(*zip(*pts), mk, label=lab)
        ax.set_xlabel(xl)
        ax.set_ylabel("time (s)")
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8)
    fig.suptitle("Direct Kirchhoff sum: time against samples and directions (log-log)", fontsize=10)
    from waveoptics.io.figures import save_figure

    save_figure(fig, IMG)


def _gps(r) -> float:
    return r["terms_per_s"] / 1e9


def _direct(res) -> dict:
    """The direct kernel against the naive kernel, NumPy, the previous kernel and fast-math."""
    d = {r["name"]: r for r in res["direct"]["rows"]}
    k32, k64, naive = d["opencl kirchhoff_U float32"], d.get("opencl kirchhoff_U float64"), d[bench.NAIVE]
    old32 = d.get("opencl kirchhoff_U_sinpi float32 (previous kernel, SLEEF sinpi)")
    old64 = d.get("opencl kirchhoff_U_sinpi float64 (previous kernel, SLEEF sinpi)")
    fm = d.get("opencl kirchhoff_U float32 fast-math")
    out = {"kernel": {"gterms_per_s": _gps(k32), "vs_naive": k32["vs_naive"], "vs_numpy": k32["vs_numpy"],
                      "error": k32["error"]},
           "naive_gterms_per_s": _gps(naive), "numpy_gterms_per_s": _gps(d["numpy direct sum (complex128)"]),
           "before_after": None, "fast_math": None}
    if old32:
        out["before_after"] = {"float32": [_gps(old32), _gps(k32), k32["terms_per_s"] / old32["terms_per_s"]],
                               "float64": [_gps(old64), _gps(k64), k64["terms_per_s"] / old64["terms_per_s"]]
                               if old64 and k64 else None}
    if fm:
        out["fast_math"] = {"gterms_per_s": _gps(fm), "vs_default": fm["terms_per_s"] / k32["terms_per_s"],
                            "error": fm["error"]}
    return out


def _scaling(res) -> dict:
    sc = res["direct_scaling"]["by_samples"] + res["direct_scaling"]["by_directions"]
    ends = {"smallest": min(sc, key=lambda r: r["terms"]), "largest": max(sc, key=lambda r: r["terms"])}
    return {k: {"terms": r["terms"], "time_s": r["opencl_float32_s"],
                "gterms_per_s": r["terms"] / r["opencl_float32_s"] / 1e9} for k, r in ends.items()}


def _fft(res) -> dict:
    """Fastest raw 2-D FFT backend per size, and what the fft solver gains from each backend."""
    f = res["fft_backends"]
    names = [k for k in f["rows"][0] if k not in ("n", "points")]
    wins = {}
    for r in f["rows"]:
        wins.setdefault(max(names, key=lambda k: r.get(k) or 0), []).append(r["n"])
    solver = []
    for r in f.get("solver") or []:
        keys = [k for k in r if k not in ("n", "transforms")]
        best = min(keys, key=lambda k: r[k])
        solver.append({"n": r["n"], "best": best, "vs_scipy": r["scipy.fft"] / r[best]})
    return {"fastest": [{"backend": k, "sizes": v} for k, v in wins.items()],
            "missing": [{"backend": k, "why": v} for k, v in f["missing"].items()], "solver": solver}


def summarize(res) -> dict:
    """The numbers the page's conclusions quote, derived from the benchmark's results *res*."""
    p = res["fft_pipeline"]["rows"][-1]
    out = {"direct": _direct(res), "scaling": _scaling(res), "fft": _fft(res), "large_patch": None,
           "pipeline": {"n": p["n"], **{k: {"time_s": p[name]["time_s"], "error": p[name]["error"]} for k, name in
                        (("order0", "fft solver order 0"), ("auto", "fft solver order auto"),
                         ("numpy", "numpy fft2 + interpolation"))}},
           "brdf_eval": None, "fft_threads": None, "simulate": None}
    lp = res["direct"].get("large_patch_errors")
    if lp:
        out["large_patch"] = {"length_wavelengths": lp["length_wavelengths"], "naive": lp[bench.NAIVE],
                              "kernel": lp["opencl kirchhoff_U float32"]}
    if "brdf_eval" in res:
        out["brdf_eval"] = [{"model": r["model"], "per_s": r["own_wi_per_s"], "vs_loop": r["batch_vs_loop"]}
                            for r in res["brdf_eval"]["rows"]]
    if "fft_threads" in res:
        ft = res["fft_threads"]
        out["fft_threads"] = {"cores": ft["cores"], "wavelengths": ft["wavelengths"],
                              "speedup": ft["rows"][-1]["speedup"], "wall_s": [ft["rows"][0]["wall_s"],
                                                                               ft["rows"][-1]["wall_s"]]}
    if "simulate" in res:
        sm = res["simulate"]
        out["simulate"] = {"first_s": sm["first"]["wall_s"], "warm_s": sm["default"]["wall_s"],
                           "no_spheres_s": sm["no_spheres"]["wall_s"], "no_spheres_vs_default": sm["no_spheres_vs_default"]}
    return out


def kept_comparison():
    """The comparison with 08faf07 that ``scripts/bench_vs_08faf07.py --write`` stored in docs/data/performance.json
    (None if none): a recompute of the rest keeps it."""
    import docs_render

    path = docs_render.data_path("performance")
    return docs_render.load_data("performance").get("vs_08faf07") if path.exists() else None


def data(res) -> dict:
    """Page data from benchmark results: the raw results (for the figure), the tables as `waveoptics bench` prints
    them, and the conclusions' numbers."""
    return {"results": res, "tables": bench.report(res), "conclusions": summarize(res)}


def compute(quick: bool = False) -> dict:
    """Run the benchmark (``waveoptics.bench.run_all``) and draw the scaling figure."""
    from waveoptics.runtime import get_runtime

    res = bench.run_all(get_runtime(), quick=quick)
    figure(res)
    out = data(res)
    kept = kept_comparison()
    if kept is not None:
        out["vs_08faf07"] = kept
    return out


def main(argv=None):
    """``--quick``: the reduced benchmark; ``--from-data``: redraw the figure and rewrite the page from the kept
    results, measuring nothing."""
    import docs_render

    args = argv if argv is not None else sys.argv[1:]
    if "--from-data" in args:   # the tables stay as measured: bench.report follows the results' key order,
        out = docs_render.load_data("performance")   # which the sorted JSON does not keep
        figure(out["results"])
        out["conclusions"] = summarize(out["results"])
    else:
        out = compute(quick="--quick" in args)
    docs_render.write_data("performance", out)
    print(f"wrote {docs_render.write('performance').relative_to(ROOT)}, {IMG.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
