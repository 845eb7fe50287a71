"""The energy of the band-limited nano lobe: its scattered albedo over incidence (a polar quadrature about the mirror
direction; towards grazing angles of the lobe handed over to first-order perturbation theory, :mod:`.tangent_blend`),
and the coherent fraction of the specular reflection it leaves (docs/physics.md §9).

:class:`BandAlbedos` holds these as methods of :class:`waveoptics.scatter.BandSeries` (its base class): they need
the series itself (``self(wi, wo, cos_sum, q=...)``), its relevant roughness (``sigma2_rel``), ``k``, ``model``,
``wavelength_nm`` and the ``_albedos`` cache.

References
----------
.. [1] H. Davies, Proc. IEE 101, 209 (1954) (Debye-Waller factor of the coherent reflection).
.. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness).
.. [3] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
.. [4] E. I. Thorsos, JASA 83(1), 78–92, 1988 (the tangent plane fails towards grazing).
"""
from __future__ import annotations

import math

import numpy as np

from .perturbation import rayleigh_rice_albedo, rayleigh_rice_tis
from .polar import polar_albedo
from .tangent_blend import blend_with_first_order, uses_vector_first_order

__all__ = ["TANGENT_PLANE_MAX_DEG", "is_conductor", "ALBEDO_THETAS_DEG", "RR_THETAS_DEG", "rr_interp",
           "BandAlbedos"]


#: incidence angles (degrees) at which the lobe's albedo E¹(θ) is computed (:meth:`BandSeries.scattered_albedo`):
#: every degree from 70° to 88°, where the lobe hands over to first order (:mod:`.tangent_blend`; with 75° and 80°
#: only, linear interpolation put the albedo at 78° 19 % above the lobe's, ABC σ = 55 nm, B = 1 µm, C = 4) and
#: first order's albedo bends towards grazing (with 83° and 86° only, the lobe at 85° held 3.3 % more light than
#: the albedo interpolated there, ABC σ = 40 nm, B = 3.7 µm, C = 2.2, 550 nm, and the energy guard cut it)
ALBEDO_THETAS_DEG = np.concatenate([np.arange(0.0, 70.0, 5.0), np.arange(70.0, 88.5, 1.0), [89.0, 89.5, 89.9]])
#: incidence (degrees) up to which the tangent-plane lobe's own albedo is trusted (beyond it the two-scale lobe is
#: first order: :mod:`.tangent_blend`, :meth:`BandSeries.scattered_albedo`): up to it the Kirchhoff and Rayleigh-Rice
#: albedos agree within 5 % on Al (ABC σ = 20 nm, C = 2.6: 0.0449 and 0.0429 at 75°), beyond it they part
#: (0.055 and 0.043 at 80°, 0.094 and 0.035 at 85°)
TANGENT_PLANE_MAX_DEG = 75.0


def is_conductor(material) -> bool:
    """Whether the coherent fraction of *material* is the complement of its scattered light (a metal, or None: the
    F = 1 surface) or the Debye-Waller factor (dielectrics and semiconductors: they also transmit;
    :meth:`BandSeries.coherent_fraction`)."""
    return material is None or bool(getattr(material, "is_metal", False))


#: incidence nodes (degrees) of Rayleigh-Rice albedo tables: its TIS bends sharply towards grazing incidence
RR_THETAS_DEG = np.concatenate([np.arange(0.0, 80.0, 5.0), np.arange(80.0, 89.9, 0.5), [89.9]])


def rr_interp(theta_deg, table):
    """A Rayleigh-Rice albedo tabulated at :data:`RR_THETAS_DEG`, interpolated by monotone cubics (PCHIP): within
    4e-3 of the quadrature at any θ (measured 3.3e-3 over 200 incidences, tests/test_rayleigh_rice_nano.py) (linear interpolation on the Kirchhoff tables' nodes was 3.5 % off at 85°,
    which the coherent-loss guard then trimmed)."""
    from scipy.interpolate import PchipInterpolator

    t = np.clip(np.asarray(theta_deg, dtype=float), RR_THETAS_DEG[0], RR_THETAS_DEG[-1])
    return PchipInterpolator(RR_THETAS_DEG, np.asarray(table))(t)


class BandAlbedos:
    """The scattered albedo, grazing continuation and coherent fraction of a band-limited lobe (module doc): the
    base class of :class:`waveoptics.scatter.BandSeries`."""

    def albedo_tables(self) -> dict:
        """The albedo tables computed so far: {(diffraction model, material key, polarization, absolute):
        (nodes, raw, continued)} (:meth:`_tables`), for a caller that keeps them between processes."""
        return dict(self._albedos)

    def add_albedo_tables(self, tables: dict) -> None:
        """Take albedo tables of :meth:`albedo_tables` computed earlier for this same series (same model,
        wavelength and code; the caller's cache key holds them): a table known here is not computed again, and
        the series' own tables are then not needed for it."""
        for key, (nodes, raw, cont) in tables.items():
            self._albedos.setdefault(tuple(key), (np.asarray(nodes, dtype=float), np.asarray(raw, dtype=float),
                                                  np.asarray(cont, dtype=float)))

    def _tables(self, dm, material, polarization, absolute: bool):
        """(nodes, raw, continued): the lobe's scattered albedo at the nodes (degrees), relative to the specular
        reflectance or *absolute* (a share of the incident light), as computed and with the grazing continuation
        of :meth:`scattered_albedo` (the same for Rayleigh-Rice)."""
        pol = polarization if material is not None else "unpolarized"   # F = 1 has no polarization
        # a rough stack's tables also depend on its interfaces' roughness correlation (cache_name holds it)
        mkey = None if material is None else getattr(material, "cache_name", getattr(material, "name", str(material)))
        key = (dm.name, mkey, pol, bool(absolute))
        tab = self._albedos.get(key)
        if tab is not None:
            return tab
        lam, model = self.wavelength_nm, self.model
        # every incidence node in one quadrature (polar_albedo with an array of incidences)
        if dm.perturbative:   # Rayleigh-Rice: its TIS, relative to the specular reflectance or absolute
            fn = rayleigh_rice_tis if absolute else rayleigh_rice_albedo
            raw = np.asarray(fn(RR_THETAS_DEG, lam, model, material, pol), dtype=float)
            tab = (RR_THETAS_DEG, raw, raw)
        else:
            # raw: the tangent-plane lobe's own albedo; continued: that of the lobe the two-scale model carries,
            # handed over to first order beyond the tangent plane's validity (waveoptics.scatter.tangent_blend);
            # every incidence node in one quadrature
            raw, cont = self._albedo_at(np.radians(ALBEDO_THETAS_DEG), dm, material, pol, absolute)
            tab = (ALBEDO_THETAS_DEG, raw, cont)
        self._albedos[key] = tab
        return tab

    def scattered_albedo(self, theta_deg, diffraction="kirchhoff", material=None,
                         polarization: str = "unpolarized", absolute: bool = False) -> np.ndarray:
        """E(θ): the share of a facet's reflected light this lobe scatters, ∫ F(θ_h) f¹ cosθ_o dω_o / F(θ), under
        the *diffraction* model's factor K and vertical phase, at incidence θ (degrees; interpolated between
        :data:`ALBEDO_THETAS_DEG`). F is the *material*'s unpolarized Fresnel reflectance at the half-vector angle
        (each scattered direction is reflected by its own facet orientation), or 1 without a material (E¹).
        *absolute*: ∫ F(θ_h) f¹ cosθ_o dω_o itself, a share of the incident light (no division by F(θ), which
        vanishes for p light at Brewster's angle).

        Computed once per model on a polar grid about the mirror direction in the plane of the grating vector q
        (Gauss-Legendre in ln|q| from far below the PSD's knee, 48 azimuths: :func:`waveoptics.scatter.polar_albedo`;
        measured against a 512² direction-cosine grid: within 2e-3 relative, tests/test_band.py). This is the light
        a facet's nano-roughness scatters at that incidence: on a conductor the coherent fraction is its complement
        (:meth:`coherent_fraction`).

        *polarization* ``s`` or ``p`` (of the incident light, relative to the plane of incidence): each direction is
        weighted by its facet's polarized reflectance relative to the specular one,
        F_pol(θ_h) / R_pol(θ) (:func:`waveoptics.materials.fresnel.F_facet_polarized`), as the lobe itself is.

        **Grazing incidence.** Towards grazing angles the tangent-plane lobes (Kirchhoff, the Harvey-Shack family)
        are outside their validity: their factor K grows as 1/cosθ_i, so their albedo grows without bound (Al, ABC
        σ = 20 nm, C = 2.6: 0.094 at 85°, 0.36 at 89°, where first-order Rayleigh-Rice theory gives 0.035 and
        0.0088). The lobe the two-scale model carries hands over to the first-order Rayleigh-Rice lobe of the same
        PSD, W f_K + (1 − W) f_RR with W = w(θ_i) w(θ_o) (w 1 up to 70°, 0 from 80°;
        :mod:`waveoptics.scatter.tangent_blend`): reciprocal, and first order where grazing light puts every
        nano-roughness (kσ cosθ → 0), whose scatter falls to 0 at grazing incidence (Tatarskii & Charnotskii 1998).
        f_RR carries the vector Q of a *material* with a complex index, else (F = 1, F0 only, thin-film stacks) it
        is the scalar Q = 1 lobe times the Fresnel factor the tangent-plane lobe has. E here is the albedo of that
        blended lobe (the tables' *continued* column; the *raw* one is the tangent-plane lobe's own), the lobe every
        form carries (the paraxial grid route too, :func:`waveoptics.brdf.nano_lobe`). Rayleigh-Rice itself is taken
        as it is.
        TANGENT_PLANE_MAX_DEG (75°) is the incidence up to which the tangent-plane lobe's own albedo is trusted
        elsewhere (the planner, the validity docs).

        References
        ----------
        .. [1] E. I. Thorsos, "The validity of the Kirchhoff approximation for rough surface scattering using a
           Gaussian roughness spectrum", JASA 83(1), 78–92, 1988 (the tangent plane fails towards grazing).
        .. [2] V. I. Tatarskii, M. Charnotskii, "On the universal behavior of scattering from a rough surface for
           small grazing angles", IEEE Trans. Antennas Propag. 46(1), 67–72, 1998.
        .. [3] J. M. Elson, J. M. Bennett, Opt. Eng. 18(2), 1979 (first-order vector theory with Q).
        """
        from .models import get_model

        dm = get_model(diffraction, perturbative=True)
        nodes, _, tab = self._tables(dm, material, polarization, absolute)
        if dm.perturbative:
            return rr_interp(theta_deg, tab)
        return np.interp(np.asarray(theta_deg, dtype=float), nodes, tab)

    def debye_waller(self, cos_theta, diffraction="kirchhoff") -> np.ndarray:
        """exp(−g_rel), g_rel = (k σ_rel(θ) c)², c the *diffraction* model's specular cos_sum (2 cosθ, or 2 for
        the frozen-phase OHS/ROHS): the coherent share of the reflected field of the band-limited surface
        (Davies 1954; σ_rel, Krywonos, Harvey & Choi 2011)."""
        from .models import get_model

        dm = get_model(diffraction, perturbative=True)
        c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
        sin = np.sqrt(np.maximum(1.0 - c * c, 0.0))
        return np.exp(-self.k ** 2 * self.sigma2_rel(sin) * np.asarray(dm.specular_cos_sum(c)) ** 2)

    def coherent_fraction(self, cos_theta, diffraction="kirchhoff", material=None,
                          polarization: str = "unpolarized") -> np.ndarray:
        """A(θ): the share of a facet's specular reflectance R(θ) (s, p or unpolarized) that stays specular.

        *On a conductor* (a metal, or no material: F = 1) A = 1 − E(θ) by energy conservation from the light its
        nano-roughness scatters (:meth:`scattered_albedo`): there is no transmitted beam, so the scattered light
        can come only from the specular one. The Debye-Waller factor exp(−g_rel) is this complement only while the
        lobe is paraxial: for wide lobes (correlation lengths of a few λ, heavy-tailed PSDs) and oblique incidence
        the scattered light exceeds 1 − exp(−g_rel), and first-order Rayleigh-Rice theory with its full
        polarization factor, which conserves energy to that order on a perfect conductor (Rice 1951), agrees with
        E¹ and not with exp(−g_rel) (measured, σ = 10 nm ABC C = 2.8 on Al at 550 nm: RR TIS/F 0.0398 / 0.0299 /
        0.0134 at θ_i = 0 / 30 / 60°, E¹ 0.0393 / 0.0297 / 0.0131, 1 − exp(−g_rel) 0.0382 / 0.0272 / 0.0069;
        tests/test_band.py).

        *On a dielectric* (any material not of the metal category) A = exp(−g_rel) (:meth:`debye_waller`): the
        specular beam falls by the Debye-Waller factor of the relevant roughness (Davies 1954), while the light
        scattered into reflection is set by the polarization factors (Rayleigh-Rice's Q, or the lobe's Fresnel
        weights) and has its own albedo (Elson & Bennett 1979; Church, Jenkinson & Zavada 1979): the rough
        interface also scatters into the transmitted half-space and takes light from the transmitted beam, so
        the reflected scatter is not the specular beam's loss. For p light at Brewster's angle R_p = 0 and the
        coherent part vanishes while the lobe still scatters Rayleigh-Rice's TIS_p. s and p average to
        unpolarized light (A does not depend on the polarization).

        guard: a conductor's E can exceed 1 where first-order Rayleigh-Rice is used far outside its domain; A is
        then 0 (no specular light left), never negative.

        References
        ----------
        .. [1] H. Davies, Proc. IEE 101, 209 (1954) (Debye-Waller factor of the coherent reflection).
        .. [2] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
        .. [3] E. L. Church, H. A. Jenkinson, J. M. Zavada, Opt. Eng. 18(2), 125–136, 1979.
        .. [4] S. O. Rice, Commun. Pure Appl. Math. 4, 351–378, 1951.
        """
        c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
        if not is_conductor(material):
            return self.debye_waller(c, diffraction)
        E = self.scattered_albedo(np.degrees(np.arccos(c)), diffraction, material, polarization)
        return np.clip(1.0 - E, 0.0, 1.0)

    def scattered_share(self, cos_theta, diffraction="kirchhoff", material=None,
                        polarization: str = "unpolarized") -> np.ndarray:
        """The light a facet at incidence θ scatters, up to a factor common to all θ: 1 − A(θ) on a conductor
        (the coherent lobe's loss, :meth:`coherent_fraction`), the lobe's absolute albedo on a dielectric
        (:meth:`scattered_albedo` with *absolute*). Ratios of it weigh tilted facets against the macro incidence
        (:func:`waveoptics.brdf.facet_scatter_weights`)."""
        c = np.clip(np.asarray(cos_theta, dtype=float), 0.0, 1.0)
        if is_conductor(material):
            return 1.0 - self.coherent_fraction(c, diffraction, material, polarization)
        return self.scattered_albedo(np.degrees(np.arccos(c)), diffraction, material, polarization, absolute=True)

    def _albedo_at(self, theta, dm, material=None, polarization="unpolarized", absolute=False) -> tuple:
        """(tangent-plane lobe, blended lobe): ∫ f¹ du dv over the disc (:func:`polar_albedo`) of the lobe and of
        the lobe handed over to first order towards grazing angles
        (:func:`waveoptics.scatter.tangent_blend.blend_with_first_order`), each direction's Fresnel factor relative
        to F(θ) (for s or p light the facet's polarized reflectance relative to the specular one), or the factor
        itself (*absolute*), at incidence *theta* (rad; a float, or a 1-D array of incidences in one quadrature).
        The series is evaluated once: the second quadrature takes the first one's values at
        the same nodes."""
        from ..materials import RelativeFacetFresnel, fresnel_function

        lam = self.wavelength_nm
        if absolute and material is not None:   # each direction reflected by its own facet
            F = fresnel_function(material, polarization)
            if polarization == "unpolarized":
                def weight(wi_b, wo):
                    h = wi_b + wo
                    h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
                    return F(np.clip(np.sum(h * wi_b, axis=-1), 0.0, 1.0), lam)
            else:
                def weight(wi_b, wo):
                    return F.at(wi_b, wo, lam)
        else:
            ratio = RelativeFacetFresnel(material, polarization)

            def weight(wi_b, wo):
                return ratio.at(wi_b, wo, lam)

        seen = []

        def lobe(wi_b, wo, q):
            f, wgt = dm.K(wi_b, wo, lam) * self(wi_b, wo, dm.cos_sum(wi_b, wo), q=q), weight(wi_b, wo)
            seen.append((f, wgt))
            return f * wgt

        def blended(wi_b, wo, q):
            f, wgt = seen.pop(0)
            # the first-order lobe carries its own Q: over the facet's F (at the pairs it is needed), which wgt holds
            Fh = ((lambda a, b: material.F_facet(a, b, lam, polarization)) if uses_vector_first_order(material)
                  else None)
            return blend_with_first_order(f, wi_b, wo, lam, self.model, material, polarization, Fh) * wgt
        own = polar_albedo(theta, self.k, self.model.length_scale, lobe)
        return own, polar_albedo(theta, self.k, self.model.length_scale, blended)

