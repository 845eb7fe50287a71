"""waveoptics: spectral wave-optics diffraction simulator.

Light scattered by a surface's nanogeometry is computed per wavelength with Kirchhoff (tangent-plane
Huygens-Fresnel) diffraction in OpenCL kernels, combined with a microfacet BRDF for the micro-scale roughness,
and integrated over the spectrum to colour. See the README for a tour.
"""
from importlib.metadata import PackageNotFoundError, version as _version

try:
    __version__ = _version("waveoptics")
except PackageNotFoundError:  # running from a checkout without install
    __version__ = "0.0.0+checkout"

__all__ = ["__version__"]
