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
  of at most ``wavelength_step_nm``, and :class:`waveoptics.brdf.SpectralNodes` answers at any λ between them;
* the tabulated lobes are kept in the per-user cache (:func:`waveoptics.cache.put_arrays`, kind
  :data:`TABLE_CACHE_KIND`) under a key of every parameter they depend on (the material's index at the nodes, the
  micro NDF, the nano statistics or the height field's bytes, the diffraction model, the nodes, the resolution)
  and the code's version (:func:`waveoptics.cache.code_version`), so a second run with the same model reads them
  instead of computing them (measured on 2 busy cores, ``render --material gold --micro-alpha 0.2``: 82-87 s CPU
  for the command with the lobes computed, 46 s with them read). They are stored as float32, the precision of the
  facet tables they are computed from (:func:`waveoptics.brdf.twoscale.facet_frame_diffraction`), with their rim
  tables (:mod:`waveoptics.brdf.tabulated_rim`) where the model has them. The entry also
  holds the albedo tables of the coherent fraction A(θ_d) at each wavelength node (:func:`albedo_tables`, float64
  as computed), so a model read from it builds no band-limited series (their tables are built on first use):
  the default ``waveoptics export`` read from the cache took 24 s CPU with the series rebuilt, 7 s without
  (issue 31).
"""
from __future__ import annotations

import functools

import numpy as np

from .. import brdf
from ..errors import FieldError, WaveopticsError
from ..request import make_nano
from ..vocabulary import RENDER_WAVELENGTH_STEP_NM
from .requests import RendererModel as _M

__all__ = ['SPECTRAL_RANGE_NM', 'DEFAULT_WAVELENGTH_STEP_NM', 'TABLE_CACHE_KIND', 'MODEL_RESOLUTION_RANGE',
           'MODEL_INTERPOLATION_ERROR', 'wavelength_nodes', 'model_resolution', 'renderer_brdf',
           'cached_renderer_brdf', 'table_key', 'albedo_tables', 'set_albedo_tables']

#: wavelengths (nm) a spectral renderer may ask for: Mitsuba 3 samples 360–830 nm
SPECTRAL_RANGE_NM = (360.0, 830.0)
#: default largest step (nm) between wavelength nodes
DEFAULT_WAVELENGTH_STEP_NM = RENDER_WAVELENGTH_STEP_NM
#: kind of the per-user cache entries holding tabulated lobes (:mod:`waveoptics.cache`)
TABLE_CACHE_KIND = "renderer-tables"

#: smallest and largest direction-grid resolution (cells per axis) :func:`model_resolution` chooses
MODEL_RESOLUTION_RANGE = (64, 128)
#: largest relative error of the tabulated lobes' interpolation between cells that :func:`model_resolution` aims
#: at, where the nano lobe is above 1e-3 of its peak: du² κ / 4 (:meth:`waveoptics.surfaces.PSDModel.lobe_curvature`
#: κ; twice linear interpolation's du² κ / 8, for the model reads the lobe bilinearly from cells that were summed
#: from bilinear reads of the facets' tables on the same grid). Measured against finer grids (Au, α 0.1, seeded
#: pairs to 85°; max |f/f_ref − 1| of the diffracted part where it is above 1e-3 of its largest value): ABC σ 10 nm,
#: B 2 µm, C 2.6 (κ 80 at 360 nm, 64² predicted 2.0 %): 1.26 % at 360 nm against 128² (tests/test_model_resolution.py),
#: 0.73 % at 438-710 nm against 256² (0.30 % on 96², 0.15 % on 128²; α 0.2 and 0.4: 0.78 % and 0.58 % on 64²);
#: Gaussian σ 10 nm, T 0.5 µm (κ 488, its flanks: it takes 128², the upper end): 5.5 % on 64² at 360 nm
#: against 128², 2.3 % on 96² against 256²
MODEL_INTERPOLATION_ERROR = 0.02


def model_resolution(nano) -> int:
    """Direction-grid cells per axis of a renderer model's tabulated lobes: the fewest (a multiple of 16 within
    :data:`MODEL_RESOLUTION_RANGE`) with du² κ / 4 at most :data:`MODEL_INTERPOLATION_ERROR`, κ the nano lobe's
    :meth:`waveoptics.surfaces.PSDModel.lobe_curvature` at the shortest wavelength node. A height field's lobe (no
    statistics to size it by) and lobes too sharp for the range take its upper end, the former fixed default."""
    lo, hi = MODEL_RESOLUTION_RANGE
    if nano is None or nano.model is None:
        return hi
    kappa = nano.model.lobe_curvature(min(SPECTRAL_RANGE_NM))
    if not kappa > 0:   # a flat lobe (σ = 0): nothing to resolve
        return lo
    need = 2.0 / np.sqrt(4.0 * MODEL_INTERPOLATION_ERROR / kappa)
    return int(np.clip(16 * np.ceil(need / 16.0), lo, hi))


def wavelength_nodes(step_nm: float = DEFAULT_WAVELENGTH_STEP_NM, span_nm=SPECTRAL_RANGE_NM) -> tuple:
    """Evenly spaced nodes (nm) over *span_nm*, both ends included, no further apart than *step_nm*."""
    lo, hi = (float(x) for x in span_nm)
    if not (np.isfinite(step_nm) and step_nm > 0):
        raise FieldError(f"wavelength_step={step_nm!r} nm is not allowed; it must be a positive length",
                         "wavelength_step")
    n = max(int(np.ceil((hi - lo) / float(step_nm) - 1e-9)), 1) + 1
    return tuple(float(x) for x in np.linspace(lo, hi, n))


def renderer_brdf(material: str = _M.material, alpha: float = _M.alpha, alpha_y: float | None = _M.alpha_y,
                  ndf: str = _M.ndf, nano: str | None = _M.nano, surface=_M.surface,
                  diffraction: str = _M.diffraction, kd: float = _M.kd, diffuse: str = _M.diffuse,
                  wavelength_step_nm: float = DEFAULT_WAVELENGTH_STEP_NM, resolution: int | None = _M.resolution,
                  exact: bool = _M.exact, shadowing: str = "smith-correlated",
                  multiple_scattering: bool = _M.multiple_scattering, cache: bool = True) -> brdf.SpectralNodes:
    """The two-scale BRDF of these parameters at the renderer's wavelength nodes (see the module doc); the
    defaults are those of :class:`waveoptics.renderers.requests.RendererModel`.

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
    resolution : int or None
        Direction-grid cells per axis of the tabulated diffracted lobes; None: :func:`model_resolution` of the nano
        lobe.
    exact : bool
        Pointwise quadrature instead of tabulated lobes (PSD statistics only; slow).
    multiple_scattering : bool
        Add the Kulla-Conty compensation lobe of the micro NDF (:mod:`waveoptics.brdf.multiscatter`).
    cache : bool
        Read the tabulated lobes from the per-user cache when they are there, and store them when computed (see
        the module doc).
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
        base = _tabulated(nano_obj, nodes, model_resolution(nano_obj) if resolution is None else int(resolution),
                          common, cache)
    return brdf.SpectralNodes(base, nodes)


def _tabulated(nano_obj, nodes, resolution: int, common: dict, cache: bool):
    """:class:`waveoptics.brdf.TabulatedTwoScaleBRDF` of these parameters, its lobes read from or written to the
    per-user cache (*cache*)."""
    from .. import cache as store
    from ..scatter.grid import DirectionGrid

    kw = dict(nano=nano_obj, wavelengths_nm=nodes, resolution=resolution, solver="auto", **common)
    digest = store.key_digest(table_key(nano_obj, nodes, resolution, common)) if cache else None
    hit = store.get_arrays(TABLE_CACHE_KIND, digest) if digest else None
    if hit is not None and {"lobes", "phis_deg"} <= set(hit):
        set_albedo_tables(nano_obj, hit)
        return brdf.TabulatedTwoScaleBRDF(table_lobes=hit["lobes"].astype(float),
                                          table_grid=DirectionGrid.hemisphere(resolution),
                                          table_phis_deg=tuple(float(x) for x in hit["phis_deg"]),
                                          table_rim=hit["rim"].astype(float) if "rim" in hit else None, **kw)
    base = brdf.TabulatedTwoScaleBRDF(**kw)
    if digest and nano_obj.sigma > 0:
        rim = {} if base.rim_table is None else {"rim": base.rim_table.astype(np.float32)}
        store.put_arrays(TABLE_CACHE_KIND, digest, {"lobes": base.table.astype(np.float32),
                                                    "phis_deg": np.degrees(base._table["phis"]), **rim,
                                                    **albedo_tables(nano_obj, nodes)})
    return base


def albedo_tables(nano_obj, nodes) -> dict:
    """The albedo tables of the band series of *nano_obj*'s statistics at the wavelength *nodes* (nm) computed so
    far (:meth:`waveoptics.scatter.BandSeries.albedo_tables`: the coherent fraction A(θ_d) the model evaluates
    per pair comes from them), as arrays for the cache entry: ``albedo_meta`` (JSON [λ, key] per table) and
    ``albedoN`` (3, n_θ) each (nodes, raw, continued). None for a height field."""
    import json

    from .. import scatter

    if nano_obj.model is None:
        return {}
    meta, out = [], {}
    for lam in nodes:
        for key, tab in scatter.band_series(nano_obj.model, float(lam)).albedo_tables().items():
            out[f"albedo{len(meta)}"] = np.stack([np.asarray(t, dtype=float) for t in tab])
            meta.append(json.dumps([float(lam), list(key)]))
    return dict(out, albedo_meta=np.array(meta, dtype=str)) if meta else {}


def set_albedo_tables(nano_obj, hit: dict) -> None:
    """Give the band series of *nano_obj* the albedo tables of a cache entry (:func:`albedo_tables`), so that the
    model read from the cache does not compute them (nor the series' own tables they come from: 8-13 s CPU for
    the 25 wavelength nodes of the default model)."""
    import json

    from .. import scatter

    if nano_obj.model is None or "albedo_meta" not in hit:
        return
    for i, text in enumerate(hit["albedo_meta"]):
        lam, key = json.loads(str(text))
        scatter.band_series(nano_obj.model, float(lam)).add_albedo_tables({tuple(key): tuple(hit[f"albedo{i}"])})


def table_key(nano_obj, nodes, resolution: int, common: dict) -> dict:
    """Every parameter the tabulated lobes of :func:`renderer_brdf` depend on, as plain data: the material's name
    and its complex index at the wavelength nodes (its data may change; F at three angles for an F0 material), the micro NDF, the nano statistics
    or a SHA-256 of the height field's heights, spacing and mask, the diffraction model, the nodes and the grid's
    resolution (with :data:`waveoptics.brdf.tabulated.THETA_NODES_DEG`, the incidences tabulated, the rim
    tables' layout, :mod:`waveoptics.brdf.tabulated_rim`, and an anisotropic table's light azimuths)."""
    import hashlib

    from ..brdf.tabulated import PHI_NODES_ANISOTROPIC, PHI_NODES_ANISOTROPIC_NDF, THETA_NODES_DEG
    from ..brdf.tabulated_rim import RIM_BLEND_DEG, RIM_CELLS, RIM_LIGHT_AZIMUTHS, RIM_THETA_DEG
    from ..materials import get_material

    mat = get_material(common["material"])
    w = np.asarray(nodes, dtype=float)
    try:
        optics = [[float(e.real), float(e.imag)] for e in np.asarray(mat.eta(w), dtype=complex)]
    except WaveopticsError:   # a material given by F0 only: its reflectance curve at each node
        optics = np.asarray(mat.F(np.array([1.0, 0.5, 0.1])[:, None], w[None, :]), dtype=float).tolist()
    if nano_obj.model is not None:
        nano = {"model": repr(nano_obj.model)}
    else:
        hf = nano_obj.surface
        h = hashlib.sha256(np.ascontiguousarray(hf.heights, dtype=float).tobytes())
        h.update(repr((float(hf.dx), None if hf.dy is None else float(hf.dy))).encode())
        if hf.mask is not None:
            h.update(np.ascontiguousarray(hf.mask, dtype=bool).tobytes())
        nano = {"height_field": h.hexdigest()}
    micro = common["micro"]
    key = {"material": str(common["material"]), "optics": optics, "micro": repr(micro), "nano": nano,
           "diffraction": str(common["diffraction"]), "wavelengths_nm": [float(x) for x in nodes],
           "resolution": int(resolution), "thetas_deg": [float(t) for t in THETA_NODES_DEG],
           "rim": [RIM_THETA_DEG, list(RIM_BLEND_DEG), list(RIM_CELLS), RIM_LIGHT_AZIMUTHS,
                   "log-monotone in phi_i"]}
    if micro.alpha_y is not None:   # the light azimuths an anisotropic table holds
        key["phis"] = [PHI_NODES_ANISOTROPIC, PHI_NODES_ANISOTROPIC_NDF, "half-vector read"]
    return key


@functools.lru_cache(maxsize=16)
def cached_renderer_brdf(**kw) -> brdf.SpectralNodes:
    """:func:`renderer_brdf` remembered per parameter set (hashable values only: a surface by its file name), so
    that a renderer that builds its plugin many times (Mitsuba's χ² adapter does per call) builds the model
    once."""
    return renderer_brdf(**kw)
