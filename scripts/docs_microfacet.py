"""Data of docs/microfacet.md (docs/data/microfacet.json; formulas with sources and prose in
docs/templates/microfacet.md): identities, energy-loss tables, kernel agreement, throughput and the NDF-lobe
figure, all computed from the code."""
from __future__ import annotations

import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from waveoptics import brdf
from waveoptics.units import direction_from_angles  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
IMG = ROOT / "docs" / "img" / "microfacet_ndf_lobes.png"


ALPHAS = [0.001, 0.01, 0.1, 0.5, 1.0]


def _dirs(theta, phi=0.0):
    return direction_from_angles(theta, phi)


def analytic_ndfs() -> list:
    """The NDFs given by a formula (the tabulated one needs a measured slope table)."""
    return [k for k, v in brdf.NDFS.items() if v.shape != "table"]


def identities() -> list:
    """Per NDF: normalization error, Smith-identity error and the radial Λ's G1 error against the closed form (None
    without a closed form)."""
    from scipy import integrate

    rows = []
    for ndf in analytic_ndfs():
        nerr, serr = 0.0, 0.0
        for a in ALPHAS:
            def integrand(u):
                t = np.arctan(a * u)
                return float(brdf.D(_dirs(np.degrees(t)), a, ndf=ndf)) * np.cos(t) * np.sin(t) * 2 * np.pi * a / (
                    1 + (a * u) ** 2)
            val = integrate.quad(integrand, 0, 4, limit=400)[0] + integrate.quad(integrand, 4, np.inf, limit=400)[0]
            nerr = max(nerr, abs(val - 1))
            m, w = brdf.normal_quadrature(a, n_phi=128)
            d = brdf.D(m, a, ndf=ndf)
            for th in (0.0, 30.0, 60.0, 80.0, 89.0):
                v = _dirs(th, 25.0)
                lhs = np.sum(w * brdf.G1(v, m, a, ndf=ndf) * np.maximum(0, m @ v) * d)
                serr = max(serr, abs(lhs / v[2] - 1))
        th = np.array([0.1, 10, 30, 60, 80, 89, 89.9, 89.99])
        lerr = None
        if ndf != "abc":
            e = 0.0
            for a in ALPHAS:
                P22 = _P22(ndf, a)
                g_q = 1 / (1 + brdf.Lambda_radial(_dirs(th), P22, a))
                g_e = 1 / (1 + brdf.NDFS[ndf].Lambda(_dirs(th), a, a, None))
                e = max(e, np.max(np.abs(g_q - g_e)))
            lerr = float(e)
        rows.append([ndf, nerr, serr, lerr])
    return rows


def _P22(ndf, a):
    if ndf == "ggx":
        return lambda r: 1 / (np.pi * a * a * (1 + r * r / (a * a)) ** 2)
    if ndf == "beckmann":
        return lambda r: np.exp(-r * r / (a * a)) / (np.pi * a * a)
    ap = brdf.blinn_phong_exponent(a)
    return lambda r: (ap + 2) / (2 * np.pi) * (1 + r * r) ** (-(ap + 4) / 2)


def quadrature_accuracy() -> dict:
    """Largest albedo error of the normal quadrature: Lambert (exact 1) at each α's nodes, and three BRDFs against
    scipy's dblquad."""
    from scipy import integrate

    rows = {"lambert": [], "dblquad": []}
    th = np.array([0.0, 30.0, 60.0, 85.0, 89.9])
    for a in ALPHAS:
        E = brdf.directional_albedo(lambda x, y: brdf.lambert(x, y, 1.0), _dirs(th), alpha=a)
        rows["lambert"].append([a, np.max(np.abs(E - 1))])
    for ndf, sh, a, t in (("beckmann", "smith", 0.1, 85.0), ("ggx", "smith-correlated", 0.5, 60.0),
                          ("abc", "cook-torrance", 0.3, 30.0)):
        wi = _dirs(t)

        def g(tt, pp):
            return float(brdf.brdf(wi, _dirs(np.degrees(tt), np.degrees(pp)), alpha=a, ndf=ndf, shadowing=sh,
                                 fresnel="one")) * np.cos(tt) * np.sin(tt)

        ref = 2 * integrate.dblquad(g, 0, np.pi, 0, np.pi / 2, epsabs=2e-6, epsrel=2e-6)[0]
        E = float(brdf.albedo(wi, alpha=a, ndf=ndf, shadowing=sh, fresnel="one"))
        rows["dblquad"].append([ndf, sh, a, t, abs(E - ref)])
    return rows


def _loss(E) -> float:
    """1 − E; below the quadrature error (|1 − E| ≤ 1e-12 here) its sign is round-off: a negative one is 0."""
    return max(1.0 - E, 0.0) if abs(1.0 - E) < 1e-9 else 1.0 - E


def energy_tables():
    """Energy loss 1 − E at 0°, 60°, 80° per α and NDF, per α and G term (GGX), and the largest E found."""
    th = np.array([0.0, 60.0, 80.0])
    alphas = [0.0, 0.001, 0.01, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0]
    ndfs = analytic_ndfs()
    rows = []
    for a in alphas:
        r = []
        for ndf in ndfs:
            E = brdf.albedo(_dirs(th), alpha=a, ndf=ndf, fresnel="one")
            r.append([_loss(e) for e in E])
        rows.append([a, r])
    loss = {"columns": ndfs, "rows": rows}
    rows = []
    for a in alphas:
        r = []
        for sh in brdf.SHADOWINGS:
            E = brdf.albedo(_dirs(th), alpha=a, ndf="ggx", shadowing=sh, fresnel="one")
            r.append([_loss(e) for e in E])
        rows.append([a, r])
    shadow = {"columns": list(brdf.SHADOWINGS), "rows": rows}
    emax = 0.0
    tgrid = np.array([0.0, 30.0, 60.0, 75.0, 85.0, 89.0])
    for ndf in ndfs:
        for sh in brdf.SHADOWINGS:
            for a in (0.0, 0.001, 0.01, 0.1, 0.3, 0.5, 1.0):
                emax = max(emax, float(np.max(brdf.albedo(_dirs(tgrid), alpha=a, ndf=ndf, shadowing=sh,
                                                        fresnel="one"))))
    return loss, shadow, emax


def tradeoff_excess() -> dict:
    """Largest total albedo − 1 of a dielectric (η = 1.5) with kd = 1, per NDF (GGX, Beckmann)."""
    th = np.array([0.0, 20.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0, 89.0])
    out = {}
    for ndf in ("ggx", "beckmann"):
        ex = -np.inf
        for a in (0.001, 0.003, 0.01, 0.03, 0.1, 0.2, 0.3, 0.5):
            ex = max(ex, float(np.max(brdf.albedo(_dirs(th), alpha=a, eta=1.5, kd=1.0, ndf=ndf) - 1)))
        out[ndf] = ex
    return out


def oren_nayar_max():
    best = (0.0, 0.0, 0.0)
    th = np.array([0.0, 45.0, 70.0, 80.0, 85.0, 89.0, 89.9])
    for s in np.linspace(0.05, 1.0, 20):
        E = brdf.directional_albedo(lambda x, y: brdf.oren_nayar(x, y, 1.0, s), _dirs(th), alpha=1.0)
        i = int(np.argmax(E))
        if E[i] > best[0]:
            best = (float(E[i]), float(s), float(th[i]))
    total = brdf.albedo(_dirs(th), alpha=0.3, eta=1.5, kd=1.0, diffuse="oren-nayar", diffuse_sigma=best[1])
    return best + (float(np.max(total)),)


def _pairs(n, seed=21):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2 * n, 3))
    v[:, 2] = np.abs(v[:, 2])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    wi, wo = v[:n], v[n:]
    h = n // 2
    wo[:h] = wi[:h] * [-1, -1, 1] + rng.normal(scale=0.1, size=(h, 3)) * [1, 1, 0]
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    return wi, wo


def kernel_agreement(rt, n=20000) -> dict:
    """Largest relative error of the OpenCL BRDF against NumPy per NDF × G term and precision."""
    wi, wo = _pairs(n)
    eta = np.array([1.5, 0.2 + 3.1j, 1.4 + 7.5j])
    kd = np.array([0.2, 0.0, 0.9])
    precisions = ["float32"] + (["float64"] if rt.fp64 else [])
    rows = []
    for ndf in [k for k in analytic_ndfs() if brdf.NDFS[k].cl_id is not None]:   # the NDFs with a kernel
        for sh in brdf.SHADOWINGS:
            r = []
            ref = brdf.brdf(wi[None], wo[None], alpha=0.3, ndf=ndf, shadowing=sh, eta=eta[:, None], kd=kd[:, None])
            for p in precisions:
                fc = brdf.brdf_cl(wi, wo, alpha=0.3, ndf=ndf, shadowing=sh, eta=eta, kd=kd, runtime=rt, precision=p)
                r.append(np.max(np.abs(fc - ref) / np.maximum(np.abs(ref), 1e-3)))
            rows.append([ndf, sh, r])
    return {"pairs": n, "precisions": precisions, "rows": rows}


def throughput(rt, n=200000) -> dict:
    """BRDF evaluations per second: NumPy, OpenCL per precision, and OpenCL with a quadrature Λ (best of 3)."""
    wi, wo = _pairs(n, seed=3)
    eta = np.array([1.5, 0.2 + 3.1j, 1.4 + 7.5j])
    kd = np.array([0.5, 0.0, 0.9])
    kw = dict(alpha=0.3, eta=eta, kd=kd)

    def best(fn):
        fn()
        ts = []
        for _ in range(3):
            t0 = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t0)
        return 3 * n / min(ts)

    out = {"pairs": n, "numpy": best(lambda: brdf.brdf(wi[None], wo[None], alpha=0.3, eta=eta[:, None],
                                                     kd=kd[:, None])),
           "opencl": [[p, best(lambda: brdf.brdf_cl(wi, wo, runtime=rt, precision=p, **kw))]
                      for p in ["float32"] + (["float64"] if rt.fp64 else [])],
           "quadrature_ndfs": [[ndf, best(lambda: brdf.brdf_cl(wi, wo, ndf=ndf, runtime=rt, precision="float32", **kw))]
                               for ndf in ("abc",)]}
    return out


def figure():
    a = 0.2
    t = np.radians(np.linspace(0, 89.5, 600))
    m = _dirs(np.degrees(t))
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    styles = {"beckmann": dict(ndf="beckmann"), "ggx": dict(ndf="ggx"), "blinn-phong": dict(ndf="blinn-phong"),
              "abc (C = 0.75)": dict(ndf="abc", ndf_shape=0.75)}
    for label, kw in styles.items():
        ax1.semilogy(np.degrees(t), brdf.D(m, a, **kw) * np.cos(t), label=label)
    ax1.set_xlabel("θ_m (degrees)")
    ax1.set_ylabel("D(m) cos θ_m  (1/sr)")
    ax1.set_title(f"NDF lobes, α = {a}")
    ax1.set_ylim(1e-6, 20)
    ax1.legend()
    thi = 45.0
    to = np.linspace(-89.5, 89.5, 721)
    wo = _dirs(np.abs(to), np.where(to < 0, 180.0, 0.0))
    wi = _dirs(thi, 180.0)
    for label, kw in styles.items():
        ax2.semilogy(to, brdf.brdf(wi, wo, alpha=a, fresnel="one", **kw), label=label)
    ax2.axvline(thi, color="0.7", lw=0.8)
    ax2.set_xlabel("θ_o in the plane of incidence (degrees; mirror at +45°)")
    ax2.set_ylabel("f (1/sr), F = 1")
    ax2.set_title("BRDF at θ_i = 45°, correlated Smith")
    ax2.set_ylim(1e-5, 50)
    ax2.legend()
    fig.tight_layout()
    from waveoptics.io.files import atomic_path

    IMG.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(IMG) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def compute() -> dict:
    """Every number of docs/microfacet.md (the throughput is timed) and the NDF-lobe figure."""
    from waveoptics.runtime import get_runtime

    rt = get_runtime()
    loss, shadow, emax = energy_tables()
    on = oren_nayar_max()
    out = {"device": f"{rt.name} ({rt.device.platform.name.strip()})", "ndf_shape": brdf.ABC_C_DEFAULT,
           "quadrature": quadrature_accuracy(), "identities": identities(), "loss": loss, "shadow": shadow,
           "emax": emax, "tradeoff_excess": tradeoff_excess(),
           "oren_nayar": dict(zip(("max", "sigma", "theta_deg", "total"), on)),
           "kernel": kernel_agreement(rt, 20000), "throughput": throughput(rt, 200000)}
    figure()
    return out


def main():
    import make_docs

    make_docs.main(["microfacet"])


if __name__ == "__main__":
    main()
