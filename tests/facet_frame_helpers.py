"""Helpers shared by the facet-frame tests: the facet-frame sum of the library at exactly one direction pair, and
the local frames the Monte-Carlo references build (written from the paper, not the package)."""
import numpy as np

from waveoptics.brdf import facet_frame_diffraction
from waveoptics.scatter.grid import DirectionGrid


def facet_frame_at(a, c, lam, mat, micro, nano, table):
    """The diffracted part (1/sr) at incidence *a* and exit *c*: the pair turned so that *a* lies at azimuth 0, *c*
    the one direction of a cell of width 2e-7, read from facet tables on *table*."""
    p = np.arctan2(a[1], a[0])
    rot = np.array([[np.cos(p), np.sin(p), 0.0], [-np.sin(p), np.cos(p), 0.0], [0.0, 0.0, 1.0]])
    a, c = rot @ a, rot @ c
    cell = DirectionGrid(1, 1, (c[0] - 1e-7, c[0] + 1e-7), (c[1] - 1e-7, c[1] + 1e-7))
    d, _, _ = facet_frame_diffraction(a, [lam], mat, micro, nano, cell, lambda x, w: mat.F(x, w), table_grid=table)
    return d[0, 0, 0]


def local_pair(ci, co, cio):
    """Directions in a facet's frame (z = m) with the cosines *ci* = i·m, *co* = o·m and *cio* = i·o: i in the x-z
    plane, o at the azimuth that keeps i·o."""
    si = np.sqrt(np.maximum(1.0 - ci * ci, 0.0))
    so = np.sqrt(np.maximum(1.0 - co * co, 0.0))
    x = np.clip(np.where(si > 1e-12, (cio - ci * co) / np.maximum(si, 1e-12), 0.0), -so, so)
    y = np.sqrt(np.maximum(so * so - x * x, 0.0))
    return np.stack([si, 0 * si, ci], axis=-1), np.stack([x, y, co], axis=-1)


def tangents(h):
    """Two unit tangents of the unit vectors *h* (..., 3), m_z > 0 (Gram-Schmidt against the x axis or y axis)."""
    a = np.where(np.abs(h[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t = a - np.sum(a * h, axis=-1, keepdims=True) * h
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    return t, np.cross(h, t)
