"""Mitsuba 3: the nano-rough glass as a BSDF with transmission, the plugin ``waveoptics_glass``.

The BSDF is :class:`waveoptics.brdf.NanoRoughDielectricBSDF` (a rough dielectric, Walter et al. 2007, whose
nano-roughness scatters to first order into both half-spaces), or :class:`waveoptics.brdf.RoughDielectricBSDF`
for ``nano`` = ``none``, at wavelength nodes (:class:`waveoptics.brdf.SpectralNodes`: f linear in λ between
nodes; pdf and sampler of the nearest node; in RGB variants f in linear sRGB and the equal mixture of the nodes'
samplers). As the ``waveoptics`` plugin (:mod:`waveoptics.renderers.mitsuba`) it computes with NumPy, so JIT
variants run in wavefront mode. Air (index 1) is on the side of the shading normal, the dielectric behind it.

Conventions (Mitsuba's; Veach 1997 §5.2 for the adjoint). The library's f(ω_i, ω_o) takes ω_i towards the light
and ω_o towards the viewer and carries the factor η_o² of radiance across the interface. Mitsuba's ``si.wi`` points
to the previous vertex of the path and ``wo`` to the next, and ``eval`` returns f |cos θ_o| for the transport mode
of the path:

* ``TransportMode.Importance`` (paths from the lights): si.wi is towards the light, so f_mi(wi, wo) = f(wi, wo);
* ``TransportMode.Radiance`` (paths from the camera): wo is towards the light, so f_mi(wi, wo) = f(wo, wi), which
  for the microfacet and Rayleigh-Rice lobes equals (η_i/η_o)² f(wi, wo) (the reciprocity rule with η²; Mitsuba's
  ``roughdielectric`` applies that factor, "account for the solid angle compression when tracing radiance").
  The coherent factors A(μ_i) of the nano-rough glass depend on the side of the light only, so the adjoint is
  evaluated as f(wo, wi), not by the η² rule.

``sample`` draws wo from the library's sampler with si.wi as its first direction (any density positive where f is
gives an unbiased estimator, Veach 1997 §9.2) and returns weight f_mi |cos θ_o| / pdf; Mitsuba's ``sample1``
makes the choice between reflection and refraction (its digits go to the library's third uniform number,
:func:`waveoptics.brdf.btdf.pack_third_uniform`) and, in RGB variants, first picks the wavelength node.
``BSDFSample3f.eta`` is the relative index η_t/η_i crossed by a transmitted sample (η at the hero wavelength, or at
the node sampled in RGB), 1 for a reflected one. The components are glossy reflection (0) and glossy transmission
(1, non-symmetric), both sides; a context that disables one gets its value, density and samples zeroed on that
side (the samples of the other lobe keep the full density: an unbiased sub-stochastic sampler).

Plugin parameters: ``material`` (a dielectric, default ``glass``), ``alpha``, ``alpha_y``, ``ndf``,
``shadowing`` (``smith`` or ``smith-correlated``), ``nano`` (``MODEL:params`` of PSD statistics or ``none``),
``multiple_scattering`` (bool), ``wavelength_step`` (nm), ``nano_frame`` (``macro``, the nano lobes about the
macro normal, or ``facet``, in each micro facet's frame: :class:`waveoptics.brdf.TwoScaleDielectricBSDF`).

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007.
.. [2] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §5.2
   (non-symmetric scattering by refraction, the adjoint BSDF) and §9.2 (sampling densities).
.. [3] W. Jakob, S. Speierer, N. Roussel, M. Nimier-David et al., *Mitsuba 3 renderer*, 2022,
   https://mitsuba-renderer.org (``mi.BSDF``, ``TransportMode``, ``BSDFSample3f.eta``, the ``roughdielectric``
   plugin).
"""
from __future__ import annotations

import functools

import numpy as np

from .. import brdf
from ..brdf.btdf import pack_third_uniform
from ..brdf.protocol import lobe_choice
from ..errors import FieldError, WaveopticsError
from ..request import psd_statistics
from ..vocabulary import DEFAULT_NANO
from .mitsuba import array_converters, load_mitsuba, plugin_inputs
from .model import DEFAULT_WAVELENGTH_STEP_NM, wavelength_nodes

__all__ = ['GLASS_PLUGIN_NAME', 'glass_model', 'cached_glass_model', 'glass_parameters', 'glass_eval',
           'glass_pdf', 'glass_sample', 'register_glass']

#: name of the glass BSDF plugin in scene descriptions
GLASS_PLUGIN_NAME = "waveoptics_glass"

#: plugin parameter → (keyword of glass_model, type)
_PARAMETERS = {
    "material": ("material", str), "alpha": ("alpha", float), "alpha_y": ("alpha_y", float), "ndf": ("ndf", str),
    "shadowing": ("shadowing", str), "nano": ("nano", str), "multiple_scattering": ("multiple_scattering", bool),
    "wavelength_step": ("wavelength_step_nm", float), "nano_frame": ("nano_frame", str),
}


def glass_parameters() -> tuple:
    """Names of the glass plugin's parameters."""
    return tuple(_PARAMETERS)


def glass_model(material: str = "glass", alpha: float = 0.1, alpha_y: float | None = None, ndf: str = "ggx",
                shadowing: str = "smith-correlated", nano: str | None = None, multiple_scattering: bool = False,
                wavelength_step_nm: float = DEFAULT_WAVELENGTH_STEP_NM, nano_frame: str = "macro"
                ) -> brdf.SpectralNodes:
    """The nano-rough glass of these parameters at the renderer's wavelength nodes (module doc).

    Parameters
    ----------
    material : str
        The dielectric behind the surface (a material name or a real index such as ``1.5``).
    alpha, alpha_y : float
        Micro roughness α of the NDF (dimensionless); *alpha_y* for an anisotropic one.
    ndf, shadowing : str
        Micro NDF and Smith masking (``smith`` or ``smith-correlated``).
    nano : str or None
        Nano-roughness PSD statistics ``MODEL:params`` (e.g. ``abc:sigma=8nm,B=2um,C=2.6``), ``none`` for none;
        None: :data:`waveoptics.vocabulary.DEFAULT_NANO`.
    multiple_scattering : bool
        Kulla-Conty energy compensation of the dielectric.
    wavelength_step_nm : float
        Largest spacing of the wavelength nodes over 360-830 nm.
    nano_frame : str
        Frame of the nano lobes (:data:`waveoptics.vocabulary.NANO_FRAMES`): ``macro`` about the macro normal
        (:class:`waveoptics.brdf.NanoRoughDielectricBSDF`), ``facet`` in each micro facet's frame
        (:class:`waveoptics.brdf.TwoScaleDielectricBSDF`, ~200x slower per evaluation).
    """
    nodes = wavelength_nodes(wavelength_step_nm)
    micro = brdf.Micro(alpha=float(alpha), alpha_y=None if alpha_y is None else float(alpha_y), ndf=ndf,
                       shadowing=shadowing)
    spec = DEFAULT_NANO if nano is None else nano
    psd = None if spec.strip().lower() in ("none", "flat", "0") else psd_statistics(spec, "the nano-rough glass")
    if psd is None:
        if nano_frame != "macro":
            raise FieldError(f"{{nano_frame}} {nano_frame!r} needs {{nano}} statistics (nano-roughness)",
                             "nano_frame", "nano")
        base = brdf.RoughDielectricBSDF(material, micro, multiple_scattering=bool(multiple_scattering))
    else:
        base = brdf.nano_rough_glass(material, micro, psd, multiple_scattering=bool(multiple_scattering),
                                     nano_frame=nano_frame)
    return brdf.SpectralNodes(base, nodes)


@functools.lru_cache(maxsize=16)
def cached_glass_model(**kw) -> brdf.SpectralNodes:
    """:func:`glass_model` remembered per parameter set (Mitsuba's χ² adapter builds its plugin per call)."""
    return glass_model(**kw)


def _model_from(items):
    kw = {}
    for key, value in items:
        if key == "id":
            continue
        if key not in _PARAMETERS:
            raise WaveopticsError(f"unknown parameter {key!r} of the {GLASS_PLUGIN_NAME} BSDF; it takes: "
                                  f"{', '.join(_PARAMETERS)}")
        name, typ = _PARAMETERS[key]
        kw[name] = typ(value)
    return cached_glass_model(**dict(sorted(kw.items())))


def _sides(wi, wo, reflection: bool, transmission: bool):
    """Mask of the pairs whose component is enabled: reflection on one side, transmission across."""
    same = (wi[:, 2] > 0) == (wo[:, 2] > 0)
    return np.where(same, reflection, transmission) & (wi[:, 2] != 0) & (wo[:, 2] != 0)


def glass_eval(model, wi, wo, lam, radiance: bool, reflection: bool = True, transmission: bool = True):
    """Mitsuba's f |cos θ_o| (n, channels) of flat Mitsuba directions *wi*, *wo* (n, 3): at the wavelengths *lam*
    (n, k) in nm, or in linear RGB (n, 3) for *lam* None; *radiance*: the transport mode is Radiance, so the
    library's f is taken with the directions swapped (module doc)."""
    a, b = (wo, wi) if radiance else (wi, wo)
    if lam is None:
        f = model.eval_spectrum(a, b) @ model.rgb_matrix
    else:
        k = lam.shape[1]
        f = model.eval(np.repeat(a, k, axis=0), np.repeat(b, k, axis=0), lam.reshape(-1)).reshape(-1, k)
    keep = _sides(wi, wo, reflection, transmission)
    return np.where(keep[:, None], f * np.abs(wo[:, 2:3]), 0.0)


def glass_pdf(model, wi, wo, lam0, reflection: bool = True, transmission: bool = True):
    """Density (1/sr over wo) of :func:`glass_sample`: the node nearest *lam0* (n,) nm, or the nodes' mixture for
    *lam0* None (RGB)."""
    p = model.pdf_rgb(wi, wo) if lam0 is None else model.pdf(wi, wo, lam0)
    return np.where(_sides(wi, wo, reflection, transmission), p, 0.0)


def _index(model, lam):
    """Real index of the dielectric at wavelengths *lam* (n,) nm."""
    from ..brdf import bulk_medium

    return np.real(np.asarray(bulk_medium(model.base.material).eta(np.asarray(lam, dtype=float)), dtype=complex))


def glass_sample(model, wi, u3, u, lam, radiance: bool, reflection: bool = True, transmission: bool = True):
    """(wo (n, 3), pdf (n,), weight f_mi |cos θ_o| / pdf (n, channels), relative index η_t/η_i (n,)) of flat
    Mitsuba directions *wi* from uniform numbers *u3* (n,) (Mitsuba's ``sample1``) and *u* (n, 2): at the hero
    wavelength lam[:, 0] (nm) with the weight at every column of *lam*, or from the node mixture in RGB (*lam*
    None). Invalid samples have wo = 0, pdf 0 and weight 0."""
    n = wi.shape[0]
    u = np.array(u, dtype=float)
    if lam is None:
        nodes = model.nodes
        idx, u3 = lobe_choice(np.asarray(u3, dtype=float), [np.full(n, 1.0 / nodes.size)] * nodes.size)
        lam_s = nodes[idx]
    else:
        lam_s = lam[:, 0]
    u[:, 1] = pack_third_uniform(u[:, 1], u3)
    wo = model.sample_wo(wi, lam_s, u)
    valid = (np.linalg.norm(wo, axis=-1) > 0.5) & _sides(wi, wo, reflection, transmission)
    wo_ok = np.where(valid[:, None], wo, np.array([0.0, 0.0, 1.0]))
    p = glass_pdf(model, wi, wo_ok, None if lam is None else lam_s, reflection, transmission)
    ok = valid & (p > 0)
    f = glass_eval(model, wi, wo_ok, lam, radiance, reflection, transmission)
    weight = np.where(ok[:, None], f / np.where(ok, p, 1.0)[:, None], 0.0)
    eta = _index(model, lam_s)
    cross = ok & ((wi[:, 2] > 0) != (wo_ok[:, 2] > 0))
    eta_rel = np.where(cross, np.where(wi[:, 2] > 0, eta, 1.0 / eta), 1.0)
    return np.where(ok[:, None], wo, 0.0), np.where(ok, p, 0.0), weight, eta_rel


def _glass_class(mi, fixed_model=None):
    """The plugin class for the variant set in *mi*; *fixed_model* (a SpectralNodes) replaces the parameters."""
    import drjit as dr

    if "mono" in mi.variant() or "polarized" in mi.variant():
        raise WaveopticsError(f"the {GLASS_PLUGIN_NAME} BSDF has no form for Mitsuba variant {mi.variant()!r}; use an "
                              "RGB or spectral variant (scalar_rgb, scalar_spectral, llvm_ad_rgb, llvm_ad_spectral)")
    spectral = mi.is_spectral
    scalar = mi.variant().startswith("scalar")

    spectrum, floats, vectors = array_converters(mi)

    class WaveopticsGlass(mi.BSDF):
        """waveoptics nano-rough glass (see :mod:`waveoptics.renderers.mitsuba_glass`)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            items = [(k, props[k]) for k in props.keys()]
            self.model = fixed_model if fixed_model is not None else _model_from(items)
            self.parameters = dict(items)
            sides = mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide
            self.m_components = [mi.BSDFFlags.GlossyReflection | sides,
                                 mi.BSDFFlags.GlossyTransmission | sides | mi.BSDFFlags.NonSymmetric]
            self.m_flags = self.m_components[0] | self.m_components[1]

        @staticmethod
        def _modes(ctx):
            return (ctx.mode == mi.TransportMode.Radiance, ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0),
                    ctx.is_enabled(mi.BSDFFlags.GlossyTransmission, 1))

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi, u, lam = plugin_inputs(si, sample2, 2, spectral, scalar)
            u3 = np.broadcast_to(np.array(sample1, dtype=float).ravel(), (wi.shape[0],))
            radiance, refl, trans = self._modes(ctx)
            u = np.clip(u, 0.0, np.nextafter(1.0, 0.0))
            wo, pdf, weight, eta = glass_sample(self.model, wi, u3, u, lam, radiance, refl, trans)
            bs = dr.zeros(mi.BSDFSample3f) if scalar else dr.zeros(mi.BSDFSample3f, wi.shape[0])
            bs.wo, bs.pdf, bs.eta = vectors(wo), floats(pdf), floats(eta)
            cross = (wi[:, 2] > 0) != (wo[:, 2] > 0)
            kind = np.where(cross, int(mi.BSDFFlags.GlossyTransmission), int(mi.BSDFFlags.GlossyReflection))
            bs.sampled_type = mi.UInt32(int(kind[0])) if scalar else mi.UInt32(kind.astype(np.uint32))
            comp = cross.astype(np.uint32)
            bs.sampled_component = mi.UInt32(int(comp[0])) if scalar else mi.UInt32(comp)
            return bs, spectrum(weight)

        def eval(self, ctx, si, wo, active=True):
            wi, wo_n, lam = plugin_inputs(si, wo, 3, spectral, scalar)
            return spectrum(glass_eval(self.model, wi, wo_n, lam, *self._modes(ctx)))

        def pdf(self, ctx, si, wo, active=True):
            wi, wo_n, lam = plugin_inputs(si, wo, 3, spectral, scalar)
            _, refl, trans = self._modes(ctx)
            return floats(glass_pdf(self.model, wi, wo_n, None if lam is None else lam[:, 0], refl, trans))

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

        def parameters_changed(self, keys):
            pass

        def to_string(self):
            return f"WaveopticsGlass[{', '.join(f'{k}={v!r}' for k, v in self.parameters.items())}]"

    return WaveopticsGlass


def register_glass(variant: str | None = None, model=None, name: str = GLASS_PLUGIN_NAME):
    """Register the glass BSDF with Mitsuba 3 under *name* for *variant* (default: the variant already set) and
    return the ``mitsuba`` module. *model* (a :class:`waveoptics.brdf.SpectralNodes` of a rough dielectric) is
    used instead of the plugin's parameters when given. JIT variants switch to wavefront mode."""
    if variant is not None:
        mi = load_mitsuba(variant)
    else:
        import mitsuba as mi
    import drjit as dr

    if not mi.variant().startswith("scalar"):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    cls = _glass_class(mi, model)
    mi.register_bsdf(name, lambda props: cls(props))
    return mi
