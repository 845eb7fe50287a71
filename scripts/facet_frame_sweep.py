"""Sweep: the two-scale diffracted part against the independent facet-frame reference; writes its table into
docs/two-scale.md (between the markers ``<!-- facet-frame sweep -->`` and ``<!-- /facet-frame sweep -->``).

Al at 550 nm, ABC σ = 10 nm, B = 2 µm, C = 2.6, Beckmann micro NDF. For each α and θ_i, over θ_o ∈ {15, 40, 60, 75,
85}° forward in the plane of incidence and {40, 70}° at φ_o = 90°, the ratio to the reference
(tests/twoscale_reference.py: a Monte-Carlo facet integral, its own sampling and G2, fed the package's
``TwoScaleBRDF.facet_nano_brdf``) of: the pointwise form; the grid form (``evaluate``, 128², read bilinearly, θ_o ≤
70°); and the paraxial shift (``evaluate(..., facet="paraxial")``, the former default).

Usage: ``PYTHONPATH=$PWD python scripts/facet_frame_sweep.py [--write]``.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

from waveoptics import brdf, surfaces
from waveoptics.scatter.grid import DirectionGrid

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
import twoscale_reference as R  # noqa: E402

LAM = 550.0
NANO = brdf.Nano(model=surfaces.PSDModel("abc", 10e-9, B=2e-6, C=2.6))
OUT = [(15, 180), (40, 180), (60, 180), (75, 180), (85, 180), (40, 90), (70, 90)]
MARK = ("<!-- facet-frame sweep -->", "<!-- /facet-frame sweep -->")


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
    return (f"| {alpha:g} | {theta:g}° | {dev(pw):.3f} | {dev(out['frame'][near]):.3f} | "
            f"{out['paraxial'].min():.2f}–{out['paraxial'].max():.2f} | {float(np.max(se / ref)):.3f} |")


def table() -> str:
    grid = DirectionGrid.hemisphere(128)
    rows = ["| micro α | θ_i | pointwise: max abs(ratio − 1) | grid 128² (θ_o ≤ 70°): max abs(ratio − 1) | "
            "paraxial shift: ratio range | reference s.e. (max) |", "|---|---|---|---|---|---|"]
    for alpha in (0.05, 0.1, 0.3, 0.5):
        for theta in (0.0, 30.0, 60.0, 80.0):
            rows.append(row(alpha, theta, grid))
    return "\n".join(rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="replace the table in docs/two-scale.md")
    args = ap.parse_args(argv)
    text = table()
    print(text)
    if args.write:
        doc = ROOT / "docs" / "two-scale.md"
        old = doc.read_text()
        block = f"{MARK[0]}\n{text}\n{MARK[1]}"
        new, n = re.subn(re.escape(MARK[0]) + ".*?" + re.escape(MARK[1]), lambda _: block, old, flags=re.S)
        doc.write_text(new if n else old)
        if not n:
            print("markers not found in docs/two-scale.md", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
