"""Two-scale BRDF: microfacets (geometric optics) carrying nano-roughness (diffraction).

Structure (Holzschuch & Pacanowski 2017; docs/physics.md §7). Micro-geometry, much larger than λ, is described by a
microfacet NDF D with roughness α; each microfacet carries nano-roughness of rms height σ_nano about λ or smaller.
Per microfacet the light splits into

* a coherent part, the fraction A(λ, θ_d) of the Fresnel-reflected light that keeps the microfacet specular
  lobe, f_c = A · F G D / (4 cosθ_i cosθ_o): on a conductor what the facet's nano lobe leaves, 1 − E(θ_d) (E the
  share of the reflected light that lobe scatters; Davies' exp(−(4π σ_rel cos θ_d / λ)²) while it is paraxial,
  σ_rel the roughness inside the propagating band); on a dielectric that Debye-Waller factor itself, the scattered
  light keeping its own albedo (:meth:`Nano.coherent_amplitude2`, docs/physics.md §9);
* a diffracted part, the nano-roughness scattering lobe f_n (PSD series or a Kirchhoff solver on a nano height
  field) carried by each microfacet in the facet's own frame: Walter et al.'s integral of a facet BRDF,
  f_diff = ∫ |ω_i·m||ω_o·m| / (|ω_i·n||ω_o·n|) f_n(ω_i^m, ω_o^m) G D(m) dm (docs/physics.md §7);
* for dielectrics, a diffuse term with the diffuse-specular trade-off (metals have none).

Evaluation on the direction-cosine plane
----------------------------------------
Lobes live on a :class:`waveoptics.scatter.DirectionGrid` over (u, v) = (sinθ cosφ, sinθ sinφ), where
cosθ_o dω_o = du dv. For PSD statistics the diffracted part is the facet integral itself
(:func:`facet_frame_diffraction`): per cell, a balance-heuristic quadrature over facet normals drawn from the micro
NDF and about the cell's half-vector, each facet's nano lobe read from tables over local incidence
(:data:`FACET_THETAS_DEG`) in that facet's frame. For a nano height field, and for a PSD lobe narrower than the
cells, it is the paraxial form (:func:`facet_route`; ``facet="paraxial"`` by name): the nano lobe at the macro
incidence is convolved with the *micro kernel* K, the F = 1 microfacet lobe f_mf(ω_i, ·) du dv re-centred on the
mirror direction, i.e. shifted to each facet's mirror direction instead of being turned with the facet (accurate
where each facet's lobe is narrow; docs/physics.md §7 gives its error on wide lobes). Both limits hold on the grid:
σ_nano → 0 gives A = 1 and f_n = 0 (the microfacet model), and α → 0 gives the pure nano lobe. Light a facet's lobe
sends below the macro horizon, or that is masked on its way out, is reported
(``info["diffraction_beyond_horizon"]``).

A specular lobe narrower than the grid (α ≲ du) cannot be sampled: its energy F·A·ρ_mf is deposited in the
mirror cell as a spike of height E/(du dv), which keeps albedo and colour exact on the grid.

References
----------
.. [1] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 66, 2017.
.. [2] B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet models for refraction through rough surfaces",
   EGSR 2007 (microfacet BRDF of a general facet BRDF, eq. 14).
.. [3] H. Davies, Proc. IEE 101, 209 (1954) (coherent fraction).
.. [4] E. Veach, PhD thesis, Stanford 1997, §9.2 (balance heuristic).
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from .. import scatter, surfaces
from ..errors import FieldError, WaveopticsError, unknown
from ..materials import Material, fresnel_function, get_material
from ..runtime import get_runtime
from ..scatter.grid import DirectionGrid, integrate
from ..surfaces.heightfield import HeightField
from ..units import check_wavelengths
from .diffuse import DIFFUSES, diffuse_tradeoff
from .microfacet import specular
from .ndf import ALPHA_MAX, ALPHA_MIN, NDFS
from .quadrature import albedo, directional_albedo

__all__ = ['SERIES_MIN_CAPTURED', 'check_series', 'NARROW_CELLS', 'CAP_TOLERANCE', 'Micro', 'Nano', 'Lobes', 'micro_kernel', 'kernel_cos_theta_d', 'facet_scatter_weights', 'nano_lobe', 'kirchhoff_scattered_lobe', 'FACET_THETAS_DEG', 'FACET_NODES_NARROW', 'FACET_NODES_WIDE', 'FACET_NODE_SPLIT', 'FACET_REFERENCE_NM', 'FACET_ROUTES', 'facet_nodes', 'facet_route', 'facet_frame_diffraction', 'FIELD_THETAS_DEG', 'FIELD_GRID_OVERSAMPLING', 'field_scattered_albedo', 'FACET_TAIL_SHARE', 'facet_incidences_deg', 'field_albedo_evaluations', 'evaluate', 'multiple_scattering_lobe', 'SPLIT_PERIODS_OF_LAMBDA', 'split_scales']


#: smallest share of the scattered light the truncated PSD series may hold in any direction (else it refuses)
SERIES_MIN_CAPTURED = 0.99
#: a PSD nano lobe narrower than this many grid cells (width λ/(π T)) is resampled preserving its energy
NARROW_CELLS = 2.0


@dataclass(frozen=True)
class Micro:
    """Micro-scale roughness: an NDF name in :data:`waveoptics.brdf.NDFS`, α (and α_y), shadowing."""

    alpha: float = 0.05
    alpha_y: float | None = None
    ndf: str = "ggx"
    shadowing: str = "smith-correlated"
    ndf_shape: float | None = None   # the NDF's shape parameter (ABC's C, EPD's/SGD's p); None: its default

    def __post_init__(self):
        for name, a in (("alpha", self.alpha), ("alpha_y", self.alpha_y)):
            if a is not None and (not np.isfinite(a) or a < 0):
                raise WaveopticsError(f"micro {name}={a!r} is not allowed; it must be >= 0")
        if self.ndf_shape is not None:
            from .ndf import _check_alpha, _ndf

            _check_alpha(min(self.alpha, ALPHA_MAX), None, _ndf(self.ndf), self.ndf_shape)

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

    def coherent_amplitude2(self, cos_theta_d, wavelength_nm, diffraction="kirchhoff", material=None,
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
        complement, 1 − E_field(θ_d) (:func:`field_scattered_albedo`): E_field is the albedo of the field's own
        diffracted lobe |U − χ̂ U_flat|² (the lobe :func:`kirchhoff_scattered_lobe` gives, same samples, window and
        diffraction model) on a direction grid of λ/(3L) cells, finer than the patch's spectrum varies, so
        nothing between the two halves is lost: roughness in evanescent frequencies neither scatters nor reduces
        the specular light (before, A = |χ̂|² took the whole variance and the albedo of heavy-tailed patches fell
        up to 12 % short of F; tests/test_twoscale.py). One or two incidences asked at once (the macro incidence)
        are evaluated exactly at the azimuth *azimuth_deg* (degrees); a spread of facet incidences is interpolated
        by monotone cubics in a table over :data:`FIELD_THETAS_DEG` per wavelength, taken at azimuth 0 (the facets
        of a micro lobe face every azimuth; for an anisotropic field this is the share of light scattered in the
        x–z plane of incidence). Coherent and diffracted halves use the same values, so the energy balance does
        not depend on this choice. With *polarization* s or p E weighs each direction by its facet's polarized reflectance, as the
        polarized lobe does, so the two halves add up to R_s or R_p.
        """
        c = np.clip(np.asarray(cos_theta_d, dtype=float), 0.0, 1.0)
        dm = scatter.get_model(diffraction, perturbative=True)
        if dm.perturbative and self.surface is not None:   # Rayleigh-Rice of the field's periodogram
            return self._rayleigh_rice_coherent(c, wavelength_nm, material)
        if self.model is not None:   # conductor: 1 − E(θ_d); dielectric: exp(−g_rel(θ_d))
            return self._per_wavelength(c, wavelength_nm, lambda bs, cc: bs.coherent_fraction(cc, dm, material,
                                                                                              polarization))
        return self._field_coherent(c, wavelength_nm, dm, material, polarization, azimuth_deg)

    def scattered_share(self, cos_theta_d, wavelength_nm, diffraction="kirchhoff", material=None,
                        polarization: str = "unpolarized", azimuth_deg: float = 0.0):
        """The light a facet at local incidence θ_d scatters, up to a factor common to all θ_d (ratios of it weigh
        tilted facets, :func:`facet_scatter_weights`): 1 − A(θ_d) on a conductor and for a height field's
        Kirchhoff lobe; on a dielectric with statistics, or a height field's periodogram under Rayleigh-Rice, the
        lobe's own absolute albedo (its coherent fraction is the Debye-Waller factor, not the complement of its
        scatter: :meth:`waveoptics.scatter.BandSeries.coherent_fraction`)."""
        c = np.clip(np.asarray(cos_theta_d, dtype=float), 0.0, 1.0)
        dm = scatter.get_model(diffraction, perturbative=True)
        if self.surface is not None and dm.perturbative and not scatter.is_conductor(material):
            return self._rayleigh_rice_tis(c, wavelength_nm, material, polarization)
        if self.model is None or scatter.is_conductor(material):
            return 1.0 - np.asarray(self.coherent_amplitude2(c, wavelength_nm, dm, material, polarization,
                                                             azimuth_deg), dtype=float)
        return self._per_wavelength(c, wavelength_nm, lambda bs, cc: bs.scattered_share(cc, dm, material,
                                                                                         polarization))

    def lobe_energy_scale(self, cos_theta_i, wavelength_nm, diffraction="kirchhoff", material=None,
                          polarization: str = "unpolarized"):
        """The factor that gives a statistics lobe at incidence θ_i its scattered albedo continued beyond the
        tangent plane's validity (:meth:`waveoptics.scatter.BandSeries.lobe_energy_scale`; 1 up to
        :data:`waveoptics.scatter.band.TANGENT_PLANE_MAX_DEG`, for Rayleigh-Rice and for height fields)."""
        c = np.clip(np.asarray(cos_theta_i, dtype=float), 0.0, 1.0)
        if self.model is None:
            return np.ones(np.broadcast_shapes(c.shape, np.shape(wavelength_nm)))
        dm = scatter.get_model(diffraction, perturbative=True)
        return self._per_wavelength(c, wavelength_nm, lambda bs, cc: bs.lobe_energy_scale(
            np.degrees(np.arccos(cc)), dm, material, polarization))

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

    def _rayleigh_rice_coherent(self, c, wavelength_nm, material):
        """1 − E_RR(θ) of the height field's periodogram (:func:`waveoptics.scatter.rayleigh_rice_albedo`),
        tabulated on :data:`waveoptics.scatter.band.RR_THETAS_DEG` per wavelength and material, on a conductor; on a
        dielectric the Debye-Waller factor of the periodogram's band (:meth:`_periodogram_debye_waller`)."""
        from ..scatter.band import RR_THETAS_DEG, rr_interp

        if not scatter.is_conductor(material):   # a dielectric: the Debye-Waller factor of the periodogram's band
            return self._periodogram_debye_waller(c, wavelength_nm)
        cache = self.__dict__.setdefault("_cache", {})
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            key = ("rr", float(l_val), None if material is None else material.name)
            if key not in cache:
                cache[key] = np.array([scatter.rayleigh_rice_albedo(t, float(l_val), self.periodogram(), material)
                                       for t in RR_THETAS_DEG])
            sel = lam_b == l_val
            E = rr_interp(np.degrees(np.arccos(c_b[sel])), cache[key])
            out[sel] = np.clip(1.0 - E, 0.0, 1.0)   # guard: first-order TIS above R means σ far outside its domain
        return out if out.ndim else float(out)

    def _periodogram_debye_waller(self, c, wavelength_nm):
        """exp(−(2k σ_rel cosθ)²), σ_rel² the height field's periodogram summed over the propagating disc of
        incidence θ (azimuth 0, the plane of the Rayleigh-Rice albedo), tabulated on
        :data:`waveoptics.scatter.band.RR_THETAS_DEG` per wavelength and interpolated linearly in sinθ (Davies 1954;
        Krywonos, Harvey & Choi 2011; docs/physics.md §9)."""
        from ..scatter.band import RR_THETAS_DEG

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
        tabulated on :data:`waveoptics.scatter.band.RR_THETAS_DEG` per wavelength, material and polarization."""
        from ..scatter.band import RR_THETAS_DEG, rr_interp

        cache = self.__dict__.setdefault("_cache", {})
        lam = np.asarray(wavelength_nm, dtype=float)
        c_b, lam_b = np.broadcast_arrays(c, lam)
        out = np.empty(c_b.shape)
        for l_val in np.unique(lam_b):
            key = ("rr-tis", float(l_val), None if material is None else material.name, polarization)
            if key not in cache:
                cache[key] = np.array([scatter.rayleigh_rice_tis(t, float(l_val), self.periodogram(), material,
                                                                 polarization) for t in RR_THETAS_DEG])
            sel = lam_b == l_val
            out[sel] = rr_interp(np.degrees(np.arccos(c_b[sel])), cache[key])
        return out if out.ndim else float(out)

    def _field_coherent(self, c, wavelength_nm, dm, material, polarization, azimuth_deg):
        """1 − E_field(θ_d) of the height field per wavelength (see :meth:`coherent_amplitude2`)."""
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
                return field_scattered_albedo(self.surface, float(t), l_val, dm, material, polarization, phi_deg)

            if asked.size <= 2:   # single incidences (the macro one): exactly, at their own azimuth
                exact = cache.setdefault(("field-exact",) + key, {})
                for t in asked:
                    if (float(t), phi) not in exact:
                        exact[(float(t), phi)] = E_at(t, phi)
                E = np.array([exact[(float(t), phi)] for t in theta[sel]])
            else:                 # a spread of facet incidences: the table's nodes that bracket it
                nodes = cache.setdefault(("field-nodes",) + key, {})
                for t in _bracketing_nodes(asked[0], asked[-1]):
                    if float(t) not in nodes:
                        nodes[float(t)] = E_at(t, 0.0)
                ts = np.array(sorted(nodes))
                E = PchipInterpolator(ts, [nodes[t] for t in ts], extrapolate=True)(theta[sel])
            # guard: near grazing incidence the tangent-plane lobe's albedo exceeds 1 (docs/two-scale.md): no
            # specular light is left there, A = 0, never negative
            out[sel] = np.clip(1.0 - E, 0.0, 1.0)
        return out if out.ndim else float(out)


@dataclass
class Lobes:
    """A two-scale evaluation for one incident direction on a direction grid.

    Arrays are (n_λ, n_v, n_u) in 1/sr: ``coherent`` (micro specular × A), ``diffraction`` (the nano lobe carried
    by the micro facets), ``diffuse`` (dielectrics), ``multiple`` (the multiple-scattering compensation lobe, or
    None when it is off), ``total``; ``microfacet`` is the plain microfacet model (same micro roughness,
    material, diffuse term and compensation lobe; no nano-roughness) for comparison.
    """

    grid: DirectionGrid
    wi: np.ndarray
    wavelengths_nm: np.ndarray
    coherent: np.ndarray
    diffraction: np.ndarray
    diffuse: np.ndarray
    microfacet: np.ndarray
    info: dict = field(default_factory=dict)
    diffuse_albedo: np.ndarray | None = None
    multiple: np.ndarray | None = None
    multiple_albedo: np.ndarray | None = None

    @property
    def total(self) -> np.ndarray:
        t = self.coherent + self.diffraction + self.diffuse
        return t if self.multiple is None else t + self.multiple

    def albedo(self, part: str = "total") -> np.ndarray:
        """Directional albedo per wavelength of a part (``total``, ``coherent``, ``diffraction``, ``multiple``,
        ...).

        The diffuse term's and the compensation lobe's shares are their exact albedos (``diffuse_albedo``, a
        quadrature of the closed form; ``multiple_albedo`` = (1 − E(μ_i)) F_ms by construction), not the grid
        sums: cells straddling the rim of the projected disc are counted whole by the grid sum, which over-counts
        a lobe that reaches the horizon (Lambert, kd = 1: 1.005 at 8² cells, 0.984 at 16², 0.961 at 128²,
        against 0.9615 exactly). Sharp lobes are the grid's own (they are normalized on it)."""
        if part == "multiple" and self.multiple is None:
            return np.zeros(self.wavelengths_nm.size)
        a = integrate(getattr(self, part), self.grid)
        if self.diffuse_albedo is not None and part in ("total", "microfacet", "diffuse"):
            a = a - integrate(self.diffuse, self.grid) + self.diffuse_albedo
        if self.multiple is not None and self.multiple_albedo is not None and part in ("total", "microfacet",
                                                                                      "multiple"):
            a = a - integrate(self.multiple, self.grid) + self.multiple_albedo
        return a

    def coherent_specular_fraction(self) -> np.ndarray:
        """Share of the specularly reflected energy that stays coherent: E_c / (E_c + E_diffraction)."""
        c, d = self.albedo("coherent"), self.albedo("diffraction")
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(c + d > 0, c / (c + d), 1.0)


def _mirror(wi):
    return np.array([-wi[0], -wi[1], wi[2]])


def _F_mirror(F, wi, lam):
    """The Fresnel factor at the mirror direction (R(θ_i), or R_s / R_p for polarized light)."""
    if hasattr(F, "at"):
        return F.at(wi, _mirror(wi), lam)
    return F(wi[2], lam)


def _mirror_cell(grid: DirectionGrid, wi):
    """(row, col) of the cell containing the mirror direction, or None if outside the grid."""
    u, v = -wi[0], -wi[1]
    j = int(np.floor((u - grid.u_range[0]) / grid.du))
    i = int(np.floor((v - grid.v_range[0]) / grid.dv))
    if 0 <= i < grid.n_v and 0 <= j < grid.n_u:
        return i, j
    return None


def _sharp(micro: Micro, grid: DirectionGrid) -> bool:
    """Whether the micro lobe is narrower than a grid cell (then it is a spike on this grid)."""
    a = micro.alpha if micro.alpha_y is None else min(micro.alpha, micro.alpha_y)
    return a < 0.75 * min(grid.du, grid.dv)


def micro_kernel(wi, micro: Micro, grid: DirectionGrid) -> np.ndarray:
    """The F = 1 micro lobe f_mf du dv (energy per cell), re-centred on the mirror direction, as a (2n_v−1, 2n_u−1) kernel.

    Its sum is the F = 1 microfacet albedo ρ_mf(ω_i) ≤ 1 (masking-shadowing and the horizon included); for a
    lobe narrower than a cell it is a unit impulse times ρ_mf. Used to convolve per-facet lobes.
    """
    n_v, n_u = grid.n_v, grid.n_u
    K = np.zeros((2 * n_v - 1, 2 * n_u - 1))
    wi = np.asarray(wi, dtype=float)
    rho = float(albedo(wi, fresnel="one", **micro.kw())) if wi[2] > 0 else 0.0
    if _sharp(micro, grid):
        K[n_v - 1, n_u - 1] = rho
        return K
    m = _mirror(wi)
    du = (np.arange(2 * n_u - 1) - (n_u - 1)) * grid.du
    dv = (np.arange(2 * n_v - 1) - (n_v - 1)) * grid.dv
    U, V = np.meshgrid(m[0] + du, m[1] + dv)
    s2 = U * U + V * V
    inside = s2 < 1.0
    wo = np.stack([U, V, np.sqrt(np.clip(1 - s2, 0, 1))], axis=-1)
    f = specular(wi, wo, fresnel="one", **micro.kw())
    K = np.where(inside, f, 0.0) * grid.du * grid.dv
    # f du dv = f cosθ_o dω_o: K holds the energy per cell. Rescale to the accurate quadrature albedo so
    # that coarse grids neither add nor lose energy.
    s = K.sum()
    return K * (rho / s) if s > 0 else K


def kernel_cos_theta_d(wi, grid: DirectionGrid) -> np.ndarray:
    """cos θ_d = ω_i · h of the facet behind each cell of :func:`micro_kernel` (the facet that reflects ω_i into the
    mirror direction shifted by that cell): the local incidence angle of its nano-roughness."""
    wi = np.asarray(wi, dtype=float)
    n_v, n_u = grid.n_v, grid.n_u
    m = _mirror(wi)
    U, V = np.meshgrid(m[0] + (np.arange(2 * n_u - 1) - (n_u - 1)) * grid.du,
                       m[1] + (np.arange(2 * n_v - 1) - (n_v - 1)) * grid.dv)
    wo = np.stack([U, V, np.sqrt(np.clip(1 - U * U - V * V, 0, 1))], axis=-1)
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    return np.clip(h @ wi, 0.0, 1.0)


def facet_scatter_weights(wi, wavelengths_nm, nano: Nano, grid: DirectionGrid, diffraction="kirchhoff",
                          material=None, polarization: str = "unpolarized", kernel=None):
    """Per-facet share of scattered light relative to the macro incidence: (1 − A(θ_d)) / (1 − A(θ_i)) on the
    kernel grid, (n_λ, 2n_v − 1, 2n_u − 1).

    The nano lobe is computed once, at the macro incidence θ_i, and shifted to every facet (paraxial
    convolution); but each facet scatters the share 1 − A(θ_d) of its own local incidence, the share its coherent
    lobe gives up (Holzschuch & Pacanowski 2017, per-facet split; docs/physics.md §7, §9). Weighting the kernel
    by this ratio makes the diffracted light of every facet equal to the light its coherent lobe lost (measured
    without it: micro α = 0.3 at normal incidence put 6.5 % more light in the diffracted lobe than the coherent lobe
    gave up).
    """
    cos_d = kernel_cos_theta_d(wi, grid)
    out = np.ones((len(wavelengths_nm),) + cos_d.shape)
    phi = _azimuth_deg(wi)
    # a height field's facet shares cost a lobe per table node: only the facets holding all but
    # FACET_TAIL_SHARE of the kernel's light get their own; the rest keep weight 1, the share of θ_i, as their
    # coherent part does (evaluate), so the halves still balance
    used = (np.ones(cos_d.shape, bool) if kernel is None or nano.surface is None
            else _significant(kernel))
    for i, lam in enumerate(wavelengths_nm):
        # the light each facet scatters (1 − A on a conductor, the lobe's own albedo on a dielectric)
        lost_i = float(nano.scattered_share(wi[2], lam, diffraction, material, polarization, phi))
        # guard: a nano surface that scatters nothing at θ_i has no lobe to weight
        if lost_i > 1e-12 and used.any():
            out[i][used] = nano.scattered_share(cos_d[used], lam, diffraction, material, polarization, phi) / lost_i
    return out


def _azimuth_deg(wi) -> float:
    """Azimuth (degrees) of a direction: the plane of incidence a height field's coherent fraction is taken in."""
    return float(np.degrees(np.arctan2(wi[1], wi[0]))) if np.hypot(wi[0], wi[1]) > 0 else 0.0


def _convolve(lobe, K, grid):
    """Convolve lobes f (n_λ, n_v, n_u), which are energy densities on the (u, v) plane, with kernel K
    ((2n_v − 1, 2n_u − 1), or one per wavelength)."""
    n_v, n_u = grid.n_v, grid.n_u
    out = signal.fftconvolve(lobe, K if K.ndim == 3 else K[None], mode="full", axes=(-2, -1))
    out = out[..., n_v - 1:2 * n_v - 1, n_u - 1:2 * n_u - 1]
    return np.maximum(out, 0.0)  # guard: FFT round-off gives tiny negatives


def nano_lobe(wi, wavelengths_nm, nano: Nano, grid: DirectionGrid, F, *, solver: str = "auto",
              device=None, precision="float32", diffraction="kirchhoff", material=None):
    """The diffracted (incoherent) nano lobe f_n (n_λ, n_v, n_u) in 1/sr for incidence *wi* on *grid*.

    Parameters
    ----------
    F : callable (cos_theta_d, wavelength_nm) -> reflectance
        Fresnel factor at the half-vector angle (docs/physics.md §1).
    solver : str
        ``"psd"`` (statistics), ``"fft"`` or ``"direct"`` (height field), ``"auto"`` picks by what is given.
    """
    w = check_wavelengths(wavelengths_nm)
    wo = grid.directions()
    wi = np.asarray(wi, dtype=float)
    h = wi[None, None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
    if solver == "auto":
        solver = "psd" if nano.model is not None else "fft"
    dm = scatter.get_model(diffraction, perturbative=True)
    if dm.perturbative:   # Rayleigh-Rice: the PSD's first-order lobe with its own polarization factor Q (no F)
        psd = nano.model if nano.model is not None else nano.periodogram()
        pol = getattr(F, "polarization", "unpolarized")
        out = np.stack([np.where(grid.inside, scatter.rayleigh_rice_lobe(wi[None, None, :], wo, lam, psd, material,
                                                                         pol), 0.0) for lam in w])
        if nano.model is not None and (np.min(w) * 1e-9 / (np.pi * nano.model.length_scale)
                                       < NARROW_CELLS * max(grid.du, grid.dv)):
            out = _resample_narrow_lobe(out, wi, w, nano, grid, F, dm, material)
        return out
    if solver == "psd":
        if nano.model is None:
            raise WaveopticsError("solver 'psd' needs nano statistics, not a height field; use fft or direct")
        out = np.empty((w.size, grid.n_v, grid.n_u))
        for i, lam in enumerate(w):
            Fi = F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam)
            out[i], cap = scatter.scattered_lobe(wi, wo, lam, nano.model, F=Fi, return_captured=True,
                                                 diffraction=diffraction)
            # beyond the tangent plane's validity the lobe carries the continued albedo (BandSeries.scattered_albedo)
            out[i] *= float(nano.lobe_energy_scale(wi[2], lam, diffraction, material,
                                                   getattr(F, "polarization", "unpolarized")))
            # guard: the truncated series misses the light of its terms m > m_max once g = (kσ(cosθ_i + cosθ_o))²
            # ≳ 30 (σ ≳ λ/2): refuse rather than return a lobe that silently lacks that energy
            low = float(np.min(np.where(grid.inside, cap, 1.0)))
            if low < SERIES_MIN_CAPTURED:
                raise WaveopticsError(
                    f"nano-roughness sigma = {nano.model.sigma * 1e9:.4g} nm is too rough for the PSD series at "
                    f"{lam:g} nm (it holds only {100 * low:.3g}% of the scattered light in some directions); use a "
                    "nano height field (solver fft or direct), or describe roughness this large by the micro "
                    "NDF (alpha)")
        out = np.where(grid.inside, out, 0.0)
        if np.min(w) * 1e-9 / (np.pi * nano.model.length_scale) < NARROW_CELLS * max(grid.du, grid.dv):
            out = _resample_narrow_lobe(out, wi, w, nano, grid, F, diffraction, material)
        return out
    if solver in ("fft", "direct"):
        if nano.surface is None:
            raise FieldError(f"solver {solver!r} needs a nano height field ({{surface}} or {{nano}} MODEL:...)", 'surface', 'nano')
        return kirchhoff_scattered_lobe(nano.surface, wi, grid, w, F, solver=solver, device=device,
                                        diffraction=diffraction,
                                        precision=precision)
    raise unknown("solver", solver, ("auto", "psd", "fft", "direct"))


#: cells whose centre lies within this many cells of the mirror direction form the core of a narrow nano lobe:
#: they are cell-averaged (:func:`_resample_narrow_lobe`); beyond, the point samples of a power-law tail
#: f ∝ ρ^−C are within C² / (24 (ρ/du)²) of the cell average (≤ 2.3 % for C ≤ 3 at 4 cells)
CORE_CELLS = 4.0
#: sub-samples per core cell and axis resolve the lobe to this fraction of its width or of the cell's distance
#: from the mirror, whichever is larger (between 2 and :data:`CORE_MAX_SUBSAMPLES` per axis)
CORE_SUBSAMPLE_STEP = 0.125
CORE_MAX_SUBSAMPLES = 64


def _lobe_at(wi, wo, lam, nano: Nano, F, diffraction, material):
    """The PSD nano lobe (1/sr) at directions *wo* (..., 3): the functions :func:`nano_lobe` samples the grid with
    (the Rayleigh-Rice lobe with its own Q, or the Kirchhoff series with F at each half-vector)."""
    dm = scatter.get_model(diffraction, perturbative=True)
    if dm.perturbative:
        return scatter.rayleigh_rice_lobe(wi[None, :], wo, lam, nano.model, material,
                                          getattr(F, "polarization", "unpolarized"))
    h = wi[None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
    Fi = F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam)
    return scatter.scattered_lobe(wi, wo, lam, nano.model, F=Fi, diffraction=diffraction)


def _core_cell_averages(wi, lam, nano: Nano, grid: DirectionGrid, F, diffraction, material, width):
    """(core mask (n_v, n_u), cell averages of the lobe over the core cells): each cell within
    :data:`CORE_CELLS` cells of the mirror direction, sub-sampled at midpoints of a regular n × n split, n set by
    :data:`CORE_SUBSAMPLE_STEP` of max(lobe *width*, the cell's distance from the mirror); sub-samples below the
    horizon count as 0 (the cell's share of the disc)."""
    mu, mv = -wi[0], -wi[1]
    cell = max(grid.du, grid.dv)
    U, V = np.meshgrid(grid.u, grid.v)
    core = grid.inside & (np.hypot(U - mu, V - mv) <= CORE_CELLS * cell)
    rows, cols = np.nonzero(core)
    if rows.size == 0:   # the mirror direction lies off the grid
        return core, np.zeros(0)
    pts, owner, count = [], [], np.zeros(rows.size)
    for k, (i, j) in enumerate(zip(rows, cols)):
        # distance from the mirror to the nearest point of the cell: the scale the lobe varies on there
        near = np.hypot(max(abs(grid.u[j] - mu) - grid.du / 2, 0.0), max(abs(grid.v[i] - mv) - grid.dv / 2, 0.0))
        n = int(np.clip(np.ceil(cell / (CORE_SUBSAMPLE_STEP * max(width, near))), 2, CORE_MAX_SUBSAMPLES))
        t = (np.arange(n) + 0.5) / n - 0.5
        su, sv = np.meshgrid(grid.u[j] + t * grid.du, grid.v[i] + t * grid.dv)
        up = su**2 + sv**2 < 1.0
        pts.append(np.stack([su[up], sv[up]], axis=-1))
        owner.append(np.full(int(up.sum()), k))
        count[k] = n * n
    uv = np.concatenate(pts)
    wo = np.concatenate([uv, np.sqrt(1.0 - np.sum(uv**2, axis=-1))[:, None]], axis=-1)
    f = _lobe_at(wi, wo, lam, nano, F, diffraction, material)
    return core, np.bincount(np.concatenate(owner), weights=f, minlength=rows.size) / count


def _resample_narrow_lobe(out, wi, wavelengths_nm, nano: Nano, grid: DirectionGrid, F, diffraction="kirchhoff",
                          material=None):
    """Energy-preserving sampling of a nano lobe narrower than the grid cells (PSD route).

    guard: the lobe's core is ~λ/(π T) wide in direction cosines; sampled at cell centres, a narrower one is missed
    or over-counted (measured: Au, σ = 20 nm, T = 30 µm, 128² grid: 18 % of the light at 450 nm lost). The cells
    near the mirror direction (the core, :data:`CORE_CELLS`) take the lobe's average over each cell instead of its
    centre value (:func:`_core_cell_averages`); the tail beyond keeps its point samples, which a heavy ABC tail's
    slow variation leaves accurate. The lobe's energy is then made its scattered albedo: on a conductor F(θ_i) · E,
    E = 1 − A the share of the reflected light the nano lobe scatters (:meth:`Nano.coherent_amplitude2`, the
    complement of the coherent fraction the specular lobe keeps, so the two add up to the reflected light; while
    the lobe is paraxial E ≈ 1 − exp(−g_i), g_i = (4πσ_rel cosθ_i / λ)², docs/physics.md §3, §9); on a dielectric
    the lobe's own absolute albedo (:meth:`waveoptics.scatter.BandSeries.scattered_albedo`), since there the coherent
    part is the Debye-Waller factor and not the complement of the scattered light. Only the core cells are scaled
    to reach it (the cell averages leave them within about 1 % of it); the tail, which the grid samples well, is
    never scaled: ABC σ = 10 nm, B = 200 µm, C = 3, 450 nm, 30°, 128² grid: the energy beyond 0.1 direction-cosine
    units within 2 % of a 1024² grid's (tests/test_narrow_lobes.py). When no core cell holds any of the lobe, that
    energy is deposited in the mirror cell (as a micro lobe narrower than a cell is, see :func:`evaluate`).

    References
    ----------
    .. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale energy split).
    .. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (band-limited relevant roughness).
    """
    cell = _mirror_cell(grid, wi)
    pol = getattr(F, "polarization", "unpolarized")
    theta_i = float(np.degrees(np.arccos(np.clip(wi[2], 0.0, 1.0))))
    for i, lam in enumerate(wavelengths_nm):
        Fi = float(np.ravel(_F_mirror(F, wi, lam))[0])
        if scatter.is_conductor(material):   # the light the coherent lobe gives up, F(θ_i)(1 − A)
            energy = Fi * (1.0 - float(nano.coherent_amplitude2(wi[2], lam, diffraction, material, pol)))
        else:   # a dielectric's lobe keeps its own albedo (the coherent part is the Debye-Waller factor)
            energy = float(scatter.band_series(nano.model, float(lam)).scattered_albedo(
                theta_i, diffraction, material, pol, absolute=True))
        width = float(lam) * 1e-9 / (np.pi * nano.model.length_scale)
        core, avg = _core_cell_averages(wi, float(lam), nano, grid, F, diffraction, material, width)
        out[i][core] = avg
        tail = float(integrate(np.where(core, 0.0, out[i]), grid))
        in_core = float(np.sum(avg)) * grid.du * grid.dv
        rest = energy - tail
        if in_core > 0 and rest > 0:
            out[i][core] *= rest / in_core
        elif cell is not None and grid.inside[cell] and rest > 0:
            out[i, cell[0], cell[1]] += rest / (grid.du * grid.dv)
    return out


def kirchhoff_scattered_lobe(surface: HeightField, wi, grid: DirectionGrid, wavelengths_nm, F, *,
                             solver: str = "fft", device=None, precision: str = "float32", warnings=None,
                             diffraction="kirchhoff"):
    """Incoherent Kirchhoff lobe of a height field: the field minus its coherent (mean) part, as a BRDF (1/sr).

    δU = U − χ̂ U_flat, with χ̂ the patch estimate of ⟨exp(i v_z h)⟩ (:func:`waveoptics.scatter.
    coherent_amplitude`) and U_flat the field of the same window without heights, removes the specular spike
    (which the two-scale model carries as the micro lobe × A) and keeps the diffracted light; the BRDF follows
    docs/physics.md §1 (:func:`waveoptics.scatter.brdf_from_field`). ``fft`` evaluates the whole grid
    (frozen-v_z expansion, see :mod:`waveoptics.scatter`); ``direct`` sums the integral on the OpenCL device
    for every grid direction inside the disc.

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963, ch. 5 (coherent and incoherent fields); docs/physics.md §1-§2.
    """


    w = check_wavelengths(wavelengths_nm)
    smp = scatter.samples(surface)
    flat = dataclasses.replace(smp, h=np.zeros_like(smp.h))
    for msg in scatter.sampling_warnings(smp, wi, w, wo=grid.directions()[grid.inside]):  # aliasing
        scatter.solvers._warn(msg, warnings)
    # the specular spike is removed here (δU), but a periodic surface's orders and a patch's speckle are just as
    # narrow (≈ λ/L): a coarser grid samples them at arbitrary points and their energy comes out wrong
    Lx, Ly = smp.extent
    lmin = float(w.min()) * 1e-9
    if grid.du > lmin / Lx * (1 + 1e-9) or grid.dv > lmin / Ly * (1 + 1e-9):
        need = int(np.ceil(2 * max(Lx, Ly) / lmin))
        scatter.solvers._warn(f"direction grid cell {grid.du:.3g} is coarser than the patch's diffraction width lambda/L = "
                  f"{lmin / max(Lx, Ly):.3g}: sharp features (grating orders, speckle) are under-sampled and their "
                  f"energy is inexact; use resolution >= {need} or a smaller patch", warnings)
    dirs = grid.directions()
    inside = grid.inside
    out = np.zeros((w.size, grid.n_v, grid.n_u))
    chi = np.array([scatter.coherent_amplitude(smp, wi, lam, diffraction) for lam in w])
    sol = scatter.get_solver(solver)
    opts = dict(runtime=get_runtime(device) if solver == "direct" else None, precision=precision,
                diffraction=diffraction)
    U, _ = sol.grid_field(smp, wi, grid, w, **opts)
    U0, _ = sol.grid_field(flat, wi, grid, w, **opts)
    out[:, inside] = scatter.brdf_from_field((U - chi[:, None, None] * U0)[:, inside], wi, dirs[inside], w,
                                             smp.area, F, diffraction)
    return np.where(inside, np.maximum(out, 0.0), 0.0)


#: facet incidences θ_d (degrees) at which a height field's scattered share E_field is tabulated per wavelength
#: (:meth:`Nano.coherent_amplitude2`): denser towards grazing, where the tangent-plane lobe's albedo bends
FIELD_THETAS_DEG = np.array([0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 68.0, 75.0, 80.0, 84.0, 87.0, 89.0])
#: cells of the grid that integrates a height field's lobe are λ / (this × L) wide: |U|² varies on the scale
#: λ/(2L) (the window's autocorrelation spans 2L), and 3 is where its integral settles (Gaussian patch at 60°:
#: 1e-3 below at 2, within 2e-4 from 3 to 12; a heavy-tailed ABC C = 2.2 patch, whose speckle reaches the
#: horizon and its 1/cosθ_o obliquity, keeps ±0.5 % of cell-quadrature scatter at any of them)
FIELD_GRID_OVERSAMPLING = 3.0


def field_scattered_albedo(surface: HeightField, theta_deg: float, wavelength_nm: float, diffraction="kirchhoff",
                           material=None, polarization: str = "unpolarized", azimuth_deg: float = 0.0) -> float:
    """E_field(θ): the share of the specularly reflected light that a height field's diffracted lobe scatters at
    incidence (θ, φ) (degrees), relative to F(θ) (unitless; > 1 is possible near grazing incidence, where the
    tangent-plane lobe's albedo grows without bound).

    The lobe is :func:`kirchhoff_scattered_lobe` (fft solver, exact Kirchhoff to its tolerance; the direct solver
    agrees to 1e-3) with each direction's Fresnel factor relative to the specular one
    (:class:`waveoptics.materials.RelativeFacetFresnel`; 1 without a *material*), integrated over a direction grid
    whose cells are λ/(3L) wide (L the patch's larger side, :data:`FIELD_GRID_OVERSAMPLING`), finer than the scale
    λ/(2L) on which |U|² varies, so that for a lobe inside the disc Σ f du dv is Parseval's sum of
    |U − χ̂ U_flat|², 1 − |χ̂|² when nothing is evanescent (measured 1e-4 on Gaussian patches). What the sum
    misses is the light of surface frequencies outside the propagating band, which does not scatter (the
    relevant roughness: Krywonos, Harvey & Choi 2011).

    References
    ----------
    .. [1] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121–1138, 2011 (relevant roughness; only the
       propagating band scatters or reduces the specular reflection).
    .. [2] M. Parseval; Bracewell, *The Fourier Transform and its Applications*, 3rd ed., ch. 6 (Rayleigh's
       theorem: the power of a sequence equals that of its DFT samples).
    """
    from ..materials import RelativeFacetFresnel
    from ..units import direction_from_angles

    smp = scatter.samples(surface)
    n = int(np.ceil(FIELD_GRID_OVERSAMPLING * max(smp.extent) / (wavelength_nm * 1e-9)))
    grid = DirectionGrid.hemisphere(n)
    wi = direction_from_angles(theta_deg, azimuth_deg)
    with warnings.catch_warnings():   # the lobe's own evaluation says what its sampling misses
        warnings.simplefilter("ignore", scatter.DiffractionWarning)
        lobe = kirchhoff_scattered_lobe(surface, wi, grid, [wavelength_nm],
                                        RelativeFacetFresnel(material, polarization), solver="fft",
                                        diffraction=diffraction)
    return float(integrate(lobe, grid)[0])


#: a height field's facets that together hold less than this share of a micro lobe's light take the coherent
#: fraction of the macro incidence instead of their own (both halves alike, so the energy balance is kept): their
#: own would cost table nodes far from θ_i for a change in the coherent/diffracted split below this share
FACET_TAIL_SHARE = 1e-3


def _significant(weights) -> np.ndarray:
    """Mask of the largest cells of *weights* (≥ 0) that hold all but :data:`FACET_TAIL_SHARE` of their sum."""
    flat = np.ravel(weights)
    order = np.argsort(flat)[::-1]
    c = np.cumsum(flat[order])
    keep = np.zeros(flat.size, bool)
    if c.size and c[-1] > 0:
        keep[order[:int(np.searchsorted(c, (1.0 - FACET_TAIL_SHARE) * c[-1])) + 1]] = True
    return keep.reshape(np.shape(weights))


def _bracketing_nodes(theta_lo: float, theta_hi: float) -> np.ndarray:
    """The :data:`FIELD_THETAS_DEG` nodes that bracket the facet incidences [θ_lo, θ_hi] (degrees)."""
    lo = np.searchsorted(FIELD_THETAS_DEG, theta_lo, side="right") - 1
    hi = np.searchsorted(FIELD_THETAS_DEG, theta_hi, side="left")
    return FIELD_THETAS_DEG[max(lo, 0):hi + 1]


def facet_incidences_deg(wi, micro: Micro, grid: DirectionGrid) -> tuple[float, float] | None:
    """Range (degrees) of the facet incidences θ_d whose own coherent fraction a height field's micro lobe at
    incidence *wi* on *grid* needs (the cells of :func:`micro_kernel` that hold all but :data:`FACET_TAIL_SHARE` of
    its light); None for a lobe narrower than a cell (only θ_i itself)."""
    if _sharp(micro, grid):
        return None
    K = micro_kernel(wi, micro, grid)
    th = np.degrees(np.arccos(kernel_cos_theta_d(wi, grid)[_significant(K)]))
    return (float(th.min()), float(th.max())) if th.size else None


def field_albedo_evaluations(micro: Micro, grid: DirectionGrid, incidences, extra: int = 0) -> int:
    """Lobes :func:`field_scattered_albedo` computes per wavelength for a height field's coherent fraction at the
    macro *incidences* (unit vectors (n, 3)) on *grid*: one each, plus the facet table's nodes that bracket the
    facet incidences under their micro lobes (:meth:`Nano.coherent_amplitude2`). *extra* more incidences (a
    sphere's table) are counted with every node (their pixels see every facet incidence)."""
    wis = np.atleast_2d(np.asarray(incidences, dtype=float))
    if extra:
        return len(wis) + int(extra) + FIELD_THETAS_DEG.size
    nodes = set()
    for wi in wis:
        rng = facet_incidences_deg(wi, micro, grid)
        if rng is not None:
            nodes.update(float(t) for t in _bracketing_nodes(*rng))
    return len(wis) + len(nodes)


#: local incidences θ' (degrees) at which the facet-frame route tabulates the nano lobe on the direction grid: the
#: nano lobe of a facet at any incidence is read between the two nodes around it, relative to the mirror direction
FACET_THETAS_DEG = np.array([0.0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 78, 81, 84, 86, 88])
#: facet normals of the grid route's quadrature (:func:`facet_nodes`): (drawn through the micro NDF's sampler,
#: shared by all cells; drawn about each cell's half-vector through the nano lobe's radial law), for a micro lobe
#: narrower than :data:`FACET_NODE_SPLIT` nano lobe widths, and for a wider one. Measured per cell against the
#: pointwise form (ABC σ = 10 nm, B = 2 µm, C = 2.6, 550 nm, Beckmann, 96²-128² grids): α = 0.05 at 30° with
#: (64, 16) ≤ 2.7 % (32 + 16: 4.8 %); α = 0.3 at 60° with (64, 64) ≤ 2.1 % (64 + 16: 6.8 %, 32 + 64: 4.5 %)
FACET_NODES_NARROW, FACET_NODES_WIDE = (64, 16), (64, 64)
#: ratio 2α / w_n (the micro lobe's spread of mirror directions over the nano lobe's width λ/(π ℓ)) below which
#: the grid route takes :data:`FACET_NODES_NARROW`
FACET_NODE_SPLIT = 0.5
#: wavelength (nm) of the nano lobe's radial law that places the grid route's half-vector normals and of w_n in
#: :func:`facet_nodes`: one for every wavelength, so that each wavelength's lobe does not depend on the others asked
FACET_REFERENCE_NM = 550.0
#: evaluate's facet integration: ``frame`` (Walter's integral, each facet's nano lobe in its own frame),
#: ``paraxial`` (the nano lobe at the macro incidence shifted to every facet's mirror direction: an FFT
#: convolution), ``auto`` (frame where :func:`facet_route` allows it)
FACET_ROUTES = ("auto", "frame", "paraxial")


def facet_route(micro: Micro, nano: Nano | None, grid: DirectionGrid, wavelengths_nm, facet: str = "auto") -> str:
    """``frame`` or ``paraxial``: how :func:`evaluate` carries the nano lobe by the facets.

    ``auto`` takes ``frame`` for PSD statistics whose nano lobe (width λ_min/(π ℓ)) is wider than
    :data:`NARROW_CELLS` grid cells; else ``paraxial``: height fields (their lobe is not tabulated over local
    incidence); a micro lobe narrower than a cell (its facets tilt by less than a cell, where the shift and the
    turn of their lobes agree); nano lobes the grid cannot resolve, which :func:`nano_lobe` deposits with their
    energy, where a facet's lobe lies within a cell or two of its mirror direction.
    """
    if facet not in FACET_ROUTES:
        raise unknown("facet", facet, FACET_ROUTES)
    if nano is None or nano.model is None:
        if facet == "frame" and nano is not None:
            raise FieldError("facet 'frame' needs nano statistics (a PSD model); a height field's lobe is "
                             "carried paraxially", "facet")
        return "paraxial"
    if facet != "auto":
        return facet
    if _sharp(micro, grid):
        return "paraxial"
    wn = float(np.min(wavelengths_nm)) * 1e-9 / (np.pi * nano.model.length_scale)
    return "paraxial" if wn < NARROW_CELLS * max(grid.du, grid.dv) else "frame"


def facet_nodes(micro: Micro, nano: Nano, wavelengths_nm) -> tuple[int, int]:
    """(NDF normals, half-vector normals per cell) of the grid route's quadrature: :data:`FACET_NODES_NARROW` when
    the micro lobe's mirror directions spread over less than :data:`FACET_NODE_SPLIT` nano lobe widths (2α < 0.5
    λ/(π ℓ) at λ = :data:`FACET_REFERENCE_NM`), where the NDF's normals carry the integral, else
    :data:`FACET_NODES_WIDE` (*wavelengths_nm* is not used: every wavelength gets the same nodes)."""
    kw = micro.kw()
    a = max(kw["alpha"], kw["alpha_y"] or 0.0)
    wn = FACET_REFERENCE_NM * 1e-9 / (np.pi * nano.model.length_scale)
    return FACET_NODES_NARROW if 2 * a < FACET_NODE_SPLIT * wn else FACET_NODES_WIDE


class _One:
    """Fresnel factor 1 (the facet-frame tables hold the lobe without F; F(θ_d) is applied per direction)."""

    def __init__(self, polarization="unpolarized"):
        self.polarization = polarization

    def __call__(self, c, lam):
        return np.ones(np.broadcast_shapes(np.shape(c), np.shape(lam)))


def _facet_table(nano: Nano, k: int, w, grid: DirectionGrid, dm, material, polarization):
    """g = f_nano cos θ_o of the nano lobe at local incidence :data:`FACET_THETAS_DEG` [k] (azimuth 0) at the cell
    centres of *grid*, (n_v, n_u, n_λ) float32: F = 1 for the Kirchhoff family (its F(θ_d) is frame-independent
    and applied afterwards), the Rayleigh-Rice lobe with its own factor Q of *material* and *polarization* (for s or
    p light Q is taken relative to the facet's own plane of incidence, not the macro one: exact for unpolarized
    light and for facets tilted in the plane of incidence).

    g is finite up to the horizon (f grows like 1/cos θ_o there); cells beyond the rim of the disc hold g of the
    rim direction on their radius, so that bilinear reads within a cell of the rim are not pulled towards 0.
    Cached on *nano*."""
    cache = nano.__dict__.setdefault("_cache", {})
    key = ("facet-table", k, tuple(float(x) for x in w), grid.n_u, grid.n_v, tuple(grid.u_range),
           tuple(grid.v_range), dm.name, getattr(material, "name", None), polarization)
    if key not in cache:
        th = np.radians(FACET_THETAS_DEG[k])
        wi = np.array([np.sin(th), 0.0, np.cos(th)])
        u, v = _centres(grid)
        # the lobe of an isotropic PSD is even in v: rows from the middle up, mirrored onto the rows below
        half = slice(grid.n_v // 2 - 1, grid.n_v) if _v_symmetric(grid) else slice(0, grid.n_v)
        u, v = u[half], v[half]
        r = np.hypot(u, v)
        shrink = np.where(r > RIM_RADIUS, RIM_RADIUS / np.where(r > 0, r, 1.0), 1.0)
        u, v = u * shrink, v * shrink
        wo = np.stack([u, v, np.sqrt(np.maximum(1.0 - u * u - v * v, 0.0))], axis=-1)
        out = np.empty((grid.n_v, grid.n_u, len(w)), dtype=np.float32)
        for i, lam in enumerate(w):
            if dm.perturbative:
                f = scatter.rayleigh_rice_lobe(wi, wo, lam, nano.model, material, polarization)
            else:
                check_series(nano.model, lam)
                f = scatter.scattered_lobe(wi, wo, lam, nano.model, F=1.0, diffraction=dm)
                # beyond the tangent plane's validity the lobe carries its continued albedo (docs/physics.md §9)
                f = f * float(np.ravel(nano.lobe_energy_scale(wi[2], lam, dm, material, polarization))[0])
            out[half, :, i] = f * wo[..., 2]
        if half.start > 0:
            out[:half.start] = out[grid.n_v - 1:grid.n_v - 1 - half.start:-1]
        cache[key] = out
    return cache[key]


def _v_symmetric(grid: DirectionGrid) -> bool:
    """Whether the rows of *grid* are symmetric about v = 0 (row i and n_v − 1 − i at opposite v)."""
    return grid.n_v % 2 == 0 and np.isclose(grid.v_range[0], -grid.v_range[1])


def check_series(model, lam):
    """Refuse nano-roughness the truncated PSD series cannot hold (its largest g, at cos θ_i + cos θ_o = 2; λ in
    nm): its terms must hold :data:`SERIES_MIN_CAPTURED` of the scattered light."""
    g = scatter.roughness_g(model.sigma, 2.0, lam)
    m_use = scatter.series_terms(g)
    captured = float(scatter.poisson_weights(g, m_use).sum() / -np.expm1(-g)) if g > 0 else 1.0
    if captured < SERIES_MIN_CAPTURED:
        raise WaveopticsError(
            f"nano-roughness sigma = {model.sigma * 1e9:.4g} nm is too rough for the PSD series at {lam:g} nm (it "
            f"holds only {100 * captured:.3g}% of the scattered light); describe roughness this large by the "
            "micro NDF (alpha)")


def _centres(grid: DirectionGrid):
    """(u, v) of the cell centres of *grid*, (n_v, n_u) each."""
    u = grid.u_range[0] + (np.arange(grid.n_u) + 0.5) * grid.du
    v = grid.v_range[0] + (np.arange(grid.n_v) + 0.5) * grid.dv
    return np.meshgrid(u, v)


def _unit_xy(v):
    """(cos φ, sin φ) of the azimuth of *v* (1, 0 on the axis)."""
    r = math.hypot(v[0], v[1])
    return (v[0] / r, v[1] / r) if r > 0 else (1.0, 0.0)


#: radius of the direction-cosine disc at which :func:`_facet_table` evaluates the cells beyond its rim
RIM_RADIUS = 1.0 - 1e-6


def _facet_stack(nano: Nano, w, grid: DirectionGrid, dm, material, polarization):
    """:func:`_facet_table` at every :data:`FACET_THETAS_DEG` node, stacked (n_θ, n_v, n_u, n_λ); cached."""
    cache = nano.__dict__.setdefault("_cache", {})
    key = ("facet-stack", tuple(float(x) for x in w), grid.n_u, grid.n_v, tuple(grid.u_range), tuple(grid.v_range),
           dm.name, getattr(material, "name", None), polarization)
    if key not in cache:
        cache[key] = np.stack([_facet_table(nano, k, w, grid, dm, material, polarization)
                               for k in range(FACET_THETAS_DEG.size)])
    return cache[key]


def _facet_read(stack, grid: DirectionGrid, theta, lo):
    """The tabulated g = f_nano cos θ_o (n, n_λ) at local incidences *theta* (rad, (n,) or scalar) and local
    directions *lo* (n, 3) whose incidence lies in the local x–z plane: the two nodes θ_k around θ, each read at
    *lo* turned about the local y axis by θ − θ_k (which takes θ's mirror direction to θ_k's; the lobe of a tilted
    facet is a turned lobe), blended linearly in θ; a node whose turned direction falls below its horizon drops
    out of the blend."""
    nodes = np.radians(FACET_THETAS_DEG)
    theta = np.broadcast_to(np.asarray(theta, dtype=float), lo.shape[:1])
    f = np.interp(theta, nodes, np.arange(nodes.size))
    a = np.minimum(np.floor(f).astype(int), nodes.size - 1)
    b = np.minimum(a + 1, nodes.size - 1)
    wb = f - a
    n_v, n_u = stack.shape[1:3]
    flat = stack.reshape(-1, stack.shape[-1])
    idx, wts = [], []
    den = np.zeros(lo.shape[0])
    for k, wk in ((a, 1.0 - wb), (b, wb)):
        beta = theta - nodes[k]
        cb, sb = np.cos(beta), np.sin(beta)
        u = lo[:, 0] * cb + lo[:, 2] * sb
        z = -lo[:, 0] * sb + lo[:, 2] * cb
        k0, j0, av, au, ok = grid.bilinear(u, lo[:, 1])
        wk = np.where(ok & (z > 0), wk, 0.0)
        i00 = (k * n_v + k0) * n_u + j0
        idx += [i00, i00 + 1, i00 + n_u, i00 + n_u + 1]
        wts += [wk * (1 - av) * (1 - au), wk * (1 - av) * au, wk * av * (1 - au), wk * av * au]
        den += wk
    val = np.einsum("cj,cjl->cl", np.stack(wts, axis=1).astype(np.float32), flat[np.stack(idx, axis=1)])
    return np.where(den[:, None] > 0, val / np.where(den > 0, den, 1.0)[:, None], 0.0)


def facet_frame_diffraction(wi, wavelengths_nm, material, micro: Micro, nano: Nano, grid: DirectionGrid, F, *,
                            diffraction="kirchhoff", polarization: str = "unpolarized",
                            table_grid: DirectionGrid | None = None, nodes: tuple[int, int] | None = None):
    """The diffracted part on *grid*: Walter's integral over facet normals m of the nano lobe in each facet's
    frame (docs/physics.md §7),

        f_diff(ω_i, ω_o) = ∫ |ω_i·m| |ω_o·m| / (|ω_i·n| |ω_o·n|) f_nano(ω_i^m, ω_o^m) G(ω_i, ω_o, m) D(m) dm,

    by the balance heuristic of two fixed node sets, as :class:`waveoptics.brdf.TwoScaleBRDF` does: N_a Sobol
    normals through the micro NDF's sampler (shared by all cells) and, per cell, N_b normals about its half-vector
    drawn through the nano lobe's radial law (they hold a heavy-tailed NDF's far facets and a nano lobe narrower
    than the micro lobe); (N_a, N_b) = *nodes* or :func:`facet_nodes`. Each facet's nano lobe is read from tables
    over local incidence (:data:`FACET_THETAS_DEG`, :func:`_facet_read`) on *table_grid* (default *grid*, a
    hemisphere); F(θ_d), the same in every facet's frame, multiplies the sum.

    Returns
    -------
    diffraction : ndarray (n_λ, n_v, n_u), 1/sr
    scattered : ndarray (n_λ,)
        The light the facets' lobes scatter, F(θ_m) (1 − A(θ_m)) per facet on a conductor and the lobe's own
        absolute albedo on a dielectric (:meth:`Nano.scattered_share`), averaged over the facets the light
        sees (the NDF nodes, weights D (ω_i·m) G1 / p, normalized by their sum, which is 1 in expectation): the
        diffracted part's albedo falls short of it by the light masked on the way out or sent below the macro
        horizon.
    reflected : ndarray (n_λ,)
        F(θ_m) averaged the same way: the light the facets reflect, coherent and diffracted together, before
        masking on the way out.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14) (a BRDF carried by each facet); §5.3 (sampling normals).
    .. [2] E. Veach, PhD thesis, 1997, §9.2 (balance heuristic of several techniques).
    """
    from .facet import NanoRadial, facet_basis, unit_nodes
    from .ndf import _ndf
    from .sampling import _sampler, pdf_normal, sample_normal
    from .shadowing import _shadowing

    w = np.asarray(wavelengths_nm, dtype=float)
    dm = scatter.get_model(diffraction, perturbative=True)
    kw = micro.kw()
    ndf, ax = kw["ndf"], kw["alpha"]
    ay = kw["alpha_y"] if kw["alpha_y"] is not None else ax
    c, spec = kw["ndf_shape"], _ndf(kw["ndf"])
    na, nb = nodes or facet_nodes(micro, nano, w)
    m_a = sample_normal(np.broadcast_to(wi, (na, 3)), unit_nodes(na), ndf=ndf, ax=ax, ay=ay, c=c)
    inside = grid.inside
    wo = grid.directions()[inside]
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.maximum(h @ wi, 1e-6)
    rad = NanoRadial(nano.model, FACET_REFERENCE_NM, dm, nb)
    level = rad.level(cos_d)
    Li, Lo = float(spec.Lambda(wi, ax, ay, c)), spec.Lambda(wo, ax, ay, c)
    gfn, _ = _shadowing(micro.shadowing)
    visible = _sampler(ndf).visible
    stack = _facet_stack(nano, w, table_grid or grid, dm, material, polarization)
    out = np.zeros((wo.shape[0], w.size))

    tgrid = table_grid or grid

    def add(m, valid):
        """Add the nodes m (3,) (an NDF node, shared by all cells) or (n_cells, 3) (one half-vector node per
        cell), weighted by the balance heuristic."""
        om = wo @ m if m.ndim == 1 else np.sum(wo * m, axis=-1)
        im = m @ wi
        D = spec.D(m, ax, ay, c)
        pa = np.where(im > 0, D * im / (1.0 + Li), 0.0) / wi[2] if visible else D * m[..., 2]
        mh = np.clip(h @ m if m.ndim == 1 else np.sum(m * h, axis=-1), 0.0, 1.0)
        pb = np.where(mh > 0, rad.pdf_r(level, 2 * cos_d * np.sqrt(np.maximum(1 - mh * mh, 0.0)))
                      * 4 * cos_d ** 2 * mh, 0.0)
        den = na * pa + nb * pb
        ok = valid & (im > 0) & (om > 0) & (den > 0) & (D > 0)
        if not ok.any():
            return
        wok = wo[ok]
        Lok = Lo[ok]
        Lik = np.full(Lok.shape, Li)
        mk = np.broadcast_to(m, wok.shape) if m.ndim == 1 else m[ok]
        G = gfn(np.broadcast_to(wi, wok.shape), wok, mk, lambda d: Lok if d is wok else Lik)
        weight = (im * D if m.ndim == 1 else (im * D)[ok]) * G / (wi[2] * wok[:, 2] * den[ok])   # × |ω_o·m| f_nano
        t, b = facet_basis(mk if m.ndim > 1 else m)
        lx, ly = np.sum(t * wi, axis=-1), np.sum(b * wi, axis=-1)
        r = np.hypot(lx, ly)
        cp, sp = np.where(r > 0, lx / np.where(r > 0, r, 1), 1.0), np.where(r > 0, ly / np.where(r > 0, r, 1), 0.0)
        ux, uy = np.sum(wok * t, axis=-1), np.sum(wok * b, axis=-1)   # turned so that ω_i^m lies in x–z
        lo = np.stack([cp * ux + sp * uy, -sp * ux + cp * uy, om[ok]], axis=-1)
        theta = np.arccos(np.clip(im if m.ndim == 1 else im[ok], 0.0, 1.0))
        out[ok] += weight[:, None] * _facet_read(stack, tgrid, theta, lo)

    for j in range(na):
        add(m_a[j], np.ones(wo.shape[0], bool))
    radii = rad.node_radii[level]                        # (n_cells, n_b)
    phis = 2 * np.pi * unit_nodes(nb)[:, 1]
    e1, e2 = facet_basis(h)
    for k in range(nb):
        s_k = radii[:, k] / (2 * cos_d)                   # a tilt s from h sends ω_i to q = 2k cosθ_d s
        ok = s_k < 1
        s_k = np.where(ok, s_k, 0.0)
        m = ((s_k * np.cos(phis[k]))[:, None] * e1 + (s_k * np.sin(phis[k]))[:, None] * e2
             + np.sqrt(1 - s_k ** 2)[:, None] * h)
        add(m, ok)
    diffraction = np.zeros((w.size, grid.n_v, grid.n_u))
    im_a = m_a @ wi
    p_a = pdf_normal(np.broadcast_to(wi, (na, 3)), m_a, ndf=ndf, ax=ax, ay=ay, c=c)
    node_w = np.where((im_a > 0) & (p_a > 0), im_a * spec.D(m_a, ax, ay, c)
                      / (wi[2] * na * np.where(p_a > 0, p_a, 1.0)), 0.0)
    mirror = 2 * im_a[:, None] * m_a - wi
    scattered, reflected = np.zeros(w.size), np.zeros(w.size)
    for i, lam in enumerate(w):
        if dm.perturbative:
            Fc = np.ones(wo.shape[0])
        else:
            Fc = F.at(np.broadcast_to(wi, wo.shape), wo, lam) if hasattr(F, "at") else F(np.clip(h @ wi, 0, 1), lam)
        diffraction[i][inside] = out[:, i] * Fc
        Fm = (F.at(np.broadcast_to(wi, (na, 3)), mirror, lam) if hasattr(F, "at")
              else F(np.clip(im_a, 0.0, 1.0), lam)) * np.ones(na)
        # per facet: F (1 − A) on a conductor, the lobe's own absolute albedo on a dielectric
        share = np.asarray(nano.scattered_share(np.clip(im_a, 0.0, 1.0), lam, dm, material, polarization))
        lost = Fm * share if scatter.is_conductor(material) else share * np.ones(na)
        # Σ node_w G1 estimates ∫ G1 (ω_i·m) D dm / cos θ_i = 1 (Smith); normalized by it, so that near grazing
        # incidence, where few NDF nodes face the light, the facets' share is not over-counted
        total_w = float(np.sum(node_w))
        scattered[i] = float(np.sum(node_w * lost) / total_w) if total_w > 0 else 0.0
        reflected[i] = float(np.sum(node_w * Fm) / total_w) if total_w > 0 else 0.0
    return diffraction, scattered, reflected


#: the diffracted lobes may exceed their budget by this share before :func:`_cap_to_coherent_loss` acts: the two
#: are integrated by different quadratures (the paraxial lobe on the evaluation grid against E¹ on a polar grid:
#: < 2e-3; the facet-frame lobe's per-cell quadrature of 64 + 16 normals against the budget's average over the NDF
#: nodes: up to 2 %, measured on glass at α = 0.1, tests/test_dielectric_energy.py)
CAP_TOLERANCE = 3e-2


def _cap_to_coherent_loss(diffraction, lost, grid: DirectionGrid, budget=None):
    """Scale the diffracted lobes down where they hold more light than the coherent lobe gave up.

    guard: on a conductor the coherent fraction is the complement of the nano lobe's own albedo (energy
    conservation, :meth:`waveoptics.brdf.Nano.coherent_amplitude2`), so the two halves agree to quadrature accuracy
    and this step does not act (it lets through up to :data:`CAP_TOLERANCE`; measured at θ_i ≤ 70° on Gaussian,
    exponential and ABC PSDs with C from 2.2 to 4, σ up to λ/10, micro α up to 0.3: the lobe exceeds its budget by
    ≤ 2e-3; with no micro roughness up to 89.5°, tests/test_grazing.py). On a dielectric the budget is all the light
    the facets receive and do not reflect coherently (the scattered light also draws on the transmitted beam), which
    the lobe does not approach (tests/test_dielectric_energy.py: glass, s, p and unpolarized, 30–75° and Brewster's
    angle). Beyond 75° the tangent-plane lobe carries an albedo continued with first-order perturbation theory
    (:meth:`waveoptics.scatter.BandSeries.scattered_albedo`; before, its obliquity made it grow without bound and
    this step trimmed it). Where it does act (a grid too coarse for a wide lobe, micro roughness at grazing
    incidence on a grid whose cells cannot resolve the facets' incidences) it warns in one line with the share it
    removed, and reports the factor (``diffraction_energy_scale``).

    Parameters
    ----------
    diffraction, lost : ndarray (n_λ, n_v, n_u), 1/sr
        The diffracted lobes and the microfacet lobe minus the coherent lobe.
    budget : ndarray (n_λ,), optional
        The light the lobes may hold instead of the integral of *lost*: the facet route's light scattered by the
        facets before masking on the way out (:func:`facet_frame_diffraction`). A facet whose mirror direction is
        masked or below the horizon still sends part of its diffracted lobe out, so in Walter's integral the
        diffracted part can exceed the coherent part's loss; it cannot exceed what the facets scatter.

    Returns
    -------
    diffraction : ndarray (n_λ, n_v, n_u)
    scale : ndarray (n_λ,)
        The factor applied per wavelength (1 where the lobe was within its share).
    """
    got = integrate(diffraction, grid)
    budget = np.maximum(integrate(lost, grid) if budget is None else np.asarray(budget, dtype=float), 0.0)
    scale = np.where(got > budget * (1.0 + CAP_TOLERANCE), budget / np.where(got > 0, got, 1.0), 1.0)
    if np.any(scale < 1.0):
        i = int(np.argmin(scale))
        warnings.warn(f"two-scale energy guard removed {100 * (1 - scale[i]):.3g}% of the diffracted light "
                      f"({got[i] - budget[i]:.3g} of the incident light) at wavelength index {i}: the nano lobe "
                      "held more than its energy budget", scatter.DiffractionWarning, stacklevel=3)
    return diffraction * scale[:, None, None], scale


def _diffracted_part(route, wi, w, mat, micro, nano, grid, F, dm, polarization, reference_grid, lost, coherent, *,
                     solver, device, precision):
    """:func:`evaluate`'s diffracted lobes by *route* (``frame``, ``paraxial`` or ``none``), the solver used, the
    guard's factor per wavelength and the light masked or sent beyond the horizon (see :func:`evaluate`)."""
    inside = grid.inside
    if route == "none":
        z = np.zeros(w.size)
        return np.zeros((w.size, grid.n_v, grid.n_u)), "none", np.ones(w.size), z
    if route == "frame":   # Walter's integral: each facet's nano lobe in its own frame
        diffraction, scattered, reflected = facet_frame_diffraction(
            wi, w, mat, micro, nano, grid, F, diffraction=dm, polarization=polarization, table_grid=reference_grid)
        diffraction = np.where(inside, diffraction, 0.0)
        # the light the facets scatter that is masked on its way out or leaves below the macro horizon
        beyond = np.maximum(scattered - integrate(diffraction, grid), 0.0)
        # guard: neither more than the facets scatter nor, with the coherent part, more than they reflect (on a
        # dielectric: more than they receive, the scattered light also drawing on the transmitted beam)
        budget = np.minimum(scattered, reflected - integrate(coherent, grid) if scatter.is_conductor(mat)
                            else integrate(lost, grid))
    else:
        fn = nano_lobe(wi, w, nano, grid, F, solver=solver, device=device, precision=precision, diffraction=dm,
                       material=mat)
        K0 = micro_kernel(wi, micro, grid)
        K = K0[None] * facet_scatter_weights(wi, w, nano, grid, dm, mat, polarization, kernel=K0)
        diffraction = np.where(inside, _convolve(fn, K, grid), 0.0)
        # the light each facet's lobe, shifted to that facet's mirror direction, puts beyond the horizon (the
        # convolution's total is Σ f_n du dv × Σ K): lost, as shadowing would lose it
        beyond = np.maximum(integrate(fn, grid) * K.sum(axis=(-2, -1)) - integrate(diffraction, grid), 0.0)
        budget = None
    if reference_grid is None:
        diffraction, energy_scale = _cap_to_coherent_loss(diffraction, lost, grid, budget)
    else:
        energy_scale = np.ones(w.size)
    used = solver if solver != "auto" else ("psd" if nano.model is not None else "fft")
    return diffraction, used, energy_scale, beyond


def evaluate(wi, wavelengths_nm, material, micro: Micro, nano: Nano | None, grid: DirectionGrid, *,
             solver: str = "auto", kd=0.5, diffuse: str = "lambert", device=None, precision="float32",
             reference_grid: DirectionGrid | None = None, diffraction: str = "kirchhoff",
             polarization: str = "unpolarized", multiple_scattering: bool = False, facet: str = "auto") -> Lobes:
    """Two-scale BRDF for one incident direction on *grid* at each wavelength, plus the plain microfacet BRDF.

    Parameters
    ----------
    wi : array_like (3,)
        Unit vector towards the light (z = macro normal, wi_z > 0).
    wavelengths_nm : array_like
        Wavelengths in nm.
    material : str or Material
        Surface material (metals get no diffuse term).
    micro : Micro
        Micro roughness (α = 0 allowed: a mirror-like micro surface).
    nano : Nano or None
        Nano roughness; None (or σ = 0) gives the microfacet model exactly.
    grid : DirectionGrid
        Output directions.
    kd : float or array (n_λ,)
        Diffuse albedo of a dielectric's substrate (ignored for metals).
    reference_grid : DirectionGrid, optional
        When *grid* is a patch of a larger grid (same cells, e.g. around a view direction), that grid: the micro
        lobe is normalized on it, so the patch holds the same values as the larger grid at its cells. The
        coherent-loss cap needs the whole lobe and is not applied on a patch (it only acts near grazing incidence).
    diffraction : str
        Diffraction model of the nano lobe and of the coherent fraction, a name in
        :data:`waveoptics.scatter.DIFFRACTION_MODELS` (default ``kirchhoff``).
    polarization : {'unpolarized', 's', 'p'}
        Of the incident light relative to the macro plane of incidence: every facet (micro and nano) reflects its
        own s/p split (:func:`waveoptics.materials.fresnel.F_facet_polarized`); the diffuse substrate is
        unpolarized.
    multiple_scattering : bool
        Add Kulla & Conty's (2017) compensation lobe of the micro NDF (:mod:`waveoptics.brdf.multiscatter`) to
        both models, as :class:`waveoptics.brdf.TwoScaleBRDF` does: nano-roughness only redistributes singly
        scattered light in direction, so the light lost to bounces between micro facets is the microfacet
        model's. Its Fresnel average F_ms is of the unpolarized F (also for s or p light).
    facet : {'auto', 'frame', 'paraxial'}
        How the facets carry the nano lobe (:func:`facet_route`): ``frame`` evaluates each facet's lobe in its own
        frame (:func:`facet_frame_diffraction`), ``paraxial`` shifts the macro-incidence lobe to each facet's
        mirror direction (an FFT convolution, fast; docs/two-scale.md gives its error); ``auto`` (default) takes
        ``frame`` for PSD statistics the grid resolves. The route taken is ``info["facet_integration"]``.

    Returns
    -------
    Lobes
    """
    dm = scatter.get_model(diffraction, perturbative=True)
    mat: Material = get_material(material)
    w = check_wavelengths(wavelengths_nm)
    wi = np.asarray(wi, dtype=float)
    wi = wi / np.linalg.norm(wi)
    if not wi[2] > 0:
        raise WaveopticsError("the incident direction must be above the surface (θ_i < 90°)")
    wo = grid.directions()
    inside = grid.inside
    shape = (w.size, grid.n_v, grid.n_u)

    if polarization == "unpolarized":
        def F(cos_d, lam):
            return mat.F(cos_d, lam)
    else:   # each facet reflects its own s/p split of the macro polarization (needs both directions)
        F = fresnel_function(mat, polarization)

    h = wi[None, None, :] + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)

    # --- micro specular lobe with F (plain microfacet) and the coherent fraction A --------------------------
    sigma_nano = 0.0 if nano is None else nano.sigma
    if _sharp(micro, grid):
        mf = np.zeros(shape)
        cell = _mirror_cell(grid, wi)
        rho = float(albedo(wi, fresnel="one", **micro.kw()))
        mf_one = np.zeros(shape)   # the same lobe with F = 1: all the light the facets receive
        if cell is not None:
            Fi = np.array([float(np.ravel(_F_mirror(F, wi, lam))[0]) for lam in w])
            mf[:, cell[0], cell[1]] = Fi * rho / (grid.du * grid.dv)
            mf_one[:, cell[0], cell[1]] = rho / (grid.du * grid.dv)
        A = np.array([float(nano.coherent_amplitude2(wi[2], lam, dm, mat, polarization, _azimuth_deg(wi)))
                      if sigma_nano > 0 else 1.0 for lam in w])
        coherent = mf * A[:, None, None]
    else:
        mf = np.empty(shape)
        coherent = np.empty(shape)
        f1 = np.where(inside, specular(wi, wo, fresnel="one", **micro.kw()), 0.0)
        # energy-preserving sampling: near grazing a narrow lobe is squeezed against the rim of the (u, v) disc and
        # the cell quadrature over- or under-counts it; scale the F = 1 lobe to the accurate quadrature albedo
        grid_rho = float(f1.sum()) * grid.du * grid.dv
        if reference_grid is not None:  # a patch: the quadrature of the whole grid it belongs to
            ref = reference_grid
            f_ref = specular(wi, ref.directions(), fresnel="one", **micro.kw())
            grid_rho = float(np.sum(np.where(ref.inside, f_ref, 0.0))) * ref.du * ref.dv
        rho = float(albedo(wi, fresnel="one", **micro.kw()))
        if grid_rho > 0:
            f1 = f1 * (rho / grid_rho)
        # a height field's facets beyond the lobe's main light keep the coherent fraction of θ_i, as their
        # diffracted weights do (facet_scatter_weights)
        used = inside if nano is None or nano.surface is None else inside & _significant(np.where(inside, f1, 0))
        for i, lam in enumerate(w):
            mf[i] = f1 * (F.at(wi, wo, lam) if hasattr(F, "at") else F(cos_d, lam))
            A = np.ones(cos_d.shape)
            if sigma_nano > 0:
                phi = _azimuth_deg(wi)
                A[:] = nano.coherent_amplitude2(wi[2], lam, dm, mat, polarization, phi)
                if used.any():
                    A[used] = nano.coherent_amplitude2(cos_d[used], lam, dm, mat, polarization, phi)
            coherent[i] = mf[i] * A
        mf = np.where(inside, mf, 0.0)
        mf_one = np.broadcast_to(np.where(inside, f1, 0.0), shape)
        coherent = np.where(inside, coherent, 0.0)

    # --- diffraction: nano lobe carried by the facets --------------------------------------------------------
    route = facet_route(micro, nano, grid, w, facet) if sigma_nano > 0 else "none"
    # a conductor's lobe holds the coherent lobe's loss; a dielectric's at most all the light the facets receive
    # and do not reflect coherently (its scattered light also draws on the transmitted beam)
    lost = (mf if scatter.is_conductor(mat) else mf_one) - coherent
    diffraction, used, energy_scale, beyond = _diffracted_part(
        route, wi, w, mat, micro, nano, grid, F, dm, polarization, reference_grid, lost, coherent,
        solver=solver, device=device, precision=precision)

    # --- diffuse (dielectrics only) ---------------------------------------------------------------------------
    diff_albedo = np.zeros(w.size)
    if mat.is_metal or np.all(np.asarray(kd) == 0) or diffuse == "none":
        diff = np.zeros(shape)
    else:
        kd_arr = np.broadcast_to(np.asarray(kd, dtype=float), (w.size,))
        diff = np.empty(shape)
        for i, lam in enumerate(w):
            def f_d(a, b, i=i, lam=lam):
                return (DIFFUSES[diffuse][0](a, b, kd_arr[i], 0.0)
                        * diffuse_tradeoff(a, b, lambda c: mat.F(c, lam)))
            diff[i] = np.where(inside, f_d(wi[None, None, :], wo), 0.0)
            diff_albedo[i] = float(directional_albedo(f_d, wi, alpha=1.0))
    # --- multiple scattering between micro facets (optional, both models) -----------------------------------
    multiple = multiple_albedo = None
    mf_total = mf + diff
    if multiple_scattering:
        multiple, multiple_albedo = multiple_scattering_lobe(wi, wo, w, mat, micro)
        multiple = np.where(inside, multiple, 0.0)
        mf_total = mf_total + multiple
    return Lobes(grid=grid, wi=wi, wavelengths_nm=w, coherent=coherent, diffraction=diffraction, diffuse=diff,
                 diffuse_albedo=diff_albedo if reference_grid is None else None,
                 multiple=multiple, multiple_albedo=multiple_albedo if reference_grid is None else None,
                 microfacet=mf_total,
                 info={"solver": used, "sigma_nano_m": sigma_nano, "micro": micro.__dict__,
                       "material": mat.name, "sharp_micro_lobe": _sharp(micro, grid),
                       "diffraction_energy_scale": energy_scale.tolist(),
                       "diffraction_beyond_horizon": (beyond if reference_grid is None
                                                      else np.full(w.size, np.nan)).tolist(),
                       "diffraction_model": dm.name, "facet_integration": route,
                       "polarization": polarization, "multiple_scattering": bool(multiple_scattering)})


def multiple_scattering_lobe(wi, wo, wavelengths_nm, material, micro: Micro):
    """(lobe (n_λ, ...) in 1/sr, albedo (n_λ,)) of Kulla & Conty's compensation for the micro NDF at the
    directions *wo* (..., 3): f_ms(μ_i, μ_o) F_ms(λ) and its albedo (1 − E(μ_i)) F_ms(λ), from the same tables
    as :class:`waveoptics.brdf.MicrofacetBRDF` (one code path; :mod:`waveoptics.brdf.multiscatter`).

    References
    ----------
    .. [1] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course.
    """
    from .protocol import MicrofacetBRDF

    b = MicrofacetBRDF(material, micro, multiple_scattering=True)
    wo = np.asarray(wo, dtype=float)
    flat = wo.reshape(-1, 3)
    wi_b = np.broadcast_to(np.asarray(wi, dtype=float), flat.shape)
    lobe = np.stack([b._f_ms(wi_b, flat, lam).reshape(wo.shape[:-1]) for lam in wavelengths_nm])
    albedo = np.array([(1.0 - float(b._ms_table()(wi[2]))) * b._F_ms(lam) for lam in wavelengths_nm])
    return lobe, albedo


#: default split: spatial periods longer than this many λ_max are micro-geometry (geometric optics)
SPLIT_PERIODS_OF_LAMBDA = 10.0


def _alpha_of_slopes(hf, ndf, ndf_shape, sx, sy):
    """(α_x, α_y) of NDF *ndf* matching the slopes of *hf*: Beckmann √2 × rms slope per axis (exact for Gaussian
    slopes); GGX per axis from the median |slope| (√3 × median, :data:`waveoptics.brdf.ndf_fit.GGX_AXIS_MEDIAN`);
    the other (isotropic) NDFs from the median slope magnitude (:func:`waveoptics.brdf.alpha_for_median_slope`)."""
    from .ndf_fit import GGX_AXIS_MEDIAN, alpha_for_median_slope

    if ndf == "beckmann":
        return float(np.sqrt(2) * (sx if sx is not None else sy)), float(np.sqrt(2) * (sy if sy is not None else sx))
    gy, gx = np.gradient(hf.heights, hf.dy, hf.dx)
    if ndf == "ggx":
        return (float(np.median(np.abs(gx)) / GGX_AXIS_MEDIAN), float(np.median(np.abs(gy)) / GGX_AXIS_MEDIAN))
    a = alpha_for_median_slope(ndf, float(np.median(np.hypot(gx, gy))), ndf_shape)
    return a, a


def split_scales(surface: HeightField, wavelengths_nm, *, cutoff_period_m: float | None = None,
                 ndf: str = "beckmann", ndf_shape=None):
    """Split a height field holding both scales into a micro NDF and a nano height field.

    The surface spectrum is cut at the spatial frequency f_c = 1 / Λ_c (default Λ_c = 10 λ_max): components of
    longer period form the micro-geometry, the rest the nano-geometry. The split is a smooth (Gaussian-edged)
    partition of unity in frequency, so micro + nano = surface exactly. The micro part's slopes give the NDF
    roughness: for Gaussian slopes the Beckmann α along an axis is √2 times the rms slope along it
    (docs/physics.md §1: α = rms |∇h| = 2σ/T for an isotropic Gaussian surface); the other NDFs (*ndf*, with
    *ndf_shape*) match the median slope instead (:mod:`waveoptics.brdf.ndf_fit`: GGX has no finite rms slope).

    Why 10 λ_max: a component of period Λ deflects light by sin θ = λ/Λ; beyond 10 λ that is < 0.1 (6°), where
    a slope distribution describes the deflection (stationary phase, docs/physics.md §1), while shorter periods
    scatter into wide angles only diffraction describes. Pass *cutoff_period_m* to choose another scale.

    Returns
    -------
    micro : Micro
        NDF (α_x, α_y) from the micro part's slopes (α_y omitted when isotropic within 5 %).
    nano : HeightField
        The high-pass part (same grid).
    info : dict
        ``cutoff_period_m``, micro/nano rms heights and slopes.

    References
    ----------
    .. [1] Holzschuch & Pacanowski 2017, §3 (scale separation); Beckmann & Spizzichino 1963 (slope statistics).
    """

    w = check_wavelengths(wavelengths_nm)
    Lc = float(cutoff_period_m) if cutoff_period_m is not None else SPLIT_PERIODS_OF_LAMBDA * float(w.max()) * 1e-9
    if not np.isfinite(Lc) or Lc <= 0:
        raise WaveopticsError(f"cut-off period {cutoff_period_m!r} m is not allowed; it must be > 0")
    h = surface.heights - surface.heights.mean()
    ny, nx = h.shape
    fx = np.fft.fftfreq(nx, surface.dx)
    fy = np.fft.fftfreq(ny, surface.dy)
    f = np.hypot(fx[None, :], fy[:, None])
    low = np.exp(-np.log(2) * (f * Lc) ** 2)  # 1/2 at f = 1/Λ_c, smooth edge (no ringing)
    micro_h = np.real(np.fft.ifft2(np.fft.fft2(h) * low))
    nano_h = h - micro_h
    meta = dict(surface.meta)
    micro_hf = HeightField(micro_h, surface.dx, surface.dy, surface.mask, dict(meta))
    nano_hf = HeightField(nano_h, surface.dx, surface.dy, surface.mask, {**meta, "split_cutoff_period_m": Lc})
    sx, sy = surfaces.rms_slopes(micro_hf)
    ax, ay = _alpha_of_slopes(micro_hf, ndf, ndf_shape, sx, sy)
    iso = abs(ax - ay) <= 0.05 * max(ax, ay)
    if not iso and not NDFS[ndf].anisotropic:
        ax = ay = float(np.sqrt(ax * ay))   # the NDF has no anisotropic form: the geometric mean, said in info
        iso = True
    micro = Micro(alpha=float(np.sqrt(ax * ay)) if iso else float(ax), alpha_y=None if iso else float(ay), ndf=ndf,
                  ndf_shape=ndf_shape)
    info = {"cutoff_period_m": Lc, "micro_rms_height_m": float(micro_h.std()), "micro_rms_slopes": [sx, sy],
            "nano_rms_height_m": float(nano_h.std()), "micro_alpha": [float(ax), float(ay)]}
    return micro, nano_hf, info
