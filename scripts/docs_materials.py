"""Data of docs/materials-fresnel.md (docs/data/materials.json; formulas and prose with sources in
docs/templates/materials.md): tables computed from the code, and its figures."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from waveoptics.materials import fresnel
from waveoptics import materials

sys.path.insert(0, str(Path(__file__).resolve().parent))
IMG = Path(__file__).resolve().parent.parent / "docs" / "img" / "fresnel_zones.png"
ZONE_ANGLES = (45.0, 60.0, 75.0, 85.0)


def fresnel_zones_sphere(path) -> None:
    """The zones over a sphere seen along its axis (the view direction is the light direction, so each pixel's
    angle of incidence is the angle between its normal and the view): F at 550 nm of gold and of glass, with the
    zone borders at 45° and 75° drawn as circles. Most of a sphere's visible area is in zone 1."""
    from waveoptics.io import figures

    n = 241
    yy, xx = np.mgrid[:n, :n]
    x = (xx + 0.5) / n * 2 - 1
    y = 1 - (yy + 0.5) / n * 2
    r2 = x * x + y * y
    on = r2 < 1
    cos_t = np.sqrt(np.clip(1 - r2, 0, 1))
    plt = figures.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(8.0, 4.0), constrained_layout=True)
    for ax, name in zip(axes, ("Au", "BK7")):
        F = np.where(on, np.asarray(materials.get_material(name).F(cos_t, 550.0), dtype=float), np.nan)
        im = ax.imshow(F, vmin=0, vmax=1, cmap="viridis", extent=[-1, 1, -1, 1])
        for a in (45, 75):
            t = np.linspace(0, 2 * np.pi, 400)
            s_ = np.sin(np.radians(a))
            ax.plot(s_ * np.cos(t), s_ * np.sin(t), "w--", lw=0.8)
            ax.text(0, s_ - 0.02, f"{a}°", color="w", ha="center", va="top", fontsize=7)
        area1 = np.sin(np.radians(45)) ** 2
        ax.set_title(f"{name}: F at 550 nm over a sphere (view = light)\nzone 1 covers {area1:.0%} of the disc",
                     fontsize=9)
        ax.set_axis_off()
        fig.colorbar(im, ax=ax, fraction=0.046, label="F")
    figures.save_figure(fig, path)


def fresnel_zones():
    """The canon's three Fresnel "zones" (Hoffman 2015): F barely changes up to about 45°, changes somewhat up
    to about 75°, and rises to 1 beyond. F(0°) and F(θ) − F(0°) at ZONE_ANGLES per preset at 550 nm (from the
    exact equations); draws the figure of F(θ) against θ with the zones shaded."""
    from waveoptics.io import figures

    theta = np.linspace(0.0, 90.0, 901)
    c = np.cos(np.radians(theta))
    rows = []
    plt = figures.pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.axvspan(0, 45, color="0.93")
    ax.axvspan(45, 75, color="0.85")
    ax.axvspan(75, 90, color="0.75")
    for x, label in ((22.5, "zone 1: F ≈ F0"), (60, "zone 2: F changes a little"), (82.5, "zone 3: F → 1")):
        ax.text(x, 1.02, label, ha="center", va="bottom", fontsize=8)
    for name in materials.PRESETS:
        m = materials.get_material(name)
        F = np.asarray(m.F(c, 550.0), dtype=float)
        f = {a: float(np.interp(a, theta, F)) for a in ZONE_ANGLES}
        rows.append({"preset": name, "f0": float(F[0]), "rise": [f[a] - float(F[0]) for a in ZONE_ANGLES]})
        if name in ("Al", "Au", "Cu", "Ag", "Ti", "Si", "glass", "water", "diamond"):
            ax.plot(theta, F, label=name, lw=1.2)
    ax.set_xlim(0, 90)
    ax.set_ylim(0, 1.1)
    ax.set_xlabel("angle of incidence θ (degrees)")
    ax.set_ylabel("unpolarized Fresnel reflectance F at 550 nm")
    ax.set_title("Fresnel zones (Hoffman 2015), exact F from measured η", fontsize=10)
    ax.legend(fontsize=7, ncol=3, loc="center left")
    IMG.parent.mkdir(parents=True, exist_ok=True)
    figures.save_figure(fig, IMG)
    return rows

#: published linear-sRGB F0 of metals: Hoffman, SIGGRAPH 2010-2013 PBS course "Background: Physically-Based
#: Shading", Table 1 (from Real-Time Rendering 3rd ed.); gold's red is clipped at 1 there
PUBLISHED_F0 = {"Cu": (0.95, 0.64, 0.54), "Al": (0.91, 0.92, 0.92), "Au": (1.00, 0.71, 0.29),
                "Ag": (0.95, 0.93, 0.88)}


def f0_data_sets() -> list:
    """For every metal preset: F0 of its default data set, the range over the experimental bulk data sets that
    cover the visible, and, where a published value exists, the data set closest to it (max channel error)."""
    from waveoptics import colour
    from waveoptics.materials.database import data_sets

    rows = []
    for name, p in materials.PRESETS.items():
        if p.category != "metal":
            continue
        sets = [d for d in data_sets(name) if d["covers_visible"]]
        f0 = {d["page"]: np.array(colour.f0_colour(materials.get_material(d["spec"]))["f0_linear"]) for d in sets}
        bulk = [d["page"] for d in sets if "experimental" in d["kind"].lower() and "thin film" not in d["kind"].lower()]
        rng = np.array([f0[b] for b in bulk]) if bulk else np.array([f0[p.page]])
        ref = PUBLISHED_F0.get(name)
        published = None
        if ref is not None:
            err = {k: float(np.max(np.abs(np.minimum(v, 1.0) - ref))) for k, v in f0.items() if k in bulk}
            best = min(err, key=err.get)
            published = {"f0": list(ref), "closest": best, "closest_error": err[best],
                         "default_error": float(np.max(np.abs(np.minimum(f0[p.page], 1.0) - ref)))}
        rows.append({"metal": name, "page": p.page, "f0": f0[p.page], "bulk_sets": len(bulk),
                     "range": list(zip(rng.min(0), rng.max(0))), "published": published})
    return rows


def _presets() -> list:
    w = np.array([450.0, 550.0, 650.0])
    out = []
    for name, p in materials.PRESETS.items():
        m = materials.get_material(name)
        out.append({"name": name, "aliases": list(p.aliases), "category": p.category, "description": p.description,
                    "source": f"{p.shelf}/{p.book}/{p.page}", "range_nm": list(m.wavelength_range_nm),
                    "f0": m.F0(w)})
    return out


def _schlick() -> list:
    """Schlick's largest error against the exact F for real indices n, over 0–90° and 0–60°."""
    c = np.cos(np.radians(np.linspace(0, 90, 9001)))
    out = []
    for n in (1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.8, 2.0, 2.42):
        err = np.abs(fresnel.F_schlick(c, fresnel.F0(n)) - fresnel.F(c, n))
        i = int(np.argmax(err))
        out.append({"n": n, "max_error": err[i], "at_deg": np.degrees(np.arccos(c[i])),
                    "max_error_60": err[c >= 0.5].max()})
    return out


def compute() -> dict:
    """The tables of docs/materials-fresnel.md; draws its two figures."""
    fresnel_zones_sphere(IMG.parent / "fresnel_zones_sphere.png")
    return {"max_clamp_nm": materials.MAX_CLAMP_NM, "presets": _presets(), "schlick": _schlick(),
            "zone_angles": list(ZONE_ANGLES), "zones": fresnel_zones(), "f0_data_sets": f0_data_sets()}


def main():
    import make_docs

    make_docs.main(["materials"])


if __name__ == "__main__":
    main()
