"""Rim tables of :class:`waveoptics.brdf.TabulatedTwoScaleBRDF`: the diffracted part near the horizon on a grid in
(cos θ_o, φ_o) instead of direction cosines.

A direction-cosine cell of width du spans an angle du / cos θ_o: 1.2° at the pole but 5.7° at 78° and 11° at
the horizon on 96² cells. Towards the horizon the diffracted lobe is concave, and a bilinear read of such cells
lies below the facet-frame sum it interpolates (at an incidence node, read at θ_o 78-80°: 1.7-5.5 % below the
sum at that direction, Beckmann α 0.05-0.1, 96²); f(ω_i, ω_o) and f(ω_o, ω_i) read that error at different
places, and the tabulated model was non-reciprocal by up to 5.5 % with both angles ≤ 80°.

At each incidence node the rim table holds the same facet-frame sum (:func:`waveoptics.brdf.
facet_frame_diffraction`, the lobes' own route, times the node's energy-guard factor) at the directions of a grid
uniform in cos θ_o over [0, cos :data:`RIM_THETA_DEG`] (cell centres) and in φ_o over [−180°, 180°]:
:data:`RIM_CELLS` = (18, 73) nodes, 1.4-1.6° apart in θ_o and 5° in φ_o (2.5° gave the same reciprocity, 1.58 / 1.08
% against 1.60 / 1.11 %, at twice the cost: the rim doubled the facet-frame kernel's work on 64² tables). Both
signs of φ_o: the lobe of an isotropic surface is even in φ_o, but the facet-frame quadrature's sum is not exactly
(Beckmann α 0.3, light at 62.4°, exit at 78.7°: 0.002736 at φ_o = +53.3° against 0.002816 at −53.3°; reciprocal for
each sign), and a table over |φ_o| made the model non-reciprocal by 2.4 % there. The read blends it with the
direction-cosine table by :func:`rim_weight`, 0 up to :data:`RIM_BLEND_DEG` [0] and 1 from [1] on, so the model is
continuous and equals the main table where its cells are fine. Measured at an incidence node (Beckmann α 0.05, ABC σ
20 nm, gold, 128²), at 40 seeded random exits per band against the sum at each: max / mean error 0.68 / 0.19 % at
θ_o 70-80°, 0.45 / 0.18 % at 80-85°, 0.85 / 0.30 % at 85-89° (with 2.5° in φ_o and the facet tables' former
bilinear read of g near their rim: 0.46 / 0.19 %, 0.52 / 0.25 %, 8.4 / 1.1 %), where the direction-cosine cells alone give 2.6 / 1.1 %, 36 / 5.2 %, 93 / 28 %.

References
----------
.. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (the facet-frame integral the tables hold).
.. [2] F. E. Nicodemus et al., NBS Monograph 160, 1977 (Helmholtz reciprocity, the property the tables restore).
"""
from __future__ import annotations

import numpy as np

from ..materials import get_material
from .roughness_scales import Micro, Nano
from .twoscale_frame import facet_frame_diffraction

__all__ = ['RIM_THETA_DEG', 'RIM_BLEND_DEG', 'RIM_CELLS', 'DirectionPoints', 'rim_cos_nodes', 'rim_phi_nodes',
           'rim_directions', 'rim_lobes', 'rim_weight', 'rim_read', 'pchip_slopes', 'pchip_between',
           'rim_across_incidence', 'RIM_LIGHT_AZIMUTHS', 'RIM_LOG_FLOOR', 'rim_light_azimuths', 'rim_light_nodes',
           'rim_across_light_azimuth']

#: polar angle (degrees) from which the rim table reaches to the horizon
RIM_THETA_DEG = 63.0
#: polar angles (degrees) of the exit over which the read hands over from the direction-cosine table to the rim
#: table (linear in cos θ_o)
RIM_BLEND_DEG = (65.0, 69.0)
#: nodes of a rim table: (cos θ_o, φ_o)
RIM_CELLS = (18, 73)
#: light azimuths (evenly spaced over [0°, 360°)) of the rim tables of an anisotropic analytic micro NDF (a measured
#: slope table keeps its main nodes': ``TabulatedTwoScaleBRDF._rim_at_light_azimuths``), at least; a table
#: with more main azimuth nodes rounds it up to a multiple of them (:func:`rim_light_azimuths`). Near the horizon
#: such a lobe changes by orders of magnitude with the light's azimuth (Al, Beckmann α 0.15 × 0.4, Gaussian σ 15 nm,
#: T 1.5 µm, 550 nm, θ_i 30°, exit 85° forward: 4.4e-4 to 0.069 /sr between φ_i 0° and 90°; exit 70°: 1e7x).
#: Facet-frame sums every 2.5° of φ_i read between nodes (max error where the lobe is above 1e-3 of its largest
#: value over φ_i; θ_i 30° and 60°, exits 70-86° in and out of the plane): linear over 4 nodes (the main tables')
#: up to 300x; the monotone cubic in log f (:func:`rim_across_light_azimuth`) over 12 / 16 / 24 / 36 nodes
#: 11-85 % / 7-160 % / 0.2-33 % / 0.1-18 % for α 0.15 × 0.4 (linear over 24 nodes: up to 11x); the narrower
#: α 0.05 × 0.3 up to 3.3x with 24 nodes at exit 70° where the lobe spans 13 orders of magnitude over φ_i.
RIM_LIGHT_AZIMUTHS = 24
#: rim values (1/sr) below which the read across light azimuth takes the lobe as 0: the floor of its logarithm
#: (above float32's smallest normal number, so the Dr.Jit read takes the same logarithm)
RIM_LOG_FLOOR = 1e-30


class DirectionPoints:
    """Directions (n, 3) in the shape of a one-row :class:`waveoptics.scatter.grid.DirectionGrid` (``n_v`` = 1,
    ``n_u`` = n, all inside, :meth:`directions`), so :func:`waveoptics.brdf.facet_frame_diffraction` evaluates its
    per-cell sum at exactly these directions."""

    def __init__(self, directions):
        self._w = np.asarray(directions, dtype=float).reshape(1, -1, 3)
        self.n_v, self.n_u = self._w.shape[:2]
        self.inside = np.ones((self.n_v, self.n_u), bool)

    def directions(self) -> np.ndarray:
        return self._w


def rim_cos_nodes(n_cos: int = RIM_CELLS[0]) -> np.ndarray:
    """cos θ_o of the rim table's rows (n_cos,), increasing: centres of n_cos equal cells over [0, cos θ_rim]."""
    return np.cos(np.radians(RIM_THETA_DEG)) * (np.arange(n_cos) + 0.5) / n_cos


def rim_phi_nodes(n_phi: int = RIM_CELLS[1]) -> np.ndarray:
    """φ_o (rad) of the rim table's columns (n_phi,): −π to π inclusive."""
    return np.linspace(-np.pi, np.pi, n_phi)


def rim_directions(cells=RIM_CELLS) -> np.ndarray:
    """Unit directions (n_cos, n_phi, 3) of the rim table's nodes."""
    c = rim_cos_nodes(cells[0])[:, None]
    p = rim_phi_nodes(cells[1])[None, :]
    s = np.sqrt(1.0 - c * c)
    return np.stack(np.broadcast_arrays(s * np.cos(p), s * np.sin(p), c), axis=-1)


def rim_lobes(wi, wavelengths_nm, material, micro: Micro, nano: Nano, grid, *, diffraction="kirchhoff",
              energy_scale=None, device=None, precision="float32", cells=RIM_CELLS) -> np.ndarray:
    """The diffracted part (n_λ, n_cos, n_phi) in 1/sr at the rim nodes (:func:`rim_directions`, their azimuths
    counted from the light's: turned by *wi*'s azimuth) for light from *wi*: :func:`waveoptics.brdf.
    facet_frame_diffraction` with the facet tables of the lobes on *grid* (the hemisphere grid of the main table,
    as :func:`waveoptics.brdf.evaluate` takes them) and the unpolarized F of *material*, times *energy_scale*
    (n_λ,) (the energy guard's factor of that node's lobes, 1 where it did not act). An isotropic table has its
    light at azimuth 0; an anisotropic micro NDF's table one rim table per light azimuth node."""
    mat = get_material(material)
    dirs = rim_directions(cells)
    phi = float(np.arctan2(wi[1], wi[0]))
    c, s = np.cos(phi), np.sin(phi)
    dirs = np.stack([c * dirs[..., 0] - s * dirs[..., 1], s * dirs[..., 0] + c * dirs[..., 1], dirs[..., 2]], -1)
    pts = DirectionPoints(dirs.reshape(-1, 3))
    d, _, _ = facet_frame_diffraction(np.asarray(wi, dtype=float), wavelengths_nm, mat, micro, nano, pts,
                                      lambda c, lam: mat.F(c, lam), diffraction=diffraction, table_grid=grid,
                                      device=device, precision=precision)
    d = d.reshape((len(wavelengths_nm),) + dirs.shape[:2])
    if energy_scale is not None:
        d = d * np.asarray(energy_scale, dtype=float).reshape(-1, 1, 1)
    return d


def rim_weight(cos_theta):
    """Weight of the rim table in the read (0 to 1): 0 for θ_o ≤ :data:`RIM_BLEND_DEG` [0], 1 from [1] on,
    linear in cos θ_o between."""
    c0, c1 = np.cos(np.radians(RIM_BLEND_DEG))
    return np.clip((c0 - np.asarray(cos_theta, dtype=float)) / (c0 - c1), 0.0, 1.0)


def rim_read(rim, k, j, x, y, z, q=None):
    """Bilinear values (n, n_j) of the rim tables *rim* (n_θ, n_λ, n_cos, n_phi) of incidence nodes k (n,) at
    wavelength indices j (n_j,), at directions (x, y, z) (n,) each; rows and columns clamped at the table's
    ends. With *q* (n,), *rim* holds one set per light azimuth node (n_q, n_θ, n_λ, n_cos, n_phi) and each point
    reads node q's."""
    n_cos, n_phi = rim.shape[-2:]
    top = np.cos(np.radians(RIM_THETA_DEG))
    fc = np.asarray(z, dtype=float) * n_cos / top - 0.5
    fp = (np.arctan2(y, x) + np.pi) * (n_phi - 1) / (2 * np.pi)
    c0 = np.clip(np.floor(fc).astype(int), 0, n_cos - 2)
    p0 = np.clip(np.floor(fp).astype(int), 0, n_phi - 2)
    ac = np.clip(fc - c0, 0.0, 1.0)[:, None]
    ap = np.clip(fp - p0, 0.0, 1.0)[:, None]
    k = np.broadcast_to(k, c0.shape)[:, None]
    j = np.asarray(j)[None, :]
    c0, p0 = c0[:, None], p0[:, None]
    if q is not None:   # (n_q, n_θ, ...) read as (n_q · n_θ, ...)
        k = np.broadcast_to(q, c0.shape[:1])[:, None] * rim.shape[1] + k
        rim = rim.reshape((-1,) + rim.shape[2:])
    return ((1 - ac) * ((1 - ap) * rim[k, j, c0, p0] + ap * rim[k, j, c0, p0 + 1])
            + ac * ((1 - ap) * rim[k, j, c0 + 1, p0] + ap * rim[k, j, c0 + 1, p0 + 1]))


def pchip_slopes(h0, h1, d0, d1, edge: bool, where=np.where):
    """Slopes of the monotone piecewise-cubic Hermite interpolant (Fritsch & Carlson 1980) at a node between
    intervals of widths *h0*, *h1* whose secant slopes are *d0*, *d1* (arrays, broadcast): the weighted harmonic
    mean (w1 + w2) / (w1/d0 + w2/d1), w1 = 2 h1 + h0, w2 = h1 + 2 h0 (Fritsch & Butland 1984), 0 where the secants
    differ in sign or either is 0. With *edge* (an end node: h0, d0 its own interval, h1, d1 the next one
    inwards) the three-point end formula ((2 h0 + h1) d0 − h0 d1) / (h0 + h1), 0 where its sign differs from d0's,
    3 d0 where the secants differ in sign and it exceeds 3 |d0|; with no next interval (h1 = 0) d0. The rules of
    scipy's ``PchipInterpolator``. *where*: ``np.where``, or ``drjit.select`` for the Dr.Jit plugin's read (the
    same arithmetic on its arrays).

    References
    ----------
    .. [1] F. N. Fritsch, R. E. Carlson, SIAM J. Numer. Anal. 17(2), 238-246, 1980 (monotone cubic Hermite).
    .. [2] F. N. Fritsch, J. Butland, SIAM J. Sci. Stat. Comput. 5(2), 300-304, 1984 (the harmonic-mean slopes).
    """
    if not edge:
        w1, w2 = 2 * h1 + h0, h1 + 2 * h0
        same = d0 * d1 > 0
        return where(same, (w1 + w2) / where(same, w1 / where(same, d0, 1.0) + w2 / where(same, d1, 1.0), 1.0), 0.0)
    end = ((2 * h0 + h1) * d0 - h0 * d1) / where(h0 + h1 > 0, h0 + h1, 1.0)
    end = where(end * d0 > 0, end, 0.0)                     # sign(end) ≠ sign(d0) (or d0 = 0): 0
    end = where((d0 * d1 <= 0) & (abs(end) > 3 * abs(d0)), 3 * d0, end)
    return where(h1 > 0, end, d0)


def pchip_between(v, th, t, where=np.where):
    """The monotone cubic Hermite interpolant (:func:`pchip_slopes`) of the four nodes a − 1, a, a + 1, a + 2 with
    values *v* and positions *th* (sequences of 4 arrays; an end node repeated where the nodes are clamped at an
    end, so that interval has width 0 and its end formula applies) at the fraction *t* of the interval a to a + 1.
    *where* as in :func:`pchip_slopes`.

    References
    ----------
    .. [1] F. N. Fritsch, R. E. Carlson, SIAM J. Numer. Anal. 17(2), 238-246, 1980 (the cubic Hermite basis).
    """
    h = [th[s + 1] - th[s] for s in range(3)]                     # 0 where clamped at an end
    d = [where(hh > 0, (v[s + 1] - v[s]) / where(hh > 0, hh, 1.0), 0.0) for s, hh in enumerate(h)]
    m1 = where(h[0] > 0, pchip_slopes(h[0], h[1], d[0], d[1], False, where),
               pchip_slopes(h[1], h[2], d[1], d[2], True, where))
    m2 = where(h[2] > 0, pchip_slopes(h[1], h[2], d[1], d[2], False, where),
               pchip_slopes(h[1], h[0], d[1], d[0], True, where))
    s2, s3 = t * t, t * t * t
    return ((2 * s3 - 3 * s2 + 1) * v[1] + (s3 - 2 * s2 + t) * h[1] * m1 + (3 * s2 - 2 * s3) * v[2]
            + (s3 - s2) * h[1] * m2)


def rim_across_incidence(rim, thetas, a, t, j, x, y, z, q=None):
    """The rim tables *rim* (n_θ, n_λ, n_cos, n_φ) of incidence nodes *thetas* (rad) read at (x, y, z) (n,) each
    (:func:`rim_read`, wavelength indices *j*) and interpolated over incidence between node a (n,) and a + 1 at
    the fraction t (n,) of the interval, (n, n_j): the monotone cubic Hermite interpolant of the four nodes a − 1
    to a + 2 (:func:`pchip_slopes`; the end formula at the first and last intervals; t = 0 at and beyond the last
    node reads that node); *q* as in :func:`rim_read`. At a fixed exit near the horizon the lobe rises steeply as
    θ_i nears the exit's mirror
    angle: linear between nodes 3-5° apart it read the Monte-Carlo facet-frame integral 2.6-4.3 % high at
    θ_o 85° forward (θ_i 74-80°, Beckmann α 0.3, Al, ABC σ 10 nm, B 2 µm, C 2.6, 550 nm; nodes 65-84°: this
    interpolant of the same reference within 0.4 %, α 0.05 within 0.4 % too, linear 0.6-0.8 %); monotone, it stays
    between the two nodes' values where they bracket no extremum, so never below 0.

    References
    ----------
    .. [1] F. N. Fritsch, R. E. Carlson, SIAM J. Numer. Anal. 17(2), 238-246, 1980.
    """
    last = thetas.size - 1
    k = [np.clip(a + s, 0, last) for s in (-1, 0, 1, 2)]
    return pchip_between([rim_read(rim, kk, j, x, y, z, q) for kk in k], [thetas[kk][:, None] for kk in k],
                         np.asarray(t, dtype=float)[:, None])


def rim_light_azimuths(n_phi: int) -> int:
    """Light azimuth nodes of the rim tables of an anisotropic table with *n_phi* main azimuth nodes: the least
    multiple of *n_phi* that is at least :data:`RIM_LIGHT_AZIMUTHS` (so the main nodes are among them)."""
    n_phi = max(int(n_phi), 1)
    return n_phi * -(-RIM_LIGHT_AZIMUTHS // n_phi)


def rim_light_nodes(phi_i, n_q: int):
    """The light azimuth nodes q − 1, q, q + 1, q + 2 (a list of 4 index arrays, periodic) around each φ_i (n,) (rad)
    among *n_q* nodes 2π/n_q apart from 0, and the fraction t (n,) of the interval q to q + 1."""
    f = np.mod(np.asarray(phi_i, dtype=float), 2 * np.pi) * n_q / (2 * np.pi)
    a = np.floor(f)
    t = f - a
    a = a.astype(int)
    return [np.mod(a + s, n_q) for s in (-1, 0, 1, 2)], t


def rim_across_light_azimuth(rim, thetas, phi_i, a, t, j, x, y, z):
    """The rim tables *rim* (n_q, n_θ, n_λ, n_cos, n_phi) of an anisotropic micro NDF, one set per light azimuth
    node (2π/n_q apart from 0, each in its light's frame), read at (x, y, z) (n,) for light at azimuth φ_i (n,)
    (rad) and incidence between node a and a + 1 at the fraction t (:func:`rim_across_incidence` at each of the
    four light azimuth nodes around φ_i), interpolated across φ_i by the monotone cubic (:func:`pchip_between`,
    periodic) of log f, (n, n_j). A light azimuth turns the NDF's axes under the light, and towards the horizon the
    lobe changes by orders of magnitude with it, close to exponentially: linear in f over 4 nodes it read up to
    300x off, in log f over 24 nodes within 0.2-33 % (:data:`RIM_LIGHT_AZIMUTHS`). Monotone per interval, the read
    lies between the values of the two nodes around φ_i; where both are below :data:`RIM_LOG_FLOOR` it is 0.
    One node (an isotropic table, its light's azimuth turned onto the node's) reads that node.

    References
    ----------
    .. [1] F. N. Fritsch, R. E. Carlson, SIAM J. Numer. Anal. 17(2), 238-246, 1980 (monotone cubic Hermite).
    """
    if rim.shape[0] == 1:
        return rim_across_incidence(rim[0], thetas, a, t, j, x, y, z)
    qs, tq = rim_light_nodes(phi_i, rim.shape[0])
    vals = [rim_across_incidence(rim, thetas, a, t, j, x, y, z, q) for q in qs]
    logs = [np.log(np.maximum(v, RIM_LOG_FLOOR)) for v in vals]
    pos = [np.full((tq.size, 1), float(s)) for s in (-1, 0, 1, 2)]
    out = np.exp(pchip_between(logs, pos, tq[:, None]))
    return np.where(np.maximum(vals[1], vals[2]) > RIM_LOG_FLOOR, out, 0.0)
