"""Data of docs/renderers.md (docs/data/renderers.json; prose in docs/templates/renderers.md) and
docs/img/renderers_render.png: the BRDF in renderers — the Mitsuba 3 plugin, the RGL export
read back by Mitsuba 3's ``measured`` model, and ``waveoptics render`` — with every number measured in this run:
the error of the wavelength interpolation against the exact model, the export's round-trip error, and the time
of the default render with each BSDF on this machine; and the polarized render of a glass sphere
(scripts/polarized_render.py, docs/img/renderers_polarized.png)."""
from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

import polarized_render  # noqa: E402  (scripts/, on the path of make_docs)
from waveoptics import brdf, surfaces
from waveoptics.cli import main as cli
from waveoptics.renderers import cached_renderer_brdf, rgl
from waveoptics.renderers import mitsuba as wm

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"

CASES = {   # label → renderer_brdf keywords
    "gold, GGX α 0.2, ABC σ 10 nm": dict(material="gold", alpha=0.2, nano="abc:sigma=10nm,B=2um,C=2.6"),
    "aluminium, GGX α 0.15 × 0.4, Gaussian σ 15 nm": dict(material="aluminium", alpha=0.15, alpha_y=0.4,
                                                           nano="gaussian:sigma=15nm,corr_length=1.5um"),
    "dielectric 1.5 + kd 0.6, α 0.25, ABC σ 20 nm": dict(material="1.5", alpha=0.25, kd=0.6,
                                                          nano="abc:sigma=20nm,B=2um,C=2.6"),
    "copper, GGX α 0.05, ABC σ 40 nm": dict(material="copper", alpha=0.05, nano="abc:sigma=40nm,B=2um,C=2.6"),
}


def _dirs(rng, n, theta_max_deg):
    th = np.radians(rng.uniform(0, theta_max_deg, n))
    ph = rng.uniform(-np.pi, np.pi, n)
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)


def interpolation_table() -> list:
    """Per material, the worst median relative error of 20 nm and 10 nm wavelength nodes (and where) against the
    exact model half-way between nodes."""
    nano = brdf.Nano(model=surfaces.PSDModel("abc", sigma=10e-9, B=2e-6, C=2.6))
    rng = np.random.default_rng(3)
    wi = _dirs(rng, 200, 80.0)
    rows = []
    for mat in ("gold", "copper", "silver", "aluminium"):
        exact = brdf.TwoScaleBRDF(material=mat, micro=brdf.Micro(alpha=0.3, ndf="ggx"), nano=nano, nodes=64)
        wo = exact.sample(wi, 550.0, rng.random((200, 2))).wo
        ok = wo[:, 2] > 0
        a, b = wi[ok], wo[ok]
        cells = []
        for step in (20.0, 10.0):
            sn = brdf.SpectralNodes(exact, tuple(np.arange(360.0, 831.0, step)))
            worst = max((float(np.median(np.abs(sn.eval(a, b, lam) / exact.eval(a, b, lam) - 1))), lam)
                        for lam in np.arange(360 + step / 2, 830, step))
            cells.append({"error": worst[0], "wavelength_nm": worst[1]})
        rows.append({"material": mat, "cells": cells})
    return rows


def round_trip_table(mi, tmp: Path) -> list:
    """Per case, the RGL export's time and size and Mitsuba's read-back error of eval and albedo."""
    rows = []
    for label, kw in CASES.items():
        model = cached_renderer_brdf(**kw)
        path = tmp / "m.bsdf"
        t0 = time.perf_counter()
        rgl.export_rgl(model, path)
        t_exp = time.perf_counter() - t0
        rng = np.random.default_rng(21)
        wi = _dirs(rng, 1000, 80.0)
        lam = 550.0 if 550.0 in model.wavelengths_nm else float(model.wavelengths_nm[9])
        s = model.sample(wi, lam, rng.random((1000, 2)))
        ok = s.pdf > 0
        wi, wo = wi[ok], s.wo[ok]
        got = rgl.read_back_eval(mi, path, wi, wo, lam)
        rel = np.abs(got / model.eval(wi, wo, lam) - 1)
        alb = []
        for th in (0.0, 40.0, 70.0):
            w1 = np.array([np.sin(np.radians(th)), 0.0, np.cos(np.radians(th))])
            est = rgl.read_back_albedo(mi, path, w1, lam, seed=int(th))
            alb.append(est / float(model.albedo(w1, lam)) - 1)
        rows.append({"label": label, "export_s": t_exp, "file_mb": path.stat().st_size / 1e6,
                     "median": np.median(rel), "p90": np.percentile(rel, 90), "albedo": alb})
    return rows


def _run(argv) -> tuple[float, dict]:
    out = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        rc = cli(argv)
    if rc != 0:
        raise SystemExit(f"waveoptics {' '.join(argv)} failed")
    return time.perf_counter() - t0, json.loads(out.getvalue())


def _timings(wall: float, s: dict) -> dict:
    return {"wall_s": wall, **s["timings_s"], "delta_e2000": {k: s["delta_e2000"][k] for k in ("mean", "p95")},
            "noise_floor": s["noise_floor_delta_e2000"]["mean"]}


#: the BSDFs of ``waveoptics render --bsdf``, in the order of the measured table
RENDER_BSDFS = ("native", "measured", "plugin")


def render_section(tmp: Path) -> dict:
    """``waveoptics render`` of gold with each way the model enters Mitsuba (the Dr.Jit plugin, the RGL export
    read by ``measured``, the NumPy plugin): times, ΔE2000 and noise floor, and the native render's picture
    (docs/img/renderers_render.png; the README's picture is ``make demo``'s and stays its own)."""
    out = {}
    old = os.environ.get("WAVEOPTICS_CACHE_DIR")
    os.environ["WAVEOPTICS_CACHE_DIR"] = str(tmp / "cache")     # empty: the first row builds the model
    try:
        for bsdf in RENDER_BSDFS:
            wall, s = _run(["render", "--material", "gold", "--micro-alpha", "0.2", "--bsdf", bsdf, "-o",
                            str(tmp / bsdf), "--overwrite", "--json"])
            out[bsdf] = _timings(wall, s)
    finally:
        if old is None:
            os.environ.pop("WAVEOPTICS_CACHE_DIR", None)
        else:
            os.environ["WAVEOPTICS_CACHE_DIR"] = old
    shutil.copyfile(tmp / "native" / "render.png", IMG / "renderers_render.png")
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"cores": cores, **out}


def compute() -> dict:
    """Every number of docs/renderers.md (minutes: it tabulates models and renders three times)."""
    IMG.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        interp = interpolation_table()
        mi = wm.load_mitsuba("llvm_ad_spectral")
        trip = round_trip_table(mi, tmp)
        rend = render_section(tmp)
        polar = polarized_render.polarized_section(IMG)
    return {"interpolation": interp, "round_trip": trip, "render": rend, "polarized": polar}


def main() -> None:
    import make_docs

    make_docs.main(["renderers"])


if __name__ == "__main__":
    main()
