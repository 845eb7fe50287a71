"""The direct Kirchhoff sum U = Σ_j w_j exp(2πi φ_j) over samples and directions: exact fixed-point phases,
the NumPy reference (:func:`kirchhoff_U`) and its OpenCL twin (:func:`kirchhoff_U_cl`, ``kernels/kirchhoff.cl``).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pyopencl as cl
import pyopencl.array as cla

from ..errors import WaveopticsError
from ..runtime import build_options, build_program, get_runtime
from .patch import Samples

__all__ = ['VECTOR_WIDTH', 'TERMS_PER_LAUNCH', 'PhaseCoefficients', 'phase_coefficients', 'kirchhoff_phase', 'kirchhoff_U', 'PAIRS_PER_ITEM', 'SINCOS_TERMS', 'sincos_poly', 'sincos_2pi', 'kirchhoff_phase_cl', 'sincos_2pi_cl', 'launch_pairs', 'exact_phase_args', 'kirchhoff_U_cl']

#: samples per SIMD step in kernels/kirchhoff.cl (16 measured fastest under PoCL on AVX-512; GPUs unroll it)
VECTOR_WIDTH = 16
#: target number of sample-direction terms per OpenCL launch (keeps each launch ~0.1-1 s on a CPU)
TERMS_PER_LAUNCH = 2**29


# ----------------------------------------------------------------------------------------------------------------
# Phase coefficients and the direct sum (NumPy twin and OpenCL)
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PhaseCoefficients:
    """Per-pair phase coefficients, all in cycles (shape (n_pairs,)).

    phase_j = ix_j a_x + iy_j a_y + h_j cz + c0 with a = A / 2³² + lo (A a uint32, exact fixed point of
    a mod 1) — see ``kernels/kirchhoff.cl``.
    """

    Ax: np.ndarray
    Ay: np.ndarray
    lox: np.ndarray
    loy: np.ndarray
    cz: np.ndarray
    c0: np.ndarray

    @property
    def size(self) -> int:
        return int(self.cz.size)

    def take(self, sl) -> "PhaseCoefficients":
        return PhaseCoefficients(*(getattr(self, k)[sl] for k in ("Ax", "Ay", "lox", "loy", "cz", "c0")))


def _fixed_point(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split cycles-per-sample *a* into (A uint32, lo) with a ≡ A / 2³² + lo (mod 1), |lo| ≤ 2⁻³³."""
    r = a - np.round(a)                       # in [-1/2, 1/2], exact in float64 for |a| < 2^52
    Ai = np.round(r * 2.0**32)
    lo = r - Ai * 2.0**-32
    return np.mod(Ai.astype(np.int64), 2**32).astype(np.uint32), lo


def phase_coefficients(smp: Samples, wi, wo, wavelengths_nm, *,
                       frozen_cos_sum: float | None = None) -> PhaseCoefficients:
    """Phase coefficients for every (wavelength, direction) pair, wavelength-major (pair = l · n_dir + d).

    Parameters
    ----------
    smp : Samples
    wi : ndarray (3,)
    wo : ndarray (n_dir, 3)
    wavelengths_nm : ndarray (n_wl,), nm
    frozen_cos_sum : float, optional
        Use cz = frozen_cos_sum / λ for every direction instead of (cos θ_i + cos θ_o) / λ: 2 cos θ_i is the ``fft``
        solver's order-0 approximation, 2 the original Harvey-Shack phase (:mod:`waveoptics.scatter.models`).
    """
    lam = np.asarray(wavelengths_nm, dtype=float)[:, None] * 1e-9
    s = np.asarray(wo)[None, :, :] + np.asarray(wi)[None, None, :]
    ax = s[..., 0] * smp.dx / lam
    ay = s[..., 1] * smp.dy / lam
    cz = (s[..., 2] if frozen_cos_sum is None else np.broadcast_to(float(frozen_cos_sum), s[..., 2].shape)) / lam
    cx, cy = (smp.nx - 1) / 2.0, (smp.ny - 1) / 2.0
    c0 = -(cx * (ax - np.round(ax)) + cy * (ay - np.round(ay)))   # origin at the patch centre
    c0 = c0 - np.round(c0)
    Ax, lox = _fixed_point(ax.ravel())
    Ay, loy = _fixed_point(ay.ravel())
    return PhaseCoefficients(Ax, Ay, lox, loy, cz.ravel(), c0.ravel())


def kirchhoff_phase(ix, iy, h, Ax, Ay, lox, loy, cz, c0) -> np.ndarray:
    """NumPy twin (float64) of the ``kirchhoff_phase`` kernel: phase in cycles reduced to [−½, ½].

    Parameters
    ----------
    ix, iy : ndarray of int, h : ndarray (m)
        Samples (broadcast against the coefficients).
    Ax, Ay : uint32; lox, loy, cz (cycles/m), c0 : float
        Coefficients of :class:`PhaseCoefficients`.
    """
    fixed = (np.asarray(ix, np.int64) * np.int64(Ax) + np.asarray(iy, np.int64) * np.int64(Ay)) % 2**32
    fixed = np.where(fixed >= 2**31, fixed - 2**32, fixed).astype(np.float64)
    p = fixed * 2.0**-32 + (np.asarray(ix) * lox + np.asarray(iy) * loy) + (np.asarray(h) * cz + c0)
    return p - np.round(p)


def kirchhoff_U(smp: Samples, coef: PhaseCoefficients, *, chunk_terms: int = 2**22) -> np.ndarray:
    """NumPy twin (float64) of the ``kirchhoff_U`` kernel: U_p = dx dy Σ_j w_j exp(2πi phase_pj).

    Returns
    -------
    ndarray of complex128 (n_pairs,), m²
    """
    n = coef.size
    out = np.empty(n, np.complex128)
    step = max(1, chunk_terms // max(smp.size, 1))
    ix, iy, h, w = smp.ix[None, :], smp.iy[None, :], smp.h[None, :], smp.w
    for a in range(0, n, step):
        c = coef.take(slice(a, a + step))
        ph = kirchhoff_phase(ix, iy, h, c.Ax[:, None].astype(np.int64), c.Ay[:, None].astype(np.int64),
                             c.lox[:, None], c.loy[:, None], c.cz[:, None], c.c0[:, None])
        out[a:a + step] = np.exp(2j * np.pi * ph) @ w
    return out * (smp.dx * smp.dy)


#: pairs summed by one work-item of ``kirchhoff_U`` (register blocking; measured fastest under PoCL on 2 cores:
#: float32 8 (5.2 G terms/s vs 4.7 for 4 and 5.1 for 16), float64 4 (1.9 vs 1.7 for 8); see docs/performance.md)
PAIRS_PER_ITEM = {"float32": 8, "float64": 4}
#: (sine, cosine) polynomial lengths of the kernels' sin/cos(2πt): sin(fπ/2) = f S(f²), cos(fπ/2) = 1 + f² C'(f²)
SINCOS_TERMS = {"float32": (4, 3), "float64": (7, 7)}


def _precision_name(dtype) -> str:
    return "float64" if np.dtype(dtype) == np.float64 else "float32"


@functools.lru_cache(maxsize=4)
def sincos_poly(precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (S, C) of the kernels' sin/cos polynomials (``kernels/wo_sincos.h``).

    sin(f π/2) ≈ f Σ_n S_n f^{2n} and cos(f π/2) ≈ Σ_n C_n f^{2n} (C_0 = 1) on |f| ≤ ½, fitted by least squares
    on 4000 Chebyshev nodes (relative error for the sine, absolute for the cosine), which is within a few per
    cent of the minimax error (Muller, *Elementary Functions*, 2016, ch. 3). Truncation error: float32 2.6e-9 /
    3.4e-8 (below half an ulp of 1), float64 7.8e-16 / 3.3e-16.

    Returns
    -------
    S, C : ndarray of float64
    """
    n_sin, n_cos = SINCOS_TERMS[precision]
    k = np.arange(4000)
    f = 0.25 + 0.25 * np.cos(np.pi * (k + 0.5) / 4000)       # Chebyshev nodes on (0, 1/2)
    x = f * f
    ys = np.sin(0.5 * np.pi * f) / f
    S = np.linalg.lstsq(np.vander(x, n_sin, increasing=True) / ys[:, None], np.ones_like(ys), rcond=None)[0]
    C = np.linalg.lstsq(np.vander(x, n_cos + 1, increasing=True)[:, 1:], np.cos(0.5 * np.pi * f) - 1.0,
                        rcond=None)[0]
    return S, np.concatenate([[1.0], C])


def sincos_options(precision: str) -> tuple[str, ...]:
    """``-DWO_SIN_C<n>=...`` / ``-DWO_COS_C<n>=...`` build options carrying :func:`sincos_poly`."""
    S, C = sincos_poly(precision)
    suffix = "f" if precision == "float32" else ""
    return (tuple(f"-DWO_SIN_C{n}={c!r}{suffix}" for n, c in enumerate(S.tolist()))
            + tuple(f"-DWO_COS_C{n}={c!r}{suffix}" for n, c in enumerate(C.tolist()) if n > 0))


def sincos_2pi(t, precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """NumPy twin of ``wo_sincos_2pi`` (``kernels/wo_sincos.h``): (sin 2πt, cos 2πt) in *precision*.

    4t = q + f with q = rint(4t) (exact), then the polynomials of :func:`sincos_poly` in f and the quadrant q.

    References
    ----------
    .. [1] W. J. Cody, W. Waite, *Software Manual for the Elementary Functions*, Prentice-Hall, 1980, ch. 8.
    """
    dt = np.float64 if precision == "float64" else np.float32
    S, C = (c.astype(dt) for c in sincos_poly(precision))
    t4 = dt(4) * np.asarray(t, dt)
    qf = np.rint(t4)
    f = t4 - qf
    x = f * f
    sp = f * np.polynomial.polynomial.polyval(x, S).astype(dt)
    cp = np.polynomial.polynomial.polyval(x, C).astype(dt)
    q = qf.astype(np.int64)
    odd = (q & 1) != 0
    s = np.where(odd, cp, sp) * np.where(q & 2, -1, 1)
    c = np.where(odd, sp, cp) * np.where((q + 1) & 2, -1, 1)
    return s.astype(dt), c.astype(dt)


def _cl_setup(runtime, precision, vector_width, smp: Samples, fast_math: bool = False,
              program: str = "kirchhoff.cl"):
    """(runtime, real dtype, program, queue, padded device sample arrays (ix, iy, h, w), padded count)."""


    rt = runtime if runtime is not None else get_runtime()
    dt = rt.real_dtype(precision)
    pname = _precision_name(dt)
    vw = int(vector_width or VECTOR_WIDTH)
    if vw not in (2, 4, 8, 16):
        raise WaveopticsError(f"vector_width={vw!r} is not allowed; use 2, 4, 8 or 16")
    extra = (f"-DWO_VW={vw}", f"-DWO_ND={PAIRS_PER_ITEM[pname]}") + sincos_options(pname)
    if fast_math:
        extra += ("-cl-fast-relaxed-math",)
    prg = build_program(rt, program, build_options(dt, extra))
    q = rt.queue
    pad = (-smp.size) % vw                       # padding samples carry w = 0

    def dev(a, t):
        return cla.to_device(q, np.ascontiguousarray(np.concatenate([a.astype(t), np.zeros(pad, t)])))

    arrays = (dev(smp.ix, np.int32), dev(smp.iy, np.int32), dev(smp.h, dt), dev(smp.w, dt))
    return rt, dt, prg, q, arrays, smp.size + pad


def default_local_size(rt):
    """1 on CPU devices (PoCL then runs the kernels' explicit vectors as written: measured 2x), else the
    driver's choice."""

    return 1 if rt.device.type & cl.device_type.CPU else None


def kirchhoff_phase_cl(smp: Samples, coef: PhaseCoefficients, pair: int = 0, *, runtime=None,
                       precision: str = "float32", vector_width: int | None = None) -> np.ndarray:
    """OpenCL ``kirchhoff_phase``: per-sample phase (cycles) of one pair, in *precision* (twin:
    :func:`kirchhoff_phase`)."""

    rt, dt, prg, q, (d_ix, d_iy, d_h, _), ns = _cl_setup(runtime, precision, vector_width, smp)
    d_out = cla.empty(q, ns, dt)
    vw = int(vector_width or VECTOR_WIDTH)
    cl.Kernel(prg, "kirchhoff_phase")(
        q, (ns // vw,), None, d_ix.data, d_iy.data, d_h.data, np.int32(ns), np.uint32(coef.Ax[pair]),
        np.uint32(coef.Ay[pair]), dt(coef.lox[pair]), dt(coef.loy[pair]), dt(coef.cz[pair]), dt(coef.c0[pair]),
        d_out.data)
    return d_out.get()[: smp.size].astype(np.float64)


def sincos_2pi_cl(t, *, runtime=None, precision: str = "float32") -> tuple[np.ndarray, np.ndarray]:
    """OpenCL ``sincos_2pi`` (the kernels' sin/cos of 2πt; twin: :func:`sincos_2pi`)."""

    t = np.asarray(t, dtype=float).ravel()
    empty = Samples(*(np.zeros(0, np.int32),) * 2, np.zeros(0), np.zeros(0), 1.0, 1.0, 1, 1, 0.0)
    rt, dt, prg, q, _, _ = _cl_setup(runtime, precision, None, empty)
    n = t.size + (-t.size) % VECTOR_WIDTH
    d_t = cla.to_device(q, np.concatenate([t.astype(dt), np.zeros(n - t.size, dt)]))
    s, c = cla.empty(q, n, dt), cla.empty(q, n, dt)
    cl.Kernel(prg, "sincos_2pi")(q, (max(1, n // VECTOR_WIDTH),), None, d_t.data, np.int32(n), s.data, c.data)
    return s.get()[: t.size], c.get()[: t.size]


def launch_pairs(smp: Samples, coef: PhaseCoefficients, *, kernel: str, chunk_args, pairs_per_item: int | None = None,
                 program: str = "kirchhoff.cl", runtime=None, precision: str = "float32",
                 local_size: int | None = None, vector_width: int | None = None, progress=None,
                 fast_math: bool = False) -> np.ndarray:
    """Run a direct-sum kernel with the arguments ``(ix, iy, h, w, n_samples, *chunk_args(...), n_pairs, U_re,
    U_im)`` over every pair, in launches of about :data:`TERMS_PER_LAUNCH` sample-pair terms.

    *chunk_args(queue, dtype, coef_chunk, start, count)* returns the per-pair device arguments of one launch;
    *pairs_per_item* is the pairs each work-item sums (default: :data:`PAIRS_PER_ITEM` of the precision). Used by
    :func:`kirchhoff_U_cl` and by the benchmark's kernel variants (:mod:`waveoptics.bench`).
    """
    rt, dt, prg, q, (d_ix, d_iy, d_h, d_w), ns = _cl_setup(runtime, precision, vector_width, smp, fast_math,
                                                            program)
    knl = cl.Kernel(prg, kernel)
    nd = PAIRS_PER_ITEM[_precision_name(dt)] if pairs_per_item is None else int(pairs_per_item)
    n = coef.size
    out = np.empty(n, np.complex128)
    lsz = default_local_size(rt) if local_size is None else (int(local_size) or None)   # 0: driver's choice
    chunk = max(256, TERMS_PER_LAUNCH // max(ns, 1))
    chunk -= chunk % nd
    for a in range(0, n, chunk):
        c = coef.take(slice(a, a + chunk))
        m = c.size
        args = chunk_args(q, dt, c, a, m)
        re, im = cla.empty(q, m, dt), cla.empty(q, m, dt)
        items = -(-m // nd)
        gsz = items if lsz is None else -(-items // lsz) * lsz
        knl(q, (gsz,), None if lsz is None else (lsz,), d_ix.data, d_iy.data, d_h.data, d_w.data,
            np.int32(ns), *args, np.int32(m), re.data, im.data)
        out[a:a + m] = re.get() + 1j * im.get()
        if progress is not None:
            progress(m)
    return out * (smp.dx * smp.dy)


def exact_phase_args(q, dt, c: PhaseCoefficients, start: int, count: int) -> tuple:
    """Device arguments of the exact-phase kernels for one launch: (Ax, Ay, lox, loy, cz, c0)."""
    dev = [cla.to_device(q, np.ascontiguousarray(x)) for x in
           (c.Ax, c.Ay, c.lox.astype(dt), c.loy.astype(dt), c.cz.astype(dt), c.c0.astype(dt))]
    return tuple(d.data for d in dev)


def kirchhoff_U_cl(smp: Samples, coef: PhaseCoefficients, *, runtime=None, precision: str = "float32",
                   local_size: int | None = None, vector_width: int | None = None, progress=None,
                   fast_math: bool = False) -> np.ndarray:
    """OpenCL direct sum (``kernels/kirchhoff.cl``, kernel ``kirchhoff_U``), twin of :func:`kirchhoff_U`.

    All pairs (every direction × wavelength) go through one program; launches are split into chunks of about
    :data:`TERMS_PER_LAUNCH` sample-pair terms so that *progress* (a callable taking a number of finished
    pairs) can report and no single launch runs for long.

    Parameters
    ----------
    precision : {'float32', 'float64'}
        float64 needs device fp64 support (``rt.fp64``).
    local_size : int, optional
        Work-group size (default: 1 on CPU devices, else the driver's choice; 0: the driver's choice).
    vector_width : int, optional
        Samples per SIMD step of the inner loop (``-DWO_VW``; default :data:`VECTOR_WIDTH`).
    fast_math : bool
        Build with ``-cl-fast-relaxed-math`` (lets the compiler reassociate sums and use faster, less accurate
        math; its effect on speed and error is measured by ``waveoptics bench``). Default off.

    Returns
    -------
    ndarray of complex128 (n_pairs,), m²
    """
    return launch_pairs(smp, coef, kernel="kirchhoff_U", chunk_args=exact_phase_args, runtime=runtime,
                        precision=precision, local_size=local_size, vector_width=vector_width, progress=progress,
                        fast_math=fast_math)
