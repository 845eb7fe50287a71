"""Rayleigh-Rice: first-order vector perturbation theory of scattering by a smooth rough surface, with the full
polarization factor Q for s and p incident and scattered light (docs/physics.md §4, §10).

    f_ab(ω_i, ω_o) = (16 π² / λ⁴) cosθ_i cosθ_o |q_ab|² S(f_x, f_y),      a, b ∈ {s, p}

with S the two-sided surface PSD at the Bragg frequency f = −(ω_i + ω_o)_xy / λ (only |f| matters for an isotropic
PSD) and, for a substrate of relative permittivity ε = (n + iκ)² (s and p relative to the planes of incidence and
scattering; φ_s the scattering azimuth measured from the specular side of the plane of incidence):

    q_ss =  (ε − 1) cosφ_s / [(cosθ_i + √(ε − sin²θ_i)) (cosθ_o + √(ε − sin²θ_o))]
    q_sp = −(ε − 1) √(ε − sin²θ_o) sinφ_s / [(cosθ_i + √(ε − sin²θ_i)) (ε cosθ_o + √(ε − sin²θ_o))]
    q_ps = −(ε − 1) √(ε − sin²θ_i) sinφ_s / [(ε cosθ_i + √(ε − sin²θ_i)) (cosθ_o + √(ε − sin²θ_o))]
    q_pp =  (ε − 1) (ε sinθ_i sinθ_o − √(ε − sin²θ_i) √(ε − sin²θ_o) cosφ_s)
            / [(ε cosθ_i + √(ε − sin²θ_i)) (ε cosθ_o + √(ε − sin²θ_o))]

(first index: incident polarization, second: scattered). Q_ab = |q_ab|². A detector that does not analyze
polarization sees f_s = f_ss + f_sp for s-polarized light, f_p = f_pp + f_ps for p, and their mean for
unpolarized light. At normal incidence and backscatter every Q tends to the normal-incidence reflectance
|(√ε − 1)/(√ε + 1)|²; for a perfect conductor (|ε| → ∞) q_ss → cosφ_s, q_pp → (sinθ_i sinθ_o − cosφ_s) /
(cosθ_i cosθ_o), q_sp → −sinφ_s / cosθ_o, q_ps → −sinφ_s / cosθ_i (Rice 1951).

Where it holds: the smooth-surface limit, (4π σ cosθ / λ)² ≪ 1 and slopes ≪ 1 (first order in σ/λ): a few nm of
rms height at visible wavelengths. It takes no shadowing and no multiple scattering; the coherent (specular)
reduction is not part of it.

References
----------
.. [1] S. O. Rice, "Reflection of electromagnetic waves from slightly rough surfaces", Commun. Pure Appl. Math.
   4, 351–378, 1951.
.. [2] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
.. [3] E. L. Church, H. A. Jenkinson, J. M. Zavada, "Relationship between surface scattering and
   microtopographic features", Opt. Eng. 18(2), 125–136, 1979.
.. [4] T. A. Germer, "Angular dependence and polarization of out-of-plane optical scattering from particulate
   contamination, subsurface defects, and surface microroughness", Appl. Opt. 36(33), 8798–8805, 1997.
.. [5] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012, ch. 4–5.
"""
from __future__ import annotations

import numpy as np

from ..errors import FieldError, unknown
from ..surfaces.psd import PSDModel
from ..vocabulary import POLARIZATIONS
from .angles import scattering_angles
from .polar import polar_albedo
from .rough_film import rough_stack_brdf, rough_stack_components, rough_stack_tis
from .series import rayleigh_rice

__all__ = ["POLARIZATIONS", "COMPONENTS", "PEC_PERMITTIVITY", "q_factors", "Q",
           "rayleigh_rice_components", "rayleigh_rice_brdf", "permittivity", "rayleigh_rice_lobe",
           "rayleigh_rice_albedo", "rayleigh_rice_tis", "periodogram_bin_sum", "is_stack", "stack_correlation"]

#: relative permittivity standing for a perfect conductor (|ε| → ∞: every q tends to Rice's limit, reflectance 1)
PEC_PERMITTIVITY = -1e12 + 0j


#: incident → scattered polarization pairs of the Jones-matrix elements
COMPONENTS = ("ss", "sp", "ps", "pp")


def q_factors(wi, wo, eps) -> dict:
    """Complex amplitude factors q_ss, q_sp, q_ps, q_pp (unitless) for permittivity *eps* (broadcasts).

    References
    ----------
    .. [1] Germer 1997, eqs. (17)–(20); Elson & Bennett 1979 (see the module references).
    """
    ci, si, co, so, cphi, sphi = scattering_angles(wi, wo)
    e = np.asarray(eps, dtype=np.complex128)
    ri = np.sqrt(e - si ** 2)      # principal branch: Re ≥ 0, Im ≥ 0 for an absorbing substrate
    ro = np.sqrt(e - so ** 2)
    ds_i, dp_i = ci + ri, e * ci + ri
    ds_o, dp_o = co + ro, e * co + ro
    return {"ss": (e - 1) * cphi / (ds_i * ds_o),
            "sp": -(e - 1) * ro * sphi / (ds_i * dp_o),
            "ps": -(e - 1) * ri * sphi / (dp_i * ds_o),
            "pp": (e - 1) * (e * si * so - ri * ro * cphi) / (dp_i * dp_o)}


def Q(wi, wo, eps, polarization: str = "unpolarized"):
    """Polarization factor Q (unitless) seen without an analyzer: Q_ss + Q_sp (s), Q_pp + Q_ps (p) or their mean
    (unpolarized)."""
    if polarization not in POLARIZATIONS:
        raise unknown("polarization", polarization, POLARIZATIONS, field="polarization")
    q = {k: np.abs(v) ** 2 for k, v in q_factors(wi, wo, eps).items()}
    s, p = q["ss"] + q["sp"], q["pp"] + q["ps"]
    return {"s": s, "p": p, "unpolarized": 0.5 * (s + p)}[polarization]


def is_stack(material) -> bool:
    """Whether *material* is a thin-film stack (:class:`~waveoptics.materials.Stack`): its first-order scatter is
    Elson's rough-stack theory (:func:`waveoptics.scatter.rough_stack_brdf`), not one interface's Q."""
    return material is not None and hasattr(material, "films") and hasattr(material, "substrate")


def stack_correlation(material):
    """The interface-roughness correlation a stack carries (``"correlated"`` unless it says otherwise)."""
    return getattr(material, "roughness_correlation", "correlated")


def rayleigh_rice_components(wi, wo, wavelength_nm, model: PSDModel, eps) -> dict:
    """The four polarized BRDFs f_ss, f_sp, f_ps, f_pp (1/sr) of the rough surface (*eps* a
    :class:`~waveoptics.materials.Stack`: of the stack with the PSD on every interface,
    :func:`waveoptics.scatter.rough_stack_components`)."""
    if is_stack(eps):
        return rough_stack_components(wi, wo, wavelength_nm, eps, model, stack_correlation(eps))
    pre = rayleigh_rice(wi, wo, wavelength_nm, model)   # Q = 1: (16π²/λ⁴) cosθ_i cosθ_o S
    return {k: pre * np.abs(v) ** 2 for k, v in q_factors(wi, wo, eps).items()}


def rayleigh_rice_brdf(wi, wo, wavelength_nm, model: PSDModel, eps, polarization: str = "unpolarized"):
    """Rayleigh-Rice BRDF (1/sr) for *polarization* of the incident light (scattered light not analyzed).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit vectors towards the light and the viewer.
    wavelength_nm : array_like, nm
    model : PSDModel
        The surface's height statistics.
    eps : complex, array or Stack
        Relative permittivity of the substrate, (n + iκ)²; or a thin-film
        :class:`~waveoptics.materials.Stack`: the first-order BRDF of the stack with *model* on every interface and
        the stack's ``roughness_correlation`` (Elson; :func:`waveoptics.scatter.rough_stack_brdf`).
    polarization : {'unpolarized', 's', 'p'}

    References
    ----------
    .. [1] Germer 1997; Elson & Bennett 1979 (one interface, module references).
    .. [2] J. M. Elson, Appl. Opt. 16(11), 2872–2881, 1977; J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt.
       22(20), 3207–3219, 1983 (rough stacks, correlated and uncorrelated interfaces).
    """
    if is_stack(eps):
        return rough_stack_brdf(wi, wo, wavelength_nm, eps, model, stack_correlation(eps), polarization)
    return rayleigh_rice(wi, wo, wavelength_nm, model, Q=Q(wi, wo, eps, polarization))


def permittivity(material, wavelength_nm):
    """Relative permittivity ε = (n + iκ)² of *material* at *wavelength_nm* (nm); None stands for a perfect
    conductor (:data:`PEC_PERMITTIVITY`, reflectance 1: the F = 1 white furnace of the two-scale model)."""
    if material is None:
        return np.broadcast_to(PEC_PERMITTIVITY, np.shape(wavelength_nm))
    if getattr(material, "schlick_only", False):
        raise FieldError(f"{{material}} {material.name!r} gives only F0; rayleigh-rice needs a complex index "
                         "(a preset, shelf/book/page or n+kj)", "material")
    if not getattr(material, "has_index", True):
        raise FieldError(f"{{material}} {material.name!r} is a thin-film stack and has no single permittivity (the "
                         "Rayleigh-Rice functions take the stack itself: rough_stack_brdf)", "material")
    return np.asarray(material.eta(wavelength_nm), dtype=np.complex128) ** 2


def rayleigh_rice_lobe(wi, wo, wavelength_nm, psd, material=None, polarization: str = "unpolarized"):
    """The Rayleigh-Rice lobe (1/sr) of a PSD (:class:`~waveoptics.surfaces.PSDModel` or a height field's
    :class:`~waveoptics.surfaces.PeriodogramPSD`) on *material* (None: a perfect conductor) as the two-scale
    model's nano lobe: it carries its own polarization factor Q, which plays the part of the Kirchhoff lobe's
    F(θ_d) (they agree at the mirror direction, to first order near it).

    A thin-film :class:`~waveoptics.materials.Stack` gives Elson's first-order BRDF of the stack with *psd* on
    every interface, correlated as the stack's ``roughness_correlation`` says
    (:func:`waveoptics.scatter.rough_stack_brdf`); its factor plays the part of the stack's F(θ_d).

    References
    ----------
    .. [1] Germer 1997 (one interface, module references).
    .. [2] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (rough stacks).
    """
    if is_stack(material):
        return rough_stack_brdf(wi, wo, wavelength_nm, material, psd, stack_correlation(material), polarization)
    eps = permittivity(material, wavelength_nm)
    return rayleigh_rice_brdf(wi, wo, wavelength_nm, psd, eps, polarization)


def _specular_reflectance(theta, wavelength_nm, material, polarization):
    """R(θ) of a flat *material* (s, p or unpolarized; 1 without one)."""
    import math

    if material is None:
        return 1.0
    wi = np.array([math.sin(theta), 0.0, math.cos(theta)])
    mirror = np.array([-wi[0], 0.0, wi[2]])
    if polarization != "unpolarized":
        return float(material.F_facet(wi, mirror, wavelength_nm, polarization))
    return float(material.F(math.cos(theta), wavelength_nm))


def rayleigh_rice_tis(theta_deg, wavelength_nm, psd, material=None, polarization: str = "unpolarized",
                      scalar: bool = False, azimuth_deg: float = 0.0) -> float:
    """TIS(θ) = ∫ f_RR cosθ_o dω_o (unitless, a share of the incident light) over the hemisphere
    (:func:`waveoptics.scatter.polar_albedo`): the light first-order roughness scatters into reflection.

    *scalar*: the first order of the scalar problem with a reflection coefficient of modulus 1 (the Dirichlet
    problem, Q = 1; the Kirchhoff lobe with F = 1 is the tangent-plane approximation of that problem) in place of
    the vector Q of the *material*. A thin-film :class:`~waveoptics.materials.Stack` gives the TIS of the stack
    with *psd* on every interface (:func:`waveoptics.scatter.rough_stack_tis`). A 1-D array of incidences
    *theta_deg* gives the TIS at each (one quadrature over all of them, :func:`~waveoptics.scatter.polar_albedo`). A
    height field's periodogram is summed over its own bins (:func:`periodogram_bin_sum`) at *azimuth_deg* (degrees;
    the light's azimuth in the field's axes, which an anisotropic field's TIS depends on; a PSD model is isotropic).

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4 (TIS of the Rayleigh-Rice BRDF).
    .. [2] E. I. Thorsos, D. R. Jackson, "The validity of the perturbation approximation for rough surface
       scattering using a Gaussian roughness spectrum", JASA 86(1), 261–277, 1989 (scalar Dirichlet first order,
       Q = 1).
    """
    import math

    lam = float(wavelength_nm)
    many = np.ndim(theta_deg) > 0
    t = [math.radians(float(x)) for x in np.ravel(theta_deg)] if many else math.radians(float(theta_deg))
    k = 2 * math.pi / (lam * 1e-9)
    if scalar:
        def lobe(wi_b, wo, q):
            return rayleigh_rice(wi_b, wo, lam, psd)
    elif is_stack(material):
        corr = stack_correlation(material)
        if many:
            return np.array([rough_stack_tis(float(x), lam, material, psd, corr, polarization)
                             for x in np.ravel(theta_deg)])
        return rough_stack_tis(theta_deg, lam, material, psd, corr, polarization)
    else:
        eps = complex(np.ravel(permittivity(material, lam))[0])

        def lobe(wi_b, wo, q):
            return rayleigh_rice_brdf(wi_b, wo, lam, psd, eps, polarization)
    if hasattr(psd, "P") and hasattr(psd, "fx"):   # a height field's periodogram: its own bins
        out = np.array([periodogram_bin_sum(x, lam, psd, lobe, math.radians(azimuth_deg)) for x in np.ravel(t)])
        return out if many else float(out[0])
    return polar_albedo(t, k, psd.length_scale, lobe)


def periodogram_bin_sum(theta, wavelength_nm, psd, lobe, azimuth: float = 0.0) -> float:
    """∫ f cosθ_o dω_o = ∫ f du dv of a first-order *lobe* (``lobe(wi, wo, q)``, 1/sr) of a height field's periodogram
    *psd* (:class:`waveoptics.surfaces.PeriodogramPSD`) at incidence *theta*, *azimuth* (rad), summed over the
    periodogram's own bins: each frequency (f_x, f_y) sends the light to (u, v) = (λ f_x − u_i, λ f_y − v_i) (the
    grating equation), a cell of λ² Δf_x Δf_y; bins beyond the unit disc are evanescent. The exact integral of the discrete
    spectrum: the polar quadrature of :func:`waveoptics.scatter.polar_albedo` (48 azimuths) samples a periodogram's
    narrow streaks (oriented scratches, gratings) by chance (a scratch field's TIS came out 26 % low, and the energy
    guard cut its lobe by that, 32-42 % with micro roughness).

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4 (TIS of the Rayleigh-Rice BRDF), §2.5 (the
       grating equation).
    """
    lam = float(wavelength_nm) * 1e-9
    FX, FY = np.meshgrid(psd.fx, psd.fy)
    w_i = np.array([np.sin(theta) * np.cos(azimuth), np.sin(theta) * np.sin(azimuth), np.cos(theta)])
    u, v = lam * FX - w_i[0], lam * FY - w_i[1]
    ok = u * u + v * v < 1.0
    if not ok.any():
        return 0.0
    wo = np.stack([u[ok], v[ok], np.sqrt(1.0 - u[ok] ** 2 - v[ok] ** 2)], axis=-1)
    wi = np.broadcast_to(w_i, wo.shape)
    dfx, dfy = float(psd.fx[1] - psd.fx[0]), float(psd.fy[1] - psd.fy[0])
    f = lobe(wi, wo, None)
    return float(np.sum(f) * lam * lam * dfx * dfy)


def rayleigh_rice_albedo(theta_deg, wavelength_nm, psd, material=None, polarization: str = "unpolarized",
                         azimuth_deg: float = 0.0) -> float:
    """E_RR(θ) = TIS(θ) / R(θ): the share of the specularly reflected light R (Fresnel, s, p or unpolarized; 1 for a
    perfect conductor) that first-order roughness scatters, with TIS = ∫ f_RR cosθ_o dω_o over the hemisphere
    (:func:`rayleigh_rice_tis`). On a conductor the coherent fraction of the two-scale model is 1 − E_RR (energy
    conservation; to first order 1 − E_RR = exp(−g) for a paraxial lobe, Church, Jenkinson & Zavada 1979); on a
    dielectric it is not (docs/physics.md §9). A 1-D array of incidences *theta_deg* gives E_RR at each.

    References
    ----------
    .. [1] E. L. Church, H. A. Jenkinson, J. M. Zavada, Opt. Eng. 18(2), 125–136, 1979 (TIS).
    .. [2] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4 (TIS of the Rayleigh-Rice BRDF).
    """
    import math

    tis = rayleigh_rice_tis(theta_deg, wavelength_nm, psd, material, polarization, azimuth_deg=azimuth_deg)
    if np.ndim(theta_deg) > 0:
        R = np.array([_specular_reflectance(math.radians(float(x)), float(wavelength_nm), material, polarization)
                      for x in np.ravel(theta_deg)])
        return tis / np.maximum(R, 1e-300)
    R = _specular_reflectance(math.radians(float(theta_deg)), float(wavelength_nm), material, polarization)
    return tis / max(R, 1e-300)
