"""Pieces of μ = |cos θ| on which an albedo or coherent-factor table of a dielectric interface is smooth: [0, 1], or
pieces split at the critical cosine of light from the denser side (total internal reflection) and, for a rough
interface's albedo, where the facets' critical circle touches their horizon (:func:`albedo_cuts`), with a variable
t per piece that crowds nodes quadratically towards the kinks (used by :func:`waveoptics.brdf.nano_tables` and
:func:`waveoptics.brdf.dielectric_tables`).

References
----------
.. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.4 (total reflection: the √ kink of the Fresnel
   factors at the critical angle).
"""
from __future__ import annotations

import numpy as np

__all__ = ["critical_cosine", "albedo_cuts", "table_pieces", "split_pieces", "piece_variable", "piece_cosine",
           "read_pieces"]


def critical_cosine(n_i, n_o):
    """μ_c = √(1 − (n_o/n_i)²), the cosine of the critical angle of light from index *n_i* onto *n_o* (real), or
    0 when n_i ≤ n_o (no total internal reflection). Dimensionless.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.4 (total reflection).
    """
    r = float(n_o) / float(n_i)
    return float(np.sqrt(1.0 - r * r)) if r < 1.0 else 0.0


def albedo_cuts(eta):
    """The cosines μ (dimensionless) where the single-scattering albedo of light from inside a dielectric of index
    *eta* (> 1) is not smooth: μ_c = √(1 − 1/η²), where the facets' circle of total internal reflection
    (|ω_i·m| = μ_c) passes the macro normal (a √ kink as α → 0), and 1/η = sin θ_c, where it touches the facets'
    horizon (m_z = 0); none for *eta* ≤ 1.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.4 (total reflection).
    """
    mu_c = critical_cosine(eta, 1.0)
    return (mu_c, float(np.sqrt(1.0 - mu_c * mu_c))) if mu_c > 0.0 else ()


def table_pieces(mu_c):
    """The pieces (lo, hi, kink at lo?, kink at hi?) of μ ∈ [0, 1] on which the tables are smooth: [0, 1], or
    [0, μ_c] and [μ_c, 1] split at a critical cosine *mu_c* > 0, where the coherent transmission vanishes as
    cos θ_t = √(1 − n² sin²θ) and the first-order TIS and the coherent factors have a √ kink (as the Fresnel
    factors: Born & Wolf §1.5.4)."""
    return split_pieces((mu_c,))


def split_pieces(cuts):
    """The pieces (lo, hi, kink at lo?, kink at hi?) of μ ∈ [0, 1] between the *cuts* inside (0, 1) (kinks of the
    tabulated function; others are dropped): [0, 1] without cuts."""
    inner = sorted({float(c) for c in cuts if 0.0 < c < 1.0})
    edges = [0.0] + inner + [1.0]
    return tuple((a, b, j > 0, j < len(inner)) for j, (a, b) in enumerate(zip(edges[:-1], edges[1:])))


def piece_variable(mu, piece):
    """The variable t ∈ [0, 1] of a *piece* (:func:`table_pieces`) at cosines *mu*: with s = (μ − lo)/(hi − lo),
    t = s, or √s at a kink at lo and 1 − √(1 − s) at a kink at hi, so that a function a + b √|μ − μ_c| is smooth
    (linear) in t near the kink (the nodes crowd quadratically towards it); arccos(1 − 2s)/π between two kinks
    (quadratic at both ends)."""
    lo, hi, k_lo, k_hi = piece
    s = np.clip((np.asarray(mu, dtype=float) - lo) / (hi - lo), 0.0, 1.0)
    if k_lo and k_hi:
        return np.arccos(1.0 - 2.0 * s) / np.pi
    if k_lo:
        return np.sqrt(s)
    if k_hi:
        return 1.0 - np.sqrt(1.0 - s)
    return s


def piece_cosine(t, piece):
    """The inverse of :func:`piece_variable`: μ at *t* on *piece*."""
    lo, hi, k_lo, k_hi = piece
    t = np.asarray(t, dtype=float)
    if k_lo and k_hi:
        s = 0.5 * (1.0 - np.cos(np.pi * t))
    else:
        s = t * t if k_lo else (1.0 - (1.0 - t) ** 2 if k_hi else t)
    return lo + (hi - lo) * s


def read_pieces(mu, pieces, t, values):
    """A table read back at cosines *mu*: *values* (pieces, samples) of each of the *pieces*
    (:func:`table_pieces`, :func:`split_pieces`) sampled at the points *t* of its variable
    (:func:`piece_variable`), linear in t between samples; a cut reads the piece below it."""
    mu = np.clip(np.asarray(mu, dtype=float), 0.0, 1.0)
    out = np.interp(piece_variable(mu, pieces[0]), t, values[0])
    for j, p in enumerate(pieces[1:], start=1):
        out = np.where(mu > p[0], np.interp(piece_variable(mu, p), t, values[j]), out)
    return out
