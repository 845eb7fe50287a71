"""Footprint queries on large height fields (issue 18): the wave-optics BRDF of a Gaussian pixel footprint against an
independent float64 Kirchhoff sum written here, the geometric footprint NDF of scratches, the mean of many
footprints against the stationary BRDF of the whole field, a plane seen the same everywhere, and memory-mapped
fields read only where a footprint looks."""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import brdf, scatter, surfaces
from waveoptics.errors import WaveopticsError
from waveoptics.units import direction_from_angles

LAM = 550.0


@pytest.fixture(scope="module")
def field():
    """A Gaussian random surface, σ = 20 nm, correlation 1 µm, 40 µm square on 1024² samples (39 nm)."""
    return surfaces.generate("gaussian", sigma="20nm", corr_length="1um", size="40um", samples=1024, seed=3)


def kirchhoff_sum(hf, weights, wi, wo, lam_nm):
    """f = K |Σ G e^{i k (ω_i+ω_o)·r} Δx Δy|² / (Σ G² Δx Δy), F = 1, in float64 (the tangent-plane formula of
    Beckmann & Spizzichino 1963, written here independently of waveoptics.scatter)."""
    k = 2 * np.pi / (lam_nm * 1e-9)
    ny, nx = hf.shape
    x = np.arange(nx) * hf.dx
    y = np.arange(ny) * hf.dy
    X, Y = np.meshgrid(x, y)
    h = hf.heights - np.sum(weights ** 2 * hf.heights) / np.sum(weights ** 2)
    area = np.sum(weights ** 2) * hf.dx * hf.dy
    out = []
    for d in wo:
        s = wi + d
        U = np.sum(weights * np.exp(1j * k * (s[0] * X + s[1] * Y + s[2] * h))) * hf.dx * hf.dy
        ci, co = wi[2], d[2]
        K = np.sum(s * s) ** 2 / (4 * (lam_nm * 1e-9) ** 2 * ci * co * (ci + co) ** 2)
        out.append(K * abs(U) ** 2 / area)
    return np.array(out)


def test_footprint_brdf_is_the_windowed_kirchhoff_sum_of_its_patch(field):
    fp = surfaces.Footprint(18e-6, 22e-6, 1.2e-6, 0.8e-6, 30.0)
    wi = direction_from_angles(30.0, 20.0)
    res = scatter.footprint_scatter(field, fp, wi, [LAM], None, resolution=64)
    patch, G = surfaces.footprint_patch(field, fp)
    dirs = res.grid.directions()[res.grid.inside]
    got = res.brdf[0][res.grid.inside]
    pick = np.argsort(got)[::-1][:: max(1, got.size // 60)][:60]      # from the peak down into the tail
    want = kirchhoff_sum(patch, G, wi, dirs[pick], LAM)
    np.testing.assert_allclose(got[pick], want, rtol=1e-5, atol=1e-9 * want.max())
    assert res.info["footprint"]["patch_samples"] == list(patch.shape[::-1])


def test_a_plane_looks_the_same_under_every_footprint():
    """A tilted plane: every footprint sees the same surface, so the same BRDF (only a phase differs)."""
    n, dx = 512, 40e-9
    x = np.arange(n) * dx
    plane = surfaces.HeightField(0.02 * x[None, :] + 0.01 * x[:, None] + np.zeros((n, n)), dx, dx)
    wi = direction_from_angles(25.0, 0.0)
    a = scatter.footprint_scatter(plane, surfaces.Footprint(5e-6, 6e-6, 1e-6), wi, [LAM], "Al", resolution=64)
    b = scatter.footprint_scatter(plane, surfaces.Footprint(14e-6, 12e-6, 1e-6), wi, [LAM], "Al", resolution=64)
    np.testing.assert_allclose(a.brdf, b.brdf, rtol=1e-6, atol=2e-5 * a.brdf.max())   # float32 fft solver


def test_many_footprints_average_to_the_stationary_brdf(field):
    """The mean of 25 footprint BRDFs (σ_p = 2 µm on a 5 × 5 lattice) tends to the BRDF of the whole 40 µm field:
    away from the specular peak (> 0.15 in direction cosines, where the lobe is above 1 % of its peak), both
    smoothed over 5 × 5 cells (the whole field's own speckle is λ/L = 0.014 wide), they differ by 14 % (median),
    tested < 20 %; the scattered fractions agree within 5 %."""
    from scipy import ndimage

    wi = direction_from_angles(20.0, 0.0)
    grid = scatter.DirectionGrid.hemisphere(64)
    whole = scatter.scatter(field, wi, [LAM], "Al", grid=grid)
    pos = np.linspace(10e-6, 30e-6, 5)
    runs = [scatter.footprint_scatter(field, surfaces.Footprint(x, y, 2e-6), wi, [LAM], "Al", grid=grid)
            for x in pos for y in pos]
    mean = scatter.incoherent_sum(runs, np.full(len(runs), 1 / len(runs)))
    a, b = (ndimage.uniform_filter(r.brdf[0], 5) for r in (mean, whole))
    u, v = grid.u[None, :], grid.v[:, None]
    away = grid.inside & (np.hypot(u + wi[0], v + wi[1]) > 0.15) & (b > 0.01 * b.max())
    assert np.median(np.abs(a[away] / b[away] - 1)) < 0.20
    assert mean.scattered_fraction[0] == pytest.approx(whole.scattered_fraction[0], rel=0.05)


def test_coherence_area_smaller_than_the_footprint_adds_intensities(field):
    """Windows of 0.75 µm over a 1.5 µm footprint: a wider, smoother lobe (the specular peak widens as λ/σ_c) with
    the same light; the limit of a coherence area as wide as the footprint is the coherent footprint."""
    fp = surfaces.Footprint(20e-6, 20e-6, 1.5e-6)
    wi = direction_from_angles(30.0, 0.0)
    grid = scatter.DirectionGrid.hemisphere(64)
    coh = scatter.footprint_scatter(field, fp, wi, [LAM], "Al", grid=grid)
    inc = scatter.footprint_scatter(field, fp, wi, [LAM], "Al", grid=grid, coherence_m=0.75e-6)
    assert inc.info["footprint"]["coherence_windows"] > 9
    assert inc.albedo[0] == pytest.approx(coh.albedo[0], rel=0.03)
    assert inc.brdf.max() < coh.brdf.max()
    same = scatter.footprint_scatter(field, fp, wi, [LAM], "Al", grid=grid, coherence_m=1.5e-6)
    np.testing.assert_array_equal(same.brdf, coh.brdf)


def test_footprint_ndf_of_parallel_scratches_lies_across_them():
    """Scratches along x tilt the normals about x: the footprint's slope law spreads along ỹ, not x̃."""
    hf = surfaces.scratches(80, "1um", "60nm", "30um", 512, orientation_deg=0.0, spread_deg=1.0, seed=5)
    table = brdf.footprint_ndf(hf, surfaces.Footprint(15e-6, 15e-6, 3e-6))
    sx, sy = table.rms_slope()
    assert sy > 0.02 and sx < 0.15 * sy
    assert table.source["footprint"]["sigma_m"] == 3e-6
    # the weighted law is normalized: ∫ P22 d(slope)² = 1
    assert np.sum(table.P) * table.step ** 2 == pytest.approx(1.0, rel=1e-12)


def test_memory_mapped_field_reads_the_same_patch(tmp_path, field):
    path = tmp_path / "big.npy"
    surfaces.save(field, path)
    big = surfaces.open_large(path)
    assert isinstance(big, surfaces.LargeHeightField) and isinstance(big.array, np.memmap)
    fp = surfaces.Footprint(7e-6, 31e-6, 1e-6)
    p1, g1 = surfaces.footprint_patch(big, fp)
    p2, g2 = surfaces.footprint_patch(field, fp)
    np.testing.assert_array_equal(p1.heights, p2.heights)
    np.testing.assert_array_equal(g1, g2)
    assert p1.shape[0] * p1.shape[1] < 0.05 * field.shape[0] * field.shape[1]   # 207² of 1024²


def test_footprint_bad_input():
    hf = surfaces.generate("gaussian", sigma="5nm", corr_length="1um", size="10um", samples=128, seed=1)
    with pytest.raises(WaveopticsError, match="leaves the field"):
        surfaces.footprint_patch(hf, surfaces.Footprint(1e-6, 5e-6, 1e-6))
    with pytest.raises(WaveopticsError, match="width must be > 0"):
        surfaces.Footprint(1e-6, 1e-6, 0.0)
    with pytest.raises(WaveopticsError, match="X,Y,SIGMA"):
        surfaces.Footprint.parse("1um,2um")


def test_cli_footprint(tmp_path, field):
    path = tmp_path / "big.npy"
    surfaces.save(field, path)
    rc, out, err, _ = run_cli(["scatter", "--surface", str(path), "--footprint", "20um,20um,1.5um", "--material",
                               "Al", "--incident", "30", "--wavelengths", "550", "--resolution", "64", "-o",
                               str(tmp_path / "s"), "--json"])
    assert rc == 0, err
    d = json.loads(out)
    assert d["surface_info"]["memory_mapped"] and d["surface_info"]["footprint"]["sigma_m"] == 1.5e-6
    rc, _, err, _ = run_cli(["scatter", "--surface", str(path), "--footprint", "39um,20um,1.5um", "--material",
                             "Al", "--incident", "30", "-o", str(tmp_path / "t")])
    assert rc == 2 and "leaves the field" in err and len(err.strip().splitlines()) == 1
    rc, _, err, _ = run_cli(["scatter", "--surface", str(path), "--coherence", "1um", "--material", "Al",
                             "--incident", "30", "-o", str(tmp_path / "u")])
    assert rc == 2 and "--coherence" in err
    rc, out, err, _ = run_cli(["brdf", "--model", "microfacet", "--micro-surface", str(path), "--footprint",
                               "20um,20um,1.5um", "--material", "Au", "--incident", "30", "--outgoing", "30,180",
                               "--json"])
    assert rc == 0, err
    assert json.loads(out)["parameters"]["footprint"] == "20um,20um,1.5um"


def test_cli_gaussian_window(tmp_path, field):
    """--window gaussian:SIGMA is a Gaussian of that width centred on the patch: the footprint at the centre."""
    small = surfaces.crop_region(field, 10e-6, 10e-6, 10e-6, 10e-6)
    p = tmp_path / "s.npz"
    surfaces.save(small, p)
    rc, out, err, _ = run_cli(["scatter", "--surface", str(p), "--window", "gaussian:1.2um", "--material", "Al",
                               "--incident", "30", "--wavelengths", "550", "--resolution", "48", "-o",
                               str(tmp_path / "g"), "--json"])
    assert rc == 0, err
    assert json.loads(out)["albedo"][0] > 0


def test_glint_pixel_is_the_footprint_kirchhoff_sum():
    """The glint renderer's per-pixel wave BRDF (scatter.footprint_brdf, an elliptical turned footprint) is the
    windowed Kirchhoff sum of its footprint (the test's own float64 sum above), at that pixel's direction pair; the
    per-pixel sums truncate the window where G < e⁻⁹ (the ellipse (x − c)ᵀ Σ⁻¹ (x − c) ≤ 18)."""
    from waveoptics.scatter import footprint_brdf

    hf = surfaces.generate("gaussian", sigma="15nm", corr_length="0.8um", size="12um", samples=256, seed=2)
    fp = surfaces.Footprint(6e-6, 6e-6, 0.7e-6, 0.5e-6, 20.0)
    patch, G = surfaces.footprint_patch(hf, fp, n_sigma=4.5)
    G = np.where(G >= np.exp(-9 * (1 + 1e-9)), G, 0.0)
    wi, wo = direction_from_angles(35.0, 10.0), direction_from_angles(20.0, 200.0)
    got, _ = footprint_brdf(hf, fp, wi, wo, [500.0, 600.0], None, precision="float64")
    want = [kirchhoff_sum(patch, G, wi, wo[None], lam)[0] for lam in (500.0, 600.0)]
    np.testing.assert_allclose(got, want, rtol=1e-9)


def test_glint_render_smoke_and_cli(tmp_path):
    """A tiny glint render of scratches: finite, non-negative, light in both images, and they differ (wave
    optics spreads a small footprint's light by diffraction); the CLI writes the set and reports per-pixel time."""
    from waveoptics.renderers import glints

    hf = surfaces.scratches(120, "0.6um", "50nm", "20um", 256, orientation_deg=0.0, spread_deg=30.0, seed=4)
    r = glints.render_glints(hf, "Al", glints.GlintSettings(size=10))
    assert r.on_field.sum() > 20
    for spec, img in ((r.wave_spectral, r.wave), (r.geometric_spectral, r.geometric)):
        assert np.all(np.isfinite(img)) and spec.min() >= 0 and spec[r.on_field].max() > 0
    assert not np.allclose(r.wave, r.geometric, rtol=0.1)
    p = tmp_path / "s.npy"
    surfaces.save(hf, p)
    rc, out, err, _ = run_cli(["render", "--glints", "--surface", str(p), "--sphere-size", "8", "--wavelengths",
                               "500,600", "-o", str(tmp_path / "g"), "--json"])
    assert rc == 0, err
    d = json.loads(out)
    assert d["timings_s"]["per_pixel"] > 0 and (tmp_path / "g" / "glints.png").is_file()
    rc, _, err, _ = run_cli(["render", "--glints", "-o", str(tmp_path / "h")])
    assert rc == 2 and "--surface" in err
