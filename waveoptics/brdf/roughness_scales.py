"""The two roughness scales of the two-scale BRDF: :class:`Micro` (an NDF, geometric optics) and :class:`Nano`
(height statistics or a height field, diffraction), with the coherent fraction A(λ, θ_d) of a facet
(:meth:`Nano.coherent_fraction`) and the light it scatters (:meth:`Nano.scattered_share`).

References
----------
.. [1] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 66, 2017.
.. [2] H. Davies, Proc. IEE 101, 209 (1954) (coherent fraction).
.. [3] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import scatter, surfaces
from ..errors import WaveopticsError
from ..vocabulary import DEFAULT_NDF
from ..surfaces.heightfield import HeightField
from .field_lobe import bracketing_nodes, field_scattered_albedo
from .ndf import ALPHA_MAX, ALPHA_MIN

__all__ = ['SERIES_MIN_CAPTURED', 'check_series', 'Micro', 'Nano', 'isotropic']


#: smallest share of the scattered light the truncated PSD series may hold in any direction (else it refuses)
SERIES_MIN_CAPTURED = 0.99


def check_series(model, lam):
    """Refuse nano-roughness the truncated PSD series cannot hold (its largest g, at cos θ_i + cos θ_o = 2; λ in
    nm): its terms must hold :data:`SERIES_MIN_CAPTURED` of the scattered light."""
    g = scatter.roughness_g(model.sigma, 2.0, lam)
    m_use = scatter.series_terms(g)
    captured = float(scatter.poisson_weights(g, m_use).sum() / -np.expm1(-g)) if g > 0 else 1.0
    if captured < SERIES_MIN_CAPTURED:
        raise WaveopticsError(
            f"nano-roughness sigma = {model.sigma * 1e9:.4g} nm is too rough for the PSD series at {lam:g} nm (it "
            f"holds only {100 * captured:.3g}% of the scattered light); use a nano height field (solver fft or "
            "direct), or describe roughness this large by the micro NDF (alpha)")


@dataclass(frozen=True)
class Micro:
    """Micro-scale roughness: an NDF name in :data:`waveoptics.brdf.NDFS`, α (and α_y), shadowing."""

    alpha: float = 0.05
    alpha_y: float | None = None
    ndf: str = DEFAULT_NDF   # one default NDF with the request and scene files (waveoptics.vocabulary)
    shadowing: str = "smith-correlated"
    ndf_shape: float | None = None   # the NDF's shape parameter (ABC's C, EPD's/SGD's p); None: its default

    def __post_init__(self):
        for name, a in (("alpha", self.alpha), ("alpha_y", self.alpha_y)):
            if a is not None and (not np.isfinite(a) or a < 0):
                raise WaveopticsError(f"micro {name}={a!r} is not allowed; it must be >= 0")
        if self.ndf_shape is not None:
            from .ndf import check_alpha, ndf_by_name

            check_alpha(min(self.alpha, ALPHA_MAX), None, ndf_by_name(self.ndf), self.ndf_shape)

    @classmethod
    def from_slopes(cls, table, shadowing: str = "smith-correlated") -> "Micro":
        """The micro roughness whose NDF is a measured slope law (:class:`waveoptics.brdf.SlopeTable`, from
        :func:`waveoptics.brdf.slope_table` or :func:`waveoptics.brdf.footprint_ndf`): NDF ``tabulated``, its D and
        Λ by quadrature of the table (Heitz 2014); α, α_y are the Beckmann-equivalent widths √2 × rms slope per
        axis, which only place quadrature nodes and size the lobe for the planner."""
        sx, sy = table.rms_slope()
        return cls(alpha=float(np.sqrt(2) * sx), alpha_y=float(np.sqrt(2) * sy), ndf="tabulated",
                   shadowing=shadowing, ndf_shape=table)

    def kw(self) -> dict:
        a = max(self.alpha, ALPHA_MIN)
        ay = None if self.alpha_y is None else max(self.alpha_y, ALPHA_MIN)
        return {"alpha": a, "alpha_y": ay, "ndf": self.ndf, "shadowing": self.shadowing, "ndf_shape": self.ndf_shape}


@dataclass(frozen=True)
class Nano:
    """Nano-scale roughness: height statistics (:class:`waveoptics.surfaces.PSDModel`) or a height field.

    With a height field the diffracted lobe comes from a Kirchhoff solver (``solver`` "fft" or "direct"); with
    statistics it comes from the PSD series (:mod:`waveoptics.scatter.series`).
    """

    model: surfaces.PSDModel | None = None
    surface: HeightField | None = None

    def __post_init__(self):
        if (self.model is None) == (self.surface is None):
            raise WaveopticsError("nano roughness needs exactly one of: PSD statistics or a height field")

    @property
    def sigma(self) -> float:
        """rms height (m) of the nano-roughness."""
        if self.model is not None:
            return self.model.sigma
        h = self.surface.heights
        return float(np.std(h[self.surface.mask] if self.surface.mask is not None else h))

    def coherent_fraction(self, cos_theta_d, wavelength_nm, diffraction="kirchhoff", material=None,
                            polarization: str = "unpolarized", azimuth_deg: float = 0.0):
        """A(λ, θ_d): fraction of the light a facet reflects coherently.

        On a dielectric (a *material* not of the metal category) with statistics, or with a height field's
        periodogram under Rayleigh-Rice, A is the Debye-Waller factor exp(−g_rel(θ_d)) of the roughness in the
        propagating band (Davies 1954), the same for s, p and unpolarized light, and the scattered light keeps
        its own albedo: a dielectric's rough interface also draws on the transmitted beam (Elson & Bennett 1979;
        :meth:`waveoptics.scatter.BandSeries.coherent_fraction`). On a conductor (a metal, or no material: F = 1),
        for statistics, 1 − E(θ_d) with E the share of the reflected light the nano lobe scatters at that incidence
        (weighted by the *material*'s Fresnel factor at each direction's half-vector; F = 1 without one): the light
        the facet's nano-roughness scatters is the light its specular reflection loses (energy conservation;
        :meth:`waveoptics.scatter.BandSeries.coherent_fraction`). The lobe is the Kirchhoff series of the roughness
        inside the propagating band (the relevant roughness, Krywonos, Harvey & Choi 2011; docs/physics.md §9), so
        variance in evanescent frequencies neither scatters nor reduces the specular light. While the lobe is
        paraxial this is the Davies (1954) factor exp(−(4πσ_rel cosθ_d/λ)²). For a height field it is the same
        complement, 1 − E_field(θ_d) (:func:`waveoptics.brdf.field_scattered_albedo`): E_field is the albedo of the field's own
        diffracted lobe |U − χ̂ U_flat|² (the lobe :func:`waveoptics.brdf.kirchhoff_scattered_lobe` gives, same samples, window and
        diffraction model; towards grazing angles handed over to the first-order lobe of the field's periodogram,
        :func:`waveoptics.brdf.field_scattered_lobe`, as the PSD route's is) on a direction grid of λ/(3L) cells,
        finer than the patch's spectrum varies, so
        nothing between the two halves is lost: roughness in evanescent frequencies neither scatters nor reduces
        the specular light (A = |χ̂|² would take the whole variance, and the albedo of heavy-tailed patches would
        fall up to 12 % short of F; tests/test_twoscale.py). One or two incidences asked at once (the macro incidence)
        are evaluated exactly at the azimuth *azimuth_deg* (degrees); a spread of facet incidences is interpolated
        by monotone cubics in a table over :data:`waveoptics.brdf.FIELD_THETAS_DEG` per wavelength, taken at azimuth 0 (the facets
        of a micro lobe face every azimuth; for an anisotropic field this is the share of light scattered in the
        x–z plane of incidence). Coherent and diffracted halves use the same values, so the energy balance does
        not depend on this choice. With *polarization* s or p E weighs each direction by its facet's polarized reflectance, as the
        polarized lobe does, so the two halves add up to R_s or R_p.
        """
        c = np.clip(np.asarray(cos_theta_d, dtype=float), 0.0, 1.0)
        dm = scatter.get_model(diffraction, perturbative=True)
        if dm.perturbative and self.surface is not None:   # Rayleigh-Rice of the field's periodogram
            return self._rayleigh_rice_coherent(c, wavelength_nm, material, azimuth_deg)
        if self.model is not None:   # conductor: 1 − E(θ_d); dielectric: exp(−g_rel(θ_d))
            return self._per_wavelength(c, wavelength_nm, lambda bs, cc: bs.coherent_fraction(cc, dm, material,
                                                                                              polarization))
        return self._field_coherent(c, wavelength_nm, dm, material, polarization, azimuth_deg)

    def scattered_share(self, cos_theta_d, wavelength_nm, diffraction="kirchhoff", material=None,
                        polarization: str = "unpolarized", azimuth_deg: float = 0.0):
        """The light a facet at local incidence θ_d scatters, up to a factor common to all θ_d (ratios of it weigh
        tilted facets, :func:`waveoptics.brdf.facet_scatter_weights`): 1 − A(θ_d) on a conductor and for a height field's
        Kirchhoff lobe; on a dielectric with statistics, or a height field's periodogram under Rayleigh-Rice, the
        lobe's own absolute albedo (its coherent fraction is the Debye-Waller factor, not the complement of its
        scatter: :meth:`waveoptics.scatter.BandSeries.coherent_fraction`)."""
        c = np.clip(np.asarray(cos_theta_d, dtype=float), 0.0, 1.0)
        dm = scatter.get_model(diffraction, perturbative=True)
        if self.surface is not None and dm.perturbative and not scatter.is_conductor(material):
            return self._rayleigh_rice_tis(c, wavelength_nm, material, polarization)
        if self.model is None or scatter.is_conductor(material):
            return 1.0 - np.asarray(self.coherent_fraction(c, wavelength_nm, dm, material, polarization,
                                                             azimuth_deg), dtype=float)
        return self._per_wavelength(c, wavelength_nm, lambda bs, cc: bs.scattered_share(cc, dm, material,
                                                                                         polarization))

    def _per_wavelength(self, c, wavelength_nm, fn):
        """fn(band_series(λ), cos) over broadcast (cos, λ) arrays, one band series per distinct λ."""
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            sel = lam_b == l_val
            out[sel] = fn(scatter.band_series(self.model, float(l_val)), c_b[sel])
        return out if out.ndim else float(out)

    def periodogram(self):
        """The height field's :class:`~waveoptics.surfaces.PeriodogramPSD` (computed once): its PSD where a
        perturbation model needs one."""
        cache = self.__dict__.setdefault("_cache", {})
        if "psd" not in cache:
            cache["psd"] = surfaces.PeriodogramPSD(self.surface)
        return cache["psd"]

    def _rayleigh_rice_coherent(self, c, wavelength_nm, material, azimuth_deg: float = 0.0):
        """1 − E_RR(θ) of the height field's periodogram (:func:`waveoptics.scatter.rayleigh_rice_albedo`, summed
        over its bins), on a conductor: one or two incidences (the macro one) exactly at *azimuth_deg*, as
        :meth:`_field_coherent` takes them, a spread of facet incidences from a table on
        :data:`waveoptics.scatter.band_energy.RR_THETAS_DEG` per wavelength and material at azimuth 0; on a
        dielectric the Debye-Waller factor of the periodogram's band (:meth:`_periodogram_debye_waller`)."""
        from ..scatter.band_energy import RR_THETAS_DEG, rr_interp

        if not scatter.is_conductor(material):   # a dielectric: the Debye-Waller factor of the periodogram's band
            return self._periodogram_debye_waller(c, wavelength_nm)
        cache = self.__dict__.setdefault("_cache", {})
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            key = ("rr", float(l_val), None if material is None else getattr(material, "cache_name", material.name))
            sel = lam_b == l_val
            asked = np.unique(c_b[sel])
            if asked.size <= 2 and float(azimuth_deg) != 0.0:   # the macro incidence: exactly, at its azimuth
                exact = cache.setdefault(key + ("exact", round(float(azimuth_deg), 9)), {})
                for a in asked:
                    if float(a) not in exact:
                        exact[float(a)] = float(scatter.rayleigh_rice_albedo(
                            float(np.degrees(np.arccos(a))), float(l_val), self.periodogram(), material,
                            azimuth_deg=float(azimuth_deg)))
                out[sel] = np.clip(1.0 - np.array([exact[float(a)] for a in c_b[sel]]), 0.0, 1.0)
                continue
            if key not in cache:
                cache[key] = np.array([scatter.rayleigh_rice_albedo(t, float(l_val), self.periodogram(), material)
                                       for t in RR_THETAS_DEG])
            E = rr_interp(np.degrees(np.arccos(c_b[sel])), cache[key])
            out[sel] = np.clip(1.0 - E, 0.0, 1.0)   # guard: first-order TIS above R means σ far outside its domain
        return out if out.ndim else float(out)

    def _periodogram_debye_waller(self, c, wavelength_nm):
        """exp(−(2k σ_rel cosθ)²), σ_rel² the height field's periodogram summed over the propagating disc of
        incidence θ (azimuth 0, the plane of the Rayleigh-Rice albedo), tabulated on
        :data:`waveoptics.scatter.band_energy.RR_THETAS_DEG` per wavelength and interpolated linearly in sinθ (Davies 1954;
        Krywonos, Harvey & Choi 2011; docs/physics.md §9)."""
        from ..scatter.band_energy import RR_THETAS_DEG

        cache = self.__dict__.setdefault("_cache", {})
        psd = self.periodogram()
        FX, FY = np.meshgrid(psd.fx, psd.fy)
        cell = (psd.fx[1] - psd.fx[0]) * (psd.fy[1] - psd.fy[0]) if psd.fx.size > 1 and psd.fy.size > 1 else 0.0
        sin_nodes = np.sin(np.radians(RR_THETAS_DEG))
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            key = ("rr-dw", float(l_val))
            R = 1.0 / (float(l_val) * 1e-9)
            if key not in cache:
                cache[key] = np.array([float(np.sum(psd.P[np.hypot(FX + s_ * R, FY) <= R])) * cell
                                       for s_ in sin_nodes])
            sel = lam_b == l_val
            cc = c_b[sel]
            s2 = np.interp(np.sqrt(np.maximum(1.0 - cc * cc, 0.0)), sin_nodes, cache[key])
            out[sel] = np.exp(-(2 * np.pi * R * 2 * cc) ** 2 * s2)
        return out if out.ndim else float(out)

    def _rayleigh_rice_tis(self, c, wavelength_nm, material, polarization):
        """TIS(θ) of the height field's periodogram (absolute, :func:`waveoptics.scatter.rayleigh_rice_tis`),
        tabulated on :data:`waveoptics.scatter.band_energy.RR_THETAS_DEG` per wavelength, material and polarization."""
        from ..scatter.band_energy import RR_THETAS_DEG, rr_interp

        cache = self.__dict__.setdefault("_cache", {})
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            key = ("rr-tis", float(l_val), None if material is None else getattr(material, "cache_name", material.name), polarization)
            if key not in cache:
                cache[key] = np.array([scatter.rayleigh_rice_tis(t, float(l_val), self.periodogram(), material,
                                                                 polarization) for t in RR_THETAS_DEG])
            sel = lam_b == l_val
            out[sel] = rr_interp(np.degrees(np.arccos(c_b[sel])), cache[key])
        return out if out.ndim else float(out)

    def _field_coherent(self, c, wavelength_nm, dm, material, polarization, azimuth_deg):
        """1 − E_field(θ_d) of the height field per wavelength (see :meth:`coherent_fraction`)."""
        from scipy.interpolate import PchipInterpolator

        cache = self.__dict__.setdefault("_cache", {})
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        theta = np.degrees(np.arccos(c_b))
        out = np.empty(c_b.shape)
        phi = round(float(azimuth_deg), 9)
        for l_val in np.unique(lam_b):
            sel = lam_b == l_val
            key = (float(l_val), dm.name, None if material is None else material.name, polarization)
            asked = np.unique(theta[sel])

            def E_at(t, phi_deg, l_val=float(l_val)):
                return field_scattered_albedo(self.surface, float(t), l_val, dm, material, polarization, phi_deg,
                                              psd=self.periodogram())

            if asked.size <= 2:   # single incidences (the macro one): exactly, at their own azimuth
                exact = cache.setdefault(("field-exact",) + key, {})
                for t in asked:
                    if (float(t), phi) not in exact:
                        exact[(float(t), phi)] = E_at(t, phi)
                E = np.array([exact[(float(t), phi)] for t in theta[sel]])
            else:                 # a spread of facet incidences: the table's nodes that bracket it
                nodes = cache.setdefault(("field-nodes",) + key, {})
                for t in bracketing_nodes(asked[0], asked[-1]):
                    if float(t) not in nodes:
                        nodes[float(t)] = E_at(t, 0.0)
                ts = np.array(sorted(nodes))
                E = PchipInterpolator(ts, [nodes[t] for t in ts], extrapolate=True)(theta[sel])
            out[sel] = _complement_of_albedo(E, l_val)
        return out if out.ndim else float(out)


def _complement_of_albedo(E, wavelength_nm):
    """1 − E of a height field's scattered shares E (:meth:`Nano.coherent_fraction`).

    guard: E > 1 would leave negative specular light; A is then 0 and a DiffractionWarning names how much light
    the clip removed. The field's lobe hands over to first order towards grazing angles
    (:func:`waveoptics.brdf.field_scattered_lobe`), so E stays far below 1 where the nano-roughness is nano (it never
    acts for ABC σ 8 nm fields on Al, micro α 0.1 at θ_i 89-89.5°, tests/test_heightfield_grazing.py)."""
    E = np.asarray(E, dtype=float)
    if np.any(E > 1.0):
        import warnings

        warnings.warn(f"height field's coherent fraction clipped at 0 at {float(wavelength_nm):g} nm: its lobe "
                      f"scatters {float(E.max()):.4g} of the specular light (the clip removed "
                      f"{float(E.max()) - 1:.3g})", scatter.DiffractionWarning, stacklevel=3)
    return np.clip(1.0 - E, 0.0, 1.0)


def isotropic(micro: Micro, nano) -> bool:
    """Whether a two-scale BRDF depends on the azimuths only through φ_o − φ_i (one rule for every table, render
    and cost estimate): an isotropic micro NDF (no ``alpha_y``) and nano-roughness that is none or isotropic
    statistics (a PSD model; a height field, even an isotropic one, is a single realization with its own azimuthal
    structure).

    Parameters
    ----------
    micro : Micro
    nano : Nano, None or bool
        The nano-roughness, or (for a caller that knows only the request's specification) whether it is given by
        statistics.
    """
    statistical = nano if isinstance(nano, bool) else (nano is None or nano.model is not None)
    return micro.alpha_y is None and statistical
