"""Diffuse terms: Lambert, Oren-Nayar, and the diffuse-specular energy trade-off.

References
----------
.. [1] M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994.
.. [2] P. Shirley, H. Hu, B. Smits, E. Lafortune, "A Practitioners' Assessment of Light Reflection Models",
   Pacific Graphics 1997.
.. [3] M. Ashikhmin, P. Shirley, "An Anisotropic Phong BRDF Model", JGT 5(2), 2000.
.. [4] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes, §5.3 (diffuse).
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import WaveopticsError
from .fresnel_terms import F_mean
from .directions import as_dirs

__all__ = ['lambert', 'oren_nayar', 'burley', 'diffuse_tradeoff', 'diffuse_parameter', 'sigma_renamed', 'DIFFUSES']

# ----------------------------------------------------------------------------------------------------------
# diffuse terms


def lambert(wi, wo, kd=1.0):
    """Lambertian BRDF kd/π (1/sr) for both directions above the surface, else 0.

    Parameters
    ----------
    kd : array_like
        Diffuse albedo c in [0, 1] (may vary with wavelength; broadcasts with the batch).

    References
    ----------
    .. [1] J. H. Lambert, *Photometria*, 1760.
    """
    wi = as_dirs(wi, "wi")
    wo = as_dirs(wo, "wo")
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    return np.where(up, np.asarray(kd, dtype=float) / np.pi, 0.0)


def diffuse_parameter(diffuse: str, diffuse_sigma: float, diffuse_roughness: float) -> float:
    """The roughness the diffuse model *diffuse* takes (:data:`DIFFUSES`): Burley's r (*diffuse_roughness*, in
    [0, 1]) for ``"burley"``, else Oren-Nayar's σ (*diffuse_sigma*, radians ≥ 0; Lambert ignores it).

    References
    ----------
    .. [1] M. Oren, S. K. Nayar, SIGGRAPH 1994 (σ). B. Burley, SIGGRAPH 2012 course notes (r).
    """
    sigma, r = float(diffuse_sigma), float(diffuse_roughness)
    if not np.isfinite(sigma) or sigma < 0:
        raise WaveopticsError(f"diffuse_sigma={sigma!r} is not allowed; the Oren-Nayar roughness σ must be >= 0 "
                              "radians")
    if not np.isfinite(r) or not 0 <= r <= 1:
        raise WaveopticsError(f"diffuse_roughness={r!r} is not allowed; Burley's roughness r must be in [0, 1]")
    return r if diffuse == "burley" else sigma


def sigma_renamed(kwargs: dict) -> str:
    """The keyword that replaced the old ``sigma=`` of :func:`waveoptics.brdf.brdf` and ``brdf_cl`` for the call's
    *diffuse* model: it held Oren-Nayar's σ (radians) or Burley's r, now ``diffuse_sigma`` and ``diffuse_roughness``
    (one name per quantity)."""
    diffuse = kwargs.get("diffuse")
    if diffuse == "burley":
        return "diffuse_roughness= (Burley's r in [0, 1])"
    if diffuse == "oren-nayar":
        return "diffuse_sigma= (Oren-Nayar's σ in radians)"
    return "diffuse_sigma= (Oren-Nayar's σ in radians) or diffuse_roughness= (Burley's r in [0, 1])"


def oren_nayar(wi, wo, kd=1.0, sigma=0.0):
    """Oren-Nayar rough-diffuse BRDF (the qualitative model), in 1/sr.

        f = (kd/π) [A + B max(0, cos(φ_i − φ_o)) sin α tan β],  α = max(θ_i, θ_o), β = min(θ_i, θ_o),
        A = 1 − 0.5 σ²/(σ² + 0.33),  B = 0.45 σ²/(σ² + 0.09),

    computed from the vectors as max(0, wi_xy·wo_xy)/max(cos θ_i, cos θ_o) for the cos Δφ sin α tan β product
    (reciprocal, no division by zero).

    Parameters
    ----------
    kd : array_like
        Albedo ρ of the facets in [0, 1].
    sigma : float
        Standard deviation of the facet slope angle, radians (0 gives Lambert). This is the diffuse roughness,
        independent of the specular α.

    Notes
    -----
    The qualitative model is an approximation of the V-cavity model with interreflections dropped; it is not
    exactly energy conserving: with kd = 1 its directional albedo is A ≤ 1 at normal incidence but rises to
    about A + B/2 at grazing incidence, slightly above 1 for σ ≈ 0.2-0.4 (see ``docs/microfacet.md``).

    References
    ----------
    .. [1] M. Oren, S. K. Nayar, "Generalization of Lambert's Reflectance Model", SIGGRAPH 1994, eq. (30).
    """
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma < 0:
        raise WaveopticsError(f"sigma={sigma!r} is not allowed; the Oren-Nayar roughness must be >= 0 radians")
    wi = as_dirs(wi, "wi")
    wo = as_dirs(wo, "wo")
    return _oren_nayar(wi, wo, kd, sigma)


def _oren_nayar(wi, wo, kd, sigma):
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    cmax = np.where(up, np.maximum(wi[..., 2], wo[..., 2]), 1.0)
    proj = np.maximum(0.0, wi[..., 0] * wo[..., 0] + wi[..., 1] * wo[..., 1])
    return np.where(up, np.asarray(kd, dtype=float) / np.pi * (A + B * proj / cmax), 0.0)


def burley(wi, wo, kd=1.0, roughness=0.5):
    """Burley's ("Disney") diffuse BRDF, in 1/sr:

        f = (kd/π) (1 + (F_D90 − 1)(1 − cos θ_i)⁵) (1 + (F_D90 − 1)(1 − cos θ_o)⁵),
        F_D90 = 0.5 + 2 r cos²θ_d,  cos θ_d = ω_i·h,

    with a diffuse roughness r in [0, 1] separate from the specular α: r = 0 darkens the grazing edges (a
    Fresnel-like loss entering and leaving a smooth surface), r = 1 brightens them (retro-reflection of rough
    surfaces). Reciprocal. It is an empirical fit to measured materials (MERL), not energy conserving: measured
    directional albedo with kd = 1 (``tests/test_microfacet.py``) is 0.976 (r = 0) to 1.036 (r = 1) at normal
    incidence, and 0.53 (r = 0) to 1.52 (r = 1) at θ_i = 89°; r = 0.5 stays within 1.00-1.03. Burley uses it
    *instead of* a Fresnel trade-off, so pass ``tradeoff=False`` to :func:`waveoptics.brdf.brdf` to reproduce the
    Disney model.

    Parameters
    ----------
    kd : array_like
        Base colour (diffuse albedo at normal incidence for F_D90 = 1) in [0, 1].
    roughness : float
        Diffuse roughness r in [0, 1] (dimensionless).

    References
    ----------
    .. [1] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes, §5.3, eq. on p. 14.
    """
    r = float(roughness)
    if not np.isfinite(r) or not 0 <= r <= 1:
        raise WaveopticsError(f"roughness={roughness!r} is not allowed; the Burley diffuse roughness must be in "
                              "[0, 1]")
    return _burley(as_dirs(wi, "wi"), as_dirs(wo, "wo"), kd, r)


def _burley(wi, wo, kd, r):
    up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    s = wi + wo
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    h = s / np.where(n > 0, n, 1.0)
    cos_d = np.clip(np.sum(wi * h, axis=-1), 0.0, 1.0)
    fd90 = 0.5 + 2.0 * r * cos_d * cos_d
    ci = np.clip(wi[..., 2], 0.0, 1.0)
    co = np.clip(wo[..., 2], 0.0, 1.0)
    val = (np.asarray(kd, dtype=float) / np.pi * (1.0 + (fd90 - 1.0) * (1.0 - ci) ** 5)
           * (1.0 + (fd90 - 1.0) * (1.0 - co) ** 5))
    return np.where(up, val, 0.0)


def diffuse_tradeoff(wi, wo, F_fn: Callable, batch_ndim: int = 0):
    """Energy-conserving weight of the diffuse term: (1 − F(θ_i))(1 − F(θ_o)) / (1 − F̄).

    The diffuse layer receives only the light the interface did not reflect, 1 − F(θ_i), and its light leaves
    through the interface with weight 1 − F(θ_o) (reciprocity), renormalized so that the diffuse albedo is
    exactly kd (1 − F(θ_i)) for a Lambertian layer: F̄ = 2∫ F(μ) μ dμ (:func:`F_mean`). With Schlick's F this is
    Shirley et al.'s coupled model, f_d = 21/(20π) kd (1 − F0)(1 − (1 − cos θ_i)⁵)(1 − (1 − cos θ_o)⁵), and
    Ashikhmin & Shirley (2000) use the same structure with a different constant; here F is the exact spectral
    Fresnel factor. The weight goes to 0 at grazing incidence or exitance, where F → 1.

    Returns
    -------
    ndarray
        Weight ≥ 0 (dimensionless); 0 where F̄ = 1 (nothing enters the surface).

    References
    ----------
    .. [1] P. Shirley, H. Hu, B. Smits, E. Lafortune, Pacific Graphics 1997, eq. (7).
    .. [2] M. Ashikhmin, P. Shirley, JGT 5(2), 2000, eq. (5).
    """
    Fi = F_fn(np.clip(wi[..., 2], 0.0, 1.0))
    Fo = F_fn(np.clip(wo[..., 2], 0.0, 1.0))
    Fbar = F_mean(F_fn, batch_ndim)
    t = 1.0 - Fbar
    return np.where(t > 0, (1.0 - Fi) * (1.0 - Fo) / np.where(t > 0, t, 1.0), 0.0)


#: diffuse terms by name: callables (wi, wo, kd, p) and kernel switch values; p is the diffuse roughness in the
#: model's own unit (Oren-Nayar σ in radians, Burley r in [0, 1], unused by Lambert)
DIFFUSES: dict[str, tuple[Callable, int]] = {
    "none": (lambda wi, wo, kd, sigma: np.zeros(np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1])), 0),
    "lambert": (lambda wi, wo, kd, sigma: _oren_nayar(wi, wo, kd, 0.0), 1),
    "oren-nayar": (_oren_nayar, 2),
    "burley": (_burley, 3),
}
