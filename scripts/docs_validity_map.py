"""Data of docs/validity-map.md (docs/data/validity_map.json; prose in docs/templates/validity_map.md): where the
project's 1-D Kirchhoff and first-order perturbation (Rayleigh-Rice) models hold against the rigorous mean of the
method of moments (waveoptics.scatter.mom) on Gaussian surfaces, over kσ, kℓ, the incidence, s and p, a perfect
conductor, aluminium and glass; with the convergence of the reference itself. Every number is computed by this script.

    PYTHONPATH=. python scripts/docs_validity_map.py            # the full map (2 processes)
    PYTHONPATH=. python scripts/docs_validity_map.py --quick    # a reduced map (< 1 min), as the tests run it
    ... --out DIR                                                # write both files into DIR instead
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from multiprocessing import Pool
from pathlib import Path

for _v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")   # one thread per process: threaded BLAS on small dense solves is slower here

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from waveoptics.materials import get_material  # noqa: E402
from waveoptics.scatter.models1d import kirchhoff_1d, spm1_1d  # noqa: E402
from waveoptics.scatter.mom import (MomRequest, gaussian_profile, mom_scatter, solve_profile,  # noqa: E402
                                    thorsos_beam)

K = 2 * math.pi
LAM_NM = 550.0
MEDIA = {"conductor": None, "aluminium": complex(get_material("Al").eta(LAM_NM)), "glass": 1.5}
MODELS = {"kirchhoff": kirchhoff_1d, "spm1": spm1_1d}
BIN_DEG = 5.0
FULL = dict(k_sigma=(0.1, 0.3, 1.0), k_ell=(2.0, 4.0, 8.0, 16.0), theta=(0.0, 40.0, 70.0), media=tuple(MEDIA),
            pols=("s", "p"), length=40.0, beam=10.0, realizations=64)
QUICK = dict(k_sigma=(0.1, 0.6), k_ell=(3.0,), theta=(0.0, 40.0), media=("conductor", "glass"), pols=("s",),
             length=24.0, beam=6.0, realizations=3)
THETA_GRAZING = 85.0


def _ppw(k_sigma, k_ell):
    """Nodes per wavelength: 10, more on steep surfaces so that the arc between nodes stays near λ/10."""
    slope = math.sqrt(2) * k_sigma / k_ell
    return 10.0 * math.sqrt(1 + (2 * slope) ** 2)


def _bins(scatter_deg):
    edges = np.arange(-90.0, 90.0 + BIN_DEG, BIN_DEG)
    return [(scatter_deg >= lo) & (scatter_deg < hi) for lo, hi in zip(edges[:-1], edges[1:])]


def _binned(values, bins):
    return np.array([np.mean(values[..., b], axis=-1) for b in bins]).T


def run_config(args):
    """One (kσ, kℓ, medium, polarization): the MoM mean and each model's errors at every incidence."""
    ks, kl, medium, pol, p = args
    n = MEDIA[medium]
    req = MomRequest(ks / K, kl / K, p["theta"], pol, n, p["length"], p["beam"], _ppw(ks, kl),
                     p["realizations"], seed=int(1000 * ks + 10 * kl), scatter_deg=tuple(np.arange(-89.5, 90, 1.0)))
    res = mom_scatter(req)
    bins = _bins(res.scatter_deg)
    rows = []
    for i, th in enumerate(res.theta_deg):
        samples = _binned(res.sigma_incoherent_samples[:, i, :], bins)          # (M, bins)
        mom_b = samples.mean(axis=0)
        noise = np.std(samples, axis=0, ddof=1) / math.sqrt(samples.shape[0])
        norm = math.sqrt(np.sum(mom_b ** 2))
        row = dict(k_sigma=ks, k_ell=kl, medium=medium, refractive_index=None if n is None else [n.real, n.imag]
                   if isinstance(n, complex) else [float(n), 0.0], polarization=pol, theta_deg=float(th),
                   mom_albedo=float(res.albedo[i]), mom_albedo_se=float(res.albedo_se[i]),
                   mom_incoherent_albedo=float(res.albedo_incoherent[i]),
                   noise_floor=float(math.sqrt(np.sum(noise ** 2)) / norm),
                   seconds_per_realization=res.seconds_per_realization, n_unknowns=res.n_unknowns,
                   realizations=p["realizations"], taper_parameter=float(res.taper_parameter[i]))
        for name, model in MODELS.items():
            sig, coh = model(th, res.scatter_deg, ks, kl, pol, n)
            fine = np.radians(np.linspace(-89.99, 89.99, 4001))
            inc = np.trapezoid(model(th, np.degrees(fine), ks, kl, pol, n)[0], fine)
            row[f"{name}_l2"] = float(math.sqrt(np.sum((_binned(sig, bins) - mom_b) ** 2)) / norm)
            row[f"{name}_albedo_error"] = float(coh + inc - res.albedo[i])
        rows.append(row)
    return rows


def _series_surface(length, k_sigma, k_ell, seed, ppw_master=40.0):
    """One Gaussian surface as a Fourier series on [−L/2, L/2), to be sampled on grids of any spacing."""
    n = int(round(length * ppw_master))
    dx = length / n
    kk = 2 * math.pi * np.fft.fftfreq(n, dx)
    w = (k_sigma / K) ** 2 * (k_ell / K) / (2 * math.sqrt(math.pi)) * np.exp(-(kk * k_ell / K) ** 2 / 4)
    coef = np.fft.fft(np.random.default_rng(seed).standard_normal(n)) * np.sqrt(2 * math.pi * w / dx) / n

    def sample(x):
        ph = np.exp(1j * np.outer(x + length / 2, kk))
        return tuple((ph @ (coef * f)).real for f in (1.0, 1j * kk, -kk ** 2))
    return sample


def convergence(quick):
    """σ and the albedo of one realization (kσ = 0.6, kℓ = 4, θᵢ = 40°) against the nodes per wavelength: the
    relative L2 change of σ from the finest grid."""
    out = []
    length, g = (24.0, 6.0) if quick else (40.0, 10.0)
    surface = _series_surface(length, 0.6, 4.0, seed=11)
    grids = (8.0, 16.0) if quick else (7.5, 10.0, 15.0, 20.0)
    cases = (("conductor", "s"),) if quick else (("conductor", "s"), ("conductor", "p"), ("aluminium", "p"),
                                                ("glass", "p"))
    for medium, pol in cases:
        ref = None
        for ppw in sorted(grids, reverse=True):
            n = int(round(length * ppw))
            x = -length / 2 + (np.arange(n) + 0.5) * length / n
            t0 = time.perf_counter()
            sol = solve_profile(x, *surface(x), [40.0], pol, MEDIA[medium], g, scatter_deg=np.arange(-89.5, 90, 1.0))
            sec = time.perf_counter() - t0
            ref = sol if ref is None else ref
            out.append(dict(medium=medium, polarization=pol, points_per_wavelength=ppw, beam_width_wl=g,
                            length_wl=length, albedo=float(sol.albedo[0]), seconds=sec,
                            sigma_change=float(np.sqrt(np.sum((sol.sigma - ref.sigma) ** 2) / np.sum(ref.sigma ** 2)))))
    return out


def taper_table(quick):
    """Flat conductor at 70° (s): the specular ratio's error against k g cos²θᵢ (the beam reaching grazing), and
    the Neumann energy loss on a rough surface against the surface length (grazing waves reaching the ends)."""
    rows = []
    for g in ((4.0,) if quick else (4.0, 6.0, 8.0, 10.0)):
        length = 8 * g
        n = int(round(10 * length))
        x = -length / 2 + (np.arange(n) + 0.5) * length / n
        z = np.zeros_like(x)
        sol = solve_profile(x, z, z, z, [70.0], "s", None, g, scatter_deg=[70.0])
        xs = np.linspace(-8 * g, 8 * g, 64001)
        a_hat = np.trapezoid(thorsos_beam(xs, 0 * xs, 70.0, g) * np.exp(-1j * K * math.sin(math.radians(70)) * xs),
                             xs)
        ref = K * math.cos(math.radians(70)) ** 2 * abs(a_hat) ** 2 / (2 * math.pi * sol.incident_power[0])
        rows.append(dict(kind="flat 70° s", beam_width_wl=g, length_wl=length,
                         taper_parameter=K * g * math.cos(math.radians(70)) ** 2,
                         error=float(sol.sigma[0, 0] / ref - 1)))
    lmax = 48.0 if quick else 96.0
    n0 = int(10 * lmax)
    x0 = -lmax / 2 + (np.arange(n0) + 0.5) * 0.1
    h0, dh0, d2h0 = gaussian_profile(n0, 0.1, 0.1, 0.5, np.random.default_rng(3))
    for length in ((24.0,) if quick else (24.0, 48.0, 96.0)):
        sel = np.abs(x0) < length / 2
        for pol in ("s", "p"):
            sol = solve_profile(x0[sel], h0[sel], dh0[sel], d2h0[sel], [0.0, 40.0], pol, None, 6.0,
                                scatter_deg=[0.0])
            rows.append(dict(kind=f"energy {pol}", beam_width_wl=6.0, length_wl=length,
                             error=[float(a - 1) for a in sol.albedo]))
    return rows


def corrected(err, noise):
    """The model's error with the sampling noise of the rigorous mean taken out: √(max(e² − n², 0)). With the
    model exact, ‖σ̂_MoM − σ‖² averages to the noise floor², so e² − n² estimates the model's own error²."""
    return math.sqrt(max(err ** 2 - noise ** 2, 0.0))


def beam_table(quick):
    """The mean incoherent reflectance (kσ = 0.3, kℓ = 4) against the beam width g (surface 4g long): it should
    not depend on g beyond the sampling error once the beam is wide enough."""
    rows = []
    widths = (6.0, 10.0) if quick else (6.0, 10.0, 14.0)
    for medium, pol in ((("conductor", "s"),) if quick else (("conductor", "s"), ("glass", "p"))):
        for g in widths:
            res = mom_scatter(MomRequest(0.3 / K, 4.0 / K, (0.0, 40.0, 70.0), pol, MEDIA[medium], 4 * g, g, 10.0,
                                         4 if quick else 16, seed=5, scatter_deg=tuple(np.arange(-89.5, 90, 1.0))))
            per = np.trapezoid(res.sigma_incoherent_samples, np.radians(res.scatter_deg), axis=-1)   # (M, n_i)
            rows.append(dict(medium=medium, polarization=pol, beam_width_wl=g, length_wl=4 * g,
                             realizations=per.shape[0],
                             incoherent=[float(v) for v in per.mean(axis=0)],
                             incoherent_se=[float(v) for v in per.std(axis=0, ddof=1) / math.sqrt(per.shape[0])],
                             albedo=[float(v) for v in res.albedo], theta_deg=[float(t) for t in res.theta_deg]))
    return rows


def _grade(c, n):
    """'5', '20' (within that tolerance, resolved: noise floor below it too), 'unresolved' (within 20 % but the
    noise floor above 20 %) or 'beyond', for the noise-corrected error c and the noise floor n."""
    if c <= 0.05 and n <= 0.05:
        return "5"
    if c <= 0.20 and n <= 0.20:
        return "20"
    return "unresolved" if c <= 0.20 else "beyond"


def _grade_of(r, model):
    return _grade(corrected(r[f"{model}_l2"], r["noise_floor"]), r["noise_floor"])


def _grids(rows, p):
    """Per model, medium and polarization: every (kσ, θᵢ) row of cells over kℓ, each cell its grade, errors and
    albedo error."""
    out = []
    for model in MODELS:
        for medium in p["media"]:
            for pol in p["pols"]:
                lines = []
                for ks in p["k_sigma"]:
                    for th in p["theta"]:
                        cells = []
                        for kl in p["k_ell"]:
                            r = next(r for r in rows if (r["k_sigma"], r["k_ell"], r["medium"], r["polarization"],
                                                         r["theta_deg"]) == (ks, kl, medium, pol, th))
                            cells.append({"grade": _grade_of(r, model), "noise": r["noise_floor"],
                                          "corrected": corrected(r[f"{model}_l2"], r["noise_floor"]),
                                          "error": r[f"{model}_l2"], "albedo_error": r[f"{model}_albedo_error"]})
                        lines.append({"k_sigma": ks, "theta_deg": th, "cells": cells})
                out.append({"model": model, "medium": medium, "polarization": pol, "rows": lines})
    return out


def _summary(rows, p):
    out = []
    for model in MODELS:
        for medium in p["media"]:
            for pol in p["pols"]:
                sel = [r for r in rows if r["medium"] == medium and r["polarization"] == pol]
                grades = [_grade_of(r, model) for r in sel]
                ok20 = [r for r, g in zip(sel, grades) if g in ("5", "20")]
                out.append({"model": model, "medium": medium, "polarization": pol, "within_5": grades.count("5"),
                            "within_20": len(ok20), "unresolved": grades.count("unresolved"), "cells": len(sel),
                            "noise_median": float(np.median([r["noise_floor"] for r in sel])),
                            "where": [[r["k_sigma"], r["k_ell"], r["theta_deg"]] for r in ok20]})
    return out


def _regions(rows, p):
    """Per model: in how many of the media × polarizations each (kσ, θᵢ, kℓ) cell is within 20 % (resolved)."""
    out = []
    for model in MODELS:
        lines = []
        for ks in p["k_sigma"]:
            for th in p["theta"]:
                cells = []
                for kl in p["k_ell"]:
                    sel = [r for r in rows if (r["k_sigma"], r["k_ell"], r["theta_deg"]) == (ks, kl, th)]
                    cells.append([sum(_grade_of(r, model) in ("5", "20") for r in sel), len(sel)])
                lines.append({"k_sigma": ks, "theta_deg": th, "cells": cells})
        out.append({"model": model, "combinations": len(p["media"]) * len(p["pols"]), "rows": lines})
    return out


def _thorsos(rows):
    """Kirchhoff on the perfect conductor (s): mean error where kℓ ≥ 6 and θᵢ ≤ 40°, against the rest (None when
    the map lacks the perfect conductor in s)."""
    pec = [r for r in rows if r["medium"] == "conductor" and r["polarization"] == "s"]
    if not pec:
        return None
    err = {id(r): corrected(r["kirchhoff_l2"], r["noise_floor"]) for r in pec}
    groups = (("kℓ ≥ 6, θᵢ ≤ 40°", [err[id(r)] for r in pec if r["k_ell"] >= 6 and r["theta_deg"] <= 40]),
              ("kℓ < 6, θᵢ ≤ 40°", [err[id(r)] for r in pec if r["k_ell"] < 6 and r["theta_deg"] <= 40]),
              ("θᵢ = 70°, all kℓ", [err[id(r)] for r in pec if r["theta_deg"] >= 70]))
    return [{"label": label, "median": float(np.median(v)), "min": min(v), "max": max(v), "cells": len(v)}
            for label, v in groups if v]


def page_data(data) -> dict:
    """The map's measurements (*data*: quick, parameters, rows, convergence, taper, beam, seconds) with what the
    page derives from them under ``page``: grades, summaries, the Thorsos check and the cost per realization."""
    p, rows = data["parameters"], data["rows"]
    nf = [r["noise_floor"] for r in rows]
    cost = {}
    for r in rows:
        cost.setdefault((r["medium"], r["n_unknowns"]), []).append(r["seconds_per_realization"])
    page = {"bin_deg": BIN_DEG, "noise": {"min": min(nf), "max": max(nf), "median": float(np.median(nf))},
            "regions": _regions(rows, p), "summary": _summary(rows, p), "thorsos": _thorsos(rows),
            "grids": _grids(rows, p),
            "cost": [{"medium": m, "unknowns": n, "seconds": float(np.median(v))}
                     for (m, n), v in sorted(cost.items())]}
    return {**data, "page": page}


def planning_table(data):
    """The compact table shipped as waveoptics/planning/validity_map.json (waveoptics.planning.validity)."""
    p = data["parameters"]
    entries = [dict(model=m, medium=r["medium"], polarization=r["polarization"], theta_deg=r["theta_deg"],
                    k_sigma=r["k_sigma"], k_ell=r["k_ell"], l2=round(r[f"{m}_l2"], 4),
                    l2_corrected=round(corrected(r[f"{m}_l2"], r["noise_floor"]), 4),
                    noise_floor=round(r["noise_floor"], 4), albedo_error=round(r[f"{m}_albedo_error"], 5))
               for m in MODELS for r in data["rows"]]
    return dict(generated_by="scripts/docs_validity_map.py", page="docs/validity-map.md",
                metric="relative L2 error of the incoherent scattering coefficient in 5-degree bins against the "
                       "method-of-moments mean; albedo_error = model minus rigorous reflectance",
                realizations=p["realizations"], length_wl=p["length"], beam_width_wl=p["beam"],
                grid=dict(k_sigma=p["k_sigma"], k_ell=p["k_ell"], theta_deg=p["theta"]), entries=entries)


def _planning_path(out):
    return out / "planning_validity_map.json" if out else ROOT / "waveoptics" / "planning" / "validity_map.json"


def measure(p, *, quick=False, processes=2, json_path=None) -> dict:
    """The map on the grid *p* (FULL or QUICK), then the convergence, truncation and beam tables; the map alone is
    written to *json_path* first (the tables take minutes)."""
    t0 = time.perf_counter()
    jobs = [(ks, kl, m, pol, p) for ks in p["k_sigma"] for kl in p["k_ell"] for m in p["media"] for pol in p["pols"]]
    if quick or processes == 1:
        rows = [r for j in jobs for r in run_config(j)]
    else:
        with Pool(processes) as pool:
            rows = [r for part in pool.map(run_config, jobs, chunksize=1) for r in part]
    data = dict(quick=quick, parameters={k: list(v) if isinstance(v, tuple) else v for k, v in p.items()},
                rows=rows)
    if json_path:
        json_path.write_text(json.dumps(data, indent=1) + "\n")
    data.update(convergence=convergence(quick), taper=taper_table(quick), beam=beam_table(quick),
                seconds=time.perf_counter() - t0)
    return data


def compute() -> dict:
    """The full map (and the planner's table waveoptics/planning/validity_map.json, written as a side effect)."""
    data = page_data(measure(dict(FULL), json_path=ROOT / "docs" / "data" / "validity_map.json"))
    _planning_path(None).write_text(json.dumps(planning_table(data), indent=0) + "\n")
    return data


def main(argv=None) -> None:
    """Build the map; *argv* defaults to the command line when run as a script."""
    import docs_render

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a reduced map (< 1 min)")
    ap.add_argument("--out", type=Path, help="write both files into this folder")
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--from-json", type=Path, help="only rewrite the page from this validity_map.json")
    ap.add_argument("--update-tables", action="store_true",
                    help="with --from-json: recompute the convergence, truncation and beam tables into that file")
    ap.add_argument("--realizations", type=int, help="realizations per configuration (full map: 64)")
    a = ap.parse_args(argv if argv is not None else sys.argv[1:])
    if a.from_json:
        data = json.loads(a.from_json.read_text())
        if a.update_tables:
            data.update(convergence=convergence(data["quick"]), taper=taper_table(data["quick"]),
                        beam=beam_table(data["quick"]))
        json_path, md_path = a.from_json, (a.out or ROOT / "docs") / "validity-map.md"
    else:
        p = dict(QUICK if a.quick else FULL)
        if a.realizations:
            p["realizations"] = a.realizations
        json_path = (a.out / "validity_map.json") if a.out else ROOT / "docs" / "data" / "validity_map.json"
        md_path = (a.out / "validity-map.md") if a.out else ROOT / "docs" / "validity-map.md"
        data = measure(p, quick=a.quick, processes=a.processes, json_path=json_path)
    data = page_data(data)
    json_path.write_text(docs_render.dumps(data), encoding="utf-8")
    md_path.write_text(docs_render.render("validity_map", data), encoding="utf-8")
    if not data["quick"]:
        _planning_path(a.out).write_text(json.dumps(planning_table(data), indent=0) + "\n")
    print(f"wrote {json_path} and {md_path} in {data['seconds']:.0f} s")


if __name__ == "__main__":
    main()
