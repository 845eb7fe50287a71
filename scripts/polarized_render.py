"""The polarized render of docs/renderers.md (its data under ``polarized`` in docs/data/renderers.json, its figure
docs/img/renderers_polarized.png): a black-glass sphere (n = 1.5, no transmission, no substrate) rendered by
the Dr.Jit plugin in Mitsuba 3's ``llvm_ad_spectral_polarized`` variant with its ``stokes`` integrator, under a
constant unpolarized sky, seen by an orthographic camera — without nano-roughness and with it.

What it measures, against closed forms written here (not the code under test):

* the degree of linear polarization DoLP = √(S₁² + S₂²)/S₀ of the sky reflected by the smooth sphere, in 2° rings
  of incidence θ = asin(r) (r the pixel's distance from the centre in sphere radii), against Fresnel's
  |R_s − R_p|/(R_s + R_p) of flat glass at the ring's centre (Born & Wolf §1.5.3): the accuracy of the coherent
  part's Mueller matrix and of the frames;
* where a linear polarizer at its darkest orientation, T = (S₀ − √(S₁² + S₂²))/(2S₀), is darkest: Brewster's
  angle arctan 1.5 = 56.3° (Brewster 1815);
* with nano-roughness, how much the diffracted light changes S₀ and the DoLP ring by ring (the effect shown:
  under a uniform sky the scattered light only moves light about, so S₀ hardly changes, but the light it moves
  arrives with other polarizations, which lightens the Brewster band).

References
----------
.. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge 1999, §1.5.3 (Fresnel's R_s, R_p) and §1.4
   (Stokes parameters, degree of polarization).
.. [2] D. Brewster, "On the laws which regulate the polarisation of light by reflexion from transparent bodies",
   Phil. Trans. R. Soc. 105, 125-159, 1815.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

VARIANT = "llvm_ad_spectral_polarized"
N_ETA = 1.5
PIXELS = 160
SPP = 64
ALPHA = 0.01
NANO = "abc:sigma=25nm,B=2um,C=2.6"
RING_DEG = 2.0
THETA_MAX_DEG = 76.0     # r < 0.97: rings beyond it hold few pixels, cut by the silhouette


def fresnel_dolp(theta_deg, n=N_ETA):
    """|R_s − R_p|/(R_s + R_p) of unpolarized light reflected by a flat dielectric of index *n* from air."""
    t = np.radians(theta_deg)
    ct = np.sqrt(1.0 - (np.sin(t) / n) ** 2)
    rs = (np.cos(t) - n * ct) / (np.cos(t) + n * ct)
    rp = (n * np.cos(t) - ct) / (n * np.cos(t) + ct)
    return np.abs(rs ** 2 - rp ** 2) / (rs ** 2 + rp ** 2)


def _stokes(mi, name: str, seed: int) -> np.ndarray:
    """S0..S3 (N, N, 4), the mean over the film's RGB channels, of the sphere with plugin *name*."""
    scene = mi.load_dict({
        "type": "scene", "integrator": {"type": "stokes", "integrator": {"type": "path", "max_depth": 2}},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": PIXELS, "height": PIXELS, "pixel_format": "rgb",
                            "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": SPP}},
        "sphere": {"type": "sphere", "bsdf": {"type": name}},
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}},
    })
    img = np.array(mi.render(scene, seed=seed), dtype=float)
    bitmap = scene.sensors()[0].film().bitmap()
    names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
    return np.stack([img[..., [names.index(f"S{k}.{c}") for c in "RGB"]].mean(-1) for k in range(4)], -1)


def _rings(S: np.ndarray) -> dict:
    """Per 2° ring of incidence: S0, DoLP and the darkest polarizer's transmission, pixel means."""
    n = S.shape[0]
    c = (np.arange(n) + 0.5) / n * 2 - 1
    r = np.hypot(*np.meshgrid(c, c))
    theta = np.degrees(np.arcsin(np.clip(r, 0.0, 1.0)))
    lin = np.hypot(S[..., 1], S[..., 2])
    edges = np.arange(0.0, THETA_MAX_DEG, RING_DEG)
    rows = []
    for a in edges:
        m = (theta >= a) & (theta < a + RING_DEG) & (r < 1.0)
        s0 = S[..., 0][m]
        rows.append({"theta_deg": a + RING_DEG / 2, "pixels": int(m.sum()), "S0": float(s0.mean()),
                     "dolp": float((lin[m] / s0).mean()), "t_min": float(((s0 - lin[m]) / (2 * s0)).mean())})
    return {"rows": rows}


def _figure(S_flat, S_nano, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    fig, ax = plt.subplots(1, 4, figsize=(15, 3.9))
    ext = (-1, 1, -1, 1)
    sigma = NANO.split("sigma=")[1].split(",")[0].replace("nm", " nm")
    for k, (S, title) in enumerate(((S_flat, "smooth glass"), (S_nano, f"nano-rough glass (ABC σ {sigma})"))):
        lin = np.hypot(S[..., 1], S[..., 2])
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where(S[..., 0] > 0, (S[..., 0] - lin) / (2 * S[..., 0]), np.nan)
        im = ax[k].imshow(t, extent=ext, cmap="magma", norm=LogNorm(1e-3, 0.5), origin="lower")
        ax[k].set_title(f"{title}\nthrough the darkest polarizer, (S0 − |S_lin|) / 2 S0", fontsize=9)
        ax[k].add_patch(plt.Circle((0, 0), np.sin(np.arctan(N_ETA)), fill=False, ls="--", lw=0.8, color="c"))
        ax[k].set_xlabel("x (sphere radii)")
        fig.colorbar(im, ax=ax[k], fraction=0.046)
    ax[0].set_ylabel("y (sphere radii)")
    ax[1].text(0.0, -0.97, "dashed: Brewster's angle 56.3°", color="c", ha="center", fontsize=8)
    th = np.linspace(0, THETA_MAX_DEG, 300)
    ax[2].plot(th, fresnel_dolp(th), "k-", lw=1, label="Fresnel, flat glass")
    for S, lab, mk in ((S_flat, "render, smooth", "o"), (S_nano, "render, nano", "s")):
        rows = _rings(S)["rows"]
        ax[2].plot([r["theta_deg"] for r in rows], [r["dolp"] for r in rows], mk, ms=3, label=lab)
    ax[2].set_xlabel("incidence θ (°), ring of the sphere")
    ax[2].set_ylabel("degree of linear polarization")
    ax[2].set_title("sky light reflected: DoLP")
    ax[2].legend(fontsize=8)
    for S, lab, mk in ((S_flat, "render, smooth", "o"), (S_nano, "render, nano", "s")):
        rows = _rings(S)["rows"]
        ax[3].semilogy([r["theta_deg"] for r in rows], [r["t_min"] for r in rows], mk, ms=3, label=lab)
    ax[3].semilogy(th, (1 - fresnel_dolp(th)) / 2, "k-", lw=1, label="Fresnel, flat glass")
    ax[3].set_xlabel("incidence θ (°), ring of the sphere")
    ax[3].set_ylabel("T = (1 − DoLP) / 2")
    ax[3].set_title("light through the darkest polarizer")
    ax[3].legend(fontsize=8)
    fig.suptitle(f"Black glass (n = {N_ETA}, GGX α {ALPHA}) under a constant unpolarized sky, orthographic "
                 f"camera on the axis, Mitsuba 3 {VARIANT}, {PIXELS}² px, {SPP} spp", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def polarized_section(img_dir: Path) -> dict:
    """Render both spheres, measure them (module doc) and write docs/img/renderers_polarized.png."""
    from waveoptics.renderers import cached_renderer_brdf
    from waveoptics.renderers.mitsuba_native import register_native

    out = {"variant": VARIANT, "pixels": PIXELS, "spp": SPP, "alpha": ALPHA, "nano": NANO, "eta": N_ETA}
    stokes = {}
    for label, nano in (("flat", "none"), ("nano", NANO)):
        t0 = time.perf_counter()
        model = cached_renderer_brdf(material=f"{N_ETA}", alpha=ALPHA, ndf="ggx", nano=nano, kd=0.0,
                                     wavelength_step_nm=40.0, resolution=96)
        t1 = time.perf_counter()
        mi = register_native(VARIANT, model=model, name=f"wo_docs_polar_{label}")
        stokes[label] = _stokes(mi, f"wo_docs_polar_{label}", seed=1)
        out[f"{label}_model_s"], out[f"{label}_render_s"] = t1 - t0, time.perf_counter() - t1
    for label, S in stokes.items():
        rings = _rings(S)["rows"]
        out[f"{label}_rings"] = rings
    flat = [r for r in out["flat_rings"] if 10.0 <= r["theta_deg"] <= 70.0]
    err = [abs(r["dolp"] - fresnel_dolp(r["theta_deg"])) for r in flat]
    out["flat_dolp_max_error"] = float(max(err))
    out["flat_dolp_max_error_at_deg"] = float(flat[int(np.argmax(err))]["theta_deg"])
    for label in ("flat", "nano"):
        rows = [r for r in out[f"{label}_rings"] if r["theta_deg"] >= 20.0]
        dark = min(rows, key=lambda r: r["t_min"])
        out[f"{label}_darkest_deg"], out[f"{label}_darkest_t"] = dark["theta_deg"], dark["t_min"]
    ratio = [b["S0"] / a["S0"] for a, b in zip(out["flat_rings"], out["nano_rings"])]
    out["nano_s0_ratio_min"], out["nano_s0_ratio_max"] = float(min(ratio)), float(max(ratio))
    out["nano_dolp_at_brewster"] = min(out["nano_rings"], key=lambda r: abs(r["theta_deg"] - 57.0))["dolp"]
    out["flat_dolp_at_brewster"] = min(out["flat_rings"], key=lambda r: abs(r["theta_deg"] - 57.0))["dolp"]
    out["brewster_deg"] = float(np.degrees(np.arctan(N_ETA)))
    _figure(stokes["flat"], stokes["nano"], img_dir / "renderers_polarized.png")
    return out
