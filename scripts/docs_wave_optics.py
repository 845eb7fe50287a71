"""Data of docs/wave-optics.md (docs/data/wave_optics.json) and docs/img/wave_optics_*.png: the numbers of the
Kirchhoff-scattering sections. All prose, the height-field sections included, is in docs/templates/wave_optics.md.
Every number and figure is computed here by the code."""
from __future__ import annotations

import math
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.special import jv

from waveoptics import brdf, scatter
from waveoptics import surfaces
from waveoptics.io.files import atomic_path
from waveoptics.units import direction_from_angles

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img"
LAM = 550.0
L = LAM * 1e-9


def _quiet(fn, *a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scatter.DiffractionWarning)
        return fn(*a, **kw)


def _runtime():
    try:
        from waveoptics.runtime import get_runtime, opencl_available

        return get_runtime() if opencl_available() else None
    except Exception:  # noqa: BLE001 - the page still documents the NumPy parts
        return None


# ----------------------------------------------------------------------------------------------------------------
# measurements


def _flat_table(rt) -> list:
    """Albedo over F(θ_i) of a flat patch per incidence and solver."""
    from waveoptics.materials import get_material

    mat = get_material("1.5")
    wl = np.array([450.0, 550.0, 650.0])
    rows = []
    for theta in (0.0, 30.0, 60.0, 75.0):
        for solver in ("fft", "direct") if rt is not None else ("fft",):
            hf = surfaces.flat(28.8e-6, 256)
            res = _quiet(scatter.scatter, hf, (theta, 0.0), wl, mat, solver=solver, resolution=128, runtime=rt)
            r = res.albedo / mat.F(math.cos(math.radians(theta)), wl)
            rows.append({"theta_deg": theta, "solver": solver, "ratios": r})
    return rows


def _coherent_table() -> list:
    """Coherent and scattered fractions of Gaussian surfaces against exp(−g) and TIS."""
    rows = []
    F = 0.9
    for sigma in (10e-9, 20e-9, 40e-9):
        for theta in (0.0, 30.0, 60.0):
            res = _quiet(scatter.scatter, lambda s: surfaces.gaussian(sigma, 1e-6, 256 * L / 4, 256, seed=s),
                         (theta, 0.0), [LAM], F, resolution=128, realizations=8, seed=100)
            g = (4 * np.pi * sigma * math.cos(math.radians(theta)) / L) ** 2
            rows.append({"sigma_nm": sigma * 1e9, "theta_deg": theta, "g": g, "exp_g": math.exp(-g),
                         "coherent": res.coherent_specular_fraction[0], "tis": F * (1 - math.exp(-g)),
                         "scattered": res.scattered_fraction[0], "albedo_over_F": res.albedo[0] / F})
    return rows


def _grating(theta=20.0, amplitudes=(20e-9, 60e-9, 120e-9), solver="fft", rt=None):
    period = 8 * L
    grid = scatter.DirectionGrid(256, 64, (-1, 1), (-0.25, 0.25))
    si, ci = math.sin(math.radians(theta)), math.cos(math.radians(theta))
    out = {}
    for a in amplitudes:
        hf = surfaces.sinusoid(a, period, (64 * L, 16 * L), (256, 64))
        res = _quiet(scatter.scatter, hf, (theta, 0.0), [LAM], grid=grid, solver=solver, runtime=rt)
        rows = []
        for m in range(-5, 6):
            um = -(si + m * L / period)
            if abs(um) >= 0.97:
                continue
            box = np.broadcast_to(np.abs(grid.u - um)[None, :] < 0.5 * L / period, grid.inside.shape)
            eta = scatter.integrate(res.brdf[0], grid, region=box)
            cm = math.sqrt(1 - um**2)
            s2 = (si + um) ** 2 + (ci + cm) ** 2
            pred = s2**2 / (4 * ci * cm * (ci + cm) ** 2) * jv(m, 2 * np.pi / L * a * (ci + cm)) ** 2
            rows.append((m, eta, pred, jv(m, 4 * np.pi * a * ci / L) ** 2))
        out[a] = (res, rows)
    return out, grid


def _grating_table(gr) -> list:
    """Per amplitude: the orders, the largest error against O_m J_m², the albedo and the paraxial error."""
    return [{"a_nm": a * 1e9, "orders": [rows[0][0], rows[-1][0]], "error": max(abs(e - p) for _, e, p, _ in rows),
             "albedo": sum(e for _, e, _, _ in rows), "paraxial": max(abs(e - q) for _, e, _, q in rows)}
            for a, (res, rows) in gr.items()]


def _beckmann(realizations=64):
    sigma, alpha = L, 0.3
    T = 2 * sigma / alpha
    grid = scatter.DirectionGrid.hemisphere(64)
    make = lambda s: surfaces.gaussian(sigma, T, 128 * L / 2, 128, seed=s)  # noqa: E731
    res = _quiet(scatter.scatter, make, (0.0, 0.0), [LAM], grid=grid, realizations=realizations, seed=100)
    res0 = _quiet(scatter.scatter, make, (0.0, 0.0), [LAM], grid=grid, realizations=realizations, seed=100, order=0)
    d = grid.directions()
    h = brdf.half_vector(res.incident, d)
    fb = np.where(grid.inside, brdf.D(h, alpha, ndf="beckmann") / (4 * np.maximum(d[..., 2], 1e-9)), 0.0)
    th_h = np.degrees(np.arccos(np.clip(h[..., 2], -1, 1)))
    # the ensemble's own rms slope (spectral derivative of each field): the fields keep the PSD where the grid
    # resolves it, so their expected rms slope is α, but 64 fields scatter about it
    fx = 2j * np.pi * np.fft.fftfreq(128, L / 2)
    slope2 = [np.mean(np.abs(np.fft.ifft2(fx[None, :] * H)) ** 2 + np.abs(np.fft.ifft2(fx[:, None] * H)) ** 2)
              for H in (np.fft.fft2(make(100 + r).heights) for r in range(realizations))]
    alpha_r = float(np.sqrt(np.mean(slope2)))
    fr = np.where(grid.inside, brdf.D(h, alpha_r, ndf="beckmann") / (4 * np.maximum(d[..., 2], 1e-9)), 0.0)
    rings, rings_r = [], []
    for a in range(0, 40, 4):
        m = grid.inside & (th_h >= a) & (th_h < a + 4)
        rings.append((a, res.brdf[0][m].mean() / fb[m].mean(), res0.brdf[0][m].mean() / fb[m].mean()))
        rings_r.append(res.brdf[0][m].mean() / fr[m].mean())
    return res, res0, fb, rings, grid, th_h, alpha_r, rings_r


def _beckmann_table(res, res0, fb, rings, grid, th_h, alpha_r, rings_r) -> dict:
    """Ring ratios to Beckmann (α = 0.3 and the ensemble's rms slope) of the exact and the order-0 lobe, and the
    albedos."""
    return {"rings": [list(r) for r in rings], "albedo": res.albedo[0], "albedo_inner": res.albedo_inner[0],
            "albedo_order0": res0.albedo[0], "albedo_order0_inner": res0.albedo_inner[0],
            "beckmann_albedo": scatter.integrate(fb, grid), "alpha_realized": alpha_r, "rings_realized": rings_r}


def _frozen_table() -> list:
    """Relative error of the frozen-v_z lobe in rings about the mirror direction, and the auto order's bands."""
    rows = []
    for name, sigma, T in (("σ = λ/20, T = 2λ", L / 20, 2 * L), ("σ = λ/4, T = 4λ", L / 4, 4 * L),
                           ("σ = λ, T = 6.7λ", L, 6.7 * L)):
        hf = surfaces.gaussian(sigma, T, 64 * L, 256, seed=5)
        smp = scatter.samples(hf)
        wi = scatter.grid.incident_dirs((30.0, 0.0))
        grid = scatter.DirectionGrid.hemisphere(96)
        d = grid.directions()
        f0 = scatter.brdf_from_field(scatter.field_fft(smp, wi, grid, LAM, 0)[0][None], wi, d, [LAM], smp.area)[0]
        Ua, info = scatter.field_fft(smp, wi, grid, LAM)
        fa = scatter.brdf_from_field(Ua[None], wi, d, [LAM], smp.area)[0]
        dist = np.hypot(d[..., 0] + wi[0], d[..., 1] + wi[1])
        cells = []
        for r0, r1 in ((0, 0.05), (0.05, 0.2), (0.2, 0.5), (0.5, 1.0), (1.0, 2.0)):
            m = grid.inside & (dist >= r0) & (dist < r1)
            cells.append(abs(f0[m].sum() / fa[m].sum() - 1) if m.any() and fa[m].sum() > 0 else None)
        rows.append({"surface": name, "rings": cells, "bands": info["bands"], "terms": info["max_order"] + 1})
    return rows


def _cost_table(rt):
    """Seconds per wavelength of each solver at two sizes, and the float32 phase error on a long strip."""
    rows = []
    phase = None
    for n, res_ in ((128, 128), (256, 256)):
        hf = surfaces.gaussian(L / 4, 4 * L, n * L / 4, n, seed=1)
        smp = scatter.samples(hf)
        grid = scatter.DirectionGrid.hemisphere(res_)
        dirs = grid.directions()[grid.inside]
        nd = dirs.shape[0]
        wi = scatter.grid.incident_dirs((30.0, 0.0))
        for order in (0, "auto"):
            t = time.perf_counter()
            _, info = scatter.field_fft(smp, wi, grid, LAM, order)
            dt = time.perf_counter() - t
            sol = {"kind": "fft", "order": 0} if order == 0 else \
                {"kind": "fft", "order": "auto", "bands": info["bands"], "transforms": info["transforms"]}
            rows.append({"patch": n, "grid": res_, "directions": nd, "solver": sol, "seconds": dt,
                         "gterms_per_s": None})
        coef = scatter.phase_coefficients(smp, wi, dirs, [LAM])
        if rt is not None:
            for prec in ("float32", "float64") if rt.fp64 else ("float32",):
                scatter.kirchhoff_U_cl(smp, coef.take(slice(0, 64)), runtime=rt, precision=prec)   # build + warm up
                t = time.perf_counter()
                scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=prec)
                dt = time.perf_counter() - t
                rows.append({"patch": n, "grid": res_, "directions": nd, "seconds": dt,
                             "solver": {"kind": "opencl", "precision": prec},
                             "gterms_per_s": smp.size * nd / dt / 1e9})
        sub = coef.take(slice(0, 256))
        t = time.perf_counter()
        scatter.kirchhoff_U(smp, sub)
        dt = (time.perf_counter() - t) * nd / sub.size
        rows.append({"patch": n, "grid": res_, "directions": nd, "solver": {"kind": "numpy"}, "seconds": dt,
                     "gterms_per_s": smp.size * nd / dt / 1e9})
    if rt is not None:
        nx = 2**16
        hf = surfaces.HeightField(np.random.default_rng(7).normal(0.0, 50e-9, (2, nx)), L / 4)
        smp = scatter.samples(hf, "boxcar")
        wi = scatter.grid.incident_dirs((60.0, 0.0))
        wo = np.array([[-math.sin(math.radians(75)), 0.0, math.cos(math.radians(75))]])
        coef = scatter.phase_coefficients(smp, wi, wo, [LAM])
        ref = scatter.kirchhoff_phase(smp.ix, smp.iy, smp.h, coef.Ax[0], coef.Ay[0], coef.lox[0], coef.loy[0], coef.cz[0],
                                coef.c0[0])
        e = scatter.kirchhoff_phase_cl(smp, coef, 0, runtime=rt, precision="float32") - ref
        err = 2 * np.pi * np.abs(e - np.round(e)).max()
        x = hf.coords()[0][smp.ix]
        k = np.float32(2 * np.pi / L)
        s = wi + wo[0]
        naive = (k * np.float32(s[0]) * x.astype(np.float32)).astype(np.float64) / (2 * np.pi) - s[0] * x / L
        nerr = 2 * np.pi * np.abs(naive - np.round(naive)).max()
        phase = {"strip_lambda": nx * L / 4 / L, "kernel_rad": err, "naive_rad": nerr}
    return rows, phase


# ----------------------------------------------------------------------------------------------------------------
# figures


def _lobe_figure(gr, beck):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    smooth = _quiet(scatter.scatter, surfaces.gaussian(20e-9, 1e-6, 256 * L / 4, 256, seed=3), (30.0, 0.0), [LAM],
                    resolution=256)
    res_b = beck[0]
    grating = _quiet(scatter.scatter, surfaces.sinusoid(60e-9, 8 * L, 64 * L, 256), (20.0, 0.0), [LAM], resolution=256)
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), layout="constrained")
    for ax, (title, res, dec) in zip(axes, (("grating a = 60 nm, Λ = 8λ, θ_i = 20°", grating, 6),
                                            ("Gaussian σ = 20 nm, T = 1 µm, θ_i = 30°", smooth, 6),
                                            ("Gaussian σ = λ, α = 0.3, θ_i = 0°, 64 real.", res_b, 3))):
        g = res.grid
        f = np.where(g.inside, res.brdf[0], np.nan)
        top = np.nanmax(f)
        im = ax.imshow(np.log10(np.maximum(f, top * 10.0**-dec)), origin="lower", extent=(*g.u_range, *g.v_range),
                       cmap="magma", vmin=np.log10(top) - dec, vmax=np.log10(top))
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("u = sin θ_o cos φ_o")
        ax.set_ylabel("v = sin θ_o sin φ_o")
        fig.colorbar(im, ax=ax, shrink=0.8, label="log10 f (1/sr)")
    path = IMG / "wave_optics_lobes.png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)
    return path.name


def _curve_figure(gr, beck):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.2), layout="constrained")
    for k, (a, (_, rows)) in enumerate(gr.items()):
        m = np.array([r[0] for r in rows])
        a1.bar(m + (k - 1) * 0.27, [r[1] for r in rows], width=0.25, label=f"a = {a * 1e9:g} nm (Kirchhoff)")
        a1.plot(m + (k - 1) * 0.27, [r[2] for r in rows], "k_", ms=10)
    a1.plot([], [], "k_", label="O_m J_m²(k a (cos θ_i + cos θ_m))")
    a1.set_xlabel("order m")
    a1.set_ylabel("efficiency η_m")
    a1.set_title("sinusoidal grating Λ = 8λ, θ_i = 20°", fontsize=10)
    a1.legend(fontsize=8)
    res, res0, fb, rings, grid, th_h = beck[:6]
    sel = grid.inside & (np.abs(grid.directions()[..., 1]) < 1.5 * grid.dv)
    u = grid.directions()[..., 0][sel]
    o = np.argsort(u)
    a2.semilogy(u[o], fb[sel][o], "k-", label="Beckmann α = 2σ/T, no shadowing")
    a2.semilogy(u[o], res.brdf[0][sel][o], "C0.", ms=4, label="Kirchhoff, 64 realizations")
    a2.semilogy(u[o], res0.brdf[0][sel][o], "C3x", ms=4, label="fft order 0 (frozen v_z)")
    a2.set_xlabel("u = sin θ_o (v ≈ 0)")
    a2.set_ylabel("f (1/sr)")
    a2.set_ylim(fb[sel].max() * 1e-4, fb[sel].max() * 3)
    a2.set_title("σ = λ, α = 0.3, normal incidence", fontsize=10)
    a2.legend(fontsize=8)
    path = IMG / "wave_optics_grating_beckmann.png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=90)
    plt.close(fig)
    return path.name


# ----------------------------------------------------------------------------------------------------------------
# page


def _models_table() -> list:
    """Each diffraction model against Kirchhoff on one Gaussian surface (σ = 60 nm, T = 1.2 µm, 128² at λ/4,
    550 nm, F = 1): relative L2 distance of the lobes and the albedo."""
    hf = surfaces.gaussian(60e-9, 1.2e-6, 128 * 137.5e-9, 128, seed=2)
    rows = []
    for theta in (0.0, 30.0, 60.0):
        res = {m: scatter.scatter(hf, (theta, 0.0), [LAM], 1.0, resolution=128, diffraction=m)
               for m, dm in scatter.DIFFRACTION_MODELS.items() if not dm.perturbative}   # Kirchhoff-family solvers
        ref = res["kirchhoff"].brdf[0]
        for m, r in res.items():
            d = float(np.linalg.norm(r.brdf[0] - ref) / np.linalg.norm(ref))
            rows.append({"model": m, "theta_deg": theta, "distance": d, "albedo": r.albedo[0],
                         "coherent": r.coherent_specular_fraction[0]})
    return rows


def _rayleigh_rice_table(theta_i=30.0, lam=550.0, n="1+6j") -> list:
    """Kirchhoff (series, F(θ_d)) over Rayleigh-Rice (unpolarized Q) in the plane of incidence, and Q_s / Q_p."""
    from waveoptics.materials import get_material

    m = surfaces.PSDModel("abc", sigma=3e-9, B=5e-6, C=3.0)
    mat = get_material(n)
    eps = mat.eta(np.array([lam]))[0] ** 2
    wi = direction_from_angles(theta_i, 0.0)
    rows = []
    for phi, side in ((180.0, "specular"), (0.0, "backscatter")):
        for th in (0.0, 20.0, 40.0, 60.0, 65.0, 70.0, 80.0, 85.0):
            wo = direction_from_angles(th, phi)
            h = (wi + wo) / np.linalg.norm(wi + wo)
            k = float(scatter.scattered_lobe(wi, wo[None], lam, m, F=mat.F(np.array([h @ wi]), lam))[0])
            r = float(scatter.rayleigh_rice_brdf(wi, wo, lam, m, eps))
            q = [float(scatter.Q(wi, wo, eps, p)) for p in ("s", "p", "unpolarized")]
            rows.append({"theta_o_deg": th, "side": side, "ratio": k / r, "Q_s": q[0], "Q_p": q[1], "Q": q[2]})
    return rows


def compute() -> dict:
    """Every number of the Kirchhoff-scattering sections of docs/wave-optics.md, and their two figures."""
    IMG.mkdir(parents=True, exist_ok=True)
    rt = _runtime()
    t0 = time.perf_counter()
    ring = {}
    for name in ("boxcar", "hann"):
        hf = surfaces.flat(32e-6, 128)
        r = scatter.scatter(hf, (0.0, 0.0), [LAM], resolution=128, window_name=name)
        ring[name] = scatter.integrate(r.brdf[0], r.grid, region=r.grid.sin_theta > 16 * L / hf.extent[0]) / r.albedo[0]
    gr, _ = _grating()
    beck = _beckmann()
    cost, phase = _cost_table(rt)
    _lobe_figure(gr, beck)
    _curve_figure(gr, beck)
    out = {"device": rt.name if rt is not None else "no OpenCL device (NumPy only)", "ring": ring,
           "horizon_sin": scatter.HORIZON_SIN, "fft_tol": scatter.FFT_TOL, "fft_band_x": scatter.FFT_BAND_X,
           "cost": cost, "phase": phase, "frozen": _frozen_table(), "flat": _flat_table(rt),
           "coherent": _coherent_table(), "grating": _grating_table(gr), "beckmann": _beckmann_table(*beck),
           "models": _models_table(), "rayleigh_rice": _rayleigh_rice_table()}
    out["seconds"] = time.perf_counter() - t0
    return out


def main():
    import make_docs

    make_docs.main(["wave_optics"])


if __name__ == "__main__":
    main()
