"""Height fields: generators against closed-form statistics, PSD normalization and fits, file round trips,
bad files, CLI. Closed forms from docs/physics.md §1, §4, §5."""
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy.integrate import quad

from waveoptics import surfaces as S
from waveoptics.cli import main as cli_main
from waveoptics.errors import WaveopticsError

# Tolerances, in one place. Ensemble checks average over SEEDS realizations; the quoted spread is the standard
# error of that mean measured at the time of writing (~0.3 %), so the tolerances leave room for finite-patch and
# finite-difference bias (forward differences underestimate the slope by ~dx²/(4T²) = 0.4 % at T = 8 dx).
SEEDS = range(12)
TOL_SIGMA = 0.02        # ensemble rms height vs σ
TOL_T = 0.03            # 1/e correlation length vs T
TOL_SLOPE = 0.03        # rms |∇h| vs α = 2σ/T, per-axis vs √2 σ/T
TOL_PSD_INT = 0.015     # ∫ 2πf S df (trapezoid from f = 0) vs the sample mean square
TOL_FIT = 0.04          # PSD fit parameters vs generator parameters (ensemble mean)
SIG, T = 5e-9, 1e-6     # 5 nm rms, 1 µm correlation length
N, DX = 512, T / 8      # 512² samples at T/8: patch 64 T


def _mean_over_seeds(fn):
    return np.mean([fn(seed) for seed in SEEDS], axis=0)


# ---------------------------------------------------------------------------------------------------- PSD models

@pytest.mark.parametrize("psd2, psd1, args, sigma", [
    (S.S_gaussian, S.S1_gaussian, (SIG, T), SIG),
    (S.S_exponential, S.S1_exponential, (SIG, T), SIG),
    (S.S_abc, S.S1_abc, (S.abc_sigma(1e-28, 3e-6, 3.3), 3e-6, 3.3), S.abc_sigma(1e-28, 3e-6, 3.3)),
])
def test_psd_models_integrate_to_sigma2(psd2, psd1, args, sigma):
    """∫ S d²f = ∫ 2πf S df = σ² and the profile PSD ∫ S₁ df over −∞..∞ = σ² (docs/physics.md §4)."""
    scale = 1 / args[1]   # T or B (the first shape parameter): frequencies of interest are ~1/scale
    v2, _ = quad(lambda f: 2 * np.pi * f * psd2(f, *args), 0, np.inf, limit=400, points=None)
    v1, _ = quad(lambda f: 2 * psd1(f, *args), 0, np.inf, limit=400)
    assert v2 == pytest.approx(sigma**2, rel=1e-7)
    assert v1 == pytest.approx(sigma**2, rel=1e-7)
    # the profile PSD is the marginal ∫ S(fx, fy) dfy
    fx = 0.7 * scale
    marg, _ = quad(lambda fy: 2 * psd2(math.hypot(fx, fy), *args), 0, np.inf, limit=400)
    assert psd1(fx, *args) == pytest.approx(marg, rel=1e-7)


def test_abc_sigma_formula_and_exponential_special_case():
    """σ² = 2πA/(B²(C−2)); C = 3, B = 2πT, A = 2πσ²T² is the exponential PSD."""
    A, B, C = 2.5e-29, 4e-6, 2.7
    assert S.abc_sigma(A, B, C) ** 2 == pytest.approx(2 * np.pi * A / (B**2 * (C - 2)), rel=1e-14)
    assert S.abc_A(S.abc_sigma(A, B, C), B, C) == pytest.approx(A, rel=1e-14)
    f = np.logspace(3, 8, 50)
    np.testing.assert_allclose(S.S_abc(f, S.abc_sigma(2 * np.pi * SIG**2 * T**2, 2 * np.pi * T, 3.0),
                                       2 * np.pi * T, 3.0),
                               S.S_exponential(f, SIG, T), rtol=1e-12)
    with pytest.raises(WaveopticsError, match="C=2.0 .*> 2"):
        S.abc_sigma(A, B, 2.0)


# ---------------------------------------------------------------------------------------------------- generators

def test_gaussian_reproduces_sigma_T_and_beckmann_alpha():
    """Over seeds: rms height σ, 1/e correlation length T, rms |∇h| = 2σ/T (Beckmann α), per axis √2σ/T."""
    def one(seed):
        st_ = S.stats(S.gaussian(SIG, T, N * DX, N, seed))
        return [st_["rms_height_m"], st_["corr_length_m"], st_["rms_slope"], st_["rms_slope_x"],
                st_["rms_slope_y"], st_["beckmann_alpha"]]
    sigma, corr, slope, sx, sy, alpha = _mean_over_seeds(one)
    assert sigma == pytest.approx(SIG, rel=TOL_SIGMA)
    assert corr == pytest.approx(T, rel=TOL_T)
    assert slope == pytest.approx(2 * SIG / T, rel=TOL_SLOPE)
    assert sx == pytest.approx(math.sqrt(2) * SIG / T, rel=TOL_SLOPE)
    assert sy == pytest.approx(math.sqrt(2) * SIG / T, rel=TOL_SLOPE)
    assert alpha == pytest.approx(2 * SIG / T, rel=TOL_SLOPE)


def test_exponential_reproduces_sigma_and_T():
    def one(seed):
        hf = S.exponential(SIG, T, 1024 * DX, 1024, seed)
        return [S.rms_height(hf), S.correlation_length(hf)]
    sigma, corr = _mean_over_seeds(one)
    assert sigma == pytest.approx(SIG, rel=TOL_SIGMA)
    assert corr == pytest.approx(T, rel=2 * TOL_T)  # more power at low f: a patch of 128 T is still finite


def test_gaussian_profile_and_non_square_grids():
    """A 1×N grid is a straight profile of the 2-D surface: σ and T are the same, rms dh/dx = √2 σ/T."""
    def one(seed):
        st_ = S.stats(S.gaussian(SIG, T, 8192 * DX, (8192, 1), seed))
        return [st_["rms_height_m"], st_["corr_length_m"], st_["rms_slope"]]
    sigma, corr, slope = _mean_over_seeds(one)
    assert sigma == pytest.approx(SIG, rel=TOL_SIGMA)
    assert corr == pytest.approx(T, rel=TOL_T)
    assert slope == pytest.approx(math.sqrt(2) * SIG / T, rel=TOL_SLOPE)
    col = S.gaussian(SIG, T, "64um", (1, 256), 3)
    assert col.shape == (256, 1) and col.dx == col.dy == pytest.approx(64e-6 / 256)
    rect = S.gaussian(SIG, T, ("64um", "16um"), (512, 64), 3)
    assert rect.shape == (64, 512)
    assert (rect.dx, rect.dy) == pytest.approx((64e-6 / 512, 16e-6 / 64))
    assert rect.extent == pytest.approx((64e-6, 16e-6))


def test_spectral_normalization_and_exact_rms():
    """Ensemble mean square on the grid is σ² × the resolved fraction (default: no rescale); renormalize=True
    scales it to σ²; exact_rms makes each realization exactly σ; every realization has zero mean."""
    small = dict(sigma=SIG, corr_length=T, size=8 * T, samples=32)   # patch of only 8 T: 0.94 resolved
    frac = S.gaussian(**small, seed=0).meta["psd_variance_fraction"]
    assert 0.8 < frac < 0.99
    ms = np.mean([np.mean(S.gaussian(**small, seed=s).heights ** 2) for s in range(400)])
    ms_re = np.mean([np.mean(S.gaussian(**small, seed=s, renormalize=True).heights ** 2) for s in range(400)])
    assert ms == pytest.approx(frac * SIG**2, rel=0.05)
    assert ms_re == pytest.approx(SIG**2, rel=0.05)
    hf = S.gaussian(SIG, T, N * DX, N, 7, exact_rms=True)
    assert np.sqrt(np.mean(hf.heights**2)) == pytest.approx(SIG, rel=1e-12)
    assert abs(hf.heights.mean()) < 1e-12 * SIG


def test_seeds_reproducible():
    a = S.gaussian(SIG, T, "32um", 128, seed=42)
    b = S.generate("gaussian", sigma="5nm", corr_length="1um", size="32um", samples=128, seed=42)
    c = S.gaussian(SIG, T, "32um", 128, seed=43)
    assert np.array_equal(a.heights, b.heights)
    assert not np.allclose(a.heights, c.heights)
    d = S.gaussian(SIG, T, "32um", 128)              # no seed: one is drawn and recorded
    assert np.array_equal(S.gaussian(SIG, T, "32um", 128, seed=d.meta["seed"]).heights, d.heights)
    s1 = S.scratches(5, "1um", "10nm", "32um", 128, seed=9)
    assert np.array_equal(s1.heights, S.scratches(5, "1um", "10nm", "32um", 128, seed=9).heights)


def test_abc_generator_sigma_and_fit():
    """ABC surfaces from σ or A; the PSD fit recovers A, B, C (ensemble mean)."""
    B, C = 4 * T, 3.5
    hfA = S.abc(B, C, "64um", 64, seed=1, A=S.abc_A(SIG, B, C))
    assert hfA.meta["sigma"] == pytest.approx(SIG, rel=1e-12)

    def one(seed):
        fit = S.fit_psd(S.abc(B, C, 1024 * DX, 1024, seed, sigma=SIG), "abc")
        return [fit["sigma_m"], fit["B_m"], fit["C"]]
    sigma, b, c = _mean_over_seeds(one)
    assert sigma == pytest.approx(SIG, rel=TOL_FIT)
    assert b == pytest.approx(B, rel=TOL_FIT)
    assert c == pytest.approx(C, rel=TOL_FIT)
    with pytest.raises(WaveopticsError, match="exactly one of A"):
        S.abc(B, C, "64um", 64, seed=1)


def test_sinusoid_rms_and_slope():
    """h = a sin(2π u/Λ): rms a/√2 over whole periods; rms |∇h| = √2 π a/Λ (forward differences exactly
    √2 a sin(π dx cosφ/Λ)/dx per axis)."""
    a, P, L, n = 20e-9, 4e-6, 80e-6, 800            # 20 periods, 40 samples per period
    for phi, (cx, cy) in ((0.0, (1, 0)), (90.0, (0, 1)), (math.degrees(math.atan2(3, 4)), (0.8, 0.6))):
        hf = S.sinusoid(a, P, L, n, orientation_deg=phi, phase_deg=17)
        assert hf.meta["periodic"]
        assert S.rms_height(hf) == pytest.approx(a / math.sqrt(2), rel=1e-9)
        dx = L / n
        sx_fd = math.sqrt(2) * a * abs(math.sin(math.pi * dx * cx / P)) / dx
        sy_fd = math.sqrt(2) * a * abs(math.sin(math.pi * dx * cy / P)) / dx
        sx, sy = S.rms_slopes(hf)
        assert sx == pytest.approx(sx_fd, rel=1e-9, abs=1e-15)
        assert sy == pytest.approx(sy_fd, rel=1e-9, abs=1e-15)
        assert S.rms_slope(hf) == pytest.approx(math.sqrt(2) * math.pi * a / P, rel=(math.pi * dx / P) ** 2 / 6)
    assert not S.sinusoid(a, P, 81e-6, n).meta["periodic"]


def test_scratches_geometry():
    """One scratch along x: depth d at its axis and full width w at half depth; count 0 is flat."""
    w, d, n, L = 2e-6, 30e-9, 512, 64e-6
    hf = S.scratches(1, w, d, L, n, orientation_deg=0, seed=5)
    col = hf.heights[:, n // 3]
    assert col.min() == pytest.approx(-d, rel=1e-3)
    assert hf.heights.max() == 0.0
    assert np.sum(col < -d / 2) * hf.dy == pytest.approx(w, abs=hf.dy)
    assert np.ptp(hf.heights, axis=1).max() < 1e-12 * d   # constant along the scratch
    assert not S.scratches(0, w, d, L, 64, seed=1).heights.any()
    many = S.scratches(40, w, d, L, 256, orientation_deg=30, spread_deg=5, length="10um", variation=0.3, seed=2)
    assert many.heights.min() >= -1.3 * d - 1e-18 and many.heights.min() < -0.5 * d


def _scratches_everywhere(count, w, d, L, n, th0, spread, ln, v, seed):
    """:func:`surfaces.scratches` as its docstring states it, every groove evaluated on every cell (the rng drawn in
    the generator's order: centre x, y, direction, width, depth)."""
    rng = np.random.default_rng(seed)
    x = (np.arange(n) - (n - 1) / 2) * (L / n)
    X, Y = x[None, :], x[:, None]
    h = np.zeros((n, n))
    for _ in range(count):
        px, py = rng.uniform(-L / 2, L / 2), rng.uniform(-L / 2, L / 2)
        th = math.radians(th0 + rng.uniform(-spread, spread))
        wi, di = w * rng.uniform(1 - v, 1 + v), d * rng.uniform(1 - v, 1 + v)
        s = -(X - px) * math.sin(th) + (Y - py) * math.cos(th)
        if ln is not None:
            s = np.hypot(s, np.maximum(np.abs((X - px) * math.cos(th) + (Y - py) * math.sin(th)) - ln / 2, 0.0))
        h = np.minimum(h, -di * np.exp(-4 * math.log(2) * s ** 2 / wi ** 2))
    return h


@pytest.mark.parametrize("th0,spread,length", [(0, 8, None), (30, 5, 10e-6), (60, 0, None), (90, 3, 6e-6),
                                               (135, 90, None)])
def test_scratches_visit_only_the_cells_their_grooves_reach(th0, spread, length):
    """The generator's banded grooves (cells within GROOVE_REACH widths of each axis) equal every groove evaluated
    on every cell to 1e-17 of the depth, in every direction (along x, along y, diagonal) and with rounded ends."""
    w, d, L, n = 0.8e-6, 40e-9, 32e-6, 256
    got = S.scratches(30, w, d, L, n, orientation_deg=th0, spread_deg=spread, length=length, variation=0.3, seed=4)
    ref = _scratches_everywhere(30, w, d, L, n, th0, spread, length, 0.3, 4)
    assert ref.min() < -0.5 * d
    np.testing.assert_allclose(got.heights, ref, rtol=0, atol=1e-17 * d)


def test_sum_of_bands_adds_variances():
    """Independent micro + nano bands: σ² adds; HeightField + and * work on one grid and refuse others."""
    comps = [{"model": "gaussian", "sigma": "4nm", "corr_length": "2um"},
             {"model": "gaussian", "sigma": "3nm", "corr_length": "0.25um"}]
    ms = np.mean([np.mean(S.generate("sum", components=comps, size="64um", samples=512, seed=s).heights ** 2)
                  for s in range(8)])
    assert math.sqrt(ms) == pytest.approx(5e-9, rel=TOL_SIGMA)
    a = S.gaussian(SIG, T, "16um", 64, 1)
    b = S.sinusoid(1e-9, "4um", "16um", 64)
    np.testing.assert_array_equal((a + b).heights, a.heights + b.heights)
    assert sum([a, b]).shape == a.shape
    np.testing.assert_array_equal((2 * a).heights, 2 * a.heights)
    with pytest.raises(WaveopticsError, match="different grids"):
        a + S.flat("16um", 32)


def test_generate_registry_errors():
    with pytest.raises(WaveopticsError, match="unknown surface model 'gausian'.*did you mean 'gaussian'"):
        S.generate("gausian", sigma="1nm")
    with pytest.raises(WaveopticsError, match="no parameter 'period'"):
        S.generate("gaussian", sigma="1nm", corr_length="1um", size="1um", samples=8, period="1um")
    with pytest.raises(WaveopticsError, match="needs parameter 'corr_length'"):
        S.generate("gaussian", sigma="1nm", size="1um", samples=8)
    with pytest.raises(WaveopticsError, match="sigma '-1nm' is negative"):
        S.generate("gaussian", sigma="-1nm", corr_length="1um", size="1um", samples=8)
    with pytest.raises(WaveopticsError, match="samples .* integers >= 1"):
        S.flat("1um", 0)
    assert set(S.GENERATORS) >= {"flat", "gaussian", "exponential", "abc", "sinusoid", "scratches"}


@settings(max_examples=25, deadline=None)
@given(nx=st.integers(1, 40), ny=st.integers(1, 40), model=st.sampled_from(["gaussian", "exponential", "abc"]))
def test_any_grid_shape_gives_finite_zero_mean_field(nx, ny, model):
    if nx * ny < 2:
        with pytest.raises(WaveopticsError, match="at least 2 samples"):
            S.generate(model, size="20um", samples=(nx, ny), seed=1,
                       **({"sigma": "2nm", "B": "3um", "C": 3} if model == "abc"
                          else {"sigma": "2nm", "corr_length": "1um"}))
        return
    params = {"sigma": "2nm", "B": "3um", "C": 3} if model == "abc" else {"sigma": "2nm", "corr_length": "1um"}
    hf = S.generate(model, size="20um", samples=(nx, ny), seed=1, **params)
    assert hf.shape == (ny, nx)
    assert np.all(np.isfinite(hf.heights))
    assert abs(hf.heights.mean()) <= 1e-9 * max(np.abs(hf.heights).max(), 1e-30)


# ---------------------------------------------------------------------------------------------------- statistics

def test_psd_integrates_to_mean_square():
    """∫ S d²f = σ² (two-sided): 2-D annuli and a 1-D profile."""
    from scipy.signal.windows import hann

    w = np.outer(hann(N, sym=False), hann(N, sym=False))
    for hf, window in ((S.gaussian(SIG, T, N * DX, N, 3), "auto"),
                       (S.gaussian(SIG, T, N * DX, N, 3), "hann"),
                       (S.exponential(SIG, T, N * DX, N, 4), "auto")):
        f, P = S.psd_radial(hf, window=window)
        integral = np.trapezoid(2 * np.pi * np.r_[0, f] * np.r_[P[0], P], np.r_[0, f])
        h = hf.heights - hf.heights.mean()
        # with a window the PSD carries the window-weighted mean square Σ(wh)²/Σw²
        target = np.mean(h**2) if window == "auto" else np.sum((w * h) ** 2) / np.sum(w**2)
        assert integral == pytest.approx(target, rel=TOL_PSD_INT)
    prof = S.gaussian(SIG, T, 8192 * DX, (8192, 1), 3)
    f, P = S.psd_radial(prof)
    assert 2 * np.trapezoid(np.r_[P[0], P], np.r_[0, f]) == pytest.approx(np.mean(prof.heights**2),
                                                                         rel=TOL_PSD_INT)


def test_psd_matches_model_and_fits_recover_parameters():
    """The radial periodogram follows πσ²T² exp(−π²T²f²); Gaussian and exponential fits recover σ, T."""
    f, P = S.psd_radial(S.gaussian(SIG, T, N * DX, N, 11))
    band = (f > 0.1 / T) & (f < 0.6 / T)
    ratio = P[band] / S.S_gaussian(f[band], SIG, T)
    assert np.median(ratio) == pytest.approx(1.0, rel=0.1)

    def one(seed):
        g = S.fit_psd(S.gaussian(SIG, T, N * DX, N, seed), "gaussian")
        # the grid resolves only part of this slowly falling spectrum, and holds S exactly where it does
        e = S.fit_psd(S.exponential(SIG, T, 1024 * DX, 1024, seed), "exponential")
        p = S.fit_psd(S.gaussian(SIG, T, 8192 * DX, (8192, 1), seed), "gaussian")
        return [g["sigma_m"], g["corr_length_m"], g["beckmann_alpha"], e["sigma_m"], e["corr_length_m"],
                p["sigma_m"], p["corr_length_m"]]
    gs, gT, ga, es, eT, ps, pT = _mean_over_seeds(one)
    assert (gs, gT, ga) == pytest.approx((SIG, T, 2 * SIG / T), rel=TOL_FIT)
    assert (es, eT) == pytest.approx((SIG, T), rel=TOL_FIT)
    assert (ps, pT) == pytest.approx((SIG, T), rel=TOL_FIT)
    with pytest.raises(WaveopticsError, match="unknown PSD model 'lorentz'"):
        S.fit_psd(S.flat("1um", 8), "lorentz")


def test_stats_with_mask_and_plane_detrend():
    """Masked samples are ignored; 'plane' removes a tilt exactly."""
    hf = S.gaussian(SIG, T, N * DX, N, 2)
    x, y = hf.coords()
    tilted = hf.heights + 1e-3 * x[None, :] - 2e-3 * y[:, None] + 7e-9
    mask = np.ones(hf.shape, bool)
    mask[100:140, 200:260] = False
    garbage = np.where(mask, tilted, 1e-3)
    masked = S.HeightField(garbage, hf.dx, hf.dy, mask=mask, meta={"periodic": True})
    ref = S.HeightField(hf.heights, hf.dx, hf.dy, mask=mask)
    s_plane = S.stats(masked, detrend="plane")
    assert s_plane["rms_height_m"] == pytest.approx(S.rms_height(ref), rel=1e-3)
    assert s_plane["valid_fraction"] == pytest.approx(mask.mean())
    assert s_plane["corr_length_m"] == pytest.approx(T, rel=0.1)
    assert S.stats(S.flat("1um", 16))["corr_length_m"] is None   # undefined for a flat field (was NaN)


def test_heightfield_validation():
    with pytest.raises(WaveopticsError, match="dtype complex128 is not allowed"):
        S.HeightField(np.zeros((4, 4), complex), 1e-7)
    with pytest.raises(WaveopticsError, match="NaN or Inf"):
        S.HeightField(np.array([[0.0, np.inf]]), 1e-7)
    with pytest.raises(WaveopticsError, match="spacing dy=-1e-07 m is not allowed"):
        S.HeightField(np.zeros((4, 4)), 1e-7, -1e-7)
    with pytest.raises(WaveopticsError, match="mask shape"):
        S.HeightField(np.zeros((4, 4)), 1e-7, mask=np.ones((3, 4), bool))


# ---------------------------------------------------------------------------------------------------- files

def _masked_field():
    hf = S.gaussian(SIG, T, (32e-6, 16e-6), (96, 48), seed=8)
    mask = np.ones(hf.shape, bool)
    mask[0, :] = False
    mask[:, -1] = False
    mask[10:20, 30:40] = False
    return hf, S.HeightField(hf.heights, hf.dx, hf.dy, mask=mask, meta=hf.meta)


@pytest.mark.parametrize("ext", S.FORMATS)
@pytest.mark.parametrize("masked", [False, True])
def test_round_trip(tmp_path, ext, masked):
    """Every format round-trips: bit-exact heights (float32-exact for EXR), exact spacing, mask, provenance."""
    plain, withmask = _masked_field()
    hf = withmask if masked else plain
    path = tmp_path / f"surf{ext}"
    S.save(hf, path)
    back = S.load(path)
    expect = hf.heights.astype(np.float32).astype(np.float64) if ext == ".exr" else hf.heights
    assert back.shape == hf.shape
    assert (back.dx, back.dy) == (hf.dx, hf.dy)
    np.testing.assert_array_equal(back.valid, hf.valid)
    np.testing.assert_array_equal(back.heights[hf.valid], expect[hf.valid])
    assert back.meta["seed"] == 8 and back.meta["model"] == "gaussian"
    with pytest.raises(WaveopticsError, match="already exists"):
        S.save(hf, path)
    S.save(hf, path, overwrite=True)


def test_foreign_text_files(tmp_path):
    """Profilometer exports: x y z columns with a column-name line, and a CSV matrix with a stated spacing."""
    x, y = np.meshgrid(np.arange(6) * 0.25, np.arange(4) * 0.5)
    z = np.random.default_rng(1).normal(size=x.shape) * 0.01
    p = tmp_path / "scan.xyz"
    np.savetxt(p, np.c_[x.ravel(), y.ravel(), z.ravel()], header="X Y Z", comments="")
    with pytest.raises(WaveopticsError, match="does not state its units.*units"):
        S.load(p)
    hf = S.load(p, units="um")
    assert hf.shape == (4, 6) and (hf.dx, hf.dy) == pytest.approx((0.25e-6, 0.5e-6))
    np.testing.assert_allclose(hf.heights, z * 1e-6, rtol=1e-15)
    m = tmp_path / "scan.csv"
    np.savetxt(m, z, delimiter=",")
    with pytest.raises(WaveopticsError, match="does not state its grid spacing.*spacing"):
        S.load(m, units="um")
    hf = S.load(m, spacing="50nm", units="um")
    assert hf.dx == hf.dy == pytest.approx(50e-9)
    np.save(tmp_path / "raw.npy", z)
    hf = S.load(tmp_path / "raw.npy", spacing=("1um", "2um"))
    assert (hf.dx, hf.dy) == (1e-6, 2e-6)


def _write(path, content):
    path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
    return path


@pytest.mark.parametrize("name, make, message", [
    ("empty.npy", lambda p: _write(p, b""), "is empty"),
    ("empty.txt", lambda p: _write(p, "# units = m\n# dx = 1e-7\n"), "no data rows"),
    ("trunc.npy", lambda p: _write(p, _npy_bytes(np.zeros((8, 8)))[:-40]), "truncated or not a valid .npy"),
    ("trunc.npz", lambda p: _write(p, _npz_bytes()[:-30]), "truncated or not a valid .npz"),
    ("trunc.exr", lambda p: _write(p, _exr_bytes(p)[:-50]), "not a readable OpenEXR"),
    ("complex.npy", lambda p: np.save(p, np.zeros((4, 4), complex)), "complex128 values; heights must be real"),
    ("strings.npz", lambda p: np.savez(p, heights=np.array([["a", "b"]]), dx=1e-7), "<U1 values"),
    ("cube.npz", lambda p: np.savez(p, heights=np.zeros((2, 2, 2)), dx=1e-7), "shape \\(2, 2, 2\\)"),
    ("nan.npz", lambda p: np.savez(p, heights=np.array([[0, np.nan]]), dx=1e-7), "NaN heights"),
    ("inf.txt", lambda p: _write(p, "# units = nm\n# dx = 50\n1 2\ninf 3\n"), "Inf heights"),
    ("zero.npz", lambda p: np.savez(p, heights=np.zeros((2, 2)), dx=0.0), "dx=0.0 m is not allowed"),
    ("neg.txt", lambda p: _write(p, "# units = nm\n# dx = -5\n1 2\n3 4\n"), "dx=-5e-09 m is not allowed"),
    ("ragged.csv", lambda p: _write(p, "# units = nm\n# dx = 5\n1,2,3\n4,5\n"), "line 4 has 2 values, expected 3"),
    ("word.txt", lambda p: _write(p, "# units = nm\n# dx = 5\n1 2\n3 x\n"), "line 4: 'x' is not a number"),
    ("fake.exr", lambda p: np.save(open(p, "wb"), np.zeros(3)), "is not an OpenEXR image .*NumPy .npy"),
    ("fake.npy", lambda p: _write(p, "1 2 3\n"), "is not a NumPy .npy file .*text"),
    ("fake.txt", lambda p: _write(p, _npz_bytes()), "is not a .txt text grid .*zip"),
    ("bin.xyz", lambda p: _write(p, b"\x00\x01\x02"), "binary data"),
    ("nospacing.npy", lambda p: np.save(p, np.zeros((3, 3))), "does not state its grid spacing"),
    ("badunit.txt", lambda p: _write(p, "# units = furlong\n# dx = 5\n1 2\n"), "unknown units 'furlong'"),
    ("surface.bmp", lambda p: _write(p, b"BM\x00\x00"), "unsupported extension '.bmp'"),
    ("surface.tif", lambda p: _write(p, b"II*\x00"), "not in an instrument format SurfaceTopography can read"),
    ("grid.xyz", lambda p: _write(p, "# units = um\n0 0 1\n0.3 0 1\n1 0 2\n"), "not on a regular grid"),
    ("dup.xyz", lambda p: _write(p, "# units = um\n0 0 1\n1 0 1\n1 0 2\n"), "duplicate"),
])
def test_bad_files_raise_one_clear_line(tmp_path, name, make, message):
    path = tmp_path / name
    make(path)
    with pytest.raises(WaveopticsError, match=message) as info:
        S.load(path)
    text = str(info.value)
    assert "\n" not in text and name in text


def test_missing_file(tmp_path):
    with pytest.raises(WaveopticsError, match="does not exist"):
        S.load(tmp_path / "nope.npz")


def _npy_bytes(a):
    import io
    buf = io.BytesIO()
    np.save(buf, a)
    return buf.getvalue()


def _npz_bytes():
    import io
    buf = io.BytesIO()
    np.savez(buf, heights=np.random.default_rng(0).normal(size=(32, 32)), dx=1e-7)
    return buf.getvalue()


def _exr_bytes(p):
    tmp = p.with_name("ok.exr")
    S.save(S.gaussian(SIG, T, "8um", 32, 1), tmp)
    return tmp.read_bytes()


# ---------------------------------------------------------------------------------------------------- CLI

def test_cli_generate_then_stats_json(tmp_path, capsys):
    out = tmp_path / "g.npz"
    rc = cli_main(["surface", "generate", "--generator", "gaussian", "--sigma", "5nm", "--corr-length", "1.2um",
                   "--size", "64um", "--samples", "256", "--seed", "3", "-o", str(out)])
    assert rc == 0 and out.is_file()
    capsys.readouterr()
    rc = cli_main(["surface", "stats", str(out), "--json", "--fit", "gaussian", "--plot", str(tmp_path / "g.png")])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0
    for key in ("samples", "spacing_m", "rms_height_m", "rms_slope", "corr_length_m", "beckmann_alpha"):
        assert key in data
    assert data["samples"] == [256, 256] and data["spacing_m"] == [0.25e-6, 0.25e-6]
    hf = S.load(out)
    assert data["rms_height_m"] == pytest.approx(S.rms_height(hf), rel=1e-12)
    assert data["beckmann_alpha"] == pytest.approx(2 * data["rms_height_m"] / data["corr_length_m"], rel=1e-12)
    assert data["psd_fit"]["gaussian"]["corr_length_m"] == pytest.approx(1.2e-6, rel=0.1)
    assert (tmp_path / "g.png").read_bytes()[:4] == b"\x89PNG"
    again = S.generate("gaussian", sigma="5nm", corr_length="1.2um", size="64um", samples=256, seed=3)
    np.testing.assert_array_equal(hf.heights, again.heights)


@pytest.mark.parametrize("model, opts", [
    ("flat", []),
    ("exponential", ["--sigma", "2nm", "--corr-length", "1um", "--seed", "1"]),
    ("abc", ["--sigma", "2nm", "--B", "5um", "--C", "3.2", "--seed", "1"]),
    ("sinusoid", ["--amplitude", "10nm", "--period", "4um", "--orientation", "30"]),
    ("scratches", ["--count", "10", "--width", "1um", "--depth", "20nm", "--spread", "5", "--seed", "1"]),
])
def test_cli_generate_every_model(tmp_path, capsys, model, opts):
    out = tmp_path / f"{model}.exr"
    rc = cli_main(["surface", "generate", "--generator", model, "--samples", "64x32", "--size", "16um,8um",
                   *opts, "-o", str(out), "--json"])
    data = json.loads(capsys.readouterr().out)
    assert rc == 0 and data["stats"]["samples"] == [64, 32]
    assert S.load(out).shape == (32, 64)


@pytest.mark.parametrize("argv, message", [
    (["--generator", "gaussian", "--sigma", "5nm"], "needs --corr-length"),
    (["--generator", "gaussian", "--sigma", "5nm", "--corr-length", "1um", "--period", "2um"],
     "--period is not an option of generator 'gaussian'"),
    (["--generator", "gaussian", "--sigma", "5", "--corr-length", "1um"], "needs a unit"),
    (["--generator", "sinusoid", "--amplitude", "1nm", "--period", "1um", "--seed", "3"], "--seed is not an option"),
])
def test_cli_errors_exit_2_with_one_line(tmp_path, capsys, argv, message):
    rc = cli_main(["surface", "generate", *argv, "-o", str(tmp_path / "x.npz")])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and err.count("\n") == 1
    assert not (tmp_path / "x.npz").exists()


def test_cli_stats_bad_file(tmp_path, capsys):
    p = tmp_path / "bad.npy"
    p.write_bytes(b"")
    assert cli_main(["surface", "stats", str(p)]) == 2
    assert "is empty" in capsys.readouterr().err


def test_psd_fit_that_ends_on_a_bound_says_so():
    """An ABC fit to a Gaussian spectrum runs its exponent C to the cap (40): the fit reports ``at_bound`` and
    warns instead of handing back the cap as a measured C; a real ABC surface fits inside the bounds."""
    import warnings

    hf = S.generate("gaussian", size="12.8um", samples="128", sigma="20nm", corr_length="0.6um", seed=3)
    with pytest.warns(UserWarning, match="ended at the bound of C"):
        fit = S.fit_psd(hf, "abc")
    assert fit["at_bound"] == ["C"]
    abc = S.abc("2um", 2.6, "64um", 512, seed=1, sigma="5nm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = S.fit_psd(abc, "abc")
    assert fit["at_bound"] == [] and fit["C"] == pytest.approx(2.6, abs=0.15)


@pytest.mark.parametrize("body", ["1,5;2,25;3,0\n0,5;1,25;2,0\n", "1,5 2,25 3,0\n0,5 1,25 2,0\n",
                                  "1.5,2.25,3.0\n0.5,1.25,2.0\n", "1,5; 2,25; 3\n0,5; 1,25; 2\n"])
def test_decimal_commas_are_read_as_decimal_marks(tmp_path, body):
    """A grid written by a spreadsheet in a decimal-comma locale ("1,5;2,25") is three values per row, not six;
    plain comma-separated numbers stay comma-separated (issue 17: decimal commas were read as more columns)."""
    p = tmp_path / "g.csv"
    p.write_text("# units = um\n# dx = 0.1\n" + body)
    hf = S.load(p)
    np.testing.assert_allclose(hf.heights * 1e6, [[1.5, 2.25, 3.0], [0.5, 1.25, 2.0]], rtol=1e-12)


def test_comma_separated_integers_stay_columns(tmp_path):
    p = tmp_path / "i.csv"
    p.write_text("# units = nm\n# dx = 0.1\n1,2,3\n4,5,6\n")
    np.testing.assert_allclose(S.load(p).heights * 1e9, [[1, 2, 3], [4, 5, 6]])
