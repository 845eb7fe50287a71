"""Names shared by the library and every front end (CLI choices, scene keys, request fields), kept free of heavy
imports so that the command line can build its parsers without loading the numerical library.
"""
from __future__ import annotations

__all__ = ["NANO_SOLVERS", "PRECISIONS", "POLARIZATIONS", "DIFFRACTION", "NDF_NAMES", "SHADOWING_NAMES",
           "FRESNEL_NAMES", "PARAMETRIC_NDF_NAMES", "DIFFUSE_NAMES", "DIFFUSE_ALIASES", "DEFAULT_NANO",
           "DEFAULT_MATERIAL", "DEFAULT_NDF", "COST_TARGET_ERROR", "COST_BUDGET_S", "COST_DELTA_E",
           "RENDER_WAVELENGTH_STEP_NM", "RENDER_BSDFS", "GLINT_SHAPES"]

#: nano-lobe solvers a simulation request may name ('auto' lets the model choose: the PSD series for statistics,
#: else the fft solver on a height field)
NANO_SOLVERS = ("auto", "psd", "fft", "direct")

#: OpenCL precisions of the height-field solvers
PRECISIONS = ("float32", "float64")

#: polarizations of the incident light (the scattered light is not analyzed)
POLARIZATIONS = ("unpolarized", "s", "p")

#: diffraction models of the nano lobe (:data:`waveoptics.scatter.DIFFRACTION_MODELS`); rayleigh-rice is a
#: perturbation model the two-scale model takes, not the Kirchhoff field solvers
DIFFRACTION = ("kirchhoff", "ghs", "rghs", "ohs", "rohs", "rayleigh-rice")

#: microfacet terms by name (the keys of :data:`waveoptics.brdf.NDFS`, ``SHADOWINGS``, ``FRESNELS``, ``DIFFUSES``)
NDF_NAMES = ("ggx", "beckmann", "blinn-phong", "abc", "epd", "sgd", "tabulated")
#: the NDFs a request or scene names by parameters alone (``tabulated`` needs a micro-scale height field)
PARAMETRIC_NDF_NAMES = NDF_NAMES[:-1]
SHADOWING_NAMES = ("smith", "smith-correlated", "cook-torrance", "implicit")
FRESNEL_NAMES = ("exact", "schlick", "one")
DIFFUSE_NAMES = ("none", "lambert", "oren-nayar", "burley")
#: other names of diffuse terms (Burley's diffuse is known as the "Disney" diffuse)
DIFFUSE_ALIASES = {"disney": "burley"}

#: the material of a request, a BRDF or a renderer that names none (one spelling: the preset's own name)
DEFAULT_MATERIAL = "Al"
#: the micro NDF of a request, a scene material or a :class:`waveoptics.brdf.Micro` that names none
DEFAULT_NDF = "beckmann"

#: nano-roughness of a request that names none: aluminium-like polish, ABC statistics (Church et al. 1989)
DEFAULT_NANO = "abc:sigma=10nm,B=2um,C=2.6"

#: defaults of the accuracy-cost study (waveoptics cost): recommend the fastest setting within 1 % relative L2 of
#: the reference, and give the ladder 35 s after the reference (rungs predicted to overrun are skipped and listed)
COST_TARGET_ERROR = 1e-2
COST_BUDGET_S = 35.0
#: the colour accuracies (ΔE2000) whose wavelength grids are rungs of the cost ladder
COST_DELTA_E = (4.0, 1.0, 0.5)

#: renderers (waveoptics.renderers): default largest step (nm) between the wavelength nodes of the BRDF handed to a
#: renderer, and how the wave-optics BRDF enters Mitsuba 3 (its RGL export read by 'measured', or the plugin)
RENDER_WAVELENGTH_STEP_NM = 20.0
RENDER_BSDFS = ("measured", "plugin")
#: what a glint render's height field textures (:data:`waveoptics.renderers.glints.SHAPES`)
GLINT_SHAPES = ("plane", "sphere")
