"""Geometric-optics microfacet BRDF: NDFs, masking-shadowing, Fresnel, diffuse terms and their quadrature.

The specular term of Cook & Torrance (1982) in the normalization of Walter et al. (2007),

    f_s(l, v) = F(v·h) G(l, v, h) D(h) / (4 (n·l)(n·v)),   h = (l + v) / |l + v|,

with a choice of normal distribution function D (:data:`NDFS`), masking-shadowing term G (:data:`SHADOWINGS`)
and Fresnel factor F (:data:`FRESNELS`), plus a Lambertian or Oren-Nayar diffuse term that receives only the
light the specular interface did not reflect (:func:`diffuse_tradeoff`).

Conventions
-----------
* Directions are unit vectors ``(..., 3)`` in the local frame of the macro surface, z the normal n.
  ``wi`` (= l) points towards the light, ``wo`` (= v) towards the viewer. Arrays broadcast against each other
  and against per-wavelength parameters (``eta``, ``F0``, ``kd`` of shape ``(n_wavelengths, 1)`` with
  directions of shape ``(n, 3)`` give results of shape ``(n_wavelengths, n)``).
* The BRDF is only defined with both directions above the surface; every function returns exactly 0 when
  ``wi_z <= 0`` or ``wo_z <= 0`` (never NaN).
* Roughness is the slope-scale α of the NDF (α is the rms slope for Beckmann). The "perceptual roughness" r of
  Burley (2012) maps to α = r² (:func:`alpha_from_roughness`). The Blinn-Phong exponent is derived from α by
  Walter et al.'s equivalence α_p = 2/α² − 2 (:func:`blinn_phong_exponent`), so every NDF takes the same α.
* α is floored at :data:`ALPHA_MIN` (a mirror is a delta function, which a BRDF evaluated at sampled
  directions cannot represent); α = 0 is therefore accepted and means "as sharp as representable".
* Units: BRDF values in 1/sr; angles in radians in this module (degrees only on the command line);
  wavelengths in nm.

OpenCL twins: ``kernels/microfacet.h`` holds the device functions with the same names (``D_ggx``, ``Lambda``,
``G1``, ``G``, ``specular``, ``oren_nayar``, ``brdf`` ...), selected by ``-D`` switches; ``kernels/microfacet.cl``
evaluates them in bulk through :func:`D_cl`, :func:`Lambda_cl` and :func:`brdf_cl`.

References
----------
.. [1] R. L. Cook, K. E. Torrance, "A Reflectance Model for Computer Graphics", ACM TOG 1(1):7-24, 1982.
.. [2] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007.
.. [3] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2):48-107,
   2014.
.. [4] J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF Models for Accurate and Efficient Rendering of
   Glossy Surfaces", ACM TOG 31(1):9, 2012.
.. [5] M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994, 239-246.
.. [6] P. Shirley, H. Hu, B. Smits, E. Lafortune, "A Practitioners' Assessment of Light Reflection Models",
   Pacific Graphics 1997.
.. [7] M. Ashikhmin, P. Shirley, "An Anisotropic Phong BRDF Model", Journal of Graphics Tools 5(2):25-32, 2000.
.. [8] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes.
.. [9] T. S. Trowbridge, K. P. Reitz, "Average irregularity representation of a rough surface for ray
   reflection", JOSA 65(5):531-536, 1975.
"""
from __future__ import annotations

import numpy as np

from ..errors import WaveopticsError, renamed_keywords, unknown
from ..vocabulary import DEFAULT_NDF
from ..materials.database import get_material
from ..units import check_wavelengths
from .diffuse import DIFFUSES, diffuse_parameter, diffuse_tradeoff, sigma_renamed
from .fresnel_terms import FRESNELS, MaterialFresnel, fresnel_fn
from .directions import as_dirs, dot_last, half_vector
from .ndf import COS_MIN, check_alpha, ndf_by_name
from .shadowing import shadowing_by_name

__all__ = ['specular', 'brdf', 'fresnel_inputs', 'spectral_brdf']

# ----------------------------------------------------------------------------------------------------------
# Fresnel factor


# ----------------------------------------------------------------------------------------------------------
# the specular term


def specular(wi, wo, *, alpha, alpha_y=None, ndf=DEFAULT_NDF, shadowing="smith-correlated", fresnel="exact",
             eta=None, F0=None, ndf_shape=None):
    """Microfacet specular BRDF F(v·h) G(l, v, h) D(h) / (4 (n·l)(n·v)) in 1/sr.

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light (l) and to the viewer (v); they broadcast.
    alpha, alpha_y, ndf, ndf_shape
        NDF and its roughness, as in :func:`D`.
    shadowing : str
        One of :data:`SHADOWINGS`.
    fresnel : str
        ``"exact"`` (needs *eta*), ``"schlick"`` (needs *F0* or *eta*) or ``"one"`` (F = 1, white furnace).
    eta : array_like of complex, optional
        Relative index n + ik of the surface, broadcasting with the direction batch (e.g. shape (n_λ, 1)).
    F0 : array_like, optional
        Normal-incidence reflectance for Schlick.

    Returns
    -------
    ndarray
        f_s ≥ 0 in 1/sr, shape of the broadcast batch; 0 where wi_z <= 0 or wo_z <= 0.

    References
    ----------
    .. [1] R. L. Cook, K. E. Torrance, ACM TOG 1(1), 1982, eq. (4) (with 4 for π as corrected in [2]).
    .. [2] B. Walter et al., EGSR 2007, eq. (20).
    """
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    gfn, _ = shadowing_by_name(shadowing)
    F_fn = fresnel_fn(fresnel, eta, F0)
    wi = as_dirs(wi, "wi")
    wo = as_dirs(wo, "wo")
    wi, wo = np.broadcast_arrays(wi, wo)
    return specular_term(wi, wo, spec, ax, ay, ndf_shape, gfn, F_fn)


def specular_geometry(wi, wo, spec, ax, ay, c, gfn) -> tuple:
    """The factors of :func:`specular_term` that do not depend on the wavelength: (cos θ_d, G, D, the floored
    denominator 4 cos θ_i cos θ_o, the mask of the pairs that reflect), to be shared by several wavelengths."""
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    h = half_vector(wi, wo)
    cos_d = np.clip(dot_last(wi, h), 0.0, 1.0)
    g = gfn(wi, wo, h, lambda w: spec.Lambda(w, ax, ay, c))
    d = spec.D(h, ax, ay, c)
    # guard: f grows like 1/cos θ towards the horizon (G ~ cos θ / α); flooring the cosines of the denominator
    # at COS_MIN bounds f (below float32 overflow for α >= ALPHA_MIN) and only changes θ > 89.999994°, where
    # f then goes continuously to 0 with G
    denom = 4.0 * np.where(up, np.maximum(wi[..., 2], COS_MIN) * np.maximum(wo[..., 2], COS_MIN), 1.0)
    # guard: 0 below the surface (and in the product of 0 and a huge D at exactly grazing directions)
    return cos_d, g, d, denom, up & (g > 0)


def specular_term(wi, wo, spec, ax, ay, c, gfn, F_fn, geometry=None):
    """F G D / (4 cos θ_i cos θ_o) (1/sr); *geometry* the pairs' :func:`specular_geometry` when already known."""
    cos_d, g, d, denom, ok = specular_geometry(wi, wo, spec, ax, ay, c, gfn) if geometry is None else geometry
    val = F_fn(cos_d) * g * d / denom
    return np.where(ok, val, 0.0)


# ----------------------------------------------------------------------------------------------------------
# the whole BRDF


@renamed_keywords(sigma=sigma_renamed)   # the old keyword held either diffuse roughness
def brdf(wi, wo, *, alpha, alpha_y=None, ndf=DEFAULT_NDF, shadowing="smith-correlated", fresnel="exact", eta=None,
         F0=None, ndf_shape=None, diffuse="lambert", kd=0.0, diffuse_sigma=0.0, diffuse_roughness=0.0, tradeoff=True):
    """Microfacet BRDF f = f_s + w f_d: specular lobe plus an optional diffuse term, in 1/sr (not × cos).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions to the light and to the viewer (normalized here; they broadcast).
    alpha, alpha_y, ndf, ndf_shape
        Specular NDF and roughness (see :func:`D`).
    shadowing : str
        ``"smith"``, ``"smith-correlated"``, ``"cook-torrance"`` or ``"implicit"``.
    fresnel : str or MaterialFresnel
        ``"exact"``, ``"schlick"`` or ``"one"``; or a material's own F(cos θ) (a thin-film stack,
        :func:`fresnel_inputs`), in place of *eta*.
    eta : array_like of complex, optional
        Complex index n + ik (per wavelength: shape (n_λ, 1) against directions (n, 3)).
    F0 : array_like, optional
        Normal-incidence reflectance (Schlick).
    diffuse : str
        ``"none"``, ``"lambert"``, ``"oren-nayar"`` or ``"burley"`` (Burley 2012).
    kd : array_like
        Diffuse albedo in [0, 1] (0: no diffuse term; metals have none).
    diffuse_sigma : float, rad
        Oren-Nayar's roughness σ (the slope angle of its V-grooves, ≥ 0; ``diffuse="oren-nayar"`` only).
    diffuse_roughness : float
        Burley's roughness r in [0, 1] (``diffuse="burley"`` only). Both are separate from the specular α.
    tradeoff : bool
        Weight the diffuse term by :func:`diffuse_tradeoff` (energy conservation between the two terms).

    Returns
    -------
    ndarray
        f ≥ 0 in 1/sr; 0 for directions below the surface.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007 (specular term).
    .. [2] P. Shirley et al., Pacific Graphics 1997 (diffuse-specular coupling).
    .. [3] M. Oren, S. K. Nayar, SIGGRAPH 1994 (rough diffuse).
    .. [4] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes (r).
    """
    spec = ndf_by_name(ndf)
    ax, ay = check_alpha(alpha, alpha_y, spec, ndf_shape)
    gfn, _ = shadowing_by_name(shadowing)
    F_fn = fresnel_fn(fresnel, eta, F0)
    if diffuse not in DIFFUSES:
        raise unknown("diffuse model", diffuse, DIFFUSES)
    kd = np.asarray(kd, dtype=float)
    if np.any(~np.isfinite(kd) | (kd < 0) | (kd > 1)):
        raise WaveopticsError(f"kd={np.asarray(kd).tolist()!r} is not allowed; the diffuse albedo must be in [0, 1]")
    sigma = diffuse_parameter(diffuse, diffuse_sigma, diffuse_roughness)
    wi = as_dirs(wi, "wi")
    wo = as_dirs(wo, "wo")
    wi, wo = np.broadcast_arrays(wi, wo)
    f = specular_term(wi, wo, spec, ax, ay, ndf_shape, gfn, F_fn)
    if diffuse != "none" and np.any(kd > 0):
        fd = DIFFUSES[diffuse][0](wi, wo, kd, sigma)
        if tradeoff:
            # F̄ must broadcast like F(θ): as many axes as the directions' batch or the Fresnel parameters
            nb = max(wi.ndim - 1, np.ndim(eta) if eta is not None else 0, np.ndim(F0) if F0 is not None else 0)
            fd = fd * diffuse_tradeoff(wi, wo, F_fn, batch_ndim=nb)
        f = f + fd
    return f


def fresnel_inputs(material, wavelength_nm, fresnel="exact") -> dict:
    """Per-wavelength Fresnel inputs of a material for :func:`brdf` / :func:`brdf_cl`.

    Parameters
    ----------
    material : str or waveoptics.materials.Material
        Anything :func:`waveoptics.materials.get_material` accepts.
    wavelength_nm : array_like
        Wavelengths in nm (1-D).
    fresnel : str
        ``"exact"`` or ``"schlick"`` (``"one"`` gives F = 1). F0-only materials always use Schlick.

    Returns
    -------
    dict
        ``{"fresnel": str, "eta": complex array (n_λ,) or None, "F0": array (n_λ,) or None}``; for a thin-film
        stack (exact) ``"fresnel"`` is a :class:`~waveoptics.brdf.fresnel_terms.MaterialFresnel` of the wavelengths
        (n_λ,), which the NumPy :func:`brdf` takes in place of a name and *eta*.
    """

    mat = get_material(material)
    w = check_wavelengths(wavelength_nm)
    if fresnel not in FRESNELS:
        raise unknown("Fresnel model", fresnel, FRESNELS)
    if fresnel == "one":
        return {"fresnel": "one", "eta": None, "F0": None}
    if mat.schlick_only or fresnel == "schlick":
        return {"fresnel": "schlick", "eta": None, "F0": np.asarray(mat.F0(w), dtype=float)}
    if not mat.has_index:   # a thin-film stack: its own F(cos θ, λ), NumPy only
        return {"fresnel": MaterialFresnel(mat, w), "eta": None, "F0": None}
    return {"fresnel": "exact", "eta": mat.eta(w), "F0": None}


def spectral_brdf(wi, wo, wavelength_nm, material, *, fresnel="exact", **kwargs):
    """:func:`brdf` for a material at several wavelengths: result shape (n_λ, *batch).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions (broadcasting batch).
    wavelength_nm : array_like
        Wavelengths in nm (1-D).
    material : str or Material
        Any specification accepted by :func:`waveoptics.materials.get_material`.
    fresnel : str
        ``"exact"`` (Material.F: exact for indices, Schlick for F0-only materials) or ``"schlick"``.
    **kwargs
        The other parameters of :func:`brdf`; ``kd`` may be per wavelength (shape (n_λ,)).
    """
    fi = fresnel_inputs(material, wavelength_nm, fresnel)
    wi = np.asarray(wi, dtype=float)
    wo = np.asarray(wo, dtype=float)
    nb = max(wi.ndim, wo.ndim) - 1
    shape = (-1,) + (1,) * nb
    eta = None if fi["eta"] is None else fi["eta"].reshape(shape)
    F0 = None if fi["F0"] is None else fi["F0"].reshape(shape)
    if isinstance(fi["fresnel"], MaterialFresnel):
        fi["fresnel"] = fi["fresnel"].reshape(shape)
    kd = np.asarray(kwargs.pop("kd", 0.0), dtype=float)
    if kd.ndim == 1:
        kd = kd.reshape(shape)
    n_w = np.atleast_1d(np.asarray(wavelength_nm)).size
    out = brdf(wi[None], wo[None], fresnel=fi["fresnel"], eta=eta, F0=F0, kd=kd, **kwargs)
    return np.broadcast_to(out, (n_w,) + out.shape[1:])
