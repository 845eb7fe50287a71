"""Polarized light on tilted micro facets: a facet's coherent fraction and scattered light for macro s or p light.

The s/p polarization of the two-scale model is that of the macro plane of incidence (ω_i, z). A micro facet with
normal m has its own plane of incidence (ω_i, m): a macro s field carries cos η_i of the facet's s field and sin η_i
of its p field (:func:`waveoptics.materials.cos2_eta_i`). Without an analyzer the facet returns the energy
cos²η_i X_pol(θ_m) + sin²η_i X_other(θ_m) of its own s and p responses X (:func:`waveoptics.materials.facet_sp_mix`):
its reflectance, and the albedo of its nano lobe, whose s–p interference term is odd in the azimuth about the
facet's plane of incidence and integrates to 0. The diffracted lobe of the Kirchhoff family already carries the
rotation: its Fresnel factor is that of the nano facet with normal h ∝ ω_i + ω_o, rotated by η(ω_i, h)
(:func:`waveoptics.materials.F_facet_polarized`), which integrated over the facet's lobe gives the same mix. The
two functions here give the facet's scattered light (the diffracted budget, the paraxial route's facet weights)
and its coherent fraction with the same mix, so that lobe and budget agree facet by facet (issue 28).

References
----------
.. [1] R. G. Priest, T. A. Germer, "Polarimetric BRDF in the microfacet model: theory and measurements", Proc. 2000
   Meeting of the Military Sensing Symposia Specialty Group on Passive Sensors, 2000.
.. [2] K. E. Torrance, E. M. Sparrow, JOSA 57(9), 1105–1114, 1967 (facet frames).
.. [3] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5 (R_s, R_p).
"""
from __future__ import annotations

import numpy as np

from .. import scatter
from ..materials import facet_sp_mix
from .roughness_scales import Nano

__all__ = ['facet_scattered_share', 'facet_coherent_fraction']


def _rotated(cos2_eta, polarization, material) -> bool:
    """Whether the mix needs both of the facet's polarizations: s or p light on a material with s and p
    reflectances, and some facet turned out of the macro plane of incidence."""
    return (polarization in ("s", "p") and material is not None and hasattr(material, "F_sp")
            and bool(np.any(np.asarray(cos2_eta) < 1.0 - 1e-12)))


def facet_scattered_share(nano: Nano, cos_theta_m, cos2_eta, wavelength_nm, diffraction="kirchhoff", material=None,
                          polarization: str = "unpolarized", azimuth_deg: float = 0.0):
    """:meth:`waveoptics.brdf.Nano.scattered_share` of facets at local incidence θ_m lit by macro s or p light:
    on a dielectric the absolute albedo of the facet's lobe, cos²η_i S_pol(θ_m) + sin²η_i S_other(θ_m); on a
    conductor, where the share is relative to the facet's reflectance, the same mix of the absolute scattered
    light R S over the mixed reflectance, (cos²η_i R_pol S_pol + sin²η_i R_other S_other) / (cos²η_i R_pol +
    sin²η_i R_other). Unpolarized light, and facets in the macro plane (cos²η_i = 1), take the share as it is.

    Parameters
    ----------
    nano : Nano
    cos_theta_m : array_like
        cos θ_m of each facet's local incidence.
    cos2_eta : array_like
        cos²η_i of each facet (:func:`waveoptics.materials.cos2_eta_i`), broadcast against *cos_theta_m*.
    wavelength_nm : float or array_like, nm

    References
    ----------
    .. [1] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000.
    """
    if not _rotated(cos2_eta, polarization, material):
        return nano.scattered_share(cos_theta_m, wavelength_nm, diffraction, material, polarization, azimuth_deg)
    S_s, S_p = (np.asarray(nano.scattered_share(cos_theta_m, wavelength_nm, diffraction, material, p, azimuth_deg),
                           dtype=float) for p in ("s", "p"))
    if not scatter.is_conductor(material):
        return facet_sp_mix(S_s, S_p, cos2_eta, polarization)
    R_s, R_p = material.F_sp(np.clip(cos_theta_m, 0.0, 1.0), wavelength_nm)
    R = facet_sp_mix(R_s, R_p, cos2_eta, polarization)
    # guard: a facet reflecting nothing scatters nothing; its share is then the plain mix (never 0/0)
    return np.where(R > 0, facet_sp_mix(R_s * S_s, R_p * S_p, cos2_eta, polarization) / np.where(R > 0, R, 1.0),
                    facet_sp_mix(S_s, S_p, cos2_eta, polarization))


def facet_coherent_fraction(nano: Nano, cos_theta_m, cos2_eta, wavelength_nm, diffraction="kirchhoff",
                            material=None, polarization: str = "unpolarized", azimuth_deg: float = 0.0):
    """:meth:`waveoptics.brdf.Nano.coherent_fraction` of facets lit by macro s or p light: on a conductor the
    share of the facet's mixed reflectance that stays specular, (cos²η_i R_pol A_pol + sin²η_i R_other A_other) /
    (cos²η_i R_pol + sin²η_i R_other), the complement of :func:`facet_scattered_share`; on a dielectric the
    Debye-Waller factor, the same for s and p (:meth:`waveoptics.scatter.BandSeries.coherent_fraction`).

    References
    ----------
    .. [1] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000.
    .. [2] H. Davies, Proc. IEE 101, 209 (1954) (the coherent fraction).
    """
    if not _rotated(cos2_eta, polarization, material) or not scatter.is_conductor(material):
        return nano.coherent_fraction(cos_theta_m, wavelength_nm, diffraction, material, polarization, azimuth_deg)
    A_s, A_p = (np.asarray(nano.coherent_fraction(cos_theta_m, wavelength_nm, diffraction, material, p,
                                                  azimuth_deg), dtype=float) for p in ("s", "p"))
    R_s, R_p = material.F_sp(np.clip(cos_theta_m, 0.0, 1.0), wavelength_nm)
    R = facet_sp_mix(R_s, R_p, cos2_eta, polarization)
    # guard: a facet reflecting nothing keeps the plain mix (never 0/0)
    return np.where(R > 0, facet_sp_mix(R_s * A_s, R_p * A_p, cos2_eta, polarization) / np.where(R > 0, R, 1.0),
                    facet_sp_mix(A_s, A_p, cos2_eta, polarization))
