"""Data of docs/accuracy-cost.md (docs/data/accuracy_cost.json, which also keeps the raw results; prose in
docs/templates/accuracy_cost.md): the accuracy–cost study (waveoptics.study.accuracy_cost) on three representative
surfaces, with its tables, Pareto fronts, recommendations and error-vs-time plots, all from one run of the code."""
from __future__ import annotations

import sys
from pathlib import Path

from waveoptics.study import accuracy_cost as cost

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
IMG = ROOT / "docs" / "img"

#: (key, title, generator spec, material); patches are 128² samples at dx = 95 nm = λ_min/4 (no aliasing at 380 nm)
SURFACES = (
    ("smooth_metal", "Smooth gold with nano-roughness (Gaussian σ = 5 nm, T = 0.5 µm)",
     "gaussian:sigma=5nm,corr_length=0.5um", "Au"),
    ("grating", "Aluminium sinusoidal grating (amplitude 40 nm, period 1.6 µm)",
     "sinusoid:amplitude=40nm,period=1.6um", "Al"),
    ("rough_gaussian", "Rough aluminium (Gaussian σ = 150 nm, T = 1.5 µm, slope α = 0.2)",
     "gaussian:sigma=150nm,corr_length=1.5um", "Al"),
)
SIZE, SAMPLES, INCIDENT = "12.16um", 128, (30.0, 0.0)
DELTA_E = cost.DEFAULT_DELTA_E
#: targets for which the recommendation is reported
TARGETS = (("error_rel_l2", 1e-1), ("error_rel_l2", 1e-2), ("error_rel_l2", 1e-3), ("delta_e2000", 1.0),
           ("error_albedo", 1e-2))



def _recommendation(rows, metric, target) -> dict:
    k = cost.recommend([r if not r.get("same_as_reference") else {} for r in rows], target, metric)
    r = rows[k] if k is not None else None
    return {"metric": metric, "target": target, "setting": None if r is None else {
        "index": k, "solver": r["solver"], "precision": r["precision"], "resolution": r["resolution"],
        "wavelengths": r["wavelengths"], "realizations": r["realizations"], "time_s": r["time_s"],
        "value": r[metric]}}


def surface(key, title, res) -> dict:
    """What the page shows of one surface's study *res*: its reference, its table (as `waveoptics cost` writes it),
    the ensemble errors and the recommendation for each target; *res* itself is kept as the raw result."""
    rows = res["settings"]
    return {"key": key, "title": title, "reference": res["reference"], "table": cost.table(res),
            "ensemble": [[i, r["ensemble_rel_l2"]] for i, r in enumerate(rows) if r.get("ensemble_rel_l2") is not None],
            "recommendations": [_recommendation(rows, m, t) for m, t in TARGETS], "results": res}


def compute(quick: bool = False) -> dict:
    """Run the study on the three surfaces (and draw their error-vs-time plots)."""
    from waveoptics.bench import machine
    from waveoptics.colour.sampling import simulation_wavelengths
    from waveoptics.runtime import get_runtime

    rt = get_runtime()
    out = []
    for key, title, model, mat in SURFACES:
        samples = 32 if quick else SAMPLES
        size = f"{float(SIZE[:-2]) * samples / SAMPLES:.4g}um"
        cfg = cost.model_config(model, size, samples, material=mat, incident=INCIDENT, seed=1, name=title)
        res_ladder = (8, 16, 32) if quick else cost.DEFAULT_RESOLUTIONS
        settings = cost.ladder(resolutions=res_ladder, delta_e=DELTA_E,
                               realizations=(1, 2) if cfg.random else (1,))
        res = cost.study(cfg, settings, target_error=1e-2, runtime=rt, budget_s=60 if quick else 400,
                         reference_solver="direct")
        cost.plot(res, IMG / f"accuracy_cost_{key}.png", title=title)
        out.append(surface(key, title, res))
        print(f"{key}: {res['time_s']:.1f} s", flush=True)
    m = machine(rt)
    return {"surfaces": out, "reference_realizations": cost.REFERENCE_REALIZATIONS,
            "wavelengths_ladder": [[de, simulation_wavelengths("D65", de).size] for de in DELTA_E],
            "wavelengths_reference": [min(DELTA_E) / 2, simulation_wavelengths("D65", min(DELTA_E) / 2).size],
            "machine": {k: m.get(k) for k in ("cpu", "cores", "device", "platform", "load_average_1min")}}


def main(argv=None):
    """``--quick``: a reduced study (32² samples, small ladders)."""
    import docs_render

    args = argv if argv is not None else sys.argv[1:]
    docs_render.write_data("accuracy_cost", compute(quick="--quick" in args))
    print(f"wrote {docs_render.write('accuracy_cost').relative_to(ROOT)}")


if __name__ == "__main__":
    main()
