"""A rigorous plane-wave solve of shallow sinusoidal gratings on the interfaces of a thin-film stack (the Rayleigh
method for a layered medium), the independent reference of tests/test_rr_stack_grating.py.

Media j = 0..L from the top: the incident medium (ε₀ = n_top², z > z₀), the films j = 1..L−1 (thickness d_j,
complex indices allowed) and the bottom medium (ε_L, real or complex). Interface l = 0..L−1 separates media l and
l + 1 at the height z_l = −(d₁ + … + d_l) and carries the profile h_l(x) = a_l cos(K x + φ_l) (a_l = 0: flat; equal
a_l and φ_l: the correlated case). Lengths are in units of 1/k₀ (k₀ = 2π/λ) and lateral wave vectors in units of
k₀, as in tests/rr_grating.py.

In every medium each order m = −M..M is a plane wave of lateral wave vector (α_m, β₀) = (α₀ + m K, β₀) with normal
wave number ±γ_{j,m}, γ = √(ε − α² − β²) (Im γ ≥ 0), an s and a p polarization (ŝ ⟂ plane of incidence,
p̂ = ŝ × k / √ε, H = k × E in units of E / Z₀). The top medium holds the incident wave and the up-going (reflected)
orders, the bottom medium the down-going (transmitted) ones, each film both. Every amplitude is referenced at the
flat interface its wave travels away from (up-going waves at the layer's lower interface, down-going ones at its
upper one, the top medium's waves at z₀), so that no exponential grows across a film (the usual stable choice of
transfer- and scattering-matrix codes). On z = z_l + h_l(x) the tangential E and H are continuous (tangents ŷ and
x̂ + h_l'(x) ẑ); with e^{iγ a cos(Kx+φ)} = Σ_q i^q J_q(γ a) e^{iq(Kx+φ)} (Jacobi–Anger) and its x-derivative
h' e^{iγh} = Σ_q i^q (a K / 2)(J_{q−1} + J_{q+1})(γ a) e^{iq(Kx+φ)}, the harmonics m = −M..M of the four
tangential components of all L interfaces give one dense linear system for the 4 L (2M + 1) amplitudes (Rayleigh
1907; the Rayleigh hypothesis holds for K a < 0.448, Millar 1971). Nothing of the library is used: it is Maxwell's
boundary conditions solved numerically, valid to every order in a_l for shallow gratings.

Efficiencies: z-flux of an order over that of the incident wave, Re γ |A|² / γ_inc (Petit 1980, ch. 1), for the
propagating orders of the top medium and of a transparent bottom medium (0 for evanescent orders and an absorbing
bottom medium).

References
----------
.. [1] M. Born and E. Wolf, *Principles of Optics*, 7th ed., Cambridge 1999, §1.6 (stratified media; the
   amplitudes referenced at each layer's own interfaces).
.. [2] Lord Rayleigh, "On the dynamical theory of gratings", Proc. R. Soc. Lond. A 79, 399–416, 1907.
.. [3] R. F. Millar, "On the Rayleigh assumption in scattering by a periodic surface II", Proc. Camb. Phil. Soc.
   69, 217–225, 1971.
.. [4] R. Petit (ed.), *Electromagnetic Theory of Gratings*, Springer 1980, ch. 1 (conical mounting, efficiencies
   from the z component of the Poynting vector).
"""
from __future__ import annotations

import numpy as np
from scipy import special

PROPAGATING = 1e-14    # |Im γ| below which an order carries flux (as tests/rr_grating.py)


def normal_wavenumbers(eps, alpha, beta):
    """γ = √(ε − α² − β²) of the orders (units of k₀), the root with Im γ ≥ 0 (decaying away from the source)."""
    g = np.sqrt(complex(eps) - alpha ** 2 - beta ** 2 + 0j)
    return np.where(g.imag < 0, -g, g)


def plane_waves(eps, alpha, beta, gz):
    """E and H = k × E of unit s and p plane waves of wave vectors (α_m, β, gz_m) in a medium ε: two (2, N, 3)
    arrays, index 0 the s wave (ŝ = ẑ × k̂_lateral; ŷ at normal incidence), 1 the p wave (p̂ = ŝ × k / √ε, unit in
    the bilinear sense)."""
    kap = np.hypot(alpha, beta)
    normal = kap == 0                                 # normal incidence: ŝ = ŷ (the limit α → 0⁺, β = 0)
    kap = np.where(normal, 1.0, kap)
    s = np.stack([np.where(normal, 0.0, -beta / kap), np.where(normal, 1.0, alpha / kap), np.zeros_like(kap)],
                 axis=-1) + 0j
    k = np.stack([alpha + 0j, np.broadcast_to(beta, alpha.shape) + 0j, gz], axis=-1)
    p = np.cross(s, k) / np.sqrt(complex(eps))
    E = np.stack([s, p])
    return E, np.cross(k[None], E)


def tangential_rows(E, H, gz, m, a, K, phi):
    """(4N, N) contribution of the waves of orders m (one polarization, amplitude vectors E, H (N, 3), signed normal
    wave numbers gz) to the harmonics m of E·ŷ, E·t, H·ŷ, H·t on z = z_l + a cos(Kx + φ), t = x̂ + h'(x) ẑ, per unit
    amplitude at the height z_l."""
    q = m[:, None] - m[None, :]                       # harmonic − order: the Bessel index
    arg = gz[None, :] * a
    ph = (1j ** q) * np.exp(1j * q * phi)
    C = ph * special.jv(q, arg)
    D = ph * 0.5 * a * K * (special.jv(q - 1, arg) + special.jv(q + 1, arg))
    return np.concatenate([E[None, :, 1] * C, E[None, :, 0] * C + E[None, :, 2] * D,
                           H[None, :, 1] * C, H[None, :, 0] * C + H[None, :, 2] * D], axis=0)


def _layer_heights(d):
    """z_l of the interfaces (z₀ = 0, downwards by the film thicknesses)."""
    return np.concatenate([[0.0], -np.cumsum(np.asarray(d, dtype=float))])


def _wave_slots(L):
    """The unknown waves as (medium, direction): the top medium's up-going, every film's up- and down-going, the
    bottom medium's down-going waves; each slot holds s and p for every order."""
    return [(0, 1)] + [(j, sgn) for j in range(1, L) for sgn in (1, -1)] + [(L, -1)]


def _reference_height(j, sgn, z):
    """The flat interface a wave of medium j travelling up (sgn 1) or down (−1) is referenced at."""
    return z[j] if sgn > 0 else z[max(j - 1, 0)]


def stack_grating_solve(n_top, films, n_bot, alpha0, beta0, K, a, pol, M=3, phi=None):
    """Orders of a stack of sinusoidal gratings lit by a unit plane wave from the top medium.

    Parameters
    ----------
    n_top : float
        Index of the incident (top) medium, real.
    films : sequence of (n_j, d_j)
        The films from the top down: index (complex allowed) and thickness (units of 1/k₀, i.e. k₀ d).
    n_bot : complex
        Index of the bottom medium (complex: absorbing, no transmitted flux).
    alpha0, beta0 : float
        Lateral wave vector of the incident wave (units of k₀), the grating vector along x.
    K : float
        Grating frequency |K| / k₀.
    a : float or sequence of float
        Amplitude of each interface's profile a_l cos(K x + φ_l), top interface first (units of 1/k₀); a scalar: the
        same amplitude on every interface.
    pol : {'s', 'p'}
        Polarization of the incident wave.
    M : int
        Orders −M..M.
    phi : sequence of float, optional
        Phase φ_l of each profile (rad); default 0 (all in phase).

    Returns
    -------
    dict
        ``orders`` (m); ``R``, ``T``: efficiencies of the reflected (top medium) and transmitted (bottom medium)
        orders, dicts 's', 'p' (analyzed) and 'total'; ``kr``, ``kt``: wave vectors (N, 3) of the orders (units of
        k₀); ``r``, ``t``: complex amplitudes (N, 2) of the s and p waves of the orders (reflected referenced at
        z₀, transmitted at the lowest interface); ``r0``, ``t0``: those of the specular order, dicts 's', 'p'.
    """
    eps = [complex(n_top) ** 2] + [complex(n) ** 2 for n, _ in films] + [complex(n_bot) ** 2]
    L = len(eps) - 1
    amp = np.broadcast_to(np.asarray(a, dtype=float), (L,))
    phases = np.zeros(L) if phi is None else np.asarray(phi, dtype=float)
    z = _layer_heights([d for _, d in films])
    m = np.arange(-M, M + 1)
    N = len(m)
    alpha = alpha0 + m * K
    gam = [normal_wavenumbers(e, alpha, beta0) for e in eps]
    slots = _wave_slots(L)
    A = np.zeros((4 * N * L, 2 * N * len(slots)), dtype=complex)
    b = np.zeros(4 * N * L, dtype=complex)
    g_inc = normal_wavenumbers(eps[0], np.array([alpha0]), beta0)
    Ei, Hi = plane_waves(eps[0], np.array([alpha0]), beta0, -g_inc)
    ip = 0 if pol == "s" else 1
    for l in range(L):
        rows = slice(4 * N * l, 4 * N * (l + 1))
        for c, (j, sgn) in enumerate(slots):
            if j not in (l, l + 1):
                continue
            gz = sgn * gam[j]
            E, H = plane_waves(eps[j], alpha, beta0, gz)
            shift = np.exp(1j * gz * (z[l] - _reference_height(j, sgn, z)))
            side = 1.0 if j == l else -1.0
            for w in range(2):
                A[rows, (2 * c + w) * N:(2 * c + w + 1) * N] = side * shift[None, :] * tangential_rows(
                    E[w], H[w], gz, m, amp[l], K, phases[l])
        if l == 0:                                    # the incident wave (order 0), referenced at z₀
            b[rows] = -tangential_rows(Ei[ip], Hi[ip], -g_inc, m, amp[0], K, phases[0])[:, N // 2]
    x = np.linalg.solve(A, b).reshape(len(slots), 2, N)
    r, t = x[0].T, x[-1].T
    flux_r = np.where(np.abs(gam[0].imag) < PROPAGATING, gam[0].real, 0.0) / g_inc.real
    transparent = abs(eps[L].imag) == 0.0 and eps[L].real > 0
    flux_t = np.where(np.abs(gam[L].imag) < PROPAGATING, gam[L].real, 0.0) / g_inc.real * transparent
    R = {"s": flux_r * np.abs(r[:, 0]) ** 2, "p": flux_r * np.abs(r[:, 1]) ** 2}
    T = {"s": flux_t * np.abs(t[:, 0]) ** 2, "p": flux_t * np.abs(t[:, 1]) ** 2}
    R["total"], T["total"] = R["s"] + R["p"], T["s"] + T["p"]
    beta = np.full(N, beta0, dtype=float)
    return {"orders": m, "R": R, "T": T, "r": r, "t": t,
            "r0": {"s": r[M, 0], "p": r[M, 1]}, "t0": {"s": t[M, 0], "p": t[M, 1]},
            "kr": np.stack([alpha, beta, gam[0]], axis=-1), "kt": np.stack([alpha, beta, -gam[L]], axis=-1)}


def stack_order_bsdf(n_top, films_m, n_bot, wi, wo, lam_m, rough=1.0, phi=None, ka=1e-3, M=3):
    """The rigorous BSDF per unit PSD (1/sr at S = 1 m⁴) of the stack from light along −ω_i in the top medium into
    ω_o (z > 0: reflected into the top medium; z < 0: transmitted into a transparent bottom medium): the efficiency
    η of order +1 of the grating a_l = rough_l · a cos(2π f·x + φ_l) whose frequency sends the incident wave into
    ω_o, f = (n_o ω_o + n_top ω_i)_xy / λ, divided by (λ / n_o)² a²/4 (a profile a cos(2π f·x) has the two-sided
    PSD (a²/4)[δ(f − f₀) + δ(f + f₀)] and d²f = (n_o/λ)² cosθ_o dΩ_o). Returns {'ss', 'sp', 'ps', 'pp'} (first
    index incident, second analyzed), equal to the first-order BSDF up to O((k a)²), a = *ka* / (k₀ max |n|).
    *films_m*: (n_j, d_j in m) from the top down; *wi*, *wo*: unit vectors (towards the light, the viewer)."""
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    n_o = complex(n_bot).real if wo[2] < 0 else n_top
    k_in, k_out = -n_top * wi[:2], n_o * wo[:2]
    kap = float(np.hypot(*(k_out - k_in)))             # |K| / k₀
    c, s = (k_out - k_in) / kap
    a0, b0 = c * k_in[0] + s * k_in[1], -s * k_in[0] + c * k_in[1]   # the grating vector along x
    k0 = 2 * np.pi / lam_m
    films = [(n, k0 * d) for n, d in films_m]
    a = ka / max(abs(complex(n)) for n in [n_top, n_bot, *(n for n, _ in films)])
    norm = (lam_m / n_o) ** 2 * (a / k0) ** 2 / 4
    out = {}
    for pol in "sp":
        res = stack_grating_solve(n_top, films, n_bot, a0, b0, kap, a * np.asarray(rough, dtype=float), pol, M=M,
                                  phi=phi)
        eff = res["T" if wo[2] < 0 else "R"]
        for b in "sp":
            out[pol + b] = eff[b][M + 1] / norm
    return out


def stack_specular_losses(n_top, films_m, n_bot, wi, fx, fy, lam_m, pol, rough=1.0, phi=None, ka=2e-3,
                          flat=None):
    """Rigorous losses (ΔR₀, ΔT₀) of the specular reflectance and transmittance (flat minus grating) of the stack
    whose interfaces carry a_l = rough_l · a cos(2π f·x + φ_l), f = (fx, fy) (1/m), per a²/4 (1/m²), for light
    from the top medium along −ω_i (*wi* towards the light, z > 0 in the top medium). *films_m*: (n_j, d_j in m)
    from the top down; a = *ka* / (k₀ max |n|). Only the ±1 orders carry the O(a²) loss (M = 1). *flat*: the flat
    stack's specular (R, T), computed when not given. With absorbing films ΔR₀ + ΔT₀ also holds the change of the
    absorption, not only the scatter. Light from the substrate side: the same call with the layers reversed (the
    profiles then read −h: φ_l + π)."""
    k0 = 2 * np.pi / lam_m
    kap = np.hypot(fx, fy) * lam_m                     # |K| / k₀
    c, s = fx * lam_m / kap, fy * lam_m / kap
    ax, ay = -n_top * wi[0], -n_top * wi[1]
    a0, b0 = c * ax + s * ay, -s * ax + c * ay        # the incident lateral wave vector, grating vector along x
    films = [(n, k0 * d) for n, d in films_m]
    a = ka / max(abs(complex(n)) for n in [n_top, n_bot, *(n for n, _ in films)])
    res = stack_grating_solve(n_top, films, n_bot, a0, b0, kap, a * np.asarray(rough, dtype=float), pol, M=1,
                              phi=phi)
    if flat is None:
        f = stack_grating_solve(n_top, films, n_bot, a0, b0, kap, 0.0, pol, M=1)
        flat = (f["R"]["total"][1], f["T"]["total"][1])
    norm = (a / k0) ** 2 / 4
    return (flat[0] - res["R"]["total"][1]) / norm, (flat[1] - res["T"]["total"][1]) / norm


def stack_integrated_losses(n_top, films_m, n_bot, wi, psd_S, length, lam_m, pol, rough=1.0,
                            correlation="correlated", n_rho=28, n_psi=20):
    """(ΔR₀, ΔT₀) of a stack of random interfaces of one isotropic PSD *psd_S* (m⁴ at |f| in 1/m; interface l's is
    rough_l² S) with correlation length *length* (m): ∫ S(f) ΔX(f) d²f over a half plane of f (each grating
    scatters into +f and −f), Gauss-Legendre in |f| on [0, 4/(π length)] and in the azimuth. *correlation*:
    'correlated' (identical interfaces, one grating on all) or 'uncorrelated' (the second-order losses of the
    interfaces add: one grating at a time)."""
    L = len(films_m) + 1
    rough = np.broadcast_to(np.asarray(rough, dtype=float), (L,))
    if correlation == "correlated":
        profiles = [rough]
    elif correlation == "uncorrelated":
        profiles = [np.where(np.arange(L) == l, rough, 0.0) for l in range(L) if rough[l] != 0.0]
    else:
        raise ValueError(f"correlation must be 'correlated' or 'uncorrelated', got {correlation!r}")
    x, w = np.polynomial.legendre.leggauss(n_rho)
    rho_max = 4.0 / (np.pi * length)
    rho, wr = 0.5 * rho_max * (x + 1), 0.5 * rho_max * w
    y, wy = np.polynomial.legendre.leggauss(n_psi)
    psi, wp = 0.5 * np.pi * (y + 1), 0.5 * np.pi * wy
    k0 = 2 * np.pi / lam_m
    f = stack_grating_solve(n_top, [(n, k0 * d) for n, d in films_m], n_bot, -n_top * wi[0], -n_top * wi[1], 0.5,
                            0.0, pol, M=1)
    flat = (f["R"]["total"][1], f["T"]["total"][1])
    dR = dT = 0.0
    for r, w1 in zip(rho, wr):
        for p, w2 in zip(psi, wp):
            for prof in profiles:
                lr, lt = stack_specular_losses(n_top, films_m, n_bot, wi, r * np.cos(p), r * np.sin(p), lam_m, pol,
                                               rough=prof, flat=flat)
                dR += w1 * w2 * r * psd_S(r) * lr
                dT += w1 * w2 * r * psd_S(r) * lt
    return dR, dT
