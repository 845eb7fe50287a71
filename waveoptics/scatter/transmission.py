"""Rayleigh-Rice in transmission: first-order scatter of a slightly rough interface between two media into both
half-spaces (the BRDF on either side and the BTDF across), docs/physics.md §15.

The interface z = h(x, y) separates medium 1 (real index n₁, z > 0) from medium 2 (index n₂, z < 0). Light comes
from ω_i in the medium of index n_i and leaves towards ω_o in the medium of index n_o (the indices of the sides of
ω_i and ω_o). To first order in h the roughness is a sheet of induced dipoles, and reciprocity gives the far field
(the derivation of :mod:`waveoptics.scatter.rough_film` for one interface with an incident medium of index n₁,
Elson 1984, Johnson et al. 2002). Across the interface (light from medium 1 into medium 2; the other way round the
media swap):

    f_t^{ab}(ω_i, ω_o) = (16 π² / λ⁴) n₁ n₂³ cosθ_i cosθ_o Q_t^{ab} S(f),   Q_t^{ab} = |q_t^{ab}|²,
    f = (n₁ ω_i + n₂ ω_o)_xy / λ                    (grating equation: n₂ sinθ_o = n₁ sinθ_i + λ f in plane),

with θ_i, θ_o the angles from the normal in each medium, φ the scattering azimuth from the forward (specular
transmission) side, κ_i = n₁ sinθ_i, κ_o = n₂ sinθ_o, ε_j = n_j², and the normal wave numbers (in units of
2π/λ) of the incident wave q₁ᵢ = n₁ cosθ_i, q₂ᵢ = √(ε₂ − κ_i²) and of the reciprocal wave
q₂ₒ = n₂ cosθ_o, q₁ₒ = √(ε₁ − κ_o²) (Im ≥ 0: evanescent beyond the critical angle):

    q_t^ss = (ε₂ − ε₁) cosφ / [(q₁ᵢ + q₂ᵢ)(q₁ₒ + q₂ₒ)]
    q_t^sp = (ε₂ − ε₁) n₂ q₁ₒ sinφ / [(q₁ᵢ + q₂ᵢ)(ε₂ q₁ₒ + ε₁ q₂ₒ)]
    q_t^ps = (ε₂ − ε₁) n₁ q₂ᵢ sinφ / [(ε₂ q₁ᵢ + ε₁ q₂ᵢ)(q₁ₒ + q₂ₒ)]
    q_t^pp = (ε₂ − ε₁) n₁ n₂ (κ_i κ_o + q₂ᵢ q₁ₒ cosφ) / [(ε₂ q₁ᵢ + ε₁ q₂ᵢ)(ε₂ q₁ₒ + ε₁ q₂ₒ)]

(first index incident, second scattered; s, p relative to the planes of incidence and scattering; the phases of
the q's are those of one choice of basis vectors and do not enter Q). On the incidence side the BRDF is
Rayleigh-Rice in a medium: Germer's q factors (:func:`waveoptics.scatter.q_factors`) of the relative
permittivity ε_o'/ε_i and the wavelength λ/n_i in the medium (a change of units of Maxwell's equations), with
f = n_i (ω_i + ω_o)_xy / λ.

Radiance convention: f is the BSDF of radiance, dP/dω_o / (P_i cosθ_o) (Stover's power definition, the
radiometric one), as :mod:`waveoptics.brdf.btdf`: ∫ f_t cosθ_o dω_o is the share of the incident power that
crosses, and reciprocity reads f_t(ω_i, ω_o) / n_o² = f_t(ω_o, ω_i) / n_i² (Veach 1997, §5.2), which the form
above obeys (n₁ n₂³ / n₂² = n₁ n₂ and Q_t symmetric under the exchange of the two waves). At normal incidence and
small scattering angles it gives Stover's smooth-surface transmitted TIS, (2π σ (n₂ − n₁) / λ)² T.

Where it holds: the smooth-surface limit of Rayleigh-Rice, (4π n σ cosθ / λ)² ≪ 1 and slopes ≪ 1. The
transmitted light needs transparent media (real n₁, n₂); the reflected part takes an absorbing medium 2. The
coherent (specular) reduction is second order and not part of it; the energy it takes is the first-order scatter
into both half-spaces (tests/test_rr_transmission.py measures that against a rigorous grating solve, and the BTDF
against SCATMECH's Microroughness_BRDF_Model in transmission).

References
----------
.. [1] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
.. [2] J. M. Elson, "Theory of light scattering from a rough surface with an inhomogeneous dielectric
   permittivity", Phys. Rev. B 30(10), 5460–5480, 1984.
.. [3] J. M. Elson, "Multilayer-coated optics: guided-wave coupling and scattering by means of interface random
   roughness", J. Opt. Soc. Am. A 12(4), 729–742, 1995 (reflection and transmission of rough stacks).
.. [4] T. A. Germer, SCATMECH (NIST): BRDF_Model ``type`` 0–3 (reflection and transmission, light from either
   side) and Roughness_Stack_BRDF_Model (after Elson 1995).
.. [5] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012, ch. 4–5 (the
   Rayleigh-Rice BSDF and the smooth-surface TIS of a transmissive surface).
.. [6] S. G. Johnson et al., "Perturbation theory for Maxwell's equations with shifting material boundaries",
   Phys. Rev. E 65, 066611, 2002.
.. [7] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §5.2.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from ..errors import FieldError, unknown
from ..vocabulary import POLARIZATIONS
from .angles import scattering_angles
from .perturbation import q_factors
from .polar import polar_albedo

__all__ = ["q_transmission", "rr_psd", "rr_btdf_components", "rr_brdf_components", "rr_bsdf_components",
           "rr_bsdf", "TIS_METHODS", "WIDE_LOBE", "hemisphere_albedo", "rr_tis_transmission", "rr_tis_reflection",
           "incident_polarization"]


def _real_index(n, name: str) -> float:
    """*n* as a real index > 0 (transmission needs transparent media)."""
    c = complex(np.ravel(np.asarray(n, dtype=np.complex128))[0])
    if not np.isfinite(c.real) or c.real <= 0 or c.imag != 0:
        raise FieldError(f"{{{name}}} {n!r} is not allowed; light crosses the interface only between transparent "
                         "media (a real index > 0)", name)
    return c.real


def q_transmission(wi, wo, n1, n2) -> dict:
    """Complex factors q_t^{ss, sp, ps, pp} (unitless) of light from medium 1 (index *n1*, real) into medium 2
    (*n2*, real): ω_i on the side of medium 1, ω_o on the side of medium 2; only |cosθ| enters, so the side each
    direction's z says is not read (module docstring).

    References
    ----------
    .. [1] Elson 1984; Johnson et al. 2002 (the boundary-perturbation dipole sheet, module references).
    """
    ci, si, co, so, cphi, sphi = scattering_angles(wi, wo)
    ci, co = np.abs(ci), np.abs(co)
    n1 = np.asarray(n1, dtype=np.complex128)
    n2 = np.asarray(n2, dtype=np.complex128)
    e1, e2 = n1 * n1, n2 * n2
    ki, ko = n1 * si, n2 * so                         # lateral wave numbers of the two waves (units of 2π/λ)
    q1i, q2o = n1 * ci, n2 * co
    q2i = np.sqrt(e2 - ki * ki + 0j)                   # principal branch: Im ≥ 0 beyond the critical angle
    q1o = np.sqrt(e1 - ko * ko + 0j)
    ds_i, dp_i = q1i + q2i, e2 * q1i + e1 * q2i
    ds_o, dp_o = q1o + q2o, e2 * q1o + e1 * q2o
    de = e2 - e1
    return {"ss": de * cphi / (ds_i * ds_o),
            "sp": de * n2 * q1o * sphi / (ds_i * dp_o),
            "ps": de * n1 * q2i * sphi / (dp_i * ds_o),
            "pp": de * n1 * n2 * (ki * ko + q2i * q1o * cphi) / (dp_i * dp_o)}


def rr_psd(model, wi, wo, wavelength_nm, n_i, n_o):
    """S(f) (m⁴) at the Bragg frequency f = (n_i ω_i + n_o ω_o)_xy / λ (1/m) of *model* (isotropic ``S(|f|)`` or
    ``S_xy(f_x, f_y)``).

    References
    ----------
    .. [1] T. A. Germer, SCATMECH, Roughness_BRDF_Model::Bragg_Frequency (the four cases of BRDF_Model type).
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    s = n_i * wi + n_o * wo
    if hasattr(model, "S_xy"):
        return model.S_xy(s[..., 0] / lam, s[..., 1] / lam)
    return model.S(np.hypot(s[..., 0], s[..., 1]) / lam)


def rr_btdf_components(wi, wo, wavelength_nm, model, n1, n2) -> dict:
    """The four polarized BTDFs f_t^{ab} (1/sr, radiance convention) across the interface: ω_i and ω_o on opposite
    sides (0 elsewhere), medium 1 (*n1*) above (z > 0), medium 2 (*n2*) below; light from below sees the media
    swapped.

    References
    ----------
    .. [1] Elson 1984, 1995; Stover 2012 ch. 5 (module references).
    """
    n1, n2 = _real_index(n1, "n1"), _real_index(n2, "n2")
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    up = wi[..., 2] > 0
    ni, no = np.where(up, n1, n2), np.where(up, n2, n1)
    q = q_transmission(wi, wo, ni, no)
    S = rr_psd(model, wi, wo, wavelength_nm, ni[..., None], no[..., None])
    ok = wi[..., 2] * wo[..., 2] < 0
    pre = 16 * np.pi ** 2 / lam ** 4 * ni * no ** 3 * np.abs(wi[..., 2] * wo[..., 2]) * S
    return {k: np.where(ok, pre * np.abs(v) ** 2, 0.0) for k, v in q.items()}


def rr_brdf_components(wi, wo, wavelength_nm, model, n1, n2) -> dict:
    """The four polarized BRDFs (1/sr) on either side of the interface: ω_i, ω_o on one side (0 elsewhere), the
    Rayleigh-Rice BRDF in the medium of ω_i (index n_i, real) over the medium across (index n_t; *n2* may be complex
    when light comes from above): Germer's q of the relative permittivity n_t²/n_i² at the wavelength λ/n_i in the
    medium, with f = n_i (ω_i + ω_o)_xy / λ.

    References
    ----------
    .. [1] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997, eqs. (17)–(20); SCATMECH BRDF_Model type 2
       (reflection inside the substrate).
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    up = wi[..., 2] > 0
    n1 = _real_index(n1, "n1")
    n2c = complex(np.ravel(np.asarray(n2, dtype=np.complex128))[0])
    if np.any(~up):                                      # light from inside medium 2: it must be transparent
        n2c = complex(_real_index(n2, "n2"))
    ni = np.where(up, n1, n2c.real)
    eps_rel = np.where(up, n2c ** 2 / n1 ** 2, n1 ** 2 / n2c ** 2)
    sz = np.where(up, 1.0, -1.0)
    ok = (wi[..., 2] * sz > 0) & (wo[..., 2] * sz > 0)
    # the incidence side turned to z > 0; guard: pairs across the interface (not a reflection) get |z| here and
    # 0 below, not a 0/0 of Germer's q
    wi_u, wo_u = wi.copy(), wo.copy()
    wi_u[..., 2] = np.abs(wi[..., 2])
    wo_u[..., 2] = np.abs(wo[..., 2])
    q = q_factors(wi_u, wo_u, eps_rel)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9 / ni
    S = rr_psd(model, wi, wo, wavelength_nm, ni[..., None], ni[..., None])
    pre = 16 * np.pi ** 2 / lam ** 4 * wi_u[..., 2] * wo_u[..., 2] * S
    return {k: np.where(ok, pre * np.abs(v) ** 2, 0.0) for k, v in q.items()}


def rr_bsdf_components(wi, wo, wavelength_nm, model, n1, n2) -> dict:
    """The four polarized first-order BSDFs (1/sr) over the whole sphere: :func:`rr_brdf_components` where ω_i
    and ω_o share a side, :func:`rr_btdf_components` across (both media transparent).

    References
    ----------
    .. [1] Elson 1984, 1995; Germer 1997 (module references).
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    r = rr_brdf_components(wi, wo, wavelength_nm, model, n1, n2)
    t = rr_btdf_components(wi, wo, wavelength_nm, model, n1, n2)
    return {k: r[k] + t[k] for k in r}


def rr_bsdf(wi, wo, wavelength_nm, model, n1, n2, polarization: str = "unpolarized"):
    """First-order BSDF (1/sr, radiance convention) of the rough interface for incident *polarization*, scattered
    light not analyzed: f_ss + f_sp (s), f_pp + f_ps (p) or their mean (unpolarized).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit vectors towards the light and the viewer, on either side of the interface (macro normal +z).
    wavelength_nm : array_like, nm
        Vacuum wavelength.
    model : PSDModel or PeriodogramPSD
        Height statistics of the interface (two-sided PSD, m⁴ at f in 1/m).
    n1, n2 : float
        Indices above (z > 0) and below; *n2* may be complex for light from above seen in reflection only.
    polarization : {'unpolarized', 's', 'p'}

    References
    ----------
    .. [1] Elson 1984, 1995; Germer 1997; Stover 2012 (module references).
    """
    transparent = complex(np.ravel(np.asarray(n2, dtype=np.complex128))[0]).imag == 0
    # an absorbing medium 2 has no transmitted light: the BRDF above it only
    f = (rr_bsdf_components if transparent else rr_brdf_components)(wi, wo, wavelength_nm, model, n1, n2)
    return incident_polarization(f, polarization)


def _incidence(theta_deg: float, from_above: bool):
    t = math.radians(float(theta_deg))
    return np.array([math.sin(t), 0.0, math.cos(t) if from_above else -math.cos(t)]), t


#: methods of :func:`rr_tis_transmission`
TIS_METHODS = ("auto", "polar", "hemisphere")


#: a lobe narrower than this in direction cosines (λ / (π ℓ n), ℓ the PSD's length scale) is integrated about its
#: centre (:func:`waveoptics.scatter.polar_albedo`) by ``method="auto"``, a wider one over the hemisphere
WIDE_LOBE = 0.05


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n: int):
    """Gauss-Legendre nodes and weights on [−1, 1] (read-only; computed once per *n*)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def hemisphere_albedo(lobe, breaks=(), n_theta: int = 64, n_psi: int = 257) -> float:
    """∫ f cosθ dω over a hemisphere of a lobe ``lobe(wo)`` (1/sr; wo (..., 3) with z ≥ 0) symmetric about the
    x–z plane.

    θ is cut at *breaks* (rad: the critical angles where a normal wave number of the first-order factors turns
    imaginary, a √ kink of the integrand); on each piece θ = θ_a + (θ_b − θ_a)(3τ² − 2τ³) with Gauss-Legendre
    nodes in τ, whose Jacobian 6τ(1 − τ) vanishes at both ends and so smooths a √ there (and the integrand's
    cosθ at the horizon); the trapezoid rule in ψ on [0, π], twice (the integrand is periodic and even in ψ).

    References
    ----------
    .. [1] P. J. Davis, P. Rabinowitz, *Methods of Numerical Integration*, 2nd ed., Academic Press 1984, §2.7
       (Gauss-Legendre), §2.9 (the trapezoid rule of periodic integrands), §2.12 (changes of variable that
       smooth endpoint singularities).
    """
    edges = [0.0] + sorted(float(b) for b in breaks if 0.0 < b < 0.5 * np.pi) + [0.5 * np.pi]
    x, w = _gauss_legendre(n_theta)
    tau, wt = 0.5 * (x + 1), 0.5 * w
    psi = np.linspace(0.0, np.pi, n_psi)
    wp = np.full(n_psi, np.pi / (n_psi - 1))
    wp[[0, -1]] *= 0.5
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        t = lo + (hi - lo) * tau * tau * (3.0 - 2.0 * tau)
        jac = (hi - lo) * 6.0 * tau * (1.0 - tau)
        st, ct = np.sin(t)[:, None], np.cos(t)[:, None]
        wo = np.stack(np.broadcast_arrays(st * np.cos(psi), st * np.sin(psi), ct), axis=-1)
        total += 2.0 * float(np.sum(lobe(wo) * (st * ct) * (wt * jac)[:, None] * wp[None, :]))
    return total


def _use_hemisphere(method, model, lam_nm, n) -> bool:
    return method == "hemisphere" or (method == "auto" and lam_nm * 1e-9 / (np.pi * model.length_scale * n)
                                      >= WIDE_LOBE)


def rr_tis_transmission(theta_deg, wavelength_nm, model, n1, n2, polarization: str = "unpolarized",
                        from_above: bool = True, method: str = "auto") -> float:
    """Transmitted TIS ∫ f_t |cosθ_o| dω_o (unitless, a share of the incident power) at incidence *theta_deg*
    (deg, in the medium of ω_i).

    *method*: ``polar``, the polar quadrature about the specular transmission direction of
    :func:`waveoptics.scatter.polar_albedo` in the direction cosines of the far side (for narrow lobes; needs that
    direction, n_i sinθ_i < n_o; within 1e-8 of the hemisphere where the integrand is smooth, 1e-3 where a wide
    lobe reaches the critical circle); ``hemisphere``, :func:`hemisphere_albedo` over the far side, cut at its
    critical angle (wide lobes, and light beyond the critical angle, whose lobe's centre lies outside
    the far side's directions); ``auto``, the hemisphere for lobes wider than :data:`WIDE_LOBE` or beyond the
    critical angle, else the polar quadrature.

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4 (TIS as the integral of the BSDF).
    """
    if method not in TIS_METHODS:
        raise unknown("method", method, TIS_METHODS, field="method")
    n1, n2 = _real_index(n1, "n1"), _real_index(n2, "n2")
    ni, no = (n1, n2) if from_above else (n2, n1)
    wi, t = _incidence(theta_deg, from_above)
    a = ni * math.sin(t) / no                            # sine of the specular transmission angle
    if method == "polar" and a >= 1.0:
        raise FieldError(f"{{theta_deg}} {float(theta_deg)!r} is beyond the critical angle "
                         f"{math.degrees(math.asin(no / ni)):.4g}°: no transmitted specular direction for the "
                         "polar quadrature (method='hemisphere' integrates there)", "theta_deg")
    lam = float(wavelength_nm)
    k = 2 * math.pi * no / (lam * 1e-9)                 # wave number on the far side
    s = -1.0 if from_above else 1.0                      # z sign of the far side

    def lobe(wo):
        wo_t = wo * np.array([1.0, 1.0, s])
        f = rr_btdf_components(np.broadcast_to(wi, wo.shape), wo_t, lam, model, n1, n2)
        return incident_polarization(f, polarization)

    if a >= 1.0 or _use_hemisphere(method, model, lam, no):
        # the reciprocal wave of a scattered direction beyond n_i / n_o on the far side is evanescent in medium i
        return hemisphere_albedo(lobe, [math.asin(ni / no)] if no > ni else [])
    return polar_albedo(math.asin(a), k, model.length_scale, lambda wi_b, wo, q: lobe(wo))


def rr_tis_reflection(theta_deg, wavelength_nm, model, n1, n2, polarization: str = "unpolarized",
                      from_above: bool = True, method: str = "auto") -> float:
    """Reflected TIS ∫ f_r |cosθ_o| dω_o (unitless) on the incidence side at *theta_deg* (deg), by
    :func:`waveoptics.scatter.polar_albedo` with the wave number of the incidence medium (``polar``) or by
    :func:`hemisphere_albedo` cut at the critical angle of total internal reflection (``hemisphere``); ``auto``
    as :func:`rr_tis_transmission`.

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4.
    """
    if method not in TIS_METHODS:
        raise unknown("method", method, TIS_METHODS, field="method")
    ni = _real_index(n1 if from_above else n2, "n1" if from_above else "n2")
    wi, t = _incidence(theta_deg, from_above)
    lam = float(wavelength_nm)
    k = 2 * math.pi * ni / (lam * 1e-9)
    s = 1.0 if from_above else -1.0

    def lobe(wo):
        wo_r = wo * np.array([1.0, 1.0, s])
        f = rr_brdf_components(np.broadcast_to(wi, wo.shape), wo_r, lam, model, n1, n2)
        return incident_polarization(f, polarization)

    if _use_hemisphere(method, model, lam, ni):
        no = complex(np.ravel(np.asarray(n2 if from_above else n1, dtype=np.complex128))[0])
        # total internal reflection of the reciprocal wave beyond sinθ_o = n_o / n_i: a √ kink there
        brk = [math.asin(no.real / ni)] if no.imag == 0 and no.real < ni else []
        return hemisphere_albedo(lobe, brk)
    return polar_albedo(t, k, model.length_scale, lambda wi_b, wo, q: lobe(wo))


def incident_polarization(f: dict, polarization: str):
    """The BSDF (1/sr) of incident *polarization* from the four components *f* (first index incident), scattered
    light not analyzed: f_ss + f_sp (s), f_pp + f_ps (p) or their mean (unpolarized)."""
    if polarization not in POLARIZATIONS:
        raise unknown("polarization", polarization, POLARIZATIONS, field="polarization")
    s, p = f["ss"] + f["sp"], f["pp"] + f["ps"]
    return {"s": s, "p": p, "unpolarized": 0.5 * (s + p)}[polarization]
