"""Mitsuba 3: loading it safely, and the ``waveoptics`` BSDF plugin.

:func:`load_mitsuba` imports Mitsuba 3 (the optional extra ``render``) and sets a variant. Its LLVM variants
compile with the system's LLVM; LLVM 15 and 16 (Debian 12's defaults) abort the process on Mitsuba 3.9's kernels
("Cannot select: fmaximum"), so the newest ``libLLVM`` ≥ :data:`LLVM_MIN` found is handed to Dr.Jit through
``DRJIT_LIBLLVM_PATH`` (a user's own setting wins), and an LLVM variant is refused with one line when none exists.

:func:`register` registers the plugin ``waveoptics``: a Python ``mi.BSDF`` whose ``eval``, ``pdf`` and ``sample``
are those of :func:`waveoptics.renderers.renderer_brdf` (the two-scale model of :mod:`waveoptics.brdf`):

* spectral variants: f at the path's wavelengths (linear between nodes), sampled at the hero wavelength (the
  first of the path's wavelengths; :class:`waveoptics.brdf.SpectralNodes`);
* RGB variants: f in linear sRGB (D65 white), sampled from the mixture of all wavelength nodes.

Mitsuba's ``eval`` is f cos θ_o (its convention); its ``si.wi`` is our first direction and its ``wo`` our second.
Plugin parameters, as in a scene file: ``material`` (string), ``alpha``, ``alpha_y`` (float), ``ndf``,
``nano`` (``MODEL:params`` or ``none``), ``surface`` (height-field file), ``diffraction``, ``kd``, ``diffuse``,
``wavelength_step`` (nm), ``resolution``, ``exact`` (bool), ``multiple_scattering`` (bool). The plugin evaluates with NumPy, so in JIT variants it
runs in wavefront mode: :func:`register` turns Dr.Jit's symbolic loops and calls off. This plugin reflects only;
the nano-rough glass, with transmission, is :mod:`waveoptics.renderers.mitsuba_glass` (``waveoptics_glass``).

References
----------
.. [1] W. Jakob, S. Speierer, N. Roussel, M. Nimier-David et al., *Mitsuba 3 renderer*, 2022,
   https://mitsuba-renderer.org (``mi.BSDF``, ``mi.register_bsdf``; the ``chi2`` module used in the tests).
.. [2] W. Jakob et al., "Dr.Jit: A Just-In-Time Compiler for Differentiable Rendering", ACM TOG 41(4), 2022.
"""
from __future__ import annotations

import glob
import os
import re

import numpy as np

from ..errors import WaveopticsError
from .model import DEFAULT_WAVELENGTH_STEP_NM, cached_renderer_brdf

__all__ = ['LLVM_MIN', 'array_converters', 'PLUGIN_NAME', 'INSTALL_HINT', 'llvm_library', 'load_mitsuba', 'register',
           'plugin_parameters', 'plugin_inputs']

#: oldest LLVM whose code generation Mitsuba 3.9's LLVM variants survive
LLVM_MIN = 17
#: name of the BSDF plugin in scene descriptions
PLUGIN_NAME = "waveoptics"
#: how to get Mitsuba 3
INSTALL_HINT = "pip install 'waveoptics[render]' (make setup installs it)"

_LLVM_DIRS = ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib",
              "/usr/local/lib", "/usr/lib/llvm-*/lib", "/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib")


def llvm_library() -> tuple[str | None, int | None]:
    """(path, major version) of the newest ``libLLVM`` shared library on this machine (None, None if none)."""
    best = (None, None)
    for d in _LLVM_DIRS:
        for path in glob.glob(os.path.join(d, "libLLVM*.so*")) + glob.glob(os.path.join(d, "libLLVM*.dylib")):
            m = re.search(r"libLLVM(?:-|\.so\.|\.)(\d+)", os.path.basename(path))
            if m and (best[1] is None or int(m.group(1)) > best[1]):
                best = (path, int(m.group(1)))
    return best


def load_mitsuba(variant: str):
    """Import Mitsuba 3, set *variant* and return the ``mitsuba`` module (see the module doc).

    Raises
    ------
    WaveopticsError
        Mitsuba 3 is not installed, the variant does not exist in this installation, or an LLVM variant has no
        usable LLVM library.
    """
    try:
        import mitsuba as mi
    except ImportError:
        raise WaveopticsError(f"Mitsuba 3 is not installed; install it with {INSTALL_HINT}") from None
    have = list(mi.variants())
    if variant not in have:
        raise WaveopticsError(f"Mitsuba variant {variant!r} is not available; this installation has: "
                              f"{', '.join(have)}")
    if variant.startswith("llvm"):
        if not os.environ.get("DRJIT_LIBLLVM_PATH"):
            path, major = llvm_library()
            if path is None or major < LLVM_MIN:
                found = "none" if path is None else f"LLVM {major}"
                raise WaveopticsError(
                    f"Mitsuba variant {variant!r} needs LLVM >= {LLVM_MIN} (found {found}; Debian: apt-get install "
                    "libllvm19); use a scalar variant (scalar_spectral, scalar_rgb) instead")
            os.environ["DRJIT_LIBLLVM_PATH"] = path
    try:
        mi.set_variant(variant)
    except ImportError as exc:
        raise WaveopticsError(f"Mitsuba variant {variant!r} cannot start: {str(exc).splitlines()[0]}") from None
    return mi


#: plugin parameter → (keyword of renderer_brdf, type)
_PARAMETERS = {
    "material": ("material", str), "alpha": ("alpha", float), "alpha_y": ("alpha_y", float),
    "ndf": ("ndf", str), "nano": ("nano", str), "surface": ("surface", str),
    "diffraction": ("diffraction", str), "kd": ("kd", float), "diffuse": ("diffuse", str),
    "wavelength_step": ("wavelength_step_nm", float), "resolution": ("resolution", int),
    "exact": ("exact", bool), "shadowing": ("shadowing", str),
    "multiple_scattering": ("multiple_scattering", bool),
}


def plugin_parameters() -> tuple:
    """Names of the plugin's parameters."""
    return tuple(_PARAMETERS)


def model_from(items) -> object:
    kw = {}
    for key, value in items:
        if key == "id" or key not in _PARAMETERS:
            if key != "id":
                raise WaveopticsError(f"unknown parameter {key!r} of the {PLUGIN_NAME} BSDF; it takes: "
                                      f"{', '.join(_PARAMETERS)}")
            continue
        name, typ = _PARAMETERS[key]
        kw[name] = typ(value)
    kw.setdefault("wavelength_step_nm", DEFAULT_WAVELENGTH_STEP_NM)
    return cached_renderer_brdf(**dict(sorted(kw.items())))


def _rows(v, width=3) -> np.ndarray:
    """A Dr.Jit vector (scalar or JIT) as a NumPy array (n, width)."""
    a = np.array(v, dtype=float)
    return a.reshape(1, width) if a.ndim == 1 else a.reshape(width, -1).T


def plugin_inputs(si, other, width, spectral: bool, scalar: bool):
    """(wi (n, 3), other (n, width), wavelengths (n, 4) or None) of a Mitsuba interaction, broadcast to a common n
    (a JIT variable of width 1 is a constant)."""
    wi, o = _rows(si.wi), _rows(other, width)
    lam = None
    if spectral:
        lam = np.array(si.wavelengths, dtype=float)
        lam = lam.reshape(1, -1) if scalar else lam.reshape(4, -1).T
    n = max(wi.shape[0], o.shape[0], 1 if lam is None else lam.shape[0])
    wi, o = np.broadcast_to(wi, (n, 3)), np.broadcast_to(o, (n, width))
    return wi, o, None if lam is None else np.broadcast_to(lam, (n, lam.shape[1]))


def _spectral_sample(model, wi, lam, u):
    """(sample, weight f cosθ_o / pdf at each of the 4 wavelengths (n, 4)) of a spectral variant: ω_o drawn at the
    hero wavelength lam[:, 0]."""
    s = model.sample(wi, lam[:, 0], u)
    wo_ok = np.where((s.pdf > 0)[:, None], s.wo, [0.0, 0.0, 1.0])
    f = model.eval(wi[:, None, :], wo_ok[:, None, :], lam)
    weight = np.where((s.pdf > 0)[:, None], f * (wo_ok[:, 2] / np.where(s.pdf > 0, s.pdf, 1.0))[:, None], 0.0)
    return s, weight


def _rgb_sample(model, wi, u):
    """(sample, its RGB weight) of an RGB variant."""
    s = model.sample_rgb(wi, u)
    return s, s.weight


def array_converters(mi):
    """(spectrum, floats, vectors): NumPy rows (n, channels), (n,) and (n, 3) to the Mitsuba types of the variant set
    in *mi* as float32 (a scalar variant takes the first row)."""
    scalar = mi.variant().startswith("scalar")

    def spectrum(values):
        v = np.asarray(values, dtype=np.float32)
        return mi.Spectrum(v[0]) if scalar else mi.Spectrum(np.ascontiguousarray(v.T))

    def floats(values):
        v = np.asarray(values, dtype=np.float32)
        return mi.Float(float(v[0])) if scalar else mi.Float(v)

    def vectors(values):
        v = np.asarray(values, dtype=np.float32)
        return mi.Vector3f(*[float(x) for x in v[0]]) if scalar else mi.Vector3f(np.ascontiguousarray(v.T))

    return spectrum, floats, vectors


def _bsdf_class(mi):
    """The plugin class for the variant set in *mi* (``mi.BSDF`` depends on the variant)."""
    import drjit as dr

    spectral = mi.is_spectral
    scalar = mi.variant().startswith("scalar")
    spectrum, floats, vectors = array_converters(mi)

    class WaveopticsBSDF(mi.BSDF):
        """waveoptics two-scale BRDF (see :mod:`waveoptics.renderers.mitsuba`)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            items = [(k, props[k]) for k in props.keys()]
            self.model = model_from(items)
            self.parameters = dict(items)
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            if self.model.base._has_diffuse():
                flags = flags | mi.BSDFFlags.DiffuseReflection
            self.m_components = [flags]
            self.m_flags = flags

        # -- helpers -------------------------------------------------------------------------------------
        @staticmethod
        def _inputs(si, other, width):
            return plugin_inputs(si, other, width, spectral, scalar)

        def _f(self, wi, wo, lam):
            """f (n, channels) in 1/sr."""
            if spectral:
                return self.model.eval(wi[:, None, :], wo[:, None, :], lam)
            return self.model.eval_rgb(wi, wo)

        def _pdf(self, wi, wo, lam):
            if spectral:
                return self.model.pdf(wi, wo, lam[:, 0])
            return self.model.pdf_rgb(wi, wo)

        @staticmethod
        def _enabled(ctx):
            return ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0)

        # -- mi.BSDF -------------------------------------------------------------------------------------
        def sample(self, ctx, si, sample1, sample2, active=True):
            wi, u, lam = self._inputs(si, sample2, 2)
            u = np.clip(u, 0.0, np.nextafter(1.0, 0.0))
            n = wi.shape[0]
            bs = dr.zeros(mi.BSDFSample3f) if scalar else dr.zeros(mi.BSDFSample3f, n)
            if not self._enabled(ctx):
                return bs, spectrum(np.zeros((n, 4 if spectral else 3)))
            s, weight = _spectral_sample(self.model, wi, lam, u) if spectral else _rgb_sample(self.model, wi, u)
            bs.wo = vectors(s.wo)
            bs.pdf = floats(s.pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, spectrum(weight)

        def eval(self, ctx, si, wo, active=True):
            wi, wo_n, lam = self._inputs(si, wo, 3)
            if not self._enabled(ctx):
                return spectrum(np.zeros((wi.shape[0], 4 if spectral else 3)))
            return spectrum(self._f(wi, wo_n, lam) * np.maximum(wo_n[:, 2], 0.0)[:, None])

        def pdf(self, ctx, si, wo, active=True):
            wi, wo_n, lam = self._inputs(si, wo, 3)
            if not self._enabled(ctx):
                return floats(np.zeros(wi.shape[0]))
            return floats(self._pdf(wi, wo_n, lam))

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"WaveopticsBSDF[{', '.join(f'{k}={v!r}' for k, v in self.parameters.items())}]"

    return WaveopticsBSDF


def register(variant: str | None = None):
    """Register the ``waveoptics`` BSDF with Mitsuba 3 for *variant* (default: the variant already set) and
    return the ``mitsuba`` module. JIT variants switch to wavefront mode (the plugin computes with NumPy)."""
    if variant is not None:
        mi = load_mitsuba(variant)
    else:
        import mitsuba as mi
    import drjit as dr

    if not mi.variant().startswith("scalar"):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    cls = _bsdf_class(mi)
    mi.register_bsdf(PLUGIN_NAME, lambda props: cls(props))
    return mi
