"""Height fields of real size read by patches (waveoptics.surfaces.tiled): continuity across tiles, determinism,
statistics against closed forms, primitives against brute force written here, and 10⁸-sample fields read with
little memory."""
import math
import tracemalloc

import numpy as np
import pytest

from waveoptics.errors import FieldError
from waveoptics.surfaces import Footprint, footprint_patch, tiled

DX = 0.1e-6


def _fields(n=4000):
    return {
        "psd": tiled.PSDField("gaussian", 20e-9, 1e-6, (n, n), DX, seed=5, tile=64),
        "psd_abc": tiled.PSDField("abc", 10e-9, 2e-6, (n, n), DX, seed=6, tile=64, C=3.5),
        "brushed": tiled.brushed((n, n), DX, seed=7),
        "scratched": tiled.scratched((n, n), DX, seed=8),
        "flakes": tiled.FlakeField((n, n), DX, size_flake=3e-6, tilt_deg=8.0, seed=9),
    }


@pytest.mark.parametrize("name", ["psd", "psd_abc", "brushed", "scratched", "flakes"])
def test_patches_agree_on_their_overlap(name):
    """Two patches crossing different tile and cell borders agree on their overlap to round-off (one global
    field), and a new instance with the same seed gives the same samples."""
    f = _fields()[name]
    big = f.patch(1000, 1200, 300, 260).heights
    small = f.patch(1137, 1301, 97, 83).heights
    ref = big[1301 - 1200:1301 - 1200 + 83, 1137 - 1000:1137 - 1000 + 97]
    scale = np.max(np.abs(big))
    assert scale > 0
    assert np.max(np.abs(small - ref)) <= 1e-12 * scale
    again = _fields()[name].patch(1137, 1301, 97, 83).heights
    assert np.array_equal(again, small)
    other = type(f).__reduce__(f)
    g = other[0](*other[1])
    assert np.array_equal(g.patch(1137, 1301, 97, 83).heights, small)     # pickled form rebuilds the same field


def test_psd_field_statistics_match_the_gaussian_correlation():
    """rms height σ and the correlation at lags T/2, T (C(r) = σ² exp(−r²/T²), Ogilvy 1991 eq. 2.14) from a
    1200² patch (120 T × 120 T)."""
    sigma, T = 20e-9, 1e-6
    f = tiled.PSDField("gaussian", sigma, T, (20000, 20000), DX, seed=11, tile=128)
    assert f.kernel_energy_kept > 1 - 1e-6
    h = f.patch(3000, 9000, 1200, 1200).heights
    h = h - h.mean()
    assert abs(h.std() / sigma - 1) < 0.04
    for lag in (5, 10):
        c = np.mean(h[:, :-lag] * h[:, lag:]) / np.mean(h * h)
        assert abs(c - math.exp(-(lag * DX / T) ** 2)) < 0.03


def test_psd_field_seeds_differ():
    a = tiled.PSDField("gaussian", 20e-9, 1e-6, (1000, 1000), DX, seed=1).patch(0, 0, 50, 50).heights
    b = tiled.PSDField("gaussian", 20e-9, 1e-6, (1000, 1000), DX, seed=2).patch(0, 0, 50, 50).heights
    assert abs(np.corrcoef(a.ravel(), b.ravel())[0, 1]) < 0.5


def test_scratches_equal_a_brute_force_sum_of_grooves():
    """Heights = min over every groove of the Gaussian groove profile with rounded ends, evaluated here on every
    sample from the cells' scratch lists (no cut-off at 3 widths)."""
    f = tiled.ScratchField((3000, 3000), DX, width=0.6e-6, depth=40e-9, length=8e-6, density=1 / (4e-6) ** 2,
                           spread_deg=90.0, variation=0.3, seed=4)
    i0, j0, n = 1234, 1500, 120
    h = f.patch(i0, j0, n, n).heights
    x = (i0 + np.arange(n)) * DX
    y = (j0 + np.arange(n)) * DX
    X, Y = np.meshgrid(x, y)
    ref = np.zeros_like(X)
    c0x, c0y = int(x[0] // f.cell), int(y[0] // f.cell)
    for cy in range(c0y - 3, c0y + 4):
        for cx in range(c0x - 3, c0x + 4):
            for px, py, th, w, d in f.scratches(cx, cy):
                t = (X - px) * math.cos(th) + (Y - py) * math.sin(th)
                s = -(X - px) * math.sin(th) + (Y - py) * math.cos(th)
                e = np.maximum(np.abs(t) - 4e-6, 0)
                ref = np.minimum(ref, -d * np.exp(-4 * math.log(2) * (s * s + e * e) / (w * w)))
    assert ref.min() < -20e-9
    assert np.max(np.abs(h - ref)) < 1e-9 * 40e-9 * 1e3     # the 3-width cut-off: exp(-36 ln2) ~ 1.5e-11 of d


def test_flakes_lie_on_the_plane_of_the_nearest_centre():
    f = tiled.FlakeField((4000, 4000), DX, size_flake=2e-6, tilt_deg=10.0, seed=3)
    i0, j0, n = 2000, 100, 60
    h = f.patch(i0, j0, n, n).heights
    C = np.array([f.flake(cx, cy) for cy in range(-3, 12) for cx in range(95, 112)])
    x = (i0 + np.arange(n)) * DX
    y = (j0 + np.arange(n)) * DX
    X, Y = np.meshgrid(x, y)
    d2 = (X[..., None] - C[:, 0]) ** 2 + (Y[..., None] - C[:, 1]) ** 2
    k = np.argmin(d2, axis=-1)
    ref = C[k, 2] * (X - C[k, 0]) + C[k, 3] * (Y - C[k, 1])
    assert np.max(np.abs(h - ref)) < 1e-18


def _peak_mb(fn):
    tracemalloc.start()
    try:
        out = fn()
        return out, tracemalloc.get_traced_memory()[1] / 2 ** 20
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("kind", ["npy", "hdf5", "procedural"])
def test_1mm_field_at_0p1um_reads_a_footprint_with_little_memory(tmp_path, kind):
    """A 1 mm × 1 mm field at 0.1 µm (10⁸ samples): a σ = 5 µm footprint's patch is read with a peak of a few MB
    (its ~401² samples), nowhere near the 0.8 GB (float64) of the field, and on disk equals the source it was
    written from (only the tiles it needs are written)."""
    n = 10000
    src = tiled.PSDField("gaussian", 20e-9, 1e-6, (n, n), DX, seed=21)
    fp = Footprint(731.3e-6, 402.9e-6, 5e-6)
    if kind == "npy":
        field = tiled.create_npy(tmp_path / "big.npy", n, n, DX)
    elif kind == "hdf5":
        field = tiled.create_hdf5(tmp_path / "big.h5", n, n, DX, chunk=512)
    else:
        field = src
    assert field.shape == (n, n) and field.shape[0] * field.shape[1] == 10 ** 8
    if kind != "procedural":
        tile = 1024
        need = {(tx, ty) for tx in (int((fp.x - 20e-6) / DX) // tile, int((fp.x + 20e-6) / DX) // tile)
                for ty in (int((fp.y - 20e-6) / DX) // tile, int((fp.y + 20e-6) / DX) // tile)}
        assert tiled.write_tiles(field, src, need, tile) == len(need)
        field = type(field).__reduce__(field)[0](*type(field).__reduce__(field)[1])    # reopen
    (patch, G), peak = _peak_mb(lambda: footprint_patch(field, fp))
    assert 401 <= patch.shape[0] <= 402 and 401 <= patch.shape[1] <= 402
    assert peak < 50
    ref, _ = footprint_patch(src, fp)
    tol = 1e-7 * np.max(np.abs(ref.heights)) if kind != "procedural" else 0.0     # float32 on disk
    assert np.max(np.abs(patch.heights - ref.heights)) <= tol
    if kind == "npy":
        assert (tmp_path / "big.npy").stat().st_blocks * 512 < 100e6        # sparse: 400 MB apparent


def test_bad_patches_are_refused():
    f = tiled.FlakeField((100, 100), DX, size_flake=1e-6, tilt_deg=5.0)
    with pytest.raises(FieldError, match="leaves the field"):
        f.patch(90, 0, 20, 5)
    with pytest.raises(FieldError, match="model"):
        tiled.PSDField("lorentz", 1e-9, 1e-6, (10, 10), DX)


def test_psd_field_stretch_makes_it_anisotropic():
    """stretch = (3, 1): correlation length 3 T along x and T along y (C = σ² exp(−x²/(3T)² − y²/T²))."""
    sigma, T = 10e-9, 0.5e-6
    f = tiled.PSDField("gaussian", sigma, T, (20000, 20000), DX, seed=12, tile=128, stretch=(3.0, 1.0))
    h = f.patch(5000, 5000, 1500, 1500).heights
    h = h - h.mean()
    assert abs(h.std() / sigma - 1) < 0.06
    v = np.mean(h * h)
    cx = np.mean(h[:, :-15] * h[:, 15:]) / v                 # lag 1.5 µm along x
    cy = np.mean(h[:-5, :] * h[5:, :]) / v                   # lag 0.5 µm along y
    assert abs(cx - math.exp(-1.0)) < 0.06 and abs(cy - math.exp(-1.0)) < 0.04
