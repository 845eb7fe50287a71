"""Data of docs/planning.md (docs/data/planning.json; prose in docs/templates/planning.md): the scene-file schema and
the decision rules (from the docstrings of waveoptics.planning.scene and .planner, single source), the planner's
thresholds, the cost model on this machine and, for every example scene, its plan and the measured time beside the
estimate — every number produced by the code (a few minutes: it plans and runs every example scene)."""
from __future__ import annotations

import re
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from waveoptics import colour
from waveoptics import planning
from waveoptics.planning import scene

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "examples" / "scenes"

#: the planner's thresholds in the order of the page's table (their meaning is in the template)
THRESHOLDS = ("ESTIMATE_RESOLUTION", "ESTIMATE_RESOLUTION_MAX", "ESTIMATE_STEP_NM", "ESTIMATE_SPHERE_THETAS", "ESTIMATE_SHARE", "FLAT_SCATTER",
              "PSD_G_MAX", "DE_PER_RELATIVE_Y", "PLAN_RESOLUTION_RANGE", "PATCH_SIGMAS", "LAMBDA_REF_NM", "F_FLAT_TOL",
              "ORDER_EFFICIENCY_MIN", "LSTAR_SLOPE_BLACK", "FLOOR_MARGIN")


def _schema() -> str:
    """The schema block of waveoptics.planning.scene's docstring (single source)."""
    doc = scene.__doc__
    block = doc.split("Schema (", 1)[1].split("References", 1)[0]
    lines = block.split("\n")[1:]
    return "\n".join(line[4:] if line.startswith("    ") else line for line in lines).strip("\n")


def decisions_doc() -> list:
    """The decision rules, one {name, text} per ````name```` block of waveoptics.planning.planner's docstring (up to
    "Costs come from", which the template says itself), with Sphinx roles written as Markdown code."""
    doc = planning.planner.__doc__.split("For every (material, light) pair of a :class:`waveoptics.planning.scene."
                                         "Scene` the planner takes, in order:", 1)[1].split("References", 1)[0]
    blocks = re.split(r"\n``(\w[\w ]*)``\n", doc)      # split before the roles are rewritten: the names are ``name``
    out = []
    for name, body in zip(blocks[1::2], blocks[2::2]):
        body = re.sub(r":(?:data|func|mod|class|meth):`~?([^`]+)`", r"`\1`", body)
        body = re.sub(r"``([^`]+)``", r"`\1`", body)
        para = " ".join(line.strip() for line in body.strip().split("\n"))
        cut = para.find("Costs come from")
        out.append({"name": name, "text": para[:cut].strip() if cut >= 0 else para})
    return out


def _run(sc, outdir, **force):
    import json

    plan = planning.plan_scene(sc, force=force)
    data = planning.execute(plan, outdir, overwrite=True)
    res = json.loads((Path(outdir) / "results.json").read_text())
    return plan, data, res


def plan_times() -> list:
    """Wall time of `waveoptics plan` on each example scene, measured as a user meets it: with an empty cache
    (the first plan on a machine: calibration and imports), a new scene on a calibrated machine, and the same
    scene again."""
    import os
    import subprocess
    import sys

    rows = []
    for path in sorted(SCENES.glob("*.toml")):
        times = []
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, WAVEOPTICS_CACHE_DIR=cache)
            for step in ("first", "new", "again"):
                if step == "new":   # calibrated, but no plan of this scene yet
                    for f in Path(cache).glob("plans-*.json"):
                        f.unlink()
                t = time.perf_counter()
                subprocess.run([sys.executable, "-m", "waveoptics", "plan", str(path)], env=env, check=True,
                               capture_output=True)
                times.append(time.perf_counter() - t)
        rows.append({"scene": path.stem, "first_s": times[0], "new_s": times[1], "again_s": times[2]})
    return rows


def cost_model() -> dict:
    """The calibration: its time, seconds per unit (in the cost model's order) and the OpenCL direct-sum term."""
    cm = planning.calibration()
    direct, why = planning.direct_calibration()
    return {"calibration_s": cm.calibration_s, "direct_term": direct, "direct_why": why,
            "units": [[k, v] for k, v in cm.as_dict().items() if k != "calibration_s"]}


def _entry(e, m) -> dict:
    return {"name": e.name, "material": e.material.name, "category": e.material.category, "light": e.light_name,
            "spd": e.spd.name, "estimated_s": m["estimated_time_s"], "measured_s": m["measured_time_s"],
            "outputs_s": m["outputs_time_s"], "files": list(m["files"]),
            "decisions": [[d, str(v), str(r)] for d, v, r in e.decisions],
            "diffraction": bool(e.effects["diffraction"]), "diffuse": bool(e.effects["diffuse"]), "solver": e.solver, "wavelengths": int(e.wavelengths_nm.size),
            "directions": e.directions, "resolution": e.resolution}


def example_scenes(tmp: Path) -> list:
    """Every example scene planned and run: its plan entries with estimated and measured times."""
    out = []
    for path in sorted(SCENES.glob("*.toml")):
        sc = scene.load(path)
        plan, data, _ = _run(sc, tmp / path.stem)
        out.append({"name": sc.name, "file": path.name, "description": sc.description,
                    "planning_s": plan.planning_time_s,
                    "entries": [_entry(e, m) for e, m in zip(plan.entries, data["materials"])]})
    return out


def skipping(tmp: Path) -> dict:
    """Smooth plastic as planned (no diffraction) against diffraction forced on: time and colour differences."""
    sc = scene.load(SCENES / "smooth-plastic.toml")
    p0, d0, r0 = _run(sc, tmp / "plastic-planned")
    p1, d1, r1 = _run(sc, tmp / "plastic-forced", diffraction=True)
    v0 = np.array([v["rgb"] for v in r0["materials"][0]["views"]])
    v1 = np.array([v["rgb"] for v in r1["materials"][0]["views"]])
    a0 = np.array(r0["materials"][0]["albedo"]["i30_0"]["rgb"])
    a1 = np.array(r1["materials"][0]["albedo"]["i30_0"]["rgb"])
    t0, t1 = d0["measured_time_s"], d1["measured_time_s"]
    return {"resolution": p0.entries[0].resolution, "forced_wavelengths": int(p1.entries[0].wavelengths_nm.size),
            "measured_s": [t0, t1], "speedup": t1 / t0,
            "estimated_s": [d0["materials"][0]["estimated_time_s"], d1["materials"][0]["estimated_time_s"]],
            "views_dE_max": float(np.max(colour.delta_e2000(v0, v1))),
            "albedo_dE": float(colour.delta_e2000(a0, a1)),
            "sphere_dE_max": r1["materials"][0]["sphere"]["delta_e2000_vs_microfacet"]["max"], "target": sc.delta_e}


def haze(tmp: Path) -> dict:
    """Polished aluminium: the planner's estimate, and the colour change at three views when diffraction is off."""
    sc = scene.load(SCENES / "polished-aluminium-haze.toml")
    views = [[25, 180], [40, 180], [0, 0]]
    probe = scene.parse({"name": "haze-views",
                         "materials": [{"name": "polished-al", "material": "Al", "roughness": sc.materials[0].roughness,
                                        "nano": {"statistics": sc.materials[0].nano.text}}],
                         "lights": [{"name": "daylight", "spd": "D65", "directions_deg": [[30, 0]]}],
                         "view": {"directions_deg": views},
                         "output": {"rgb_images": False, "tables": True}})
    q0, _, s0 = _run(probe, tmp / "haze-on")
    q1, _, s1 = _run(probe, tmp / "haze-off", diffraction=False)
    h0 = np.array([v["rgb"] for v in s0["materials"][0]["views"]])
    h1 = np.array([v["rgb"] for v in s1["materials"][0]["views"]])
    return {"alpha": sc.materials[0].roughness, "nano": sc.materials[0].nano.text,
            "estimated_dE": q0.entries[0].metrics["estimated_delta_e"],
            "views": [{"theta_deg": t, "dE": float(x)} for (t, _), x in zip(views, colour.delta_e2000(h0, h1))]}


def compute() -> dict:
    """Every number and code-derived text of docs/planning.md."""
    t_start = time.perf_counter()
    out = {"schema": _schema(), "decisions": decisions_doc(), "long_request_s": planning.LONG_REQUEST_S,
           "plan_times": plan_times(), "cost_model": cost_model(),
           "thresholds": {name: getattr(planning, name) if isinstance(getattr(planning, name), (int, float))
                          else str(getattr(planning, name)) for name in THRESHOLDS}}
    tmp = Path(tempfile.mkdtemp(prefix="wo-docs-planning-"))
    try:
        out.update(scenes=example_scenes(tmp), skipping=skipping(tmp), haze=haze(tmp))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    out["seconds"] = time.perf_counter() - t_start
    return out


def main() -> None:
    import make_docs

    make_docs.main(["planning"])


if __name__ == "__main__":
    main()
