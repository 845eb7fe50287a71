"""Benchmarks: the project's kernels against what a user would otherwise write, in one run on one machine.

Measured (each a function returning plain data; :func:`run_all` runs them all, ``waveoptics bench`` prints them
and ``scripts/docs_performance.py`` turns them into ``docs/performance.md``):

* :func:`direct_kernels` — the direct Kirchhoff sum (docs/physics.md §1) on one problem: the project's OpenCL kernel
  (float32, float64, fast-math), the kernel it replaced (``kirchhoff_U_sinpi``, run as it was: driver-chosen
  work-groups), the naive OpenCL kernel (``kirchhoff_U_naive``: float phase k s·x in radians,
  native_sin/native_cos, driver-chosen work-groups), a plain NumPy direct sum (``exp(1j k s·r) @ w``) and the
  project's float64 NumPy twin :func:`waveoptics.scatter.kirchhoff_U`: throughput in terms/s (sample ×
  direction × wavelength), the ratio to the naive kernel and to NumPy, and the error against the twin relative to
  Σ w dx dy.
* :func:`direct_scaling` — time of the same against the number of samples and of directions (four sizes each).
* :func:`fft_backends` — 2-D complex FFT throughput (points/s) of numpy.fft, scipy.fft (pocketfft, 1 and 2
  workers), pyFFTW (planned FFTW objects, if installed) and pyvkfft on the OpenCL device (if installed;
  device-resident data, transfers excluded).
* :func:`fft_pipeline` — the ``fft`` solver (:func:`waveoptics.scatter.field_fft`, chirp-z onto the direction
  grid, frozen v_z and banded Taylor series) against the NumPy FFT pipeline a user would write (zero-padded
  ``numpy.fft.fft2`` of w·exp(i v_z h), bilinear interpolation of the field onto the grid), over four patch sizes,
  with errors against the direct sum on a subset of cells.
* :func:`math_errors` — largest absolute error of the device's sin/cos/sinpi/cospi/native_/half_ built-ins and of
  the kernels' own sin/cos polynomial (``kernels/wo_sincos.h``) against float64 NumPy, on reduced (|x| ≤ π) and
  large (|x| ≤ 10⁴) arguments.

Times are the best of several repeats (wall clock, after a warm-up call that builds the kernels). They depend on
the machine and on its load; :func:`machine` records what it was.

References
----------
.. [1] docs/physics.md §1 (direct sum and its cost O(samples × directions)); Rabiner, Schafer & Rader 1969 (chirp-z).
.. [2] M. Frigo, S. G. Johnson, "The design and implementation of FFTW3", Proc. IEEE 93(2), 2005.
"""
from __future__ import annotations

import contextlib
import math
import os
import platform
import time
import warnings

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
import scipy.fft as sfft
from scipy.interpolate import RegularGridInterpolator

from . import scatter
from .scatter.direct import exact_phase_args, launch_pairs
from .runtime import build_options, build_program, get_runtime
from .surfaces.heightfield import HeightField
from .units import direction_from_angles

__all__ = ['WAVELENGTH_NM', 'MATH_FUNCTIONS', 'best_time', 'machine', 'numpy_direct_sum', 'NAIVE', 'large_patch_errors', 'direct_kernels', 'direct_scaling', 'fft_backends', 'numpy_fft_pipeline', 'fft_pipeline', 'math_errors', 'run_all', 'report']

#: nm, the benchmark wavelength
WAVELENGTH_NM = 500.0
#: OpenCL math functions measured by :func:`math_errors`, in the row order of ``kernels/bench_math.cl``
MATH_FUNCTIONS = ("sin", "cos", "sinpi", "cospi", "wo_sin_2pi", "wo_cos_2pi", "native_sin", "native_cos",
                  "half_sin", "half_cos")


def best_time(fn, repeat: int = 3, min_time: float = 0.0) -> float:
    """Best wall time (s) of *fn()* over *repeat* calls (more while the total is below *min_time*), after one
    warm-up call."""
    fn()
    times = []
    t_all = time.perf_counter()
    while len(times) < repeat or (time.perf_counter() - t_all < min_time and len(times) < 50):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def machine(rt=None) -> dict:
    """CPU, core count, load and the OpenCL device (what the numbers depend on)."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    out = {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__}
    try:
        out["load_average_1min"] = os.getloadavg()[0]
    except OSError:
        pass
    if rt is not None:
        out["device"] = rt.name
        out["platform"] = rt.device.platform.version.strip()
        out["fp64"] = bool(rt.fp64)
    return out


def _problem(n: int, n_dir: int, seed: int = 1):
    """An n × n Gaussian patch (σ = 60 nm, dx = λ/4) and n_dir directions spread over the hemisphere."""
    rng = np.random.default_rng(seed)
    hf = HeightField(rng.normal(0.0, 60e-9, (n, n)), WAVELENGTH_NM * 1e-9 / 4)
    smp = scatter.samples(hf)
    wi = scatter.grid._incident((30.0, 0.0))
    wo = direction_from_angles(np.degrees(np.arcsin(np.sqrt(rng.uniform(0, 0.98, n_dir)))),
                               rng.uniform(0, 360, n_dir))
    return smp, wi, wo


def numpy_direct_sum(smp: scatter.Samples, wi, wo, wavelength_nm: float, chunk_terms: int = 2**22) -> np.ndarray:
    """The direct sum as a user would write it in NumPy: U = dx dy Σ w exp(i k (ω_i + ω_o)·(x, y, h)), complex128,
    coordinates from the patch centre (the reference of the benchmark's 'NumPy direct sum')."""
    k = 2 * np.pi / (wavelength_nm * 1e-9)
    x = (smp.ix - (smp.nx - 1) / 2) * smp.dx
    y = (smp.iy - (smp.ny - 1) / 2) * smp.dy
    r = np.stack([x, y, smp.h])                       # (3, n)
    s = np.asarray(wo) + np.asarray(wi)
    out = np.empty(len(s), np.complex128)
    step = max(1, chunk_terms // max(smp.size, 1))
    for a in range(0, len(s), step):
        out[a:a + step] = np.exp(1j * k * (s[a:a + step] @ r)) @ smp.w
    return out * (smp.dx * smp.dy)


#: the baseline's row name
NAIVE = "opencl naive native_sin float32 fast-math"


def kirchhoff_U_sinpi_cl(smp, coef, *, runtime=None, precision="float32", local_size=0, **kw):
    """The direct-sum kernel before the speed work (``kernels/bench_kirchhoff.cl``): exact phase, SLEEF
    sinpi/cospi per term, one pair per work-item; run as it was, with driver-chosen work-groups."""
    return launch_pairs(smp, coef, kernel="kirchhoff_U_sinpi", program="bench_kirchhoff.cl", pairs_per_item=1,
                        chunk_args=exact_phase_args, runtime=runtime, precision=precision, local_size=local_size,
                        **kw)


def _naive_args(smp):
    """Per-launch arguments of the naive kernel: v = 2π s / λ in rad/m from the cycles-per-sample coefficients
    (reduced mod one cycle: the same exponential), and the patch geometry."""
    def args(q, dt, c, start, count):
        lat = [np.asarray(A, np.float64) * 2.0**-32 + lo for A, lo in ((c.Ax, c.lox), (c.Ay, c.loy))]
        lat = [np.where(x >= 0.5, x - 1.0, x) for x in lat]
        k = (2 * np.pi * lat[0] / smp.dx, 2 * np.pi * lat[1] / smp.dy, 2 * np.pi * c.cz)
        dev = [cla.to_device(q, np.ascontiguousarray(x.astype(dt))) for x in k]
        return (*[d.data for d in dev], dt(smp.dx), dt(smp.dy), dt((smp.nx - 1) / 2), dt((smp.ny - 1) / 2))
    return args


def kirchhoff_U_naive_cl(smp, coef, *, runtime=None, precision="float32", **kw):
    """The naive direct sum a user would write first (``kernels/bench_kirchhoff.cl``): float phase k s·x in
    radians, native_sin/native_cos, one pair per work-item, scalar loop: the benchmark's baseline."""
    return launch_pairs(smp, coef, kernel="kirchhoff_U_naive", program="bench_kirchhoff.cl", pairs_per_item=1,
                        chunk_args=_naive_args(smp), runtime=runtime, precision=precision, **kw)


def _naive(smp, coef, rt):
    """The naive kernel as its author would run it: -cl-fast-relaxed-math (without it PoCL cannot vectorize the
    sum and it runs ~10x slower), driver-chosen work-groups."""
    return kirchhoff_U_naive_cl(smp, coef, runtime=rt, precision="float32", local_size=0, fast_math=True)


def large_patch_errors(rt, n: int = 2**16, n_dir: int = 16) -> dict:
    """Error of each OpenCL variant on a 2 × n strip (n λ/4 long: 16384 λ for n = 2^16), against the float64
    twin, relative to the rms scattered field √⟨|U|²⟩ over the directions: where an unreduced float32 phase k·x
    fails."""
    rng = np.random.default_rng(7)
    hf = HeightField(rng.normal(0.0, 50e-9, (2, n)), WAVELENGTH_NM * 1e-9 / 4)
    smp = scatter.samples(hf, "boxcar")
    wi = scatter.grid._incident((60.0, 0.0))
    wo = direction_from_angles(rng.uniform(0, 80, n_dir), rng.uniform(0, 360, n_dir))
    coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
    ref = scatter.kirchhoff_U(smp, coef)
    scale = float(np.sqrt(np.mean(np.abs(ref) ** 2)))
    out = {"samples": smp.size, "length_wavelengths": n / 4}
    runs = {"opencl kirchhoff_U float32": lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt),
            "opencl kirchhoff_U float32 fast-math": lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, fast_math=True),
            NAIVE: lambda: _naive(smp, coef, rt)}
    if rt.fp64:
        runs["opencl kirchhoff_U float64"] = lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision="float64")
    for name, fn in runs.items():
        out[name] = float(np.max(np.abs(fn() - ref)) / scale)
    return out


def direct_kernels(rt, n: int = 256, n_dir: int = 4096, numpy_dirs: int = 64, repeat: int = 3) -> dict:
    """Throughput and error of the direct-sum implementations on one n × n patch and n_dir directions.

    The NumPy variants run on the first *numpy_dirs* directions only (they are ~100× slower); their terms/s are
    per term all the same.
    """
    smp, wi, wo = _problem(n, n_dir)
    coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
    sub = slice(0, numpy_dirs)
    U_ref = scatter.kirchhoff_U(smp, coef.take(sub))
    scale = float(np.sum(smp.w) * smp.dx * smp.dy)
    terms = smp.size * coef.size
    rows = []

    def add(name, fn, n_terms, u_slice):
        t = best_time(fn, repeat)
        U = fn()
        err = float(np.max(np.abs(U[u_slice] - U_ref)) / scale)
        rows.append({"name": name, "time_s": t, "terms": int(n_terms), "terms_per_s": n_terms / t, "error": err})

    precs = ["float32"] + (["float64"] if rt.fp64 else [])
    for p in precs:
        add(f"opencl kirchhoff_U {p}", lambda p=p: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision=p), terms, sub)
    for p in precs:
        add(f"opencl kirchhoff_U_sinpi {p} (previous kernel, SLEEF sinpi)",
            lambda p=p: kirchhoff_U_sinpi_cl(smp, coef, runtime=rt, precision=p), terms, sub)
    add("opencl kirchhoff_U float32 fast-math",
        lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision="float32", fast_math=True), terms, sub)
    add(NAIVE, lambda: _naive(smp, coef, rt), terms, sub)
    n_np = smp.size * numpy_dirs
    add("numpy direct sum (complex128)", lambda: numpy_direct_sum(smp, wi, wo[sub], WAVELENGTH_NM), n_np,
        slice(None))
    add("numpy twin kirchhoff_U (float64)", lambda: scatter.kirchhoff_U(smp, coef.take(sub)), n_np, slice(None))
    by = {r["name"]: r for r in rows}
    naive = by[NAIVE]["terms_per_s"]
    npy = by["numpy direct sum (complex128)"]["terms_per_s"]
    for r in rows:
        r["vs_naive"] = r["terms_per_s"] / naive
        r["vs_numpy"] = r["terms_per_s"] / npy
    return {"samples": smp.size, "directions": int(coef.size), "numpy_directions": numpy_dirs,
            "wavelength_nm": WAVELENGTH_NM, "rows": rows, "large_patch_errors": large_patch_errors(rt)}


def direct_scaling(rt, sizes=(32, 64, 128, 256), directions=(256, 1024, 4096, 16384), fixed_n: int = 128,
                   fixed_dirs: int = 1024, numpy_max_terms: float = 3e7, repeat: int = 2) -> dict:
    """Time (s) of the direct sum vs samples (n × n, *fixed_dirs* directions) and vs directions (*fixed_n*²
    samples): the project's kernel (float32, float64), the naive kernel and the NumPy direct sum (only where it
    has at most *numpy_max_terms* terms)."""

    def one(n, nd):
        smp, wi, wo = _problem(n, nd)
        coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
        row = {"samples": smp.size, "directions": nd, "terms": smp.size * nd}
        row["opencl_float32_s"] = best_time(lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt), repeat)
        row["opencl_float64_s"] = (best_time(lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision="float64"),
                                             repeat) if rt.fp64 else None)
        row["naive_float32_s"] = best_time(lambda: _naive(smp, coef, rt), repeat)
        row["numpy_s"] = (best_time(lambda: numpy_direct_sum(smp, wi, wo, WAVELENGTH_NM), 1)
                          if smp.size * nd <= numpy_max_terms else None)
        return row

    return {"by_samples": [one(n, fixed_dirs) for n in sizes],
            "by_directions": [one(fixed_n, nd) for nd in directions]}


def fft_backends(sizes=(256, 512, 1024), repeat: int = 3, rt=None, solver_sizes=(128, 256, 512)) -> dict:
    """2-D complex FFT throughput (points/s) per implementation and size; unavailable ones are listed with the
    reason."""

    rng = np.random.default_rng(0)
    rows, missing = [], {}
    impls = {"numpy.fft": lambda a: np.fft.fft2(a),
             "scipy.fft workers=1": lambda a: sfft.fft2(a, workers=1),
             "scipy.fft workers=2": lambda a: sfft.fft2(a, workers=2)}
    try:
        import pyfftw

        def fftw(a, threads, _cache={}):
            key = (a.shape, threads)
            if key not in _cache:       # planned once (FFTW_MEASURE), outside the timed calls
                src = pyfftw.empty_aligned(a.shape, "complex128")
                dst = pyfftw.empty_aligned(a.shape, "complex128")
                _cache[key] = (src, pyfftw.FFTW(src, dst, axes=(0, 1), threads=threads,
                                                flags=("FFTW_MEASURE",)))
            src, plan = _cache[key]
            src[...] = a
            return plan()

        impls["pyfftw threads=1"] = lambda a: fftw(a, 1)
        impls["pyfftw threads=2"] = lambda a: fftw(a, 2)
    except ImportError as exc:
        missing["pyfftw"] = f"not installed ({exc})"
    vk = None
    if rt is not None:
        try:
            from pyvkfft.opencl import VkFFTApp

            vk = VkFFTApp
        except Exception as exc:  # noqa: BLE001 - an optional package that may fail to import in many ways
            missing["pyvkfft"] = f"not usable ({type(exc).__name__}: {str(exc).splitlines()[0][:120]})"
    for n in sizes:
        a = rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))
        row = {"n": n, "points": n * n}
        for name, fn in impls.items():
            row[name] = n * n / best_time(lambda fn=fn: fn(a), repeat)
        if vk is not None:

            try:
                d = cla.to_device(rt.queue, a.astype(np.complex64))
                app = vk(d.shape, d.dtype, queue=rt.queue, ndim=2, inplace=True)

                def run(app=app, d=d):
                    app.fft(d)
                    rt.queue.finish()

                row["pyvkfft opencl complex64 (device-resident)"] = n * n / best_time(run, repeat)
            except Exception as exc:  # noqa: BLE001
                missing["pyvkfft"] = f"failed on {rt.name}: {type(exc).__name__}: {str(exc)[:120]}"
        rows.append(row)
    return {"rows": rows, "missing": missing, "solver": _solver_backends(solver_sizes, repeat)}


def _solver_backends(sizes, repeat: int) -> list[dict]:
    """Time (s) of the fft solver (:func:`waveoptics.scatter.field_fft`, order auto, n × n patch onto an n × n
    grid) with scipy.fft's default, with ``scipy.fft.set_workers(2)`` and with pyFFTW as scipy.fft's backend —
    the choice that matters for the solver, whose chirp-z transforms are batches of 1-D FFTs."""


    ctx = {"scipy.fft": contextlib.nullcontext, "scipy.fft workers=2": lambda: sfft.set_workers(2)}
    try:
        import pyfftw.interfaces.scipy_fft as pfs
        from pyfftw.interfaces import cache

        cache.enable()
        ctx["pyfftw backend"] = lambda: sfft.set_backend(pfs)
    except ImportError:
        pass
    rng = np.random.default_rng(4)
    out = []
    for n in sizes:
        smp = scatter.samples(HeightField(rng.normal(0.0, 30e-9, (n, n)), WAVELENGTH_NM * 1e-9 / 4))
        wi = scatter.grid._incident((30.0, 0.0))
        grid = scatter.DirectionGrid.hemisphere(n)
        row = {"n": n, "transforms": scatter.field_fft(smp, wi, grid, WAVELENGTH_NM)[1]["transforms"]}
        for name, c in ctx.items():
            with c():
                row[name] = best_time(lambda: scatter.field_fft(smp, wi, grid, WAVELENGTH_NM), repeat)
        out.append(row)
    return out


def numpy_fft_pipeline(smp: scatter.Samples, wi, grid: scatter.DirectionGrid, wavelength_nm: float,
                       pad: int | None = None) -> np.ndarray:
    """The FFT pipeline a user would write: frozen v_z = 2k cos θ_i, zero-padded ``numpy.fft.fft2`` of
    w exp(i v_z h) (pad × pad, default the next power of two ≥ 2 max(nx, ny)), then bilinear interpolation of the
    field at s_xy dx/λ cycles per sample onto the grid's cells (m², zero outside the disc)."""

    lam = wavelength_nm * 1e-9
    h, w = smp.grid_arrays()
    g = w * np.exp(2j * np.pi * (2 * wi[2] / lam) * h)
    P = pad or 1 << int(math.ceil(math.log2(2 * max(smp.nx, smp.ny))))
    # Σ g e^{+2πi f n}: the inverse FFT times P², frequencies f = k/P (cycles per sample), shifted to [-1/2, 1/2)
    F = np.fft.fftshift(np.fft.ifft2(g, s=(P, P))) * (P * P)
    f = (np.arange(P) - P // 2) / P
    re = RegularGridInterpolator((f, f), F.real, bounds_error=False, fill_value=0.0)
    im = RegularGridInterpolator((f, f), F.imag, bounds_error=False, fill_value=0.0)
    U, V = np.meshgrid(grid.u, grid.v)
    pts = np.stack([((wi[1] + V) * smp.dy / lam).ravel(), ((wi[0] + U) * smp.dx / lam).ravel()], axis=1)
    out = (re(pts) + 1j * im(pts)).reshape(U.shape)
    # origin at the patch centre, as the project's solvers
    cx, cy = (smp.nx - 1) / 2, (smp.ny - 1) / 2
    out *= np.exp(-2j * np.pi * (cx * (wi[0] + U) * smp.dx / lam + cy * (wi[1] + V) * smp.dy / lam))
    return np.where(grid.inside, out, 0.0) * smp.dx * smp.dy


def fft_pipeline(sizes=(64, 128, 256, 512), repeat: int = 2, check_cells: int = 200, rt=None) -> dict:
    """The ``fft`` solver (order 0 and auto) against :func:`numpy_fft_pipeline` on n × n patches with an n × n
    direction grid: time and error of |U|² against the direct sum (float64 kernel or twin) on *check_cells*
    cells, relative to the flat-patch peak (Σ w dx dy)²."""
    rows = []
    rng = np.random.default_rng(3)
    for n in sizes:
        hf = HeightField(rng.normal(0.0, 30e-9, (n, n)), WAVELENGTH_NM * 1e-9 / 4)
        smp = scatter.samples(hf)
        wi = scatter.grid._incident((30.0, 0.0))
        grid = scatter.DirectionGrid.hemisphere(n)
        cells = np.flatnonzero(grid.inside)
        pick = np.sort(rng.choice(cells, size=min(check_cells, cells.size), replace=False))
        wo = grid.directions().reshape(-1, 3)[pick]
        coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
        if rt is not None and rt.fp64:
            U_ref = scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision="float64")
        else:
            U_ref = scatter.kirchhoff_U(smp, coef)
        I_ref = np.abs(U_ref) ** 2
        top = float(np.sum(smp.w) * smp.dx * smp.dy) ** 2
        row = {"n": n, "samples": smp.size, "cells": grid.n_u * grid.n_v}
        for name, fn in (("fft solver order 0", lambda: scatter.field_fft(smp, wi, grid, WAVELENGTH_NM, 0)[0]),
                         ("fft solver order auto", lambda: scatter.field_fft(smp, wi, grid, WAVELENGTH_NM, "auto")[0]),
                         ("numpy fft2 + interpolation", lambda: numpy_fft_pipeline(smp, wi, grid, WAVELENGTH_NM))):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t = best_time(fn, repeat)
                U = fn().ravel()[pick]
            row[name] = {"time_s": t, "error": float(np.max(np.abs(np.abs(U) ** 2 - I_ref)) / top)}
        rows.append(row)
    return {"rows": rows, "wavelength_nm": WAVELENGTH_NM}


def math_errors(rt, n: int = 200_001) -> dict:
    """Largest absolute error of the device's math built-ins (and the kernels' polynomial) against float64 NumPy.

    Arguments x are uniform random float32 (float64) values; the exact value is computed from the same x in float64
    (sinpi: sin(π (x mod 2)); wo_sin_2pi: sin(2π (x mod 1)), the reduction exact). Two ranges: |x| ≤ π and
    |x| ≤ 10⁴ (large phases; the error there is the function's on its float32 argument — the argument's own
    rounding, which dominates a naive k·x phase, is measured by :func:`large_patch_errors`).
    """


    def cyc(x, period):   # x mod period, exact in float64, so that π x keeps all its digits
        return x - period * np.rint(x / period)

    exact = {"sin": np.sin, "cos": np.cos, "sinpi": lambda x: np.sin(np.pi * cyc(x, 2.0)),
             "cospi": lambda x: np.cos(np.pi * cyc(x, 2.0)), "wo_sin_2pi": lambda x: np.sin(2 * np.pi * cyc(x, 1.0)),
             "wo_cos_2pi": lambda x: np.cos(2 * np.pi * cyc(x, 1.0)),
             "native_sin": np.sin, "native_cos": np.cos, "half_sin": np.sin, "half_cos": np.cos}
    out = {}
    for prec in ["float32"] + (["float64"] if rt.fp64 else []):
        dt = rt.real_dtype(prec)
        prg = build_program(rt, "bench_math.cl", build_options(dt, scatter.direct._sincos_options(prec)))
        knl = cl.Kernel(prg, "math_builtins")
        nf = len(MATH_FUNCTIONS) if prec == "float32" else 6
        res = {}
        rng = np.random.default_rng(11)
        for label, lim in (("|x|<=pi", math.pi), ("|x|<=1e4", 1e4)):
            x = rng.uniform(-lim, lim, n).astype(dt)
            d_x = cla.to_device(rt.queue, x)
            d_o = cla.empty(rt.queue, nf * n, dt)
            knl(rt.queue, (n,), None, d_x.data, np.int32(n), d_o.data)
            vals = d_o.get().reshape(nf, n).astype(np.float64)
            x64 = x.astype(np.float64)
            for k, name in enumerate(MATH_FUNCTIONS[:nf]):
                err = float(np.max(np.abs(vals[k] - exact[name](x64))))
                res.setdefault(name, {})[label] = err
        out[prec] = res
    return out


def brdf_eval_rates(n: int = 100_000, loop: int = 300) -> dict:
    """Evaluations per second of ``eval()`` (:mod:`waveoptics.brdf.protocol`) for the microfacet model and the
    two-scale PSD model (gold, micro GGX α = 0.1, the default nano statistics, 550 nm) by quadrature and from its
    tabulated diffracted lobes, batched against a plain Python loop calling it one (ω_i, ω_o, λ) at a time; with one
    shared ω_i and with every pair its own ω_i (as a renderer asks)."""
    from . import brdf
    from .request import DEFAULT_NANO, make_nano

    rng = np.random.default_rng(7)

    def dirs(k):
        d = rng.normal(size=(k, 3))
        d[:, 2] = np.abs(d[:, 2])
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    micro = brdf.Micro(alpha=0.1)
    nano = make_nano(DEFAULT_NANO, [550.0])
    models = {"microfacet": brdf.MicrofacetBRDF("gold", micro),
              "twoscale (PSD, quadrature)": brdf.TwoScaleBRDF("gold", micro, nano=nano),
              "twoscale (PSD, tabulated 128²)": brdf.TabulatedTwoScaleBRDF("gold", micro, nano=nano,
                                                                          wavelengths_nm=(550.0,))}
    wo = dirs(n)
    wi_one = np.array([0.5, 0.0, np.sqrt(0.75)])
    wi_many = dirs(n)
    rows = []
    for name, b in models.items():
        m = n // 10 if "quadrature" in name else n
        b.eval(wi_one, wo[:16], 550.0)  # build tables once
        t_one = best_time(lambda: b.eval(wi_one, wo[:m], 550.0), repeat=2)
        t_many = best_time(lambda: b.eval(wi_many[:m], wo[:m], 550.0), repeat=2)
        t_loop = best_time(lambda: [b.eval(wi_many[j], wo[j], 550.0) for j in range(loop)], repeat=1)
        rows.append({"model": name, "pairs": m, "shared_wi_per_s": m / t_one, "own_wi_per_s": m / t_many,
                     "loop_per_s": loop / t_loop, "batch_vs_loop": (m / t_many) / (loop / t_loop)})
    return {"rows": rows}


def fft_threads(n: int = 256, n_wavelengths: int = 8, repeat: int = 2) -> dict:
    """The fft solver's wall and CPU time on one core and on all of them (wavelengths in parallel threads,
    :func:`waveoptics.runtime.cpu_workers`): an n × n Gaussian patch onto an n × n grid at *n_wavelengths*."""
    from .runtime import cpu_workers

    smp, wi, _ = _problem(n, 4)
    grid = scatter.DirectionGrid.hemisphere(n)
    wl = np.linspace(450.0, 650.0, n_wavelengths)
    sol = scatter.get_solver("fft")
    out = {"n": n, "wavelengths": n_wavelengths, "cores": cpu_workers(), "rows": []}
    for workers in sorted({1, cpu_workers()}):
        c0 = time.process_time()
        wall = best_time(lambda: sol.grid_field(smp, wi, grid, wl, workers=workers), repeat=repeat)
        cpu = (time.process_time() - c0) / (repeat + 1)
        out["rows"].append({"threads": workers, "wall_s": wall, "cpu_s": cpu})
    base = out["rows"][0]["wall_s"]
    for r in out["rows"]:
        r["speedup"] = base / r["wall_s"]
    return out


def run_all(rt=None, quick: bool = False, progress=None) -> dict:
    """Every benchmark (smaller sizes with *quick*), with :func:`machine`."""

    rt = rt or get_runtime()
    step = progress or (lambda *_: None)
    t0 = time.perf_counter()
    out = {"machine": machine(rt), "quick": quick}
    if quick:
        out["math_errors"] = math_errors(rt, n=20_001)
        step(1)
        out["direct"] = direct_kernels(rt, n=64, n_dir=512, numpy_dirs=32, repeat=1)
        step(1)
        out["direct_scaling"] = direct_scaling(rt, sizes=(16, 24, 32, 48), directions=(32, 64, 128, 256),
                                               fixed_n=32, fixed_dirs=64, repeat=1)
        step(1)
        out["fft_backends"] = fft_backends(sizes=(64, 128), repeat=1, rt=rt, solver_sizes=(32, 64))
        step(1)
        out["fft_pipeline"] = fft_pipeline(sizes=(32, 48, 64, 96), repeat=1, check_cells=50, rt=rt)
        step(1)
        out["brdf_eval"] = brdf_eval_rates(n=5_000, loop=50)
        step(1)
        out["fft_threads"] = fft_threads(n=64, n_wavelengths=4, repeat=1)
    else:
        out["math_errors"] = math_errors(rt)
        step(1)
        out["direct"] = direct_kernels(rt)
        step(1)
        out["direct_scaling"] = direct_scaling(rt)
        step(1)
        out["fft_backends"] = fft_backends(rt=rt)
        step(1)
        out["fft_pipeline"] = fft_pipeline(rt=rt)
        step(1)
        out["brdf_eval"] = brdf_eval_rates()
        step(1)
        out["fft_threads"] = fft_threads()
    step(1)
    out["machine"]["load_average_1min_after"] = machine()["load_average_1min"] if hasattr(os, "getloadavg") else None
    out["time_s"] = time.perf_counter() - t0
    return out


def _g(v, fmt=".3g"):
    return "—" if v is None else format(v, fmt)


def report(res: dict) -> str:
    """The benchmark results as Markdown tables (the text of ``waveoptics bench`` and docs/performance.md)."""
    m = res["machine"]
    lines = [f"Machine: {m['cpu']}, {m['cores']} cores; OpenCL device {m.get('device')} ({m.get('platform')}); "
             f"1-min load average {m.get('load_average_1min', float('nan')):.2f} before, "
             f"{_g(m.get('load_average_1min_after'), '.2f')} after.", ""]
    d = res["direct"]
    lines += [f"### Direct Kirchhoff sum: {d['samples']} samples × {d['directions']} directions "
              f"(NumPy rows: {d['numpy_directions']} directions)", "",
              "| implementation | time (s) | G terms/s | × naive kernel | × NumPy direct sum | max error / Σw |",
              "|---|---|---|---|---|---|"]
    for r in d["rows"]:
        lines.append(f"| {r['name']} | {r['time_s']:.3g} | {r['terms_per_s'] / 1e9:.3g} | {r['vs_naive']:.3g} "
                     f"| {r['vs_numpy']:.3g} | {r['error']:.2e} |")
    s = res["direct_scaling"]
    for key, title in (("by_samples", "samples (directions fixed)"), ("by_directions", "directions (samples fixed)")):
        lines += ["", f"### Direct sum: time (s) against {title}", "",
                  "| samples | directions | terms | kernel float32 | kernel float64 | naive float32 | NumPy "
                  "| G terms/s float32 |", "|---|---|---|---|---|---|---|---|"]
        for r in s[key]:
            lines.append(f"| {r['samples']} | {r['directions']} | {r['terms']:.3g} | {_g(r['opencl_float32_s'])} "
                         f"| {_g(r['opencl_float64_s'])} | {_g(r['naive_float32_s'])} | {_g(r['numpy_s'])} "
                         f"| {r['terms'] / r['opencl_float32_s'] / 1e9:.3g} |")
    f = res["fft_backends"]
    names = [k for k in f["rows"][0] if k not in ("n", "points")]
    lines += ["", "### 2-D complex FFT: M points/s", "", "| n × n | " + " | ".join(names) + " |",
              "|---|" + "---|" * len(names)]
    for r in f["rows"]:
        lines.append(f"| {r['n']} | " + " | ".join(_g(r.get(k) and r[k] / 1e6) for k in names) + " |")
    for k, why in f["missing"].items():
        lines.append(f"\n{k}: {why}")
    sb = f.get("solver") or []
    if sb:
        names = [k for k in sb[0] if k not in ("n", "transforms")]
        lines += ["", "### fft solver (order auto, n × n patch onto an n × n grid): time (s) per FFT backend", "",
                  "| n | 2-D chirp-z transforms | " + " | ".join(names) + " |", "|---|---|" + "---|" * len(names)]
        for r in sb:
            lines.append(f"| {r['n']} | {r['transforms']} | " + " | ".join(_g(r[k]) for k in names) + " |")
    p = res["fft_pipeline"]
    keys = ["fft solver order 0", "fft solver order auto", "numpy fft2 + interpolation"]
    lines += ["", "### fft solver vs a NumPy FFT pipeline (n × n patch onto an n × n direction grid)", "",
              "| n | " + " | ".join(f"{k}: time (s) | error" for k in keys) + " |", "|---|" + "---|---|" * len(keys)]
    for r in p["rows"]:
        lines.append(f"| {r['n']} | " + " | ".join(f"{r[k]['time_s']:.3g} | {r[k]['error']:.1e}" for k in keys)
                     + " |")
    if "brdf_eval" in res:
        lines += ["", "### BRDF eval(): (ω_i, ω_o, λ) evaluations per second (NumPy, one process)", "",
                  "| model | pairs | batch, one ω_i | batch, own ω_i per pair | Python loop | batch ÷ loop |",
                  "|---|---|---|---|---|---|"]
        for r in res["brdf_eval"]["rows"]:
            lines.append(f"| {r['model']} | {r['pairs']} | {r['shared_wi_per_s']:.3g} | {r['own_wi_per_s']:.3g} "
                         f"| {r['loop_per_s']:.3g} | {r['batch_vs_loop']:.3g} |")
    if "fft_threads" in res:
        ft = res["fft_threads"]
        lines += ["", f"### fft solver on 1 and {ft['cores']} cores ({ft['n']}² patch and grid, "
                  f"{ft['wavelengths']} wavelengths in parallel threads)", "",
                  "| threads | wall (s) | CPU (s) | speed-up |", "|---|---|---|---|"]
        for r in ft["rows"]:
            lines.append(f"| {r['threads']} | {r['wall_s']:.3g} | {r['cpu_s']:.3g} | {r['speedup']:.3g} |")
    me = res["math_errors"]
    lines += ["", "### Math built-ins: largest absolute error against float64 NumPy", "",
              "| function | " + " | ".join(f"{p} {lab}" for p in me for lab in next(iter(me[p].values()))) + " |",
              "|---|" + "---|" * sum(len(next(iter(me[p].values()))) for p in me)]
    for name in MATH_FUNCTIONS:
        cells = []
        for p in me:
            for lab in next(iter(me[p].values())):
                cells.append(_g(me[p].get(name, {}).get(lab), ".2e"))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
