"""Anisotropy by stretching (Heitz 2014, §5.3): the anisotropic D and Λ of an NDF defined isotropically (EPD, SGD),
and α(φ)² tan²θ of the closed-form anisotropic NDFs.

References
----------
.. [1] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014, §5.3.
"""
from __future__ import annotations

import numpy as np

__all__ = ['stretch_factors', 'D_stretched', 'Lambda_stretched', 'STRETCH_EXPONENT']


def tan2_stretched(w, ax, ay):
    """(α_x² w_x² + α_y² w_y²) / w_z², i.e. α(φ)² tan²θ, for w_z > 0 (else inf)."""
    wz = w[..., 2]
    num = (ax * w[..., 0]) ** 2 + (ay * w[..., 1]) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(wz > 0, num / np.where(wz > 0, wz * wz, 1.0), np.inf)



def stretch_factors(ax, ay, exponent):
    """(ᾱ, k_x, k_y) of the stretched form of an isotropic NDF: the base roughness ᾱ = √(α_x α_y) and the slope
    stretches k = (α/ᾱ)^e, where e is how the NDF's slope scale grows with α (1 for a slope scale α, as EPD;
    ½ for a tan²θ scale α, as SGD), so that along x the law has the slope scale of α_x and along y that of α_y.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3 (stretch invariance of the slope distribution and of Λ).
    """
    ax = np.asarray(ax, dtype=float)
    ay = ax if ay is None else np.asarray(ay, dtype=float)
    base = np.sqrt(ax * ay)
    return base, (ax / base) ** exponent, (ay / base) ** exponent


def D_stretched(D_iso, m, ax, ay, c, exponent):
    """D of the isotropic NDF *D_iso* stretched to (α_x, α_y), 1/sr.

    The slopes of the stretched surface are (k_x x̃, k_y ỹ) with (x̃, ỹ) distributed as the isotropic law of
    roughness ᾱ (:func:`stretch_factors`), so P22(x̃, ỹ) = P22_ᾱ(x̃/k_x, ỹ/k_y) / (k_x k_y); with D = P22 / cos⁴θ
    and m' ∝ (m_x/k_x, m_y/k_y, m_z) of norm n this is D(m) = D_ᾱ(m') / (n⁴ k_x k_y). Equal α gives *D_iso*.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3, eqs. (8) and (79).
    """
    if ay is None or np.all(np.asarray(ay) == np.asarray(ax)):
        return D_iso(m, ax, None, c)
    base, kx, ky = stretch_factors(ax, ay, exponent)
    v = np.stack([m[..., 0] / kx, m[..., 1] / ky, m[..., 2]], axis=-1)
    n = np.linalg.norm(v, axis=-1)
    return D_iso(v / n[..., None], base, None, c) / (n ** 4 * kx * ky)


def Lambda_stretched(Lambda_iso, w, ax, ay, c, exponent):
    """Smith Λ of the stretched NDF: the isotropic Λ of roughness ᾱ at the stretched direction
    (k_x w_x, k_y w_y, w_z) (its cot θ divided by the projected stretch √(k_x² cos²φ + k_y² sin²φ)).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3, eq. (80).
    """
    if ay is None or np.all(np.asarray(ay) == np.asarray(ax)):
        return Lambda_iso(w, ax, None, c)
    base, kx, ky = stretch_factors(ax, ay, exponent)
    v = np.stack([w[..., 0] * kx, w[..., 1] * ky, w[..., 2]], axis=-1)
    return Lambda_iso(v / np.linalg.norm(v, axis=-1, keepdims=True), base, None, c)


#: how each stretched NDF's slope scale grows with α (:func:`stretch_factors`)
STRETCH_EXPONENT = {"epd": 1.0, "sgd": 0.5}
