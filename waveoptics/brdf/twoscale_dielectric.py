"""Two-scale rough glass: micro facets of a rough dielectric, each carrying the nano-roughness of
:class:`waveoptics.brdf.NanoRoughDielectricBSDF` in its own frame, in reflection and transmission over the sphere.

The interface separates air (z > 0) from a dielectric of real index η (z < 0). Each facet of normal m (NDF D, slope
scale α) is a flat nano-rough interface: it reflects and refracts a coherent part and scatters the rest into both
half-spaces by first-order perturbation (Rayleigh-Rice, :func:`waveoptics.scatter.rr_bsdf`). Walter et al.'s
integral of a BSDF carried by every facet (2007, eq. 14) then gives

    f(ω_i, ω_o) = f_c(ω_i, ω_o) + f_d(ω_i, ω_o),

* coherent part: the microfacet BSDF of :class:`waveoptics.brdf.RoughDielectricBSDF` (Walter eqs. 20 and 21, the
  refraction Jacobian η_o² |i·h||o·h| / (η_i (i·h) + η_o (o·h))² in transmission) whose Fresnel factors F and 1 − F
  are reduced by the coherent shares A_R(|i·h|), A_T(|i·h|) of the facet at its own incidence (A_T read at the
  air side's cosine of the Snell pair, :func:`coherent_transmission_share`; the second-order
  mean field of :func:`waveoptics.brdf.coherent_split`, tabulated by :func:`waveoptics.brdf.nano_tables`; for
  small slopes of the nano-roughness they are the Debye-Waller reduction of the specular light, refined so that
  the specular loss equals the first-order scatter into both half-spaces);
* diffracted part: the nano lobe f_n of each facet at the facet's local directions,

      f_d(ω_i, ω_o) = ∫ |ω_i·m| |ω_o·m| / (|ω_i·n| |ω_o·n|) f_n(ω_i^m, ω_o^m) G(ω_i, ω_o, m) D(m) dω_m,

  over facets that each direction sees from its own side ((ω·m) ω_z > 0), G Smith's masking-shadowing of either
  side (:func:`waveoptics.brdf.btdf.sided_G2`, the Beta-function form in transmission when height-correlated). The
  integral is the fixed quadrature of :class:`waveoptics.brdf.TwoScaleBRDF` (:func:`waveoptics.brdf.facet.
  quadrature_normals`): the balance heuristic of N/2 normals with density D(m) cos θ_m and N/2 antithetic normals
  about the half-vector h through the nano lobe's radial law, where h is the half-vector of reflection or the
  generalized half-vector of refraction (Walter eq. 16), and a tilt s from h moves the facet's grating vector by
  q = k |η_i ω_i + η_o ω_o| s (2k cos θ_d s in reflection). The nodes depend on h and |η_i ω_i + η_o ω_o| only,
  so the sum is the same for ω_i and ω_o swapped, and reciprocity with the η² factor of radiance,
  f(i, o)/η_o² = f(o, i)/η_i², holds to rounding for the diffracted part (f_n obeys it) and for the coherent
  transmission (A_T T is reciprocal, and A_T is read at the pair's air-side cosine; Veach 1997, §5.2).

The α → 0 limit is :class:`waveoptics.brdf.NanoRoughDielectricBSDF` (its coherent factors at μ_i and its nano
lobe about the macro normal). Energy: each facet conserves A_R F + A_T (1 − F) + TIS_R + TIS_T = 1 (lossless), so a
white furnace over the sphere gives the flat case's R + T up to the energy single scattering loses on the micro
surface (Smith's G; as :class:`RoughDielectricBSDF` without its compensation). ``multiple_scattering=True`` adds
the micro surface's multiple scattering: the compensation lobes of :class:`RoughDielectricBSDF` (Kulla & Conty
2017; :func:`waveoptics.brdf.btdf.dielectric_tables` of the facets without nano-roughness), which return the
energy 1 − E(μ_i) that single scattering between smooth facets loses; the nano lobes ride on single scattering.
Since each facet conserves energy, the two-scale surface's single-scattering loss is that of the smooth facets up
to the nano light's own (different) shadowing, a few % of the light times the difference in Smith's loss: R + T
over the sphere = 1 within 3.3e-4 up to α = 1 from air (tests/test_twoscale_dielectric.py); from the glass at
30-50° the lobes return the facets' loss within 2.9e-5 and R + T is off by the nano part's −1.7e-3 to +3.7e-4
(α 0.3, 1; 64 facet nodes; tests/test_btdf_tables.py). The lobes are sampled with
probability (1 − TIS_R − TIS_T)(1 − E(μ_i)) (a cosine-weighted direction on either side, as the base class).

Sampling: the coherent lobes (Walter §5.3, :class:`RoughDielectricBSDF`'s sampler) with probability
1 − TIS_R(μ_i) − TIS_T(μ_i), else the nano lobe on the reflection (TIS_R) or transmission (TIS_T) side: one of N/2
facet normals m_k drawn by the micro NDF's sampler for ω_i at fixed Sobol points
(:func:`waveoptics.brdf.facet.sampler_normals`), then a cosine-weighted direction about m_k on the chosen side of
that facet; a direction that leaves on the wrong side of the macro surface is an invalid sample (weight 0). The
density p(ω_o) = TIS_side (2/N) Σ_k |ω_o·m_k| / π over the facets that see ω_o on the chosen side is exact.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, eqs. (14), (16), (20), (21), (23) and §5.3.
.. [2] N. Holzschuch, R. Pacanowski, "A Two-Scale Microfacet Reflectance Model Combining Reflection and
   Diffraction", ACM TOG 36(4), 66, 2017 (facets carrying the nano-roughness).
.. [3] J. M. Elson, Phys. Rev. B 30(10), 5460–5480, 1984; J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012,
   ch. 4–5 (first-order scatter into both half-spaces).
.. [4] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014, §6.
.. [5] E. Veach, PhD thesis, Stanford, 1997, §5.2 (the η² factor of radiance) and §9.2 (balance heuristic).
.. [6] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course, the
   dielectric energy compensation.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError, unknown
from .btdf import RoughDielectricBSDF, albedo_multiple, albedo_single, half_vector_refraction
from .shadowing import sided_G2, sided_lambda
from .directions import dot_last
from .facet import (NanoRadial, facet_basis, local_pair, quadrature_density, quadrature_normals, sampler_normals)
from .nano_dielectric import NanoRoughDielectricBSDF
from .protocol import broadcast_incidence, lobe_choice
from .smith import gl01

__all__ = ["TWOSCALE_DIELECTRIC_NODES", "ALBEDO_MU_NODES", "ALBEDO_PHI_NODES", "pair_half_vector",
           "coherent_transmission_share", "TwoScaleDielectricBSDF", "NANO_FRAME_BSDFS", "nano_rough_glass"]

#: quadrature points over facet normals of the diffracted part (a power of two: an unscrambled Sobol set)
TWOSCALE_DIELECTRIC_NODES = 256
#: Gauss-Legendre nodes in |cos θ_o| per hemisphere of the diffracted part's albedo
ALBEDO_MU_NODES = 32
#: midpoint nodes in φ_o of the diffracted part's albedo
ALBEDO_PHI_NODES = 64
#: direction pairs per block of the facet quadrature (memory: pairs × nodes)
_CHUNK_NODES = 2 ** 19


def pair_half_vector(wi, wo, eta):
    """The half-vector of each direction pair (n, 3) turned to z > 0 and half the length of the wave-vector sum it
    is the direction of: sign(i_z)(ω_i + ω_o) and |ω_i + ω_o| / 2 = cos θ_d in reflection; the generalized
    half-vector −(η_i ω_i + η_o ω_o) and |η_i ω_i + η_o ω_o| / 2 in transmission (η_i, η_o the indices of the
    directions' media, air above and *eta* below). Returns (h (n, 3), half-length (n,), transmission? (n,)).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eqs. (13) and (16).
    """
    eta_i = np.where(wi[:, 2] > 0, 1.0, eta)
    eta_o = np.where(wo[:, 2] > 0, 1.0, eta)
    trans = wi[:, 2] * wo[:, 2] < 0
    v = np.where(trans[:, None], eta_i[:, None] * wi + eta_o[:, None] * wo, wi + wo)
    half = 0.5 * np.linalg.norm(v, axis=-1)
    hr = v * np.where(wi[:, 2] < 0, -1.0, 1.0)[:, None] / np.maximum(2.0 * half, 1e-300)[:, None]
    h = np.where(trans[:, None], half_vector_refraction(wi, wo, eta_i, eta_o), hr)
    return h, half, trans


def coherent_transmission_share(tab, mu, up, eta):
    """A_T of a facet at incidence cosine *mu* on the side *up* (boolean; air above, index *eta* below): the
    table of light from air (:func:`waveoptics.brdf.nano_tables`) at the air side's cosine of the Snell pair,
    √(1 − η² (1 − μ²)) for light from the glass. The coherent transmittance is the same for both directions of
    the pair (reciprocity; :mod:`waveoptics.brdf.nano_dielectric`), so the share is reciprocal to rounding (the
    two sides' tables agree to their interpolation error, ≤ 1e-4). Dimensionless.

    References
    ----------
    .. [1] E. Veach, PhD thesis, 1997, §5.2; M. Born, E. Wolf, *Principles of Optics*, §1.5 (Snell's law).
    """
    mu = np.asarray(mu, dtype=float)
    mu_air = np.where(up, mu, np.sqrt(np.maximum(1.0 - eta * eta * (1.0 - mu * mu), 0.0)))
    return tab.at("A_T", mu_air, True)


@functools.lru_cache(maxsize=64)
def _radial(psd, lam: float, n: int) -> NanoRadial:
    """The nano lobe's radial law (a proposal of the quadrature: the PSD's shape about the facet's mirror)."""
    return NanoRadial(psd, lam, "rayleigh-rice", n)


@dataclass(frozen=True)
class TwoScaleDielectricBSDF(NanoRoughDielectricBSDF):
    """Two-scale rough glass (module doc): micro facets (``micro``: NDF, α, ``smith`` or ``smith-correlated``)
    of a dielectric ``material``, each carrying the nano-roughness ``psd`` (:class:`~waveoptics.surfaces.PSDModel`,
    m⁴) in its own frame; reflection and transmission over the whole sphere with ``eval`` / ``pdf`` / ``sample`` /
    ``albedo`` (as :class:`waveoptics.brdf.RoughDielectricBSDF`).

    ``eval_parts`` gives ``reflection`` and ``transmission`` (the coherent part), ``multiple`` (the compensation
    lobes, 0 unless ``multiple_scattering``) and ``nano``
    (the diffracted part), in 1/sr; ``albedo_parts`` their albedos (``nano_reflection``, ``nano_transmission``).

    Parameters
    ----------
    material, micro, psd
        As :class:`waveoptics.brdf.NanoRoughDielectricBSDF`.
    multiple_scattering : bool
        Add the micro surface's multiple scattering (Kulla-Conty lobes; module doc).
    nodes : int
        Quadrature points over facet normals per evaluation of the diffracted part (a power of two ≥ 16); the
        sampler draws from half as many normals.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007; N. Holzschuch, R. Pacanowski 2017 (module references).
    """

    nodes: int = TWOSCALE_DIELECTRIC_NODES

    def __post_init__(self):
        super().__post_init__()
        n = int(self.nodes)
        if n < 16 or n & (n - 1):
            raise FieldError(f"{{nodes}}={self.nodes!r} is not allowed; use a power of two >= 16", "nodes")

    # -- coherent part: the microfacet BSDF with each facet's coherent share --------------------------------------
    def _parts1(self, wi, wo, lam):
        fr, ft, mr, mt = RoughDielectricBSDF._parts1(self, wi, wo, lam)
        eta = self._eta(lam)
        h, _, _ = pair_half_vector(wi, wo, eta)
        tab = self._nano(lam)
        up, mu = wi[:, 2] > 0, np.abs(dot_last(wi, h))
        return fr * tab.at("A_R", mu, up), ft * coherent_transmission_share(tab, mu, up, eta), mr, mt

    # -- diffracted part: the facet-frame integral of the nano lobe ----------------------------------------------
    def _f_nano(self, wi, wo, lam):
        out = np.zeros(wi.shape[0])
        step = max(1, _CHUNK_NODES // self.nodes)
        for a in range(0, wi.shape[0], step):
            sl = slice(a, a + step)
            out[sl] = self._f_nano_chunk(wi[sl], wo[sl], lam)
        return out

    def _f_nano_chunk(self, wi, wo, lam):
        """Walter's integral over facet normals by the balance heuristic of two node sets (module doc), 1/sr."""
        eta = self._eta(lam)
        spec, ndf, ax, ay, c = self._args()
        ok_pair = (wi[:, 2] != 0) & (wo[:, 2] != 0)
        wi = np.where(ok_pair[:, None], wi, [0.0, 0.0, 1.0])
        wo = np.where(ok_pair[:, None], wo, [0.0, 0.0, 1.0])
        h, half, trans = pair_half_vector(wi, wo, eta)
        # guard: half = 0 only for a degenerate pair (ω_o = −ω_i in reflection, η_i ω_i = −η_o ω_o in transmission),
        # where the half-vector has no direction; the floor only keeps the node placement (cos θ_d level, offsets)
        # finite there, the nodes' density enters their weights, so no value is scaled by it
        half = np.maximum(half, 1e-6)
        rad = _radial(self.psd, float(lam), self.nodes // 2)
        level = rad.level(half)
        m, valid = quadrature_normals(h, half, rad, level, self.nodes // 2, ndf=ndf, ax=ax, ay=ay, c=c)
        D = spec.D(m, ax, ay, c)
        den = quadrature_density(m, D, h, half, rad, level, self.nodes // 2)
        im = dot_last(wi[:, None, :], m)
        om = dot_last(wo[:, None, :], m)
        ok = valid & (im * wi[:, 2:3] > 0) & (om * wo[:, 2:3] > 0) & (den > 0)
        li, lo = local_pair(im, om, dot_last(wi, wo)[:, None])
        fn = self._nano_interface(lam).bsdf(li, lo, lam, self.psd)
        G = sided_G2(sided_lambda(spec, wi, ax, ay, c)[:, None], sided_lambda(spec, wo, ax, ay, c)[:, None],
                     trans[:, None], self.micro.shadowing)
        val = np.abs(im * om) * fn * G * D / np.where(ok, den, 1.0)
        out = np.sum(np.where(ok, val, 0.0), axis=1) / np.abs(wi[:, 2] * wo[:, 2])
        return np.where(ok_pair, out, 0.0)

    # -- sampling ------------------------------------------------------------------------------------------------
    def _facet_normals(self, wi):
        """The sampler's facet normals (n, N/2, 3) for ω_i on either side (the NDF seen from ω_i's side)."""
        _, ndf, ax, ay, c = self._args()
        up = np.where(wi[:, 2:3] < 0, -wi, wi)
        return sampler_normals(up, self.nodes // 2, ndf=ndf, ax=ax, ay=ay, c=c)

    def _pdf_nano(self, wi, wo, lam):
        """Density (1/sr) of the nano sampler (module doc), its lobe probabilities included."""
        p_r, p_t = self._p_nano(wi, lam)
        m = self._facet_normals(wi)
        s = np.sign(wi[:, 2])[:, None]
        im = dot_last(wi[:, None, :], m)
        om = dot_last(wo[:, None, :], m)
        same = (wo[:, 2] * wi[:, 2] > 0)[:, None]
        side = np.where(same, om * s > 0, om * s < 0)
        mean = np.mean(np.where((im * s > 0) & side, np.abs(om) / np.pi, 0.0), axis=1)
        return np.where(wo[:, 2] != 0, np.where(same[:, 0], p_r, p_t) * mean, 0.0)

    def _pdf1(self, wi, wo, lam):
        p_r, p_t = self._p_nano(wi, lam)
        return (1.0 - p_r - p_t) * RoughDielectricBSDF._pdf1(self, wi, wo, lam) + self._pdf_nano(wi, wo, lam)

    def _sample_nano(self, wi, u, reflect):
        """ω_o of the nano sampler for lobe *reflect* (boolean: the reflection side of the chosen facet); invalid
        samples are 0."""
        n = self.nodes // 2
        k = np.minimum((u[:, 0] * n).astype(int), n - 1)
        u0 = np.clip(u[:, 0] * n - k, 0.0, np.nextafter(1.0, 0.0))
        m = self._facet_normals(wi)[np.arange(k.size), k]
        s = np.sign(wi[:, 2]) * np.where(reflect, 1.0, -1.0)      # the side of the facet the light leaves on
        r = np.sqrt(u0)
        phi = 2.0 * np.pi * u[:, 1]
        t, b = facet_basis(m)
        z = s * np.sqrt(np.maximum(1.0 - u0, 0.0))
        wo = (r * np.cos(phi))[:, None] * t + (r * np.sin(phi))[:, None] * b + z[:, None] * m
        valid = (dot_last(wi, m) * wi[:, 2] > 0) & (wo[:, 2] * s > 0)
        return np.where(valid[:, None], wo, 0.0)

    def _sample1(self, wi, u, lam):
        p_r, p_t = self._p_nano(wi, lam)
        idx, u[:, 0] = lobe_choice(u[:, 0], [1.0 - p_r - p_t, p_r, p_t])
        wo = RoughDielectricBSDF._sample1(self, wi, u.copy(), lam)
        nano = idx > 0
        if np.any(nano):
            wo[nano] = self._sample_nano(wi[nano], u[nano], idx[nano] == 1)
        return wo

    # -- albedo --------------------------------------------------------------------------------------------------
    def _albedo_nano(self, w1, lam):
        """(R, T) of the diffracted part at one ω_i: Gauss-Legendre in |cos θ_o| (:data:`ALBEDO_MU_NODES`) and the
        midpoint rule in φ_o (:data:`ALBEDO_PHI_NODES`) on each hemisphere."""
        x, wx = gl01(ALBEDO_MU_NODES)
        phi = (np.arange(ALBEDO_PHI_NODES) + 0.5) * 2.0 * np.pi / ALBEDO_PHI_NODES
        st = np.sqrt(1.0 - x * x)
        out = {}
        for sgn in (1.0, -1.0):
            wo = np.stack([np.outer(st, np.cos(phi)), np.outer(st, np.sin(phi)),
                           np.outer(sgn * x, np.ones_like(phi))], axis=-1).reshape(-1, 3)
            f = self._f_nano(np.broadcast_to(w1, wo.shape), wo, lam).reshape(x.size, phi.size)
            out[sgn * w1[2] > 0] = float(np.sum(wx[:, None] * x[:, None] * f) * 2.0 * np.pi / phi.size)
        return out[True], out[False]

    def albedo_parts(self, wi, wavelength_nm) -> dict:
        """∫ f |cos θ_o| dω_o of each part (dimensionless): ``reflection`` and ``transmission`` of the coherent part
        by quadrature over facet normals (:func:`waveoptics.brdf.btdf.albedo_single` with each facet's coherent
        shares), ``nano_reflection`` and ``nano_transmission`` by quadrature of the diffracted part over each
        hemisphere; ``multiple_reflection``, ``multiple_transmission`` of the compensation lobes
        (:func:`waveoptics.brdf.btdf.albedo_multiple`; 0 unless ``multiple_scattering``)."""
        wi_f, lam_f, shape = broadcast_incidence(wi, wavelength_nm)
        keys = ("reflection", "transmission", "multiple_reflection", "multiple_transmission", "nano_reflection",
                "nano_transmission")
        out = {k: np.zeros(lam_f.size) for k in keys}
        spec, ndf, ax, ay, c = self._args()
        for j, (w1, l1) in enumerate(zip(wi_f, lam_f)):
            if w1[2] == 0:
                continue
            lam = float(l1)
            tab, eta = self._nano(lam), self._eta(lam)
            R, T = albedo_single(w1[None], eta, spec, ndf, ax, ay, c, self.micro.shadowing,
                                 facet_factors=lambda mu, up: (tab.at("A_R", mu, up),
                                                               coherent_transmission_share(tab, mu, up, eta)))
            out["reflection"][j], out["transmission"][j] = R[0], T[0]
            out["nano_reflection"][j], out["nano_transmission"][j] = self._albedo_nano(w1, lam)
            if self.multiple_scattering:
                out["multiple_reflection"][j], out["multiple_transmission"][j] = albedo_multiple(
                    w1, self._tables(lam))
        return {k: v.reshape(shape) for k, v in out.items()}


#: the nano-rough glass by the frame of its nano lobes (:data:`waveoptics.vocabulary.NANO_FRAMES`)
NANO_FRAME_BSDFS = {"macro": NanoRoughDielectricBSDF, "facet": TwoScaleDielectricBSDF}


def nano_rough_glass(material, micro, psd, multiple_scattering: bool = False, nano_frame: str = "macro"):
    """The nano-rough glass of *material* (a dielectric), *micro* (NDF, α, shadowing) and nano-roughness *psd*
    (:class:`~waveoptics.surfaces.PSDModel`, m⁴) with its nano lobes in the frame *nano_frame*
    (:data:`NANO_FRAME_BSDFS`: ``macro`` about the macro normal, ``facet`` in each micro facet's frame).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007; N. Holzschuch, R. Pacanowski 2017 (module references).
    """
    if nano_frame not in NANO_FRAME_BSDFS:
        raise unknown("frame of the nano lobes", nano_frame, NANO_FRAME_BSDFS, field="nano_frame")
    return NANO_FRAME_BSDFS[nano_frame](material, micro, multiple_scattering=multiple_scattering, psd=psd)
