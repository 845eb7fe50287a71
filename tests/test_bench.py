"""Correctness of the speed work (issue 6) — not timings: the kernels' sin/cos polynomial against its NumPy twin
and against exact sin/cos, every variant of the direct kernel (register-blocked tails, work-group sizes, vector
widths, fast-math, the naive baseline) against the float64 NumPy twin in float32 and float64, the measurement of
the math built-ins, the NumPy alternatives the benchmark compares with, and the ``bench`` CLI's output shape.
"""
import json

import numpy as np
import pytest

from cli_helpers import run_cli
from waveoptics import scatter
from waveoptics import bench
from waveoptics.surfaces.heightfield import HeightField
from waveoptics.units import direction_from_angles

#: tolerances, in one place
TOL = {
    "poly32": 1.2e-7,        # |wo_sincos_2pi − sin/cos(2πt)| in float32 (a float32 sin is within ~6e-8)
    "poly64": 5e-15,
    "twin32": 2.4e-7,        # kernel polynomial vs its NumPy twin (different FMA contraction)
    "twin64": 1e-15,
    "U32": 2e-5,             # |U_cl − U_twin| / Σ w dx dy (as tests/test_diffraction.py)
    "U64": 1e-12,
    "U32_fast": 1e-4,        # -cl-fast-relaxed-math
    "naive32": 1e-3,         # float phase in radians on a ~20 λ patch
    "naive64": 1e-6,         # PoCL evaluates native_sin/native_cos of a double in float accuracy (measured 3e-8)
}


@pytest.fixture(scope="module")
def problem():
    rng = np.random.default_rng(2024)
    h = rng.normal(0.0, 70e-9, (30, 37))
    mask = np.ones_like(h, bool)
    mask[4:7, 5:20] = False
    smp = scatter.samples(HeightField(h, 125e-9, 110e-9, mask))
    wi = scatter.grid.incident_dirs((40.0, 15.0))
    wo = direction_from_angles(rng.uniform(0, 85, 61), rng.uniform(0, 360, 61))   # 61: not a multiple of 8 or 4
    coef = scatter.phase_coefficients(smp, wi, wo, [450.0, 633.0])
    return smp, wi, wo, coef, scatter.kirchhoff_U(smp, coef), float(np.sum(smp.w) * smp.dx * smp.dy)


def test_sincos_poly_twin_is_sin_and_cos():
    t = np.concatenate([np.linspace(-2.0, 2.0, 40001), np.random.default_rng(1).uniform(-3e3, 3e3, 20000)])
    for p, tol in (("float32", TOL["poly32"]), ("float64", TOL["poly64"])):
        tt = t.astype(np.float32 if p == "float32" else np.float64)
        s, c = scatter.sincos_2pi(tt, p)
        t64 = tt.astype(np.float64)
        x = 2 * np.pi * (t64 - np.rint(t64))          # exact reduction: the reference keeps its digits
        assert np.abs(s - np.sin(x)).max() < tol
        assert np.abs(c - np.cos(x)).max() < tol
    # quadrant boundaries are exact: sin(2π k/4) and cos are 0, ±1
    k = np.arange(-8, 9)
    for p in ("float32", "float64"):
        s, c = scatter.sincos_2pi(k / 4.0, p)
        assert np.array_equal(s, np.array([0.0, 1.0, 0.0, -1.0])[k % 4])
        assert np.array_equal(c, np.array([1.0, 0.0, -1.0, 0.0])[k % 4])


def test_sincos_kernel_matches_twin(rt, precision):
    t = np.random.default_rng(5).uniform(-100.0, 100.0, 5001)
    s, c = scatter.sincos_2pi_cl(t, runtime=rt, precision=precision)
    s2, c2 = scatter.sincos_2pi(t, precision)
    tol = TOL["twin" + precision[-2:]]
    assert np.abs(s - s2).max() < tol and np.abs(c - c2).max() < tol
    t64 = t.astype(s.dtype).astype(np.float64)
    x = 2 * np.pi * (t64 - np.rint(t64))
    assert np.abs(s - np.sin(x)).max() < TOL["poly" + precision[-2:]]


@pytest.mark.parametrize("local_size, vector_width", [(None, None), (0, None), (4, 8), (1, 4), (3, 2)])
def test_direct_kernel_variants_match_twin(rt, precision, problem, local_size, vector_width):
    """Register blocking leaves a tail of pairs (122 = 15·8 + 2); work-group sizes and vector widths do not
    change the result."""
    smp, _, _, coef, U_ref, scale = problem
    U = scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision, local_size=local_size,
                         vector_width=vector_width)
    assert np.abs(U - U_ref).max() / scale < TOL["U" + precision[-2:]]


def test_fast_math_previous_and_naive_kernels_match_twin(rt, precision, problem):
    smp, _, _, coef, U_ref, scale = problem
    U = scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision, fast_math=True)
    assert np.abs(U - U_ref).max() / scale < (TOL["U32_fast"] if precision == "float32" else 1e-10)
    Un = bench.kirchhoff_U_naive_cl(smp, coef, runtime=rt, precision=precision)
    assert np.abs(Un - U_ref).max() / scale < TOL["naive" + precision[-2:]]
    Us = bench.kirchhoff_U_sinpi_cl(smp, coef, runtime=rt, precision=precision)
    assert np.abs(Us - U_ref).max() / scale < TOL["U" + precision[-2:]]


def test_benchmark_variants_are_not_in_the_solver_program():
    """The production program holds only the solver's kernels; the benchmark's variants build from their own file."""
    from waveoptics.runtime import kernel_source

    assert "kirchhoff_U_naive" not in kernel_source("kirchhoff.cl")
    assert "kirchhoff_U_sinpi" not in kernel_source("kirchhoff.cl")
    assert "__kernel void kirchhoff_U_naive" in kernel_source("bench_kirchhoff.cl")


def test_naive_float32_loses_accuracy_on_a_long_patch(rt):
    """Why the project's kernel reduces the phase exactly: on a 4096 λ strip the naive float32 phase is wrong by
    far more than the project's float32 kernel."""
    res = bench.large_patch_errors(rt, n=2**14, n_dir=8)
    assert res["opencl kirchhoff_U float32"] < 1e-3
    assert res[bench.NAIVE] > 30 * res["opencl kirchhoff_U float32"]


def test_numpy_alternatives_are_the_same_sums(problem):
    """The benchmark's NumPy direct sum equals the twin; the NumPy FFT pipeline equals the fft solver (order 0)
    where the grid falls on FFT bins."""
    smp, wi, wo, coef, U_ref, scale = problem
    Un = bench.numpy_direct_sum(smp, wi, wo, 450.0)
    n = wo.shape[0]
    assert np.allclose(np.abs(Un), np.abs(U_ref[:n]), atol=1e-12 * scale)
    hf = HeightField(np.random.default_rng(3).normal(0, 30e-9, (32, 32)), 125e-9)
    s = scatter.samples(hf)
    grid = scatter.DirectionGrid.hemisphere(32)
    wi30 = scatter.grid.incident_dirs((30.0, 0.0))               # s_x dx / λ = (0.5 + u) / 4 falls on bins k / 256
    U0 = scatter.field_fft(s, wi30, grid, 500.0, 0)[0]
    Up = bench.numpy_fft_pipeline(s, wi30, grid, 500.0, pad=256)
    top = float(np.sum(s.w) * s.dx * s.dy)
    assert np.abs(Up - U0).max() < 1e-12 * top


def test_math_errors_measures_the_builtins(rt):
    res = bench.math_errors(rt, n=4001)
    f32 = res["float32"]
    assert set(f32) == set(bench.MATH_FUNCTIONS)
    # the kernels' polynomial is as accurate as the built-in sin/cos on reduced and on large arguments
    for lab in ("|x|<=pi", "|x|<=1e4"):
        assert f32["wo_sin_2pi"][lab] < TOL["poly32"] and f32["wo_cos_2pi"][lab] < TOL["poly32"]
        assert all(np.isfinite(v[lab]) for v in f32.values())
    if rt.fp64:
        for lab in ("|x|<=pi", "|x|<=1e4"):
            assert res["float64"]["wo_sin_2pi"][lab] < TOL["poly64"]


def test_bench_cli_quick_json(tmp_path):
    out = tmp_path / "b"
    rc, stdout, stderr, _ = run_cli(["bench", "--quick", "--json", "-o", str(out)])
    assert rc == 0, stderr
    res = json.loads(stdout)
    assert {"machine", "direct", "direct_scaling", "fft_backends", "fft_pipeline", "math_errors"} <= set(res)
    assert len(res["direct_scaling"]["by_samples"]) >= 4 and len(res["direct_scaling"]["by_directions"]) >= 4
    names = {row["name"] for row in res["direct"]["rows"]}
    assert {bench.NAIVE, "numpy direct sum (complex128)", "numpy twin kirchhoff_U (float64)"} <= names
    for row in res["direct"]["rows"]:
        assert row["terms_per_s"] > 0 and row["error"] < 1e-3
    assert (out / "bench.json").is_file() and "Direct Kirchhoff sum" in (out / "bench.md").read_text()
    sim = res["simulate"]    # simulate() against --no-spheres, in one process (the quick run's small request)
    assert sim["fields"] == {"resolution": 16, "wavelengths": [550.0]} and sim["units"]["wall_s"].startswith("s")
    for key in ("first", "default", "no_spheres"):
        assert sim[key]["wall_s"] > 0 and sim[key]["cpu_s"] > 0
    assert 10 * sim["no_spheres"]["parts_s"]["sphere_table"] < sim["default"]["parts_s"]["sphere_table"]
    assert 0 < sim["no_spheres_vs_default"] < 1      # the sphere table is work on top of the lobe at the light
    assert "simulate() (resolution=16" in (out / "bench.md").read_text()
    rc, _, stderr, _ = run_cli(["bench", "--quick", "-o", str(out)])
    assert rc == 2 and "already exists" in stderr
