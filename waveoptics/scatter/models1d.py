"""The project's scattering models written for 1-D Gaussian surfaces, to be held against the method of moments.

A 1-D surface z = h(x) with Gaussian correlation σ² exp(−τ²/ℓ²) (two-sided PSD W(K) = σ²ℓ/(2√π) e^{−K²ℓ²/4}),
light in the x–z plane at θᵢ, scattered to θₛ (specular at θₛ = θᵢ, the convention of :mod:`.mom`). Both models
return the incoherent scattering coefficient σ(θₛ) normalized as in :mod:`.mom` (power per radian over the
incident power: ∫σ dθₛ is the diffuse reflectance) and the coherent (specular) reflectance.

* Kirchhoff (tangent plane, stationary phase; the 1-D Beckmann-Spizzichino series). With v = k(sinθₛ − sinθᵢ,
  cosθᵢ + cosθₛ), F = (1 + cos(θᵢ + θₛ))/(cosθᵢ + cosθₛ) and the Fresnel amplitude r at the local angle
  (θᵢ + θₛ)/2 of the facet that reflects θᵢ into θₛ:

      σ_KA = kℓ |r|² F² / (2√π cosθᵢ) · e^{−g} Σ_{m≥1} g^m/(m! √m) e^{−vₓ²ℓ²/(4m)},   g = v_z²σ²,
      coherent reflectance |r(θᵢ)|² e^{−(2kσ cosθᵢ)²}.

  (Thorsos 1988 for the perfect conductor, where |r| = 1; the Fresnel factor at the specular-facet
  angle is Beckmann & Spizzichino's.)
* First-order perturbation (Rayleigh-Rice, 1-D): σ_SPM = 4k³ cosθᵢ cos²θₛ |α|² W(vₓ), with
  α_s = (ε − 1)/((cosθᵢ + qᵢ)(cosθₛ + qₛ)), α_p = (ε − 1)(ε sinθᵢ sinθₛ − qᵢqₛ)/((ε cosθᵢ + qᵢ)(ε cosθₛ + qₛ)),
  q = √(ε − sin²θ); for a perfect conductor |α_s| = 1 (Dirichlet: 4k³ cosθᵢ cos²θₛ W) and
  |α_p| = (1 − sinθᵢ sinθₛ)/(cosθᵢ cosθₛ) (Neumann: 4k³ (1 − sinθᵢ sinθₛ)² W / cosθᵢ). Coherent reflectance:
  |r(θᵢ)|² e^{−(2kσ cosθᵢ)²} (the same Debye-Waller factor, docs/physics.md § 2).

References
----------
.. [1] E. I. Thorsos, "The validity of the Kirchhoff approximation for rough surface scattering using a Gaussian
   roughness spectrum", J. Acoust. Soc. Am. 83(1), 78–92, 1988.
.. [2] E. I. Thorsos, D. R. Jackson, "The validity of the perturbation approximation for rough surface scattering
   using a Gaussian roughness spectrum", J. Acoust. Soc. Am. 86(1), 261–277, 1989.
.. [3] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon 1963.
.. [4] S. O. Rice, "Reflection of electromagnetic waves from slightly rough surfaces", Comm. Pure Appl. Math. 4,
   351–378, 1951.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import special

__all__ = ["fresnel_amplitude_1d", "kirchhoff_1d", "spm1_1d"]


def _q(eps, s):
    r = np.sqrt(eps - s * s + 0j)
    return np.where(r.imag < 0, -r, r)


def fresnel_amplitude_1d(theta_rad, refractive_index, polarization):
    """Fresnel amplitude of ψ (E_y for s, H_y for p) at incidence *theta_rad*; −1 (s) or +1 (p) for a perfect
    conductor (refractive_index None).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., § 1.5.2.
    """
    c, s = np.cos(theta_rad), np.sin(theta_rad)
    if refractive_index is None:
        return np.full(np.shape(c), -1.0 if polarization == "s" else 1.0) + 0j
    e = complex(refractive_index) ** 2
    q = _q(e, s)
    return (c - q) / (c + q) if polarization == "s" else (e * c - q) / (e * c + q)


def kirchhoff_1d(theta_i_deg, theta_s_deg, k_sigma, k_ell, polarization="s", refractive_index=None):
    """(σ_KA(θₛ), coherent reflectance) of the 1-D Kirchhoff model (module doc); k_sigma = kσ, k_ell = kℓ.

    References
    ----------
    .. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988.
    .. [2] P. Beckmann, A. Spizzichino, 1963, ch. 5.
    """
    ti, ts = math.radians(theta_i_deg), np.radians(np.asarray(theta_s_deg, float))
    ci, cs = math.cos(ti), np.cos(ts)
    vx_l = k_ell * (np.sin(ts) - math.sin(ti))
    g = (k_sigma * (ci + cs)) ** 2
    F = (1 + np.cos(ti + ts)) / (ci + cs)
    r2 = np.abs(fresnel_amplitude_1d((ti + ts) / 2, refractive_index, polarization)) ** 2
    m_max = int(np.max(g) + 12 * math.sqrt(np.max(g)) + 30)
    m = np.arange(1, m_max + 1)[:, None]
    with np.errstate(divide="ignore"):
        terms = np.exp(-g + m * np.log(g) - special.gammaln(m + 1) - 0.5 * np.log(m) - vx_l ** 2 / (4 * m))
    series = np.where(g > 0, terms.sum(axis=0), 0.0)
    sigma = k_ell * r2 * F ** 2 / (2 * math.sqrt(math.pi) * ci) * series
    coherent = float(np.abs(fresnel_amplitude_1d(ti, refractive_index, polarization)) ** 2
                     * math.exp(-(2 * k_sigma * ci) ** 2))
    return sigma, coherent


def spm1_1d(theta_i_deg, theta_s_deg, k_sigma, k_ell, polarization="s", refractive_index=None):
    """(σ_SPM(θₛ), coherent reflectance) of first-order perturbation theory in 1-D (module doc).

    References
    ----------
    .. [1] E. I. Thorsos, D. R. Jackson, J. Acoust. Soc. Am. 86(1), 261–277, 1989 (perfect conductor).
    .. [2] S. O. Rice, Comm. Pure Appl. Math. 4, 351–378, 1951; A. A. Maradudin et al., Ann. Phys. 203, 255, 1990.
    """
    ti, ts = math.radians(theta_i_deg), np.radians(np.asarray(theta_s_deg, float))
    ci, cs, si, ss = math.cos(ti), np.cos(ts), math.sin(ti), np.sin(ts)
    if refractive_index is None:
        alpha2 = np.ones_like(ts) if polarization == "s" else ((1 - si * ss) / (ci * cs)) ** 2
    else:
        e = complex(refractive_index) ** 2
        qi, qs = _q(e, si), _q(e, ss)
        if polarization == "s":
            alpha = (e - 1) / ((ci + qi) * (cs + qs))
        else:
            alpha = (e - 1) * (e * si * ss - qi * qs) / ((e * ci + qi) * (e * cs + qs))
        alpha2 = np.abs(alpha) ** 2
    k3w = k_sigma ** 2 * k_ell / (2 * math.sqrt(math.pi)) * np.exp(-(k_ell * (ss - si)) ** 2 / 4)
    sigma = 4 * ci * cs ** 2 * alpha2 * k3w
    coherent = float(np.abs(fresnel_amplitude_1d(ti, refractive_index, polarization)) ** 2
                     * math.exp(-(2 * k_sigma * ci) ** 2))
    return sigma, coherent
