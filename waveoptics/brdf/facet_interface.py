"""What one flat facet of a rough dielectric reflects and transmits: the facet interface that
:class:`waveoptics.brdf.RoughDielectricBSDF` asks for R and T per facet.

* :class:`BareInterface`: air over a dielectric of real index η, R = F(|i·m|, η_t/η_i) the exact unpolarized
  Fresnel reflectance and T = 1 − F (Born & Wolf §1.5.2; total internal reflection from inside: R = 1, T = 0).
* :class:`CoatedInterface`: the same substrate under thin films (an anti-reflection coating), each facet a flat
  stack (the films follow the micro-roughness conformally). R and T are the stack's unpolarized reflectance and
  Poynting-flux transmittance into the medium across (:func:`waveoptics.materials.stack.R`, ``T``: s and p averaged).
  Light from the glass side sees the stack reversed: the substrate is then the incidence medium and air the
  medium beyond, the films in the reverse order. Thin parallel layers do not change the refracted direction (n sin θ
  is conserved across them: Snell's law between air and the substrate), so the BSDF's geometry keeps η = Re n of the
  substrate; absorbing films lose A = 1 − R − T per facet. Transmittance is reciprocal, T₁₂(θ₁) = T₂₁(θ₂) for
  Snell-related angles (Stokes relations of the whole stack; Born & Wolf §1.6.4), which keeps the BSDF's
  η² reciprocity rule.

:func:`facet_interface_of` picks the interface of a material at one wavelength (:data:`FACET_INTERFACES`, by whether
the material has a single index); :func:`as_interface` takes a bare real index as its :class:`BareInterface`.

References
----------
.. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.2-1.5.3 (Fresnel formulae, energy flux), §1.6.4
   (stratified media: one film's Airy formula; reciprocity of transmission).
.. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press 2010, ch. 2 (transmittance of a stack),
   ch. 4 (anti-reflection coatings).
.. [3] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, EGSR 2007, eqs. (20), (21) (F and 1 − F of each facet).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..materials import fresnel as _fresnel
from ..materials import stack as _stack

__all__ = ['bulk_medium', 'BareInterface', 'CoatedInterface', 'FACET_INTERFACES', 'facet_interface_of', 'as_interface']


@dataclass(frozen=True)
class BareInterface:
    """Air (index 1) over a dielectric of real index ``eta``: R = F, T = 1 − F per facet (module doc)."""

    eta: float
    #: R + T = 1 per facet
    lossless = True

    def RT(self, cos_i, from_above):
        """(R, T) (dimensionless) of facets seen at |cos| *cos_i* from air (*from_above* True) or from the glass.

        References
        ----------
        .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.2.
        """
        F = _fresnel.F(cos_i, np.where(from_above, self.eta, 1.0 / self.eta))
        return F, 1.0 - F


@dataclass(frozen=True)
class CoatedInterface:
    """Air over thin films over a dielectric of real index ``eta``, at ``wavelength_nm`` (nm): ``n_films`` (complex
    indices) and ``d_films_nm`` (nm) from the substrate outwards (module doc)."""

    eta: float
    n_films: tuple
    d_films_nm: tuple
    wavelength_nm: float

    @property
    def lossless(self) -> bool:
        """True when no film absorbs (k = 0): R + T = 1 per facet."""
        return all(np.imag(n) == 0 for n in self.n_films)

    def RT(self, cos_i, from_above):
        """(R, T) (dimensionless; R + T < 1 with absorbing films) of facets seen at |cos| *cos_i* from air
        (*from_above* True: the stack as written) or from the glass (the stack reversed).

        References
        ----------
        .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.3, §1.6.4.
        .. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.6.
        """
        c = np.asarray(cos_i, dtype=float)
        up = np.broadcast_to(from_above, c.shape)
        R, T = np.zeros(c.shape), np.zeros(c.shape)
        lam = self.wavelength_nm
        sides = ((up, self.eta, self.n_films, self.d_films_nm, 1.0),
                 (~up, 1.0, self.n_films[::-1], self.d_films_nm[::-1], self.eta))
        for sel, n_beyond, films, d, n_inc in sides:
            if np.any(sel):
                R[sel] = _stack.R(c[sel], lam, n_beyond, films, d, n_incident=n_inc)
                T[sel] = _stack.T(c[sel], lam, n_beyond, films, d, n_incident=n_inc)
        return R, T


def _bare(material, wavelength_nm: float) -> BareInterface:
    return BareInterface(float(np.real(material.eta(np.array([wavelength_nm]))[0])))


def _coated(material, wavelength_nm: float) -> CoatedInterface:
    n_sub, n_films = material.indices(np.array([wavelength_nm]))
    return CoatedInterface(float(np.real(n_sub[0])), tuple(complex(n[0]) for n in n_films),
                           tuple(material.thicknesses_nm), float(wavelength_nm))


#: the facet interface of a material by whether it has a single index (``Material.has_index``): a bare
#: dielectric, or a thin-film stack (:class:`waveoptics.materials.Stack`) on a dielectric substrate
FACET_INTERFACES = {True: _bare, False: _coated}


def facet_interface_of(material, wavelength_nm: float):
    """The facet interface (:class:`BareInterface` or :class:`CoatedInterface`) of *material* at *wavelength_nm*
    (nm); its ``eta`` is Re n of the (substrate) dielectric."""
    return FACET_INTERFACES[bool(material.has_index)](material, float(wavelength_nm))


def bulk_medium(material):
    """The material whose index the light has inside the glass: *material* itself (one index), or a thin-film
    stack's substrate (films thinner than the coherence length change what a facet reflects and transmits, not the
    medium the transmitted light travels in: its direction obeys Snell's law between air and the substrate; Born &
    Wolf, *Principles of Optics*, 7th ed., §1.6.1)."""
    return material if material.has_index else material.substrate


def as_interface(eta_or_interface):
    """A facet interface as given, or the :class:`BareInterface` of a real index η."""
    if hasattr(eta_or_interface, "RT"):
        return eta_or_interface
    return BareInterface(float(eta_or_interface))
