"""The albedo of a lobe concentrated about the mirror direction, by quadrature on a polar grid about the mirror
point in direction cosines (shared by the band lobe's albedo and Rayleigh-Rice's total integrated scatter)."""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate

__all__ = ["polar_albedo"]


def polar_albedo(theta, k, length_scale, lobe):
    """∫ f cosθ_o dω_o = ∫ f du dv over the disc of directions (u, v) for incidence θ (rad) in the x–z plane, of a
    lobe ``lobe(wi, wo, q)`` (1/sr; q = k × distance from the mirror point in direction cosines, 1/m) concentrated
    about the mirror direction with features down to |q| ~ 1/*length_scale* (m).

    Polar coordinates (|q|, ψ) about the mirror point: along each azimuth geometric in |q| up to half the way to
    the rim, then q = q_rim − τ² with τ uniform, which removes a 1/cosθ_o of the integrand at the horizon
    (∝ 1/√(q_rim − q)). The lobe is taken symmetric about the plane of incidence (ψ ↔ −ψ): half the azimuths,
    twice. Measured against a 384² direction-cosine grid: within 3e-4 relative (tests/test_band.py).

    *theta* a scalar gives a float (the lobe sees arrays wi, wo (n_ψ, n, 3), q (n_ψ, n)); a 1-D array of
    incidences gives their albedos (n_θ,) from one call of *lobe* per piece of the grid, on arrays with a leading
    axis of incidences (wi, wo (n_θ, n_ψ, n, 3), q (n_θ, n_ψ, n)): the same nodes and sums as one call per
    incidence, so the same numbers up to rounding (measured: bit-identical albedo tables of the band series).
    """
    scalar = np.ndim(theta) == 0
    th = [float(t) for t in np.atleast_1d(np.asarray(theta, dtype=float))]
    n_psi = 24
    psi = (np.arange(n_psi) + 0.5) * (np.pi / n_psi)
    a = np.array([[math.sin(t)] for t in th])                            # (n_θ, 1)
    # distance from the mirror point (−a, 0) to the unit circle along (cos ψ, sin ψ), in direction cosines
    b = -a * np.cos(psi)
    t_rim = -b + np.sqrt(np.maximum(b * b - (a * a - 1.0), 0.0))
    q_rim = k * t_rim                                                    # (n_θ, n_psi)
    q_lo = np.minimum(min(1e-3 / length_scale, 1e-4 * k), 0.25 * q_rim)
    x = np.linspace(0.0, 1.0, 300)
    q1 = np.concatenate([np.zeros(q_rim.shape + (1,)),
                         q_lo[..., None] * (0.5 * q_rim / q_lo)[..., None] ** x], axis=-1)   # to q_rim/2
    tau = np.linspace(0.0, 1.0, 161) * np.sqrt(0.5 * q_rim)[..., None]
    q2 = q_rim[..., None] - tau ** 2                                     # q_rim/2 .. q_rim
    wi = np.array([[math.sin(t), 0.0, math.cos(t)] for t in th])        # (n_θ, 3)
    total = np.zeros(len(th))
    for q, jac, var in ((q1, 1.0, q1), (q2, 2 * tau, tau)):
        u = q / k * np.cos(psi)[:, None] - a[..., None]
        v = q / k * np.sin(psi)[:, None]
        z = np.sqrt(np.clip(1.0 - u * u - v * v, 0.0, 1.0))
        ok = z > 0
        wo = np.stack([u, v, np.where(ok, z, 1.0)], axis=-1)
        wi_b = np.broadcast_to(wi[:, None, None, :], wo.shape)
        # a scalar θ hands the lobe arrays without the leading axis (n_ψ, n), as before arrays of θ were taken
        f = np.where(ok, lobe(wi_b[0], wo[0], q[0])[None] if scalar else lobe(wi_b, wo, q), 0.0)
        # du dv = q dq dψ / k²; the second piece integrates over τ with dq = 2τ dτ
        total += 2.0 * np.sum(integrate.trapezoid(f * q * jac, var, axis=-1), axis=-1) * (np.pi / n_psi) / k ** 2
    return float(total[0]) if scalar else total
