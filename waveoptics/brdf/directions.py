"""Unit directions of the BRDF: validation of direction arrays, the half-vector and the mirror direction.

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, eqs. (13)-(14) (half-vector of reflection).
"""
from __future__ import annotations

import numpy as np

from ..errors import WaveopticsError

__all__ = ['half_vector', 'reflect']


def dot_last(a, b):
    """a·b over the last axis (arrays broadcast). For 3-vectors the three products are summed in order, which is
    what ``np.sum(a * b, axis=-1)`` gives, bit for bit, at a third of its time (a reduction over a length-3 axis
    is slow in NumPy)."""
    a, b = np.asarray(a), np.asarray(b)
    if a.shape[-1:] == (3,) and b.shape[-1:] == (3,):
        return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]
    return np.sum(a * b, axis=-1)


def as_dirs(w, name):
    w = np.asarray(w, dtype=np.float64)
    if w.shape[-1:] != (3,):
        raise WaveopticsError(f"{name} must have shape (..., 3) (unit vectors), got {w.shape}")
    if not np.all(np.isfinite(w)):
        raise WaveopticsError(f"{name} contains non-finite values; directions must be finite unit vectors")
    norm = np.linalg.norm(w, axis=-1, keepdims=True)
    # guard: a zero vector is not a direction; it is treated as below the surface (result 0)
    return np.where(norm > 0, w / np.where(norm > 0, norm, 1.0), np.array([0.0, 0.0, -1.0]))


def half_vector(wi, wo):
    """Unit half-vector h = (wi + wo)/|wi + wo| (returns n where wi = −wo, which only occurs below the surface).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit directions.
    """
    s = np.asarray(wi, dtype=float) + np.asarray(wo, dtype=float)
    n = np.linalg.norm(s, axis=-1, keepdims=True)
    return np.where(n > 0, s / np.where(n > 0, n, 1.0), np.array([0.0, 0.0, 1.0]))


def reflect(w, m):
    """Mirror direction of *w* about the unit normal *m*: 2 (w·m) m − w."""
    return 2.0 * dot_last(w, m)[..., None] * m - w
