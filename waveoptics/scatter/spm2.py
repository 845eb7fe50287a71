"""The coherent (mean) reflection and transmission of a slightly rough interface between two transparent media to
second order in the height: the second-order small-perturbation method (SPM2), docs/physics.md §15.

The interface z = h(x, y) separates the incidence medium (real index n₁, ε₁ = n₁², z > 0) from the other medium
(n₂, z < 0). The mean specular amplitudes of a random surface of isotropic PSD S(f) (two-sided, m⁴, ∫ S d²f = σ²)
are r̄ = r₀ + r₂ and t̄ = t₀ + t₂ for s and p light, with r₀, t₀ the Fresnel amplitudes and

    x₂ = k₀² [ 4 ∫ S(f) P_x(λ f) d²f + (σ² / 2) D_x ],        x ∈ {r, t},  k₀ = 2π / λ,

(the co-polarized mean amplitudes; the cross-polarized ones cancel between f and its mirror image f_y → −f_y).

Derivation (done here, from the boundary conditions; the same equations tests/rr_grating.py solves without
expanding). Each wave of the field is a plane wave of lateral wave vector Q (units of k₀) and normal wave number
g (γ₁ = √(ε₁ − |Q|²) above, −γ₂ below, Im γ ≥ 0), with the bases of tests/rr_grating.py: an s wave has
E = ŝ, H = k × ŝ = |Q| ẑ − g Q̂; a p wave E = (g Q̂ − |Q| ẑ) / n, H = n ŝ (ŝ = ẑ × Q̂, H in units of E / Z₀). On
z = h the tangential components E_t + (∇h) E_z and H_t + (∇h) H_z are continuous (tangents x̂ + h_x ẑ and
ŷ + h_y ẑ). For one Fourier component h = (a/2)(e^{iK·r} + e^{−iK·r}) (a and K in units of 1/k₀ and k₀),
e^{igh} = 1 + igh − g²h²/2 + O(a³): a wave of order Q adds at the harmonic Q + lK (l = ±1) the source

    (i a / 2) [g V_t + l K V_z],    V ∈ {E, H}          (first order),

and at its own harmonic −(g² a² / 4) V_t (second order; h ∇h has no constant term). Above minus below, the
tangential fields of the outgoing waves of one order balance a source (e, h) (tangential vectors) when

    r_s = (h·Q̂ − γ₂ e·ŝ) / (γ₁ + γ₂),             t_s = (h·Q̂ + γ₁ e·ŝ) / (γ₁ + γ₂),
    r_p = −n₁ (ε₂ e·Q̂ + γ₂ h·ŝ) / (ε₂ γ₁ + ε₁ γ₂),   t_p = (n₁ r_p + h·ŝ) / n₂

(:func:`match_flat`; the incident wave as the source gives Fresnel's r₀, t₀). The first-order amplitudes x₁ of
the order Q₀ + K are those of the source of the incident, reflected and transmitted waves of order Q₀
(l = +1); they return to the specular order with l = −1 and give P_x(K) per a²; the second-order source of the
order-0 waves gives D_x per a²/4. A grating of amplitude a thus changes the specular amplitude by
a² [P(K) + P(−K) + D/4], and a random surface (independent gratings of a_f² = 4 S(f) d²f on a half plane of f)
by the formula above. This is the second-order term of the Rayleigh-Rice expansion, as in Maradudin & Mills
1975 and Johnson 1999, written here for any azimuth of K (conical), both sides of the interface and beyond the
critical angle (evanescent γ₂). It holds to O((k₀ σ)²) and small slopes.

The specular losses are, to O(σ²) (the |x₂|² term is of fourth order):

    ΔR = R₀ − |r̄|² = −2 Re(r₀* r₂),    ΔT = T₀ − (γ₂/γ₁)|t̄|² = −2 (γ₂/γ₁) Re(t₀* t₂)   (0 beyond the critical
    angle, where γ₂ is imaginary),

and ΔR + ΔT is the first-order scatter TIS_R + TIS_T (the optical theorem; measured in tests/test_spm2.py against
:func:`waveoptics.scatter.rr_tis_reflection` and :func:`~waveoptics.scatter.rr_tis_transmission`, a different
route through Elson's dipole sheet).

Quadrature (:func:`loss_quadrature`, shared with :mod:`waveoptics.scatter.spm2_stack`, where each pair of rough
interfaces is one weighted term): f in polar coordinates (ρ = λ|f|, ψ from the plane of incidence);
Gauss-Legendre pieces in ρ cut at the Rayleigh anomalies (|Q₀ + K| = n₁ or n₂, a √ kink of P: on each ray the
roots of ρ² + 2ρκ cosψ + κ² = n²) and at multiples of the PSD's width λ / (π ℓ), each piece mapped by
3τ² − 2τ³ (whose Jacobian smooths a √ at both ends), and a last piece to ρ = ∞ (ρ = ρ_e / (1 − u)); in ψ on
[0, π] (the integrand is even in ψ), cut where a ray touches a circle and where a circle crosses a ring of the
radial cuts (near grazing incidence a circle passes close to the origin, where the PSD is), each piece mapped the
same way. At large |K| the loss kernels approach a(ψ) |K| + b(ψ) (the rest falls off as |K|⁻¹ or faster), with
a ∝ cosψ for p light (its integral over the azimuth vanishes for an isotropic PSD) and a = 0 for s: the integrand
carries the kernel less this asymptote, taken from two points at |K| = 10⁴ and 2 · 10⁴, and b is integrated
against S separately (σ² / (2π) times its ψ integral), so PSDs with slow algebraic tails (ABC with C near 2, whose
∫ S |f| d²f is infinite) converge. Where the slope's ψ integral does not vanish (a film of a stack,
:mod:`waveoptics.scatter.spm2_stack`) it is added against ∫ S |f| d²f (:func:`first_moment`), and refused where
that diverges. Converged to ≤ 1.3e-3 at the default nodes from 0° to 89.7°, ℓ from 50 nm to 10 µm,
n = 1.33 to 2.4, both sides (≤ 5e-4 below 85°; the worst at ℓ = 50 nm).

References
----------
.. [1] A. A. Maradudin, D. L. Mills, "Scattering and absorption of electromagnetic radiation by a semi-infinite
   medium in the presence of surface roughness", Phys. Rev. B 11(4), 1392–1415, 1975 (the mean field to second
   order).
.. [2] J. T. Johnson, "Third-order small-perturbation method for scattering from dielectric rough surfaces",
   J. Opt. Soc. Am. A 16(11), 2720–2736, 1999 (SPM to third order; the second-order mean field of a dielectric).
.. [3] Lord Rayleigh, "On the dynamical theory of gratings", Proc. R. Soc. Lond. A 79, 399–416, 1907 (the plane-wave
   expansion and boundary conditions expanded here).
.. [4] A. G. Voronovich, *Wave Scattering from Rough Surfaces*, 2nd ed., Springer 1999, §2.3 (small-perturbation
   method, mean field and the optical theorem).
.. [5] P. J. Davis, P. Rabinowitz, *Methods of Numerical Integration*, 2nd ed., Academic Press 1984, §2.7, §2.12
   (Gauss-Legendre; changes of variable that smooth endpoint singularities).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from ..errors import FieldError

__all__ = ["match_flat", "spm2_kernel", "PSD_TAIL_EXPONENTS", "tail_exponent", "radial_moment", "first_moment",
           "loss_quadrature",
           "coherent_losses", "SPM2_NODES", "K_LIMIT", "CHUNK_NODES"]

#: Gauss-Legendre nodes per piece of the radial (ρ) and azimuthal (ψ) quadrature of :func:`coherent_losses`
SPM2_NODES = (12, 10)

#: |K| (units of k₀) of the first of the two far points that give the kernels' asymptote a |K| + b
K_LIMIT = 1e4

#: nodes of the PSD plane per call of the kernels in :func:`loss_quadrature` (rays of ψ in chunks: bounded memory)
CHUNK_NODES = 1 << 15

#: the exponent C of each PSD family's tail S ∝ |f|^−C (∞: faster than any power; ABC: its own C)
PSD_TAIL_EXPONENTS = {"gaussian": math.inf, "exponential": 3.0}

#: breakpoints of the radial quadrature in units of the PSD width λ / (π ℓ) (a Gaussian PSD is e^{−36} at 6)
_PSD_BREAKS = (0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0)


def _basis(Q):
    """|Q|, Q̂ and ŝ = ẑ × Q̂ of lateral wave vectors Q (..., 2); Q̂ = x̂ where Q = 0."""
    kap = np.hypot(Q[..., 0], Q[..., 1])
    safe = np.where(kap > 0, kap, 1.0)
    kh = np.where((kap > 0)[..., None], Q / safe[..., None], np.array([1.0, 0.0]))
    return kap, kh, np.stack([-kh[..., 1], kh[..., 0]], axis=-1)


def _gamma(eps, kap):
    """Normal wave number √(ε − |Q|²) with Im ≥ 0 (decaying away from the interface)."""
    g = np.sqrt(eps - kap * kap + 0j)
    return np.where(g.imag < 0, -g, g)


def _wave(pol, g, n, kap):
    """A unit s or p plane wave of normal wave number g in a medium of index n, as the coefficients
    (E·ŝ, E·Q̂, E_z, H·ŝ, H·Q̂, H_z) in the basis of its order (module doc)."""
    if pol == "s":
        return 1.0, 0.0, 0.0, 0.0, -g, kap
    return 0.0, g / n, -kap / n, n, 0.0, 0.0


def _dot(a, b):
    """a · b of lateral vectors (..., 2)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]


def match_flat(es, ek, hs, hk, g1, g2, n1, n2):
    """Amplitudes (r_s, r_p, t_s, t_p) of the outgoing waves of one order (normal wave numbers *g1* above, *g2*
    below) whose tangential fields, above minus below, cancel a source of tangential fields e, h given by their
    components e·ŝ, e·Q̂, h·ŝ, h·Q̂ in the order's basis, on a flat interface between indices *n1* (above) and
    *n2* (module doc).

    References
    ----------
    .. [1] Module derivation (the s and p parts of the tangential boundary conditions decouple per order).
    """
    e1, e2 = n1 * n1, n2 * n2
    rp = -n1 * (e2 * ek + g2 * hs) / (e2 * g1 + e1 * g2)
    return (hk - g2 * es) / (g1 + g2), rp, (hk + g1 * es) / (g1 + g2), (n1 * rp + hs) / n2


def _order(Q, n1, n2):
    """|Q|, Q̂, ŝ, the normal wave numbers and the four outgoing waves (coefficients, g, sign: + above,
    − below) of order Q."""
    kap, kh, sh = _basis(Q)
    g1, g2 = _gamma(n1 * n1, kap), _gamma(n2 * n2, kap)
    waves = [(_wave("s", g1, n1, kap), g1, 1.0), (_wave("p", g1, n1, kap), g1, 1.0),
             (_wave("s", -g2, n2, kap), -g2, -1.0), (_wave("p", -g2, n2, kap), -g2, -1.0)]
    return kap, kh, sh, g1, g2, waves


def _source(terms, basis_from, K, l, basis_to):
    """First-order source (per a) at the harmonic shifted by l K of the waves *terms* ((coefficients, g, sign,
    amplitude)) of one order (basis ŝ, Q̂ *basis_from*): (i/2) Σ sign · amp · [g V_t + l K V_z] for V = E and H,
    as its components (e·ŝ, e·Q̂, h·ŝ, h·Q̂) in *basis_to*."""
    sums = [sum(s * a * (g * c[i] if i % 3 < 2 else c[i]) for c, g, s, a in terms) for i in range(6)]
    out = []
    for v in (basis_to[0], basis_to[1]):
        out.append([_dot(basis_from[0], v), _dot(basis_from[1], v), l * _dot(K, v)])
    (ss, ks, Ks), (sk, kk, Kk) = out
    es = 0.5j * (sums[0] * ss + sums[1] * ks + sums[2] * Ks)
    ek = 0.5j * (sums[0] * sk + sums[1] * kk + sums[2] * Kk)
    hs = 0.5j * (sums[3] * ss + sums[4] * ks + sums[5] * Ks)
    hk = 0.5j * (sums[3] * sk + sums[4] * kk + sums[5] * Kk)
    return es, ek, hs, hk


def spm2_kernel(kappa, K, n1, n2, pols=("s", "p")):
    """The second-order kernels of the specular amplitudes for light from the medium *n1* (above) onto *n2*.

    Parameters
    ----------
    kappa : float
        Lateral wave number of the incident wave, n₁ sinθ_i (units of k₀; along x).
    K : array_like (..., 2)
        Grating vectors (units of k₀).
    n1, n2 : float
        Real indices of the incidence medium and of the other one.
    pols : sequence of {'s', 'p'}
        Incident polarizations.

    Returns
    -------
    dict
        Per polarization (x0, P, D): the flat amplitudes (r_s, r_p, t_s, t_p) (scalars), the kernels P(K) (per a²,
        through the order Q₀ + K; arrays of K's shape) and D (per a²/4, the second-order source of the specular
        order; scalars); and ``g`` the specular order's normal wave numbers (γ₁, γ₂).

    References
    ----------
    .. [1] Maradudin & Mills 1975; Johnson 1999; Rayleigh 1907 (module doc: the derivation).
    """
    K = np.asarray(K, dtype=float)
    Q0 = np.array([float(kappa), 0.0])
    kap0, kh0, sh0, g10, g20, waves0 = _order(Q0, n1, n2)
    kap1, kh1, sh1, g11, g21, waves1 = _order(Q0 + K, n1, n2)
    b0, b1 = (sh0, kh0), (sh1, kh1)
    out = {"g": (g10, g20)}
    for pol in pols:
        inc = _wave(pol, -g10, n1, kap0)
        x0 = match_flat(inc[0], inc[1], inc[3], inc[4], g10, g20, n1, n2)   # the incident wave as the source
        terms0 = [(inc, -g10, 1.0, 1.0)] + [(c, g, s, x) for (c, g, s), x in zip(waves0, x0)]
        x1 = match_flat(*_source(terms0, b0, K, 1.0, b1), g11, g21, n1, n2)
        P = match_flat(*_source([(c, g, s, x) for (c, g, s), x in zip(waves1, x1)], b1, K, -1.0, b0), g10, g20,
                       n1, n2)
        diag = [sum(s * a * (-g * g) * c[i] for c, g, s, a in terms0) for i in (0, 1, 3, 4)]
        out[pol] = (x0, P, match_flat(*diag, g10, g20, n1, n2))
    return out


def _loss_kernels(kappa, K, n1, n2):
    """Per polarization (L_R, L_T, D_R, D_T): the integrands of ΔR, ΔT over f per unit S (without k₀²) and the
    diagonal terms per σ², of the co-polarized specular amplitudes; and the flat (R₀, T₀)."""
    ker = spm2_kernel(kappa, K, n1, n2)
    g1, g2 = ker["g"]
    cross = float(g2.real / g1.real) if abs(g2.imag) < 1e-12 else 0.0   # no transmitted power beyond θ_c
    out = {}
    for j, pol in enumerate(("s", "p")):
        x0, P, D = ker[pol]
        r0, t0 = np.conj(x0[j]), np.conj(x0[j + 2])
        out[pol] = (-8.0 * np.real(r0 * P[j]), -8.0 * cross * np.real(t0 * P[j + 2]), -float(np.real(r0 * D[j])),
                    -cross * float(np.real(t0 * D[j + 2])), float(abs(r0) ** 2), cross * float(abs(t0) ** 2))
    return out


def _smooth_gl(n):
    """Nodes τ and weights of ∫₀¹ dτ after τ = 3u² − 2u³ (u Gauss-Legendre on [0, 1])."""
    x, w = np.polynomial.legendre.leggauss(n)
    u, wu = 0.5 * (x + 1.0), 0.5 * w
    return u * u * (3.0 - 2.0 * u), wu * 6.0 * u * (1.0 - u)


def _psi_pieces(kappa, indices, widths):
    """Cuts of ψ ∈ [0, π]: where a ray from the origin touches a circle |Q₀ + K| = n (κ > n), and where a circle
    crosses a ring of the radial cuts at the PSDs' scales (ρ = b · width): cosψ = (n² − κ² − ρ²) / (2 ρ κ)."""
    cuts = [math.pi - math.asin(n / kappa) for n in indices if kappa > n]
    for n in indices:
        for rho in (b * width for width in widths for b in _PSD_BREAKS):
            c = (n * n - kappa * kappa - rho * rho) / (2.0 * rho * kappa) if kappa > 0 else 2.0
            if -1.0 < c < 1.0:
                cuts.append(math.acos(c))
    return [0.0] + sorted(set(c for c in cuts if 0.0 < c < math.pi)) + [math.pi]


def _pole_radius(kappa, psi, pole):
    """ρ where the ray ψ from K = 0 meets the circle |Q₀ + K| = *pole* (> κ: one crossing on every ray)."""
    return -kappa * np.cos(psi) + np.sqrt(pole * pole - (kappa * np.sin(psi)) ** 2)


def _rho_breaks(kappa, psi, indices, widths, poles=()):
    """Radial cuts (n_psi, n_cut) on each ray ψ: the Rayleigh anomalies and the PSDs' scales, sorted (0 where a
    circle misses the ray: zero-width pieces); and for each pole circle (a guided mode, |Q₀ + K| = κ_m > κ) a
    window ρ_m ± h symmetric about its crossing (h half the distance to the nearest other cut), whose nodes and
    weights are symmetric about ρ_m: the principal value of the pole's 1 / (ρ − ρ_m) term sums to 0 there."""
    cos, sin = np.cos(psi), np.sin(psi)
    cols = [np.full(psi.shape, b * width) for width in widths for b in _PSD_BREAKS]
    for n in indices:
        disc = np.sqrt(np.maximum(n * n - (kappa * sin) ** 2, 0.0))
        roots = (-kappa * cos - disc, -kappa * cos + disc) if kappa > n else (-kappa * cos + disc,)
        cols += [np.where((root > 0) & (n * n >= (kappa * sin) ** 2), root, 0.0) for root in roots]
    base = np.stack([np.zeros(psi.shape)] + cols, axis=-1)
    roots = [_pole_radius(kappa, psi, pole) for pole in poles]
    for i, root in enumerate(roots):
        others = np.concatenate([base] + [r[:, None] for k, r in enumerate(roots) if k != i], axis=-1)
        below = np.max(np.where(others < root[:, None], others, 0.0), axis=-1)
        above = np.min(np.where(others > root[:, None], others, np.inf), axis=-1)
        h = 0.5 * np.minimum(root - below, above - root)
        cols += [root - h, root + h]
    return np.sort(np.stack(cols, axis=-1), axis=-1)


def _nodes(kappa, indices, widths, nodes, poles=()):
    """ψ nodes and weights (n_psi,) on [0, π] and ρ nodes and weights (n_psi, n) on [0, ∞) (module doc)."""
    n_rho, n_psi = nodes
    t_p, w_p = _smooth_gl(n_psi)
    cuts = _psi_pieces(kappa, tuple(indices) + tuple(poles), widths)
    psi = np.concatenate([lo + (hi - lo) * t_p for lo, hi in zip(cuts[:-1], cuts[1:])])
    w_psi = np.concatenate([(hi - lo) * w_p for lo, hi in zip(cuts[:-1], cuts[1:])])
    edges = np.concatenate([np.zeros((psi.size, 1)), _rho_breaks(kappa, psi, indices, widths, poles)], axis=-1)
    t_r, w_r = _smooth_gl(n_rho)
    span = (edges[:, 1:] - edges[:, :-1])[..., None]
    rho = (edges[:, :-1, None] + span * t_r).reshape(psi.size, -1)
    w_rho = (span * w_r).reshape(psi.size, -1)
    x, w = np.polynomial.legendre.leggauss(n_rho)
    u, wu = 0.5 * (x + 1.0), 0.5 * w
    end = edges[:, -1:]
    rho = np.concatenate([rho, end / (1.0 - u)], axis=-1)              # the last piece, to ρ = ∞
    w_rho = np.concatenate([w_rho, end * wu / (1.0 - u) ** 2], axis=-1)
    return psi, w_psi, rho, w_rho


def tail_exponent(psd):
    """The exponent C of a PSD's tail S ∝ |f|^−C (:data:`PSD_TAIL_EXPONENTS`; ABC: its C), None when unknown.

    References
    ----------
    .. [1] E. L. Church, P. Z. Takacs, "The optimal estimation of finish parameters", Proc. SPIE 1530, 71–85, 1991
       (the ABC, K-correlation, PSD and its f^−C tail).
    """
    if getattr(psd, "kind", None) == "abc":
        return float(psd.C)
    return PSD_TAIL_EXPONENTS.get(getattr(psd, "kind", None))


def radial_moment(W, power, exponent, length):
    """∫ W(|f|) |f|^*power* d²f (m^(2 − power)) of a weight W (m⁴ at |f| in 1/m) whose tail falls as
    |f|^−*exponent*, with a correlation *length* (m) to scale the integral (x = |f| ℓ, split at 1, relative
    accuracy 1e-10); None where it diverges (exponent ≤ 2 + power, or unknown).

    References
    ----------
    .. [1] R. Piessens et al., *QUADPACK*, Springer 1983 (adaptive Gauss-Kronrod quadrature on [0, 1] and
       [1, ∞)).
    """
    if exponent is None or exponent <= 2.0 + power:
        return None
    ell = float(length)

    def integrand(x):
        return 2.0 * math.pi * x ** (1 + power) * W(x / ell)

    total = sum(integrate.quad(integrand, lo, hi, limit=200, epsabs=0.0, epsrel=1e-10)[0]
                for lo, hi in ((0.0, 1.0), (1.0, np.inf)))
    return total / ell ** (2 + power)


def first_moment(W, exponent, length):
    """∫ W |f| d²f (m) of :func:`radial_moment`; None where it diverges (tail exponent ≤ 3 or unknown).

    References
    ----------
    .. [1] R. Piessens et al., *QUADPACK*, Springer 1983.
    """
    return radial_moment(W, 1, exponent, length)


def _slope_term(terms, slope, scale, w_psi, lam):
    """λ Σ_t M_t ∫ a_t(ψ) dψ / (2π): the kernels' far slope a(ψ) |K| against the first moments M_t (the
    integrand carries the kernel less a |K|), where ∫ a dψ is more than 1e-6 of ∫ |a| dψ (not a cosψ that
    averages out) and of the kernels' median size *scale* (n_terms, n_losses) per unit |K|; FieldError where such
    a term meets a divergent moment."""
    mean = 2.0 * np.einsum("a,tla->tl", w_psi, slope)                    # ∫ a dψ over [0, 2π]
    noise = 1e-6 * np.maximum(2.0 * np.einsum("a,tla->tl", w_psi, np.abs(slope)), 2.0 * math.pi * scale)
    significant = np.abs(mean) > noise
    out = np.zeros(slope.shape[1])
    for t, (_, _, _, moment) in enumerate(terms):
        if not np.any(significant[t]):
            continue
        if moment is None:
            raise FieldError("{psd}: the losses grow as ∫ S |f| d²f at high frequencies (|K| a(ψ) with a "
                             "non-zero azimuthal mean), which diverges for this PSD's tail (S ∝ |f|^−C, C <= 3): "
                             "ΔR and ΔT separately are not finite to second order", "psd")
        out += np.where(significant[t], moment * lam * mean[t] / (2.0 * math.pi), 0.0)
    return out


def loss_quadrature(kappa, indices, wavelength_nm, terms, loss_kernels, nodes=SPM2_NODES, poles=(),
                    residues=None) -> dict:
    """k₀² Σ_t ∫ W_t(f) L_t(λ f) d²f over the plane of spatial frequencies f for kernels L_t even in ψ (the
    quadrature of the module doc, shared by :func:`coherent_losses` and
    :func:`waveoptics.scatter.stack_coherent_losses`).

    Parameters
    ----------
    kappa : float
        Lateral wave number of the incident wave (units of k₀; along x).
    indices : sequence of float
        Real indices of the two half-spaces (the Rayleigh anomalies |Q₀ + K| = n are cut).
    wavelength_nm : float, nm
        Vacuum wavelength.
    terms : sequence of (W, integral, lengths, moment)
        Per term t: the weight W_t(|f|) (m⁴ at |f| in 1/m: a PSD, or c_jk √(S_j S_k)), its integral ∫ W_t d²f (m²),
        one length or a tuple of lengths ℓ (m) whose widths λ / (π ℓ) place the radial cuts, and its first
        moment ∫ W_t |f| d²f (m; :func:`first_moment`), None where it diverges: then the kernels' slope a(ψ)
        must integrate to 0 over ψ (a ∝ cosψ, one interface), else FieldError.
    loss_kernels : callable
        ``loss_kernels(K)`` for grating vectors K (..., 2) (units of k₀): a dict of polarizations, each an array
        (n_terms, n_losses, ...) of kernels per a² (the integrand per unit W without k₀²).
    nodes : (int, int)
        Gauss-Legendre nodes per piece in ρ and in ψ.
    poles : sequence of float
        Lateral wave numbers κ_m (units of k₀, each > κ) of circles |Q₀ + K| = κ_m where the kernels have a
        simple pole 1 / (ρ − ρ_m − i0) on each ray (guided modes): integrated as a principal value (a window
        symmetric about ρ_m) plus *residues*.
    residues : callable
        ``residues(pole, K_m)`` at the poles' crossings K_m (n_psi, 2): a dict of polarizations, each an array
        (n_terms, n_losses, n_psi) of the δ(ρ − ρ_m) weights of the kernels (per unit W without k₀²).

    Returns
    -------
    dict
        Per polarization, an array (n_losses,) of the integrals (dimensionless).

    References
    ----------
    .. [1] Davis & Rabinowitz 1984 (Gauss-Legendre pieces, smoothing changes of variable); module doc (the
       asymptote a(ψ) |K| + b(ψ) subtracted and b integrated against ∫ W d²f).
    """
    lam = float(wavelength_nm) * 1e-9
    k0 = 2.0 * math.pi / lam
    widths = tuple(sorted({lam / (math.pi * float(ell)) for _, _, lengths, _ in terms
                           for ell in np.atleast_1d(lengths)}))
    psi, w_psi, rho, w_rho = _nodes(kappa, indices, widths, nodes, poles)
    direction = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
    K = rho[..., None] * direction[:, None, :]
    weights = np.stack([2.0 * w_psi[:, None] * w_rho * rho * W(rho / lam) / lam ** 2 for W, _, _, _ in terms])
    integrals = np.array([float(i) for _, i, _, _ in terms])
    far = [loss_kernels(k * direction) for k in (K_LIMIT, 2.0 * K_LIMIT)]
    # the kernel's asymptote a(ψ) |K| + b(ψ) from two far points
    slope = {pol: (far[1][pol] - far[0][pol]) / K_LIMIT for pol in far[0]}
    limit = {pol: far[0][pol] - slope[pol] * K_LIMIT for pol in far[0]}
    inner = {pol: 0.0 for pol in far[0]}
    scale = {pol: 0.0 for pol in far[0]}
    step = max(1, CHUNK_NODES // rho.shape[1])
    for rows in (slice(i, i + step) for i in range(0, psi.size, step)):     # bounded memory
        for pol, values in loss_kernels(K[rows]).items():
            loss = values - slope[pol][..., rows, None] * rho[rows] - limit[pol][..., rows, None]
            inner[pol] = inner[pol] + np.einsum("tab,tlab->l", weights[:, rows], loss)
            # the kernels' size: the median, which a node next to a guided mode's pole does not move
            scale[pol] = np.maximum(scale[pol], np.median(np.abs(values), axis=(-2, -1)))
    delta = []
    for pole in poles:
        rho_m = _pole_radius(kappa, psi, pole)
        w_m = np.stack([2.0 * w_psi * rho_m * W(rho_m / lam) / lam ** 2 for W, _, _, _ in terms])
        delta.append((w_m, residues(pole, rho_m[:, None] * direction)))
    out = {}
    for pol in far[0]:
        tail = integrals @ (2.0 * np.einsum("a,tla->tl", w_psi, limit[pol])) / (2.0 * math.pi)
        tail = tail + _slope_term(terms, slope[pol], scale[pol], w_psi, lam)
        pole_terms = sum(np.einsum("ta,tla->l", w_m, res[pol]) for w_m, res in delta)
        out[pol] = k0 ** 2 * (inner[pol] + tail + pole_terms)
    return out


def coherent_losses(mu, n_i, n_o, psd, wavelength_nm, nodes=SPM2_NODES) -> dict:
    """The second-order losses of the specular reflectance and transmittance of a random rough interface (SPM2,
    module doc) for light at incidence cosine *mu* from the medium of index *n_i* onto *n_o*.

    Parameters
    ----------
    mu : float
        cosθ_i in the incidence medium, in (0, 1].
    n_i, n_o : float
        Real indices of the incidence medium and of the other one.
    psd : PSDModel
        Isotropic height statistics (``S(f)`` in m⁴ at |f| in 1/m, ``sigma`` in m, ``length_scale`` in m).
    wavelength_nm : float, nm
        Vacuum wavelength.
    nodes : (int, int)
        Gauss-Legendre nodes per piece in ρ and in ψ.

    Returns
    -------
    dict
        ``R0``, ``T0`` (the flat interface's specular reflectance and transmittance) and ``dR``, ``dT`` (their
        second-order losses R₀ − |r̄|², T₀ − (γ₂/γ₁)|t̄|², dimensionless), each a dict of 's' and 'p'.

    References
    ----------
    .. [1] Maradudin & Mills 1975; Johnson 1999 (module doc); Davis & Rabinowitz 1984 (the quadrature).
    """
    mu, n_i, n_o = float(mu), float(n_i), float(n_o)
    if not 0.0 < mu <= 1.0:
        raise FieldError(f"{{mu}} {mu!r} is not allowed; the incidence cosine must lie in (0, 1]", "mu")
    for name, n in (("n_i", n_i), ("n_o", n_o)):
        if not (np.isfinite(n) and n > 0):
            raise FieldError(f"{{{name}}} {n!r} is not allowed; the media must be transparent (a real index > 0)",
                             name)
    if not (np.isfinite(float(wavelength_nm)) and float(wavelength_nm) > 0):
        raise FieldError(f"{{wavelength_nm}} {wavelength_nm!r} is not allowed; it must be > 0 nm", "wavelength_nm")
    lam = float(wavelength_nm) * 1e-9
    k0 = 2.0 * math.pi / lam
    kappa = n_i * math.sqrt(max(1.0 - mu * mu, 0.0))
    sigma2 = float(psd.sigma) ** 2

    def kernels(K):
        ker = _loss_kernels(kappa, K, n_i, n_o)
        return {pol: np.stack(ker[pol][:2])[None] for pol in ("s", "p")}

    # one interface: the kernels' far slope a(ψ) ∝ cos ψ integrates to 0 over ψ (module doc), so its moment never
    # enters; 0 in place of ∫ S |f| d²f keeps a PSD whose moment diverges (ABC C <= 3) from tripping the films'
    # check on the rounding of a(ψ) where every kernel is ~1e-11 (grazing light from the glass)
    integrals = loss_quadrature(kappa, (n_i, n_o), wavelength_nm, [(psd.S, sigma2, psd.length_scale, 0.0)],
                                kernels, nodes)
    flat = _loss_kernels(kappa, np.zeros(2), n_i, n_o)
    out = {k: {} for k in ("R0", "T0", "dR", "dT")}
    for pol in ("s", "p"):
        for i, key in enumerate(("dR", "dT")):
            out[key][pol] = float(integrals[pol][i]) + k0 ** 2 * sigma2 * flat[pol][i + 2]
        out["R0"][pol], out["T0"][pol] = flat[pol][4], flat[pol][5]
    return out
