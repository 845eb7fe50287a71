"""Helpers shared by the Mitsuba plugin tests: evaluating a loaded BSDF at given direction pairs."""
import numpy as np


def eval_pdf(mi, plugin, wi, wo, lam, ctx=None):
    """(f cos θ_o (n, channels), pdf (n,)) from the plugin, per point in scalar variants; *ctx* a
    ``mi.BSDFContext`` (default: Radiance, every component)."""
    import drjit as dr

    ctx = mi.BSDFContext() if ctx is None else ctx
    n = wi.shape[0]
    if mi.variant().startswith("scalar"):
        got, pdf = [], []
        for j in range(n):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(*[float(x) for x in wi[j]])
            if mi.is_spectral:
                si.wavelengths = mi.Spectrum(*[float(x) for x in lam[j]])
            w = mi.Vector3f(*[float(x) for x in wo[j]])
            got.append(np.array(plugin.eval(ctx, si, w), dtype=float).ravel())
            pdf.append(float(plugin.pdf(ctx, si, w)))
        return np.array(got), np.array(pdf)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T.astype(np.float32)))
    if mi.is_spectral:
        si.wavelengths = mi.Spectrum(np.ascontiguousarray(lam.T.astype(np.float32)))
    w = mi.Vector3f(np.ascontiguousarray(wo.T.astype(np.float32)))
    got = np.array(plugin.eval(ctx, si, w), dtype=float).reshape(-1, n).T
    return got, np.array(plugin.pdf(ctx, si, w), dtype=float).ravel()


def mueller_matrices(mi, plugin, wi, wo, lam, mode):
    """The plugin's Mueller matrices f cos θ_o (4, 4, 4 wavelengths, n) in an LLVM polarized variant; *mode* a
    ``mi.TransportMode``."""
    import drjit as dr

    n = wi.shape[0]
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T.astype(np.float32)))
    si.wavelengths = mi.UnpolarizedSpectrum(np.ascontiguousarray(lam.T.astype(np.float32)))
    m = plugin.eval(mi.BSDFContext(mode), si, mi.Vector3f(np.ascontiguousarray(wo.T.astype(np.float32))))
    return np.array([[np.array(m[r][c], dtype=float).reshape(4, n) for c in range(4)] for r in range(4)])
