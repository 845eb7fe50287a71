"""The BRDF as a function: ``eval``, ``pdf``, ``sample`` and ``albedo`` at any (ω_i, ω_o, λ).

Every BRDF model of waveoptics implements :class:`BRDF` (as Mitsuba 3's ``BSDF`` and pbrt-v4's ``BxDF`` do):

* ``eval(wi, wo, wavelength_nm)`` → f in 1/sr (not multiplied by cos θ_o);
* ``pdf(wi, wo, wavelength_nm)`` → density in 1/sr (over solid angle of ω_o) with which ``sample`` draws ω_o;
* ``sample(wi, wavelength_nm, u)`` → :class:`BRDFSample` (ω_o, weight f cos θ_o / pdf, pdf), u uniform in
  [0, 1)² (the first number also picks the lobe of a mixture, pbrt's remapping);
* ``albedo(wi, wavelength_nm)`` → ∫ f cos θ_o dω_o by quadrature of ``eval`` (dimensionless).

Conventions: directions are unit vectors (..., 3) in the local frame of the macro surface (z the normal), ω_i
towards the light, ω_o towards the viewer; wavelengths in nm. Arguments broadcast with NumPy rules (direction
arrays over their leading axes, wavelengths as a plain array), so one call evaluates many pairs at many
wavelengths. Below the surface f = pdf = 0 and samples have weight 0. Models evaluate one wavelength at a time
(grouping equal wavelengths), which keeps spectral inputs exact.

:class:`MicrofacetBRDF` is the geometric-optics model (specular microfacet lobe plus the energy-coupled diffuse
term); the two-scale model is :class:`waveoptics.brdf.TwoScaleBRDF`.

References
----------
.. [1] M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed., 2023, §9.1 (the BxDF interface)
   and §2.4 (remapping one uniform sample to choose a lobe).
.. [2] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §9.2
   (mixture densities of several sampling techniques).
.. [3] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, unknown
from ..materials import Material, get_material
from ..units import check_wavelengths
from ..vocabulary import DEFAULT_MATERIAL
from .diffuse import DIFFUSES, diffuse_parameter, diffuse_tradeoff
from .fresnel_terms import FRESNELS
from .microfacet import specular_geometry, specular_term
from .directions import as_dirs
from .ndf import ALPHA_MAX, check_alpha, ndf_by_name
from .quadrature import directional_albedo, slope_table_of
from .sampling import pdf_reflected, sample_reflected
from .shadowing import shadowing_by_name
from .roughness_scales import Micro

__all__ = ['BRDFSample', 'BRDF', 'SphereBSDF', 'MicrofacetBRDF', 'TwoScaleParts', 'sample_cosine', 'pdf_cosine', 'lobe_choice',
           'check_uniform']


@dataclass(frozen=True)
class BRDFSample:
    """One importance sample per input: outgoing unit directions ``wo`` (..., 3), ``weight`` = f cos θ_o / pdf
    (dimensionless; 0 for an invalid sample) and ``pdf`` (1/sr, 0 for an invalid sample)."""

    wo: np.ndarray
    weight: np.ndarray
    pdf: np.ndarray


def sample_cosine(u):
    """Cosine-weighted hemisphere direction from u (..., 2): a uniform disc point lifted (Malley's method)."""
    r = np.sqrt(u[..., 0])
    phi = 2.0 * np.pi * u[..., 1]
    return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1.0 - u[..., 0], 0.0))], axis=-1)


def pdf_cosine(wo):
    """Density cos θ_o / π of :func:`sample_cosine` (1/sr), 0 below the surface."""
    return np.maximum(wo[..., 2], 0.0) / np.pi


def lobe_choice(u0, probs):
    """Pick lobe j with probability probs[j] (each (n,)) from u0 (n,), and remap u0 to a fresh uniform number
    (pbrt-v4 §2.4). Returns (index (n,), remapped u0)."""
    cdf = np.cumsum(np.stack(probs, axis=0), axis=0)
    cdf = cdf / np.where(cdf[-1] > 0, cdf[-1], 1.0)
    idx = np.sum(u0[None, :] >= cdf[:-1], axis=0)
    lo = np.where(idx > 0, np.take_along_axis(np.vstack([np.zeros_like(u0), cdf]), idx[None], 0)[0], 0.0)
    hi = np.take_along_axis(cdf, idx[None], 0)[0]
    width = hi - lo
    remapped = np.where(width > 0, (u0 - lo) / np.where(width > 0, width, 1.0), 0.5)
    return idx, np.clip(remapped, 0.0, np.nextafter(1.0, 0.0))


def check_uniform(u):
    """*u* as a float array of uniform numbers in [0, 1) with last axis 2 (else a FieldError naming ``u``)."""
    u = np.asarray(u, dtype=float)
    if u.shape[-1:] != (2,) or np.any(~np.isfinite(u)) or np.any((u < 0) | (u >= 1)):
        raise FieldError(f"u must be uniform numbers in [0, 1) of shape (..., 2), got shape {u.shape}", "u")
    return u


def broadcast_pair(wi, wo, wavelength_nm):
    """Flatten broadcast (wi, wo, λ) to (n, 3), (n, 3), (n,); returns them and the batch shape."""
    wi = as_dirs(wi, "wi")
    wo = as_dirs(wo, "wo")
    lam = np.asarray(wavelength_nm, dtype=float)
    check_wavelengths(lam.ravel() if lam.size else lam)
    shape = np.broadcast_shapes(wi.shape[:-1], wo.shape[:-1], lam.shape)
    wi = np.broadcast_to(wi, shape + (3,)).reshape(-1, 3)
    wo = np.broadcast_to(wo, shape + (3,)).reshape(-1, 3)
    return wi, wo, np.broadcast_to(lam, shape).reshape(-1), shape


def broadcast_incidence(wi, wavelength_nm):
    """Flatten broadcast (wi, λ) to (n, 3), (n,); returns them and the batch shape."""
    wi = as_dirs(wi, "wi")
    lam = np.asarray(wavelength_nm, dtype=float)
    check_wavelengths(lam.ravel() if lam.size else lam)
    shape = np.broadcast_shapes(wi.shape[:-1], lam.shape)
    return np.broadcast_to(wi, shape + (3,)).reshape(-1, 3), np.broadcast_to(lam, shape).reshape(-1), shape


class BRDF:
    """Base of every BRDF model (see the module doc). Subclasses implement the one-wavelength methods
    ``_eval1(wi, wo, lam)``, ``_pdf1(wi, wo, lam)``, ``_sample1(wi, u, lam)`` → (wo, pdf) on flat arrays and
    ``_albedo_parts(lam)`` → [(f(wi, wo), α_x, α_y)], the terms to integrate and the slope widths that place
    their quadrature nodes."""

    def eval(self, wi, wo, wavelength_nm):
        """f(ω_i, ω_o, λ) in 1/sr (broadcast shape of the inputs)."""
        wi, wo, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        return self._eval_flat(wi, wo, lam).reshape(shape)

    def _eval_nodes(self, wi, wo, wavelengths_nm) -> np.ndarray:
        """f (n, n_λ) in 1/sr at flat direction pairs (n, 3) and every wavelength of *wavelengths_nm*: one
        ``_eval1`` per wavelength (a model that shares work between wavelengths overrides it)."""
        return np.stack([self._eval1(wi, wo, lam) for lam in wavelengths_nm], axis=-1)

    def pdf(self, wi, wo, wavelength_nm):
        """Density (1/sr over ω_o) of :meth:`sample`."""
        wi, wo, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        return self._pdf_flat(wi, wo, lam).reshape(shape)

    def sample(self, wi, wavelength_nm, u) -> BRDFSample:
        """Importance-sample ω_o for ω_i at λ from u (..., 2) uniform in [0, 1)²."""
        u = check_uniform(u)
        wi_b, u2, lam, shape = broadcast_pair(wi, np.zeros(u.shape[:-1] + (3,)) + [0, 0, 1], wavelength_nm)
        u_flat = np.broadcast_to(u, shape + (2,)).reshape(-1, 2)
        wo = self._sample_flat(wi_b, u_flat, lam)
        up = (wi_b[:, 2] > 0) & (wo[:, 2] > 0)
        wo_ok = np.where(up[:, None], wo, np.array([0.0, 0.0, 1.0]))
        f = self._eval_flat(wi_b, wo_ok, lam)
        p = self._pdf_flat(wi_b, wo_ok, lam)
        ok = up & (p > 0)
        weight = np.where(ok, f * np.maximum(wo_ok[:, 2], 0.0) / np.where(ok, p, 1.0), 0.0)
        return BRDFSample(wo=wo.reshape(shape + (3,)), weight=weight.reshape(shape),
                          pdf=np.where(ok, p, 0.0).reshape(shape))

    def sample_wo(self, wi, wavelength_nm, u):
        """The sampled ω_o alone (..., 3) for ω_i at λ from u (..., 2) uniform in [0, 1)², wherever the sampler
        puts it (a BSDF's transmitted directions below the surface included; 0 for an invalid sample), for a
        caller that weights the samples itself with :meth:`eval` and :meth:`pdf` (a renderer's transport mode)."""
        u = check_uniform(u)
        wi_b, _, lam, shape = broadcast_pair(wi, np.zeros(u.shape[:-1] + (3,)) + [0, 0, 1], wavelength_nm)
        u_flat = np.array(np.broadcast_to(u, shape + (2,)).reshape(-1, 2))
        return self._sample_flat(wi_b, u_flat, lam).reshape(shape + (3,))

    def albedo(self, wi, wavelength_nm):
        """Directional albedo ∫ f cos θ_o dω_o (dimensionless) by quadrature of :meth:`eval` over half-vectors
        (:func:`waveoptics.brdf.directional_albedo`, nodes placed by each term's width)."""
        wi_f, lam_f, shape = broadcast_incidence(wi, wavelength_nm)
        out = np.zeros(lam_f.size)
        micro = getattr(self, "micro", None)   # a slope table's nodes follow its bins
        table = None if micro is None else slope_table_of(micro.ndf, micro.ndf_shape)
        for j, (w1, l1) in enumerate(zip(wi_f, lam_f)):
            if w1[2] <= 0:
                continue
            for f, alpha, alpha_y in self._albedo_parts(float(l1)):
                out[j] += float(directional_albedo(
                    lambda a, b, f=f: f(np.broadcast_to(a, b.shape), b), w1, alpha=alpha, alpha_y=alpha_y,
                    table=table))
        return out.reshape(shape)

    # -- flat arrays (n, 3), (n,): one call of the one-wavelength methods per distinct wavelength ----------------
    def _eval_flat(self, wi, wo, lam):
        return self._by_wavelength(self._eval1, wi, wo, lam)

    def _pdf_flat(self, wi, wo, lam):
        return self._by_wavelength(self._pdf1, wi, wo, lam)

    def _sample_flat(self, wi, u, lam):
        wo = np.zeros_like(wi)
        for val in np.unique(lam):
            sel = lam == val
            wo[sel] = self._sample1(wi[sel], u[sel].copy(), float(val))
        return wo

    @staticmethod
    def _by_wavelength(fn, wi, wo, lam):
        out = np.zeros(lam.size)
        for val in np.unique(lam):
            sel = lam == val
            out[sel] = fn(wi[sel], wo[sel], float(val))
        return out

    def _albedo_parts(self, lam):
        raise NotImplementedError


class SphereBSDF(BRDF):
    """Base of the BSDFs over the whole sphere (reflection and transmission): directions may lie on either side,
    ``eval`` gives f in the radiance convention (Veach 1997, §5.2), ``sample`` weights f |cos θ_o| / pdf, and
    ``albedo`` is ∫ f |cos θ_o| dω_o over the sphere, the sum of the subclass's ``albedo_parts``.

    References
    ----------
    .. [1] E. Veach, PhD thesis, Stanford, 1997, §5.2 (the η² factor of radiance in transmission).
    """

    def sample(self, wi, wavelength_nm, u) -> BRDFSample:
        """Importance-sample ω_o on the sphere for ω_i at λ from u (..., 2) uniform in [0, 1)²; invalid samples
        have ``wo`` = 0, weight 0 and pdf 0."""
        u = check_uniform(u)
        wi_b, _, lam, shape = broadcast_pair(wi, np.zeros(u.shape[:-1] + (3,)) + [0, 0, 1], wavelength_nm)
        u_flat = np.broadcast_to(u, shape + (2,)).reshape(-1, 2)
        wo = self._sample_flat(wi_b, u_flat, lam)
        valid = np.linalg.norm(wo, axis=-1) > 0.5
        wo_ok = np.where(valid[:, None], wo, np.array([0.0, 0.0, 1.0]))
        f = self._eval_flat(wi_b, wo_ok, lam)
        p = self._pdf_flat(wi_b, wo_ok, lam)
        ok = valid & (p > 0)
        weight = np.where(ok, f * np.abs(wo_ok[:, 2]) / np.where(ok, p, 1.0), 0.0)
        return BRDFSample(wo=np.where(ok[:, None], wo, 0.0).reshape(shape + (3,)), weight=weight.reshape(shape),
                          pdf=np.where(ok, p, 0.0).reshape(shape))

    def albedo_parts(self, wi, wavelength_nm) -> dict:
        raise NotImplementedError

    def albedo(self, wi, wavelength_nm):
        """Directional albedo ∫ f |cos θ_o| dω_o over the sphere (dimensionless; R + T, 1 for a lossless interface
        with every bounce counted): the sum of :meth:`albedo_parts`."""
        return sum(self.albedo_parts(wi, wavelength_nm).values())


@dataclass(frozen=True)
class MicrofacetBRDF(BRDF):
    """Geometric-optics microfacet BRDF of a material: the specular term F G D / (4 cos θ_i cos θ_o) plus, for
    dielectrics, a diffuse substrate with the diffuse-specular trade-off (as :func:`waveoptics.brdf.brdf`).

    Parameters
    ----------
    material : str or Material
        Spectral complex index (metals get no diffuse term).
    micro : Micro
        NDF, α (α_y) and shadowing.
    kd : float
        Diffuse albedo of a dielectric's substrate, in [0, 1].
    diffuse : str
        A name in :data:`waveoptics.brdf.DIFFUSES`.
    fresnel : str
        ``exact`` (the material's F) or ``one`` (F = 1, white furnace).
    ndf_shape : float
        Tail exponent of the ABC NDF.
    diffuse_sigma : float, rad
        Oren-Nayar's roughness σ in [0, π/2] (``diffuse="oren-nayar"``; separate from the specular α).
    multiple_scattering : bool
        Add Kulla & Conty's (2017) compensation lobe for light that bounces between facets
        (:mod:`waveoptics.brdf.multiscatter`): the white furnace then holds at every incidence.
    diffuse_roughness : float
        Burley's roughness r in [0, 1] (``diffuse="burley"``; default 0, as before the split from
        *diffuse_sigma*).

    Sampling: visible normals for GGX, D cos θ_m for the other NDFs (:mod:`waveoptics.brdf.sampling`), cosine
    sampling for the diffuse term, mixed in proportion F(θ_i) : kd (1 − F(θ_i)).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (20) (specular term) and §5.3 (sampling).
    .. [2] E. Heitz, JCGT 7(4), 2018 (visible normals).
    .. [3] P. Shirley et al., Pacific Graphics 1997 (the diffuse-specular coupling).
    .. [4] M. Oren, S. K. Nayar, SIGGRAPH 1994 (σ); B. Burley, SIGGRAPH 2012 course notes (r).
    """

    material: Material | str = DEFAULT_MATERIAL
    micro: Micro = Micro()
    kd: float = 0.0
    diffuse: str = "lambert"
    fresnel: str = "exact"
    ndf_shape: float | None = None
    diffuse_sigma: float = 0.0
    multiple_scattering: bool = False
    diffuse_roughness: float = 0.0

    def __post_init__(self):
        if not (np.isfinite(self.diffuse_sigma) and 0 <= self.diffuse_sigma <= np.pi / 2):
            raise FieldError(f"diffuse_sigma={self.diffuse_sigma!r} rad is not allowed; it must be in [0, π/2]",
                             "diffuse_sigma")
        if not (np.isfinite(self.diffuse_roughness) and 0 <= self.diffuse_roughness <= 1):
            raise FieldError(f"diffuse_roughness={self.diffuse_roughness!r} is not allowed; Burley's r must be in "
                             "[0, 1]", "diffuse_roughness")
        if self.diffuse == "burley" and self.diffuse_sigma != 0:
            raise FieldError("diffuse_sigma is Oren-Nayar's σ; Burley's roughness is diffuse_roughness",
                             "diffuse_sigma")
        object.__setattr__(self, "material", get_material(self.material))
        if self.diffuse not in DIFFUSES:
            raise unknown("diffuse model", self.diffuse, DIFFUSES)
        if self.fresnel not in ("exact", "one"):
            raise unknown("Fresnel model", self.fresnel, [k for k in FRESNELS if k != "schlick"])
        if not (np.isfinite(self.kd) and 0 <= self.kd <= 1):
            raise FieldError(f"kd={self.kd!r} is not allowed; the diffuse albedo must be in [0, 1]", "kd")
        spec = ndf_by_name(self.micro.ndf)
        shape = getattr(self.micro, "ndf_shape", None)
        if self.ndf_shape is None:
            object.__setattr__(self, "ndf_shape", shape)
        elif shape is not None and shape != self.ndf_shape:
            raise FieldError(f"ndf_shape={self.ndf_shape!r} differs from micro.ndf_shape={shape!r}; give it once",
                             "ndf_shape")
        if self.ndf_shape is not None:
            check_alpha(min(self.micro.alpha, ALPHA_MAX), None, spec, self.ndf_shape)

    # -- pieces shared with the two-scale model ---------------------------------------------------------
    def _F(self, lam):
        if self.fresnel == "one":
            return lambda c: np.ones_like(np.asarray(c, dtype=float))
        return lambda c: self.material.F(c, lam)

    def _micro_args(self):
        kw = self.micro.kw()
        return kw["ndf"], kw["alpha"], (kw["alpha_y"] if kw["alpha_y"] is not None else kw["alpha"])

    def _specular_geometry(self, wi, wo) -> tuple:
        """The wavelength-independent factors of :meth:`_f_specular` (:func:`specular_geometry`)."""
        ndf, ax, ay = self._micro_args()
        gfn, _ = shadowing_by_name(self.micro.shadowing)
        return specular_geometry(wi, wo, ndf_by_name(ndf), ax, ay, self.ndf_shape, gfn)

    def _f_specular(self, wi, wo, F_fn, geometry=None):
        ndf, ax, ay = self._micro_args()
        gfn, _ = shadowing_by_name(self.micro.shadowing)
        return specular_term(wi, wo, ndf_by_name(ndf), ax, ay, self.ndf_shape, gfn, F_fn, geometry)

    def _has_diffuse(self):
        return (not self.material.is_metal) and self.kd > 0 and self.diffuse != "none"

    def _f_diffuse(self, wi, wo, F_fn):
        if not self._has_diffuse():
            return np.zeros(wi.shape[0])
        rough = diffuse_parameter(self.diffuse, self.diffuse_sigma, self.diffuse_roughness)
        return DIFFUSES[self.diffuse][0](wi, wo, self.kd, rough) * diffuse_tradeoff(wi, wo, F_fn)

    def _p_diffuse(self, wi, lam):
        """Probability of sampling the diffuse lobe: kd (1 − F(θ_i)) / (F(θ_i) + kd (1 − F(θ_i)))."""
        if not self._has_diffuse():
            return np.zeros(wi.shape[0])
        Fi = self._F(lam)(np.clip(wi[:, 2], 0.0, 1.0))
        d = self.kd * (1.0 - Fi)
        return d / np.maximum(Fi + d, 1e-300)

    def _sample_specular(self, wi, u):
        ndf, ax, ay = self._micro_args()
        wo, _ = sample_reflected(wi, u, ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)
        return wo

    def _pdf_specular(self, wi, wo):
        ndf, ax, ay = self._micro_args()
        return pdf_reflected(wi, wo, ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)

    # -- multiple scattering (Kulla & Conty 2017) ------------------------------------------------------------
    def _ms_table(self):
        from .multiscatter import albedo_table

        ndf, ax, ay = self._micro_args()
        shape = float(self.ndf_shape) if isinstance(self.ndf_shape, (int, float, np.number)) else self.ndf_shape
        return albedo_table(ndf, float(np.sqrt(ax * ay)), self.micro.shadowing, shape)

    def _F_ms(self, lam):
        from .fresnel_terms import F_mean
        from .multiscatter import F_ms

        return float(F_ms(float(F_mean(self._F(lam))), self._ms_table().E_avg))

    def _f_ms(self, wi, wo, lam):
        if not self.multiple_scattering:
            return np.zeros(wi.shape[0])
        from .multiscatter import f_ms

        return f_ms(wi[:, 2], wo[:, 2], self._ms_table()) * self._F_ms(lam)

    # -- protocol ------------------------------------------------------------------------------------------
    def _eval1(self, wi, wo, lam):
        F_fn = self._F(lam)
        return self._f_specular(wi, wo, F_fn) + self._f_diffuse(wi, wo, F_fn) + self._f_ms(wi, wo, lam)

    def _p_cosine(self, wi, lam):
        """Probability of cosine sampling: the diffuse term and the multiple-scattering lobe, against F(θ_i) for the
        specular lobe."""
        if not self.multiple_scattering:
            return self._p_diffuse(wi, lam)
        Fi = self._F(lam)(np.clip(wi[:, 2], 0.0, 1.0))
        d = self.kd * (1.0 - Fi) if self._has_diffuse() else np.zeros(wi.shape[0])
        m = (1.0 - self._ms_table()(wi[:, 2])) * self._F_ms(lam)
        return (d + m) / np.maximum(Fi + d + m, 1e-300)

    def _pdf1(self, wi, wo, lam):
        pc = self._p_cosine(wi, lam)
        return (1.0 - pc) * self._pdf_specular(wi, wo) + pc * pdf_cosine(wo)

    def _sample1(self, wi, u, lam):
        pc = self._p_cosine(wi, lam)
        idx, u[:, 0] = lobe_choice(u[:, 0], [1.0 - pc, pc])
        return np.where((idx == 1)[:, None], sample_cosine(u), self._sample_specular(wi, u))

    def _albedo_parts(self, lam):
        _, ax, ay = self._micro_args()
        return [(lambda a, b: self._eval1(a.reshape(-1, 3), b.reshape(-1, 3), lam).reshape(b.shape[:-1]), ax, ay)]


@dataclass(frozen=True)
class TwoScaleParts(MicrofacetBRDF):
    """What every two-scale BRDF function shares (docs/physics.md §7): the coherent part A(θ_d) f_mf and the
    diffuse substrate in closed form, the optional multiple-scattering lobe of the micro NDF, the split of
    :meth:`eval_parts`, and sampling as a mixture of the coherent, diffracted and cosine lobes in proportion
    F(θ_i)A(θ_i) : F(θ_i)(1 − A(θ_i)) : kd(1 − F(θ_i)) + (1 − E(μ_i)) F_ms.

    Subclasses supply the diffracted part: ``_f_diffraction(wi, wo, lam)``, ``_pdf_diffraction``,
    ``_sample_diffraction(wi, u, lam)`` (invalid samples below the surface) and ``_diffraction_width(lam)``
    (slope-like width placing the albedo quadrature's nodes).
    """

    nano: object = None          # waveoptics.brdf.Nano or None
    diffraction: str = "kirchhoff"

    # Multiple scattering (``multiple_scattering=True``): the Kulla-Conty lobe of the micro NDF, unchanged. The
    # single-scattering two-scale lobe (coherent + diffracted) reflects the light of the single-scattering
    # microfacet lobe, only redistributed in direction by the nano-roughness (its white furnace follows the
    # microfacet albedo: tests/test_twoscale.py), so the light lost to multiple bounces between micro facets is
    # the same 1 − E(μ_i); the compensation lobe is already direction-averaged (diffuse-like), so diffraction does
    # not reshape it. The white furnace this gives is measured in tests/test_multiscatter.py.

    @property
    def lobe_material(self) -> Material:
        """The material whose reflectance the nano lobe carries, as a grid evaluation takes it
        (:func:`waveoptics.brdf.evaluate`): the surface's own with ``fresnel="exact"``; with ``fresnel="one"`` the
        reflector of F = 1 (``"f0:1"``: F = 1 at every angle, a conductor's coherent fraction 1 − E, the scalar
        Q = 1 first-order lobe), which the coherent part (:meth:`_A`) and the pointwise form's facets take as
        material None. A tabulated form built with the surface's material under ``fresnel="one"`` held the metal's
        lobes (its F(θ) < 1, its vector first-order factor) beside a coherent part of F = 1: its white furnace (Al,
        ABC σ 20 nm, B 2 µm, C 2.6, 550 nm, Beckmann α 0.3) was 0.991 at normal incidence and 1.010 at 89.5°
        where the microfacet albedo is 1.000 and 0.994 (GGX α 0.05: 0.932 at 85° against 0.903); now within
        2.2e-3 of it (tests/test_tabulated_white_furnace.py)."""
        return self.material if self.fresnel == "exact" else get_material("f0:1")

    @property
    def _rough(self) -> bool:
        return self.nano is not None and self.nano.sigma > 0

    def _A(self, cos_d, lam):
        """Coherent fraction A(θ_d) of each facet (1 without nano-roughness)."""
        if not self._rough:
            return np.ones_like(np.asarray(cos_d, dtype=float))
        # the lobe's light is weighted by the Fresnel factor this BRDF applies (none with fresnel="one")
        return self.nano.coherent_fraction(cos_d, lam, self.diffraction,
                                             self.material if self.fresnel == "exact" else None)

    def _share(self, cos_d, lam):
        """The light a facet at local incidence θ_d scatters, up to a common factor (:meth:`waveoptics.brdf.Nano.
        scattered_share`): 1 − A on a conductor, the lobe's own albedo on a dielectric."""
        return self.nano.scattered_share(cos_d, lam, self.diffraction,
                                         self.material if self.fresnel == "exact" else None)

    def _smooth_parts(self, wi, wo, lam, geometry=None):
        """(coherent, diffuse) in 1/sr for flat arrays at one wavelength (*geometry*: the pairs'
        :meth:`_specular_geometry` when already known)."""
        F_fn = self._F(lam)
        h = wi + wo
        h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
        cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
        return self._f_specular(wi, wo, F_fn, geometry) * self._A(cos_d, lam), self._f_diffuse(wi, wo, F_fn)

    def _parts(self, wi, wo, lam):
        coherent, diffuse = self._smooth_parts(wi, wo, lam)
        diffraction = self._f_diffraction(wi, wo, lam) if self._rough else np.zeros(wi.shape[0])
        return coherent, diffraction, diffuse, self._f_ms(wi, wo, lam)

    def eval_parts(self, wi, wo, wavelength_nm) -> dict:
        """The parts of :meth:`eval` separately: ``coherent``, ``diffraction``, ``diffuse`` and ``multiple`` (the
        multiple-scattering lobe; 0 unless ``multiple_scattering``), in 1/sr."""
        wi, wo, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        out = {k: np.zeros(lam.size) for k in ("coherent", "diffraction", "diffuse", "multiple")}
        for val in np.unique(lam):
            sel = lam == val
            for key, v in zip(out, self._parts(wi[sel], wo[sel], float(val))):
                out[key][sel] = v
        return {key: v.reshape(shape) for key, v in out.items()}

    def _eval1(self, wi, wo, lam):
        return sum(self._parts(wi, wo, lam))

    def _f_diffraction_nodes(self, wi, wo, wavelengths_nm) -> np.ndarray:
        """The diffracted part (n, n_λ) at every wavelength of *wavelengths_nm* (a tabulated model reads them all
        at once)."""
        return np.stack([self._f_diffraction(wi, wo, lam) for lam in wavelengths_nm], axis=-1)

    def _eval_nodes(self, wi, wo, wavelengths_nm) -> np.ndarray:
        """:meth:`_eval1` at every wavelength of *wavelengths_nm* (n, n_λ), the diffracted part of all of them in
        one :meth:`_f_diffraction_nodes` and the microfacet geometry once (the same sums as :meth:`_parts`)."""
        diffraction = self._f_diffraction_nodes(wi, wo, wavelengths_nm) if self._rough else None
        geometry = self._specular_geometry(wi, wo)
        out = []
        for i, lam in enumerate(wavelengths_nm):
            coherent, diffuse = self._smooth_parts(wi, wo, lam, geometry)
            d = diffraction[:, i] if diffraction is not None else np.zeros(wi.shape[0])
            out.append(sum((coherent, d, diffuse, self._f_ms(wi, wo, lam))))
        return np.stack(out, axis=-1)

    def _probs(self, wi, lam):
        """Lobe probabilities (coherent, diffracted, cosine) for each ω_i: the cosine lobe serves the diffuse term
        and the multiple-scattering lobe, in proportion kd (1 − F(θ_i)) + (1 − E(μ_i)) F_ms."""
        Fi = self._F(lam)(np.clip(wi[:, 2], 0.0, 1.0))
        A = self._A(np.clip(wi[:, 2], 0.0, 1.0), lam) * np.ones(wi.shape[0])
        d = self.kd * (1.0 - Fi) if self._has_diffuse() else np.zeros(wi.shape[0])
        if self.multiple_scattering:
            d = d + (1.0 - self._ms_table()(wi[:, 2])) * self._F_ms(lam)
        total = np.maximum(Fi + d, 1e-300)
        return Fi * A / total, Fi * (1.0 - A) / total, d / total

    def _pdf1(self, wi, wo, lam):
        pc, pn, pd = self._probs(wi, lam)
        out = pc * self._pdf_specular(wi, wo) + pd * pdf_cosine(wo)
        if self._rough:
            out = out + pn * self._pdf_diffraction(wi, wo, lam)
        return out

    def _sample1(self, wi, u, lam):
        pc, pn, pd = self._probs(wi, lam)
        idx, u[:, 0] = lobe_choice(u[:, 0], [pc, pn, pd])
        wo = np.where((idx == 2)[:, None], sample_cosine(u), self._sample_specular(wi, u))
        sel = idx == 1
        if self._rough and np.any(sel):
            wo[sel] = self._sample_diffraction(wi[sel], u[sel], lam)
        return wo

    def _albedo_parts(self, lam):
        _, ax, ay = self._micro_args()

        def smooth(x, y):
            a, b = x.reshape(-1, 3), y.reshape(-1, 3)
            c, d = self._smooth_parts(a, b, lam)
            return (c + d + self._f_ms(a, b, lam)).reshape(y.shape[:-1])

        parts = [(smooth, ax, ay)]
        if self._rough:
            wn = self._diffraction_width(lam)   # the nano lobe widens the micro lobe in every direction
            parts.append((lambda x, y: self._f_diffraction(x.reshape(-1, 3), y.reshape(-1, 3), lam)
                          .reshape(y.shape[:-1]), float(np.hypot(ax, wn)), float(np.hypot(ay, wn))))
        return parts

