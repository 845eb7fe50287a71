"""Data of docs/surfaces.md (docs/data/surfaces.json; prose in docs/templates/surfaces.md) and its figures
(docs/img/surfaces_*.png): height-field generators checked against their closed forms,
PSD fits and the cost of generation, every number computed by the code."""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np

from waveoptics import surfaces as S
from waveoptics.io.files import atomic_path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
IMG = ROOT / "docs" / "img"
SEEDS = range(16)
SIG, T = 5e-9, 1e-6

def _gaussian_table():
    rows = []
    for t_dx, n in ((2, 128), (4, 256), (8, 256), (8, 512), (16, 512), (16, 1024)):
        dx = T / t_dx
        vals = []
        for seed in SEEDS:
            hf = S.gaussian(SIG, T, n * dx, n, seed)
            st = S.stats(hf)
            vals.append([st["rms_height_m"] / SIG, st["corr_length_m"] / T, st["rms_slope"] / (2 * SIG / T),
                         st["beckmann_alpha"] / (2 * SIG / T)])
        v = np.array(vals)
        m, sd = v.mean(0), v.std(0)
        rows.append({"T_over_dx": t_dx, "samples": n, "resolved_fraction": hf.meta["psd_variance_fraction"],
                     "means": m, "spreads": sd[:3]})
    return rows


def _fit_table():
    cases = [
        ("gaussian σ=5 nm, T=1 µm", lambda s: S.gaussian(SIG, T, 64e-6, 512, s), "gaussian",
         {"sigma_m": SIG, "corr_length_m": T}),
        ("gaussian profile 1×8192", lambda s: S.gaussian(SIG, T, 1024e-6, (8192, 1), s), "gaussian",
         {"sigma_m": SIG, "corr_length_m": T}),
        ("exponential σ=5 nm, T=1 µm", lambda s: S.exponential(SIG, T, 128e-6, 1024, s, renormalize=False),
         "exponential", {"sigma_m": SIG, "corr_length_m": T}),
        ("ABC σ=5 nm, B=4 µm, C=3.5", lambda s: S.abc(4e-6, 3.5, 128e-6, 1024, s, sigma=SIG), "abc",
         {"sigma_m": SIG, "B_m": 4e-6, "C": 3.5}),
    ]
    rows = []
    for name, make, model, truth in cases:
        fits = [S.fit_psd(make(s), model) for s in SEEDS]
        cells = []
        for k, v in truth.items():
            r = np.array([f[k] / v for f in fits])
            cells.append({"parameter": k, "mean": r.mean(), "std": r.std()})
        rows.append({"surface": name, "model": model, "parameters": cells})
    return rows


def _psd_integral_table():
    rows = []
    for name, make in (("gaussian 512², T = 8 dx", lambda s: S.gaussian(SIG, T, 64e-6, 512, s)),
                       ("exponential 512², T = 8 dx", lambda s: S.exponential(SIG, T, 64e-6, 512, s)),
                       ("ABC 512², B = 32 dx, C = 3.5", lambda s: S.abc(4e-6, 3.5, 64e-6, 512, s, sigma=SIG))):
        for window in ("auto", "hann"):
            r = []
            for seed in SEEDS:
                hf = make(seed)
                f, P = S.psd_radial(hf, window=window)
                integral = np.trapezoid(2 * np.pi * np.r_[0, f] * np.r_[P[0], P], np.r_[0, f])
                r.append(integral / np.mean(hf.heights ** 2))
            rows.append({"surface": name, "window": window, "mean": np.mean(r), "std": np.std(r)})
    return rows


def _timing_table():
    rows = []
    for model, params in (("gaussian", {"sigma": SIG, "corr_length": T}),
                          ("abc", {"sigma": SIG, "B": 4e-6, "C": 3.5}),
                          ("scratches", {"count": 50, "width": 1e-6, "depth": 20e-9})):
        for n in (512, 2048):
            t0 = time.perf_counter()
            hf = S.generate(model, size=n * T / 8, samples=n, seed=1, **params)
            t1 = time.perf_counter()
            S.stats(hf)
            t2 = time.perf_counter()
            S.fit_psd(hf, "abc" if model == "abc" else "gaussian")
            t3 = time.perf_counter()
            rows.append({"model": model, "samples": n, "generate_s": t1 - t0, "stats_s": t2 - t1,
                         "fit_psd_s": t3 - t2})
    return rows


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    size, n = 32e-6, 256
    fields = [("gaussian σ=5 nm, T=1 µm", S.gaussian(SIG, T, size, n, 1)),
              ("exponential σ=5 nm, T=1 µm", S.exponential(SIG, T, size, n, 1)),
              ("ABC σ=5 nm, B=4 µm, C=3.5", S.abc(4e-6, 3.5, size, n, 1, sigma=SIG)),
              ("sinusoid a=5 nm, Λ=4 µm, 30°", S.sinusoid(5e-9, 4e-6, size, n, orientation_deg=30)),
              ("scratches 20 × (0.5 µm, 20 nm)", S.scratches(20, 0.5e-6, 20e-9, size, n, 20, 10, seed=1)),
              ("micro (T=4 µm) + nano (T=0.3 µm)", S.gaussian(8e-9, 4e-6, size, n, 1)
               + S.gaussian(2e-9, 0.3e-6, size, n, 2))]
    fig, axes = plt.subplots(2, 3, figsize=(13, 8))
    for ax, (title, hf) in zip(axes.ravel(), fields):
        x, y = hf.coords()
        im = ax.imshow(hf.heights * 1e9, origin="lower", cmap="viridis",
                       extent=[x[0] * 1e6, x[-1] * 1e6, y[0] * 1e6, y[-1] * 1e6])
        fig.colorbar(im, ax=ax, label="height (nm)", shrink=0.8)
        ax.set(title=title, xlabel="x (µm)", ylabel="y (µm)")
    fig.tight_layout()
    out1 = IMG / "surfaces_models.png"
    with atomic_path(out1) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for label, hf, model, args in (
            ("gaussian", S.gaussian(SIG, T, 64e-6, 512, 3), S.S_gaussian, (SIG, T)),
            ("exponential", S.exponential(SIG, T, 64e-6, 512, 3, renormalize=False), S.S_exponential, (SIG, T)),
            ("ABC", S.abc(4e-6, 3.5, 64e-6, 512, 3, sigma=SIG), S.S_abc, (SIG, 4e-6, 3.5))):
        f, P = S.psd_radial(hf)
        line, = ax.loglog(f * 1e-6, P, ".", ms=2, alpha=0.6, label=f"{label}: radial periodogram")
        ax.loglog(f * 1e-6, model(f, *args), color=line.get_color(), lw=1.2, label=f"{label}: closed form")
    ax.set(xlabel="|f| (1/µm)", ylabel="S(f) (m⁴)", ylim=(1e-38, 1e-26))
    ax.legend(fontsize=8)
    fig.tight_layout()
    out2 = IMG / "surfaces_psd.png"
    with atomic_path(out2) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    plt.close(fig)
    return out1.name, out2.name


def compute() -> dict:
    """Every number of docs/surfaces.md; draws its two figures."""
    IMG.mkdir(parents=True, exist_ok=True)
    img_models, img_psd = _figure()
    A = S.abc_A(SIG, 4e-6, 3.5)
    return {"seeds": len(SEEDS), "img_models": img_models, "img_psd": img_psd, "gaussian": _gaussian_table(),
            "psd_integral": _psd_integral_table(), "fits": _fit_table(),
            "abc": {"A_m4": A, "sigma_nm": S.abc_sigma(A, 4e-6, 3.5) * 1e9}, "timing": _timing_table(),
            "load_average_1min": os.getloadavg()[0], "cores": os.cpu_count()}


def main():
    import make_docs

    make_docs.main(["surfaces"])


if __name__ == "__main__":
    main()
