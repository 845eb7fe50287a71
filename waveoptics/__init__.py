"""waveoptics: spectral wave-optics diffraction simulator.

Light scattered by a surface's nanogeometry is computed per wavelength with Kirchhoff (tangent-plane
Huygens-Fresnel) diffraction in OpenCL kernels, combined with a microfacet BRDF for the micro-scale roughness,
and integrated over the spectrum to colour. See the README for a tour and docs/architecture.md for the layout.

Sub-packages (bottom to top): ``materials`` (optical constants, Fresnel), ``colour`` (spectra to colour),
``surfaces`` (height fields, PSDs), ``scatter`` (Kirchhoff diffraction solvers, PSD series), ``brdf`` (microfacet
and two-scale BRDFs), then ``request`` (one simulation request), the jobs ``simulate``, ``compare``, ``study``,
``bench``, ``renderers``, ``scatter_job`` (``waveoptics scatter``'s request and run), ``planning`` (scene files, the effect planner) and ``distributed`` (tables and sweeps on Dask).

The main entry points are attributes of the package, loaded on first use (PEP 562), so that ``import waveoptics``
and the command line's parsers stay quick.

Examples
--------
>>> import waveoptics as wo
>>> req = wo.SimulationRequest("Au", micro_alpha=0.1, wavelengths_nm=(450, 550, 650), resolution=16)
>>> req.params()["wavelengths_nm"]
[450.0, 550.0, 650.0]
"""
import importlib
from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("waveoptics")
except PackageNotFoundError:  # running from a checkout without install
    __version__ = "0.0.0+checkout"

#: entry point -> (module, attribute or None for the module itself)
_ENTRY_POINTS = {
    "SimulationRequest": ("waveoptics.request", "SimulationRequest"),
    "ScatterRequest": ("waveoptics.scatter_job", "ScatterRequest"),
    "HeightField": ("waveoptics.surfaces", "HeightField"),
    "get_material": ("waveoptics.materials", "get_material"),
    "MicrofacetBRDF": ("waveoptics.brdf", "MicrofacetBRDF"),
    "TwoScaleBRDF": ("waveoptics.brdf", "TwoScaleBRDF"),
    "TabulatedTwoScaleBRDF": ("waveoptics.brdf", "TabulatedTwoScaleBRDF"),
    "open_table": ("waveoptics.distributed.table", "open_table"),
    **{name: (f"waveoptics.{name}", None) for name in
       ("simulate", "materials", "colour", "surfaces", "scatter", "brdf", "request", "planning", "distributed")},
}

__all__ = ["__version__", *_ENTRY_POINTS]


def __getattr__(name):
    if name not in _ENTRY_POINTS:
        raise AttributeError(f"module 'waveoptics' has no attribute {name!r}")
    module, attr = _ENTRY_POINTS[name]
    value = importlib.import_module(module)
    return value if attr is None else getattr(value, attr)


def __dir__():
    return sorted(set(globals()) | set(_ENTRY_POINTS))
