"""The models' own speed: BRDF ``eval()`` rates and the time of a default ``simulate``, each against the obvious
alternative in the same run.

Written against the package's public names only (absolute imports, nothing private), so that
``scripts/bench_vs_08faf07.py`` runs this very file on an older tree of the package (issue 28's "today",
commit 08faf07) and on this one, and compares like with like.

References
----------
.. [1] docs/physics.md §7 (the two-scale BRDF whose cost is measured); docs/performance.md (the tables).
"""
from __future__ import annotations

import time

import numpy as np

try:
    from waveoptics.bench.common import best_time
except ImportError:   # 08faf07's bench was one module, waveoptics/bench.py, with the same timer
    from waveoptics.bench import best_time

__all__ = ['brdf_eval_rates', 'SIMULATE_QUICK', 'SIMULATE_UNITS', 'simulate_times']

#: the fields of the small ``simulate`` that ``bench --quick`` times in place of the default (16² cells, 1 wavelength)
SIMULATE_QUICK = {"resolution": 16, "wavelengths": (550.0,)}

#: units of :func:`simulate_times`'s numbers
SIMULATE_UNITS = {"wall_s": "s, wall clock", "cpu_s": "s, CPU time of this process (all its threads)",
                  "parts_s": "s, simulate's own timings_s (setup, lobe at the light, sphere table; wall clock)",
                  "no_spheres_vs_default": "1, warm wall time of --no-spheres over the default's"}


def brdf_eval_rates(n: int = 100_000, loop: int = 300, resolution: int = 128, min_time: float = 1.0) -> dict:
    """Evaluations per second of ``eval()`` (:mod:`waveoptics.brdf.protocol`) for the microfacet model and the
    two-scale PSD model (gold, micro GGX α = 0.1, the default nano statistics, 550 nm) by quadrature and from its
    tabulated diffracted lobes, batched against a plain Python loop calling it one (ω_i, ω_o, λ) at a time; with one
    shared ω_i and with every pair its own ω_i (as a renderer asks); ``vs_microfacet``: the own-ω_i rate relative to
    the microfacet model's in the same run. *resolution*: the tabulated lobes' grid (its build dominates the
    measure's own cost; a look-up's cost barely depends on it). *min_time* (s): each batch is repeated until this
    much time has passed (at most 50 times) and the best kept: a batch of the fast models takes ~0.1 s, which a
    loaded machine's scheduler can double."""
    from waveoptics import brdf
    from waveoptics.request import DEFAULT_NANO, make_nano

    rng = np.random.default_rng(7)

    def dirs(k):
        d = rng.normal(size=(k, 3))
        d[:, 2] = np.abs(d[:, 2])
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    micro = brdf.Micro(alpha=0.1, ndf="ggx")   # the NDF the recorded baselines were timed with
    nano = make_nano(DEFAULT_NANO, [550.0])
    models = {"microfacet": brdf.MicrofacetBRDF("gold", micro),
              "twoscale (PSD, quadrature)": brdf.TwoScaleBRDF("gold", micro, nano=nano),
              f"twoscale (PSD, tabulated {resolution}²)": brdf.TabulatedTwoScaleBRDF(
                  "gold", micro, nano=nano, wavelengths_nm=(550.0,), resolution=resolution)}
    wo = dirs(n)
    wi_one = np.array([0.5, 0.0, np.sqrt(0.75)])
    wi_many = dirs(n)
    rows = []
    for name, b in models.items():
        m = n // 10 if "quadrature" in name else n
        b.eval(wi_one, wo[:16], 550.0)  # build tables once
        t_one = best_time(lambda: b.eval(wi_one, wo[:m], 550.0), repeat=2, min_time=min_time)
        t_many = best_time(lambda: b.eval(wi_many[:m], wo[:m], 550.0), repeat=2, min_time=min_time)
        t_loop = best_time(lambda: [b.eval(wi_many[j], wo[j], 550.0) for j in range(loop)], repeat=1)
        rows.append({"model": name, "pairs": m, "shared_wi_per_s": m / t_one, "own_wi_per_s": m / t_many,
                     "loop_per_s": loop / t_loop, "batch_vs_loop": (m / t_many) / (loop / t_loop)})
    for r in rows:   # the cost of the two-scale models relative to the plain microfacet BRDF, in the same run
        r["vs_microfacet"] = r["own_wi_per_s"] / rows[0]["own_wi_per_s"]
    return {"rows": rows}


def _timed_simulate(sphere: bool, fields: dict) -> dict:
    """Wall and CPU time (s) of one ``waveoptics.simulate.simulate(sphere=sphere, **fields)`` and its own
    breakdown ``timings_s`` (setup, lobe at the light, sphere table)."""
    from waveoptics.simulate import simulate

    t0, c0 = time.perf_counter(), time.process_time()
    sim = simulate(sphere=sphere, **fields)
    out = {"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    out["parts_s"] = {k: float(v) for k, v in (getattr(sim, "timings_s", None) or {}).items()}
    return out


def simulate_times(quick: bool = False, repeat: int = 2) -> dict:
    """Time (s, wall and CPU of this process) of ``simulate()`` with every field at its default, against the same
    request without the sphere renders' table (``simulate --no-spheres``: the two-scale and microfacet lobes at the
    light only), in one process.

    The default's first call is reported apart (``first``): it also pays the process's one-off costs (OpenCL kernel
    builds, lazy imports, per-process caches), which a fresh ``waveoptics simulate`` pays every time. Then each
    variant runs *repeat* more times and keeps its best (``warm``, the cost of the computation itself);
    ``no_spheres_vs_default``: warm wall time of --no-spheres over the default's, so 1 − it is the share of the
    sphere table, the part issue 28's facet-frame tables changed most. *quick*: :data:`SIMULATE_QUICK` fields (a
    smoke test of the measure, not the default).
    """
    fields = dict(SIMULATE_QUICK) if quick else {}
    out = {"fields": {k: list(v) if isinstance(v, tuple) else v for k, v in fields.items()}, "repeat": repeat,
           "units": SIMULATE_UNITS, "first": _timed_simulate(True, fields)}
    for name, sphere in (("default", True), ("no_spheres", False)):
        runs = [_timed_simulate(sphere, fields) for _ in range(repeat)]
        out[name] = min(runs, key=lambda r: r["wall_s"])
    out["no_spheres_vs_default"] = out["no_spheres"]["wall_s"] / out["default"]["wall_s"]
    return out
