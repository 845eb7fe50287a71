"""Sweep: the two-scale diffracted part against the independent facet-frame reference; ``--write`` stores its rows
as ``facet_frame_sweep`` in docs/data/two_scale.json and re-renders docs/two-scale.md (the table between the
markers ``<!-- facet-frame sweep -->`` and ``<!-- /facet-frame sweep -->`` of docs/templates/two_scale.md).

Al at 550 nm, ABC σ = 10 nm, B = 2 µm, C = 2.6, Beckmann micro NDF. For each α and θ_i, over θ_o ∈ {15, 40, 60, 75,
85}° forward in the plane of incidence and {40, 70}° at φ_o = 90°, the ratio to the reference
(tests/twoscale_reference.py: a Monte-Carlo facet integral, its own sampling and G2, fed the package's
``TwoScaleBRDF.facet_nano_brdf``) of: the pointwise form; the grid form (``evaluate``, 128², read bilinearly, θ_o ≤
70°); and the paraxial shift (``evaluate(..., facet="paraxial")``, the former default).

``--narrow``: nano lobes narrower than the grid's cells (ABC σ = 10 nm, B 200 µm / C 3 and B 50 µm / C 2.4, Al,
450 nm, 128²): the diffracted light in rings 0.1-0.2, 0.2-0.4 and beyond 0.4 direction cosines from the mirror (exits
up to 85°) of the grid form (``facet="auto"``, now the frame route with finer tables,
``waveoptics.brdf.facet_tables``) and of the paraxial shift (the route such lobes took before) over the pointwise
facet-frame form averaged over the same cells (tests/test_narrow_lobe_twoscale.py's rule); stored as
``narrow_lobe_sweep``.

Usage: ``PYTHONPATH=$PWD python scripts/facet_frame_sweep.py [--narrow] [--write]``.
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


def narrow_row(nano, alpha, theta, grid):
    """Ring ratios (min, max) of the grid form and of the paraxial shift over the pointwise form, one (α, θ_i)."""
    from test_narrow_lobe_twoscale import RINGS, _cell_averages

    micro = brdf.Micro(alpha=alpha, ndf="beckmann")
    wi = R.direction(theta)
    ref = brdf.TwoScaleBRDF("aluminium", micro, nano=nano)
    d = grid.directions()
    r = np.hypot(d[..., 0] + wi[0], d[..., 1] + wi[1])
    want, got = [], {"auto": [], "paraxial": []}
    for a, b, s in RINGS:
        iv, iu = np.nonzero((r > a) & (r <= b) & grid.inside & (d[..., 2] > np.cos(np.radians(85.0))))
        want.append(_cell_averages(lambda wo: ref.eval_parts(wi, wo, 450.0)["diffraction"], grid, iv, iu, s).sum())
        for route in got:
            got[route].append((iv, iu))
    out = {}
    for route, cells in got.items():
        L = brdf.evaluate(wi, [450.0], "aluminium", micro, nano, grid, facet=route)
        ratio = [L.diffraction[0][iv, iu].sum() / w for (iv, iu), w in zip(cells, want)]
        out["grid" if route == "auto" else route] = [float(min(ratio)), float(max(ratio))]
        if route == "auto":
            out["route"] = L.info["facet_integration"]
    return out


def narrow_table() -> list:
    """One row per (B, C, α, θ_i) of narrow nano lobes on 128² (module doc)."""
    import warnings

    grid = DirectionGrid.hemisphere(128)
    rows = []
    for B, C in ((200e-6, 3.0), (50e-6, 2.4)):
        nano = brdf.Nano(model=surfaces.PSDModel("abc", 10e-9, B=B, C=C))
        for alpha in (0.005, 0.05, 0.1, 0.3):   # 0.005: a micro lobe narrower than a cell (the paraxial route)
            for theta in (0.0, 30.0, 60.0, 70.0, 80.0, 85.0):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    row_ = narrow_row(nano, alpha, theta, grid)
                rows.append({"B_um": B * 1e6, "C": C, "alpha": alpha, "theta_deg": theta, **row_})
                print(rows[-1], flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="store the rows in docs/data/two_scale.json and "
                                                          "re-render docs/two-scale.md")
    ap.add_argument("--narrow", action="store_true", help="the sweep of narrow nano lobes (module doc)")
    args = ap.parse_args(argv)
    rows = narrow_table() if args.narrow else table()
    if not args.narrow:
        for r in rows:
            print(r)
    if args.write:
        data = docs_render.load_data("two_scale")
        data["narrow_lobe_sweep" if args.narrow else "facet_frame_sweep"] = rows
        docs_render.write_data("two_scale", data)
        docs_render.write("two_scale")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
