"""Names shared by the library and every front end (CLI choices, scene keys, request fields), kept free of heavy
imports so that the command line can build its parsers without loading the numerical library.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["NANO_FRAMES", "DEFAULT_NANO_FRAME", "NANO_SOLVERS", "PRECISIONS", "POLARIZATIONS", "DIFFRACTION", "NDF_NAMES", "SHADOWING_NAMES",
           "FRESNEL_NAMES", "PARAMETRIC_NDF_NAMES", "DIFFUSE_NAMES", "DIFFUSE_ALIASES", "DEFAULT_NANO",
           "DEFAULT_MATERIAL", "DEFAULT_NDF", "COST_TARGET_ERROR", "COST_BUDGET_S", "COST_DELTA_E",
           "RENDER_WAVELENGTH_STEP_NM", "RENDER_BSDFS", "RENDER_BSDF_AUTO", "RENDER_MODELS", "GLINT_SHAPES", "ROUGHNESS_CORRELATIONS",
           "FIELD_SOLVERS", "FIELD_BACKENDS", "DETRENDS"]

#: nano-lobe solvers a simulation request may name ('auto' lets the model choose: the PSD series for statistics,
#: else the fft solver on a height field)
NANO_SOLVERS = ("auto", "psd", "fft", "direct")

#: OpenCL precisions of the height-field solvers
PRECISIONS = ("float32", "float64")

#: the Kirchhoff solvers of a height field (the keys of :data:`waveoptics.scatter.SOLVERS`), and where the direct
#: sum runs (:data:`waveoptics.scatter.BACKENDS`)
FIELD_SOLVERS = ("fft", "direct")
FIELD_BACKENDS = ("opencl", "numpy")

#: what is removed from a height field's heights first (:data:`waveoptics.surfaces.DETRENDS`)
DETRENDS = ("mean", "plane", "none")

#: polarizations of the incident light (the scattered light is not analyzed)
POLARIZATIONS = ("unpolarized", "s", "p")

#: named correlations of a thin-film stack's interface roughness (a coefficient in [0, 1] is also taken):
#: profiles replicated through the films, or independent (Elson, Rahn & Bennett 1983)
ROUGHNESS_CORRELATIONS = ("correlated", "uncorrelated")

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
#: frames of the nano lobes of a nano-rough glass: ``macro`` about the macro normal (the α → 0 form,
#: :class:`waveoptics.brdf.NanoRoughDielectricBSDF`), ``facet`` in each micro facet's own frame (the two-scale glass,
#: :class:`waveoptics.brdf.TwoScaleDielectricBSDF`)
NANO_FRAMES = ("macro", "facet")
#: the frame of the nano lobes of the nano-rough glass when none is given
DEFAULT_NANO_FRAME = NANO_FRAMES[0]
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
#: renderer, and how the wave-optics BRDF enters Mitsuba 3 (its RGL export read by 'measured', the NumPy plugin, or
#: the Dr.Jit plugin 'native'); RENDER_BSDF_AUTO lets the render job choose (waveoptics.renderers.jobs.choose_bsdf)
RENDER_WAVELENGTH_STEP_NM = 20.0
RENDER_BSDFS = ("measured", "plugin", "native")
RENDER_BSDF_AUTO = "auto"
#: the surface models ``waveoptics render`` renders (waveoptics.renderers.jobs.RENDER_MODEL_KINDS): the two-scale
#: BRDF, and the rough dielectric (nano-rough glass, reflection and transmission; waveoptics.renderers.glass_render)
RENDER_MODELS = ("twoscale", "rough-dielectric")
#: what a glint render's height field textures (:data:`waveoptics.renderers.glints.SHAPES`)
GLINT_SHAPES = ("plane", "sphere")


# ----------------------------------------------------------------------------------------------------------------
# BRDF models by name (the factories of :data:`waveoptics.brdf.BRDF_MODELS`, what ``waveoptics brdf --model`` runs):
# each model's parameters with their unit, default and meaning, here so that a front end builds its options from
# them without loading the numerical library (a test holds them to the factories' signatures)

__all__ += ["ModelParameter", "REQUIRED", "BRDF_MODEL_HELP", "BRDF_MODEL_PARAMETERS"]


@dataclass(frozen=True)
class ModelParameter:
    """A keyword argument of a BRDF model factory: its *name*, *unit* ("1" dimensionless, "" for names and
    objects), *default* (:data:`REQUIRED` when it has none) and *meaning*."""

    name: str
    unit: str
    default: object
    meaning: str


#: the default of a parameter that must be given
REQUIRED = "required"

_ALPHA = (ModelParameter("alpha", "1", None, "the NDF's slope scale α (α_x if anisotropic), in [0, 2]; or roughness"),
          ModelParameter("roughness", "1", None, "perceptual roughness r, α = r² (instead of alpha)"),
          ModelParameter("alpha_y", "1", None, "α_y of an anisotropic NDF (ggx, beckmann, epd, sgd)"),
          ModelParameter("ndf", "", DEFAULT_NDF, "microfacet normal distribution (NDF_NAMES)"),
          ModelParameter("ndf_shape", "1", None, "shape parameter of abc (C), epd and sgd (p); None: its default"))
_SLOPES = ModelParameter("slope_table", "", None, "the NDF of a micro height field's slopes (a SlopeTable); "
                                                  "replaces alpha, roughness, ndf and ndf_shape")
_SHADOWING = ModelParameter("shadowing", "", "smith-correlated", "masking-shadowing term (SHADOWING_NAMES)")
_INDEX = (ModelParameter("material", "", None, "the substrate: a material name (or ior)"),
          ModelParameter("ior", "1", None, "the substrate as a constant complex index 'N+Kj' (or material)"),
          ModelParameter("fresnel", "", "exact", "Fresnel factor: exact, schlick or one (F = 1, white furnace)"))
_DIFFUSE = (ModelParameter("diffuse", "", "lambert", "diffuse model (DIFFUSE_NAMES)"),
            ModelParameter("kd", "1", 0.0, "diffuse albedo"),
            ModelParameter("diffuse_sigma_deg", "deg", 0.0, "Oren-Nayar roughness σ, in [0, 90]"))
_MS = ModelParameter("multiple_scattering", "", False, "add the Kulla-Conty multiple-scattering compensation")
_KERNEL = (ModelParameter("backend", "", "numpy", "numpy or opencl (the evaluation; the albedo uses NumPy)"),
           ModelParameter("precision", "", "float32", "OpenCL floating-point precision (PRECISIONS)"))
_DEVICE = ModelParameter("device", "", None, "OpenCL device (None: the default)")
_DIFFRACTION = ModelParameter("diffraction", "", "kirchhoff", "diffraction model of the nano lobe (DIFFRACTION)")
_CORRELATION = ModelParameter("roughness_correlation", "", ROUGHNESS_CORRELATIONS[0],
                              "of a thin-film stack's interface roughness under rayleigh-rice: correlated, "
                              "uncorrelated or a coefficient in [0, 1] (ROUGHNESS_CORRELATIONS)")
_POLARIZATION = ModelParameter("polarization", "", "unpolarized", "polarization of the incident light "
                                                                  "(POLARIZATIONS)")

#: one-line description of each BRDF model
BRDF_MODEL_HELP = {
    "microfacet": "geometric-optics microfacet BRDF (Cook-Torrance / Walter et al. 2007) with a diffuse term",
    "kirchhoff": "wave-optics Kirchhoff BRDF of a height-field file (waveoptics.scatter)",
    "rayleigh-rice": "first-order Rayleigh-Rice BRDF of a smooth rough surface from its PSD, with the "
                     "polarization factor Q (s, p, unpolarized; JSON also gives ss, sp, ps, pp); over a "
                     "transparent material (glass, a stack on glass) also into it (--outgoing θ > 90°), light "
                     "from inside it (--incident θ > 90°), and --albedo gives R and T",
    "twoscale": "two-scale BRDF: micro NDF carrying PSD nano-roughness (Holzschuch & Pacanowski 2017), evaluated "
                "at the given directions; JSON also gives its coherent, diffraction and diffuse parts",
    "rough-dielectric": "BSDF of a rough dielectric interface (Walter et al. 2007): reflection and transmission "
                        "(air above, the material below; --outgoing θ > 90° is transmitted, --incident θ > 90° "
                        "lights it from inside; --albedo gives R and T); JSON also gives its reflection, "
                        "transmission and multiple parts",
    "table": "a BRDF table file (waveoptics table) as a function: its diffracted lobes interpolated between "
             "incidences relative to the specular direction, coherent and diffuse parts exact; a glass table "
             "(table --transmission) as a BSDF over the sphere (θ > 90: transmitted, or light from inside; "
             "--albedo gives R and T); at the table's wavelengths",
}

#: the parameters of each BRDF model factory besides ``wavelengths_nm`` (nm), in the factory's order
BRDF_MODEL_PARAMETERS = {
    "microfacet": (*_ALPHA[:3], _ALPHA[3], _ALPHA[4], _SLOPES, _SHADOWING, *_INDEX, *_DIFFUSE,
                   ModelParameter("diffuse_roughness", "1", 0.5, "Burley diffuse roughness r, in [0, 1]"),
                   ModelParameter("tradeoff", "", True, "weight the diffuse term by (1 - F(θi))(1 - F(θo)) / "
                                                        "(1 - F̄)"),
                   _MS, *_KERNEL, _DEVICE),
    "kirchhoff": (ModelParameter("surface", "m", REQUIRED, "the height field (heights and spacing in m)"), *_INDEX,
                  ModelParameter("solver", "", "direct", "direct Kirchhoff sum or fft on a hemisphere grid"),
                  *_KERNEL, ModelParameter("window", "", "hann", "taper over the patch (a scipy window name)"),
                  ModelParameter("resolution", "", None, "cells per side of the fft grid and of the albedo "
                                                         "quadrature (None: resolves the specular spike; 256)"),
                  ModelParameter("realizations", "", 1, "tiles of the height field averaged"),
                  _DIFFRACTION, _POLARIZATION, _DEVICE),
    "rayleigh-rice": (ModelParameter("psd", "m", REQUIRED, "the surface's power spectral density (a PSD model or "
                                                           "a height field's periodogram; heights in m)"),
                      *_INDEX[:2], _POLARIZATION,
                      ModelParameter("resolution", "", None, "cells per side of the albedo quadrature (None: "
                                                             "512)"),
                      _CORRELATION),
    "twoscale": (ModelParameter("nano", "", None, "the nano-roughness statistics (a Nano), or surface"),
                 ModelParameter("surface", "m", None, "a nano height field (heights and spacing in m), or nano"),
                 *_ALPHA, _SLOPES, _SHADOWING, *_INDEX, *_DIFFUSE, _DIFFRACTION, _MS,
                 ModelParameter("resolution", "", None, "direction grid of the lobes tabulated from surface "
                                                        "(None: 128)"),
                 _CORRELATION),
    "rough-dielectric": (*_ALPHA, _SHADOWING, *_INDEX, _MS,
                         ModelParameter("psd", "m^4", None, "nano-roughness height statistics (a PSDModel): their "
                                                            "first-order scatter into both half-spaces "
                                                            "(NanoRoughDielectricBSDF); None: none"),
                         ModelParameter("nano_frame", "", DEFAULT_NANO_FRAME, "frame of the nano lobes of psd (NANO_FRAMES): "
                                                                   "macro (about the macro normal, right as α → 0) "
                                                                   "or facet (each micro facet's: "
                                                                   "TwoScaleDielectricBSDF, ~200x slower)")),
    "table": (ModelParameter("table", "", REQUIRED, "a BRDF table as a function (waveoptics.distributed.table."
                                                    "open_table)"),),
}
