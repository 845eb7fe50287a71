"""First-order scatter of a thin-film stack with rough interfaces into both half-spaces, light from either side:
the full-sphere BSDF of the stack of :mod:`waveoptics.scatter.rough_film` over a transparent substrate
(docs/physics.md §15 for one interface).

Model
-----
The stack, its interfaces and the dipole sheet p_j = ε₀ h_j [(ε_below − ε_above) E_t + (1/ε_above − 1/ε_below)
D_z ẑ / ε₀] of a rough interface are those of :mod:`~waveoptics.scatter.rough_film` (Johnson et al. 2002; Elson
1984). Air (index 1) lies above (z > 0), the substrate (index n_s) below; ω_i and ω_o (unit vectors towards the
light and the viewer) lie on either side: n_i, n_o are the indices of their media (1 above, n_s below) and
θ_i, θ_o their angles from the normal there.

Derivation. (a) The incident wave has unit electric amplitude in its medium n_i, E^a its flat-stack field at
interface j. (b) A dipole p in the stack radiates into the observer's medium (index n_o, ε_o = n_o²) the far
field E = (k²/4πε₀ε_o)(e^{ikr}/r) p_⊥ with k = n_o k₀ (Jackson §9.2 in a medium): k²/ε_o = k₀², so
E = (k₀²/4πε₀)(e^{i n_o k₀ r}/r) p_⊥, whatever n_o. (c) Lorentz reciprocity between p and a test dipole at the
far point (Sipe 1987): the component along ê_b of that far field is (k₀²/4πε₀)(e^{i n_o k₀ r}/r) p · E'_b,
where E'_b is the flat-stack field of a unit plane wave of polarization b coming in from ω_o in the medium n_o.
(d) Radiance convention (Stover's power BSDF, as :mod:`~waveoptics.scatter.transmission`): the scattered power
per solid angle is r² n_o |E|² / 2Z₀ and the incident power on an area A is n_i A |cosθ_i| / 2Z₀, so
f = dP/dω_o / (P_i |cosθ_o|) carries n_o / n_i. (e) The incident wave's lateral phase e^{−i k₀ n_i ω_i·x}
times the reciprocal wave's e^{−i k₀ n_o ω_o·x} integrates each sheet to the Fourier transform H_j(f) of h_j at
f = (n_i ω_i + n_o ω_o)_xy / λ (the grating equation), with ⟨H_j H_k*⟩ = A S_jk(f) over the illuminated area A
(two-sided PSDs). Altogether

    f_ab(ω_i, ω_o) = (n_o / n_i) k₀⁴ / (16 π² |cosθ_i cosθ_o|) Σ_j Σ_k c_jk √(S_j S_k) Re(G_j^{ab} G_k^{ab*}),
    G_j^{ab} = (ε_below − ε_above) [ E_t^a · E'_t^b + D_z^a D'_z^b / (ε_above ε_below) ],
    f = (n_i ω_i + n_o ω_o)_xy / λ                                                                        (1)

with S_jk = c_jk √(S_j S_k) and G as in :mod:`~waveoptics.scatter.rough_film` eq. (1), which is (1) at n_i = n_o = 1.
G_j^{ab} is symmetric in the two waves, so f_ab(ω_i, ω_o) / n_o² = f_ba(ω_o, ω_i) / n_i²: the reciprocity of
radiance across media (Veach 1997, §5.2). A wave coming from the substrate is the mirror image (z → −z) of the
reversed stack lit from above (:func:`~waveoptics.scatter.rough_film.interface_fields`); its lateral index is
κ = n_s sinθ, and where κ > 1 its field in the air is evanescent (beyond the critical angle), as is the
reciprocal wave of an observer in the substrate beyond the critical angle. With no films (1) is the Rayleigh-Rice
BRDF on either side and BTDF across of one interface (:mod:`~waveoptics.scatter.transmission`, held against a
rigorous grating solve and SCATMECH), which tests/test_rough_film_sides.py checks to 1e-10.

Where it holds: the smooth-surface limit at every interface, as :mod:`~waveoptics.scatter.rough_film`. A
direction below needs a transparent substrate (films may absorb): a real index, or one whose k is below
:data:`TRANSPARENT_K` n (a catalogued glass's k ~ 1e-8), whose real part is then used (the radiance just below the
interface; absorption along the path in the substrate is the renderer's); light from above over an absorbing
substrate is scattered into the air only (:func:`~waveoptics.scatter.rough_film.rough_stack_components`), 0 below.
Light scattered into guided modes of the films (lateral indices above n_s and 1: no far-field direction; Elson
1995) is not part of the BSDF, which has no pole over the propagating directions: the power they carry is in
neither TIS.

References
----------
.. [1] J. M. Elson, "Theory of light scattering from a rough surface with an inhomogeneous dielectric
   permittivity", Phys. Rev. B 30(10), 5460–5480, 1984.
.. [2] J. M. Elson, "Multilayer-coated optics: guided-wave coupling and scattering by means of interface random
   roughness", J. Opt. Soc. Am. A 12(4), 729–742, 1995 (scatter of rough stacks into reflection and transmission).
.. [3] S. G. Johnson, M. Ibanescu, M. A. Skorobogatiy, O. Weisberg, J. D. Joannopoulos, Y. Fink, "Perturbation
   theory for Maxwell's equations with shifting material boundaries", Phys. Rev. E 65, 066611, 2002.
.. [4] J. E. Sipe, "New Green-function formalism for surface optics", J. Opt. Soc. Am. B 4(4), 481–489, 1987.
.. [5] J. D. Jackson, *Classical Electrodynamics*, 3rd ed., Wiley 1999, §9.2 (the far field of an electric dipole).
.. [6] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §5.2.
.. [7] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012, ch. 4–5 (the BSDF and the
   TIS of a transmissive surface).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import FieldError, unknown
from .polar import polar_albedo
from .rough_film import (correlated_sum, cross_psd_pairs, cross_psd_weights, interface_amplitudes, interface_psd_list,
                         interface_spectra, rough_stack_components, stack_layers)
from .transmission import TIS_METHODS, WIDE_LOBE, hemisphere_albedo, incident_polarization

__all__ = ["TRANSPARENT_K", "substrate_is_transparent", "rough_stack_bsdf_components", "rough_stack_bsdf",
           "rough_stack_tis_sides"]

#: the largest extinction coefficient, relative to n, of a substrate taken as transparent (with its real index n):
#: the BSDF changes by O(k/n) there. A catalogued glass has k ~ 1e-8 (BK7 at 550 nm: 7e-9, absorbed over
#: millimetres, far from the interface); a metal's k/n is of order 1 and more.
TRANSPARENT_K = 1e-6


def substrate_is_transparent(eps_substrate) -> bool:
    """Whether the substrate (its permittivity: one value, or one a wavelength) lets light cross: n = √ε with
    Re n > 0 and |Im n| ≤ :data:`TRANSPARENT_K` Re n."""
    n = np.sqrt(np.asarray(eps_substrate, dtype=np.complex128))
    return bool(np.all(n.real > 0) and np.all(np.abs(n.imag) <= TRANSPARENT_K * n.real))


def _transparent_layers(stack_or_layers, wavelength_nm):
    """(ε list, thicknesses, transparent): :func:`~waveoptics.scatter.rough_film.stack_layers`, the substrate's
    index taken real when it counts as transparent (:data:`TRANSPARENT_K`)."""
    eps, d = stack_layers(stack_or_layers, wavelength_nm)
    clear = substrate_is_transparent(eps[0])
    if clear and np.any(np.imag(eps[0]) != 0):
        eps = [np.asarray(np.sqrt(eps[0]).real ** 2, dtype=np.complex128), *eps[1:]]
    return eps, d, clear


def _refuse_absorbing(what: str):
    raise FieldError("{stack}: " + what + " needs a transparent substrate (a real index > 0); an absorbing one "
                     "takes light from above only", "stack")


def rough_stack_bsdf_components(wi, wo, wavelength_nm, stack_or_layers, interface_psds,
                                correlation="correlated") -> dict:
    """The four polarized first-order BSDFs f_ss, f_sp, f_ps, f_pp (1/sr, radiance convention; first index incident,
    second scattered) of eq. (1) of the module docstring over the whole sphere: ω_i, ω_o (..., 3) towards the light
    and the viewer, z < 0 in the substrate. Arguments as :func:`~waveoptics.scatter.rough_film.rough_stack_brdf`.
    Over an absorbing substrate: light from above only, 0 below.

    References
    ----------
    .. [1] Elson 1984, 1995; Johnson et al. 2002; Sipe 1987; Veach 1997 (module references).
    """
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    eps, d, clear = _transparent_layers(stack_or_layers, wavelength_nm)
    n = len(eps) - 1
    below_i, below_o = wi[..., 2] < 0, wo[..., 2] < 0
    if not clear:
        if np.any(below_i):
            _refuse_absorbing("light from inside the substrate (wi with z < 0)")
        # guard: nothing crosses into an absorbing substrate: the air side as today, 0 below
        f = rough_stack_components(wi, wo, wavelength_nm, stack_or_layers, interface_psds, correlation)
        return {ab: np.where(below_o, 0.0, v) for ab, v in f.items()}
    n_s = np.sqrt(eps[0]).real
    n_i, n_o = np.where(below_i, n_s, 1.0), np.where(below_o, n_s, 1.0)
    S = interface_spectra(wi, wo, wavelength_nm, stack_or_layers, interface_psds, n, n_i, n_o)
    c = cross_psd_weights(correlation, n)
    G = interface_amplitudes(wi, wo, wavelength_nm, eps, d)
    ci, co = wi[..., 2], wo[..., 2]
    ok = (ci != 0) & (co != 0)
    k0 = 2.0 * np.pi / (np.asarray(wavelength_nm, dtype=float) * 1e-9)
    pre = n_o / n_i * k0 ** 4 / (16.0 * np.pi ** 2 * np.where(ok, np.abs(ci * co), 1.0))
    pairs = cross_psd_pairs(S, c)
    return {ab: np.where(ok, pre * correlated_sum(Gab, S, c, pairs), 0.0) for ab, Gab in G.items()}


def rough_stack_bsdf(wi, wo, wavelength_nm, stack_or_layers, interface_psds, correlation="correlated",
                     polarization: str = "unpolarized"):
    """First-order BSDF (1/sr, radiance convention) of a rough thin-film stack over the whole sphere for incident
    *polarization*, scattered light not analyzed (eq. (1) of the module docstring).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit vectors towards the light and the viewer (macro normal +z, air above; z < 0 in the substrate).
    wavelength_nm : array_like, nm
        Vacuum wavelength (broadcast against the directions).
    stack_or_layers : Stack, Material or (n_substrate, n_films, d_films_nm)
        The stack, films from the substrate outwards (:func:`~waveoptics.scatter.rough_film.stack_layers`); the
        substrate must be transparent where a direction lies below (an absorbing one: the air side only).
    interface_psds : PSDModel, PeriodogramPSD, None or sequence of them
        Height PSD of each interface (m⁴ at f in 1/m), substrate interface first; None for a smooth one.
    correlation : {'correlated', 'uncorrelated'}, float or (n, n) array
        Cross-correlation of the interfaces' profiles (:func:`~waveoptics.scatter.rough_film.cross_psd_weights`).
    polarization : {'unpolarized', 's', 'p'}
        Incident polarization ('unpolarized': the mean of s and p).

    References
    ----------
    .. [1] Elson 1984, 1995; Stover 2012 (module references).
    """
    f = rough_stack_bsdf_components(wi, wo, wavelength_nm, stack_or_layers, interface_psds, correlation)
    return incident_polarization(f, polarization)


def _side_tis(lobe, theta, n_in, n_o, n_other, lam_nm, scale, method) -> float:
    """∫ lobe(wo) |cosθ_o| dω_o over one hemisphere (lobe sees wo with z ≥ 0 in that medium, index *n_o*) for
    incidence θ (rad) in the medium *n_in*: polar quadrature about the specular direction, or the hemisphere cut at
    the critical angle asin(n_other / n_o) for wide lobes and beyond the critical angle."""
    a = n_in * math.sin(theta) / n_o                     # sine of the specular direction on this side
    if method == "polar" and a >= 1.0:
        raise FieldError(f"{{theta_deg}} {math.degrees(theta)!r} is beyond the critical angle: no specular "
                         "direction for the polar quadrature (method='hemisphere' integrates there)", "theta_deg")
    wide = method == "hemisphere" or (method == "auto" and lam_nm * 1e-9 / (math.pi * scale * n_o) >= WIDE_LOBE)
    if a >= 1.0 or wide:
        return hemisphere_albedo(lobe, [math.asin(n_other / n_o)] if n_other < n_o else [])
    return polar_albedo(math.asin(a), 2.0 * math.pi * n_o / (lam_nm * 1e-9), scale, lambda wi_b, wo, q: lobe(wo))


def rough_stack_tis_sides(theta_deg, wavelength_nm, stack_or_layers, interface_psds, correlation="correlated",
                          polarization: str = "unpolarized", from_above: bool = True, method: str = "auto"):
    """(TIS_R, TIS_T): the shares of the incident power (unitless) scattered into the incidence side and across,
    ∫ f |cosθ_o| dω_o over each hemisphere, for light at *theta_deg* (deg, from the normal in its own medium) from
    the air (*from_above*) or from inside the substrate.

    *method* as :func:`~waveoptics.scatter.transmission.rr_tis_transmission`: ``polar``, the polar quadrature of
    :func:`~waveoptics.scatter.polar_albedo` about the specular direction of each side (narrow lobes);
    ``hemisphere``, :func:`~waveoptics.scatter.transmission.hemisphere_albedo` cut at the critical angle; ``auto``,
    the hemisphere for lobes wider than :data:`~waveoptics.scatter.transmission.WIDE_LOBE` or a side with no
    specular direction (beyond the critical angle), else polar. Over an absorbing substrate TIS_T is 0.

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012, §4.4 (TIS as the integral of the BSDF).
    .. [2] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (TIS of multilayers).
    """
    if method not in TIS_METHODS:
        raise unknown("method", method, TIS_METHODS, field="method")
    lam = float(wavelength_nm)
    eps, _, clear = _transparent_layers(stack_or_layers, lam)
    if not from_above and not clear:
        _refuse_absorbing("light from inside the substrate (from_above=False)")
    psds = [m for m in interface_psd_list(interface_psds, len(eps) - 1) if m is not None]
    if not psds:
        return 0.0, 0.0
    scale = min(m.length_scale for m in psds)
    t = math.radians(float(theta_deg))
    up = 1.0 if from_above else -1.0
    wi = np.array([math.sin(t), 0.0, up * math.cos(t)])
    n_s = float(np.sqrt(eps[0]).real) if clear else math.inf
    n_in, n_far = (1.0, n_s) if from_above else (n_s, 1.0)

    def lobe(z_sign):
        def f(wo):
            w = wo * np.array([1.0, 1.0, z_sign])
            return rough_stack_bsdf(wi, w, lam, stack_or_layers, interface_psds,
                                    correlation, polarization)
        return f

    tis_r = _side_tis(lobe(up), t, n_in, n_in, n_far, lam, scale, method)
    tis_t = _side_tis(lobe(-up), t, n_in, n_far, n_in, lam, scale, method) if clear else 0.0
    return tis_r, tis_t
