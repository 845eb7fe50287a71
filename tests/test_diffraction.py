"""Kirchhoff scattering solvers against physics (docs/physics.md §1, §2, §5) and the OpenCL kernel against its NumPy twin.

Oracles: a flat mirror reflects F(θ_i) into the mirror direction; Gaussian heights keep a coherent fraction
exp(−g) and scatter TIS = F (1 − exp(−g)) (Davies 1954; Bennett & Porteus 1961); a sinusoidal grating sends
O_m J_m²(k a (cos θ_i + cos θ_m)) into the orders sin θ_m = sin θ_i + m λ/Λ (Raman-Nath; docs/physics.md §5, with
the obliquity O_m of §1); σ ≫ λ tends to Beckmann F D / (4 cos θ_i cos θ_o) with α = 2σ/T (Beckmann &
Spizzichino 1963). Surfaces are seeded (surfaces.gaussian(seed=...)), grids are small (≤ 256²) to keep the file
fast on 2 cores.
"""
import json
import math
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import jv

from cli_helpers import run_cli
from waveoptics import brdf, scatter
from waveoptics import io, surfaces
from waveoptics.errors import WaveopticsError
from waveoptics.surfaces.heightfield import HeightField
from waveoptics.units import direction_from_angles

LAM = 500.0                      # nm
L = LAM * 1e-9                   # m

#: tolerances, in one place
TOL = {
    "flat_albedo_rel": 5e-3,         # |E/F − 1| for a flat patch up to 60° (obliquity across the spike)
    "flat_spike_share": 0.99,        # share of the albedo within 4 λ/L of the mirror direction
    "phase32_rad": 5e-6,             # float32 kernel phase vs float64 twin on a 16384 λ strip
    "phase64_rad": 1e-12,
    "U32_rel": 2e-5,                 # kernel vs twin, relative to the flat-field peak Σ w dx dy
    "U64_rel": 1e-12,
    "fft_exact_rel": 1e-7,           # fft(order auto) vs direct sum, relative to Σ w dx dy
    "coherent_abs": 0.02,            # |⟨χ⟩|² vs exp(−g) over 8 realizations
    "coherent_patch_rel": 5e-3,      # one patch: |χ̂|² vs exp(−g_w) with its own w²-weighted rms
    "tis_rel": 0.10,                 # scattered vs F (1 − exp(−g)), relative
    "grating_abs": 2e-3,             # per-order efficiency vs O_m J_m²
    "grating_rel": 0.01,
    "beckmann_ring_rel": 0.06,       # ring means of the averaged lobe vs Beckmann for θ_h < 24°
    "beckmann_albedo_rel": 0.02,
    "energy_rel": 5e-3,              # albedo ≤ max(F, flat albedo) (1 + this)
    "reciprocity32_rel": 2e-4,
    "reciprocity64_rel": 1e-9,
}


def _quiet(fn, *a, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scatter.DiffractionWarning)
        return fn(*a, **kw)


# ------------------------------------------------------------------------------------------------------------
# kernels against the NumPy twins


def test_phase_reduction_float32_large_patch(rt, precision):
    """Fixed-point lateral phase keeps float32 errors ~1e-6 rad on a 2^16-sample (16384 λ) strip, where the
    naive float32 k·x loses ~1e-2 rad."""
    n = 2**16
    rng = np.random.default_rng(7)
    hf = HeightField(rng.normal(0.0, 50e-9, (2, n)), L / 4)
    smp = scatter.samples(hf, "boxcar")
    wi = scatter.grid.incident_dirs((60.0, 0.0))
    wo = direction_from_angles([75.0, 20.0], [180.0, 33.0])
    coef = scatter.phase_coefficients(smp, wi, wo, [LAM])
    x, y = hf.coords()
    for p in range(2):
        ref = scatter.kirchhoff_phase(smp.ix, smp.iy, smp.h, coef.Ax[p], coef.Ay[p], coef.lox[p], coef.loy[p],
                                coef.cz[p], coef.c0[p])
        s = wi + wo[p]
        naive64 = (s[0] * x[smp.ix] + s[1] * y[smp.iy] + s[2] * smp.h) / L
        d = ref - naive64
        assert np.abs(d - np.round(d)).max() < 1e-9          # the twin is the phase of docs/physics.md §1
        ph = scatter.kirchhoff_phase_cl(smp, coef, p, runtime=rt, precision=precision)
        e = ph - ref
        err = 2 * np.pi * np.abs(e - np.round(e)).max()
        assert err < TOL[f"phase{precision[-2:]}_rad"], err
    k = np.float32(2 * np.pi / L)
    naive32 = (k * np.float32(s[0]) * x[smp.ix].astype(np.float32)
               + k * np.float32(s[1]) * y[smp.iy].astype(np.float32)).astype(np.float64) / (2 * np.pi)
    e = naive32 - (s[0] * x[smp.ix] + s[1] * y[smp.iy]) / L
    assert 2 * np.pi * np.abs(e - np.round(e)).max() > 1e-3  # why the reduction is needed


def test_kirchhoff_U_cl_matches_numpy(rt, precision, rng):
    h = rng.normal(0.0, 80e-9, (40, 48))
    mask = np.ones_like(h, bool)
    mask[5:9, 10:30] = False
    hf = HeightField(h, L / 4, L / 3, mask)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((35.0, 20.0))
    wo = direction_from_angles(rng.uniform(0, 89, 300), rng.uniform(0, 360, 300))
    coef = scatter.phase_coefficients(smp, wi, wo, [420.0, 555.5, 690.0])
    Un = scatter.kirchhoff_U(smp, coef)
    Uc = scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision)
    scale = smp.w.sum() * smp.dx * smp.dy
    assert np.abs(Uc - Un).max() / scale < TOL[f"U{precision[-2:]}_rel"]


def test_direct_twin_is_the_kirchhoff_integral(rng):
    """The NumPy twin equals the plain sum Σ w exp(i k s·(x, y, h)) dx dy written from docs/physics.md §1."""
    hf = surfaces.gaussian(40e-9, 1e-6, 12e-6, (40, 32), seed=3)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((20.0, 45.0))
    wo = direction_from_angles(rng.uniform(0, 80, 50), rng.uniform(0, 360, 50))
    U = scatter.kirchhoff_U(smp, scatter.phase_coefficients(smp, wi, wo, [LAM]))
    x, y = hf.coords()
    X, Y = np.meshgrid(x, y)
    w = scatter.window(hf)
    k = 2 * np.pi / L
    ref = np.array([np.sum(w * np.exp(1j * k * (s[0] * X + s[1] * Y + s[2] * hf.heights)))
                    for s in wo + wi]) * hf.dx * hf.dy
    assert np.allclose(np.abs(U) ** 2, np.abs(ref) ** 2, rtol=1e-9, atol=1e-12 * np.abs(ref).max() ** 2)


# ------------------------------------------------------------------------------------------------------------
# fft solver against the direct sum


def test_fft_order0_equals_frozen_direct_sum(rng):
    """order=0 is exactly the Kirchhoff sum with v_z frozen at 2 k cos θ_i (chirp-z = DTFT samples)."""
    hf = surfaces.gaussian(60e-9, 1e-6, 16e-6, 64, seed=11)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((25.0, 10.0))
    grid = scatter.DirectionGrid.hemisphere(32)
    U, info = scatter.field_fft(smp, wi, grid, LAM, order=0)
    assert info["transforms"] == 1
    coef = scatter.phase_coefficients(smp, wi, grid.directions()[grid.inside], [LAM], frozen_cos_sum=2 * wi[2])
    Ud = scatter.kirchhoff_U(smp, coef)
    assert np.abs(U[grid.inside] - Ud).max() < 1e-10 * smp.w.sum() * smp.dx * smp.dy


@pytest.mark.parametrize("sigma_lam", [0.05, 1.0])
def test_fft_auto_equals_direct_everywhere(sigma_lam):
    """The banded Taylor series makes the fft solver exact Kirchhoff over the whole disc, smooth or rough."""
    hf = surfaces.gaussian(sigma_lam * L, 4 * sigma_lam * L + L, 16 * L, 64, seed=2)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((40.0, 0.0))
    grid = scatter.DirectionGrid.hemisphere(24)
    U, info = scatter.field_fft(smp, wi, grid, LAM)
    Ud = scatter.kirchhoff_U(smp, scatter.phase_coefficients(smp, wi, grid.directions()[grid.inside], [LAM]))
    assert np.abs(U[grid.inside] - Ud).max() < TOL["fft_exact_rel"] * smp.w.sum() * smp.dx * smp.dy
    assert info["bands"] >= (2 if sigma_lam > 0.5 else 1)


def test_fft_order0_holds_near_specular_only():
    """Frozen v_z: error grows with the distance from the specular direction (docs/physics.md §1)."""
    hf = surfaces.gaussian(L / 20, 2 * L, 32 * L, 128, seed=5)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((0.0, 0.0))
    grid = scatter.DirectionGrid.hemisphere(64)
    d = grid.directions()
    f0 = scatter.brdf_from_field(scatter.field_fft(smp, wi, grid, LAM, 0)[0][None], wi, d, [LAM], smp.area)[0]
    fa = scatter.brdf_from_field(scatter.field_fft(smp, wi, grid, LAM)[0][None], wi, d, [LAM], smp.area)[0]
    dist = np.hypot(d[..., 0] + wi[0], d[..., 1] + wi[1])
    near = grid.inside & (dist < 0.05)
    far = grid.inside & (dist > 0.5)
    assert abs(f0[near].sum() / fa[near].sum() - 1) < 1e-3
    assert abs(f0[far].sum() / fa[far].sum() - 1) > 0.1


# ------------------------------------------------------------------------------------------------------------
# flat surface: mirror spike with albedo F(θ_i)


@pytest.mark.parametrize("solver", ["fft", "direct"])
@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0])
def test_flat_surface_is_a_mirror(rt, solver, theta):
    from waveoptics.materials import get_material

    mat = get_material("1.5")
    wl = np.array([450.0, 550.0, 650.0])
    # L = 64 λ_min: the spike (width ~λ/L) is narrow enough that F(θ_d) and the obliquity vary little across it;
    # resolution 128 ≥ 2 L/λ_min resolves it. The direct solver uses dx = λ_min/2 (fewer terms): the aliased
    # copies of a mirror spike fall outside the disc.
    hf = surfaces.flat(28.8e-6, 256 if solver == "fft" else 128)
    res = _quiet(scatter.scatter, hf, (theta, 30.0), wl, mat, solver=solver, resolution=128, runtime=rt)
    F = mat.F(math.cos(math.radians(theta)), wl)
    assert np.all(np.abs(res.albedo / F - 1) < TOL["flat_albedo_rel"]), res.albedo / F
    assert np.allclose(res.coherent_specular_fraction, 1.0) and np.all(res.scattered_fraction < 1e-5 * F)
    g = res.grid
    d = g.directions()
    wi = res.incident
    for i, lam in enumerate(wl):
        # the peak sits in the cell of the mirror direction
        j = np.unravel_index(np.argmax(res.brdf[i]), res.brdf[i].shape)
        assert abs(g.u[j[1]] + wi[0]) <= g.du and abs(g.v[j[0]] + wi[1]) <= g.dv
        near = np.hypot(d[..., 0] + wi[0], d[..., 1] + wi[1]) < 4 * lam * 1e-9 / hf.extent[0]
        assert scatter.integrate(res.brdf[i], g, region=near) / res.albedo[i] > TOL["flat_spike_share"]


def test_window_suppresses_edge_ringing():
    hf = surfaces.flat(32e-6, 128)
    far = {}
    for name in ("boxcar", "hann"):
        res = scatter.scatter(hf, (0.0, 0.0), [LAM], resolution=128, window_name=name)
        r = res.grid.sin_theta
        far[name] = scatter.integrate(res.brdf[0], res.grid, region=r > 16 * L / hf.extent[0]) / res.albedo[0]
    assert far["boxcar"] > 1e-3 and far["hann"] < 1e-6, far


# ------------------------------------------------------------------------------------------------------------
# Gaussian surface, σ ≪ λ: coherent fraction and TIS (docs/physics.md §2)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0])
def test_smooth_gaussian_coherent_fraction_and_tis(theta):
    sigma, F = 20e-9, 0.9
    res = scatter.scatter(lambda s: surfaces.gaussian(sigma, 1e-6, 32e-6, 256, seed=s), (theta, 0.0), [LAM], F,
                    resolution=128, realizations=8, seed=100)
    g = (4 * np.pi * sigma * math.cos(math.radians(theta)) / L) ** 2
    assert abs(res.coherent_specular_fraction[0] - math.exp(-g)) < TOL["coherent_abs"]
    tis = F * (1 - math.exp(-g))
    assert abs(res.scattered_fraction[0] / tis - 1) < TOL["tis_rel"], (res.scattered_fraction, tis)
    assert abs(res.albedo[0] / F - 1) < TOL["flat_albedo_rel"]


def test_coherent_fraction_of_one_patch_is_exp_minus_g_of_its_heights():
    wi = scatter.grid.incident_dirs((0.0, 0.0))
    for seed in range(3):
        smp = scatter.samples(surfaces.gaussian(25e-9, 2e-6, 64e-6, 256, seed=seed))
        w2 = smp.w**2
        sw = math.sqrt(np.sum(w2 * smp.h**2) / np.sum(w2))
        chi2 = abs(scatter.coherent_amplitude(smp, wi, LAM)) ** 2
        assert abs(chi2 / math.exp(-(4 * np.pi * sw / L) ** 2) - 1) < TOL["coherent_patch_rel"]


# ------------------------------------------------------------------------------------------------------------
# sinusoidal grating (docs/physics.md §5)


def _grating_efficiencies(res, a, period, theta):
    g, lam = res.grid, res.wavelengths_nm[0] * 1e-9
    si, ci = math.sin(math.radians(theta)), math.cos(math.radians(theta))
    out = []
    for m in range(-4, 5):
        um = -(si + m * lam / period)                 # sin θ_m = sin θ_i + m λ/Λ on the specular side
        if abs(um) >= 0.97:
            continue
        box = np.broadcast_to(np.abs(g.u - um)[None, :] < 0.5 * lam / period, g.inside.shape)
        eta = scatter.integrate(res.brdf[0], g, region=box)
        cm = math.sqrt(1 - um**2)
        s = np.array([si + um, 0.0, ci + cm])
        O = np.sum(s**2) ** 2 / (4 * ci * cm * (ci + cm) ** 2)
        pred = O * jv(m, 2 * np.pi / lam * a * (ci + cm)) ** 2
        peak = np.unravel_index(np.argmax(np.where(box, res.brdf[0], 0)), box.shape)
        out.append((m, eta, pred, g.u[peak[1]] - um))
    return out


@pytest.mark.parametrize("theta", [0.0, 20.0])
@pytest.mark.parametrize("a", [20e-9, 60e-9, 120e-9])
def test_grating_orders_follow_bessel(a, theta):
    period = 8 * L
    hf = surfaces.sinusoid(a, period, (64 * L, 16 * L), (256, 64))
    grid = scatter.DirectionGrid(256, 64, (-1, 1), (-0.25, 0.25))
    res = scatter.scatter(hf, (theta, 0.0), [LAM], grid=grid)
    effs = _grating_efficiencies(res, a, period, theta)
    assert len(effs) >= 7
    for m, eta, pred, du in effs:
        assert abs(eta - pred) < TOL["grating_abs"] + TOL["grating_rel"] * pred, (m, eta, pred)
        if pred > 1e-3:
            assert abs(du) <= grid.du, (m, du)


def test_grating_direct_solver_and_small_amplitude_limit(rt):
    """Direct (OpenCL) solver on the same grating; at normal incidence and small a/Λ, η_m ≈ J_m²(4πa/λ)."""
    a, period = 30e-9, 8 * L
    hf = surfaces.sinusoid(a, period, (64 * L, 16 * L), (256, 64))
    grid = scatter.DirectionGrid(256, 32, (-1, 1), (-0.25, 0.25))
    res = _quiet(scatter.scatter, hf, (0.0, 0.0), [LAM], grid=grid, solver="direct", runtime=rt)
    for m, eta, pred, _ in _grating_efficiencies(res, a, period, 0.0):
        assert abs(eta - pred) < TOL["grating_abs"] + TOL["grating_rel"] * pred
        if abs(m) <= 2:
            assert abs(eta - jv(m, 4 * np.pi * a / L) ** 2) < 0.01 + 0.05 * pred


# ------------------------------------------------------------------------------------------------------------
# Gaussian surface, σ ≫ λ: Beckmann limit (docs/physics.md §1)


def test_rough_gaussian_tends_to_beckmann():
    """64 realizations, σ = λ, α = 2σ/T = 0.3, normal incidence. Ring means of the averaged lobe in θ_h agree with
    F D / (4 cos θ_i cos θ_o) (no shadowing) to 6 % inside θ_h < 24°; the far tail is heavier (finite g = 158 and
    the patch's diffraction), which docs/wave-optics.md reports."""
    sigma, alpha = L, 0.3
    T = 2 * sigma / alpha
    grid = scatter.DirectionGrid.hemisphere(64)
    res = _quiet(scatter.scatter, lambda s: surfaces.gaussian(sigma, T, 128 * L / 2, 128, seed=s), (0.0, 0.0), [LAM],
                 grid=grid, realizations=64, seed=100)
    d = grid.directions()
    wi = res.incident
    h = brdf.half_vector(wi, d)
    fb = np.where(grid.inside, brdf.D(h, alpha, ndf="beckmann") / (4 * wi[2] * np.maximum(d[..., 2], 1e-9)),
                  0.0)
    th_h = np.degrees(np.arccos(np.clip(h[..., 2], -1, 1)))
    for a in range(0, 24, 4):
        m = grid.inside & (th_h >= a) & (th_h < a + 4)
        assert abs(res.brdf[0][m].mean() / fb[m].mean() - 1) < TOL["beckmann_ring_rel"], a
    assert abs(res.albedo[0] / scatter.integrate(fb, grid) - 1) < TOL["beckmann_albedo_rel"]


# ------------------------------------------------------------------------------------------------------------
# energy and reciprocity


@settings(max_examples=12, deadline=None, derandomize=True)
@given(alpha=st.floats(0.0, 0.3), sigma_lam=st.floats(0.0, 0.3), theta=st.floats(0.0, 70.0),
       phi=st.floats(0.0, 360.0), F=st.floats(0.2, 1.0), lam=st.floats(400.0, 700.0), seed=st.integers(0, 99))
def test_albedo_never_exceeds_fresnel(alpha, sigma_lam, theta, phi, F, lam, seed):
    sigma = max(sigma_lam * lam * 1e-9, 1e-12)
    T = float(np.clip(2 * sigma / max(alpha, 1e-6), 1.5 * lam * 1e-9, 8 * lam * 1e-9))
    hf = surfaces.gaussian(sigma, T, 32 * lam * 1e-9, 128, seed=seed)
    res = _quiet(scatter.scatter, hf, (theta, phi), [lam], F, resolution=128, detrend="plane")
    assert np.all(np.isfinite(res.brdf)) and res.brdf.min() >= 0
    bound = max(F, res.flat_albedo[0]) * (1 + TOL["energy_rel"])
    assert res.albedo[0] <= bound, (res.albedo[0], F)


def test_direct_solver_is_reciprocal(rt, precision, rng):
    hf = surfaces.gaussian(0.3 * L, 2 * L, 12 * L, 48, seed=4)
    a = direction_from_angles(rng.uniform(0, 70, 12), rng.uniform(0, 360, 12))
    b = direction_from_angles(rng.uniform(0, 70, 12), rng.uniform(0, 360, 12))
    fwd = np.array([_quiet(scatter.brdf, hf, a[i], b[i:i + 1], [LAM], 0.7, runtime=rt, backend="opencl",
                           precision=precision)[0, 0] for i in range(12)])
    rev = np.array([_quiet(scatter.brdf, hf, b[i], a[i:i + 1], [LAM], 0.7, runtime=rt, backend="opencl",
                           precision=precision)[0, 0] for i in range(12)])
    assert np.all(fwd > 0)
    assert np.abs(fwd - rev).max() / fwd.max() < TOL[f"reciprocity{precision[-2:]}_rel"]


# ------------------------------------------------------------------------------------------------------------
# robustness, warnings, API


def test_grazing_and_masked_inputs_stay_finite():
    hf = surfaces.gaussian(0.5 * L, 2 * L, 16 * L, 64, seed=1)
    for theta in (89.99, 90.0):
        res = _quiet(scatter.scatter, hf, (theta, 0.0), [LAM], resolution=48)
        assert np.all(np.isfinite(res.brdf)) and res.brdf.min() >= 0 and np.isfinite(res.albedo).all()
    mask = np.zeros(hf.shape, bool)
    mask[10:40, 5:60] = True
    res = _quiet(scatter.scatter, HeightField(hf.heights, hf.dx, mask=mask), (30.0, 0.0), [LAM], resolution=48)
    assert np.isfinite(res.albedo).all()


def test_sampling_warnings():
    hf = surfaces.flat(16 * L, 32)                    # dx = λ/2
    with pytest.warns(scatter.DiffractionWarning, match="aliasing"):
        scatter.scatter(hf, (60.0, 0.0), [LAM], resolution=64)
    with pytest.warns(scatter.DiffractionWarning, match="coarse direction grid"):
        scatter.scatter(surfaces.flat(64 * L, 256), (0.0, 0.0), [LAM], resolution=64)


def test_realizations_and_split_patch():
    hf = surfaces.gaussian(20e-9, 1e-6, 32e-6, 128, seed=9)
    tiles = scatter.split_patch(hf, 4)
    assert len(tiles) == 4 and all(t.shape == (64, 64) for t in tiles)
    res = _quiet(scatter.scatter, hf, (10.0, 0.0), [LAM], resolution=64, realizations=4)
    ref = [_quiet(scatter.scatter, t, (10.0, 0.0), [LAM], resolution=64) for t in tiles]
    assert res.realizations == 4
    assert np.allclose(res.brdf, np.mean([r.brdf for r in ref], axis=0))
    with pytest.raises(WaveopticsError, match="cannot split"):
        scatter.split_patch(hf, 7 * 11 * 13)


@pytest.mark.parametrize("kwargs, match", [
    ({"solver": "ray"}, "unknown solver 'ray'"),
    ({"order": -1}, "fft order -1 is not allowed"),
    ({"window_name": "nosuchwindow"}, "window 'nosuchwindow' is not allowed"),
    ({"material": 1.5}, "constant reflectance 1.5 is not allowed"),
    ({"detrend": "cubic"}, "unknown detrend 'cubic'"),
])
def test_bad_inputs_raise_one_clear_error(kwargs, match):
    hf = surfaces.flat(8e-6, 16)
    kw = {"resolution": 16, **kwargs}
    with pytest.raises(WaveopticsError, match=match):
        _quiet(scatter.scatter, hf, (10.0, 0.0), [LAM], **kw)


def test_incident_out_of_range():
    with pytest.raises(WaveopticsError, match="outside the allowed range"):
        scatter.scatter(surfaces.flat(8e-6, 16), (95.0, 0.0), [LAM], resolution=16)


# ------------------------------------------------------------------------------------------------------------
# output: spectral OpenEXR and the CLI


def test_spectral_exr_layout(tmp_path):
    import re

    from colour.io.fichet2021 import PATTERN_FICHET2021, match_groups_to_nm

    assert io.spectral_channel_name(550) == "T.550,000000nm"
    assert io.spectral_channel_name(412.25, emissive=True) == "S0.412,250000nm"
    for wl in (380.0, 555.5, 1000.125):
        m = re.fullmatch(rf"T\.{PATTERN_FICHET2021}", io.spectral_channel_name(wl))
        assert m and match_groups_to_nm(m.group(1), m.group(3) or "", m.group(4)) == pytest.approx(wl)
    res = _quiet(scatter.scatter, surfaces.flat(16e-6, 64), (20.0, 0.0), [450.0, 550.0], resolution=64)
    paths = scatter.write_scatter(res, tmp_path / "out")
    layers, header = io.read_spectral_exr(paths["lobes.exr"])
    assert list(layers) == [450.0, 550.0]
    assert np.allclose(layers[550.0], res.grid.to_image(res.brdf[1]).astype(np.float32))   # top row = highest v
    assert header["spectralLayoutVersion"] == "1.0" and "direction cosines" in header["parametrization"]
    with pytest.raises(WaveopticsError, match="already exists"):
        scatter.write_scatter(res, tmp_path / "out")


def _cli(*args):
    """``waveoptics ARGS`` in-process (the console script itself is run by tests/test_bad_input.py)."""
    rc, out, err, _ = run_cli(args)
    return SimpleNamespace(returncode=rc, stdout=out, stderr=err)


def test_cli_scatter_and_brdf(tmp_path):
    surf = tmp_path / "g.npz"
    surfaces.save(surfaces.gaussian(20e-9, 1e-6, 16e-6, 128, seed=1), surf)
    out = tmp_path / "run"
    r = _cli("scatter", "--surface", str(surf), "--material", "one", "--incident", "30,0", "--wavelengths",
             "450:650:100", "--resolution", "64", "-o", str(out), "--json")
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    summ = json.loads((out / "summary.json").read_text())
    for key in ("wavelengths_nm", "albedo", "coherent_specular_fraction", "scattered_fraction"):
        assert len(summ[key]) == 3 and summ[key] == data[key]
    assert "total" in summ["timings_s"] and (out / "lobes.exr").is_file() and (out / "lobes.png").is_file()
    assert abs(summ["albedo"][1] - 1) < 0.01
    r = _cli("scatter", "--surface", str(surf), "--material", "one", "--incident", "30", "--wavelengths", "500",
             "-o", str(out))
    assert r.returncode == 2 and "already exists" in r.stderr and "Traceback" not in r.stderr
    r = _cli("scatter", "--surface", str(surf), "--material", "one", "--incident", "30", "--wavelengths", "500",
             "--solver", "direct", "--resolution", "32", "-o", str(tmp_path / "d"), "--json")
    assert r.returncode == 0, r.stderr
    r = _cli("brdf", "--model", "kirchhoff", "--surface", str(surf), "--fresnel", "one", "--incident", "30",
             "--outgoing", "30,180", "--outgoing", "60,180", "--wavelengths", "500", "--json")
    assert r.returncode == 0, r.stderr
    vals = [v["brdf"] for v in json.loads(r.stdout)["values"]]
    assert vals[0] > 100 * vals[1] > 0                # specular peak vs far off-specular
