"""The baselines the project's kernels are measured against, as a user would otherwise write them: the direct sum
in NumPy, the naive OpenCL kernel and the kernel the project replaced (launch code of ``kernels/bench_kirchhoff.cl``),
and the NumPy FFT pipeline.

References
----------
.. [1] docs/physics.md §1 (direct sum and its cost O(samples × directions)).
"""
from __future__ import annotations

import math

import numpy as np
import pyopencl.array as cla
from scipy.interpolate import RegularGridInterpolator

from .. import scatter
from ..scatter.direct import exact_phase_args, launch_pairs

__all__ = ['numpy_direct_sum', 'footprint_exact_brdf', 'NAIVE', 'kirchhoff_U_sinpi_cl', 'kirchhoff_U_naive_cl', 'numpy_fft_pipeline']


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


def footprint_exact_brdf(heights, dx: float, fp, wi, wo, wavelength_nm: float, n_sigma: float = 5.0,
                         chunk_terms: int = 2**22) -> np.ndarray:
    """The wave BRDF of Gaussian footprint *fp* (σ, centre in m from the first sample of *heights*, spacing *dx*)
    at the direction pairs (ω_i, ω_o (n, 3)) by a plain float64 sum over its samples within *n_sigma* widths:
    f = K |ΔxΔy Σ G e^{ik s·(x − c, h)}|² / (Σ G² ΔxΔy), K = |s|⁴ / (4 λ² cos θ_i cos θ_o (cos θ_i + cos θ_o)²)
    (docs/physics.md §1; Beckmann & Spizzichino 1963 ch. 3), np.exp of complex128; the reference of
    :func:`waveoptics.bench.footprint_evaluations`."""
    sig = fp.sigma
    i0, i1 = math.floor((fp.x - n_sigma * sig) / dx), math.ceil((fp.x + n_sigma * sig) / dx) + 1
    j0, j1 = math.floor((fp.y - n_sigma * sig) / dx), math.ceil((fp.y + n_sigma * sig) / dx) + 1
    X, Y = np.meshgrid(np.arange(i0, i1) * dx - fp.x, np.arange(j0, j1) * dx - fp.y)
    G = np.exp(-(X * X + Y * Y) / (2 * sig * sig)).ravel()
    r = np.stack([X.ravel(), Y.ravel(), np.asarray(heights[j0:j1, i0:i1], dtype=float).ravel()])
    lam = wavelength_nm * 1e-9
    s = np.asarray(wi, dtype=float) + np.asarray(wo, dtype=float)
    U = np.empty(len(s), np.complex128)
    step = max(1, chunk_terms // G.size)
    for a in range(0, len(s), step):
        U[a:a + step] = np.exp(2j * np.pi / lam * (s[a:a + step] @ r)) @ G
    U *= dx * dx
    ci, co = np.broadcast_to(np.asarray(wi, float), s.shape)[:, 2], np.asarray(wo, float)[:, 2]
    K = np.sum(s * s, axis=1) ** 2 / (4 * lam ** 2 * ci * co * (ci + co) ** 2)
    return K * np.abs(U) ** 2 / (np.sum(G * G) * dx * dx)


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


def naive_sum(smp, coef, rt):
    """The naive kernel as its author would run it: -cl-fast-relaxed-math (without it PoCL cannot vectorize the
    sum and it runs ~10x slower), driver-chosen work-groups."""
    return kirchhoff_U_naive_cl(smp, coef, runtime=rt, precision="float32", local_size=0, fast_math=True)


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
