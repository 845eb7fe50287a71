"""Write docs/measured-surfaces.md (+ docs/img/measured_*.png and the sample docs/data/brushed_aluminium.x3p):
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
DOC = ROOT / "docs" / "measured-surfaces.md"
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


STEPS = [
    ("Look at the file", "What the instrument wrote: grid, spacing, the unit the file states (X3P stores metres), "
                         "the drop-outs (valid fraction). The tilt dominates the raw map: compare its rms height "
                         "and correlation length with those of the levelled map below.",
     f"surface stats {SAMPLE_REL}"),
    ("Level and crop", "Remove the tilt of the mounted sample (least-squares plane) and keep a region. The .npz "
                       "output keeps the whole provenance (format, instrument, acquisition time, region, "
                       "levelling); an .x3p output would record SurfaceTopography as its instrument.",
     f"surface prepare {SAMPLE_REL} --detrend plane --crop 0um,0um,20um,20um -o prepared.npz"),
    ("Measure it", "Statistics of the prepared field and an ABC fit of its PSD (the nano-scale statistics).",
     "surface stats prepared.npz --fit abc"),
    ("Split the scales and simulate",
     "`--split` cuts the field at a period of 10 λmax: the long-period part becomes the micro NDF (its α is "
     "measured from its slopes), the short-period part is the nano height field that diffracts.",
     "simulate --surface prepared.npz --split --material Al --incident 30 --wavelengths 400:700:50nm "
     "--resolution 96 --sphere-size 160 -o measured_run"),
    ("Deform it", "Stretch the surface by 1.5 along x and turn it by 30° (Nagano et al. 2015 model skin "
                  "microstructure under strain this way): slopes along a stretched axis fall by the stretch factor, "
                  "and the NDF turns with the surface (figure below).",
     "surface transform prepared.npz --stretch 1.5,1 --rotate 30 -o deformed.npz"),
    ("Compare over incidence", "The same surface, two-scale against the microfacet model at several angles.",
     "compare --surface prepared.npz --split --material Al --wavelengths 400:700:100nm --resolution 64 "
     "--angles 0:60:30"),
]


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


def main() -> None:
    if not SAMPLE.exists():   # the shipped sample stays as it is (its acquisition time is part of the page)
        make_sample()
    IMG.mkdir(parents=True, exist_ok=True)
    parts = ["# Measured surfaces: from an instrument file to appearance\n",
             "*Generated by `scripts/docs_measured.py` — do not edit by hand: every output below is what the "
             "commands printed in that run.*\n",
             "Profilometers, white-light interferometers, confocal microscopes and AFMs write their height maps in "
             "their own formats. waveoptics reads them through "
             "SurfaceTopography (the PyPI package of Pastewka et al., the surface-metrology community's reader of instrument formats) "
             "(`pip install 'waveoptics[instruments]'`; `make setup` installs it): .x3p (ISO 5436-2), .sdf "
             "(ISO 25178-71), .sur and .mnt (Digital Surf), .datx and binary .dat (Zygo), .opd and .opdx "
             "(Bruker/Wyko, Dektak), .plu/.plux (Sensofar), .vk4/.vk6 (Keyence), .al3d (Alicona), .gwy "
             "(Gwyddion), .nc (NetCDF), .spm (Bruker Nanoscope), .ibw (Igor), .mdt (NT-MDT) and more "
             "(`waveoptics.surfaces.instruments.INSTRUMENT_EXTS`). It writes .x3p, .gwy and .nc. Its own "
             "readers remain for .npz, .npy (+ JSON sidecar), .exr and text grids.\n",
             "## Options that complete a file's metadata\n",
             "Every command that takes a height field (`scatter`, `simulate`, `compare`, `brdf`, `cost`, "
             "`surface stats`, `surface prepare`, and `file = {...}` in scene files) has the same three:\n",
             "| option | meaning |\n|---|---|\n"
             "| `--units UNIT` | unit of heights and lengths, for a file that does not state it (m, mm, um, nm, pm, "
             "A); a unit that contradicts the file's own is refused |\n"
             "| `--spacing D[,DY]` | grid spacing with its unit, for a file that does not state its size; it "
             "overrides the file's spacing otherwise |\n"
             "| `--channel N\\|NAME` | the data channel of a multi-channel file (AFM: height, amplitude, phase; "
             "default: the file's height channel) |\n",
             "Samples the instrument marks as undefined become the height field's mask: they are left out of the "
             "statistics and of the scattering aperture. The format, channel, unit of the file, instrument and "
             "acquisition time are kept in the height field (`HeightField.provenance()`) and written as "
             "`surface_info` into `summary.json` of `simulate` and `scatter` and into `surface stats --json`.\n",
             "## A worked example\n",
             f"The sample `{SAMPLE_REL}` was written by SurfaceTopography's X3P writer (`make_sample()` in the "
             "script): brushed aluminium, parallel scratches 1.5 µm wide and 40 nm deep along x with an ABC polish "
             "of σ = 4 nm, a 256² map at 90 nm spacing (heights given to the writer in µm), tilted by 0.4 µm across the field as a mounted "
             "sample is, with 0.5 % drop-outs. Run the steps from the repository root.\n"]
    tmp = Path(tempfile.mkdtemp(prefix="wo-measured-"))
    (tmp / "docs" / "data").mkdir(parents=True)
    shutil.copy(SAMPLE, tmp / SAMPLE_REL)
    try:
        for title, text, argv in STEPS:
            t0 = time.perf_counter()
            out = _run(argv, tmp)
            dt = time.perf_counter() - t0
            parts.append(f"### {title}\n\n{text}\n\n```console\n$ waveoptics {argv}\n{out}\n```\n"
                         f"*({dt:.1f} s on the machine that generated this page.)*\n")
        summary = json.loads((tmp / "measured_run" / "summary.json").read_text())
        _sphere_figure(tmp / "measured_run", IMG / "measured_spheres.png")
        _ndf_figure(tmp / "prepared.npz", tmp / "deformed.npz", IMG / "measured_ndf_transform.png")
        info = summary["parameters"]["surface_info"]
        split = summary["parameters"]["split"]
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    parts.append("### What the run recorded\n\n`summary.json` → `parameters.surface_info` (the provenance of the "
                 "nano height field that was simulated) and `parameters.split`:\n\n```json\n"
                 + json.dumps({"surface_info": info, "split": split}, indent=2, ensure_ascii=False)
                 + "\n```\n")
    parts.append("![Spheres of the measured surface: two-scale wave optics, microfacet only, and their ΔE2000]"
                 "(img/measured_spheres.png)\n\n"
                 "With the split at 10 λmax almost all of this sample's slope is nano-scale: the micro α is "
                 f"{max(split['micro_alpha']):.2g}, so geometric optics sees a near-mirror whose highlight of a "
                 "directional light is smaller than a pixel (the dark middle sphere), while wave optics spreads the "
                 "light into the coloured streak across the scratches and a halo from the polish.\n")
    parts.append("### The NDF before and after the deformation\n\n"
                 "![Slope distributions (the NDF in slope space) of the prepared and the deformed surface]"
                 "(img/measured_ndf_transform.png)\n\n"
                 "The slope distribution of a height field is its NDF in slope space (D(m) = P22(−m_x/m_z, "
                 "−m_y/m_z)/cos⁴θ_m, physics.md §6). The scratches along x put the slopes along y; stretching by 1.5 "
                 "along x compresses the x slopes, and the rotation turns the whole distribution by 30°.\n")
    parts.append("## Limits\n\n"
                 "- Non-uniform line scans (samples at irregular positions, some stylus profilometers) are refused: "
                 "the solvers need a regular grid. Resample them first (SurfaceTopography's `to_uniform`).\n"
                 "- Levelling removes a plane only; curved parts (ISO 25178's form removal by polynomials) need "
                 "SurfaceTopography's `detrend(detrend_mode='curvature')` before export.\n"
                 "- A map's spacing limits the directions it can scatter to: spacing ≤ λ/4 covers the whole "
                 "hemisphere (physics.md §1); coarser maps get an aliasing warning.\n"
                 "- An .x3p, .gwy or .nc written by waveoptics records SurfaceTopography as its instrument (X3P has "
                 "one instrument record); write .npz to keep the original instrument in the file.\n"
                 "- The split at 10 λmax is fixed: on this sample the 1.5 µm scratches fall below the cut-off and "
                 "diffract as nano-geometry (the micro α is ~0.002): periods below 10 λ deflect light by more than 6°, "
                 "where only diffraction describes them (`waveoptics.brdf.twoscale.split_scales`).\n")
    with atomic_path(DOC, overwrite=True) as t:
        t.write_text("\n".join(parts))


if __name__ == "__main__":
    main()
