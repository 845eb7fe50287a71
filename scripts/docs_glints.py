"""Data of docs/glints.md (docs/data/glints.json; prose in docs/templates/glints.md) and the figures
docs/img/glints_footprints.png, glints_brushed.png, glints_flakes.png: per-pixel footprint BRDFs and what they
cost, and glint renders at real scale — every number measured in this run (GLINTS_DOC_SIZE sets the brushed
sphere's size, default 128)."""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np

from waveoptics import brdf, scatter, surfaces
from waveoptics.io import figures
from waveoptics.units import direction_from_angles

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
LAM = 550.0


def _time(fn, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def timing_table() -> list:
    """Footprints per second of the per-pixel sums (scatter.pixel_brdf) at real footprint sizes, footprints on a
    lattice 2σ apart as a render's pixels."""
    from waveoptics.surfaces import tiled

    field = tiled.procedural("psd", 2e-3, 0.1e-6, seed=3)
    wi, wo = direction_from_angles(30.0, 0.0), direction_from_angles(28.0, 181.0)
    lam = [450.0, 500.0, 550.0, 600.0, 650.0]
    rows = []
    for sig in (1e-6, 2e-6, 5e-6, 10e-6, 30e-6):
        m = max(2, int(round(8 * 2e-6 / sig)))          # m × m footprints 2σ apart (a render's pixel pitch)
        n = m * m
        fps = [surfaces.Footprint(300e-6 + 2 * sig * a, 300e-6 + 2 * sig * b, sig) for a in range(m)
               for b in range(m)]
        cells = []
        for backend, prec in (("opencl", "float64"), ("opencl", "float32"), ("numpy", None)):
            if backend == "numpy" and sig > 5e-6:
                cells.append(None)
                continue
            k = n if backend == "opencl" else max(1, n // 16)
            scatter.pixel_brdf(field, fps[:1], wi, wo, lam, "Al", backend=backend, precision=prec)   # build
            r = scatter.pixel_brdf(field, fps[:k], wi, wo, lam, "Al", backend=backend, precision=prec)
            t = r.timings_s["sums"]
            cells.append({"per_s": k / t, "msamples_per_s": r.samples / t / 1e6})
        rows.append({"sigma_um": sig * 1e6, "samples_per_footprint": r.samples / max(1, k), "cells": cells})
    return rows


def figure(field, scratched) -> None:
    wi = direction_from_angles(30.0, 0.0)
    grid = scatter.DirectionGrid.hemisphere(96)
    plt = figures.pyplot()
    fig, axes = plt.subplots(2, 4, figsize=(13.5, 6.8), layout="constrained")
    for ax, x in zip(axes[0], (8e-6, 16e-6, 24e-6, 32e-6)):
        r = scatter.footprint_scatter(field, surfaces.Footprint(x, 20e-6, 1.5e-6), wi, [LAM], "Al", grid=grid)
        im = ax.imshow(np.log10(np.maximum(r.brdf[0], 1e-4)), extent=[-1, 1, -1, 1], origin="lower",
                       cmap="magma", vmin=-4, vmax=2.5)
        ax.set_title(f"wave BRDF at x = {x * 1e6:g} µm", fontsize=9)
        ax.set_xlabel("u = sinθ cosφ")
        ax.set_ylabel("v = sinθ sinφ")
    fig.colorbar(im, ax=axes[0, :].tolist(), label="log10 f (1/sr)", shrink=0.9)
    for ax, x in zip(axes[1], (7e-6, 12e-6, 18e-6, 23e-6)):
        t = brdf.footprint_ndf(scratched, surfaces.Footprint(x, 15e-6, 1.5e-6), bins=48)
        im2 = ax.imshow(t.P, extent=[-t.L, t.L, -t.L, t.L], origin="lower", cmap="viridis")
        ax.set_title(f"scratches: footprint NDF at x = {x * 1e6:g} µm", fontsize=9)
        ax.set_xlabel("slope x̃ = −m_x/m_z")
        ax.set_ylabel("slope ỹ = −m_y/m_z")
    fig.colorbar(im2, ax=axes[1, :].tolist(), label="P22 (per slope²)", shrink=0.9)
    fig.suptitle("One surface, different pixels: Gaussian footprints σ_p = 1.5 µm (top: Gaussian random Al surface, "
                 "σ = 20 nm, T = 1 µm, light at θ_i = 30°, φ_i = 0 (on the +x side), 550 nm; bottom: scratches "
                 "along x)", fontsize=9)
    figures.save_figure(fig, IMG / "glints_footprints.png")


def glint_section():
    """The glint scene: a brushed-aluminium sphere and a flake sphere at real scale, rendered by the command line
    (its estimate, its per-pixel cost); returns one row per scene (the images are copied to docs/img)."""
    import contextlib
    import io
    import json
    import shutil
    import tempfile

    from waveoptics.cli import main as cli

    def render(surface, size, out, *extra):
        buf, err = io.StringIO(), io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(err):
            rc = cli(["render", "--glints", "--surface", surface, "--material", "Al", "--sphere-size", str(size),
                      "--shape", "sphere", "--incident", "40,150", "--view", "25,200", "-o", str(out), "--json",
                      *extra])
        if rc != 0:
            raise SystemExit("glint render failed: " + err.getvalue()[-2000:])
        return json.loads(buf.getvalue()), time.perf_counter() - t0

    rows = []
    with tempfile.TemporaryDirectory() as d:
        for key, surface, size in SCENES:
            sm, wall = render(surface, size, Path(d) / key)
            t, e, fs = sm["timings_s"], sm["estimate"], sm["footprint_sigma_m"]
            rows.append({"key": key, "surface": surface, "size": size, "size_px": sm["size_px"], "pixels": t["pixels"],
                         "footprint_sigma_um": [fs[0] * 1e6, fs[1] * 1e6], "estimate_s": e["estimate_s"],
                         "wall_s": t["wall"], "wall_total_s": wall, "cpu_s": t["cpu"],
                         "per_pixel_ms": t["per_pixel"] * 1e3, "footprints_per_s": t["footprints_per_s"],
                         "read_s": t["read"]})
            shutil.copyfile(Path(d) / key / "glints.png", IMG / f"glints_{key}.png")
    return rows


def dask_speedup(size: int = 96, repeats: int = 2) -> dict:
    """The same glint render (brushed sphere, ``size``² px on a field of size/128 mm, as the brushed scene) in this
    process and on a Dask LocalCluster of 1 and of 2 single-threaded worker processes (the executor of
    ``render --glints --workers N``), each worker warmed first (imports, the OpenCL kernel, the material): the wall
    time of the render, best of *repeats* runs taken in turn, the CPU time the workers spent, and the load average
    of the machine before and after (it is shared: other processes take cores meanwhile)."""
    import importlib

    from waveoptics.distributed import dask_client
    from waveoptics.renderers import glints
    from waveoptics.surfaces import tiled

    field = tiled.procedural("brushed", size / 128 * 1e-3, 0.1e-6, seed=1)
    s = glints.GlintSettings(size=size, shape="sphere", light_deg=40.0, light_azimuth_deg=150.0, view_deg=25.0,
                             view_azimuth_deg=200.0)
    tiny = glints.GlintSettings(size=8, shape="sphere", wavelengths_nm=s.wavelengths_nm)
    glints.render_glints(field, "Al", tiny)                              # this process warmed too
    load0 = os.getloadavg()[0]
    runs = {"in_process": [], "1": [], "2": []}
    cpu = {"1": [], "2": []}
    ref = None
    with dask_client(1) as c1, dask_client(2) as c2:
        for c in (c1, c2):
            c.run(importlib.import_module, "waveoptics.renderers.glints")
            c.run(glints.render_glints, field, "Al", tiny)
        for _ in range(repeats):
            t0 = time.perf_counter()
            r = glints.render_glints(field, "Al", s)
            runs["in_process"].append(time.perf_counter() - t0)
            ref = r.wave_spectral if ref is None else ref
            for key, c in (("1", c1), ("2", c2)):
                p0 = sum(c.run(time.process_time).values())
                t0 = time.perf_counter()
                r = glints.render_glints(field, "Al", s, executor=c.get_executor())
                runs[key].append(time.perf_counter() - t0)
                cpu[key].append(sum(c.run(time.process_time).values()) - p0)
                if not np.array_equal(r.wave_spectral, ref):
                    raise SystemExit(f"the render on {key} Dask worker(s) differs from the in-process one")
    best = {k: min(v) for k, v in runs.items()}
    return {"size": size, "surface": f"procedural:brushed:{size / 128:g}mm:0.1um:1", "repeats": repeats,
            "wall_s": {k: round(v, 1) for k, v in best.items()}, "runs_s": runs,
            "worker_cpu_s": {k: round(min(v), 1) for k, v in cpu.items()},
            "speedup_2_over_1": round(best["1"] / best["2"], 2),
            "speedup_2_over_in_process": round(best["in_process"] / best["2"], 2),
            "load_before": round(load0, 2), "load_after": round(os.getloadavg()[0], 2)}


#: image size of the brushed scene (GLINTS_DOC_SIZE); its field is 1 mm per 128 px, so that footprints stay
#: ~2-3 µm (the sphere's pixel pitch is 2.1 R / size with R = 0.9 W / π) and the cost grows as the size squared
DOC_SIZE = int(os.environ.get("GLINTS_DOC_SIZE", "128"))
#: (image name, --surface, image size) of the scenes
SCENES = (("brushed", f"procedural:brushed:{DOC_SIZE / 128:g}mm:0.1um:1", DOC_SIZE),
          ("flakes", f"procedural:flakes:{0.75 * DOC_SIZE / 128:g}mm:0.1um:2", 3 * DOC_SIZE // 4))


def cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()


def compute() -> dict:
    """Every number of docs/glints.md (and its figures): footprint throughput and the two glint renders."""
    IMG.mkdir(parents=True, exist_ok=True)
    field = surfaces.generate("gaussian", sigma="20nm", corr_length="1um", size="40um", samples=1024, seed=3)
    scratched = surfaces.scratches(80, "1um", "60nm", "30um", 512, orientation_deg=0.0, spread_deg=1.0, seed=5)
    figure(field, scratched)
    return {"cores": cores(), "throughput": timing_table(), "scenes": glint_section(), "dask": dask_speedup()}


def main() -> None:
    import make_docs

    make_docs.main(["glints"])


if __name__ == "__main__":
    main()
