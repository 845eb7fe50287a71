"""The reciprocal grazing continuation of the tangent-plane (Kirchhoff family) nano lobe: beyond the tangent plane's
validity the lobe becomes the first-order Rayleigh-Rice lobe of the same PSD,

    f = W f_K + (1 − W) f_RR,    W = w(θ_i) w(θ_o),

in the frame of the surface that carries the nano-roughness (a micro facet's own frame in the two-scale model), w = 1
up to :data:`TANGENT_PLANE_BLEND_DEG` [0], falling smoothly (a cubic smoothstep in θ) to 0 at
:data:`TANGENT_PLANE_BLEND_DEG` [1]. Both lobes are reciprocal and W is symmetric in ω_i and ω_o, so the blend is
reciprocal (Helmholtz) at every pair, and at grazing incidence or exit it is the first-order lobe, exact as
kσ cosθ → 0 where grazing light puts every nano-roughness (Thorsos 1988; Thorsos & Jackson 1989).

f_RR is Rayleigh-Rice's lobe with the vector polarization factor Q of the material (Elson & Bennett 1979) for a
material with a complex index, Elson's first-order lobe of the rough stack for a thin-film stack (the nano PSD on
every interface, correlated as the stack says; :func:`waveoptics.scatter.rough_stack_brdf`), and the scalar first
order of a reflection coefficient of modulus 1 (the Dirichlet problem, Q = 1, whose tangent-plane approximation is
the Kirchhoff lobe with F = 1) times the Kirchhoff family's Fresnel factor for F = 1 and for materials that give only
F0. For a stack the blended lobe's albedo is Elson's first-order TIS within 1.2 % from 80° (Al|Al2O3:120nm and
1.5|TiO2:60nm, ABC σ 5 nm; tests/test_stack_grazing_energy.py); inside the window the Kirchhoff lobe with the stack's
F is itself 2.0x that TIS at 75° (Al|Al2O3:120nm), so the blend there is 1.33-1.41x first order.

Measured (Al at 550 nm, unpolarized, the lobe's scattered share E = ∫ f cosθ_o dω_o / R against Rayleigh-Rice's
TIS/R written from Q): ABC σ = 10 nm, B = 3 µm, C = 2.8: 0.978 / 0.980 / 0.961 / 1.003 / 1.000 / 1.000 at θ_i = 0 / 30 /
60 / 75 / 80 / 85° (the Kirchhoff lobe alone: 0.986 / 0.991 / 0.986 / 1.055 / 1.278 / 2.551); Gaussian σ = 5 nm,
T = 1 µm: 0.993 / 0.996 / 1.007 / 1.037 / 1.000 / 1.000. With the window at (75°, 85°) the share at 80° is 1.10,
at (80°, 88°) 1.22 and at 85° 1.45: the tangent-plane lobe is already 28 % above first order at 80°.

References
----------
.. [1] E. I. Thorsos, "The validity of the Kirchhoff approximation for rough surface scattering using a Gaussian
   roughness spectrum", JASA 83(1), 78–92, 1988 (the tangent plane fails towards grazing angles).
.. [2] E. I. Thorsos, D. R. Jackson, "The validity of the perturbation approximation for rough surface scattering
   using a Gaussian roughness spectrum", JASA 86(1), 261–277, 1989 (first order holds as kσ cosθ → 0).
.. [3] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979 (Q).
.. [4] H. von Helmholtz; F. E. Nicodemus et al., NBS Monograph 160, 1977 (reciprocity of the BRDF).
.. [5] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (first order of rough stacks).
"""
from __future__ import annotations

import numpy as np

from .perturbation import is_stack, rayleigh_rice_lobe
from .series import rayleigh_rice

__all__ = ["TANGENT_PLANE_BLEND_DEG", "tangent_plane_weight", "blend_weight", "uses_vector_first_order",
           "first_order_lobe", "first_order_over_fresnel", "blend_with_first_order"]

#: local angles (degrees) of incidence or exit between which the tangent-plane lobe hands over to first order: up to
#: the first the Kirchhoff lobe is kept, beyond the second it is the Rayleigh-Rice lobe (module doc for the measure)
TANGENT_PLANE_BLEND_DEG = (70.0, 80.0)


def tangent_plane_weight(cos_theta) -> np.ndarray:
    """w(θ): 1 up to :data:`TANGENT_PLANE_BLEND_DEG` [0], 0 beyond [1], the cubic smoothstep 1 − x²(3 − 2x) of
    x = (θ − θ_0)/(θ_1 − θ_0) between (continuous with its first derivative)."""
    t0, t1 = TANGENT_PLANE_BLEND_DEG
    theta = np.degrees(np.arccos(np.clip(np.asarray(cos_theta, dtype=float), -1.0, 1.0)))
    x = np.clip((theta - t0) / (t1 - t0), 0.0, 1.0)
    return 1.0 - x * x * (3.0 - 2.0 * x)


def blend_weight(wi, wo) -> np.ndarray:
    """W = w(θ_i) w(θ_o) of unit directions (..., 3) in the frame of the nano-rough surface: symmetric in ω_i, ω_o."""
    return tangent_plane_weight(np.asarray(wi)[..., 2]) * tangent_plane_weight(np.asarray(wo)[..., 2])


def uses_vector_first_order(material) -> bool:
    """Whether the first-order lobe carries the material's own vector factor (Q of a material with one complex
    permittivity; Elson's rough-stack factor of a thin-film stack) or is the scalar Q = 1 lobe times the Kirchhoff
    family's Fresnel factor (None: F = 1; F0 only)."""
    if is_stack(material):
        return True
    return (material is not None and bool(getattr(material, "has_index", True))
            and not bool(getattr(material, "schlick_only", False)))


def first_order_lobe(wi, wo, wavelength_nm, psd, material=None, polarization: str = "unpolarized"):
    """The Rayleigh-Rice lobe (1/sr) the tangent-plane lobe hands over to: with the material's vector Q, or Elson's
    rough-stack lobe of a stack (:func:`waveoptics.scatter.rayleigh_rice_lobe`) where
    :func:`uses_vector_first_order`, else the scalar Q = 1 lobe
    (16π²/λ⁴) cosθ_i cosθ_o S, to be multiplied by the Kirchhoff family's Fresnel factor as that lobe is."""
    if uses_vector_first_order(material):
        return rayleigh_rice_lobe(wi, wo, wavelength_nm, psd, material, polarization)
    return rayleigh_rice(wi, wo, wavelength_nm, psd)


def blend_with_first_order(f_k, wi, wo, wavelength_nm, psd, material=None, polarization: str = "unpolarized",
                           fresnel=None):
    """W f_K + (1 − W) f_RR / F: the blended lobe *without* the Kirchhoff family's Fresnel factor F, which the
    caller multiplies in as it does for f_K (module doc).

    Parameters
    ----------
    f_k : ndarray
        The tangent-plane lobe without its Fresnel factor (K × the PSD series), broadcast with the directions.
    wi, wo : ndarray (..., 3)
        Directions in the frame of the nano-rough surface.
    fresnel : ndarray, callable or None
        F of each pair (the factor the caller applies), or a function F(ω_i, ω_o) of the pairs (n, 3) where W < 1;
        needed where :func:`uses_vector_first_order`: f_RR carries its own Q, so it is divided by F here (0 where
        F = 0, where the caller's product is 0 whatever it holds).

    Returns
    -------
    ndarray
        The blended lobe over F; f_RR is evaluated only where W < 1.
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    W = np.broadcast_to(blend_weight(wi, wo), np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1], np.shape(f_k)))
    out = W * f_k
    far = W < 1.0
    if not np.any(far):
        return out
    wi_b = np.broadcast_to(wi, far.shape + (3,))[far]
    wo_b = np.broadcast_to(wo, far.shape + (3,))[far]
    fr = (fresnel if callable(fresnel) or fresnel is None
          else np.broadcast_to(np.asarray(fresnel, dtype=float), far.shape)[far])
    out = np.array(out, dtype=float)
    out[far] += (1.0 - W[far]) * first_order_over_fresnel(wi_b, wo_b, wavelength_nm, psd, material, polarization, fr)
    return out


def first_order_over_fresnel(wi, wo, wavelength_nm, psd, material=None, polarization: str = "unpolarized",
                             fresnel=None):
    """f_RR / F of :func:`blend_with_first_order` at paired directions (n, 3): the first-order lobe over the
    Kirchhoff family's Fresnel factor F the caller applies (divided only where :func:`uses_vector_first_order`: the
    lobe carries its own Q; 0 where F = 0). *fresnel*: F per pair (n,) or a function F(ω_i, ω_o). The blend is
    W f_K + (1 − W) × this, so a table may hold this and f_K − this apart and apply W at the exact directions
    (:func:`waveoptics.brdf.facet_frame_diffraction`)."""
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    rr = np.asarray(first_order_lobe(wi, wo, wavelength_nm, psd, material, polarization), dtype=float)
    if uses_vector_first_order(material):
        F = np.asarray(fresnel(wi, wo) if callable(fresnel) else fresnel, dtype=float)
        rr = np.where(F > 0, rr / np.where(F > 0, F, 1.0), 0.0)
    return rr
