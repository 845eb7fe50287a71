"""waveoptics: spectral wave-optics diffraction simulator.

Light scattered by a surface's nanogeometry is computed per wavelength with Kirchhoff (tangent-plane
Huygens-Fresnel) diffraction in OpenCL kernels, combined with a microfacet BRDF for the micro-scale roughness,
and integrated over the spectrum to colour. See the README for a tour and docs/architecture.md for the layout.

Sub-packages (bottom to top): ``materials`` (optical constants, Fresnel), ``colour`` (spectra to colour),
``surfaces`` (height fields, PSDs), ``scatter`` (Kirchhoff diffraction solvers, PSD series), ``brdf`` (microfacet
and two-scale BRDFs), then ``request`` (one simulation request), the jobs ``simulate``, ``compare``, ``cost``,
``bench``, ``planning`` (scene files, the effect planner) and ``distributed`` (tables and sweeps on Dask).

Examples
--------
>>> import waveoptics as wo
>>> req = wo.SimulationRequest("Au", micro_alpha=0.1, wavelengths_nm=(450, 550, 650), resolution=16)
>>> req.params()["wavelengths_nm"]
[450.0, 550.0, 650.0]
"""
from importlib.metadata import PackageNotFoundError, version as _version

from . import brdf, colour, materials, scatter, simulate, surfaces
from .materials import get_material
from .request import SimulationRequest
from .surfaces import HeightField

try:
    __version__ = _version("waveoptics")
except PackageNotFoundError:  # running from a checkout without install
    __version__ = "0.0.0+checkout"

__all__ = ["__version__", "SimulationRequest", "HeightField", "get_material", "simulate", "materials", "colour",
           "surfaces", "scatter", "brdf"]
