"""Sphere12 measurement: ``waveoptics simulate``'s sphere table of an anisotropic analytic micro NDF with PSD
statistics, read at lights between its azimuth nodes, with 4 azimuths (before) and with the count
:func:`waveoptics.simulate.sphere_nodes` takes now (:func:`waveoptics.brdf.tabulated.light_azimuth_nodes`: 12).

Al, Beckmann α 0.15 × 0.4, Gaussian σ 15 nm, T 1.5 µm, 450/550/650 nm, 64² cells, the sphere table's incidence nodes
(:data:`waveoptics.simulate.SPHERE_THETAS_DEG`, 10° steps) with its rim tables, built as :func:`waveoptics.simulate.run`
builds it. Reference: :func:`waveoptics.brdf.evaluate` (the grid route) at the light itself. Error: the 90th
percentile and the max of |f / f_ref − 1| of the diffracted part over exits to θ_o 60° where f_ref is above 1 % of
its peak, pooled over the wavelengths and φ_i 22.5° and 37.5° (midway and a quarter between nodes 30° and 45°
apart), at θ_i 30° and 60° (incidence nodes) and 35° (midway between them). Build time: min of 3 (CPU time of the
process is noisy on a shared machine: "under load").

Run: PYTHONPATH=$PWD WAVEOPTICS_WORKERS=1 python scripts/sphere_light_azimuths.py [n_phi ...]   (default 4 12)
"""
from __future__ import annotations

import sys
import time

import numpy as np

from waveoptics import brdf, surfaces
from waveoptics.brdf import Micro, Nano, TabulatedTwoScaleBRDF
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.simulate import sphere_nodes

LAMS = (450.0, 550.0, 650.0)
MICRO = Micro(alpha=0.15, alpha_y=0.4, ndf="beckmann")
NANO = Nano(model=surfaces.PSDModel("gaussian", 15e-9, T=1.5e-6))
RES = 64
LIGHTS = {30.0: (22.5, 37.5), 35.0: (22.5, 37.5), 60.0: (22.5, 37.5)}


def _dir(th, ph):
    th, ph = np.radians(th), np.radians(ph)
    return np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])


def build(n_phi):
    thetas, _ = sphere_nodes(MICRO, NANO)
    t = time.perf_counter()
    m = TabulatedTwoScaleBRDF("aluminium", MICRO, nano=NANO, wavelengths_nm=LAMS, resolution=RES, thetas_deg=thetas,
                              n_phi=n_phi)
    return m, time.perf_counter() - t


def errors(m, th, phis):
    grid = DirectionGrid.hemisphere(RES)
    wo = grid.directions()[grid.inside]
    e = []
    for ph in phis:
        ref = brdf.evaluate(_dir(th, ph), LAMS, "aluminium", MICRO, NANO, grid).diffraction
        for j, lam in enumerate(LAMS):
            r = ref[j][grid.inside]
            sel = (wo[:, 2] > np.cos(np.radians(60.0))) & (r > 0.01 * r.max())
            f = np.ravel(m.eval_parts(np.broadcast_to(_dir(th, ph), wo[sel].shape), wo[sel], lam)["diffraction"])
            e.append(np.abs(f / r[sel] - 1))
    e = np.concatenate(e)
    return np.percentile(e, 90), e.max(), e.size


def main(counts):
    print("default count:", sphere_nodes(MICRO, NANO)[1], "azimuths")
    for n in counts:
        times = []
        for _ in range(3):
            m, dt = build(n)
            times.append(dt)
        print(f"n_phi {n}: table {m.table.shape}, build min {min(times):.1f} s (of {', '.join(f'{x:.1f}' for x in times)})",
              flush=True)
        for th, phis in LIGHTS.items():
            p90, mx, k = errors(m, th, phis)
            print(f"  theta_i {th:g}: p90 {100 * p90:.2f} %  max {100 * mx:.2f} %  ({k} exits)", flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [4, 12])
