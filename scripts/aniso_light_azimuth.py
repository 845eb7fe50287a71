"""Issue 28 measurement: an anisotropic analytic micro NDF's main tables read between light-azimuth nodes.

Al, Beckmann α 0.15 × 0.4, Gaussian σ 15 nm, T 1.5 µm, 550 nm, 64² cells. The grid route's lobes
(:func:`waveoptics.brdf.evaluate`) are computed at θ_i 30° and 60° and light azimuths every 7.5° over [0°, 180°)
(the rest by the half-turn symmetry); tables of N light azimuths are subsets of them. Each candidate read of the
tables at a light φ_i in [0°, 90°] (every 7.5°) is compared with the lobe computed at that light itself, at exits to
60° where it is above 1 % of its peak: the 90th percentile and the max of |read / lobe − 1|.

Candidates (each node's table read at ω_o, then blended across φ_i; a node whose point lies beyond its horizon drops
out): ``shift`` (the tables in the surface's frame, read at each node's mirror point plus the offset in direction
cosines: the read before issue 28), ``turn`` (each node's table turned with the light: the NDF's axes turn under
it, as the rim tables are read), ``half`` (each node read at the exit whose half-vector with the node's light is
(ω_i, ω_o)'s, times cos θ_o' / cos θ_o: :func:`waveoptics.brdf.tabulated_reads.half_vector_exit`); blended ``-lin``
(linearly), ``-log`` (the monotone cubic of log f over four nodes, as the rim tables), ``-pchip`` (the monotone
cubic of f), ``-cr`` (Catmull-Rom of f) or ``-near`` (the nearest node); ``lib`` is the library's own read.
``between`` reads θ_i 30° and 60° midway between incidence nodes 25/35° and 55/65° (the library's 12-azimuth
half-vector read against the shifted read of 4 nodes).

Run: PYTHONPATH=$PWD python scripts/aniso_light_azimuth.py [cache.npz] [N:kind,kind ...]   (default: all of N
4, 8, 12, 16, 24), or ... [cache.npz] between [cache_between.npz]. Its numbers are quoted at
``waveoptics.brdf.tabulated.PHI_NODES_ANISOTROPIC_NDF`` and in that module's doc.
"""
from __future__ import annotations

import os
import sys
import time

import numpy as np

from waveoptics import brdf, surfaces
from waveoptics.brdf import Micro, Nano, TabulatedTwoScaleBRDF
from waveoptics.brdf.tabulated_rim import RIM_LOG_FLOOR, pchip_between
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
MICRO = Micro(alpha=0.15, alpha_y=0.4, ndf="beckmann")
NANO = Nano(model=surfaces.PSDModel("gaussian", 15e-9, T=1.5e-6))
THETAS = (30.0, 60.0)
STEP = 7.5
GRID = DirectionGrid.hemisphere(64)


def _dir(th, ph):
    th, ph = np.radians(th), np.radians(ph)
    return np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])


def lobes(path):
    """(n_az over [0, 360°) every 7.5°, n_θ, 64, 64): computed over [0, 180°), the rest turned by π."""
    if os.path.exists(path):
        return np.load(path)["lobes"]
    half = int(180 / STEP)
    out = np.zeros((2 * half, len(THETAS), GRID.n_v, GRID.n_u))
    for a in range(half):
        for k, th in enumerate(THETAS):
            out[a, k] = brdf.evaluate(_dir(th, a * STEP), [LAM], "aluminium", MICRO, NANO, GRID).diffraction[0]
    out[half:] = out[:half, :, ::-1, ::-1]
    np.savez(path, lobes=out)
    return out


def table(all_lobes, n):
    every = all_lobes.shape[0] // n
    sub = all_lobes[::every][:, :, None]
    return TabulatedTwoScaleBRDF("aluminium", MICRO, nano=NANO, wavelengths_nm=(LAM,), thetas_deg=THETAS,
                                 table_lobes=sub, table_grid=GRID, table_phis_deg=tuple(360.0 * np.arange(n) / n),
                                 rim=False)


def _rot(w, phi):
    """Vectors (m, 3) turned about z by +phi (rad)."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=-1)


def read_turned(m, k, p, phi_i, wo):
    """Node p's table (θ node k = θ_i) read at ω_o turned from the light's azimuth φ_i onto the node's."""
    w = _rot(wo, m._table["phis"][p] - phi_i)
    pp = np.full(w.shape[0], p)
    return m._lookup(pp, np.full(w.shape[0], k), [0], w[:, 0], w[:, 1])[:, 0]   # never beyond the horizon


def read_shifted(m, k, p, phi_i, wo):
    """Node p's table (surface frame) read at its mirror point plus ω_o's offset from ω_i's mirror point."""
    th, ph = np.radians(THETAS[k]), m._table["phis"][p]
    u = -np.sin(th) * np.cos(ph) + wo[:, 0] + np.sin(th) * np.cos(phi_i)
    v = -np.sin(th) * np.sin(ph) + wo[:, 1] + np.sin(th) * np.sin(phi_i)
    val = m._lookup(np.full(u.size, p), np.full(u.size, k), [0], u, v)[:, 0]
    return np.where(u * u + v * v < 1, val, np.nan)


def read_half(m, k, p, phi_i, wo):
    """Node p's table read at the exit whose half-vector with the node's light has the slopes of (ω_i, ω_o)'s,
    times cos θ_o' / cos θ_o (f cos θ_i cos θ_o ∝ D(h) G F)."""
    th = np.radians(THETAS[k])
    wi = np.broadcast_to(np.array([np.sin(th) * np.cos(phi_i), np.sin(th) * np.sin(phi_i), np.cos(th)]), wo.shape)
    ph = m._table["phis"][p]
    wn = np.broadcast_to(np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)]), wo.shape)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    w = 2 * np.sum(wn * h, axis=-1, keepdims=True) * h - wn
    val = m._lookup(np.full(w.shape[0], p), np.full(w.shape[0], k), [0], w[:, 0], w[:, 1])[:, 0]
    return np.where(w[:, 2] > 0, val * w[:, 2] / wo[:, 2], np.nan)


def read(m, kind, k, phi_deg, wo):
    n = m._table["phis"].size
    phi_i = np.radians(phi_deg)
    wi = np.broadcast_to(_dir(THETAS[k], phi_deg), wo.shape)
    if kind == "lib":
        return m.eval_parts(wi, wo, LAM)["diffraction"]
    f = np.mod(phi_i, 2 * np.pi) * n / (2 * np.pi)
    a, t = int(np.floor(f + 1e-12)), f - np.floor(f + 1e-12)
    one = {"half": read_half, "turn": read_turned, "shift": read_shifted}[kind.split("-")[0]]
    # a node whose point lies beyond its horizon (NaN) drops out of the blend, as in the library's read
    v = [one(m, k, (a + s) % n, phi_i, wo)[:, None] for s in (-1, 0, 1, 2)]
    if kind.endswith("lin"):
        w1, w2 = (1 - t) * ~np.isnan(v[1]), t * ~np.isnan(v[2])
        return ((w1 * np.nan_to_num(v[1]) + w2 * np.nan_to_num(v[2])) / np.maximum(w1 + w2, 1e-300))[:, 0]
    if kind.endswith("near"):
        return np.nan_to_num(v[1 + int(t > 0.5)])[:, 0]
    v[1] = np.where(np.isnan(v[1]), v[2], v[1])
    v[2] = np.where(np.isnan(v[2]), v[1], v[2])
    v[0] = np.where(np.isnan(v[0]), v[1], v[0])
    v[3] = np.where(np.isnan(v[3]), v[2], v[3])
    v = [np.nan_to_num(x) for x in v]
    pos = [np.full_like(v[0], float(s)) for s in (-1, 0, 1, 2)]
    if kind.endswith("pchip"):   # the monotone cubic of f itself
        return pchip_between(v, pos, np.full_like(v[0], t))[:, 0]
    if kind.endswith("cr"):      # Catmull-Rom (uniform cubic Hermite with central-difference slopes) of f
        m1, m2 = (v[2] - v[0]) / 2, (v[3] - v[1]) / 2
        t2, t3 = t * t, t * t * t
        out = (2 * t3 - 3 * t2 + 1) * v[1] + (t3 - 2 * t2 + t) * m1 + (3 * t2 - 2 * t3) * v[2] + (t3 - t2) * m2
        return np.maximum(out, 0.0)[:, 0]
    lg = [np.log(np.maximum(x, RIM_LOG_FLOOR)) for x in v]
    pos = [np.full_like(v[0], float(s)) for s in (-1, 0, 1, 2)]
    return np.exp(pchip_between(lg, pos, np.full_like(v[0], t)))[:, 0]


def errors(all_lobes, m, kind, k, phi_deg):
    ref = all_lobes[int(round(phi_deg / STEP)), k][GRID.inside]
    wo = GRID.directions()[GRID.inside]
    sel = (wo[:, 2] > np.cos(np.radians(60.0))) & (ref > 0.01 * ref.max())
    e = np.abs(read(m, kind, k, phi_deg, wo[sel]) / ref[sel] - 1)
    return np.percentile(e, 90), e.max()


class Shifted(TabulatedTwoScaleBRDF):
    """Today's read (before issue 28's fix) of the same tables: shifted in direction cosines, never by h."""
    half_vector_read = False


def between_incidence(path, all_lobes):
    """θ_i 30° and 60° midway between incidence nodes 25/35° and 55/65°: the library's half-vector read of 12
    azimuth nodes and the shifted read of 4 nodes, against the lobes at that light (:func:`lobes`)."""
    thetas = (25.0, 35.0, 55.0, 65.0)
    if os.path.exists(path):
        lob = np.load(path)["lobes"]
    else:
        lob = np.zeros((12, len(thetas), GRID.n_v, GRID.n_u))
        for a in range(6):
            for k, th in enumerate(thetas):
                lob[a, k] = brdf.evaluate(_dir(th, 30.0 * a), [LAM], "aluminium", MICRO, NANO, GRID).diffraction[0]
        lob[6:] = lob[:6, :, ::-1, ::-1]
        np.savez(path, lobes=lob)
    wo = GRID.directions()[GRID.inside]
    for cls, n in ((Shifted, 4), (TabulatedTwoScaleBRDF, 12)):
        m = cls("aluminium", MICRO, nano=NANO, wavelengths_nm=(LAM,), thetas_deg=thetas, rim=False,
                table_lobes=lob[::12 // n][:, :, None], table_grid=GRID, table_phis_deg=tuple(360.0 * np.arange(n) / n))
        for k, th in enumerate(THETAS):
            e = []
            for phi in np.arange(0.0, 90.0 + 1e-9, STEP):
                ref = all_lobes[int(round(phi / STEP)), k][GRID.inside]
                sel = (wo[:, 2] > np.cos(np.radians(60.0))) & (ref > 0.01 * ref.max())
                got = m.eval_parts(np.broadcast_to(_dir(th, phi), wo[sel].shape), wo[sel], LAM)["diffraction"]
                r = np.abs(got / ref[sel] - 1)
                e.append((np.percentile(r, 90), r.max(), got.sum() / ref[sel].sum() - 1))
            e = np.array(e)
            print(f"between incidence nodes, {cls.__name__} N {n:2d} θ_i {th:2.0f}: worst p90 / max "
                  f"{100 * e[:, 0].max():.1f} / {100 * e[:, 1].max():.1f} %, sum over the cells within "
                  f"{100 * np.abs(e[:, 2]).max():.1f} %", flush=True)


def main():
    all_lobes = lobes(sys.argv[1] if len(sys.argv) > 1 else "/tmp/aniso_lobes.npz")
    phis = np.arange(0.0, 90.0 + 1e-9, STEP)
    if sys.argv[2:3] == ["between"]:
        return between_incidence("/tmp/aniso_lobes_between.npz" if len(sys.argv) < 4 else sys.argv[3], all_lobes)
    runs = [(int(a), b.split(",")) for a, b in (x.split(":") for x in sys.argv[2:])] or [
        (4, ["shift-lin", "turn-lin", "turn-log", "half-lin", "half-log"])] + [
        (n, ["turn-lin", "turn-log", "half-lin", "half-log"]) for n in (8, 12, 16, 24)] + [(12, ["lib"])]
    for n, kinds in runs:
        m = table(all_lobes, n)
        for kind in kinds:
            for k, th in enumerate(THETAS):
                e = np.array([errors(all_lobes, m, kind, k, p) for p in phis])
                row = " ".join(f"{100 * a:4.0f}/{100 * b:4.0f}" for a, b in e)
                print(f"N {n:2d} {kind:8s} θ_i {th:2.0f}: p90/max % at φ_i 0..90 step 7.5: {row} | worst "
                      f"{100 * e[:, 0].max():.1f} % / {100 * e[:, 1].max():.1f} %", flush=True)


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"{time.perf_counter() - t0:.1f} s")
