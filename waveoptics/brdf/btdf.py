"""Rough dielectric interface: the microfacet BSDF of reflection and refraction over the whole sphere (Walter et al.
2007), with Kulla & Conty's (2017) energy compensation for dielectrics.

The interface separates air (index 1, z > 0) from a dielectric of real index η (z < 0). For ω_i (towards the light)
and ω_o (towards the viewer), η_i and η_o are the indices of the media they lie in, and η_t the index across the
interface from ω_i (the relative index of the Fresnel factor is η_t/η_i: η from outside, 1/η from inside).

* Reflection (ω_i, ω_o on one side), h_r = sign(i_z)(ω_i + ω_o)/|ω_i + ω_o| (Walter eq. 13):
  f_r = F(|i·h|) G(i, o, h) D(h) / (4 |i_z| |o_z|) (eq. 20).
* Transmission (opposite sides), the generalized half vector h_t = −(η_i ω_i + η_o ω_o)/|η_i ω_i + η_o ω_o|
  turned to z > 0 (eq. 16):
  f_t = |i·h| |o·h| / (|i_z| |o_z|) · η_o² (1 − F(|i·h|)) G(i, o, h) D(h) / (η_i (i·h) + η_o (o·h))² (eq. 21).

Both vanish unless (i·h) i_z > 0 and (o·h) o_z > 0 (each direction on the side of the facet it sees). f_t is the
BSDF of radiance: it carries the factor η_o² of the change of radiance across the interface, so its reciprocity
rule is f_t(i, o)/η_o² = f_t(o, i)/η_i² (Veach 1997, §5.2), and the energy albedo ∫ f |cos θ_o| dω_o of the
smooth limit is R = F(θ_i) + T = 1 − F(θ_i).

F is the exact unpolarized Fresnel reflectance of a dielectric (:func:`waveoptics.materials.fresnel.F`; total
internal reflection from inside gives F = 1), and 1 − F its transmittance; a thin-film stack on the glass puts the
stack's R and T in their place (:mod:`waveoptics.brdf.facet_interface`; multiple scattering if it is lossless).
D is any NDF of :data:`waveoptics.brdf.NDFS`; G is Smith's with the NDF's Λ (a direction below the surface sees
the microsurface upside down: Λ(ω) is Λ(−ω)), either separable,
G1(i) G1(o) (``smith``, Walter eq. 23), or height-correlated (``smith-correlated``, Heitz 2014 §6.2):
1/(1 + Λ(i) + Λ(o)) in reflection and the Beta function B(1 + Λ(i), 1 + Λ(o)) in transmission (the light must
be unmasked above the facet's height and unshadowed below it).

Sampling (Walter §5.3): a normal m is drawn from the NDF's sampler (:mod:`waveoptics.brdf.sampling`: visible
normals for GGX, D cos θ_m otherwise) for the direction turned above the surface, then reflection with probability
F(|i·m|) and refraction otherwise (R/(R + T) of a coated facet, whose absorbing films make R + T < 1). The
densities over ω_o are p(m) F / (4 |i·h|) and p(m) (1 − F) η_o² |o·h| / (η_i (i·h) + η_o (o·h))² (the Jacobians
of eqs. 14 and 17). The choice between
reflection and refraction takes a third uniform number from the low digits of u₁ (the protocol passes two).
Samples that leave on the wrong side of the macro surface are invalid (weight 0, ``wo`` = 0), so ∫ pdf dω_o is
the fraction of valid samples (1 for a mirror, below 1 as α grows).

Multiple scattering (``multiple_scattering=True``, Kulla & Conty 2017, dielectric part): the single-scattering
albedo E↑(μ) (light from outside) and E↓(μ) (from inside, total internal reflection included) are tabulated with
F exact, and the energy 1 − E(μ_i) returns through diffuse-like lobes on both sides,

    f_ms(i, o) = c_io (1 − E_i(μ_i)) (1 − E_o(μ_o)) / (π (1 − Ē_o)),

with E_i, E_o the tables of the sides of ω_i, ω_o. The share c that leaves through the interface is
(1 − F̄↑) x from outside and (1 − F̄↓)(1 − x) from inside (F̄ = 2 ∫ F μ dμ of each side), the rest is reflected;
x/(1 − x) = η² (1 − F̄↓)(1 − Ē↓) / ((1 − F̄↑)(1 − Ē↑)) makes the transmitted lobes obey the η² reciprocity rule
above. The albedo is then E(μ_i) + (1 − E(μ_i)) = 1 from either side; the lobes' shape is an approximation of
the true multiple scattering (Heitz et al. 2016), their energy exact up to the tables' error.

The tables (:func:`dielectric_tables`): E↓ has the √ kink of total internal reflection at the critical cosine μ_c =
√(1 − 1/η²) as α → 0 (a steep shoulder of width ~α), and a weaker one at μ = 1/η, where the facets' critical circle
touches their horizon (:func:`waveoptics.brdf.albedo_cuts`), so it is tabulated on the three pieces between them
(:func:`waveoptics.brdf.split_pieces`), each a cubic spline in a variable that crowds the nodes towards the cuts;
its albedos from the glass integrate over facet normals about ω_i, split at the facets' critical angle
(:func:`waveoptics.brdf.incidence_normal_quadrature`, α ≥ 0.2), and Ē is the mean of the tables as read back, so
that the lobes return exactly 1 − E(μ_i). Against a direct integral of Walter's closed forms
(tests/test_btdf_tables.py) the tables are within 1.0e-4 at α = 0.3 and 1 (20-75° in the glass, 0-75° from air) and
the white furnace from the glass at 30-50° within 2.8e-5 (linear on 32 Gauss-Legendre nodes over [0, 1]: up to
2.3e-3 and 9.2e-4). Below α = 0.2 the albedos are integrated over slopes about the macro normal: within 5e-4 of a
direct integral near the critical angle (α 0.05-0.15, 41-48°; ≤ 1e-4 elsewhere). A table costs 0.5-0.7 s of CPU
(ggx, beckmann; 0.2-0.4 s as linear tables), once per (NDF, α, η).

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, eqs. (13)-(23) and §5.3.
.. [2] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014, §6.
.. [3] E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018.
.. [4] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course (Physically
   Based Shading in Theory and Practice), the dielectric energy compensation.
.. [5] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §5.2
   (non-symmetric scattering by refraction: the η² factor of radiance).
.. [6] E. Heitz, J. Hanika, E. d'Eon, C. Dachsbacher, "Multiple-scattering microfacet BSDFs with the Smith
   model", ACM TOG 35(4), 2016.
.. [7] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.2 (Fresnel formulae, total internal reflection).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import FieldError, unknown
from ..materials import Material, get_material
from .directions import dot_last, reflect
from .facet_interface import as_interface, facet_interface_of
from .fresnel_terms import F_mean
from .ndf import COS_MIN, check_alpha, ndf_by_name
from .protocol import SphereBSDF, broadcast_incidence, broadcast_pair, lobe_choice
from .mu_pieces import albedo_cuts, piece_cosine, read_pieces, split_pieces
from .incidence_quadrature import INCIDENCE_ALPHA_MIN, incidence_normal_quadrature
from .quadrature import normal_quadrature
from .sampling import pdf_normal, sample_normal
from .shadowing import sided_G2, sided_lambda
from .smith import gl01
from .twoscale import Micro

__all__ = ['DIELECTRIC_SHADOWINGS', 'DIELECTRIC_MS_NODES', 'UNIFORM_DIGITS', 'pack_third_uniform', 'refract',
           'half_vector_refraction', 'albedo_single', 'DielectricTables',
           'dielectric_tables', 'albedo_multiple', 'RoughDielectricBSDF']

#: masking-shadowing terms of the BSDF (the Smith forms, which have a transmission case)
DIELECTRIC_SHADOWINGS = ("smith", "smith-correlated")
#: Gauss-Legendre nodes in the variable t of each piece of μ of the albedo tables of the energy compensation
#: (one piece outside, three inside: :func:`waveoptics.brdf.albedo_cuts`)
DIELECTRIC_MS_NODES = 24
#: samples in t per piece of the tables' cubic splines (read back by linear interpolation)
DIELECTRIC_DENSE_SAMPLES = 257
#: Gauss-Legendre nodes in μ per piece of the tables' means Ē
DIELECTRIC_MEAN_NODES = 128
#: low digits of u₁ that give the third uniform number (reflection or refraction): u₁ resolves 2⁻²⁴ in the normal
UNIFORM_DIGITS = float(2 ** 24)


def pack_third_uniform(u1, u3):
    """u₁ rounded down to the grid 2⁻²⁴ (:data:`UNIFORM_DIGITS`) with the uniform number *u3* ∈ [0, 1) in its low
    digits, so that the samplers of this module, which read their third uniform number from those digits, draw it
    from *u3* (a renderer that has three independent numbers, e.g. Mitsuba's ``sample1``, passes it here). The
    result stays in [0, 1) and within 2⁻²⁴ of u₁; float64 keeps 28 bits of *u3* below the grid."""
    u1 = np.asarray(u1, dtype=float)
    # guard: u3 within 2⁻²⁸ of 1 would round the sum up to the next grid point (and u₁ = 1 − 2⁻²⁴ up to 1)
    u3 = np.clip(np.asarray(u3, dtype=float), 0.0, 1.0 - 2.0 ** -28)
    return (np.floor(u1 * UNIFORM_DIGITS) + u3) / UNIFORM_DIGITS


def refract(w, m, eta_rel):
    """Refracted direction of *w* (..., 3) through a facet of unit normal *m* on the side of *w* (w·m > 0), for
    the relative index η_t/η_i *eta_rel*: t = −w/η + (c/η − √(1 − (1 − c²)/η²)) m, c = w·m (Snell's law in vector
    form). Returns (t, ok); ok is False under total internal reflection (t is then 0).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (40).
    """
    c = dot_last(w, m)
    eta_rel = np.asarray(eta_rel, dtype=float)
    k = 1.0 - (1.0 - c * c) / (eta_rel * eta_rel)
    ok = k > 0
    t = -w / eta_rel[..., None] + (c / eta_rel - np.sqrt(np.where(ok, k, 0.0)))[..., None] * m
    return np.where(ok[..., None], t, 0.0), ok


def half_vector_refraction(wi, wo, eta_i, eta_o):
    """Generalized half vector of refraction −(η_i ω_i + η_o ω_o)/|η_i ω_i + η_o ω_o|, turned to z ≥ 0 (unitless).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (16).
    """
    v = -(np.asarray(eta_i, dtype=float)[..., None] * wi + np.asarray(eta_o, dtype=float)[..., None] * wo)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    h = v / np.where(n > 0, n, 1.0)
    return np.where(h[..., 2:3] < 0, -h, h)


def _sides(wi, wo, eta):
    """η_i, η_o, η_t (index across the interface from ω_i) of flat arrays: air (1) above, η below."""
    up_i = wi[:, 2] > 0
    eta_i = np.where(up_i, 1.0, eta)
    eta_o = np.where(wo[:, 2] > 0, 1.0, eta)
    return eta_i, eta_o, np.where(up_i, eta, 1.0)


def _pair_geometry(wi, wo, eta):
    """(η_i, η_o, η_t, reflection?, transmission?, h, ω_i·h, ω_o·h, valid?) of flat direction pairs (n, 3): the half
    vector of reflection, or the generalized half vector of refraction (Walter et al. 2007, eq. 16), turned to the
    +z side; pairs whose half vector puts either direction on the wrong side of its microfacet are not valid (their
    h is set to +z)."""
    zi, zo = wi[:, 2], wo[:, 2]
    eta_i, eta_o, eta_t = _sides(wi, wo, eta)
    refl = zi * zo > 0
    trans = zi * zo < 0
    hr = (wi + wo) * np.sign(zi)[:, None]
    hr = hr / np.maximum(np.linalg.norm(hr, axis=-1, keepdims=True), 1e-300)
    h = np.where(refl[:, None], hr, half_vector_refraction(wi, wo, eta_i, eta_o))
    ih, oh = dot_last(wi, h), dot_last(wo, h)
    ok = (refl | trans) & (ih * zi > 0) & (oh * zo > 0) & (h[:, 2] > 0)
    h = np.where(ok[:, None], h, np.array([0.0, 0.0, 1.0]))
    return eta_i, eta_o, eta_t, refl, trans, h, ih, oh, ok


def _single(wi, wo, iface, spec, ax, ay, c, shadowing):
    """Single-scattering (f_r, f_t) in 1/sr (module doc) of flat arrays (n, 3) through the facet interface *iface*
    (:mod:`waveoptics.brdf.facet_interface`: its R in place of F, its T in place of 1 − F)."""
    zi, zo = wi[:, 2], wo[:, 2]
    eta_i, eta_o, eta_t, refl, trans, h, ih, oh, ok = _pair_geometry(wi, wo, iface.eta)
    F, T = iface.RT(np.abs(ih), zi > 0)
    D = spec.D(h, ax, ay, c)
    G = sided_G2(sided_lambda(spec, wi, ax, ay, c), sided_lambda(spec, wo, ax, ay, c), trans, shadowing)
    # guard: cosines floored at COS_MIN in the denominators (G already vanishes at the horizon)
    cc = np.maximum(np.abs(zi), COS_MIN) * np.maximum(np.abs(zo), COS_MIN)
    fr = np.where(ok & refl, F * G * D / (4.0 * cc), 0.0)
    den = (eta_i * ih + eta_o * oh) ** 2
    ft = np.abs(ih * oh) / cc * eta_o ** 2 * T * G * D / np.where(den > 0, den, 1.0)
    return fr, np.where(ok & trans & (den > 0), ft, 0.0)


def _single_pdf(wi, wo, iface, ndf, ax, ay, c):
    """Density (1/sr over ω_o) of :func:`_sample_single`."""
    zi = wi[:, 2]
    eta_i, eta_o, eta_t, refl, trans, h, ih, oh, ok = _pair_geometry(wi, wo, iface.eta)
    up = np.where(zi[:, None] < 0, -wi, wi)
    pm = pdf_normal(up, h, ndf=ndf, ax=ax, ay=ay, c=c)
    F, T = _choice(*iface.RT(np.abs(ih), zi > 0))
    den = (eta_i * ih + eta_o * oh) ** 2
    jr = F / (4.0 * np.maximum(np.abs(ih), 1e-300))
    jt = T * eta_o ** 2 * np.abs(oh) / np.where(den > 0, den, 1.0)
    return np.where(ok, pm * np.where(refl, jr, np.where(den > 0, jt, 0.0)), 0.0)


def _choice(R, T):
    """Probabilities (R/(R + T), T/(R + T)) of reflection and refraction on a facet (Walter §5.3 samples by F; with
    absorbing films R + T < 1); (1, 0) where R + T = 0."""
    tot = R + T
    pos = tot > 0
    return np.where(pos, R / np.where(pos, tot, 1.0), 1.0), np.where(pos, T / np.where(pos, tot, 1.0), 0.0)


def _sample_single(wi, u, iface, ndf, ax, ay, c):
    """ω_o of the single-scattering lobes (module doc); invalid samples are 0."""
    zi = wi[:, 2]
    s = np.sign(zi)
    m = sample_normal(np.where(zi[:, None] < 0, -wi, wi), u, ndf=ndf, ax=ax, ay=ay, c=c)
    ih = dot_last(wi, m)
    eta_i = np.where(zi > 0, 1.0, iface.eta)
    eta_t = np.where(zi > 0, iface.eta, 1.0)
    F, _ = _choice(*iface.RT(np.abs(ih), zi > 0))
    uc = np.modf(u[:, 1] * UNIFORM_DIGITS)[0]
    wr = reflect(wi, m)
    wt, ok_t = refract(wi, s[:, None] * m, eta_t / eta_i)
    choose_r = uc < F
    wo = np.where(choose_r[:, None], wr, wt)
    valid = (ih * s > 0) & np.where(choose_r, wr[:, 2] * s > 0, ok_t & (wt[:, 2] * s < 0))
    return np.where(valid[:, None], wo, 0.0)


@dataclass(frozen=True)
class DielectricTables:
    """Single-scattering albedos (R + T, F exact) of a rough interface, ``E_up`` for light from outside and
    ``E_down`` from inside: on each side, per piece of μ (``pieces_up``: [0, 1]; ``pieces_down``: split at
    :func:`waveoptics.brdf.albedo_cuts`, where total internal reflection sets in on the facets), a cubic spline in
    the piece's variable t (:func:`waveoptics.brdf.piece_variable`) through :data:`DIELECTRIC_MS_NODES`
    Gauss-Legendre nodes, sampled at ``t`` (arrays (pieces, samples)); their averages Ē = 2 ∫ E μ dμ of the tables
    as read back, the mean Fresnel reflectances F̄ of each side, and the shares of the compensated energy that cross
    the interface, ``t_up`` = (1 − F̄↑) x and ``t_down`` = (1 − F̄↓)(1 − x) (module doc)."""

    pieces_up: tuple
    pieces_down: tuple
    t: np.ndarray
    E_up: np.ndarray
    E_down: np.ndarray
    Eavg_up: float
    Eavg_down: float
    Favg_up: float
    Favg_down: float
    t_up: float
    t_down: float

    def E(self, mu, up):
        """E at cosines *mu* ≥ 0 on the side *up* (boolean array): the piece of each μ, linear in t between the
        spline's samples (:func:`waveoptics.brdf.read_pieces`)."""
        return np.where(up, read_pieces(mu, self.pieces_up, self.t, self.E_up),
                        read_pieces(mu, self.pieces_down, self.t, self.E_down))


def _albedo_nodes(w1, eta_rel, ax, ay, symmetric):
    """Facet normals and weights (sr) of :func:`albedo_single` at one direction: about ω_i, split at the critical
    angle (:func:`waveoptics.brdf.incidence_normal_quadrature`), for light from the denser side and a lobe at
    least :data:`waveoptics.brdf.INCIDENCE_ALPHA_MIN` wide; else over slopes about the macro normal."""
    if eta_rel < 1.0 and min(ax, ay) >= INCIDENCE_ALPHA_MIN:
        return incidence_normal_quadrature(w1, eta_rel, symmetric=symmetric)
    m, w = normal_quadrature(ax, ay)
    if symmetric:
        keep = m[:, 1] >= 0
        m, w = m[keep], np.where(m[keep, 1] > 0, 2.0, 1.0) * w[keep]
    return m, w


def albedo_single(wi, iface, spec, ndf, ax, ay, c, shadowing, symmetric=False, facet_factors=None):
    """(R, T) = ∫ f_r |cos θ_o| dω_o, ∫ f_t |cos θ_o| dω_o (dimensionless) for each wi (n, 3), by quadrature over
    microfacet normals (:func:`waveoptics.brdf.normal_quadrature`, nodes placed by α): each normal m gives the
    mirror and the refracted direction, dω_o = 4 |i·m| dω_m and (η_i (i·m) + η_o (o·m))² / (η_o² |o·m|) dω_m
    (Walter eqs. 14, 17). *iface*: a real index η below air, or a facet interface
    (:func:`waveoptics.brdf.facet_interface_of`, R and T per facet). *symmetric*: an isotropic lobe with ω_i in the
    xz plane, integrated over the half m_y ≥ 0 (twice). *facet_factors*: a function (|i·m|, from_above) →
    (a_r, a_t) of arrays over the normals that scales each facet's reflection and refraction (the coherent share of
    a nano-rough facet); None: 1.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eqs. (14), (17), (20), (21).
    """
    iface = as_interface(iface)
    R = np.zeros(len(wi))
    T = np.zeros(len(wi))
    for j, w1 in enumerate(wi):
        s = 1.0 if w1[2] > 0 else -1.0
        eta_i, eta_t = (1.0, iface.eta) if s > 0 else (iface.eta, 1.0)
        m, w = _albedo_nodes(w1, eta_t / eta_i, ax, ay, symmetric)
        ih = m @ w1
        vis = ih * s > 0
        wr = reflect(w1, m)
        wt, ok = refract(np.broadcast_to(w1, m.shape), s * m, np.full(len(m), eta_t / eta_i))
        a = np.broadcast_to(w1, m.shape)
        fr, _ = _single(a, wr, iface, spec, ax, ay, c, shadowing)
        _, ft = _single(a, np.where(ok[:, None], wt, np.array([0.0, 0.0, s])), iface, spec, ax, ay, c, shadowing)
        oh = dot_last(wt, m)
        den = (eta_i * ih + eta_t * oh) ** 2
        jt = den / np.where(ok, eta_t ** 2 * np.abs(oh), 1.0)
        a_r, a_t = (1.0, 1.0) if facet_factors is None else facet_factors(np.abs(ih), s > 0)
        R[j] = np.sum(np.where(vis, a_r * fr * np.abs(wr[:, 2]) * 4.0 * np.abs(ih), 0.0) * w)
        T[j] = np.sum(np.where(vis & ok, a_t * ft * np.abs(wt[:, 2]) * jt, 0.0) * w)
    return R, T


def _cosine_mean(values, pieces, t):
    """2 ∫ E μ dμ of a table as :func:`waveoptics.brdf.read_pieces` reads it back: Gauss-Legendre in μ on each
    piece of μ (dimensionless)."""
    x, w = gl01(DIELECTRIC_MEAN_NODES)
    total = 0.0
    for lo, hi, _, _ in pieces:
        mu = lo + (hi - lo) * x
        total += 2.0 * (hi - lo) * float(np.sum(w * mu * read_pieces(mu, pieces, t, values)))
    return total


@functools.lru_cache(maxsize=64)
def dielectric_tables(ndf: str, alpha: float, eta, shadowing: str, ndf_shape: float | None) -> DielectricTables:
    """The albedo tables of the energy compensation (:class:`DielectricTables`) of an isotropic interface.

    Parameters
    ----------
    ndf : str
        NDF name (:data:`waveoptics.brdf.NDFS`).
    alpha : float
        Isotropic slope scale α (dimensionless).
    eta : float or facet interface
        Real index of the medium below (air above), or a lossless facet interface (a thin-film stack on it,
        :func:`waveoptics.brdf.facet_interface_of`: its R and T in place of F and 1 − F, R + T = 1 per facet).
    shadowing : str
        ``smith`` or ``smith-correlated``.
    ndf_shape : float or None
        The NDF's shape parameter.

    References
    ----------
    .. [1] C. Kulla, A. Conty, SIGGRAPH 2017 course, the dielectric energy compensation.
    """
    spec = ndf_by_name(ndf)
    iface = as_interface(eta)
    eta = iface.eta
    x, _ = gl01(DIELECTRIC_MS_NODES)
    t = np.linspace(0.0, 1.0, DIELECTRIC_DENSE_SAMPLES)
    pieces = {1.0: split_pieces(()), -1.0: split_pieces(albedo_cuts(eta))}
    E = {}
    for sgn in (1.0, -1.0):
        rows = []
        for piece in pieces[sgn]:
            mu = piece_cosine(x, piece)
            wi = np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), sgn * mu], axis=-1)
            R, T = albedo_single(wi, iface, spec, ndf, alpha, alpha, ndf_shape, shadowing, symmetric=True)
            # guard: a single-scattering albedo cannot exceed 1, but the quadrature's error can put it slightly
            # above (as in waveoptics.brdf.multiscatter); above 1 the compensation lobe 1 − E would turn negative
            rows.append(np.minimum(CubicSpline(x, np.minimum(R + T, 1.0))(t), 1.0))
        E[sgn] = np.array(rows)
    Eavg_up = _cosine_mean(E[1.0], pieces[1.0], t)
    Eavg_down = _cosine_mean(E[-1.0], pieces[-1.0], t)
    Favg_up = float(F_mean(lambda mu: iface.RT(mu, True)[0]))
    Favg_down = float(F_mean(lambda mu: iface.RT(mu, False)[0]))
    lost_up, lost_down = max(1.0 - Eavg_up, 1e-12), max(1.0 - Eavg_down, 1e-12)
    ratio = eta * eta * (1.0 - Favg_down) * lost_down / ((1.0 - Favg_up) * lost_up)
    share = ratio / (1.0 + ratio)
    return DielectricTables(pieces_up=pieces[1.0], pieces_down=pieces[-1.0], t=t, E_up=E[1.0], E_down=E[-1.0],
                            Eavg_up=Eavg_up, Eavg_down=Eavg_down,
                            Favg_up=Favg_up, Favg_down=Favg_down, t_up=(1.0 - Favg_up) * share,
                            t_down=(1.0 - Favg_down) * (1.0 - share))


def _f_ms(wi, wo, tab: DielectricTables):
    """The compensation lobes (module doc) in 1/sr: (reflection, transmission) of flat arrays."""
    up_i, up_o = wi[:, 2] > 0, wo[:, 2] > 0
    lost_i = 1.0 - tab.E(np.abs(wi[:, 2]), up_i)
    lost_o = 1.0 - tab.E(np.abs(wo[:, 2]), up_o)
    norm_o = np.pi * np.maximum(1.0 - np.where(up_o, tab.Eavg_up, tab.Eavg_down), 1e-12)
    t = np.where(up_i, tab.t_up, tab.t_down)
    val = lost_i * lost_o / norm_o
    ok = (wi[:, 2] != 0) & (wo[:, 2] != 0)
    same = up_i == up_o
    return np.where(ok & same, (1.0 - t) * val, 0.0), np.where(ok & ~same, t * val, 0.0)


def albedo_multiple(w1, tab: DielectricTables):
    """(reflection, transmission) albedos ∫ f_ms |cos θ_o| dω_o (dimensionless) of the compensation lobes at one
    direction *w1* (3,), by Gauss-Legendre quadrature in |cos θ_o| on each piece of each side's table (the lobes
    depend on θ_o only).

    References
    ----------
    .. [1] C. Kulla, A. Conty, SIGGRAPH 2017 course, the dielectric energy compensation.
    """
    g, wg = gl01(DIELECTRIC_MEAN_NODES)
    refl = trans = 0.0
    for sgn, pieces in ((1.0, tab.pieces_up), (-1.0, tab.pieces_down)):
        for lo, hi, _, _ in pieces:
            x, wx = lo + (hi - lo) * g, (hi - lo) * wg
            wo = np.stack([np.sqrt(1.0 - x * x), np.zeros_like(x), sgn * x], axis=-1)
            mr, mt = _f_ms(np.broadcast_to(w1, wo.shape), wo, tab)
            refl += 2.0 * np.pi * np.sum(wx * x * mr)
            trans += 2.0 * np.pi * np.sum(wx * x * mt)
    return refl, trans


@dataclass(frozen=True)
class RoughDielectricBSDF(SphereBSDF):
    """The BSDF of a rough interface between air (z > 0) and a dielectric (z < 0): reflection and transmission
    over the whole sphere (module doc), as a function with ``eval`` / ``pdf`` / ``sample`` / ``albedo``.

    Unlike the BRDFs of :mod:`waveoptics.brdf.protocol`, directions may lie on either side: ``eval`` gives f_r
    when ω_i, ω_o are on one side and f_t (with its η_o² radiance factor) across; light from inside (i_z < 0) sees
    the relative index 1/η. ``albedo`` is ∫ f |cos θ_o| dω_o over the sphere; ``sample`` returns weight
    f |cos θ_o| / pdf.

    Parameters
    ----------
    material : str or Material
        The dielectric below the surface; its index is Re n(λ) (the bulk's absorption k belongs to the medium,
        not to the interface). Metals and F0-only materials are refused.
    micro : Micro
        NDF, α (α_y) and shadowing (``smith`` or ``smith-correlated``).
    multiple_scattering : bool
        Add the Kulla-Conty dielectric compensation (isotropic tables of √(α_x α_y)).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eqs. (20), (21), §5.3.
    .. [2] C. Kulla, A. Conty, SIGGRAPH 2017 course (dielectric energy compensation).
    """

    material: Material | str = "1.5"
    micro: Micro = Micro()
    multiple_scattering: bool = False
    #: whether the class takes a thin-film stack as its material (facets coated: R and T of the stack)
    takes_stack: ClassVar[bool] = True

    def __post_init__(self):
        mat = get_material(self.material)
        if mat.is_metal or mat.schlick_only:
            raise FieldError(f"{{material}} {mat.name!r} is not a dielectric with a refractive index; the rough "
                             "dielectric needs one (e.g. glass or 1.5)", "material")
        object.__setattr__(self, "material", mat)
        if not mat.has_index and not self.takes_stack:
            raise FieldError(f"{{material}} {mat.name!r} is a thin-film stack, which the rough dielectric with "
                             "{psd} does not take (its nano tables are of a bare interface); drop one of them",
                             "material", "psd")
        if self.micro.shadowing not in DIELECTRIC_SHADOWINGS:
            raise unknown("shadowing model of the rough dielectric", self.micro.shadowing, DIELECTRIC_SHADOWINGS,
                          field="shadowing")
        spec = ndf_by_name(self.micro.ndf)
        kw = self.micro.kw()
        check_alpha(kw["alpha"], kw["alpha_y"], spec, kw["ndf_shape"])

    # -- pieces -------------------------------------------------------------------------------------------------
    def _iface(self, lam):
        """The facet interface at *lam* (nm): bare, or coated by the material's films (Snell with the substrate)."""
        iface = facet_interface_of(self.material, lam)
        if abs(iface.eta - 1.0) < 1e-9:
            raise FieldError(f"the index {iface.eta!r} of {{material}} at {lam:g} nm equals the outside's (1): there "
                             "is no interface", "material")
        return iface

    def _eta(self, lam):
        return self._iface(lam).eta

    def _args(self):
        kw = self.micro.kw()
        ay = kw["alpha_y"] if kw["alpha_y"] is not None else kw["alpha"]
        return ndf_by_name(kw["ndf"]), kw["ndf"], kw["alpha"], ay, kw["ndf_shape"]

    def _tables(self, lam):
        _, ndf, ax, ay, c = self._args()
        shape = float(c) if isinstance(c, (int, float, np.number)) else c
        iface = self._iface(lam)
        if not iface.lossless:
            raise FieldError(f"{{material}} {self.material.name!r} has absorbing films at {lam:g} nm; "
                             "{multiple_scattering} needs lossless ones (its lobes return all of 1 − E)",
                             "material", "multiple_scattering")
        return dielectric_tables(ndf, float(np.sqrt(ax * ay)), iface, self.micro.shadowing, shape)

    def _parts1(self, wi, wo, lam):
        """(reflection, transmission, multiple reflection, multiple transmission) in 1/sr at one wavelength."""
        spec, _, ax, ay, c = self._args()
        fr, ft = _single(wi, wo, self._iface(lam), spec, ax, ay, c, self.micro.shadowing)
        if not self.multiple_scattering:
            zero = np.zeros(len(wi))
            return fr, ft, zero, zero
        mr, mt = _f_ms(wi, wo, self._tables(lam))
        return fr, ft, mr, mt

    def eval_parts(self, wi, wo, wavelength_nm) -> dict:
        """The parts of :meth:`eval` in 1/sr: ``reflection`` and ``transmission`` (single scattering) and
        ``multiple`` (the compensation lobes; 0 unless ``multiple_scattering``)."""
        wi, wo, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        out = {k: np.zeros(lam.size) for k in ("reflection", "transmission", "multiple")}
        for val in np.unique(lam):
            sel = lam == val
            fr, ft, mr, mt = self._parts1(wi[sel], wo[sel], float(val))
            out["reflection"][sel], out["transmission"][sel], out["multiple"][sel] = fr, ft, mr + mt
        return {k: v.reshape(shape) for k, v in out.items()}

    def _eval1(self, wi, wo, lam):
        return sum(self._parts1(wi, wo, lam))

    def _p_ms(self, wi, lam):
        """Probability of the compensation lobes: their energy 1 − E(μ_i) (the single lobes carry E(μ_i))."""
        if not self.multiple_scattering:
            return np.zeros(len(wi))
        return 1.0 - self._tables(lam).E(np.abs(wi[:, 2]), wi[:, 2] > 0)

    def _pdf1(self, wi, wo, lam):
        _, ndf, ax, ay, c = self._args()
        p = _single_pdf(wi, wo, self._iface(lam), ndf, ax, ay, c)
        if not self.multiple_scattering:
            return p
        tab = self._tables(lam)
        pm = self._p_ms(wi, lam)
        t = np.where(wi[:, 2] > 0, tab.t_up, tab.t_down)
        same = (wi[:, 2] > 0) == (wo[:, 2] > 0)
        p_cos = np.where(same, 1.0 - t, t) * np.abs(wo[:, 2]) / np.pi
        return (1.0 - pm) * p + pm * np.where((wi[:, 2] != 0) & (wo[:, 2] != 0), p_cos, 0.0)

    def _sample1(self, wi, u, lam):
        _, ndf, ax, ay, c = self._args()
        pm = self._p_ms(wi, lam)
        idx, u[:, 0] = lobe_choice(u[:, 0], [1.0 - pm, pm])
        wo = _sample_single(wi, u, self._iface(lam), ndf, ax, ay, c)
        ms = idx == 1
        if np.any(ms):
            tab = self._tables(lam)
            s = np.sign(wi[ms, 2])
            cross = np.modf(u[ms, 1] * UNIFORM_DIGITS)[0] < np.where(s > 0, tab.t_up, tab.t_down)
            r = np.sqrt(u[ms, 0])
            phi = 2.0 * np.pi * u[ms, 1]
            z = np.sqrt(np.maximum(1.0 - u[ms, 0], 0.0)) * np.where(cross, -s, s)
            wo[ms] = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
        return wo

    def albedo_parts(self, wi, wavelength_nm) -> dict:
        """∫ f |cos θ_o| dω_o of each part (dimensionless): ``reflection`` and ``transmission`` by quadrature over
        microfacet normals (:func:`albedo_single`), ``multiple_reflection`` and ``multiple_transmission`` by
        Gauss-Legendre quadrature in cos θ_o of the compensation lobes (which depend on θ_o only)."""
        wi_f, lam_f, shape = broadcast_incidence(wi, wavelength_nm)
        keys = ("reflection", "transmission", "multiple_reflection", "multiple_transmission")
        out = {k: np.zeros(lam_f.size) for k in keys}
        spec, ndf, ax, ay, c = self._args()
        for j, (w1, l1) in enumerate(zip(wi_f, lam_f)):
            if w1[2] == 0:
                continue
            R, T = albedo_single(w1[None], self._iface(float(l1)), spec, ndf, ax, ay, c, self.micro.shadowing)
            out["reflection"][j], out["transmission"][j] = R[0], T[0]
            if self.multiple_scattering:
                out["multiple_reflection"][j], out["multiple_transmission"][j] = albedo_multiple(
                    w1, self._tables(float(l1)))
        return {k: v.reshape(shape) for k, v in out.items()}
