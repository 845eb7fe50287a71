"""The coherent (mean) reflection and transmission of a thin-film stack with slightly rough interfaces, to second
order in the heights (SPM2 of a layered medium), light from the air or from inside the (transparent) substrate.

Geometry: media m = 0 … M from the exit half-space (m = 0) up to the incidence half-space (m = M); interface j
(j = 0 … M − 1) lies between medium j below and medium j + 1 above at height z_j + h_j(x, y); films are the media
1 … M − 1 (thicknesses d_m, complex indices allowed), the half-spaces are transparent (real indices). Light from
the air (``from_above``) takes the stack as :func:`waveoptics.scatter.stack_layers` lists it (substrate first);
light from the substrate takes it upside down (heights change sign, which a quadratic form in them does not see).

Derivation (the one of :mod:`waveoptics.scatter.spm2` for one interface, carried through the layers). Each
Fourier order of lateral wave vector Q (units of k₀; κ = |Q|, basis ŝ = ẑ × Q̂, Q̂) carries in every medium an s
and a p field. Both are described by two quantities continuous across a flat interface, the ones Abelès' matrices
propagate (Born & Wolf §1.6.2): for s, U = E·ŝ and V = −H·Q̂; for p, U = H·ŝ and V = E·Q̂ (H in units of E / Z₀,
the wave bases of spm2). In a medium of permittivity ε with q = √(ε − κ²) Maxwell's equations give

    s:  ∂_z E_t = i V ŝ,                ∂_z H_t = −i q² U Q̂,      E_z = 0,          H_z = κ U,
    p:  ∂_z E_t = i (q²/ε) U Q̂,        ∂_z H_t = i ε V ŝ,         E_z = −κ U / ε,   H_z = 0.

On z = z_j + h_j the tangential E_t + (∇h) E_z and H_t + (∇h) H_z are continuous. For h_j = (a_j/2)(e^{iK·r} +
e^{−iK·r}) the fields at z_j + h expand as V + h ∂_z V + (h²/2) ∂_z² V. A field of order Q thus adds at the order
Q' = Q + lK (l = ±1) the source (per a_j) e = ½ [∂_z E_t + i lK E_z], h = ½ [∂_z H_t + i lK H_z] taken above minus
below; with q² = ε − κ² and κQ̂ + lK = κ'Q̂' its components in the basis of Q' are (ŝ, Q̂ of Q; ŝ', Q̂' of Q')

    e·ŝ' = (i/2) ⟦V_s ŝ·ŝ' + U_p Q̂·ŝ'⟧,      e·Q̂' = (i/2) ⟦V_s ŝ·Q̂' + U_p Q̂·Q̂' − κκ' U_p / ε⟧,
    h·ŝ' = (i/2) ⟦ε V_p ŝ·ŝ' − ε U_s Q̂·ŝ'⟧,  h·Q̂' = (i/2) ⟦ε V_p ŝ·Q̂' − ε U_s Q̂·Q̂' + κκ' U_s⟧

(⟦·⟧: above minus below, each side with its own ε and its own field), and the flat stack answers with the field
of order Q' whose jump at z_j is minus the source: ⟦U_s⟧ = −e·ŝ', ⟦V_s⟧ = h·Q̂', ⟦U_p⟧ = −h·ŝ', ⟦V_p⟧ = −e·Q̂'.
For the continuous field of the flat stack (the incident order) the jumps reduce to Δε E_t and Δ(1/ε) D_z, the
dipole sheet of Elson (1984) and of :mod:`waveoptics.scatter.rough_film`. At the specular harmonic h_j² adds
(a_j²/4) ⟦∂_z² V_t⟧ = −(a_j²/4) ⟦q² V_t⟧ (h ∇h has no constant term), whose flat-stack answer is the jump
(ε_{j+1} − ε_j)(U, V) of the incident order's field at z_j. One grating on every interface changes the specular
amplitudes by Σ_jk a_j a_k [P_jk(K) + P_jk(−K)] + Σ_j (a_j²/4) D_j, where P_jk is the order Q₀ + K excited at
interface k (l = +1) and returned to the specular order at interface j (l = −1, each source with its ½), and a
random surface with ⟨H_j H_k*⟩ = S_jk = c_jk √(S_j S_k) by

    x₂ = k₀² [ 4 Σ_jk c_jk ∫ √(S_j S_k) P_jk(λ f) d²f + Σ_j (σ_j² / 2) D_j ],        x ∈ {r, t},

with ΔR = −2 Re(r₀* r₂) and ΔT = −2 (γ₀/γ_M) Re(t₀* t₂) (0 when the exit medium's γ₀ is imaginary) as for one
interface. For no films this is spm2's kernel (tests/test_spm2_stack.py: to 1e-12); two interfaces at zero
distance telescope into the one between their outer media.

The flat stack's answer to a jump (ΔU, ΔV) at interface j: below it the field goes out downwards, V = Y↓_j U,
above it upwards, V = Y↑_j U, so U⁻ = (ΔV − Y↑ ΔU) / (Y↑ − Y↓), U⁺ = U⁻ + ΔU. The admittances come from the
characteristic matrix [[cos β, i sin β / η], [i η sin β, cos β]] of each film (β = k₀ q d, η = q (s) or q / ε
(p)) acting on V = Y U, written with e^{2iβ} (|e^{2iβ}| ≤ 1 for Im q ≥ 0) so that nothing grows:

    Y↓_{j} = (Y↓_{j−1} (1 + e^{2iβ}) − η (1 − e^{2iβ})) / ((1 + e^{2iβ}) − (1 − e^{2iβ}) Y↓_{j−1} / η),
    Y↓_0 = −η_0,  Y↑_{M−1} = η_M,  Y↑ likewise downwards with the signs of the inverse matrix,

and the field is carried away from the source by U_{j−1} = U_j 2 e^{iβ} / ((1 + e^{2iβ}) − (1 − e^{2iβ}) Y↓_{j−1}
/ η) (and upwards alike): the decaying direction only, stable for absorbing films and evanescent orders
(Rouard's recurrence in admittance form; (1 − e^{2iβ}) / q is taken with expm1, finite at q = 0). The incident
order: U = u 2 η_M / (η_M − Y↓_{M−1}) at the top interface (u = 1 for s, n_M for p), r₀ = (η_M + Y↓) / (η_M − Y↓).

Guided modes: where Y↑_j = Y↓_j for a real |Q| the flat stack has a mode (a film above both half-spaces' indices,
or a surface plasmon on a film of Re ε < 0) and P_jk a simple pole on the integration range (every |Q₀ + K| ≥ 0
occurs). :func:`guided_modes` finds them as the real roots κ_m of the mode condition of the stack without its
absorption (sign changes of Im(η_M U − V) of the bottom half-space's decaying field carried to the top with the
characteristic matrices, normalized per layer; Brent's method). A lossless stack's pole is approached from the
causal side: a small absorption moves κ_m to Im κ_m > 0, and Q₀ lies inside the circle |Q₀ + K| = κ_m (κ₀ < the
half-spaces' indices < κ_m), so every ray of K crosses it once outwards, dκ/dρ > 0, and the pole is
A / (ρ − ρ_m − i0) = A [P 1/(ρ − ρ_m) + iπ δ(ρ − ρ_m)] (Sokhotski-Plemelj): the principal value on a window
symmetric about ρ_m (its 1/(ρ − ρ_m) part sums to 0 on symmetric nodes) plus 8π Im(x₀* A) at ρ_m, with A from
two points ρ_m (1 ± 10⁻⁷). This is the power the roughness couples into the guided modes, lost to the specular
beams: ΔR + ΔT exceeds the first-order TIS_R + TIS_T into the half-spaces by it (4 % to 200 % for a 150 nm film
of index 2 on glass, ℓ = 0.3 µm). Measured against the absorbing limit (tests/test_spm2_stack.py: the
film with ε + iη, brute-force quadrature through each mode's Lorentzian, η → 0) within 3.3e-6. An absorbing stack
with such a mode (a pole just off the axis, a Lorentzian the quadrature does not resolve) is refused by name.

Far field of the kernels: at large |K| the s kernels of a film grow as a(ψ) |K| with a non-zero azimuthal mean,
ΔR up and ΔT down by the same (checked against the rigorous film grating up to |K| = 60 k₀), unlike one interface
where a ∝ cosψ averages out. The quadrature therefore adds λ ∫ a dψ / (2π) times ∫ S |f| d²f
(:func:`waveoptics.scatter.first_moment`); for PSD tails S ∝ |f|^−C with C ≤ 3 (exponential, ABC with C ≤ 3)
that moment diverges and ΔR, ΔT are refused (their sum, the total loss, stays finite).

Optical theorem: without guided modes, ΔR + ΔT equals the first-order TIS_R + TIS_T of
:func:`waveoptics.scatter.rough_stack_tis_sides` (the stack's BSDF over both hemispheres, another route) within
8.1e-6 (one and two films, correlated, uncorrelated and c = 0.5, both sides, beyond the critical angle).

Quadrature: :func:`waveoptics.scatter.loss_quadrature` of spm2 (cuts at the half-spaces' light cones, where the
kernels have their √ kinks: the films' q enter only through entire functions of q²; the PSDs' widths; the far
asymptote a |K| + b subtracted per interface pair; each pair of PSDs one weighted term c_jk √(S_j S_k)). Against
a brute-force polar sum of the same kernels within 1.8e-9 (one film, Gaussian ℓ = 0.3 µm). The kernels' structure
in |K| (Fabry-Perot and leaky-mode peaks) narrows with the films' optical thickness: the nodes per piece grow as
:func:`node_scale` (⌈H/2⌉ for H half-waves; converged to 3.3e-6 for a 1 µm MgF₂ film, 2.2e-4 without), and stacks
beyond :data:`MAX_HALF_WAVES` are refused. One call (default nodes, min of 3 under load): 14 ms for one film
from the air, 20 ms from the glass, 26 ms for two films, 34 ms with two guided modes, 2 s for a 1 µm film with
eight. Where it holds: O((k₀ σ_j)²) and small slopes at every interface.

References
----------
.. [1] A. A. Maradudin, D. L. Mills, Phys. Rev. B 11(4), 1392–1415, 1975 (the mean field of a rough
   semi-infinite medium to second order in the height).
.. [2] J. T. Johnson, J. Opt. Soc. Am. A 16(11), 2720–2736, 1999 (the small-perturbation method of a dielectric
   rough surface to third order; its second-order mean field).
.. [3] J. M. Elson, "Theory of light scattering from a rough surface with an inhomogeneous dielectric
   permittivity", Phys. Rev. B 30(10), 5460–5480, 1984 (first-order sources Δε E_t, Δ(1/ε) D_z of a displaced
   boundary in a stratified medium).
.. [4] J. M. Elson, "Multilayer-coated optics: guided-wave coupling and scattering by means of interface random
   roughness", J. Opt. Soc. Am. A 12(4), 729–742, 1995 (the guided-mode poles of a rough stack).
.. [5] M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge 1999, §1.6.2 (characteristic matrix);
   F. Abelès, Ann. Phys. (Paris) 12(5), 596–640, 1950.
.. [6] O. S. Heavens, *Optical Properties of Thin Solid Films*, Butterworths 1955, §4.3 (Rouard's recurrence).
.. [7] D. Marcuse, *Theory of Dielectric Optical Waveguides*, Academic Press 1974, §1.3 (slab modes, cut-off).
.. [8] W. Appel, *Mathematics for Physics and Physicists*, Princeton 2007, §8.1 (the Sokhotski-Plemelj formula).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ..errors import FieldError
from .rough_film import cross_psd_weights, interface_psd_list, stack_layers
from .rough_film_sides import TRANSPARENT_K, substrate_is_transparent
from .spm2 import SPM2_NODES, first_moment, loss_quadrature, radial_moment, tail_exponent

__all__ = ["GUIDED_SAMPLES", "stack_media", "flat_stack", "stack_response", "stack_amplitudes", "stack_loss_kernels", "node_scale", "MAX_HALF_WAVES", "guided_modes",
           "stack_coherent_losses"]

#: the most half-waves of optical thickness Σ Re(n_m) d_m / (λ/2) of a stack's films that the quadrature takes (its
#: nodes grow with the thickness, :func:`node_scale`)
MAX_HALF_WAVES = 12

#: samples of |Q| (quadratically crowded towards the half-spaces' index) in the search of :func:`guided_modes`
GUIDED_SAMPLES = 4000


def _q(eps, kappa):
    """q = √(ε − κ²) on the branch Im q ≥ 0."""
    q = np.sqrt(eps - kappa * kappa + 0j)
    return np.where(q.imag < 0, -q, q)


def stack_media(stack_or_layers, wavelength_nm, from_above=True):
    """(ε of the media from the exit half-space up to the incidence one, k₀ d of the films in that order, the
    interfaces' order: index into the substrate-first interfaces of :func:`waveoptics.scatter.stack_layers`); a
    substrate with k ≤ :data:`~waveoptics.scatter.TRANSPARENT_K` n taken with its real index (FieldError beyond).

    References
    ----------
    .. [1] Born & Wolf §1.6 (the stratified medium).
    """
    eps, d = stack_layers(stack_or_layers, float(wavelength_nm))
    if not substrate_is_transparent(eps[0]):
        raise FieldError(f"{{stack}}: the substrate must be transparent (k <= {TRANSPARENT_K} n); its ε is "
                         f"{complex(eps[0])!r}", "stack")
    eps = [complex(np.sqrt(complex(eps[0])).real ** 2)] + [complex(e) for e in eps[1:]]
    kd = [2.0 * math.pi * x / float(wavelength_nm) for x in d]
    order = list(range(len(eps) - 1))
    if not from_above:
        eps, kd, order = eps[::-1], kd[::-1], order[::-1]
    return eps, kd, order


def flat_stack(kappa, eps, kd, pol):
    """The flat stack for one order (lateral wave number *kappa*, array) and polarization: a dict of the media's
    ``eta`` (q or q/ε), the admittances ``down`` (Y↓_j) and ``up`` (Y↑_j) per interface and the carrying factors
    ``td`` (U_j = td_j U_{j+1}) and ``tu`` (U_{j+1} = tu_j U_j) of a field going out of a source (module doc).

    References
    ----------
    .. [1] Born & Wolf §1.6.2 (characteristic matrix); Heavens 1955 §4.3 (Rouard's recurrence).
    """
    kappa = np.asarray(kappa, dtype=float)
    q = [_q(e, kappa) for e in eps]
    eta = q if pol == "s" else [qm / e for qm, e in zip(q, eps)]
    n_if = len(eps) - 1
    e1, c, a, b = [None] * (n_if + 1), [None] * (n_if + 1), [None] * (n_if + 1), [None] * (n_if + 1)
    for m in range(1, n_if):
        beta = q[m] * kd[m - 1]
        e1[m] = np.exp(1j * beta)
        small = q[m] == 0
        # (1 − e^{2iβ}) / q, finite at q = 0 (the film's light cone)
        ratio = np.where(small, -2j * kd[m - 1], -np.expm1(2j * beta) / np.where(small, 1.0, q[m]))
        c[m] = 1.0 + e1[m] * e1[m]
        a[m] = ratio if pol == "s" else eps[m] * ratio                       # (1 − e^{2iβ}) / η
        b[m] = q[m] * q[m] * ratio * (1.0 if pol == "s" else 1.0 / eps[m])  # η (1 − e^{2iβ})
    down = [-eta[0]]
    for m in range(1, n_if):
        y = down[-1]
        down.append((y * c[m] - b[m]) / (c[m] - a[m] * y))
    up = [eta[n_if]]
    for m in range(n_if - 1, 0, -1):
        y = up[0]
        up.insert(0, (y * c[m] + b[m]) / (c[m] + a[m] * y))
    td = [2.0 * e1[j + 1] / (c[j + 1] - a[j + 1] * down[j]) for j in range(n_if - 1)]
    tu = [2.0 * e1[j + 1] / (c[j + 1] + a[j + 1] * up[j + 1]) for j in range(n_if - 1)]
    return {"eta": eta, "down": down, "up": up, "td": td, "tu": tu}


def stack_response(flat, k, dU, dV):
    """The flat stack's field of one order and polarization that jumps by (*dU*, *dV*) at interface *k*: per
    interface j, (U, V) above and (U, V) below it (module doc).

    References
    ----------
    .. [1] Module derivation (the outgoing fields on either side of the source).
    """
    up, down = flat["up"][k], flat["down"][k]
    u_below = (dV - up * dU) / (up - down)
    u_above = u_below + dU
    out = [None] * len(flat["up"])
    out[k] = (u_above, up * u_above, u_below, down * u_below)
    u = u_below
    for j in range(k - 1, -1, -1):
        u = flat["td"][j] * u
        out[j] = (u, flat["down"][j] * u) * 2
    u = u_above
    for j in range(k + 1, len(out)):
        u = flat["tu"][j - 1] * u
        out[j] = (u, flat["up"][j] * u) * 2
    return out


def _excite(field, eps_a, eps_b, kap, kap_t, cx, cy):
    """The jumps (ΔU_s, ΔV_s, ΔU_p, ΔV_p) of the order Q₀ + K (Q̂' = (cx, cy)) answering the first-order source
    (per a) of the incident order's continuous field *field* (U_s, V_s, U_p, V_p) across an interface of ε
    *eps_a* over *eps_b*: the general jumps (module doc) with ⟦V_s⟧ = ⟦U_p⟧ = 0, i.e. Δε E_t and Δ(1/ε) D_z."""
    us, vs, up, vp = field
    de = 0.5j * (eps_a - eps_b)
    return 0.0, de * (vp * cy - us * cx), -de * (vp * cx + us * cy), 0.5j * (1.0 / eps_a - 1.0 / eps_b) * kap * kap_t * up


def _return(above, below, eps_a, eps_b, kap_t, kap, cx, cy, pol):
    """The specular order's jumps (ΔU, ΔV) of polarization *pol* answering the first-order source (per a) of
    the field of order Q₀ + K (Q̂ = (cx, cy)) with sides *above*, *below* ((U_s, V_s, U_p, V_p) each) across an
    interface of ε *eps_a* over *eps_b* (module doc: ŝ·ŝ' = Q̂·Q̂' = cx, Q̂·ŝ' = cy, ŝ·Q̂' = −cy); a field
    continuous there (the same arrays on both sides) jumps only through Δε and Δ(1/ε)."""
    if all(a is b for a, b in zip(above, below)):
        us, vs, up, vp = above
        if pol == "s":
            return 0.0, 0.5j * (eps_a - eps_b) * (-vp * cy - us * cx)
        return -0.5j * (eps_a - eps_b) * (vp * cx - us * cy), 0.5j * (1.0 / eps_a - 1.0 / eps_b) * kap * kap_t * up
    sides = []
    for (us, vs, up, vp), e in ((above, eps_a), (below, eps_b)):
        if pol == "s":          # −e·ŝ', h·Q̂'
            sides.append((vs * cx + up * cy, e * (-vp * cy - us * cx) + kap * kap_t * us))
        else:                   # −h·ŝ', −e·Q̂'
            sides.append((e * (vp * cx - us * cy), -vs * cy + up * cx - kap * kap_t * up / e))
    (x1, y1), (x2, y2) = sides
    return -0.5j * (x1 - x2), (0.5j if pol == "s" else -0.5j) * (y1 - y2)


def _incident(flat, pol, n_top, n_if):
    """The incident order's (U, V) per interface (continuous) and its amplitudes r₀, t₀ (module doc)."""
    eta, y = flat["eta"][-1], flat["down"][-1]
    u = 1.0 if pol == "s" else n_top
    U = [None] * n_if
    U[-1] = u * 2.0 * eta / (eta - y)
    for j in range(n_if - 2, -1, -1):
        U[j] = flat["td"][j] * U[j + 1]
    return [(x, flat["down"][j] * x) for j, x in enumerate(U)], (eta + y) / (eta - y), U[0]


def _specular_map(flat, k, u_top, u_bot):
    """(r, t) amplitudes of the specular order per unit ΔU and per unit ΔV at interface *k*."""
    out = []
    for dU, dV in ((1.0, 0.0), (0.0, 1.0)):
        f = stack_response(flat, k, dU, dV)
        out.append((f[-1][0] / u_top, f[0][2] / u_bot))
    return out


def stack_amplitudes(kappa, K, eps, kd, rough):
    """The second-order kernels of the specular amplitudes of a flat stack for light from its top medium (lateral
    wave number *kappa*, along x; units of k₀), for grating vectors *K* (..., 2) and the rough interfaces *rough*.

    Returns
    -------
    dict
        Per polarization: ``P`` a dict of (j, k) → (r, t) kernels P_jk per a_j a_k (complex arrays of K's
        shape, module doc), ``D`` a dict j → (r, t) per a_j²/4, ``x0`` the flat amplitudes (r₀, t₀) and ``cross``
        the exit medium's γ₀/γ_M (0 beyond its critical angle).

    References
    ----------
    .. [1] Maradudin & Mills 1975; Johnson 1999; Elson 1984 (module doc: the derivation).
    """
    K = np.asarray(K, dtype=float)
    n_if = len(eps) - 1
    n_top, n_bot = math.sqrt(eps[-1].real), math.sqrt(eps[0].real)
    Q1 = K + np.array([float(kappa), 0.0])
    kap1 = np.hypot(Q1[..., 0], Q1[..., 1])
    safe = np.where(kap1 > 0, kap1, 1.0)
    cx, cy = np.where(kap1 > 0, Q1[..., 0] / safe, 1.0), np.where(kap1 > 0, Q1[..., 1] / safe, 0.0)
    g_top, g_bot = _q(eps[-1], kappa), _q(eps[0], kappa)
    cross = float(g_bot.real / g_top.real) if abs(g_bot.imag) < 1e-12 else 0.0
    first = {p: flat_stack(kap1, eps, kd, p) for p in ("s", "p")}
    out = {}
    for pol in ("s", "p"):
        flat0 = flat_stack(np.asarray(float(kappa)), eps, kd, pol)
        fields, r0, t0 = _incident(flat0, pol, n_top, n_if)
        u_bot = 1.0 if pol == "s" else n_bot
        spec = {j: _specular_map(flat0, j, n_top if pol == "p" else 1.0, u_bot) for j in rough}
        state = {j: (fields[j] + (0.0, 0.0)) if pol == "s" else ((0.0, 0.0) + fields[j]) for j in rough}
        P, D = {}, {}
        for k in rough:
            jumps = _excite(state[k], eps[k + 1], eps[k], kappa, kap1, cx, cy)
            fs = stack_response(first["s"], k, jumps[0], jumps[1])
            fp = stack_response(first["p"], k, jumps[2], jumps[3])
            for j in rough:
                above = (fs[j][0], fs[j][1], fp[j][0], fp[j][1])
                below = (fs[j][2], fs[j][3], fp[j][2], fp[j][3])
                dU, dV = _return(above, below, eps[j + 1], eps[j], kap1, kappa, cx, cy, pol)
                (rU, tU), (rV, tV) = spec[j]
                P[(j, k)] = (rU * dU + rV * dV, tU * dU + tV * dV)
        for j in rough:
            (rU, tU), (rV, tV) = spec[j]
            U, V = fields[j]
            D[j] = ((eps[j + 1] - eps[j]) * (rU * U + rV * V), (eps[j + 1] - eps[j]) * (tU * U + tV * V))
        out[pol] = {"P": P, "D": D, "x0": (complex(r0), complex(t0 / u_bot)), "cross": cross}
    return out


def stack_loss_kernels(kappa, K, eps, kd, rough):
    """The second-order loss kernels of :func:`stack_amplitudes`: per polarization ``L`` a dict of (j, k) →
    (L_R, L_T) = (−8 Re(r₀* P^r_jk), −8 (γ₀/γ_M) Re(t₀* P^t_jk)) (per a², arrays of K's shape: the integrand of
    ΔR, ΔT per unit c_jk √(S_j S_k) without k₀², module doc); ``D`` a dict j → (D_R, D_T) per σ_j² without k₀²;
    ``R0``, ``T0`` of the flat stack.

    References
    ----------
    .. [1] Maradudin & Mills 1975 (the specular losses −2 Re(x₀* x₂) to second order).
    """
    out = {}
    for pol, a in stack_amplitudes(kappa, K, eps, kd, rough).items():
        (r0, t0), cross = np.conj(a["x0"]), a["cross"]
        out[pol] = {"L": {jk: (-8.0 * np.real(r0 * r), -8.0 * cross * np.real(t0 * t)) for jk, (r, t) in a["P"].items()},
                    "D": {j: (-float(np.real(r0 * r)), -cross * float(np.real(t0 * t))) for j, (r, t) in a["D"].items()},
                    "R0": float(abs(r0) ** 2), "T0": cross * float(abs(t0) ** 2)}
    return out


def _mode_function(kappa, eps, kd, pol):
    """Im(η_M U − V) of the field that decays into the bottom half-space, carried to the top with the films'
    characteristic matrices (each step scaled by a positive number, which keeps the sign) for real *eps*:
    zero where the stack has a guided mode of lateral wave number *kappa* (module doc)."""
    q = [_q(e, kappa) for e in eps]
    eta = q if pol == "s" else [qm / e for qm, e in zip(q, eps)]
    U, V = np.ones_like(q[0]), -eta[0]
    for m in range(1, len(eps) - 1):
        beta = q[m] * kd[m - 1]
        x, y = beta.real, np.abs(beta.imag)
        ch, sh = 0.5 * (1.0 + np.exp(-2.0 * y)), 0.5 * (1.0 - np.exp(-2.0 * y)) * np.sign(beta.imag)
        c, s = np.cos(x) * ch - 1j * np.sin(x) * sh, np.sin(x) * ch + 1j * np.cos(x) * sh   # e^{−|Im β|} cos, sin
        safe = np.where(q[m] == 0, 1.0, q[m])
        s_q = np.where(q[m] == 0, kd[m - 1] * np.exp(-y), s / safe)                          # sin β / q
        s_eta, eta_s = (s_q, q[m] * q[m] * s_q) if pol == "s" else (eps[m] * s_q, q[m] * q[m] * s_q / eps[m])
        U, V = c * U + 1j * s_eta * V, 1j * eta_s * U + c * V
        norm = np.maximum(np.abs(U), np.abs(V))
        U, V = U / norm, V / norm
    return (eta[-1] * U - V).imag


def guided_modes(eps, kd):
    """The guided modes of the flat stack *eps* (bottom to top; k₀ d *kd*) with its absorption dropped: a list of
    (polarization, lateral wave number κ_m, film) for each root of the mode function (sign changes on |Q| from
    the half-spaces' larger index up to the films' largest, or up to 4 √|ε| of the media where a film has
    Re ε < 0: surface plasmons), refined by Brent's method; *film* is the candidate film of the largest |Re ε|
    (0 = the one on the bottom medium). Empty when no film exceeds both half-spaces' indices or has Re ε < 0.

    References
    ----------
    .. [1] Born & Wolf §1.6 (modes as the zeros of the characteristic matrix's boundary form); Elson 1995
       (guided-wave coupling by interface roughness); R. P. Brent, *Algorithms for Minimization without
       Derivatives*, Prentice-Hall 1973, ch. 4.
    """
    real = [complex(e).real for e in eps]
    top = max(real[0], real[-1])
    films = [m for m in range(1, len(eps) - 1) if real[m] > top or real[m] < 0.0]
    if not films:
        return []
    lo = math.sqrt(top)
    hi = max(math.sqrt(real[m]) if real[m] > 0 else 4.0 * math.sqrt(max(abs(x) for x in real)) for m in films)
    film = max(films, key=lambda m: abs(real[m])) - 1
    t = np.linspace(0.0, 1.0, GUIDED_SAMPLES + 1)[1:]
    kappa = lo + (hi - lo) * t * t
    modes = []
    for pol in ("s", "p"):
        f = _mode_function(kappa, real, kd, pol)
        for i in np.nonzero(np.sign(f[1:]) * np.sign(f[:-1]) < 0)[0]:
            root = optimize.brentq(lambda x: float(_mode_function(np.array([x]), real, kd, pol)[0]),
                                   kappa[i], kappa[i + 1], xtol=1e-15, rtol=1e-15)
            modes.append((pol, root, film))
    return modes


def _pole_weights(kappa, K_m, eps, kd, rough, pairs):
    """The δ(ρ − ρ_m) weights 8π Im(x₀* A) of the loss kernels at a guided mode's crossings K_m (n_psi, 2), A the
    residue in ρ of the amplitude kernel (from two points ρ_m (1 ± ε), its Laurent series' odd part), summed
    over each group of interface pairs *pairs* with their c_jk: per polarization (n_groups, 2, n_psi).

    References
    ----------
    .. [1] Sokhotski-Plemelj: 1 / (x − i0) = P(1/x) + iπ δ(x), the causal side of a lossless pole (absorption
       moves a guided mode to Im κ_m > 0, where dκ/dρ > 0 on every ray: Q₀ lies inside the mode's circle).
    """
    eps_rel = 1e-7
    plus, minus = (stack_amplitudes(kappa, K_m * (1.0 + e), eps, kd, rough) for e in (eps_rel, -eps_rel))
    rho_m = np.hypot(K_m[..., 0], K_m[..., 1])
    out = {}
    for pol in "sp":
        (r0, t0), cross = np.conj(plus[pol]["x0"]), plus[pol]["cross"]

        def weight(jk, i):
            A = 0.5 * eps_rel * rho_m * (plus[pol]["P"][jk][i] - minus[pol]["P"][jk][i])
            return 8.0 * math.pi * np.imag((r0 if i == 0 else t0) * A) * (1.0 if i == 0 else cross)

        out[pol] = np.stack([np.stack([sum(w * weight((j, k), i) for j, k, w in group) for i in (0, 1)])
                             for group in pairs])
    return out


def _pair_weight(psd_j, psd_k):
    """(W(f) = √(S_j S_k), ∫ W d²f in m², the lengths, ∫ W |f| d²f in m or None) of a pair of interfaces' PSDs."""
    if psd_j is psd_k:
        return (psd_j.S, float(psd_j.sigma) ** 2, psd_j.length_scale,
                first_moment(psd_j.S, tail_exponent(psd_j), psd_j.length_scale))

    def W(f):
        return np.sqrt(psd_j.S(f) * psd_k.S(f))

    c_j, c_k = tail_exponent(psd_j), tail_exponent(psd_k)
    exponent = None if c_j is None or c_k is None else 0.5 * (c_j + c_k)
    lengths = (psd_j.length_scale, psd_k.length_scale)
    # ∫ W d²f: every PSD's tail falls faster than |f|^−2, so does √(S_j S_k)
    total = radial_moment(W, 0, 2.0 + 1e-9 if exponent is None else exponent, min(lengths))
    return W, total, lengths, first_moment(W, exponent, min(lengths))


def node_scale(eps, kd):
    """The factor m on the nodes per piece of the quadrature for films of *eps* (bottom to top) and k₀ d *kd*:
    ⌈H / 2⌉ for an optical thickness of H half-waves, H = Σ Re(n_m) k₀ d_m / π (the kernels' Fabry-Perot and
    leaky-mode structure in |K| narrows as 1/H); FieldError beyond :data:`MAX_HALF_WAVES`.

    References
    ----------
    .. [1] Davis & Rabinowitz 1984, §2.7 (Gauss-Legendre error against the integrand's oscillation); the
       convergence measured in tests/test_spm2_stack.py.
    """
    half_waves = sum(abs(complex(e) ** 0.5).real * k for e, k in zip(eps[1:-1], kd)) / math.pi
    if half_waves > MAX_HALF_WAVES:
        raise FieldError(f"{{stack}}: the films' optical thickness is {half_waves:.3g} half-waves; the coherent "
                         f"losses are built up to {MAX_HALF_WAVES} (the kernels' Fabry-Perot and leaky-mode "
                         "structure in |K| needs ever finer nodes)", "stack")
    return max(1, math.ceil(half_waves / 2.0))


def _check(mu, wavelength_nm):
    mu = float(mu)
    if not 0.0 < mu <= 1.0:
        raise FieldError(f"{{mu}} {mu!r} is not allowed; the incidence cosine must lie in (0, 1]", "mu")
    if not (np.isfinite(float(wavelength_nm)) and float(wavelength_nm) > 0):
        raise FieldError(f"{{wavelength_nm}} {wavelength_nm!r} is not allowed; it must be > 0 nm", "wavelength_nm")
    return mu, float(wavelength_nm)


def stack_coherent_losses(mu, from_above, stack_or_layers, interface_psds, correlation, wavelength_nm,
                          nodes=SPM2_NODES) -> dict:
    """The second-order losses of the specular reflectance and transmittance of a film stack on a transparent
    substrate (air above) whose interfaces are randomly rough (module doc), light at incidence cosine *mu* from
    the air (*from_above*) or from inside the substrate.

    Parameters
    ----------
    mu : float
        cosθ_i in the incidence medium, in (0, 1].
    from_above : bool
        Light from the air (True) or from the substrate.
    stack_or_layers : Stack, material or (n_substrate, n_films, d_films_nm)
        As :func:`waveoptics.scatter.stack_layers` (films from the substrate outwards; complex film indices
        allowed; the substrate's index real).
    interface_psds : PSDModel, None or sequence
        One PSD for every interface, or one per interface (substrate first; None for a smooth one).
    correlation : {'correlated', 'uncorrelated'}, float or array
        The interfaces' cross-correlation c_jk (:func:`waveoptics.scatter.cross_psd_weights`).
    wavelength_nm : float, nm
        Vacuum wavelength.
    nodes : (int, int)
        Gauss-Legendre nodes per piece in ρ and in ψ (:func:`waveoptics.scatter.loss_quadrature`) for films up to
        two half-waves thick; times :func:`node_scale` for thicker ones.

    Returns
    -------
    dict
        ``R0``, ``T0`` (the flat stack's specular reflectance and transmittance into the other half-space) and
        ``dR``, ``dT`` (their second-order losses, dimensionless), each a dict of 's' and 'p'.

    Raises
    ------
    FieldError
        When a film can guide a mode (a pole of the kernels on the integration range, module doc).

    References
    ----------
    .. [1] Maradudin & Mills 1975; Johnson 1999; Elson 1984, 1995 (module doc); Davis & Rabinowitz 1984.
    """
    mu, lam_nm = _check(mu, wavelength_nm)
    eps, kd, order = stack_media(stack_or_layers, lam_nm, bool(from_above))
    n_if = len(eps) - 1
    psds = interface_psd_list(interface_psds, n_if)
    if any(m is not None and not hasattr(m, "S") for m in psds):
        raise FieldError("{interface_psds}: the coherent losses take isotropic PSDs (with S(|f|))", "interface_psds")
    psds = [psds[i] for i in order]                       # internal order: exit side first
    c = cross_psd_weights(correlation, n_if)[np.ix_(order, order)]
    rough = [j for j in range(n_if) if psds[j] is not None and float(psds[j].sigma) > 0]
    kappa = math.sqrt(eps[-1].real) * math.sqrt(max(1.0 - mu * mu, 0.0))
    flat = stack_loss_kernels(kappa, np.zeros(2), eps, kd, rough)
    out = {"R0": {p: flat[p]["R0"] for p in "sp"}, "T0": {p: flat[p]["T0"] for p in "sp"},
           "dR": {p: 0.0 for p in "sp"}, "dT": {p: 0.0 for p in "sp"}}
    if not rough:
        return out
    scale = node_scale(eps, kd)
    modes = guided_modes(eps, kd)
    if modes and any(abs(e.imag) > 0.0 for e in eps):
        film = modes[0][2] if from_above else n_if - 2 - modes[0][2]
        raise FieldError(f"{{stack}}: film {film} (from the substrate) guides a mode at n sinθ = {modes[0][1]:.4g} "
                         "and the stack absorbs: its pole lies near the integration range, whose residue is built "
                         "for lossless stacks only", "stack")
    groups = {}
    for j in rough:
        for k in rough:
            if c[j, k] != 0.0:
                key = tuple(sorted((id(psds[j]), id(psds[k]))))
                groups.setdefault(key, (psds[j], psds[k], []))[2].append((j, k, float(c[j, k])))
    terms = [_pair_weight(a, b) for a, b, _ in groups.values()]
    pairs = [p for _, _, p in groups.values()]

    def kernels(K):
        ker = stack_loss_kernels(kappa, K, eps, kd, rough)
        return {pol: np.stack([np.stack([sum(w * ker[pol]["L"][(j, k)][i] for j, k, w in group) for i in (0, 1)])
                               for group in pairs]) for pol in "sp"}

    def residues(pole, K_m):
        return _pole_weights(kappa, K_m, eps, kd, rough, pairs)

    integrals = loss_quadrature(kappa, (math.sqrt(eps[0].real), math.sqrt(eps[-1].real)), lam_nm, terms, kernels,
                                tuple(n * scale for n in nodes), poles=tuple(sorted({m[1] for m in modes})),
                                residues=residues)
    k0 = 2.0 * math.pi / (lam_nm * 1e-9)
    for pol in "sp":
        for i, key in enumerate(("dR", "dT")):
            diag = sum(float(psds[j].sigma) ** 2 * flat[pol]["D"][j][i] for j in rough)
            out[key][pol] = float(integrals[pol][i]) + k0 ** 2 * diag
    return out
