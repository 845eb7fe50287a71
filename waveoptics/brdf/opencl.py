"""OpenCL twins of the microfacet functions (``kernels/microfacet.h``, ``kernels/microfacet.cl``).
"""
from __future__ import annotations

import numpy as np
import pyopencl.array as cla

from ..errors import WaveopticsError, renamed_keywords, unknown
from ..vocabulary import DEFAULT_NDF
from ..materials import fresnel as _fresnel
from ..runtime import build_options, build_program, get_runtime, program_kernel
from .diffuse import DIFFUSES, diffuse_parameter, sigma_renamed
from .fresnel_terms import F_mean
from .microfacet import FRESNELS, fresnel_fn
from .directions import as_dirs
from .ndf import NDFS, check_alpha, ndf_by_name


def ndf_shape_parameter(spec, ndf_shape) -> float:
    """The shape parameter passed to the kernel: the given one, the NDF's default, or 0 (unused)."""
    if ndf_shape is not None:
        return float(ndf_shape)
    return float(spec.shape_default) if spec.shape_default is not None else 0.0
from .shadowing import shadowing_by_name

__all__ = ['D_cl', 'Lambda_cl', 'brdf_cl', 'ndf_shape_parameter']

# ----------------------------------------------------------------------------------------------------------
# OpenCL twins


def _cl_setup(runtime, precision, defines=()):

    rt = runtime if runtime is not None else get_runtime()
    dt = rt.real_dtype(precision)
    prg = build_program(rt, "microfacet.cl", build_options(dt, tuple(defines)))
    return rt, dt, prg


def _defines(ndf=None, shadowing=None, fresnel=None, diffuse=None, tradeoff=None):
    d = []
    if ndf is not None:
        spec = ndf_by_name(ndf)
        if spec.cl_id is None:
            raise WaveopticsError(f"NDF {ndf!r} has no OpenCL kernel; evaluate it with NumPy (kernel NDFs: "
                                  + ", ".join(k for k, v in NDFS.items() if v.cl_id is not None) + ")")
        d.append(f"-DWO_NDF={spec.cl_id}")
    if shadowing is not None:
        d.append(f"-DWO_SHADOWING={shadowing_by_name(shadowing)[1]}")
    if fresnel is not None:
        if fresnel not in FRESNELS:
            raise unknown("Fresnel model", fresnel, FRESNELS)
        d.append(f"-DWO_FRESNEL={FRESNELS[fresnel][1]}")
    if diffuse is not None:
        if diffuse not in DIFFUSES:
            raise unknown("diffuse model", diffuse, DIFFUSES)
        d.append(f"-DWO_DIFFUSE={DIFFUSES[diffuse][1]}")
    if tradeoff is not None:
        d.append(f"-DWO_TRADEOFF={int(bool(tradeoff))}")
    return d


def _vec_dev(queue, w, dt):

    return cla.to_device(queue, np.ascontiguousarray(np.asarray(w, dtype=dt).reshape(-1, 3)).ravel())


def _ndf_kernel(kname, w, alpha, alpha_y, ndf, ndf_shape, runtime, precision):

    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    w = as_dirs(w, "w")
    rt, dt, prg = _cl_setup(runtime, precision, _defines(ndf=ndf))
    n = w.size // 3
    d_w = _vec_dev(rt.queue, w, dt)
    d_out = cla.empty(rt.queue, max(n, 1), dt)
    program_kernel(prg, kname)(rt.queue, (max(n, 1),), None, d_w.data, d_out.data, dt(ax), dt(ay), dt(ndf_shape_parameter(spec, ndf_shape)),
                        np.int32(n))
    return d_out.get()[:n].reshape(w.shape[:-1]).astype(np.float64)


def D_cl(m, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, ndf_shape=None, runtime=None, precision="float32"):
    """OpenCL twin of :func:`D` (kernel ``D_eval`` in ``kernels/microfacet.cl``)."""
    return _ndf_kernel("D_eval", m, alpha, alpha_y, ndf, ndf_shape, runtime, precision)


def Lambda_cl(w, alpha, alpha_y=None, *, ndf=DEFAULT_NDF, ndf_shape=None, runtime=None, precision="float32"):
    """OpenCL twin of :func:`Lambda` (kernel ``Lambda_eval``); +inf below the surface like the NumPy one."""
    return _ndf_kernel("Lambda_eval", w, alpha, alpha_y, ndf, ndf_shape, runtime, precision)


@renamed_keywords(sigma=sigma_renamed)   # the old keyword held either diffuse roughness
def brdf_cl(wi, wo, *, alpha, alpha_y=None, ndf=DEFAULT_NDF, shadowing="smith-correlated", fresnel="exact", eta=None,
            F0=None, ndf_shape=None, diffuse="lambert", kd=0.0, diffuse_sigma=0.0, diffuse_roughness=0.0,
            tradeoff=True, runtime=None,
            precision="float32"):
    """OpenCL twin of :func:`brdf` for N direction pairs at M wavelengths (kernel ``brdf_eval``).

    Parameters
    ----------
    wi, wo : array_like (N, 3)
        Pairs of unit directions (broadcast to a common N).
    eta, F0, kd : array_like, shape (M,) or scalar
        Per-wavelength complex index, Schlick F0 and diffuse albedo (M = 1 when all are scalars).
    runtime : waveoptics.runtime.Runtime, optional
        Defaults to :func:`waveoptics.runtime.get_runtime`.
    precision : str
        ``"float32"`` or ``"float64"`` (needs device fp64).
    Other parameters
        As in :func:`brdf`; the model switches become ``-D`` build options.

    Returns
    -------
    ndarray (M, N)
        f in 1/sr (float64 copy of the device result).
    """

    if not isinstance(fresnel, str):
        raise WaveopticsError("brdf_cl evaluates the named Fresnel models (exact, schlick, one); a material's own "
                              "reflectance (a thin-film stack) is evaluated with NumPy (brdf)")
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    F_fn = fresnel_fn(fresnel, eta, F0)
    kd_a = np.atleast_1d(np.asarray(kd, dtype=float))
    if np.any(~np.isfinite(kd_a) | (kd_a < 0) | (kd_a > 1)):
        raise WaveopticsError(f"kd={np.asarray(kd).tolist()!r} is not allowed; the diffuse albedo must be in [0, 1]")
    sigma = diffuse_parameter(diffuse, diffuse_sigma, diffuse_roughness)   # the kernel's one diffuse roughness
    wi = as_dirs(wi, "wi").reshape(-1, 3)
    wo = as_dirs(wo, "wo").reshape(-1, 3)
    wi, wo = np.broadcast_arrays(wi, wo)
    n = wi.shape[0]
    eta_a = np.atleast_1d(np.asarray(1.0 if eta is None else eta, dtype=np.complex128))
    F0_a = np.atleast_1d(np.asarray(_fresnel.F0(eta_a) if F0 is None else F0, dtype=float))
    m = max(eta_a.size, F0_a.size, kd_a.size)
    eta_a, F0_a, kd_a = (np.broadcast_to(a.ravel(), (m,)) for a in (eta_a, F0_a, kd_a))
    Fbar = F_mean(F_fn, 1).reshape(-1) if (tradeoff and diffuse != "none") else np.zeros(1)
    Fbar = np.broadcast_to(Fbar, (m,))
    rt, dt, prg = _cl_setup(runtime, precision, _defines(ndf, shadowing, fresnel, diffuse, tradeoff))
    q = rt.queue
    args = [_vec_dev(q, wi, dt), _vec_dev(q, wo, dt)]
    args += [cla.to_device(q, np.ascontiguousarray(a, dtype=dt)) for a in (eta_a.real, eta_a.imag, F0_a, kd_a, Fbar)]
    d_out = cla.empty(q, max(n * m, 1), dt)
    program_kernel(prg, "brdf_eval")(q, (max(n, 1), m), None, *[a.data for a in args], d_out.data, dt(ax), dt(ay), dt(ndf_shape_parameter(spec, ndf_shape)),
                  dt(sigma), np.int32(n))
    return d_out.get()[: n * m].reshape(m, n).astype(np.float64)
