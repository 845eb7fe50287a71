"""The BRDF a renderer receives: the two-scale model of one material, built once per parameter set, at wavelength
nodes that cover a spectral renderer's range.

:func:`renderer_brdf` is shared by the Mitsuba 3 plugin (:mod:`waveoptics.renderers.mitsuba`), the RGL export
(:mod:`waveoptics.renderers.rgl`) and ``waveoptics render``, so the three show one model.

* nano-roughness given as PSD statistics (``MODEL:params``) or as a height-field file; ``none`` gives the
  microfacet model (the two-scale model without nano-roughness is it exactly);
* the diffracted part is tabulated over incidence on a direction grid (:class:`waveoptics.brdf.
  TabulatedTwoScaleBRDF`, ~1 µs per evaluation) unless ``exact`` asks for the pointwise quadrature
  (:class:`waveoptics.brdf.TwoScaleBRDF`, ~200 µs per evaluation, PSD statistics only);
* the wavelength nodes span :data:`SPECTRAL_RANGE_NM` (the range Mitsuba 3's spectral variants sample) in steps
  of at most ``wavelength_step_nm``, and :class:`waveoptics.brdf.SpectralNodes` answers at any λ between them.
"""
from __future__ import annotations

import functools

import numpy as np

from .. import brdf
from ..errors import FieldError
from ..request import make_nano
from ..vocabulary import RENDER_WAVELENGTH_STEP_NM

__all__ = ['SPECTRAL_RANGE_NM', 'DEFAULT_WAVELENGTH_STEP_NM', 'wavelength_nodes', 'renderer_brdf',
           'cached_renderer_brdf']

#: wavelengths (nm) a spectral renderer may ask for: Mitsuba 3 samples 360–830 nm
SPECTRAL_RANGE_NM = (360.0, 830.0)
#: default largest step (nm) between wavelength nodes
DEFAULT_WAVELENGTH_STEP_NM = RENDER_WAVELENGTH_STEP_NM


def wavelength_nodes(step_nm: float = DEFAULT_WAVELENGTH_STEP_NM, span_nm=SPECTRAL_RANGE_NM) -> tuple:
    """Evenly spaced nodes (nm) over *span_nm*, both ends included, no further apart than *step_nm*."""
    lo, hi = (float(x) for x in span_nm)
    if not (np.isfinite(step_nm) and step_nm > 0):
        raise FieldError(f"wavelength_step={step_nm!r} nm is not allowed; it must be a positive length",
                         "wavelength_step")
    n = max(int(np.ceil((hi - lo) / float(step_nm) - 1e-9)), 1) + 1
    return tuple(float(x) for x in np.linspace(lo, hi, n))


def renderer_brdf(material: str = "aluminium", alpha: float = 0.1, alpha_y: float | None = None,
                  ndf: str = "ggx", nano: str | None = None, surface=None,
                  diffraction: str = "kirchhoff", kd: float = 0.0, diffuse: str = "lambert",
                  wavelength_step_nm: float = DEFAULT_WAVELENGTH_STEP_NM, resolution: int = 128,
                  exact: bool = False, shadowing: str = "smith-correlated",
                  multiple_scattering: bool = False) -> brdf.SpectralNodes:
    """The two-scale BRDF of these parameters at the renderer's wavelength nodes (see the module doc).

    Parameters
    ----------
    material : str
        Material name (``waveoptics materials``) or a constant complex index ``n+kj``.
    alpha, alpha_y : float
        Micro-scale roughness (GGX/Beckmann α, dimensionless); *alpha_y* for an anisotropic surface.
    ndf : str
        Micro NDF (:data:`waveoptics.brdf.NDFS`).
    nano : str or None
        Nano-roughness ``MODEL:params`` (e.g. ``abc:sigma=10nm,B=2um,C=2.6``), or ``none`` for none; None means
        the default of :data:`waveoptics.vocabulary.DEFAULT_NANO` unless *surface* is given.
    surface : HeightField, str, Path or None
        Nano height field, or its file (any format ``waveoptics surface stats`` reads, with its spacing inside).
    diffraction : str
        Diffraction model (:data:`waveoptics.scatter.DIFFRACTION_MODELS`).
    kd, diffuse
        Diffuse albedo and model of a dielectric's substrate.
    wavelength_step_nm : float
        Largest spacing of the wavelength nodes (nm).
    resolution : int
        Direction-grid cells per axis of the tabulated diffracted lobes.
    exact : bool
        Pointwise quadrature instead of tabulated lobes (PSD statistics only; slow).
    multiple_scattering : bool
        Add the Kulla-Conty compensation lobe of the micro NDF (:mod:`waveoptics.brdf.multiscatter`).
    """
    from ..vocabulary import DEFAULT_NANO

    nodes = wavelength_nodes(wavelength_step_nm)
    if nano is not None and surface is not None:
        raise FieldError("give only one of nano (statistics) and surface (a height-field file)", "nano")
    micro = brdf.Micro(alpha=float(alpha), alpha_y=None if alpha_y is None else float(alpha_y), ndf=ndf,
                       shadowing=shadowing)
    common = dict(material=material, micro=micro, kd=float(kd), diffuse=diffuse, diffraction=diffraction,
                  multiple_scattering=bool(multiple_scattering))
    if surface is not None:
        nano_obj = make_nano(None, nodes, surface=surface)
    else:
        spec = DEFAULT_NANO if nano is None else nano
        nano_obj = None if spec.strip().lower() in ("none", "flat", "0") else make_nano(spec, nodes)
    if nano_obj is None:
        base = brdf.TwoScaleBRDF(nano=None, **common)
    elif exact:
        if nano_obj.model is None:
            raise FieldError("exact evaluation needs nano statistics (MODEL:params), not a height field", "exact")
        base = brdf.TwoScaleBRDF(nano=nano_obj, **common)
    else:
        base = brdf.TabulatedTwoScaleBRDF(nano=nano_obj, wavelengths_nm=nodes, resolution=int(resolution),
                                          solver="auto", **common)
    return brdf.SpectralNodes(base, nodes)


@functools.lru_cache(maxsize=16)
def cached_renderer_brdf(**kw) -> brdf.SpectralNodes:
    """:func:`renderer_brdf` remembered per parameter set (hashable values only: a surface by its file name), so
    that a renderer that builds its plugin many times (Mitsuba's χ² adapter does per call) builds the model
    once."""
    return renderer_brdf(**kw)
