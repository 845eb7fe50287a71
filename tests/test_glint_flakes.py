"""The patch NDF of a flake field (issue 32 c): flakes are planes with steps at their borders, and the geometric
footprint BRDF must hold only the flakes' own normals. The reference is written here from the generator's seeds —
each cell's flake drawn from ``default_rng(SeedSequence([seed, 2, cx, cy]))`` (indices shifted by 2⁴⁰), each sample
on the flake of its nearest centre (brute force) — and P22(t) = Σ G N(s_flake − t; σ_s²) / Σ G over the footprint's
3√2 σ ellipse (G ≥ e⁻⁹, the kernel's truncation; Yan et al. 2016's patch NDF with intrinsic roughness)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from waveoptics import surfaces
from waveoptics.errors import FieldError
from waveoptics.renderers import glints
from waveoptics.scatter import pixel_brdf
from waveoptics.surfaces import Footprint
from waveoptics.surfaces import tiled
from waveoptics.surfaces.tiled import FlakeField

DX = 0.1e-6
SIZE, TILT, SEED = 5e-6, 8.0, 4
SIGMA_S = 0.01


def _flakes(x0, x1, y0, y1):
    """(centre x, centre y, slope x, slope y) of every cell's flake around [x0, x1] × [y0, y1], from the seeds."""
    out = []
    for cy in range(int(y0 // SIZE) - 2, int(y1 // SIZE) + 3):
        for cx in range(int(x0 // SIZE) - 2, int(x1 // SIZE) + 3):
            rng = np.random.default_rng(np.random.SeedSequence([SEED, 2 + 2 ** 40, cx + 2 ** 40, cy + 2 ** 40]))
            u = rng.random(2)
            s = rng.normal(0.0, math.tan(math.radians(TILT)), 2)
            out.append(((cx + u[0]) * SIZE, (cy + u[1]) * SIZE, s[0], s[1]))
    return np.array(out)


def _reference(fp_x, fp_y, sigma):
    """(G weights, slopes (n, 2) of each sample's flake, the heights) over a ±4.5σ box, G truncated to the circle
    r²/σ² ≤ 18 (G ≥ e⁻⁹, as the kernel; the samples on the circle itself, to 1e-9, count)."""
    i0, i1 = math.floor((fp_x - 4.5 * sigma) / DX), math.ceil((fp_x + 4.5 * sigma) / DX) + 1
    j0, j1 = math.floor((fp_y - 4.5 * sigma) / DX), math.ceil((fp_y + 4.5 * sigma) / DX) + 1
    X, Y = np.meshgrid(np.arange(i0, i1) * DX, np.arange(j0, j1) * DX)
    F = _flakes(X.min(), X.max(), Y.min(), Y.max())
    d2 = (X.ravel()[:, None] - F[:, 0]) ** 2 + (Y.ravel()[:, None] - F[:, 1]) ** 2
    k = np.argmin(d2, axis=1)
    r2 = ((X.ravel() - fp_x) ** 2 + (Y.ravel() - fp_y) ** 2) / sigma ** 2
    G = np.exp(-0.5 * r2) * (r2 <= 18 * (1 + 1e-9))
    h = F[k, 2] * (X.ravel() - F[k, 0]) + F[k, 3] * (Y.ravel() - F[k, 1])
    return G, F[k, 2:], h.reshape(X.shape), (i0, j0, i1, j1)


def _half_vectors(t):
    """Unit half vectors of slopes t (n, 2): h ∝ (−t_x, −t_y, 1)."""
    h = np.column_stack([-t[:, 0], -t[:, 1], np.ones(len(t))])
    return h / np.linalg.norm(h, axis=1, keepdims=True)


FX, FY, SIG = 40e-6, 41e-6, 3e-6


def _probe():
    """The seeds' patch NDF of the footprint (FX, FY, SIG) at each flake's own slope and at slopes far from every
    flake (≥ 10 σ_s): (half vectors (n, 2 + far), P22 wanted, number of own slopes, the reference's heights and
    box)."""
    G, slopes, h, box = _reference(FX, FY, SIG)
    own = np.unique(slopes, axis=0)
    g = np.linspace(-0.45, 0.45, 25)
    grid = np.column_stack([a.ravel() for a in np.meshgrid(g, g)])
    far = grid[np.min(np.linalg.norm(grid[:, None, :] - own[None], axis=-1), axis=1) > 10 * SIGMA_S]
    assert len(own) >= 3 and len(far) > 300
    t = np.vstack([own, far])
    own, which = np.unique(slopes, axis=0, return_inverse=True)
    W = np.bincount(which.ravel(), weights=G)                            # G-weight of each flake in the footprint
    d2 = np.sum((own[None] - t[:, None]) ** 2, axis=-1)
    want = (np.exp(-0.5 * d2 / SIGMA_S ** 2) @ W) / (G.sum() * 2 * math.pi * SIGMA_S ** 2)
    return _half_vectors(t), want, len(own), h, box


def _ndf(field, hv, x=FX, y=FY):
    """The geometric footprint BRDF of *field* at ω_i = ω_o = hv, times 4 h_z⁶ (= P22 with F = 1)."""
    r = pixel_brdf(field, [Footprint(x, y, SIG)] * len(hv), hv, hv, (550.0,), slope_sigma=SIGMA_S)
    return r.geometric[:, 0] * 4 * hv[:, 2] ** 6


def test_flake_patch_ndf_holds_only_the_flakes_normals():
    """At ω_i = ω_o = h (so f = P22 / (4 h_z⁶), F = 1) the geometric footprint BRDF of a flake field equals the
    seeds' P22 to 1e-9 of its peak at each flake's own slope and at slopes far from every flake (≥ 10 σ_s:
    no facet is there, f < 1e-12 of the peak); the same heights with central differences (a plain HeightField)
    do show facets there, > 1e-5 of the peak (the steps between flakes: the cross artefact's cause)."""
    field = FlakeField((800, 800), DX, size_flake=SIZE, tilt_deg=TILT, seed=SEED)
    hv, want, n_own, h, (i0, j0, i1, j1) = _probe()
    got = _ndf(field, hv)
    peak = want.max()
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * peak)
    assert np.all(got[n_own:] < 1e-12 * peak)
    # the same heights as a plain height field (central differences across the steps): facets no flake has
    hf = surfaces.HeightField(field.region(i0 - 3, j0 - 3, i1 + 3, j1 + 3).heights, DX, DX)
    np.testing.assert_allclose(hf.heights[3:-3, 3:-3], h, rtol=0, atol=1e-15)      # the seeds' heights
    spurious = _ndf(hf, hv, FX - (i0 - 3) * DX, FY - (j0 - 3) * DX)[n_own:]
    assert np.max(spurious) > 1e-5 * peak


def test_flake_field_read_from_a_file_keeps_each_flakes_plane(tmp_path):
    """A flake field written to disk (float32 heights; .npy and chunked HDF5, by tiles) with its label map and
    plane slopes (surfaces.regions): read back as NpyField, HDF5Field or open_large, its geometric footprint
    BRDF equals the seeds' P22 to 1e-9 of the peak, < 1e-12 far from every flake; the same .npy without its
    regions differences across the steps (> 1e-5 of the peak far from every flake)."""
    src = FlakeField((560, 560), DX, size_flake=SIZE, tilt_deg=TILT, seed=SEED)
    hv, want, n_own, _, _ = _probe()
    peak = want.max()
    npy = tiled.create_npy(tmp_path / "flakes.npy", 560, 560, DX)
    h5 = tiled.create_hdf5(tmp_path / "flakes.h5", 560, 560, DX, chunk=128)
    assert tiled.write_tiles(npy, src, tile=256) == 9 and tiled.write_tiles(h5, src, tile=256) == 9
    lab, tab = surfaces.npy_region_paths(npy.path)
    assert lab.name == "flakes.regions.npy" and np.load(lab, mmap_mode="r").dtype == np.int32
    for field in (npy, h5, tiled.NpyField(npy.path), tiled.HDF5Field(h5.path), surfaces.open_large(npy.path)):
        assert field.gives_slopes
        got = _ndf(field, hv)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * peak)
        assert np.all(got[n_own:] < 1e-12 * peak)
    lab.unlink()
    plain = surfaces.open_large(npy.path)
    assert not plain.gives_slopes
    assert np.max(_ndf(plain, hv)[n_own:]) > 1e-5 * peak


def test_stored_regions_are_checked(tmp_path):
    """Labels outside the table, or a label map of another shape, are refused, naming the field."""
    npy = tiled.create_npy(tmp_path / "f.npy", 40, 40, DX)
    with pytest.raises(FieldError, match="index the table"):
        surfaces.write_regions(npy.path, (40, 40), np.full((4, 4), 3, np.int32), np.zeros((2, 2)))
    surfaces.write_regions(npy.path, (40, 40), np.ones((4, 4), np.int32), np.zeros((2, 2)), (36, 36))
    np.save(surfaces.npy_region_paths(npy.path)[1], np.zeros((1, 2)))          # the table shrinks under the map
    with pytest.raises(FieldError, match="outside the table") as e:
        tiled.NpyField(npy.path).region_slopes(30, 30, 40, 40)
    assert e.value.field == "regions"
    np.save(surfaces.npy_region_paths(npy.path)[0], np.zeros((3, 3), np.int32))
    with pytest.raises(FieldError, match="shape"):
        tiled.NpyField(npy.path)


def test_flake_plane_render_geometric_panel_has_no_step_facets():
    """A 16² plane render of a flake field: the geometric BRDF of 30 random lit pixels is the seeds' P22 at each
    one's own footprint and half vector (1e-9 of the brightest), so no pixel shows a normal outside its flakes'
    normals."""
    field = FlakeField((700, 700), DX, size_flake=SIZE, tilt_deg=TILT, seed=SEED)
    s = glints.GlintSettings(size=16, shape="plane", view_deg=20.0, light_deg=25.0, wavelengths_nm=(550.0,),
                             intrinsic_slope=SIGMA_S)
    r = glints.render_glints(field, "f0:1", s)
    lit = np.argwhere(r.on_field & (r.directions[..., 2] > 0) & (r.directions[..., 5] > 0))
    assert len(lit) > 80
    got, want = [], []
    for j, i in lit[np.random.default_rng(7).choice(len(lit), 30, replace=False)]:
        x, y, s1, s2, ang = r.footprints[j, i]
        wi, wo = r.directions[j, i, :3], r.directions[j, i, 3:]
        hv = (wi + wo) / np.linalg.norm(wi + wo)
        t = -hv[:2] / hv[2]
        c, sn = math.cos(math.radians(ang)), math.sin(math.radians(ang))
        Rm = np.array([[c, -sn], [sn, c]])
        C = Rm @ np.diag([s1 * s1, s2 * s2]) @ Rm.T                 # σ_1 along the angle, counter-clockwise
        Ci = np.linalg.inv(C)
        hx, hy = 4.5 * math.sqrt(C[0, 0]), 4.5 * math.sqrt(C[1, 1])
        i0, i1 = math.floor((x - hx) / DX), math.ceil((x + hx) / DX) + 1
        j0, j1 = math.floor((y - hy) / DX), math.ceil((y + hy) / DX) + 1
        X, Y = np.meshgrid(np.arange(i0, i1) * DX, np.arange(j0, j1) * DX)
        F = _flakes(X.min(), X.max(), Y.min(), Y.max())
        k = np.argmin((X.ravel()[:, None] - F[:, 0]) ** 2 + (Y.ravel()[:, None] - F[:, 1]) ** 2, axis=1)
        rx, ry = X.ravel() - x, Y.ravel() - y
        q = Ci[0, 0] * rx * rx + 2 * Ci[0, 1] * rx * ry + Ci[1, 1] * ry * ry
        G = np.exp(-0.5 * q) * (q <= 18 * (1 + 1e-9))                          # truncated: G ≥ e⁻⁹
        P22 = (np.exp(-0.5 * np.sum((F[k, 2:] - t) ** 2, axis=1) / SIGMA_S ** 2) @ G) / (
            G.sum() * 2 * math.pi * SIGMA_S ** 2)
        want.append(P22 / hv[2] ** 4 / (4 * wi[2] * wo[2]))
        got.append(r.geometric_brdf[j, i, 0])
    got, want = np.array(got), np.array(want)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-9 * want.max())
