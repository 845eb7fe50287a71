"""What one nano-rough interface of a glass scatters and keeps coherent: the bare interface between air and a
dielectric, or the same dielectric under thin films (an anti-reflection coating) whose interfaces are rough.

:class:`waveoptics.brdf.NanoRoughDielectricBSDF` and :class:`waveoptics.brdf.TwoScaleDielectricBSDF` ask a nano
interface for three things at a vacuum wavelength λ:

* ``bsdf(wi, wo, λ, psd)``: the first-order BSDF (1/sr, radiance convention) over the whole sphere, light from
  either side: Rayleigh-Rice in reflection and transmission for the bare interface
  (:func:`waveoptics.scatter.rr_bsdf`), Elson's rough-stack scatter into both half-spaces for a coated one
  (:func:`waveoptics.scatter.rough_stack_bsdf`);
* ``tis(θ, λ, psd, polarization, from_above)``: its integral over each half-space, (TIS_R, TIS_T);
* ``losses(μ, from_above, psd, λ)``: the second-order mean field's specular losses ΔR, ΔT of s and p light and the
  flat interface's R₀, T₀ (:func:`waveoptics.scatter.coherent_losses` for one interface,
  :func:`waveoptics.scatter.stack_coherent_losses` for a stack), from which the coherent shares
  A_R = 1 − ΔR/R₀ and A_T = 1 − ΔT/T₀ of unpolarized light follow (:func:`coherent_shares`).

A coated interface's films follow the nano-roughness with the correlation the stack names
(``roughness_correlation``: a thin evaporated film replicates its substrate; Elson, Rahn & Bennett 1983) and the
rms of interface j is r_j times the nano model's (``interface_roughness``): interface j's PSD is r_j² S. The
substrate's index is taken real (Re n; the glass is transparent), as the facet interface does
(:mod:`waveoptics.brdf.facet_interface`).

:func:`nano_interface_of` picks the nano interface of a material at one wavelength (:data:`NANO_INTERFACES`, by the
kind of its facet interface).

References
----------
.. [1] J. M. Elson, "Theory of light scattering from a rough surface with an inhomogeneous dielectric
   permittivity", Phys. Rev. B 30(10), 5460–5480, 1984; J. M. Elson, "Multilayer-coated optics: guided-wave
   coupling and scattering by means of interface random roughness", J. Opt. Soc. Am. A 12(4), 729–742, 1995.
.. [2] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (correlated interfaces).
.. [3] A. A. Maradudin, D. L. Mills, Phys. Rev. B 11(4), 1392–1415, 1975; J. T. Johnson, J. Opt. Soc. Am. A
   16(11), 2720–2736, 1999 (the second-order mean field).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..scatter.rough_film_sides import rough_stack_bsdf, rough_stack_tis_sides
from ..errors import FieldError
from ..scatter.spm2 import coherent_losses, first_moment, tail_exponent
from ..scatter.spm2_stack import stack_coherent_losses
from ..scatter.transmission import rr_bsdf, rr_tis_reflection, rr_tis_transmission
from .facet_interface import BareInterface, CoatedInterface, facet_interface_of

__all__ = ["BareNano", "CoatedNano", "NANO_INTERFACES", "nano_interface_of", "coherent_shares", "check_film_psd"]


@dataclass(frozen=True)
class BareNano:
    """Air over a nano-rough dielectric of real index ``eta`` (module doc)."""

    eta: float

    def bsdf(self, wi, wo, wavelength_nm, psd):
        """First-order BSDF (1/sr) over the sphere, unpolarized (:func:`waveoptics.scatter.rr_bsdf`).

        References
        ----------
        .. [1] Elson 1984 (module references).
        """
        return rr_bsdf(wi, wo, wavelength_nm, psd, 1.0, self.eta)

    def tis(self, theta_deg, wavelength_nm, psd, polarization, from_above):
        """(TIS_R, TIS_T) (dimensionless) of *polarization* at incidence *theta_deg* (deg) on its side."""
        args = (theta_deg, wavelength_nm, psd, 1.0, self.eta, polarization)
        return (rr_tis_reflection(*args, from_above=from_above), rr_tis_transmission(*args, from_above=from_above))

    def losses(self, mu, from_above, psd, wavelength_nm) -> dict:
        """R₀, T₀, ΔR, ΔT of s and p light at incidence cosine *mu* (:func:`waveoptics.scatter.coherent_losses`)."""
        n_i, n_o = (1.0, self.eta) if from_above else (self.eta, 1.0)
        return coherent_losses(mu, n_i, n_o, psd, wavelength_nm)


@dataclass(frozen=True)
class CoatedNano:
    """Air over rough thin films over a dielectric (module doc): the facet interface ``iface``
    (:class:`~waveoptics.brdf.facet_interface.CoatedInterface`: Re n of the substrate, the films' indices and
    thicknesses in nm, substrate first), the interfaces' ``correlation`` and rms ``scales`` r_j (substrate
    interface first)."""

    iface: CoatedInterface
    correlation: object = "correlated"
    scales: tuple = ()

    @property
    def eta(self) -> float:
        """Re n of the substrate (the index the transmitted light travels in)."""
        return self.iface.eta

    def _layers(self):
        return (self.iface.eta, self.iface.n_films, self.iface.d_films_nm)

    def _psds(self, psd):
        """Interface j's PSD model: the nano model with σ scaled by r_j (S ∝ σ²)."""
        scales = self.scales or (1.0,) * (len(self.iface.n_films) + 1)
        return [dataclasses.replace(psd, sigma=psd.sigma * r) if r != 1.0 else psd for r in scales]

    def bsdf(self, wi, wo, wavelength_nm, psd):
        """First-order BSDF (1/sr) over the sphere, unpolarized (:func:`waveoptics.scatter.rough_stack_bsdf`).

        References
        ----------
        .. [1] Elson 1984, 1995 (module references).
        """
        return rough_stack_bsdf(wi, wo, wavelength_nm, self._layers(), self._psds(psd), self.correlation)

    def tis(self, theta_deg, wavelength_nm, psd, polarization, from_above):
        """(TIS_R, TIS_T) (dimensionless) of *polarization* at incidence *theta_deg* (deg) on its side."""
        return rough_stack_tis_sides(theta_deg, wavelength_nm, self._layers(), self._psds(psd), self.correlation,
                                     polarization, from_above=from_above)

    def losses(self, mu, from_above, psd, wavelength_nm) -> dict:
        """R₀, T₀, ΔR, ΔT of s and p light at incidence cosine *mu*
        (:func:`waveoptics.scatter.stack_coherent_losses`)."""
        return stack_coherent_losses(mu, from_above, self._layers(), self._psds(psd), self.correlation,
                                     wavelength_nm)


def check_film_psd(psd) -> None:
    """Refuse (FieldError naming ``psd``) a nano-roughness whose ∫ S |f| d²f diverges (S ∝ |f|^−C with C ≤ 3:
    exponential, ABC with C ≤ 3) on a coated glass: in the films the second-order mean field grows as |K| at large
    spatial frequency, so its split between R and T depends on roughness beyond any band
    (:mod:`waveoptics.scatter.spm2_stack`). Checked when the BSDF is made rather than in a renderer's first lookup.

    References
    ----------
    .. [1] E. L. Church, P. Z. Takacs, Proc. SPIE 1530, 71–85, 1991 (the ABC PSD's f^−C tail).
    """
    if first_moment(psd.S, tail_exponent(psd), psd.length_scale) is None:
        c = tail_exponent(psd)
        raise FieldError(f"{{psd}} {psd.kind} (tail S ∝ |f|^-{c:g}) is not allowed on a coated glass: its films' "
                         "coherent split needs ∫ S |f| d²f, which diverges for C <= 3; use a gaussian PSD or abc "
                         "with C > 3", "psd")


def _bare(material, iface: BareInterface) -> BareNano:
    return BareNano(iface.eta)


def _coated(material, iface: CoatedInterface) -> CoatedNano:
    return CoatedNano(iface, material.roughness_correlation, tuple(material.roughness_scales))


#: the nano interface by the kind of facet interface (:data:`waveoptics.brdf.facet_interface.FACET_INTERFACES`)
NANO_INTERFACES = {BareInterface: _bare, CoatedInterface: _coated}


def nano_interface_of(material, wavelength_nm: float):
    """The nano interface (:class:`BareNano` or :class:`CoatedNano`) of *material* at *wavelength_nm* (nm)."""
    iface = facet_interface_of(material, wavelength_nm)
    return NANO_INTERFACES[type(iface)](material, iface)


def coherent_shares(losses: dict):
    """(A_R, A_T) of unpolarized light from the losses of :meth:`BareNano.losses`: 1 − (ΔR_s + ΔR_p)/(R_s + R_p)
    and 1 − (ΔT_s + ΔT_p)/(T_s + T_p).

    References
    ----------
    .. [1] Maradudin & Mills 1975; Johnson 1999 (module references).
    """
    c = losses
    R2, T2 = c["R0"]["s"] + c["R0"]["p"], c["T0"]["s"] + c["T0"]["p"]
    dR, dT = c["dR"]["s"] + c["dR"]["p"], c["dT"]["s"] + c["dT"]["p"]
    # guard: beyond the critical angle T₀ is 0 (and so ΔT), and so is the coherent light A_T would scale
    return (1.0 - dR / R2 if R2 > 1e-12 else 1.0), (1.0 - dT / T2 if T2 > 1e-12 else 1.0)
