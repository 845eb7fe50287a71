"""An independent reference for the two-scale BRDF, written from the papers (not from ``waveoptics``).

Imported by tests as ``import twoscale_reference``. Nothing here imports the package under test: every formula is
written from its source (see each function's References), in pure NumPy/SciPy, vectorized, with seeded generators.

Contents
--------
* Microfacet pieces (Walter et al. 2007; Heitz 2014): isotropic Beckmann and GGX ``D``, Smith ``Lambda``, ``G1``,
  the height-correlated ``G2``, a sampler of ``D(m) cos θ_m`` and its pdf.
* The facet-frame two-scale integral (:func:`facet_integral`): micro-facets drawn from the NDF, each carrying a
  nano-scale BRDF ``f_nano`` evaluated in the facet's own frame; Monte Carlo with a balance-heuristic mixture
  (Veach 1997) of NDF sampling and sampling about the half vector; returns (mean, standard error).
* The coherent part (:func:`coherent_part`) and a directional albedo of any callable BRDF (:func:`albedo_mc`,
  :func:`albedo_quadrature`).
* Nano lobes written from the papers: ABC / K-correlation and Gaussian PSDs, first-order vector perturbation theory
  (Rayleigh-Rice) with the polarization factors Q_ss, Q_sp, Q_ps, Q_pp, its total integrated scatter, and the
  coherent reflectance of a slightly rough surface (Davies 1954).

Conventions
-----------
Directions are unit vectors, arrays of shape (N, 3), in the macro frame (z = macro normal) unless said otherwise.
``wi`` points towards the light and ``wo`` towards the viewer, both with z > 0 for a reflection (so the mirror of
``wi`` about the normal is ``(-wi_x, -wi_y, wi_z)``). Lengths are in nm, spatial frequencies in 1/nm, PSDs in nm^4
(per (1/nm)^2), BRDFs in 1/sr. The nano lobe interface is ``f_nano(wi, wo, wavelength_nm) -> (N,)`` with ``wi``,
``wo`` in the facet's local frame (z = facet normal), 0 where either z ≤ 0.

References
----------
B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet models for refraction through rough surfaces",
EGSR 2007. E. Heitz, "Understanding the masking-shadowing function in microfacet-based BRDFs", JCGT 3(2), 2014.
E. Veach, "Robust Monte Carlo methods for light transport simulation", PhD thesis, Stanford 1997, ch. 9.
J. M. Elson, J. M. Bennett, "Relation between the angular dependence of scattering and the statistical properties of
optical surfaces", JOSA 69(1), 31, 1979. E. L. Church, H. A. Jenkinson, J. M. Zavada, "Relationship between surface
scattering and microtopographic features", Opt. Eng. 18(2), 125, 1979. J. C. Stover, *Optical Scattering:
Measurement and Analysis*, 3rd ed., SPIE 2012, ch. 4. H. Davies, "The reflection of electromagnetic waves from a
rough surface", Proc. IEE 101, 209, 1954. E. L. Church, P. Z. Takacs, T. A. Leonard, "The prediction of BRDFs from
surface profile measurements", Proc. SPIE 1165, 1989 (ABC PSD). Project summary: docs/physics.md §4, §6, §7.
"""
from __future__ import annotations

import numpy as np
from scipy.special import erfc

NDFS = ("beckmann", "ggx")
_TINY = 1e-300


# ----------------------------------------------------------------------------------------------------------------
# small vector helpers
# ----------------------------------------------------------------------------------------------------------------

def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def direction(theta_deg, phi_deg=0.0):
    """Unit vector(s) at polar angle θ and azimuth φ (degrees), shape (..., 3)."""
    t, p = np.deg2rad(theta_deg), np.deg2rad(phi_deg)
    t, p = np.broadcast_arrays(t, p)
    return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)


def half_vector(wi, wo):
    """h = (wi + wo) / |wi + wo| (reflection half vector)."""
    return _unit(np.asarray(wi, float) + np.asarray(wo, float))


def onb(n):
    """Orthonormal tangents (t1, t2) of unit vectors n (..., 3), branchless.

    References
    ----------
    T. Duff et al., "Building an orthonormal basis, revisited", JCGT 6(1), 2017.
    """
    n = np.asarray(n, float)
    x, y, z = n[..., 0], n[..., 1], n[..., 2]
    s = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + z)
    b = x * y * a
    t1 = np.stack([1.0 + s * x * x * a, s * b, -s * x], axis=-1)
    t2 = np.stack([b, s + y * y * a, -y], axis=-1)
    return t1, t2


def to_facet_frame(w, m):
    """Express w in the local frame of facet normal m (m becomes +z).

    The frame is the minimal rotation taking m to z, about the axis m × z (equivalently z × m with the opposite
    angle): R x = x + v × x + v × (v × x) / (1 + c), v = m × z, c = m · z (Rodrigues). For an isotropic nano lobe the
    azimuth of the local frame does not matter (the lobe depends only on the relative geometry of wi and wo about
    the facet normal); for an anisotropic one this choice fixes it. Undefined at m = −z (not needed: m_z > 0).

    Parameters
    ----------
    w : array (..., 3)
    m : array (..., 3), unit, m_z > −1
    """
    w, m = np.broadcast_arrays(np.asarray(w, float), np.asarray(m, float))
    v = np.stack([m[..., 1], -m[..., 0], np.zeros_like(m[..., 0])], axis=-1)   # m × z
    c = m[..., 2]
    vx = np.cross(v, w)
    return w + vx + np.cross(v, vx) / (1.0 + c)[..., None]


# ----------------------------------------------------------------------------------------------------------------
# microfacet pieces (Walter et al. 2007; Heitz 2014)
# ----------------------------------------------------------------------------------------------------------------

def _check_ndf(ndf):
    if ndf not in NDFS:
        raise ValueError(f"ndf must be one of {NDFS}, got {ndf!r}")


def _tan2(w):
    z = np.clip(np.asarray(w, float)[..., 2], -1.0, 1.0)
    z2 = z * z
    with np.errstate(divide="ignore"):
        return np.where(z2 > 0, (1.0 - z2) / np.maximum(z2, _TINY), np.inf)


def D(m, alpha, ndf="beckmann"):
    """Isotropic NDF D(m), 1/sr, normalized so that ∫ D(m) (m·n) dω_m = 1; 0 for m_z ≤ 0.

    Beckmann: exp(−tan²θ/α²) / (π α² cos⁴θ). GGX: α² / (π cos⁴θ (α² + tan²θ)²).

    Parameters
    ----------
    m : array (..., 3), unit micro-normals
    alpha : float, roughness (Walter 2007's α; for Beckmann the rms of |∇h|, √2 × the per-axis rms slope)
    ndf : {"beckmann", "ggx"}

    References
    ----------
    Walter et al. 2007, eqs. 25 and 33; Heitz 2014 §5.
    """
    _check_ndf(ndf)
    m = np.asarray(m, float)
    cz = m[..., 2]
    t2 = _tan2(m)
    a2 = float(alpha) ** 2
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        c4 = np.maximum(cz, _TINY) ** 4
        if ndf == "beckmann":
            d = np.exp(-t2 / a2) / (np.pi * a2 * c4)
        else:
            d = a2 / (np.pi * c4 * (a2 + t2) ** 2)
    return np.where(cz > 0, np.nan_to_num(d, nan=0.0, posinf=0.0), 0.0)


def Lambda(w, alpha, ndf="beckmann"):
    """Smith Λ(w) of the isotropic NDF (Heitz 2014 eqs. 72 (Beckmann) and 86 (GGX)).

    Beckmann: a = 1 / (α tanθ), Λ = (erf(a) − 1)/2 + exp(−a²) / (2 a √π). GGX: Λ = (−1 + √(1 + α² tan²θ)) / 2.
    Λ = 0 at the normal; Λ → ∞ at the horizon.

    References
    ----------
    Heitz 2014 §5.1-5.2; Walter et al. 2007 eqs. 27 and 34.
    """
    _check_ndf(ndf)
    t2 = _tan2(w)
    alpha = float(alpha)
    if ndf == "ggx":
        with np.errstate(invalid="ignore", over="ignore"):
            return np.where(np.isfinite(t2), 0.5 * (np.sqrt(1.0 + alpha * alpha * t2) - 1.0), np.inf)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        a = 1.0 / (alpha * np.sqrt(t2))
        lam = -0.5 * erfc(a) + np.exp(-a * a) / (2.0 * a * np.sqrt(np.pi))
    lam = np.where(t2 == 0.0, 0.0, lam)
    return np.where(np.isfinite(t2), lam, np.inf)


def G1(w, m, alpha, ndf="beckmann"):
    """Smith masking χ⁺(w·m / w·n) / (1 + Λ(w)) (Heitz 2014 eq. 43)."""
    w, m = np.asarray(w, float), np.asarray(m, float)
    ok = (_dot(w, m) * w[..., 2]) > 0
    return np.where(ok, 1.0 / (1.0 + Lambda(w, alpha, ndf)), 0.0)


def G2(wi, wo, m, alpha, ndf="beckmann"):
    """Height-correlated Smith masking-shadowing χ⁺(wi·m) χ⁺(wo·m) / (1 + Λ(wi) + Λ(wo)) (Heitz 2014 eq. 99).

    Reflection only (wi_z, wo_z > 0).
    """
    wi, wo, m = (np.asarray(x, float) for x in (wi, wo, m))
    ok = (_dot(wi, m) > 0) & (_dot(wo, m) > 0) & (wi[..., 2] > 0) & (wo[..., 2] > 0)
    with np.errstate(invalid="ignore"):
        g = 1.0 / (1.0 + Lambda(wi, alpha, ndf) + Lambda(wo, alpha, ndf))
    return np.where(ok, g, 0.0)


def sample_ndf(alpha, n, rng, ndf="beckmann"):
    """Draw n micro-normals with pdf D(m) cos θ_m (per sr) by inverting the cdf of tan²θ_m.

    Beckmann: tan²θ = −α² ln(1 − u); GGX: tan²θ = α² u / (1 − u); φ = 2π u₂.

    References
    ----------
    Walter et al. 2007 eqs. 28-29 and 35-36.
    """
    _check_ndf(ndf)
    u1, u2 = rng.random(n), rng.random(n)
    a2 = float(alpha) ** 2
    t2 = -a2 * np.log1p(-u1) if ndf == "beckmann" else a2 * u1 / (1.0 - u1)
    c = 1.0 / np.sqrt(1.0 + t2)
    s = np.sqrt(np.maximum(0.0, 1.0 - c * c))
    p = 2.0 * np.pi * u2
    return np.stack([s * np.cos(p), s * np.sin(p), c], axis=-1)


def pdf_ndf(m, alpha, ndf="beckmann"):
    """pdf (per sr) of :func:`sample_ndf`: D(m) cos θ_m."""
    m = np.asarray(m, float)
    return D(m, alpha, ndf) * np.maximum(m[..., 2], 0.0)


def microfacet_brdf(wi, wo, alpha, F=1.0, ndf="beckmann"):
    """Walter's specular microfacet BRDF F G2 D(h) / (4 |i·n| |o·n|), with a constant (or array) F.

    References
    ----------
    Walter et al. 2007 eq. 20; Heitz 2014 eq. 3 with the height-correlated G2.
    """
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    h = half_vector(wi, wo)
    den = 4.0 * np.abs(wi[..., 2] * wo[..., 2])
    with np.errstate(divide="ignore", invalid="ignore"):
        f = F * G2(wi, wo, h, alpha, ndf) * D(h, alpha, ndf) / den
    return np.where(den > 0, np.nan_to_num(f), 0.0)


def coherent_part(wi, wo, alpha, A, F, ndf="beckmann"):
    """Coherent (specular) part of the two-scale BRDF: A(i·h) F(i·h) G2(i,o,h) D(h) / (4 |i·n| |o·n|).

    Parameters
    ----------
    wi, wo : arrays (N, 3), macro frame
    alpha : float
    A : callable cos θ_d -> coherent fraction (e.g. exp(−(4π σ cos θ_d / λ)²), Davies 1954)
    F : callable cos θ_d -> Fresnel reflectance

    References
    ----------
    Walter et al. 2007 eq. 20 (microfacet BRDF); Davies 1954 (coherent fraction); Holzschuch & Pacanowski,
    ACM TOG 36(4) 2017 (the structure); docs/physics.md §7.
    """
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    cd = np.clip(_dot(wi, half_vector(wi, wo)), 0.0, 1.0)
    return np.asarray(A(cd)) * np.asarray(F(cd)) * microfacet_brdf(wi, wo, alpha, 1.0, ndf)


# ----------------------------------------------------------------------------------------------------------------
# a 2-D heavy-tailed proposal about a centre (bivariate Student t with ν = 1)
# ----------------------------------------------------------------------------------------------------------------

def _t2d_sample(scale, n, rng):
    """(n, 2) offsets with density (1 / (2π s²)) (1 + r²/s²)^(−3/2) (radial cdf 1 − (1 + r²/s²)^(−1/2))."""
    u1, u2 = rng.random(n), rng.random(n)
    r = scale * np.sqrt(np.maximum((1.0 - u1) ** -2 - 1.0, 0.0))
    p = 2.0 * np.pi * u2
    return np.stack([r * np.cos(p), r * np.sin(p)], axis=-1)


def _t2d_pdf(r2, scale):
    s2 = scale * scale
    return (1.0 + r2 / s2) ** -1.5 / (2.0 * np.pi * s2)


def _sample_about(h, scale, n, rng):
    """Unit vectors m about the unit vectors h (P, 3): direction cosines (u, v) of m in h's tangent frame drawn from
    the 2-D proposal, m = u t1 + v t2 + √(1 − u² − v²) h. Returns m (P, n, 3) and a mask of valid draws (u²+v² < 1);
    invalid draws count as samples with zero contribution (the proposal is a sub-probability on the sphere)."""
    P = h.shape[0]
    t1, t2 = onb(h)
    uv = _t2d_sample(scale, P * n, rng).reshape(P, n, 2)
    r2 = np.sum(uv * uv, axis=-1)
    ok = r2 < 1.0
    w = np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))
    m = uv[..., :1] * t1[:, None] + uv[..., 1:] * t2[:, None] + w[..., None] * h[:, None]
    m = np.where(ok[..., None], m, h[:, None])
    return _unit(m), ok


def _pdf_about(m, h, scale):
    """Solid-angle pdf of :func:`_sample_about` at m (P, n, 3): p_2d(u, v) × (m·h) (projection Jacobian)."""
    t1, t2 = onb(h)
    u = _dot(m, t1[:, None])
    v = _dot(m, t2[:, None])
    c = _dot(m, h[:, None])
    return np.where(c > 0, _t2d_pdf(u * u + v * v, scale) * np.maximum(c, 0.0), 0.0)


def _mis_sum(y_by_technique):
    """Multi-sample balance-heuristic estimate: the sum of all contributions y = g / Σ_t n_t p_t, and its standard
    error sqrt(Σ_t n_t Var_t(y)) (Veach 1997 §9.2). Each entry is an array (P, n_t)."""
    mean = sum(np.sum(y, axis=1) for y in y_by_technique if y.shape[1])
    var = sum(y.shape[1] * np.var(y, axis=1, ddof=1) for y in y_by_technique if y.shape[1] > 1)
    return mean, np.sqrt(var)


# ----------------------------------------------------------------------------------------------------------------
# the facet-frame two-scale integral (Walter et al. 2007, facets carrying a BRDF)
# ----------------------------------------------------------------------------------------------------------------

def facet_integrand(f_nano, wi, wo, m, wavelength_nm, alpha, ndf="beckmann", frame=None):
    """|i·m| |o·m| / (|i·n| |o·n|) · f_nano(i_m, o_m; λ) · G2(i, o, m) · D(m) at micro-normals m.

    Parameters
    ----------
    f_nano : callable (wi (N, 3), wo (N, 3), wavelength_nm) -> (N,), in the facet frame
    wi, wo : arrays (P, 3), macro frame
    m : array (P, n, 3), micro-normals
    frame : callable (w (..., 3), m (..., 3)) -> local directions (..., 3), z = w·m; None: :func:`to_facet_frame`
        (the azimuth of the local frame matters for an anisotropic nano lobe only)
    """
    wi_, wo_ = np.broadcast_to(wi[:, None], m.shape), np.broadcast_to(wo[:, None], m.shape)
    frame = frame or to_facet_frame
    im, om = frame(wi_, m), frame(wo_, m)
    fn = np.asarray(f_nano(im.reshape(-1, 3), om.reshape(-1, 3), wavelength_nm), float).reshape(m.shape[:-1])
    ok = (im[..., 2] > 0) & (om[..., 2] > 0) & (m[..., 2] > 0)
    jac = np.abs(im[..., 2] * om[..., 2]) / np.abs(wi[:, None, 2] * wo[:, None, 2])
    g = jac * np.where(ok, fn, 0.0) * G2(wi_, wo_, m, alpha, ndf) * D(m, alpha, ndf)
    return np.where(ok, g, 0.0)


def facet_integral(f_nano, wi, wo, wavelength_nm, alpha, ndf="beckmann", nano_width=None, n_samples=4096,
                   seed=0, ndf_fraction=0.5, frame=None):
    """Diffracted part of a two-scale BRDF as the facet-frame integral, by Monte Carlo.

        f_diff(i, o) = ∫ |i·m| |o·m| / (|i·n| |o·n|) · f_nano(i_m, o_m; λ) · G2(i, o, m) · D(m) dω_m

    with i_m, o_m the directions in the facet frame (:func:`to_facet_frame`). Importance sampling is a
    balance-heuristic mixture (Veach 1997, multi-sample model with fixed counts) of (a) m ~ D(m) cos θ_m
    (:func:`sample_ndf`; good when the micro lobe is the narrower one) and (b) m about the half vector h(i, o),
    with a heavy-tailed (bivariate Student t, ν = 1) density of scale ``nano_width / 2`` in direction cosines of m
    about h (good when the nano lobe is the narrower one: tilting a facet by δ moves its mirror direction by 2δ).

    Parameters
    ----------
    f_nano : callable (wi (N, 3), wo (N, 3), wavelength_nm) -> (N,) BRDF in 1/sr, in the facet frame
    wi, wo : arrays (P, 3) or (3,), unit, macro frame, z > 0
    wavelength_nm : float, passed to f_nano
    alpha : float, micro roughness
    ndf : {"beckmann", "ggx"}
    nano_width : float or None, direction cosines: the angular width of the nano lobe (None: technique (a) only)
    n_samples : int, samples per (i, o) pair (split between the techniques)
    seed : int, of ``np.random.default_rng``
    ndf_fraction : float in (0, 1], share of the samples drawn by technique (a)
    frame : the facet frame of :func:`facet_integrand` (None: :func:`to_facet_frame`)

    Returns
    -------
    mean, stderr : arrays (P,), 1/sr

    References
    ----------
    Walter et al. 2007 eq. 8 (a rough surface whose micro-facets carry a BRDF f_m); Heitz 2014 eq. 99 (G2);
    Veach 1997 §9.2 (balance heuristic); Holzschuch & Pacanowski 2017 (two scales); docs/physics.md §7.
    """
    wi, wo = np.atleast_2d(_unit(wi)), np.atleast_2d(_unit(wo))
    wi, wo = np.broadcast_arrays(wi, wo)
    rng = np.random.default_rng(seed)
    P = wi.shape[0]
    use_b = nano_width is not None and nano_width > 0
    na = int(round(n_samples * (ndf_fraction if use_b else 1.0)))
    nb = n_samples - na if use_b else 0
    h = half_vector(wi, wo)
    ms = [sample_ndf(alpha, P * na, rng, ndf).reshape(P, na, 3)]
    oks = [np.ones((P, na), bool)]
    if nb:
        mb, okb = _sample_about(h, 0.5 * nano_width, nb, rng)
        ms.append(mb)
        oks.append(okb)
    ys = []
    for m, ok in zip(ms, oks):
        q = na * pdf_ndf(m, alpha, ndf)
        if nb:
            q = q + nb * _pdf_about(m, h, 0.5 * nano_width)
        g = facet_integrand(f_nano, wi, wo, m, wavelength_nm, alpha, ndf, frame)
        with np.errstate(divide="ignore", invalid="ignore"):
            ys.append(np.where(ok & (q > 0), g / np.where(q > 0, q, 1.0), 0.0))
    return _mis_sum(ys)


# ----------------------------------------------------------------------------------------------------------------
# directional albedo of any BRDF
# ----------------------------------------------------------------------------------------------------------------

def albedo_mc(brdf, wi, n_samples=65536, seed=0, width=None, uniform_fraction=0.5):
    """∫ f(wi, wo) cos θ_o dω_o by Monte Carlo, with its standard error.

    cos θ_o dω_o = d(o_x) d(o_y) (projected solid angle is area on the direction-cosine disc), so the techniques
    are (a) o_xy uniform on the unit disc (pdf 1/π) and, if ``width`` is given, (b) o_xy about the mirror point
    −wi_xy with a bivariate Student t (ν = 1) of scale ``width``, combined by the balance heuristic (Veach 1997).

    Parameters
    ----------
    brdf : callable (wi (N, 3), wo (N, 3)) -> (N,) in 1/sr
    wi : array (P, 3) or (3,)
    width : float or None, direction cosines: the lobe width about the mirror direction

    Returns
    -------
    mean, stderr : arrays (P,)

    References
    ----------
    Veach 1997 §9.2; Nicodemus et al., NBS Monograph 160 (1977) (projected solid angle).
    """
    wi = np.atleast_2d(_unit(wi))
    P = wi.shape[0]
    rng = np.random.default_rng(seed)
    use_b = width is not None and width > 0
    na = int(round(n_samples * (uniform_fraction if use_b else 1.0)))
    nb = n_samples - na
    r = np.sqrt(rng.random((P, na)))
    p = 2 * np.pi * rng.random((P, na))
    pts = [np.stack([r * np.cos(p), r * np.sin(p)], axis=-1)]
    if nb:
        pts.append(-wi[:, None, :2] + _t2d_sample(width, P * nb, rng).reshape(P, nb, 2))
    ys = []
    for xy in pts:
        r2 = np.sum(xy * xy, axis=-1)
        ok = r2 < 1.0
        q = na / np.pi * np.ones_like(r2)
        if nb:
            d = xy + wi[:, None, :2]
            q = q + nb * _t2d_pdf(np.sum(d * d, axis=-1), width)
        wo = np.concatenate([xy, np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))[..., None]], axis=-1)
        wo = np.where(ok[..., None], wo, np.array([0.0, 0.0, 1.0]))
        f = np.asarray(brdf(np.broadcast_to(wi[:, None], wo.shape).reshape(-1, 3), wo.reshape(-1, 3)), float)
        ys.append(np.where(ok, f.reshape(r2.shape) / q, 0.0))
    return _mis_sum(ys)


def disc_quadrature(center_xy, n_angle=128, n_gauss=8):
    """Nodes and weights over the unit direction-cosine disc (area element = cos θ_o dω_o), in polar coordinates
    about ``center_xy`` (inside the disc) with geometric Gauss-Legendre panels in the radius (fine near the centre,
    for a lobe peaked there, and near the rim, for the √(1 − r²) edge) and the periodic trapezoid rule in angle.

    Returns
    -------
    xy : array (K, 2), w : array (K,)
    """
    c = np.asarray(center_xy, float)
    psi = 2 * np.pi * (np.arange(n_angle) + 0.5) / n_angle
    d = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
    cd = d @ c
    rho_max = -cd + np.sqrt(cd * cd - c @ c + 1.0)
    breaks = np.unique(np.concatenate([[0.0], np.geomspace(1e-6, 0.5, 16), 1.0 - np.geomspace(0.5, 1e-7, 12), [1.0]]))
    x, wx = np.polynomial.legendre.leggauss(n_gauss)
    a, b = breaks[:-1, None], breaks[1:, None]
    t = (0.5 * (b - a) * x + 0.5 * (a + b)).ravel()
    wt = (0.5 * (b - a) * wx).ravel()
    rho = rho_max[:, None] * t[None, :]
    xy = c + rho[..., None] * d[:, None, :]
    w = (2 * np.pi / n_angle) * rho * rho_max[:, None] * wt[None, :]
    return xy.reshape(-1, 2), w.ravel()


def albedo_quadrature(brdf, wi, n_angle=128, n_gauss=8):
    """∫ f(wi, wo) cos θ_o dω_o by deterministic quadrature (:func:`disc_quadrature` about the mirror point), with an
    error estimate: the difference from the same rule at half the angular and radial orders.

    Returns
    -------
    value, error_estimate : floats (wi a single direction (3,))
    """
    wi = _unit(wi)
    out = []
    for na, ng in ((n_angle, n_gauss), (max(n_angle // 2, 8), max(n_gauss // 2, 2))):
        xy, w = disc_quadrature(-wi[:2], na, ng)
        wo = np.concatenate([xy, np.sqrt(np.clip(1.0 - np.sum(xy * xy, -1), 0.0, 1.0))[:, None]], axis=-1)
        f = np.asarray(brdf(np.broadcast_to(wi, wo.shape), wo), float)
        out.append(float(np.sum(w * f)))
    return out[0], abs(out[0] - out[1])


# ----------------------------------------------------------------------------------------------------------------
# nano lobes: PSDs, Rayleigh-Rice, coherent reflectance
# ----------------------------------------------------------------------------------------------------------------

def abc_psd(sigma_nm, B_nm, C):
    """ABC / K-correlation PSD S(f) = A / (1 + (B f)²)^(C/2), f in 1/nm, S in nm^4, normalized to ∫ S d²f = σ².

    Derivation: ∫ S d²f = 2π A ∫₀^∞ f (1 + B² f²)^(−C/2) df = (2π A / B²) ∫₀^∞ x (1 + x²)^(−C/2) dx
    = 2π A / (B² (C − 2)) for C > 2, hence A = σ² B² (C − 2) / (2π).

    References
    ----------
    Church, Takacs & Leonard, Proc. SPIE 1165 (1989); docs/physics.md §4.
    """
    if not C > 2:
        raise ValueError(f"C must exceed 2 (finite σ), got {C}")
    A = sigma_nm ** 2 * B_nm ** 2 * (C - 2.0) / (2.0 * np.pi)

    def S(f):
        return A / (1.0 + (B_nm * np.asarray(f, float)) ** 2) ** (0.5 * C)
    S.sigma_nm = sigma_nm
    return S


def gaussian_psd(sigma_nm, T_nm):
    """PSD of the correlation σ² exp(−r²/T²): S(f) = π σ² T² exp(−π² T² f²) (Fourier convention e^{−2πi f·r}).

    Derivation: ∫ exp(−r²/T²) e^{−2πi f·r} d²r = π T² exp(−π² T² f²) (product of two 1-D Gaussian transforms).

    References
    ----------
    Stover 2012 ch. 4; docs/physics.md §4.
    """
    def S(f):
        return np.pi * sigma_nm ** 2 * T_nm ** 2 * np.exp(-(np.pi * T_nm * np.asarray(f, float)) ** 2)
    S.sigma_nm = sigma_nm
    return S


def fresnel_rs_rp(cos_i, eps):
    """Complex Fresnel amplitude reflection coefficients from vacuum onto a medium of permittivity ε = n²:
    r_s = (cos − √(ε − sin²)) / (cos + √(ε − sin²)), r_p = (ε cos − √(ε − sin²)) / (ε cos + √(ε − sin²)).
    Principal square root (Im ≥ 0 for Im ε ≥ 0, an absorbing medium with n + ik).

    References
    ----------
    Born & Wolf, *Principles of Optics*, 7th ed., §1.5.2.
    """
    c = np.clip(np.asarray(cos_i, float), 0.0, 1.0)
    eps = np.asarray(eps, complex)
    k = np.sqrt(eps - (1.0 - c * c))
    return (c - k) / (c + k), (eps * c - k) / (eps * c + k)


def fresnel_R(cos_i, eps, pol="unpolarized"):
    """Fresnel reflectance |r_s|², |r_p|² or their mean."""
    rs, rp = fresnel_rs_rp(cos_i, eps)
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    return {"s": Rs, "p": Rp, "unpolarized": 0.5 * (Rs + Rp)}[pol]


def _scatter_geometry(wi, wo):
    """sin/cos of θi, θo and of the scattering azimuth φs measured from the specular half-plane (φs = 0 in the
    plane of incidence on the far side of the normal from wi)."""
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    ci, co = np.clip(wi[..., 2], 0.0, 1.0), np.clip(wo[..., 2], 0.0, 1.0)
    si = np.hypot(wi[..., 0], wi[..., 1])
    so = np.hypot(wo[..., 0], wo[..., 1])
    ex = np.where(si > 0, -wi[..., 0] / np.where(si > 0, si, 1.0), 1.0)     # specular azimuth direction (−wi_xy)
    ey = np.where(si > 0, -wi[..., 1] / np.where(si > 0, si, 1.0), 0.0)
    ox = np.where(so > 0, wo[..., 0] / np.where(so > 0, so, 1.0), 1.0)
    oy = np.where(so > 0, wo[..., 1] / np.where(so > 0, so, 1.0), 0.0)
    return ci, si, co, so, ex * ox + ey * oy, ex * oy - ey * ox


def rayleigh_rice_Q(wi, wo, eps):
    """Polarization factors Q_ss, Q_sp, Q_ps, Q_pp of first-order vector perturbation theory (first letter:
    incident polarization, second: scattered), ε = n² the substrate permittivity, k_j = √(ε − sin²θ_j):

        Q_ss = |(ε − 1) cos φs / ((cos θi + k_i)(cos θo + k_o))|²
        Q_sp = |(ε − 1) k_o sin φs / ((cos θi + k_i)(ε cos θo + k_o))|²
        Q_ps = |(ε − 1) k_i sin φs / ((ε cos θi + k_i)(cos θo + k_o))|²
        Q_pp = |(ε − 1) (k_i k_o cos φs − ε sin θi sin θo) / ((ε cos θi + k_i)(ε cos θo + k_o))|²

    At the specular direction (θo = θi, φs = 0) Q_ss = |r_s|², Q_pp = |r_p|², Q_sp = Q_ps = 0, since
    (cos − k)(cos + k) = 1 − ε and (ε cos − k)(ε cos + k) = (ε − 1)(ε − (1 + ε) sin²θ).

    Returns
    -------
    dict of arrays (N,): "ss", "sp", "ps", "pp"

    References
    ----------
    Elson & Bennett, JOSA 69(1) 1979; Church, Jenkinson & Zavada, Opt. Eng. 18(2) 1979; Stover 2012 ch. 4
    (the Q factors of the Rayleigh-Rice BRDF); Germer, Appl. Opt. 36(33) 1997.
    """
    ci, si, co, so, cphi, sphi = _scatter_geometry(wi, wo)
    eps = np.asarray(eps, complex)
    ki, ko = np.sqrt(eps - si * si), np.sqrt(eps - so * so)
    e1 = eps - 1.0
    si_, pi_ = ci + ki, eps * ci + ki
    so_, po_ = co + ko, eps * co + ko
    return {
        "ss": np.abs(e1 * cphi / (si_ * so_)) ** 2,
        "sp": np.abs(e1 * ko * sphi / (si_ * po_)) ** 2,
        "ps": np.abs(e1 * ki * sphi / (pi_ * so_)) ** 2,
        "pp": np.abs(e1 * (ki * ko * cphi - eps * si * so) / (pi_ * po_)) ** 2,
    }


def rayleigh_rice_Q_pol(wi, wo, eps, pol="unpolarized"):
    """Q for an incident polarization, detector insensitive to polarization: Q_s = Q_ss + Q_sp, Q_p = Q_ps + Q_pp,
    unpolarized Q = (Q_ss + Q_sp + Q_ps + Q_pp) / 2 (mean of the s and p sums). Also "ss", "sp", "ps", "pp"."""
    q = rayleigh_rice_Q(wi, wo, eps)
    if pol in q:
        return q[pol]
    qs, qp = q["ss"] + q["sp"], q["ps"] + q["pp"]
    return {"s": qs, "p": qp, "unpolarized": 0.5 * (qs + qp)}[pol]


def rayleigh_rice_brdf(wi, wo, wavelength_nm, psd, eps, pol="unpolarized"):
    """First-order perturbation BRDF f = (16 π² / λ⁴) cos θi cos θo Q S(f), f = |(wo + wi)_xy| / λ.

    With wi pointing to the light, the propagation direction of the incident wave is −wi, so the surface frequency
    (o − k̂_inc)_xy / λ of the papers is (wo + wi)_xy / λ here (0 at the mirror direction).

    Parameters
    ----------
    wi, wo : arrays (N, 3), unit, z > 0 (0 returned otherwise)
    wavelength_nm : float
    psd : callable f (1/nm) -> S (nm^4), isotropic
    eps : complex, or callable wavelength_nm -> complex
    pol : {"unpolarized", "s", "p", "ss", "sp", "ps", "pp"}

    References
    ----------
    Elson & Bennett 1979; Church, Jenkinson & Zavada 1979; Stover 2012 ch. 4; docs/physics.md §4.
    """
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    e = eps(wavelength_nm) if callable(eps) else eps
    lam = float(wavelength_nm)
    fr = np.hypot(wo[..., 0] + wi[..., 0], wo[..., 1] + wi[..., 1]) / lam
    q = rayleigh_rice_Q_pol(wi, wo, e, pol)
    f = 16.0 * np.pi ** 2 / lam ** 4 * wi[..., 2] * wo[..., 2] * q * psd(fr)
    return np.where((wi[..., 2] > 0) & (wo[..., 2] > 0), f, 0.0)


def rayleigh_rice_nano(psd, eps, pol="unpolarized"):
    """The Rayleigh-Rice lobe as a nano-lobe callable ``f_nano(wi, wo, wavelength_nm)`` (facet frame)."""
    def f_nano(wi, wo, wavelength_nm):
        return rayleigh_rice_brdf(wi, wo, wavelength_nm, psd, eps, pol)
    return f_nano


def rayleigh_rice_tis(theta_i_deg, wavelength_nm, psd, eps, pol="unpolarized", n_angle=128, n_gauss=8):
    """Total integrated scatter of the Rayleigh-Rice lobe, ∫ f cos θo dω_o over the hemisphere (deterministic
    quadrature, :func:`albedo_quadrature`). Returns (TIS, error estimate).

    In the narrow-lobe limit (correlation length ≫ λ) it tends to R(θi) (4π σ cos θi / λ)² (Davies 1954;
    Bennett & Porteus 1961; Stover 2012 ch. 4).
    """
    wi = direction(theta_i_deg)

    def f(a, b):
        return rayleigh_rice_brdf(a, b, wavelength_nm, psd, eps, pol)
    return albedo_quadrature(f, wi, n_angle, n_gauss)


def coherent_reflectance(theta_i_deg, wavelength_nm, sigma_nm, eps, pol="unpolarized"):
    """Specular (coherent) reflectance of a slightly rough surface: R_pol(θi) exp(−(4π σ cos θi / λ)²).

    References
    ----------
    H. Davies, Proc. IEE 101, 209 (1954); H. E. Bennett, J. O. Porteus, JOSA 51, 123 (1961); docs/physics.md §2.
    """
    c = np.cos(np.deg2rad(theta_i_deg))
    return fresnel_R(c, eps, pol) * np.exp(-(4.0 * np.pi * sigma_nm * c / wavelength_nm) ** 2)


def gaussian_nano(albedo, width):
    """A test nano lobe: a 2-D Gaussian of rms ``width`` (direction cosines, per axis) about the mirror direction in
    the facet frame, f = albedo · g(o_xy + i_xy): reciprocal, and its albedo ∫ f cos θo dω_o = ∫ f d²o_xy → ``albedo``
    as width → 0 (the projected solid angle is the area d²o_xy on the direction-cosine disc)."""
    def f_nano(wi, wo, wavelength_nm=None):
        wi, wo = np.asarray(wi, float), np.asarray(wo, float)
        d2 = (wo[..., 0] + wi[..., 0]) ** 2 + (wo[..., 1] + wi[..., 1]) ** 2
        g = np.exp(-0.5 * d2 / width ** 2) / (2.0 * np.pi * width ** 2)
        ok = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        return np.where(ok, albedo * g, 0.0)
    return f_nano
