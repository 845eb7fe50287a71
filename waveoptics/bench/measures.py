"""The benchmarks, each a function returning plain data, and :func:`run_all`, which runs them all (the measured
quantities are listed in :mod:`waveoptics.bench`).

References
----------
.. [1] docs/physics.md §1 (direct sum and its cost O(samples × directions)); Rabiner, Schafer & Rader 1969 (chirp-z).
"""
from __future__ import annotations

import contextlib
import math
import os
import time
import warnings

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
import scipy.fft as sfft

from .. import scatter
from ..runtime import build_options, build_program, get_runtime
from ..surfaces.heightfield import HeightField
from ..units import direction_from_angles
from .baselines import (NAIVE, footprint_exact_brdf, naive_sum, kirchhoff_U_sinpi_cl, numpy_direct_sum,
                        numpy_fft_pipeline)
from .common import WAVELENGTH_NM, bench_problem, best_time, machine
from .model_speed import brdf_eval_rates, simulate_times

__all__ = ['MATH_FUNCTIONS', 'large_patch_errors', 'direct_kernels', 'direct_scaling', 'fft_backends', 'fft_pipeline',
           'math_errors', 'fft_threads', 'footprint_evaluations', 'run_all']

#: OpenCL math functions measured by :func:`math_errors`, in the row order of ``kernels/bench_math.cl``
MATH_FUNCTIONS = ("sin", "cos", "sinpi", "cospi", "wo_sin_2pi", "wo_cos_2pi", "native_sin", "native_cos",
                  "half_sin", "half_cos")


def large_patch_errors(rt, n: int = 2**16, n_dir: int = 16) -> dict:
    """Error of each OpenCL variant on a 2 × n strip (n λ/4 long: 16384 λ for n = 2^16), against the float64
    twin, relative to the rms scattered field √⟨|U|²⟩ over the directions: where an unreduced float32 phase k·x
    fails."""
    rng = np.random.default_rng(7)
    hf = HeightField(rng.normal(0.0, 50e-9, (2, n)), WAVELENGTH_NM * 1e-9 / 4)
    smp = scatter.samples(hf, "boxcar")
    wi = scatter.grid.incident_dirs((60.0, 0.0))
    wo = direction_from_angles(rng.uniform(0, 80, n_dir), rng.uniform(0, 360, n_dir))
    coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
    ref = scatter.kirchhoff_U(smp, coef)
    scale = float(np.sqrt(np.mean(np.abs(ref) ** 2)))
    out = {"samples": smp.size, "length_wavelengths": n / 4}
    runs = {"opencl kirchhoff_U float32": lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt),
            "opencl kirchhoff_U float32 fast-math": lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, fast_math=True),
            NAIVE: lambda: naive_sum(smp, coef, rt)}
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
    smp, wi, wo = bench_problem(n, n_dir)
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
    add(NAIVE, lambda: naive_sum(smp, coef, rt), terms, sub)
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
        smp, wi, wo = bench_problem(n, nd)
        coef = scatter.phase_coefficients(smp, wi, wo, [WAVELENGTH_NM])
        row = {"samples": smp.size, "directions": nd, "terms": smp.size * nd}
        row["opencl_float32_s"] = best_time(lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt), repeat)
        row["opencl_float64_s"] = (best_time(lambda: scatter.kirchhoff_U_cl(smp, coef, runtime=rt, precision="float64"),
                                             repeat) if rt.fp64 else None)
        row["naive_float32_s"] = best_time(lambda: naive_sum(smp, coef, rt), repeat)
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
        wi = scatter.grid.incident_dirs((30.0, 0.0))
        grid = scatter.DirectionGrid.hemisphere(n)
        row = {"n": n, "transforms": scatter.field_fft(smp, wi, grid, WAVELENGTH_NM)[1]["transforms"]}
        for name, c in ctx.items():
            with c():
                row[name] = best_time(lambda: scatter.field_fft(smp, wi, grid, WAVELENGTH_NM), repeat)
        out.append(row)
    return out


def fft_pipeline(sizes=(64, 128, 256, 512), repeat: int = 2, check_cells: int = 200, rt=None) -> dict:
    """The ``fft`` solver (order 0 and auto) against :func:`numpy_fft_pipeline` on n × n patches with an n × n
    direction grid: time and error of |U|² against the direct sum (float64 kernel or twin) on *check_cells*
    cells, relative to the flat-patch peak (Σ w dx dy)²."""
    rows = []
    rng = np.random.default_rng(3)
    for n in sizes:
        hf = HeightField(rng.normal(0.0, 30e-9, (n, n)), WAVELENGTH_NM * 1e-9 / 4)
        smp = scatter.samples(hf)
        wi = scatter.grid.incident_dirs((30.0, 0.0))
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
        prg = build_program(rt, "bench_math.cl", build_options(dt, scatter.direct.sincos_options(prec)))
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


def fft_threads(n: int = 256, n_wavelengths: int = 8, repeat: int = 2) -> dict:
    """The fft solver's wall and CPU time on one core and on all of them (wavelengths in parallel threads,
    :func:`waveoptics.runtime.cpu_workers`): an n × n Gaussian patch onto an n × n grid at *n_wavelengths*."""
    from ..runtime import cpu_workers

    smp, wi, _ = bench_problem(n, 4)
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


def footprint_evaluations(rt, sigmas_um=(2.0, 5.0, 10.0), grid: int = 5, repeat: int = 2) -> dict:
    """One Gaussian footprint's wave BRDF at 0.1 µm spacing (a Gaussian random field, σ = 20 nm, T = 1 µm;
    λ = 500 nm; ω_i at direction cosines (0.3, 0.1); *grid* × *grid* ω_o about the mirror direction, a step of half
    the speckle width λ/(2πσ)) by the library's direct sum (:func:`waveoptics.scatter.pixel_brdf`, NumPy twin and
    OpenCL kernel) and by Yan et al. 2018's Gabor kernels (:func:`waveoptics.scatter.gabor_footprint_brdf`):
    time per direction pair (the Gabor kernels built once per footprint, counted) and the errors of energy (Σ f
    over the grid) and peak against the exact float64 sum over ±5σ (:func:`footprint_exact_brdf`)."""
    from ..surfaces import Footprint, generators

    dx = 0.1e-6
    n = int(math.ceil(2 * 5.2 * max(sigmas_um) * 1e-6 / dx)) + 8
    hf = generators.gaussian(20e-9, 1e-6, (n * dx, n * dx), (n, n), seed=32)
    precision = "float64" if rt.fp64 else "float32"
    rows = []
    for sig_um in sigmas_um:
        fp = Footprint((n / 2 + 0.3) * dx, (n / 2 - 0.4) * dx, sig_um * 1e-6)
        wi = _direction(0.3, 0.1)
        m = (np.arange(grid) - (grid - 1) / 2) * 0.5 * WAVELENGTH_NM * 1e-9 / (2 * np.pi * fp.sigma)
        wo = np.array([_direction(-0.3 + u, -0.1 + v) for v in m for u in m])
        ref = footprint_exact_brdf(hf.heights, dx, fp, wi, wo, WAVELENGTH_NM)
        runs = {"numpy": lambda: scatter.pixel_brdf(hf, [fp] * len(wo), wi, wo, [WAVELENGTH_NM],
                                                    backend="numpy").wave[:, 0],
                "opencl": lambda: scatter.pixel_brdf(hf, [fp] * len(wo), wi, wo, [WAVELENGTH_NM], precision=precision,
                                                     runtime=rt).wave[:, 0],
                "gabor": lambda: scatter.gabor_footprint_brdf(hf, fp, wi, wo, [WAVELENGTH_NM])[:, 0]}
        box = scatter.gabor_kernels(hf, fp).size
        row = {"sigma_um": sig_um, "samples": box, "pairs": len(wo), "opencl_precision": precision}
        for name, fn in runs.items():
            row[f"{name}_s_per_pair"] = best_time(fn, repeat) / len(wo)
            f = fn()
            row[f"{name}_energy_error"] = float(abs(np.sum(f) / np.sum(ref) - 1))
            row[f"{name}_peak_error"] = float(abs(f.max() / ref.max() - 1))
        row["gabor_vs_numpy_time"] = row["gabor_s_per_pair"] / row["numpy_s_per_pair"]
        row["gabor_vs_opencl_time"] = row["gabor_s_per_pair"] / row["opencl_s_per_pair"]
        row["gabor_vs_numpy_peak_error"] = row["gabor_peak_error"] / max(row["numpy_peak_error"], 1e-300)
        rows.append(row)
    return {"rows": rows, "wavelength_nm": WAVELENGTH_NM, "spacing_um": dx * 1e6,
            "kernel_sigma": scatter.KERNEL_SIGMA}


def _direction(u: float, v: float) -> np.ndarray:
    """The unit direction (u, v, √(1 − u² − v²)) of direction cosines u, v."""
    return np.array([u, v, math.sqrt(1.0 - u * u - v * v)])


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
        out["brdf_eval"] = brdf_eval_rates(n=5_000, loop=50, resolution=32, min_time=0.0)
        step(1)
        out["fft_threads"] = fft_threads(n=64, n_wavelengths=4, repeat=1)
        step(1)
        out["footprints"] = footprint_evaluations(rt, sigmas_um=(2.0, 5.0), grid=3, repeat=1)
        step(1)
        out["simulate"] = simulate_times(quick=True, repeat=1)
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
        out["footprints"] = footprint_evaluations(rt)
        step(1)
        out["simulate"] = simulate_times()
    step(1)
    out["machine"]["load_average_1min_after"] = machine()["load_average_1min"] if hasattr(os, "getloadavg") else None
    out["time_s"] = time.perf_counter() - t0
    return out
