"""BRDF models by name (:data:`BRDF_MODELS`), each set up from plain keyword arguments; each model's parameters,
with their unit, default and meaning, are :data:`BRDF_MODEL_PARAMETERS` (kept in :mod:`waveoptics.vocabulary`, so
that a front end builds its options from them without loading this package), and :func:`build_brdf_model` sets a
model up by name.

Each factory validates its parameters and returns a :class:`ModelEvaluation`, the model ready to evaluate at any
directions at the wavelengths it was set up for (``waveoptics brdf --model NAME`` parses its options into these
keyword arguments and prints what the evaluation returns).

Errors are :class:`waveoptics.errors.FieldError` naming the keyword arguments.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007 (microfacet).
.. [2] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4):66, 2017 (twoscale).
.. [3] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012, §4 (Rayleigh-Rice).
.. [4] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course
   (rough-dielectric, multiple scattering).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import FieldError, unknown
from ..vocabulary import BRDF_MODEL_HELP, BRDF_MODEL_PARAMETERS, DEFAULT_MATERIAL, DEFAULT_NDF

__all__ = ['ModelEvaluation', 'function_evaluation', 'microfacet_model', 'kirchhoff_model', 'rayleigh_rice_model',
           'twoscale_model', 'rough_dielectric_model', 'table_model', 'BRDF_MODELS', 'BRDF_MODEL_PARAMETERS',
           'BRDF_MODEL_HELP', 'build_brdf_model']


def _each(iterable, desc):
    """The default progress wrapper: the iterable itself."""
    return iterable


@dataclass(frozen=True)
class ModelEvaluation:
    """A BRDF model set up for its parameters and wavelengths λ (nm, shape (n_λ,)).

    Attributes
    ----------
    evaluate : callable(wi, wo, progress=None) -> ndarray (n_λ, n_in, n_out)
        BRDF in 1/sr (not × cos θ_o) for unit directions wi (n_in, 3) and wo (n_out, 3).
    albedo : callable(wi, progress=None) -> ndarray (n_λ, n_in)
        Directional albedo ∫ f cos θ_o dω_o (dimensionless).
    components : callable(wi, wo) -> dict, optional
        Named parts of the BRDF, each (n_λ, n_in, n_out) in 1/sr.
    albedo_components : callable(wi) -> dict, optional
        Named parts of the albedo, each (n_λ, n_in) (dimensionless; a BSDF over the sphere: ``reflection``,
        ``transmission``, ``multiple_reflection``, ...), summing to ``albedo``.

    *progress* is an optional wrapper ``progress(iterable, desc)`` of the loops over incident directions (a
    progress bar).
    """

    evaluate: Callable
    albedo: Callable
    components: Callable | None = None
    albedo_components: Callable | None = None


def _one_index(material, ior):
    """The substrate: a material name or a complex index (not both); None when neither is given."""
    if material is not None and ior is not None:
        raise FieldError("give only one of {material} and {ior}", "material", "ior")
    return material if material is not None else ior


def _alpha(alpha, roughness, model: str) -> float:
    """α from *alpha* or from the perceptual *roughness* (exactly one)."""
    from .roughness import alpha_from_roughness

    if (alpha is None) == (roughness is None):
        raise FieldError(f"give exactly one of {{alpha}} or {{roughness}} for the {model} model", "alpha", "roughness")
    return alpha if alpha is not None else float(alpha_from_roughness(roughness))


def _check_diffuse_sigma(diffuse_sigma_deg) -> None:
    if not np.isfinite(diffuse_sigma_deg) or not 0 <= diffuse_sigma_deg <= 90:
        raise FieldError(f"{{diffuse_sigma_deg}} {diffuse_sigma_deg!r} is not allowed; the Oren-Nayar roughness must "
                         "be in [0, 90] degrees", "diffuse_sigma_deg")


def _per_wavelength(kw: dict, n_axes: int) -> dict:
    """Reshape the per-wavelength arrays of *kw* to (n_λ, 1, ..., 1) for NumPy broadcasting."""
    from .fresnel_terms import MaterialFresnel

    out = dict(kw)
    for key in ("eta", "F0"):
        if out.get(key) is not None:
            out[key] = np.asarray(out[key]).reshape((-1,) + (1,) * n_axes)
    if isinstance(out.get("fresnel"), MaterialFresnel):   # a thin-film stack's F: its wavelengths shaped as eta's
        out["fresnel"] = out["fresnel"].reshape((-1,) + (1,) * n_axes)
    return out


def _microfacet_params(wavelengths_nm, *, alpha, roughness, alpha_y, ndf, ndf_shape, slope_table, shadowing,
                       material, ior, fresnel, diffuse, kd, diffuse_sigma_deg, diffuse_roughness, tradeoff) -> dict:
    """Keyword arguments of :func:`waveoptics.brdf.brdf`; Fresnel inputs per wavelength (n_λ,)."""
    from .microfacet import fresnel_inputs
    from .roughness_scales import Micro

    if slope_table is not None:   # the NDF of a micro height field's slopes; α, α_y place the quadrature's nodes
        micro = Micro.from_slopes(slope_table)
        ndf, ndf_shape, alpha, alpha_y = "tabulated", slope_table, micro.alpha, micro.alpha_y
    else:
        alpha = _alpha(alpha, roughness, "microfacet")
    spec = _one_index(material, ior)
    if spec is None:
        if fresnel != "one":
            raise FieldError("the microfacet model needs {material} or {ior} (or {fresnel} one for a white "
                             "furnace)", "material", "ior", "fresnel")
        fi = {"fresnel": "one", "eta": None, "F0": None}
    else:
        fi = fresnel_inputs(spec, wavelengths_nm, fresnel)
    _check_diffuse_sigma(diffuse_sigma_deg)
    if diffuse == "burley" and not 0 <= diffuse_roughness <= 1:
        raise FieldError(f"{{diffuse_roughness}} {diffuse_roughness!r} is not allowed; it must be in [0, 1]",
                         "diffuse_roughness")
    burley = diffuse == "burley"   # each model gets its own roughness only (the other stays 0)
    return dict(alpha=alpha, alpha_y=alpha_y, ndf=ndf, shadowing=shadowing, ndf_shape=ndf_shape,
                diffuse=diffuse, kd=kd, diffuse_sigma=0.0 if burley else float(np.radians(diffuse_sigma_deg)),
                diffuse_roughness=diffuse_roughness if burley else 0.0, tradeoff=tradeoff, **fi)


def _ms_brdf(kw, material, ior, fresnel, backend):
    """The microfacet BRDF function with multiple-scattering compensation (:class:`waveoptics.MicrofacetBRDF`)."""
    from .protocol import MicrofacetBRDF
    from .roughness_scales import Micro

    if backend == "opencl":
        raise FieldError("{multiple_scattering} is evaluated with NumPy; use {backend} numpy", "multiple_scattering",
                         "backend")
    if fresnel not in ("exact", "one"):
        raise FieldError(f"{{multiple_scattering}} needs {{fresnel}} exact or one, not {fresnel!r}",
                         "multiple_scattering", "fresnel")
    spec = material if material is not None else ior
    micro = Micro(alpha=kw["alpha"], alpha_y=kw["alpha_y"], ndf=kw["ndf"], shadowing=kw["shadowing"],
                  ndf_shape=kw["ndf_shape"])
    # with fresnel one and no material the index is never used (F = 1); a dielectric keeps the diffuse term
    return MicrofacetBRDF(spec if spec is not None else "1.5", micro, kd=kw["kd"], diffuse=kw["diffuse"],
                          fresnel=fresnel, diffuse_sigma=kw["diffuse_sigma"],
                          diffuse_roughness=kw["diffuse_roughness"], multiple_scattering=True)


def microfacet_model(*, wavelengths_nm, alpha=None, roughness=None, alpha_y=None, ndf=DEFAULT_NDF, ndf_shape=None,
                     slope_table=None, shadowing="smith-correlated", material=None, ior=None, fresnel="exact",
                     diffuse="lambert", kd=0.0, diffuse_sigma_deg=0.0, diffuse_roughness=0.5, tradeoff=True,
                     multiple_scattering=False, backend="numpy", precision="float32", device=None) -> ModelEvaluation:
    """The geometric-optics microfacet BRDF (Cook-Torrance / Walter et al. 2007) with a diffuse term.

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm.
    alpha, roughness : float
        Exactly one: the NDF's slope scale α (α_x if anisotropic; dimensionless, in [0, 2]) or the perceptual
        roughness r (α = r²).
    alpha_y : float, optional
        α_y of the anisotropic NDFs (dimensionless).
    ndf, ndf_shape, shadowing : str, float, str
        NDF name (:data:`waveoptics.brdf.NDFS`), its shape parameter, masking-shadowing term.
    slope_table : SlopeTable, optional
        The NDF of a micro height field's slopes (:func:`waveoptics.brdf.slope_table`); replaces *alpha*,
        *roughness*, *ndf* and *ndf_shape*.
    material, ior : str, optional
        The substrate: a material name or a complex index ``"N+Kj"`` (one of them unless *fresnel* is ``"one"``).
    fresnel : str
        ``"exact"``, ``"schlick"`` or ``"one"`` (F = 1).
    diffuse, kd : str, float
        Diffuse model and albedo (dimensionless).
    diffuse_sigma_deg : float
        Oren-Nayar roughness σ in degrees, in [0, 90].
    diffuse_roughness : float
        Burley diffuse roughness in [0, 1].
    tradeoff : bool
        Weight the diffuse term by (1 − F(θ_i))(1 − F(θ_o)) / (1 − F̄).
    multiple_scattering : bool
        Kulla-Conty compensation (NumPy, exact or one Fresnel).
    backend, precision, device : str
        ``"numpy"`` or ``"opencl"`` (evaluation only; the albedo always uses NumPy), the OpenCL precision and
        device.
    """
    from .microfacet import brdf
    from .opencl import brdf_cl
    from .quadrature import albedo as quad_albedo
    from ..runtime import get_runtime

    kw = _microfacet_params(wavelengths_nm, alpha=alpha, roughness=roughness, alpha_y=alpha_y, ndf=ndf,
                            ndf_shape=ndf_shape, slope_table=slope_table, shadowing=shadowing, material=material,
                            ior=ior, fresnel=fresnel, diffuse=diffuse, kd=kd, diffuse_sigma_deg=diffuse_sigma_deg,
                            diffuse_roughness=diffuse_roughness, tradeoff=tradeoff)
    n_w = len(wavelengths_nm)
    lam = np.asarray(wavelengths_nm, dtype=float)
    if backend == "opencl" and not isinstance(kw["fresnel"], str):
        raise FieldError(f"{{material}} {material!r} is a thin-film stack, whose reflectance is evaluated with NumPy; "
                         "use {backend} numpy", "material", "backend")

    def evaluate(wi, wo, progress=None):
        if multiple_scattering:
            return _ms_brdf(kw, material, ior, fresnel, backend).eval(wi[None, :, None, :], wo[None, None, :, :],
                                                                      lam[:, None, None])
        if backend == "opencl":
            a = np.repeat(wi, len(wo), axis=0)
            b = np.tile(wo, (len(wi), 1))
            fk = dict(kw)
            for key in ("eta", "F0"):
                if fk.get(key) is None:
                    fk.pop(key)
            f = brdf_cl(a, b, runtime=get_runtime(device), precision=precision, **fk)
            return np.broadcast_to(f, (n_w, a.shape[0])).reshape(n_w, len(wi), len(wo))
        f = brdf(wi[None, :, None, :], wo[None, None, :, :], **_per_wavelength(kw, 2))
        return np.broadcast_to(f, (n_w, len(wi), len(wo)))

    def albedo(wi, progress=None):
        each = progress or _each
        if multiple_scattering:
            b = _ms_brdf(kw, material, ior, fresnel, backend)
            out = [b.albedo(w[None, :], lam) for w in each(wi, "albedo")]
            return np.stack(out, axis=-1)
        kw1 = _per_wavelength(kw, 1)
        out = [quad_albedo(w, **kw1) for w in each(wi, "albedo")]
        return np.broadcast_to(np.stack(out, axis=-1), (n_w, len(wi)))

    return ModelEvaluation(evaluate, albedo)


def kirchhoff_model(*, wavelengths_nm, surface, material=None, ior=None, fresnel="exact", solver="direct",
                    backend="numpy", precision="float32", window="hann", resolution=None, realizations=1,
                    diffraction="kirchhoff", polarization="unpolarized", device=None) -> ModelEvaluation:
    """The wave-optics BRDF of a height field (:func:`waveoptics.scatter.brdf`).

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm.
    surface : HeightField
        The height field (heights and spacing in m).
    material, ior : str, optional
        The substrate (one of them unless *fresnel* is ``"one"``).
    fresnel : str
        ``"exact"``, ``"schlick"`` or ``"one"``.
    solver, backend, precision, window, realizations, diffraction, polarization, device
        As :func:`waveoptics.scatter.brdf`.
    resolution : int, optional
        Cells per side of the fft grid and of the albedo quadrature (default: resolves the specular spike; albedo
        256).
    """
    from ..materials.database import get_material
    from ..materials.fresnel import F_schlick
    from ..runtime import get_runtime
    from .. import scatter

    if surface is None:
        raise FieldError("the kirchhoff model needs {surface} (a height field)", "surface")
    spec = _one_index(material, ior)
    if fresnel == "one" or spec is None:
        if fresnel != "one":
            raise FieldError("the kirchhoff model needs {material} or {ior} (or {fresnel} one)", "material", "ior",
                             "fresnel")
        F = None
    else:
        mat = get_material(spec)
        if fresnel == "schlick":

            def F(c, w, _m=mat):
                return F_schlick(c, _m.F0(w))
        else:
            F = mat
    rt = get_runtime(device) if backend == "opencl" and solver == "direct" else None
    common = dict(solver=solver, backend=backend, precision=precision, window_name=window,
                  realizations=realizations, runtime=rt, diffraction=diffraction, polarization=polarization)

    def evaluate(wi, wo, progress=None):
        each = progress or _each
        out = [scatter.brdf(surface, w, wo, wavelengths_nm, F, resolution=resolution, **common)
               for w in each(wi, "kirchhoff")]
        return np.stack(out, axis=1)

    def albedo(wi, progress=None):
        each = progress or _each
        out = [scatter.scatter(surface, w, wavelengths_nm, F, resolution=resolution or 256, **common).albedo
               for w in each(wi, "albedo")]
        return np.stack(out, axis=1)

    return ModelEvaluation(evaluate, albedo)


def rayleigh_rice_model(*, wavelengths_nm, psd, material=None, ior=None, polarization="unpolarized",
                        resolution=None, roughness_correlation="correlated") -> ModelEvaluation:
    """First-order Rayleigh-Rice BRDF of a smooth rough surface from its PSD, with the polarization factor Q.

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm.
    psd : PSDModel or PeriodogramPSD
        The surface's power spectral density (heights in m).
    material, ior : str
        The substrate's complex index: a material with index data, or ``"N+Kj"`` (exactly one); or a thin-film
        stack ``"SUBSTRATE|FILM:THICKNESS|..."``: Elson's first-order BRDF of the stack with *psd* on every
        interface (:func:`waveoptics.scatter.rough_stack_brdf`).
    polarization : str
        ``"s"``, ``"p"`` or ``"unpolarized"``.
    resolution : int, optional
        Cells per side of the albedo quadrature grid (default 512).
    roughness_correlation : str or float
        Of a stack's interface profiles: ``"correlated"`` (default, a film replicating its substrate),
        ``"uncorrelated"`` or a coefficient in [0, 1] (:func:`waveoptics.materials.roughness_correlation`);
        unused for a bare material.

    A transparent substrate (glass, or a stack on glass) also scatters into the material: ``evaluate`` takes
    directions ω_o below the surface (the first-order BTDF into the substrate, radiance convention,
    :func:`waveoptics.scatter.rough_stack_bsdf`, which without films is the single interface's Rayleigh-Rice in
    transmission), and the albedo is ``reflection`` + ``transmission`` (the transmitted TIS,
    :func:`waveoptics.scatter.rough_stack_tis_sides`). Below an absorbing substrate nothing propagates: such
    directions are refused.

    References
    ----------
    .. [1] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997 (one interface).
    .. [2] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (rough stacks).
    .. [3] J. M. Elson, Phys. Rev. B 30(10), 5460–5480, 1984; J. C. Stover, *Optical Scattering*, 3rd ed., SPIE
       2012, ch. 5 (first-order scatter into the substrate).
    """
    from ..materials.database import get_material
    from ..materials.thinfilm import with_roughness_correlation
    from .. import scatter

    spec = _one_index(material, ior)
    if spec is None:
        raise FieldError("the rayleigh-rice model needs {material} or {ior} (the substrate's index)", "material", "ior")
    mat = get_material(spec)
    if mat.schlick_only:
        raise FieldError(f"{{material}} {spec!r} gives only F0; rayleigh-rice needs a complex index "
                         "(a preset, shelf/book/page or an index N+Kj)", "material")
    mat = with_roughness_correlation(mat, roughness_correlation)
    # a thin-film stack stands in for ε: the Rayleigh-Rice functions take it to Elson's rough-stack BRDF
    eps = mat if scatter.is_stack(mat) else scatter.permittivity(mat, wavelengths_nm)
    w3 = wavelengths_nm[:, None, None]

    clear = scatter.substrate_is_transparent(
        (mat.substrate if scatter.is_stack(mat) else mat).eta(wavelengths_nm) ** 2)
    corr = scatter.stack_correlation(mat)

    def inside(wi, wo):
        """Pairs that touch the material's side (light from inside, or a direction into it), (1, n_in, n_out)."""
        for name, w in (("incident", wi), ("outgoing", wo)):
            if np.any(w[:, 2] < 0) and not clear:
                raise FieldError(f"{{{name}}} below the surface: {mat.name!r} absorbs, nothing propagates in it "
                                 "(a transparent substrate scatters into itself and lights from inside)", name)
        return (wi[:, 2] < 0)[None, :, None] | (wo[:, 2] < 0)[None, None, :]

    def evaluate(wi, wo, progress=None):
        a, b = wi[None, :, None, :], wo[None, None, :, :]
        return np.where(inside(wi, wo), scatter.rough_stack_bsdf(a, b, w3, mat, psd, corr, polarization),
                        scatter.rayleigh_rice_brdf(a, b, w3, psd, _per_lambda(eps), polarization))

    def components(wi, wo):
        a, b = wi[None, :, None, :], wo[None, None, :, :]
        sel = inside(wi, wo)
        t = scatter.rough_stack_bsdf_components(a, b, w3, mat, psd, corr) if np.any(sel) else None
        r = scatter.rayleigh_rice_components(a, b, w3, psd, _per_lambda(eps))
        return r if t is None else {k: np.where(sel, t[k], v) for k, v in r.items()}

    def parts(wi, progress=None):
        """``reflection`` (a hemisphere grid of the Rayleigh-Rice BRDF from air; the stack's TIS on the incidence
        side from inside) and, over a transparent material, ``transmission`` (the TIS across)."""
        inside(wi, wi)
        grid = scatter.DirectionGrid.hemisphere(resolution or 512)
        wo = grid.directions()
        out = {k: np.zeros((len(wavelengths_nm), len(wi))) for k in ("reflection", "transmission")}
        for i, w in enumerate(wi):
            theta = float(np.degrees(np.arccos(min(abs(w[2]), 1.0))))
            for j, lam in enumerate(wavelengths_nm):
                if clear:
                    r, out["transmission"][j, i] = scatter.rough_stack_tis_sides(theta, lam, mat, psd, corr,
                                                                                 polarization, from_above=w[2] > 0)
                    if w[2] < 0:
                        out["reflection"][j, i] = r
            if w[2] > 0:
                f = scatter.rayleigh_rice_brdf(w, wo[None], w3, psd, _per_lambda(eps), polarization)
                out["reflection"][:, i] = scatter.integrate(np.where(grid.inside, f, 0.0), grid)
        return out if clear else {"reflection": out["reflection"]}

    return ModelEvaluation(evaluate, lambda wi, progress=None: sum(parts(wi).values()), components,
                           parts if clear else None)


def _per_lambda(eps):
    """ε per wavelength shaped (n_λ, 1, 1) against (λ, ω_i, ω_o); a stack as it is (it takes λ itself)."""
    return eps if not isinstance(eps, np.ndarray) else eps[:, None, None]


def function_evaluation(setup: Callable, wavelengths_nm) -> ModelEvaluation:
    """The :class:`ModelEvaluation` of a BRDF function (:mod:`waveoptics.brdf.protocol`) built by *setup(wi)*
    (wi (n_in, 3) or None): evaluation, parts and albedo come from the object."""
    w3 = wavelengths_nm[:, None, None]

    def evaluate(wi, wo, progress=None):
        return setup(wi).eval(wi[None, :, None, :], wo[None, None, :, :], w3)

    def components(wi, wo):
        return setup(wi).eval_parts(wi[None, :, None, :], wo[None, None, :, :], w3)

    def albedo(wi, progress=None):
        return setup(wi).albedo(wi[None, :, :], wavelengths_nm[:, None])

    def albedo_components(wi):
        return setup(wi).albedo_parts(wi[None, :, :], wavelengths_nm[:, None])

    return ModelEvaluation(evaluate, albedo, components, albedo_components)


def twoscale_model(*, wavelengths_nm, nano=None, surface=None, alpha=None, roughness=None, alpha_y=None, ndf=DEFAULT_NDF,
                   ndf_shape=None, slope_table=None, shadowing="smith-correlated", material=None, ior=None,
                   fresnel="exact", diffuse="lambert", kd=0.0, diffuse_sigma_deg=0.0, diffraction="kirchhoff",
                   multiple_scattering=False, resolution=None,
                   roughness_correlation="correlated") -> ModelEvaluation:
    """The two-scale BRDF: a micro NDF carrying nano-roughness (Holzschuch & Pacanowski 2017), as a function.

    With *nano* (a :class:`waveoptics.brdf.Nano` of PSD statistics) it is :class:`waveoptics.brdf.TwoScaleBRDF`
    (exact at any direction pair); with a *surface* height field, :class:`waveoptics.brdf.TabulatedTwoScaleBRDF`
    with its incidence nodes at the incident angles evaluated (so nothing is interpolated in θ_i), built once per
    set of incident angles.

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm.
    nano, surface : Nano or HeightField
        Exactly one: the nano-roughness statistics, or a height field (heights and spacing in m).
    alpha, roughness, alpha_y, ndf, ndf_shape, slope_table, shadowing
        The micro roughness, as :func:`microfacet_model`.
    material, ior : str, optional
        The substrate (one of them unless *fresnel* is ``"one"``).
    fresnel : str
        ``"exact"`` or ``"one"``.
    diffuse, kd, diffuse_sigma_deg : str, float, float
        Diffuse model, albedo and Oren-Nayar σ in degrees (in [0, 90]).
    diffraction : str
        Model of the nano lobe (:data:`waveoptics.vocabulary.DIFFRACTION`).
    multiple_scattering : bool
        Kulla-Conty compensation of the micro lobe.
    resolution : int, optional
        Direction grid of the tabulated lobes (default 128; *surface* only).
    roughness_correlation : str or float
        Of a thin-film stack's interface roughness under ``diffraction="rayleigh-rice"`` (default correlated;
        :func:`waveoptics.materials.roughness_correlation`).
    """
    from ..materials.database import get_material
    from ..materials.thinfilm import with_roughness_correlation
    from .pointwise import TwoScaleBRDF
    from .tabulated import TabulatedTwoScaleBRDF
    from .roughness_scales import Micro, Nano

    if (surface is None) == (nano is None):
        raise FieldError("give exactly one of {nano} and {surface} for the twoscale model", "nano", "surface")
    spec = _one_index(material, ior)
    if spec is None and fresnel != "one":
        raise FieldError("the twoscale model needs {material} or {ior} (or {fresnel} one)", "material", "ior",
                         "fresnel")
    if fresnel == "schlick":
        raise FieldError("{fresnel} schlick is not available for the twoscale model; use exact or one", "fresnel")
    _check_diffuse_sigma(diffuse_sigma_deg)
    if slope_table is not None:   # the NDF of a micro height field's slopes
        micro = Micro.from_slopes(slope_table, shadowing)
    else:
        micro = Micro(alpha=_alpha(alpha, roughness, "twoscale"), alpha_y=alpha_y, ndf=ndf, shadowing=shadowing,
                      ndf_shape=ndf_shape)
    # a stack carries its interfaces' roughness correlation to the Rayleigh-Rice nano lobe and coherent fraction
    mat = with_roughness_correlation(get_material(spec if spec is not None else DEFAULT_MATERIAL),
                                     roughness_correlation)
    common = dict(material=mat, micro=micro, kd=kd, diffuse=diffuse,
                  fresnel=fresnel, diffuse_sigma=float(np.radians(diffuse_sigma_deg)), diffraction=diffraction,
                  multiple_scattering=multiple_scattering)
    cache = {}

    def build(wi):
        thetas = None if wi is None else tuple(np.round(np.degrees(np.arccos(np.clip(wi[:, 2], -1, 1))), 9))
        if thetas not in cache:
            if surface is None:
                cache[thetas] = TwoScaleBRDF(nano=nano, **common)
            else:
                nodes = (0.0,) if thetas is None else tuple(sorted(set(float(t) for t in thetas)))
                cache[thetas] = TabulatedTwoScaleBRDF(nano=Nano(surface=surface),
                                                      wavelengths_nm=tuple(np.asarray(wavelengths_nm, dtype=float)),
                                                      resolution=resolution or 128, thetas_deg=nodes, solver="fft",
                                                      **common)
        return cache[thetas]

    return function_evaluation(build, wavelengths_nm)


def rough_dielectric_model(*, wavelengths_nm, alpha=None, roughness=None, alpha_y=None, ndf=DEFAULT_NDF, ndf_shape=None,
                           shadowing="smith-correlated", material=None, ior=None, fresnel="exact",
                           multiple_scattering=False, psd=None, nano_frame="macro") -> ModelEvaluation:
    """The BSDF of a rough dielectric interface, reflection and transmission over the whole sphere (Walter et al.
    2007; :class:`waveoptics.brdf.RoughDielectricBSDF`), as a function: directions with z < 0 lie in the
    dielectric; the albedo is R + T; its parts are ``reflection``, ``transmission`` and ``multiple``.

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm.
    alpha, roughness, alpha_y, ndf, ndf_shape : float, float, float, str, float
        The micro roughness, as :func:`microfacet_model`.
    shadowing : str
        ``smith`` or ``smith-correlated``.
    material, ior : str
        The dielectric below the surface: a material name or a real index (exactly one).
    fresnel : str
        ``exact`` only (the transmission is 1 − F; with a thin-film stack as *material*, ``"BK7|MgF2:100nm"``, each
        facet reflects the stack's R and transmits its T: :func:`waveoptics.brdf.facet_interface_of`).
    multiple_scattering : bool
        Kulla-Conty dielectric energy compensation.
    psd : PSDModel, optional
        Nano-roughness height statistics (m⁴): the interface also scatters their first-order (Rayleigh-Rice) light
        into both half-spaces, which its coherent lobes give up (:class:`waveoptics.brdf.NanoRoughDielectricBSDF`,
        right as α → 0); its extra part is ``nano``.
    nano_frame : str
        Frame of the nano lobes of *psd* (:data:`waveoptics.vocabulary.NANO_FRAMES`): ``macro`` about the macro
        normal (:class:`waveoptics.brdf.NanoRoughDielectricBSDF`), ``facet`` in each micro facet's frame
        (:class:`waveoptics.brdf.TwoScaleDielectricBSDF`: right at any α, ~200x slower per evaluation).
    """
    from .btdf import RoughDielectricBSDF
    from .twoscale import Micro
    from .twoscale_dielectric import nano_rough_glass

    spec = _one_index(material, ior)
    if spec is None:
        raise FieldError("the rough-dielectric model needs {material} or {ior} (the dielectric's index)", "material",
                         "ior")
    if fresnel != "exact":
        raise FieldError(f"{{fresnel}} {fresnel!r} is not available for the rough-dielectric model; it uses the "
                         "exact dielectric Fresnel factor (transmission 1 − F)", "fresnel")
    micro = Micro(alpha=_alpha(alpha, roughness, "rough-dielectric"), alpha_y=alpha_y, ndf=ndf, shadowing=shadowing,
                  ndf_shape=ndf_shape)
    if psd is None:
        if nano_frame != "macro":
            raise FieldError(f"{{nano_frame}} {nano_frame!r} needs {{psd}} (nano-roughness statistics)", "nano_frame",
                             "psd")
        bsdf = RoughDielectricBSDF(spec, micro, multiple_scattering=multiple_scattering)
    else:
        bsdf = nano_rough_glass(spec, micro, psd, multiple_scattering=multiple_scattering, nano_frame=nano_frame)
    return function_evaluation(lambda wi: bsdf, wavelengths_nm)


def table_model(*, wavelengths_nm, table) -> ModelEvaluation:
    """A BRDF table as a function (:func:`waveoptics.distributed.table.open_table` opens a table file as one):
    evaluation, parts and albedo come from the table object.

    Parameters
    ----------
    wavelengths_nm : ndarray (n_λ,)
        Wavelengths in nm (the table's own).
    table : BRDF function
        An object with ``eval``, ``eval_parts`` and ``albedo`` (:mod:`waveoptics.brdf.protocol`).
    """
    if table is None:
        raise FieldError("the table model needs {table} (a BRDF table as a function)", "table")
    return function_evaluation(lambda wi: table, wavelengths_nm)


#: BRDF model factories by name; each takes keyword arguments (``wavelengths_nm`` and the model's parameters,
#: :data:`BRDF_MODEL_PARAMETERS`) and returns a :class:`ModelEvaluation`
BRDF_MODELS: dict[str, Callable] = {
    "microfacet": microfacet_model,
    "kirchhoff": kirchhoff_model,
    "rayleigh-rice": rayleigh_rice_model,
    "twoscale": twoscale_model,
    "rough-dielectric": rough_dielectric_model,
    "table": table_model,
}


def build_brdf_model(name: str, wavelengths_nm, **params) -> ModelEvaluation:
    """The BRDF model *name* (:data:`BRDF_MODELS`) set up at *wavelengths_nm* (nm) with *params*, its parameters
    (:data:`BRDF_MODEL_PARAMETERS`; a parameter left out takes its default). A parameter the model does not take
    is refused, naming the models that take it."""
    if name not in BRDF_MODELS:
        raise unknown("BRDF model", name, BRDF_MODELS, field="model")
    own = {p.name for p in BRDF_MODEL_PARAMETERS[name]}
    extra = [k for k in params if k not in own]
    if extra:
        takers = [m for m, ps in BRDF_MODEL_PARAMETERS.items() if any(p.name == extra[0] for p in ps)]
        raise FieldError(f"{{{extra[0]}}} is not a parameter of the {name} model" +
                         (f" (it is one of {', '.join(takers)})" if takers else ""), extra[0])
    return BRDF_MODELS[name](wavelengths_nm=wavelengths_nm, **params)
