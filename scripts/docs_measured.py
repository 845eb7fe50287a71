"""Data of docs/measured-surfaces.md (docs/data/measured.json; prose in docs/templates/measured.md), the figures
docs/img/measured_*.png and the sample docs/data/brushed_aluminium.x3p:
the measured-surface workflow — read an instrument file, level, crop, split the scales, simulate, compare — run
through the command line exactly as a user types it, every output printed here produced by that run."""
from __future__ import annotations

import contextlib
import io
import json
import shlex
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

from waveoptics import surfaces as S
from waveoptics.cli import main as cli
from waveoptics.io.files import atomic_path

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
SAMPLE = ROOT / "docs" / "data" / "brushed_aluminium.x3p"
SAMPLE_REL = "docs/data/brushed_aluminium.x3p"


def make_sample(path: Path = SAMPLE) -> Path:
    """A synthetic interferometer map of brushed aluminium, written by SurfaceTopography's X3P writer (ISO 5436-2,
    32-bit floats, heights in µm): parallel scratches along x (the micro scale) plus an ABC polish (the nano
    scale), a tilt of the mounted sample (0.4 µm over the field) and 0.5 % drop-outs, as instruments deliver."""
    from SurfaceTopography import Topography

    n, dx = 256, 90e-9
    size = f"{n * dx * 1e6:.6g}um"
    micro = S.scratches(120, "1.5um", "40nm", size, n, orientation_deg=0.0, spread_deg=3.0, variation=0.5, seed=11)
    nano = S.abc("2um", 2.6, size, n, seed=12, sigma="4nm")
    hf = micro + nano
    x, y = hf.coords()
    tilt = 0.4e-6 * (x[None, :] - x[0]) / (x[-1] - x[0]) + 0.1e-6 * (y[:, None] - y[0]) / (y[-1] - y[0])
    h_um = (hf.heights + tilt) * 1e6
    rng = np.random.default_rng(13)
    dropped = rng.random(h_um.shape) < 0.005
    h = np.ma.masked_array(h_um.T, mask=dropped.T)            # SurfaceTopography's layout: h[ix, iy]
    topo = Topography(h, (n * dx * 1e6, n * dx * 1e6), unit="µm")
    with atomic_path(path, overwrite=True) as tmp:
        topo.to_x3p(str(tmp), dtype="F", manufacturer="waveoptics docs",
                    model="synthetic white-light interferometer map")
    return path


def _run(argv: str, cwd: Path) -> str:
    """Run ``waveoptics ARGV`` in *cwd* in-process; its stdout (the command must succeed)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = cli(shlex.split(argv))
    if rc != 0:
        raise RuntimeError(f"waveoptics {argv} failed: {err.getvalue()}")
    return out.getvalue().rstrip()


#: the worked example's commands, in order (key -> argv); their explanations are in the template
STEPS = {
    "look": f"surface stats {SAMPLE_REL}",
    "prepare": f"surface prepare {SAMPLE_REL} --detrend plane --crop 0um,0um,20um,20um -o prepared.npz",
    "measure": "surface stats prepared.npz --fit abc",
    "simulate": "simulate --surface prepared.npz --split --material Al --incident 30 --wavelengths 400:700:50nm "
                "--resolution 96 --sphere-size 160 -o measured_run",
    "deform": "surface transform prepared.npz --stretch 1.5,1 --rotate 30 -o deformed.npz",
    "compare": "compare --surface prepared.npz --split --material Al --wavelengths 400:700:100nm --resolution 64 "
               "--angles 0:60:30",
}


def _sphere_figure(run: Path, path: Path) -> None:
    """The run's two sphere renders side by side with their ΔE2000, titled, with the light direction."""
    from waveoptics import colour
    from waveoptics.renderers import sphere as render
    from waveoptics.io.files import read_exr

    imgs = []
    for name in ("sphere_wave.exr", "sphere_microfacet.exr"):
        ch, _ = read_exr(run / name)
        rgb = ch["RGB"] if "RGB" in ch else np.stack([ch["R"], ch["G"], ch["B"]], axis=-1)   # bindings may group
        imgs.append(np.asarray(rgb, dtype=float))
    summary = json.loads((run / "summary.json").read_text())
    lum = colour.luminance(imgs[0])
    pos = lum[lum > 1e-8]
    exposure = min(0.18 / float(np.exp(np.mean(np.log(pos)))), 4.0)
    n = imgs[0].shape[0]
    yy, xx = np.mgrid[:n, :n]
    on = (xx + 0.5 - n / 2) ** 2 + (yy + 0.5 - n / 2) ** 2 <= (n / 2) ** 2     # the sphere's disc
    dE = np.full(on.shape, np.nan)
    dE[on] = colour.delta_e2000(imgs[0][on], imgs[1][on])
    render.plot_spheres([render.tonemap(i, exposure) for i in imgs],
                        ["two-scale (wave optics)", "microfacet only"], path, diff=dE,
                        light_deg=tuple(summary["parameters"]["incident_deg"]), exposure=exposure)


def _ndf_figure(before: Path, after: Path, path: Path) -> None:
    """2-D histograms of the slopes (∂h/∂x, ∂h/∂y) of two height fields, side by side, log density."""
    from matplotlib.colors import LogNorm

    from waveoptics.io import figures

    plt = figures.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(8.4, 3.9), constrained_layout=True)
    lim = 0.0
    slopes = []
    for p in (before, after):
        hf = S.load(p)
        gy, gx = np.gradient(hf.heights, hf.dy, hf.dx)
        ok = hf.valid.copy()
        ok[:, [0, -1]] = False
        ok[[0, -1], :] = False
        slopes.append((gx[ok], gy[ok]))
        lim = max(lim, float(np.percentile(np.hypot(gx[ok], gy[ok]), 99.5)))
    for ax, (gx, gy), title in zip(axes, slopes, ("prepared", "stretched 1.5 along x, turned 30°")):
        hist = ax.hist2d(gx, gy, bins=81, range=[[-lim, lim], [-lim, lim]], density=True, norm=LogNorm(),
                         cmap="magma")
        ax.set_title(f"slope distribution: {title}", fontsize=9)
        ax.set_xlabel("slope ∂h/∂x")
        ax.set_ylabel("slope ∂h/∂y")
        ax.set_aspect("equal")
    fig.colorbar(hist[3], ax=axes, label="density of slopes (log)", shrink=0.85)
    figures.save_figure(fig, path)


def compute() -> dict:
    """Run the worked example's commands in a scratch folder: what each printed and how long it took, what
    summary.json recorded of the surface (as written, key order kept) and the largest micro α; the figures."""
    if not SAMPLE.exists():   # the shipped sample stays as it is (its acquisition time is part of the page)
        make_sample()
    IMG.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="wo-measured-"))
    (tmp / "docs" / "data").mkdir(parents=True)
    shutil.copy(SAMPLE, tmp / SAMPLE_REL)
    steps = {}
    try:
        for key, argv in STEPS.items():
            t0 = time.perf_counter()
            out = _run(argv, tmp)
            steps[key] = {"argv": argv, "output": out, "seconds": time.perf_counter() - t0}
        summary = json.loads((tmp / "measured_run" / "summary.json").read_text())
        _sphere_figure(tmp / "measured_run", IMG / "measured_spheres.png")
        _ndf_figure(tmp / "prepared.npz", tmp / "deformed.npz", IMG / "measured_ndf_transform.png")
        info = summary["parameters"]["surface_info"]
        split = summary["parameters"]["split"]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return {"sample": SAMPLE_REL, "steps": steps, "micro_alpha_max": max(split["micro_alpha"]),
            "recorded_json": json.dumps({"surface_info": info, "split": split}, indent=2, ensure_ascii=False)}


def main() -> None:
    import make_docs

    make_docs.main(["measured"])


if __name__ == "__main__":
    main()
