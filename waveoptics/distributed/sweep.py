"""Parameter sweeps: the --vary grammar, one simulation per point on Dask, a CSV of albedo, ΔE and cost.
"""
from __future__ import annotations

import csv
import dataclasses
import itertools
import json
import math
import time
from pathlib import Path
from typing import Callable

import numpy as np

from .. import colour, io, simulate, surfaces
from ..renderers.sphere import skipped_spheres
from ..errors import FieldError, WaveopticsError, unknown
from ..request import NANO_PARAMS, SimulationRequest, nano_key, parse_nano
from ..units import LENGTH_UNITS, parse_length, parse_number_list
from .cases import case_token, surface_digest
from .cluster import DEFAULT_RETRIES, check_cluster_args, Job, run_timed, warm_workers
from .store import refuse_or_prepare, Store, check_resume_overwrite, partial_path

__all__ = ['MAX_SWEEP_POINTS', 'parse_length_list', 'VARY', 'parse_vary', 'apply_vary', 'sweep_points', 'sweep_point', 'SWEEP_COLUMNS', 'value_text', 'run_sweep', 'read_sweep']

# ----------------------------------------------------------------------------------------------------------------
# Sweeps
# ----------------------------------------------------------------------------------------------------------------

def _split_values(text: str) -> list[str]:
    # ';' separates values that may contain commas themselves (f0:0.9,0.6,0.3)
    sep = ";" if ";" in text else ","
    vals = [v.strip() for v in text.split(sep) if v.strip()]
    if not vals:
        raise FieldError(f"{{vary}}: no values in {text!r}", 'vary')
    return vals


def parse_length_list(text: str, *, name: str = "length") -> list[float]:
    """Lengths in metres from ``"1nm,5nm"`` or ``"1nm:20nm:5"`` (START:STOP:STEP, a bare STEP takes START's
    unit, STOP included when on the grid; see :func:`waveoptics.units.parse_number_list`)."""
    s = str(text).strip()
    if ":" not in s:
        return [parse_length(p, name=name, allow_zero=True) for p in _split_values(s)]
    parts = [p.strip() for p in s.split(":")]
    if len(parts) != 3:
        raise WaveopticsError(f"{name} {text!r} is not a length list; write 1nm:20nm:5 or 1nm,5nm,10nm")
    unit = next((u for u in sorted(LENGTH_UNITS, key=len, reverse=True) if parts[0].endswith(u)), None)
    if unit is None:
        raise WaveopticsError(f"{name} {text!r}: START needs a unit (e.g. 1nm:20nm:5)")
    nums = [parse_length(p, default_unit=unit, name=name, allow_zero=True) / LENGTH_UNITS[unit] for p in parts]
    vals = parse_number_list(":".join(f"{x:.17g}" for x in nums), name=name)
    return [float(v) * LENGTH_UNITS[unit] for v in vals]


def _set_nano_param(case: SimulationRequest, key: str, value) -> SimulationRequest:
    if case.surface is not None:
        raise FieldError(f"{{vary}} {key}: the nano roughness is a height-field file; vary {{nano}} parameters "
                              "only with {nano} MODEL:params", 'vary', 'nano')
    model, p = parse_nano(case.nano)
    key = nano_key(key)
    if key not in NANO_PARAMS[model]:
        raise FieldError(f"{{vary}} nano.{key}: {model} has no parameter {key!r}; allowed: "
                              f"{', '.join(NANO_PARAMS[model])}", 'vary')
    p[key] = value
    kinds = NANO_PARAMS[model]
    text = ",".join(f"{k}={v:.17g}m" if kinds[k] == "length" else f"{k}={v:.17g}" for k, v in p.items())
    return dataclasses.replace(case, nano=f"{model}:{text}")


def _vary_nano(key: str):
    def parse(text, model_kind):
        if model_kind == "length":
            return parse_length_list(text, name=f"vary nano.{key}")
        return [float(v) for v in parse_number_list(text, name=f"vary nano.{key}")]
    return parse


#: --vary NAME -> (help, parser of the value list, setter (case, value) -> case)
VARY = {
    "material": ("material names (';' separates values that contain commas)",
                 lambda s: _split_values(s), lambda c, v: dataclasses.replace(c, material=v)),
    "sigma_nano": ("rms height of the nano roughness, lengths (1nm:20nm:5 or 2nm,5nm)",
                   lambda s: parse_length_list(s, name="vary sigma_nano"),
                   lambda c, v: _set_nano_param(c, "sigma", v)),
    "micro_alpha": ("micro NDF roughness α", lambda s: [float(x) for x in parse_number_list(s, name="vary "
                                                                                                  "micro_alpha")],
                    lambda c, v: dataclasses.replace(c, micro_alpha=v)),
    "alpha_y": ("α_y of an anisotropic micro NDF (α_x is micro_alpha)",
                lambda s: [float(x) for x in parse_number_list(s, name="vary alpha_y")],
                lambda c, v: dataclasses.replace(c, alpha_y=v)),
    "theta": ("incident zenith angle, degrees", lambda s: [float(x) for x in parse_number_list(s, name="vary theta")],
              lambda c, v: dataclasses.replace(c, incident_deg=(v, c.incident_deg[1]))),
    "kd": ("diffuse albedo of a dielectric", lambda s: [float(x) for x in parse_number_list(s, name="vary kd")],
           lambda c, v: dataclasses.replace(c, kd=v)),
    "ndf": ("micro NDF name (ggx, beckmann)", lambda s: _split_values(s), lambda c, v: dataclasses.replace(c, ndf=v)),
    "illuminant": ("light source (';' separates values that contain commas)", lambda s: _split_values(s),
                   lambda c, v: dataclasses.replace(c, illuminant=v)),
    "diffraction": ("diffraction model of the nano lobe (kirchhoff, ghs, rghs, ohs, rohs)", lambda s: _split_values(s),
                    lambda c, v: dataclasses.replace(c, diffraction=v)),
}


#: most points of one sweep (a guard against products of fine ranges that would run for days)
MAX_SWEEP_POINTS = 10_000


def parse_vary(text: str, base: SimulationRequest | None = None) -> tuple[str, list]:
    """Parse one ``--vary NAME=VALUES`` into (name, values); names: :data:`VARY` or ``nano.KEY``."""
    name, eq, values = str(text).partition("=")
    name = name.strip()
    if not eq or not values.strip():
        raise FieldError(f"{{vary}} {text!r} is not NAME=VALUES (e.g. material=Au,Ag,Cu or sigma_nano=1nm:20nm:5)", 'vary')
    if name.startswith("nano."):
        key = nano_key(name[5:])
        model = parse_nano(base.nano)[0] if base is not None and base.nano else None
        kind = NANO_PARAMS.get(model, {}).get(key, "length" if key in ("sigma", "corr_length", "B") else "number")
        vals = _vary_nano(key)(values, kind)
    elif name in VARY:
        vals = VARY[name][1](values)
    else:
        raise unknown("parameter", name, [*VARY, "nano.KEY"], field='vary')
    if not vals:
        raise FieldError(f"{{vary}} {text!r} gives no values", 'vary')
    seen = set()
    for v in vals:   # a repeated value is the same point computed twice under one name: a typo, not a sweep
        key = v if isinstance(v, str) else float(f"{float(v):.12g}")
        if key in seen:
            raise FieldError(f"{{vary}} {text!r} gives the value {value_text(name, v)} twice; each point once", 'vary')
        seen.add(key)
    return name, vals


def apply_vary(case: SimulationRequest, name: str, value) -> SimulationRequest:
    """*case* with parameter *name* set to *value*."""
    if name.startswith("nano."):
        return _set_nano_param(case, name[5:], value)
    return VARY[name][2](case, value)


def sweep_points(base: SimulationRequest, varies: list[tuple[str, list]]) -> list[tuple[dict, SimulationRequest]]:
    """The Cartesian product of the *varies* lists applied to *base*: [(values by name, case), ...]."""
    names = [n for n, _ in varies]
    if len(set(names)) != len(names):
        raise FieldError("{vary}: a parameter is given twice; list all its values in one {vary}", 'vary')
    n_points = math.prod(len(v) for _, v in varies)
    if n_points > MAX_SWEEP_POINTS:
        raise FieldError(f"{{vary}} gives {n_points:.3g} points; at most {MAX_SWEEP_POINTS} are allowed in one sweep "
                         "(use coarser steps, or split it)", 'vary')
    out = []
    for combo in itertools.product(*(vals for _, vals in varies)):
        case = base
        for n, v in zip(names, combo):
            case = apply_vary(case, n, v)
        out.append((dict(zip(names, combo)), case.resolved()))
    return out


def sweep_point(case: SimulationRequest, *, surface=None, sphere_size: int = 64, device=None) -> dict:
    """Simulate one sweep point on a worker and reduce it to summaries.

    *surface* (HeightField) replaces loading ``case.surface`` on the worker.

    Returns
    -------
    dict
        ``albedo_{R,G,B}`` and ``microfacet_albedo_{R,G,B}`` (linear sRGB of the directional albedo at the
        incident direction), ``albedo_mean`` / ``microfacet_albedo_mean`` (mean over wavelengths),
        ``dE_albedo`` (CIEDE2000 between the two albedo colours), ``dE_sphere_mean`` / ``dE_sphere_max``
        (per-pixel CIEDE2000 of sphere renders of both models; None, not computed, with *sphere_size* 0),
        ``coherent_fraction``
        (mean over wavelengths), ``sigma_nano_m``, ``solver``, ``n_wavelengths``, ``cost_s`` (wall time, s).
    """
    t0 = time.perf_counter()
    sim = simulate.run(case.resolved(), surface=surface, sphere=sphere_size > 0, device=device)
    rgb, rgb_mf = sim.rgb_albedo("total"), sim.rgb_albedo("microfacet")
    row = {f"albedo_{c}": float(rgb[i]) for i, c in enumerate("RGB")}
    row.update({f"microfacet_albedo_{c}": float(rgb_mf[i]) for i, c in enumerate("RGB")})
    row["albedo_mean"] = float(np.mean(sim.lobes.albedo("total")))
    row["microfacet_albedo_mean"] = float(np.mean(sim.lobes.albedo("microfacet")))
    row["dE_albedo"] = float(colour.delta_e2000(rgb, rgb_mf))
    if sphere_size > 0:
        _, _, dE, mask = simulate.render_spheres(sim, sphere_size)
        row["dE_sphere_mean"] = float(dE[mask].mean()) if mask.any() else 0.0
        row["dE_sphere_max"] = float(dE[mask].max()) if mask.any() else 0.0
    else:   # not computed: None (an empty CSV cell, JSON null), never a 0 that would read as "no difference"
        row["dE_sphere_mean"] = row["dE_sphere_max"] = None
    row["coherent_fraction"] = float(np.mean(sim.lobes.coherent_specular_fraction()))
    row["sigma_nano_m"] = float(sim.params["sigma_nano_m"])
    row["solver"] = sim.params["solver"]
    row["n_wavelengths"] = int(sim.wavelengths_nm.size)
    row["cost_s"] = time.perf_counter() - t0
    return row


#: columns of a sweep table after the varied parameters
SWEEP_COLUMNS = ("albedo_R", "albedo_G", "albedo_B", "microfacet_albedo_R", "microfacet_albedo_G",
                 "microfacet_albedo_B", "albedo_mean", "microfacet_albedo_mean", "dE_albedo", "dE_sphere_mean",
                 "dE_sphere_max", "coherent_fraction", "sigma_nano_m", "solver", "n_wavelengths", "cost_s")


def _is_length(name: str) -> bool:
    key = name[5:] if name.startswith("nano.") else None
    return name == "sigma_nano" or any(kinds.get(key) == "length" for kinds in NANO_PARAMS.values())


def value_text(name: str, v) -> str:
    """A swept value as written in the table: lengths with a unit (``6nm``, ``1.5um``), numbers with 6 digits."""
    if _is_length(name) and isinstance(v, float):
        return f"{v * 1e9:.6g}nm" if abs(v) < 1e-6 else f"{v * 1e6:.6g}um"
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def run_sweep(base: SimulationRequest, varies: list[tuple[str, list]], output, *, surface=None, sphere_size: int = 64,
              workers: int | None = None, scheduler: str | None = None, client=None, resume: bool = False,
              overwrite: bool = False, device: str | None = None, progress=None,
              retries: int = DEFAULT_RETRIES, task_fn: Callable = sweep_point,
              no_sphere_reason: str = "not asked (sphere_size=0)") -> dict:
    """Run a parameter sweep on Dask and write a table of summaries (CSV, or JSON if *output* ends in .json).

    One task per sweep point; finished rows stream into ``OUT.partial/`` exactly like table blocks (see
    :func:`run_table` for *surface*, *resume*, *overwrite*, *workers*, *scheduler*, *client*, *retries*).
    With *sphere_size* 0 the ``dE_sphere_*`` values are null (not computed) and each row's ``skipped`` entry
    (:func:`waveoptics.renderers.sphere.skipped_spheres`, as in ``waveoptics simulate``'s summary) says why:
    *no_sphere_reason*.

    Returns
    -------
    dict
        ``output``, ``rows`` (list of dicts, in sweep order), ``points``, ``computed``, ``skipped``, ``wall_s``.
    """
    t0 = time.perf_counter()
    final = Path(output)
    if final.suffix.lower() not in (".csv", ".json"):
        raise WaveopticsError(f"sweep output {str(final)!r}: use a .csv or .json file name")
    points = sweep_points(base, varies)
    partial = partial_path(final)
    for _, case in points:
        case.validate()
    params = {"base": base.params(), "vary": [[n, list(vals)] for n, vals in varies],
              "sphere_size": int(sphere_size)}
    hf = surface
    if hf is None and base.surface is not None:
        hf = surfaces.load(base.surface)
    if hf is not None:
        params["surface_digest"] = surface_digest(hf)
    token = case_token(params)
    check_resume_overwrite(resume, overwrite)
    if resume and final.exists() and not partial.exists():
        return {"output": str(final), "rows": read_sweep(final), "points": len(points), "computed": 0,
                "skipped": len(points), "wall_s": time.perf_counter() - t0}
    check_cluster_args(workers, scheduler)
    refuse_or_prepare(final, partial, resume=resume, overwrite=overwrite)
    store = Store(partial, {"kind": "sweep", "token": token, "parameters": params}, resume=resume)
    names = [f"p{i:05d}" for i in range(len(points))]
    todo = [i for i, n in enumerate(names) if not store.has(n, ".json")]
    computed = []
    timings = dict.fromkeys(("start_s", "compute_s", "store_s", "stop_s"), 0.0)

    def on_result(job, row):
        t = time.perf_counter()
        i = job.args[0]
        io.write_json(store.path(names[i], ".json"), row)
        computed.append(names[i])
        timings["store_s"] += time.perf_counter() - t

    def submit(cl):
        warm_workers(cl, [c for _, c in points], device)
        hf_ref = cl.scatter(hf, broadcast=False, hash=False) if hf is not None else None
        return [Job(f"wo-sweep-{token}-{names[i]}", _sweep_task,
                     (i, points[i][1], task_fn, hf_ref, sphere_size, device)) for i in todo]

    run_timed(client, workers, scheduler, bool(todo), submit, on_result, timings, retries=retries,
               progress=progress)
    rows = []
    skipped = {"skipped": skipped_spheres(no_sphere_reason)} if sphere_size == 0 else {}
    for i, (vals, case) in enumerate(points):
        row = json.loads(store.path(names[i], ".json").read_text())
        rows.append({"point": i, **{n: value_text(n, v) for n, v in vals.items()}, **row, **skipped})
    _write_rows(rows, final, [n for n, _ in varies], overwrite=overwrite or resume)
    store.remove()
    return {"output": str(final), "rows": rows, "points": len(points), "computed": len(computed),
            "skipped": len(points) - len(todo), "wall_s": time.perf_counter() - t0, "timings_s": timings}


def _sweep_task(i, case, task_fn, surface, sphere_size, device):
    # i is unused by the computation; it ties the result to its point in on_result
    return task_fn(case, surface=surface, sphere_size=sphere_size, device=device)


def _write_rows(rows, final: Path, varied: list[str], *, overwrite: bool) -> None:
    if final.suffix.lower() == ".json":
        io.write_json(final, rows, overwrite=overwrite)
        return

    cols = ["point", *varied, *SWEEP_COLUMNS, *(["skipped"] if any("skipped" in r for r in rows) else [])]
    with io.atomic_path(final, overwrite=overwrite) as tmp, open(tmp, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        wr.writeheader()
        for r in rows:   # None (not computed) is an empty cell
            wr.writerow({k: _csv_cell(v) for k, v in r.items()})


def _csv_cell(v):
    if isinstance(v, dict):   # a ``skipped`` entry: "WHAT: WHY; ..."
        return "; ".join(f"{what}: {why}" for what, why in v.items())
    return f"{v:.9g}" if isinstance(v, float) else v


def _from_csv(key: str, text: str):
    if text == "":
        return None
    if key == "skipped":
        return dict(item.split(": ", 1) for item in text.split("; "))
    return text


def read_sweep(path) -> list[dict]:
    """Rows of a sweep table: JSON as written; CSV values as text, except an empty cell, which is None (a value
    not computed, JSON's null), and the ``skipped`` column, read back into the entry JSON holds
    (``{"sphere renders": why}``)."""
    p = Path(path)
    if p.suffix.lower() == ".json":
        return json.loads(p.read_text())

    with open(p, newline="") as fh:
        return [{k: _from_csv(k, v) for k, v in row.items()} for row in csv.DictReader(fh)]
