"""Geometric-optics and two-scale BRDFs.

Files: roughness (α from perceptual roughness and Blinn-Phong exponents), directions (half-vector, mirror direction),
smith (Smith masking; Λ by radial quadrature), anisotropy (stretched NDFs), ndf_closed (GGX, Beckmann, Blinn-Phong),
ndf_shaped (ABC, EPD, SGD), ndf (the NDF registry: D, Λ, G1 by name), shadowing (G terms), fresnel_terms (exact, Schlick or unit F; mean F), diffuse (Lambert, Oren-Nayar, trade-off),
microfacet (the Cook-Torrance specular term and the full BRDF), quadrature (directional albedo), opencl (kernel
twins), twoscale (micro facets carrying nano-roughness: coherent lobe plus diffracted lobe on a direction grid),
sampling (microfacet normal samplers), protocol (the BRDF as a function: eval / pdf / sample / albedo; the
microfacet model), pointwise (the two-scale model as a function), tabulated (the same from diffracted lobes tabulated over
incidence, any nano-roughness), measured_ndf (an NDF tabulated from a height field's slopes), chi2 (goodness-of-fit test of samplers), multiscatter (Kulla-Conty energy compensation), spectral (a BRDF known at wavelength nodes, evaluated at any λ and in RGB), ndf_fit (the α of any NDF that matches a surface's slopes), models (the BRDF models by name, from keyword arguments:
BRDF_MODELS).
"""
from .measured_ndf import *  # noqa: F401,F403
from .roughness import *  # noqa: F401,F403
from .directions import *  # noqa: F401,F403
from .smith import *  # noqa: F401,F403
from .anisotropy import *  # noqa: F401,F403
from .ndf_closed import *  # noqa: F401,F403
from .ndf_shaped import *  # noqa: F401,F403
from .ndf import *  # noqa: F401,F403
from .shadowing import *  # noqa: F401,F403
from .fresnel_terms import *  # noqa: F401,F403
from .diffuse import *  # noqa: F401,F403
from .microfacet import *  # noqa: F401,F403
from .quadrature import *  # noqa: F401,F403
from .opencl import *  # noqa: F401,F403
from .twoscale import *  # noqa: F401,F403
from .sampling import *  # noqa: F401,F403
from .protocol import *  # noqa: F401,F403
from .pointwise import *  # noqa: F401,F403
from .tabulated import *  # noqa: F401,F403
from .spectral import *  # noqa: F401,F403
from .ndf_fit import *  # noqa: F401,F403
from .chi2 import *  # noqa: F401,F403
from .multiscatter import *  # noqa: F401,F403
from .models import *  # noqa: F401,F403
from . import measured_ndf, roughness, directions, smith, anisotropy, ndf_closed, ndf_shaped, ndf, shadowing, fresnel_terms, diffuse, microfacet, quadrature, opencl, twoscale, sampling, protocol, pointwise, tabulated, chi2, multiscatter, spectral, ndf_fit, models  # noqa: F401

__all__ = measured_ndf.__all__ + roughness.__all__ + directions.__all__ + smith.__all__ + anisotropy.__all__ + ndf_closed.__all__ + ndf_shaped.__all__ + ndf.__all__ + shadowing.__all__ + fresnel_terms.__all__ + diffuse.__all__ + microfacet.__all__ + quadrature.__all__ + opencl.__all__ + twoscale.__all__ + sampling.__all__ + protocol.__all__ + pointwise.__all__ + tabulated.__all__ + chi2.__all__ + multiscatter.__all__ + spectral.__all__ + ndf_fit.__all__ + models.__all__
