"""Data of docs/colour.md (docs/data/colour.json; prose in docs/templates/colour.md) and its figures
(docs/img/colour_*.png): the spectral pipeline, with every number computed by the code."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from waveoptics import materials
from waveoptics import colour as wcolour
from waveoptics.io.files import atomic_path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
IMG = ROOT / "docs" / "img"

#: Hoffman's course-notes table (from Real-Time Rendering 3rd ed.), linear F0, for comparison only
HOFFMAN_RTR3 = {"Fe": (0.56, 0.57, 0.58), "Cu": (0.95, 0.64, 0.54), "Au": (1.00, 0.71, 0.29),
                "Al": (0.91, 0.92, 0.92), "Ag": (0.95, 0.93, 0.88)}

CIE_WHITES = [("D65", "2", (95.047, 100.0, 108.883)), ("D65", "10", (94.811, 100.0, 107.304)),
              ("D50", "2", (96.422, 100.0, 82.521)), ("A", "2", (109.850, 100.0, 35.585))]


def white_table():
    """White points of the perfect reflector (XYZ ×100) against the CIE tables, and the largest difference."""
    rows = []
    for ill, obs, cie in CIE_WHITES:
        ours = 100 * wcolour.white_XYZ(ill, obs)
        rows.append({"illuminant": ill, "observer": obs, "ours": ours, "cie": list(cie),
                     "difference": np.abs(ours - cie).max() / 100})
    return rows


def step_tables() -> dict:
    """Worst ΔE2000 per wavelength step and method, and the grids chosen for a few targets."""
    lights = ("D65", "A", "F2", "F11", "E")
    steps = wcolour.STEPS_NM[:-1]
    rows, worse = [], []
    for ill in lights:
        errs = {m: wcolour.step_errors(ill, steps, method=m) for m in ("linear", "spline")}
        for method, err in errs.items():
            rows.append({"light": ill, "method": method, "errors": [[err[s][0], err[s][1]] for s in steps]})
        worse += [[ill, s] for s in steps if errs["spline"][s][0] > errs["linear"][s][0]]
    targets = (1.0, 0.5, 0.2)
    choices = []
    for ill in lights:
        cells = []
        for target in targets:
            n = [wcolour.simulation_wavelengths(ill, target, method=m) for m in ("linear", "spline")]
            cells.append([[np.diff(g)[0], g.size] for g in n])
        choices.append({"light": ill, "grids": cells})
    return {"steps_nm": list(steps), "errors": rows, "spline_worse": worse, "targets": list(targets),
            "choices": choices, "rgb_laser_lines": len(wcolour.RGB_LASER_NM)}


def f0_tables():
    metals, others = [], []
    for name, preset in materials.PRESETS.items():
        d = wcolour.f0_colour(materials.get_material(name))
        if preset.category == "metal":
            metals.append({"name": name, "f0_linear": d["f0_linear"], "srgb8": list(d["f0_srgb8"]), "Y": d["Y"],
                           "hoffman": HOFFMAN_RTR3.get(name), "description": preset.description})
        others.append({"name": name, "f0_linear": d["f0_linear"], "Y": d["Y"], "category": d["category"],
                       "forbidden_zone": bool(d["forbidden_zone"]), "preset_category": preset.category})
    return metals, others


def _blue_spread(pages):
    blues = [wcolour.f0_colour(materials.get_material(p))["f0_linear"][2] for p in pages]
    return [min(blues), max(blues)]


def plot_swatches(swatches, path):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(1.0 * len(swatches), 1.3), dpi=100)
    FigureCanvasAgg(fig)
    for i, (name, rgb8) in enumerate(swatches):
        ax = fig.add_axes((i / len(swatches), 0.25, 1 / len(swatches), 0.75))
        ax.imshow(np.array(rgb8, dtype=np.uint8).reshape(1, 1, 3))
        ax.set_axis_off()
        fig.text((i + 0.5) / len(swatches), 0.08, name, ha="center", fontsize=10)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")


def metamer_section() -> dict:
    rows = []
    for lines in ((465.0, 532.0, 638.0), wcolour.RGB_LASER_NM):
        m = wcolour.metamer_summary("D65", lines)
        rows.append({"lines_nm": list(m["lines_nm"]), "power_fractions": m["power_fractions"],
                     "XYZ_target": m["XYZ_target"], "XYZ_mix": m["XYZ_mix"]})
    P = wcolour.metamer_laser_weights("D65", (465.0, 532.0, 638.0))
    wcolour.plot_metamers("D65", (465.0, 532.0, 638.0), P, IMG / "colour_metamer_d65.png", overwrite=True)
    residual = np.abs(wcolour.spd_to_XYZ(wcolour.laser((465.0, 532.0, 638.0), P))
                      - wcolour.spd_to_XYZ("D65")).max() / wcolour.spd_to_XYZ("D65")[1]
    import colour

    names = list(colour.SDS_COLOURCHECKERS["ColorChecker N Ohta"])
    w, R = wcolour.reference_reflectances()
    R = R[: len(names)]
    dE = wcolour.delta_e2000(wcolour.reflectance_to_rgb(R, w, "D65"), wcolour.reflectance_to_rgb(R, w, "rgb-laser"))
    w10, d10 = wcolour.white_XYZ("rgb-laser", "10"), wcolour.white_XYZ("D65", "10")
    return {"rows": rows, "residual": residual, "colorchecker_mean": float(dE.mean()),
            "colorchecker_max": float(dE.max()), "colorchecker_worst": names[int(np.argmax(dE))],
            "observer_10_dE": float(wcolour.delta_e2000(wcolour.XYZ_to_rgb(w10), wcolour.XYZ_to_rgb(d10)))}


def compute() -> dict:
    """Every number of docs/colour.md; draws its two figures."""
    import colour

    IMG.mkdir(parents=True, exist_ok=True)
    whites = white_table()
    grid = wcolour.spectral_grid("D65", 5.0)
    metals, others = f0_tables()
    plot_swatches([(m["name"], m["srgb8"]) for m in metals], IMG / "colour_f0_metals.png")
    return {"colour_version": colour.__version__, "whites": whites,
            "white_residual": max(w["difference"] for w in whites),
            "srgb_white": np.abs(wcolour.reflectance_to_rgb(np.ones(grid.size), grid, "D65") - 1.0).max(),
            "steps": step_tables(), "metals": metals, "presets": others,
            "gold_blue_spread": _blue_spread(["main/Au/Johnson", "main/Au/McPeak", "main/Au/Babar",
                                              "main/Au/Olmon-sc"]),
            "silver_blue_spread": _blue_spread(["main/Ag/Johnson", "main/Ag/McPeak", "main/Ag/Hagemann",
                                                "main/Ag/Werner"]),
            "ag_hagemann": wcolour.f0_colour(materials.get_material("main/Ag/Hagemann"))["f0_linear"],
            "metamer": metamer_section()}


def main():
    import make_docs

    make_docs.main(["colour"])


if __name__ == "__main__":
    main()
