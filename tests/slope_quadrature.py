"""Quadrature over microfacet normals for tests of rough glass (tests/test_btdf.py, tests/test_coated_glass.py):
nodes in the slope plane, independent of the library's own quadratures."""
from __future__ import annotations

import numpy as np


def slope_nodes(alpha, n_s=24, n_phi=96):
    """Microfacet normals (K, 3) and solid-angle weights: slope p = α τ (cos φ, sin φ), τ = tan(πs/2), s by
    Gauss-Legendre on four panels of (0, 1), φ by the midpoint rule; dω_m = cos³θ_m α² τ dτ dφ."""
    x, w = np.polynomial.legendre.leggauss(n_s)
    s_nodes, s_w = [], []
    for a, b in ((0.0, 0.4), (0.4, 0.7), (0.7, 0.9), (0.9, 1.0)):
        s_nodes.append(a + (b - a) * (x + 1) / 2)
        s_w.append((b - a) / 2 * w)
    s, ws = np.concatenate(s_nodes), np.concatenate(s_w)
    tau = np.tan(np.pi * s / 2)
    dtau = np.pi / 2 / np.cos(np.pi * s / 2) ** 2
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    T, P = np.meshgrid(tau, phi, indexing="ij")
    W = (ws * dtau)[:, None] * np.ones_like(P) * 2 * np.pi / n_phi
    px, py = alpha * T * np.cos(P), alpha * T * np.sin(P)
    cz = 1 / np.sqrt(1 + px ** 2 + py ** 2)
    m = np.stack([-px * cz, -py * cz, cz], axis=-1).reshape(-1, 3)
    return m, (cz ** 3 * alpha ** 2 * T * W).ravel()


def quad_albedo(b, i, alpha, eta, lam):
    """(R, T) = ∫ (f_r, f_t)(i, o) |cos θ_o| dω_o of the single-scattering parts of *b* (a BSDF over the sphere,
    air above a dielectric of index *eta*) at *lam* (nm), over microfacet normals (Walter eqs. 14, 17, 40)."""
    m, w = slope_nodes(alpha)
    side = 1.0 if i[2] > 0 else -1.0
    eta_i, eta_t = (1.0, eta) if side > 0 else (eta, 1.0)
    c = m @ i
    vis = c * side > 0
    o_r = 2 * c[:, None] * m - i
    e = eta_i / eta_t
    k = 1 + e * e * (c * c - 1)
    ok = vis & (k > 0)
    o_t = (e * c - side * np.sqrt(np.where(k > 0, k, 0)))[:, None] * m - e * i    # Walter eq. (40)
    o_t = np.where(ok[:, None], o_t, [0, 0, -side])
    oh = np.sum(o_t * m, axis=1)
    jac_t = (eta_i * c + eta_t * oh) ** 2 / (eta_t ** 2 * np.abs(oh))              # 1 / Walter eq. (17)
    pr = b.eval_parts(np.broadcast_to(i, o_r.shape), o_r, lam)["reflection"]
    pt = b.eval_parts(np.broadcast_to(i, o_t.shape), o_t, lam)["transmission"]
    R = np.sum(np.where(vis, pr * np.abs(o_r[:, 2]) * 4 * np.abs(c), 0) * w)
    T = np.sum(np.where(ok, pt * np.abs(o_t[:, 2]) * jac_t, 0) * w)
    return float(R), float(T)


def quad_multiple(b, i, lam, n=64, n_phi=8):
    """∫ f_ms |cos θ_o| dω_o of the compensation lobes of *b* at *lam* (nm) over both hemispheres (Gauss-Legendre
    in cos θ_o, midpoint rule in φ)."""
    x, w = np.polynomial.legendre.leggauss(n)
    mu, wmu = (x + 1) / 2, w / 2
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    total = 0.0
    for side in (1.0, -1.0):
        M, P = np.meshgrid(mu, phi, indexing="ij")
        S = np.sqrt(1 - M * M)
        o = np.stack([S * np.cos(P), S * np.sin(P), side * M], axis=-1).reshape(-1, 3)
        f = b.eval_parts(np.broadcast_to(i, o.shape), o, lam)["multiple"].reshape(M.shape)
        total += float(np.sum(f * M * wmu[:, None]) * 2 * np.pi / n_phi)
    return total
