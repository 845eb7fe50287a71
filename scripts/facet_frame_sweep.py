"""Sweep: the two-scale diffracted part against the independent facet-frame reference; ``--write`` stores its rows
as ``facet_frame_sweep`` in docs/data/two_scale.json and re-renders docs/two-scale.md (the table between the
markers ``<!-- facet-frame sweep -->`` and ``<!-- /facet-frame sweep -->`` of docs/templates/two_scale.md).

Al at 550 nm, ABC σ = 10 nm, B = 2 µm, C = 2.6, Beckmann micro NDF. For each α and θ_i, over θ_o ∈ {15, 40, 60, 75,
85}° forward in the plane of incidence and {40, 70}° at φ_o = 90°, the ratio to the reference
(tests/twoscale_reference.py: a Monte-Carlo facet integral, its own sampling and G2, fed the package's
``TwoScaleBRDF.facet_nano_brdf``) of: the pointwise form; the grid form (``evaluate``, 128², read bilinearly, θ_o ≤
70°); and the paraxial shift (``evaluate(..., facet="paraxial")``, the former default).

Usage: ``PYTHONPATH=$PWD python scripts/facet_frame_sweep.py [--write]``.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from waveoptics import brdf, surfaces
from waveoptics.scatter.grid import DirectionGrid

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "scripts"))
import docs_render  # noqa: E402
import twoscale_reference as R  # noqa: E402

LAM = 550.0
NANO = brdf.Nano(model=surfaces.PSDModel("abc", 10e-9, B=2e-6, C=2.6))
OUT = [(15, 180), (40, 180), (60, 180), (75, 180), (85, 180), (40, 90), (70, 90)]


def row(alpha, theta, grid):
    micro = brdf.Micro(alpha=alpha, ndf="beckmann")
    b = brdf.TwoScaleBRDF("aluminium", micro, nano=NANO)
    wi = R.direction(theta)
    wo = R.direction([o[0] for o in OUT], [o[1] for o in OUT])
    wi_b = np.broadcast_to(wi, wo.shape)
    ref, se = R.facet_integral(b.facet_nano_brdf, wi_b, wo, LAM, alpha, "beckmann", nano_width=LAM / 2000.0,
                               n_samples=40000, seed=11)
    pw = b.eval_parts(wi_b, wo, LAM)["diffraction"] / ref
    out = {}
    for route in ("frame", "paraxial"):
        L = brdf.evaluate(wi, [LAM], "aluminium", micro, NANO, grid, facet=route)
        out[route] = grid.interpolate(L.diffraction[0], wo[:, 0], wo[:, 1]) / ref
    near = np.array([o[0] <= 70 for o in OUT])
    dev = lambda r: float(np.max(np.abs(r - 1)))  # noqa: E731
    return {"alpha": alpha, "theta_deg": theta, "pointwise": dev(pw), "grid": dev(out["frame"][near]),
            "paraxial": [float(out["paraxial"].min()), float(out["paraxial"].max())],
            "reference_se": float(np.max(se / ref))}


def table() -> list:
    """One row per (α, θ_i): the largest deviations of the pointwise and grid forms, the paraxial ratio range and
    the reference's standard error."""
    grid = DirectionGrid.hemisphere(128)
    return [row(alpha, theta, grid) for alpha in (0.05, 0.1, 0.3, 0.5) for theta in (0.0, 30.0, 60.0, 80.0)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="store the rows in docs/data/two_scale.json and "
                                                          "re-render docs/two-scale.md")
    args = ap.parse_args(argv)
    rows = table()
    for r in rows:
        print(r)
    if args.write:
        data = docs_render.load_data("two_scale")
        data["facet_frame_sweep"] = rows
        docs_render.write_data("two_scale", data)
        docs_render.write("two_scale")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
