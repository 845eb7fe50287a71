"""The benchmark results as Markdown tables: the text of ``waveoptics bench`` and of docs/performance.md.
"""
from __future__ import annotations

from .measures import MATH_FUNCTIONS

__all__ = ['report', 'simulate_table', 'REPORT_FILES', 'write_report']


def _g(v, fmt=".3g"):
    return "—" if v is None else format(v, fmt)


def report(res: dict) -> str:
    """The benchmark results as Markdown tables (the text of ``waveoptics bench`` and docs/performance.md)."""
    m = res["machine"]
    lines = [f"Machine: {m['cpu']}, {m['cores']} cores; OpenCL device {m.get('device')} ({m.get('platform')}); "
             f"1-min load average {m.get('load_average_1min', float('nan')):.2f} before, "
             f"{_g(m.get('load_average_1min_after'), '.2f')} after.", ""]
    d = res["direct"]
    lines += [f"### Direct Kirchhoff sum: {d['samples']} samples × {d['directions']} directions "
              f"(NumPy rows: {d['numpy_directions']} directions)", "",
              "| implementation | time (s) | G terms/s | × naive kernel | × NumPy direct sum | max error / Σw |",
              "|---|---|---|---|---|---|"]
    for r in d["rows"]:
        lines.append(f"| {r['name']} | {r['time_s']:.3g} | {r['terms_per_s'] / 1e9:.3g} | {r['vs_naive']:.3g} "
                     f"| {r['vs_numpy']:.3g} | {r['error']:.2e} |")
    s = res["direct_scaling"]
    for key, title in (("by_samples", "samples (directions fixed)"), ("by_directions", "directions (samples fixed)")):
        lines += ["", f"### Direct sum: time (s) against {title}", "",
                  "| samples | directions | terms | kernel float32 | kernel float64 | naive float32 | NumPy "
                  "| G terms/s float32 |", "|---|---|---|---|---|---|---|---|"]
        for r in s[key]:
            lines.append(f"| {r['samples']} | {r['directions']} | {r['terms']:.3g} | {_g(r['opencl_float32_s'])} "
                         f"| {_g(r['opencl_float64_s'])} | {_g(r['naive_float32_s'])} | {_g(r['numpy_s'])} "
                         f"| {r['terms'] / r['opencl_float32_s'] / 1e9:.3g} |")
    f = res["fft_backends"]
    names = [k for k in f["rows"][0] if k not in ("n", "points")]
    lines += ["", "### 2-D complex FFT: M points/s", "", "| n × n | " + " | ".join(names) + " |",
              "|---|" + "---|" * len(names)]
    for r in f["rows"]:
        lines.append(f"| {r['n']} | " + " | ".join(_g(r.get(k) and r[k] / 1e6) for k in names) + " |")
    for k, why in f["missing"].items():
        lines.append(f"\n{k}: {why}")
    sb = f.get("solver") or []
    if sb:
        names = [k for k in sb[0] if k not in ("n", "transforms")]
        lines += ["", "### fft solver (order auto, n × n patch onto an n × n grid): time (s) per FFT backend", "",
                  "| n | 2-D chirp-z transforms | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
        for r in sb:
            lines.append(f"| {r['n']} | {r['transforms']} | " + " | ".join(_g(r[k]) for k in names) + " |")
    p = res["fft_pipeline"]
    keys = ["fft solver order 0", "fft solver order auto", "numpy fft2 + interpolation"]
    lines += ["", "### fft solver vs a NumPy FFT pipeline (n × n patch onto an n × n direction grid)", "",
              "| n | " + " | ".join(f"{k}: time (s) | error" for k in keys) + " |", "|---|" + "---|---|" * len(keys)]
    for r in p["rows"]:
        lines.append(f"| {r['n']} | " + " | ".join(f"{r[k]['time_s']:.3g} | {r[k]['error']:.1e}" for k in keys)
                     + " |")
    if "brdf_eval" in res:
        lines += ["", "### BRDF eval(): (ω_i, ω_o, λ) evaluations per second (NumPy, one process)", "",
                  "| model | pairs | batch, one ω_i | batch, own ω_i per pair | Python loop | batch ÷ loop "
                  "| own ω_i ÷ microfacet |",
                  "|---|---|---|---|---|---|---|"]
        for r in res["brdf_eval"]["rows"]:
            vs = r.get("vs_microfacet")
            lines.append(f"| {r['model']} | {r['pairs']} | {r['shared_wi_per_s']:.3g} | {r['own_wi_per_s']:.3g} "
                         f"| {r['loop_per_s']:.3g} | {r['batch_vs_loop']:.3g} | "
                         f"{'' if vs is None else format(vs, '.3g')} |")
    if "fft_threads" in res:
        ft = res["fft_threads"]
        lines += ["", f"### fft solver on 1 and {ft['cores']} cores ({ft['n']}² patch and grid, "
                  f"{ft['wavelengths']} wavelengths in parallel threads)", "",
                  "| threads | wall (s) | CPU (s) | speed-up |", "|---|---|---|---|"]
        for r in ft["rows"]:
            lines.append(f"| {r['threads']} | {r['wall_s']:.3g} | {r['cpu_s']:.3g} | {r['speedup']:.3g} |")
    if "footprints" in res:
        fe = res["footprints"]
        lines += ["", f"### One footprint at {fe['spacing_um']:.3g} µm spacing: the direct sum (NumPy twin, OpenCL) "
                  f"against Yan et al. 2018's Gabor kernels (σ_k = {fe['kernel_sigma']:g} Δ), λ = "
                  f"{fe['wavelength_nm']:g} nm; errors of energy / peak against an exact float64 sum over ±5σ", "",
                  "| σ (µm) | samples | pairs | NumPy (ms/pair) | OpenCL (ms/pair) | Gabor (ms/pair) | Gabor ÷ NumPy "
                  "| Gabor ÷ OpenCL | NumPy error | OpenCL error | Gabor error | Gabor ÷ NumPy peak error |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in fe["rows"]:
            err = {k: f"{r[k + '_energy_error']:.1e} / {r[k + '_peak_error']:.1e}" for k in ("numpy", "opencl", "gabor")}
            lines.append(f"| {r['sigma_um']:g} | {r['samples']} | {r['pairs']} | {r['numpy_s_per_pair'] * 1e3:.3g} "
                         f"| {r['opencl_s_per_pair'] * 1e3:.3g} ({r['opencl_precision']}) "
                         f"| {r['gabor_s_per_pair'] * 1e3:.3g} | {r['gabor_vs_numpy_time']:.3g} "
                         f"| {r['gabor_vs_opencl_time']:.3g} | {err['numpy']} | {err['opencl']} | {err['gabor']} "
                         f"| {r['gabor_vs_numpy_peak_error']:.3g} |")
    if "simulate" in res:
        lines += ["", *simulate_table(res["simulate"])]
    me = res["math_errors"]
    lines += ["", "### Math built-ins: largest absolute error against float64 NumPy", "",
              "| function | " + " | ".join(f"{p} {lab}" for p in me for lab in next(iter(me[p].values()))) + " |",
              "|---|" + "---|" * sum(len(next(iter(me[p].values()))) for p in me)]
    for name in MATH_FUNCTIONS:
        cells = []
        for p in me:
            for lab in next(iter(me[p].values())):
                cells.append(_g(me[p].get(name, {}).get(lab), ".2e"))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def simulate_table(sim: dict) -> list[str]:
    """The lines of the ``simulate()`` table (:func:`waveoptics.bench.simulate_times`'s result *sim*)."""
    fields = ", ".join(f"{k}={v}" for k, v in sim["fields"].items()) or "every field at its default"
    lines = [f"### simulate() ({fields}) against --no-spheres, one process: time (s)", "",
             "| run | wall (s) | CPU (s) | setup (s) | lobe at the light (s) | sphere table (s) |",
             "|---|---|---|---|---|---|"]
    for key, label in (("first", "default, first call of the process"), ("default", "default, warm"),
                       ("no_spheres", "--no-spheres, warm")):
        r = sim[key]
        parts = r.get("parts_s", {})
        lines.append(f"| {label} | {r['wall_s']:.3g} | {r['cpu_s']:.3g} | {_g(parts.get('setup'))} "
                     f"| {_g(parts.get('lobe'))} | {_g(parts.get('sphere_table'))} |")
    lines += ["", f"--no-spheres ÷ default (warm wall time): {sim['no_spheres_vs_default']:.3g}"]
    return lines


#: files of ``bench -o DIR``
REPORT_FILES = ("bench.json", "bench.md")


def write_report(directory, res: dict, text: str, *, overwrite: bool = False) -> None:
    """Write the benchmark results *res* as bench.json and their :func:`report` *text* as bench.md into
    *directory* (each file whole: :func:`waveoptics.io.files.atomic_path`)."""
    from pathlib import Path

    from ..io.files import atomic_path, write_json

    out = Path(directory)
    write_json(out / "bench.json", res, overwrite=overwrite)
    with atomic_path(out / "bench.md", overwrite=overwrite) as tmp:
        tmp.write_text(text + "\n")
