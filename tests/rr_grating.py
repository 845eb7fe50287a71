"""A rigorous plane-wave solve of a shallow sinusoidal grating between two media (the Rayleigh method), the
independent reference of tests/test_rr_transmission.py.

The interface z = a cos(K x) separates medium 1 (ε₁ = n₁², z above) from medium 2 (ε₂ = n₂²). Above: the incident
plane wave and the reflected orders, below: the transmitted orders, each a plane wave of lateral wave vector
(α₀ + m K, β₀) (units of k₀ = 2π/λ, lengths in 1/k₀) with s and p amplitudes. The tangential E and H are
continuous on the surface (tangents ŷ and x̂ + h'(x) ẑ); expanding e^{iγ h(x)} = Σ_l i^l J_l(γ a) e^{ilKx} and
h'(x) e^{iγ h(x)} = Σ_l i^l (a K / 2)(J_{l−1} + J_{l+1})(γ a) e^{ilKx} and matching the harmonics m = −M..M gives a
linear system for the 4(2M + 1) amplitudes (Rayleigh 1907; the Rayleigh hypothesis holds for K a < 0.448,
Millar 1971). Nothing of the library is used: it is Maxwell's boundary conditions solved numerically, valid to
every order in a for a shallow grating, so its ±1 efficiencies hold the first-order BSDF to O((k a)²) and its
specular loss is the second-order energy that first-order scatter must account for.

References
----------
.. [1] Lord Rayleigh, "On the dynamical theory of gratings", Proc. R. Soc. Lond. A 79, 399–416, 1907.
.. [2] R. F. Millar, "On the Rayleigh assumption in scattering by a periodic surface II", Proc. Camb. Phil. Soc.
   69, 217–225, 1971.
.. [3] R. Petit (ed.), *Electromagnetic Theory of Gratings*, Springer 1980, ch. 1 (conical mounting, efficiencies
   from the z component of the Poynting vector).
"""
from __future__ import annotations

import numpy as np
from scipy import special


def _kz(eps, alpha, beta):
    g = np.sqrt(eps - alpha ** 2 - beta ** 2 + 0j)
    return np.where(g.imag < 0, -g, g)


def _bases(alpha, beta, gz, eps):
    """(ŝ, p̂, k) of plane waves of wave vectors (α_j, β, γ_j) in a medium ε, each (N, 3), with H = k × E (units
    of E / Z₀) and p̂ = ŝ × k / √ε (unit in the bilinear sense, also for evanescent waves)."""
    kap = np.hypot(alpha, beta)
    s = np.stack([-beta / kap, alpha / kap, np.zeros_like(alpha)], axis=-1).astype(complex)
    k = np.stack([alpha + 0j, np.full_like(alpha, beta) + 0j, gz], axis=-1)
    p = np.cross(s, k) / np.sqrt(eps + 0j)
    return s, p, k


def _blocks(E, H, gz, orders, m, a, K):
    """(4N, n_waves) columns of waves with amplitude vectors E, H (n_waves, 3), z wave numbers gz and orders
    *orders*: their contributions to E·ŷ, E·t₂, H·ŷ, H·t₂ at the harmonics m (t₂ = x̂ + h'(x) ẑ)."""
    lval = m[:, None] - orders[None, :]                                   # (N, n_waves)
    arg = gz[None, :] * a
    C = (1j ** lval) * special.jv(lval, arg)
    D = (1j ** lval) * 0.5 * a * K * (special.jv(lval - 1, arg) + special.jv(lval + 1, arg))
    return np.concatenate([E[None, :, 1] * C, E[None, :, 0] * C + E[None, :, 2] * D,
                           H[None, :, 1] * C, H[None, :, 0] * C + H[None, :, 2] * D], axis=0)


def grating_solve(n1, n2, alpha0, beta0, K, a, pol, M=3):
    """Efficiencies of the sinusoidal grating for a unit incident wave from medium 1 with lateral wave vector
    (alpha0, beta0) (units of k₀) and polarization *pol* ('s' or 'p', relative to the plane of incidence).

    Returns dict with ``orders`` (m), ``R`` and ``T`` (efficiencies of the orders, dicts 's', 'p' of the analyzed
    polarization and 'total'; 0 for evanescent orders), and ``kr``, ``kt`` (wave vectors of the orders).
    """
    e1, e2 = complex(n1) ** 2, complex(n2) ** 2
    m = np.arange(-M, M + 1)
    alpha = alpha0 + m * K
    g1 = _kz(e1, alpha, beta0)
    g2 = _kz(e2, alpha, beta0)
    g10 = _kz(e1, alpha0, beta0)
    sr, pr, kr = _bases(alpha, beta0, g1, e1)
    st, pt, kt = _bases(alpha, beta0, -g2, e2)
    cols = [_blocks(E, np.cross(k, E), gz, m, m, a, K) * sign
            for E, k, gz, sign in ((sr, kr, g1, 1.0), (pr, kr, g1, 1.0), (st, kt, -g2, -1.0), (pt, kt, -g2, -1.0))]
    A = np.stack(cols, axis=-1).reshape(4 * len(m), 4 * len(m))          # unknowns ordered (order, wave type)
    si, pi_, ki = _bases(np.array([alpha0]), beta0, np.array([-g10]), e1)
    Ei = si if pol == "s" else pi_
    b = -_blocks(Ei, np.cross(ki, Ei), np.array([-g10]), np.array([0]), m, a, K)[:, 0]
    x = np.linalg.solve(A, b).reshape(len(m), 4)
    prop1 = np.where(np.abs(g1.imag) < 1e-14, g1.real, 0.0) / g10.real
    prop2 = np.where(np.abs(g2.imag) < 1e-14, g2.real, 0.0) / g10.real
    R = {"s": prop1 * np.abs(x[:, 0]) ** 2, "p": prop1 * np.abs(x[:, 1]) ** 2}
    T = {"s": prop2 * np.abs(x[:, 2]) ** 2, "p": prop2 * np.abs(x[:, 3]) ** 2}
    R["total"], T["total"] = R["s"] + R["p"], T["s"] + T["p"]
    return {"orders": m, "R": R, "T": T, "kr": np.stack([alpha, np.full(len(m), beta0), g1], axis=-1),
            "kt": np.stack([alpha, np.full(len(m), beta0), -g2], axis=-1)}


def specular_losses(n_i, n_o, wi, fx, fy, lam_m, pol, ka=2e-3, flat=None):
    """Rigorous losses (ΔR₀, ΔT₀) of the specular reflectance and transmittance (flat minus grating) of a grating of
    spatial frequency (fx, fy) (1/m), per a²/4 (1/m²), for light from medium n_i along −ω_i (*wi* towards the
    light, z > 0 in medium n_i); the amplitude a is *ka* / (k₀ max(n_i, n_o)). Only the ±1 orders carry the O(a²)
    loss (M = 1). *flat*: the flat interface's specular (R, T), which does not depend on the grating (computed
    when not given)."""
    k0 = 2 * np.pi / lam_m
    kap = np.hypot(fx, fy) * lam_m                     # |K| / k₀
    c, s = fx * lam_m / kap, fy * lam_m / kap
    ax, ay = -n_i * wi[0], -n_i * wi[1]
    a0, b0 = c * ax + s * ay, -s * ax + c * ay        # the incident lateral wave vector, grating vector along x
    a = ka / max(n_i, n_o)
    res = grating_solve(n_i, n_o, a0, b0, kap, a, pol, M=1)
    i0 = res["orders"] == 0
    if flat is None:
        f = grating_solve(n_i, n_o, a0, b0, kap, 0.0, pol, M=1)
        flat = (f["R"]["total"][i0][0], f["T"]["total"][i0][0])
    norm = (a / k0) ** 2 / 4
    return (flat[0] - res["R"]["total"][i0][0]) / norm, (flat[1] - res["T"]["total"][i0][0]) / norm


def integrated_losses(n_i, n_o, wi, psd_S, length, lam_m, pol, n_rho=28, n_psi=20):
    """(ΔR₀, ΔT₀) of a random surface of isotropic PSD *psd_S* (m⁴ at |f| in 1/m) with correlation length *length*
    (m): ∫ S(f) ΔX(f) d²f over a half plane of f (each grating scatters into +f and −f), Gauss-Legendre in |f| on
    [0, 4/(π length)] and in the azimuth."""
    x, w = np.polynomial.legendre.leggauss(n_rho)
    rho_max = 4.0 / (np.pi * length)
    rho, wr = 0.5 * rho_max * (x + 1), 0.5 * rho_max * w
    y, wy = np.polynomial.legendre.leggauss(n_psi)
    psi, wp = 0.5 * np.pi * (y + 1), 0.5 * np.pi * wy
    dR = dT = 0.0
    f = grating_solve(n_i, n_o, -n_i * wi[0], -n_i * wi[1], 0.5, 0.0, pol, M=1)
    flat = (f["R"]["total"][1], f["T"]["total"][1])
    for r, w1 in zip(rho, wr):
        for p, w2 in zip(psi, wp):
            lr, lt = specular_losses(n_i, n_o, wi, r * np.cos(p), r * np.sin(p), lam_m, pol, flat=flat)
            dR += w1 * w2 * r * psd_S(r) * lr
            dT += w1 * w2 * r * psd_S(r) * lt
    return dR, dT
