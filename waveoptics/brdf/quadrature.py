"""Directional albedo of a BRDF by quadrature over microfacet normals (nodes follow the NDF's width; a measured
slope table's nodes follow its bins, :func:`table_nodes`).

References
----------
.. [1] B. Walter et al., EGSR 2007, eq. (14) (Jacobian of the reflection mapping).
.. [2] P. J. Davis, P. Rabinowitz, *Methods of Numerical Integration*, 2nd ed., 1984, §2.7 (Gauss-Legendre rules,
   exact for polynomials of degree 2k − 1 on each panel; a panel edge at each discontinuity of the integrand).
"""
from __future__ import annotations

import functools
import itertools
from typing import Callable

import numpy as np

from .microfacet import brdf
from .directions import as_dirs, reflect
from .ndf import ALPHA_MIN
from .smith import gl01

__all__ = ['NODE_BLOCK', 'TABLE_GL_ORDER', 'normal_quadrature', 'table_nodes', 'directional_albedo', 'albedo',
           'slope_table_of']

# ----------------------------------------------------------------------------------------------------------
# quadrature over microfacet normals and directional albedo


#: most quadrature nodes held at once: the nodes are made and used one radial block at a time, so memory stays
#: bounded whatever the anisotropy (the node count grows with α_max/α_min; all at once took 3.1 GB for α = 2,
#: α_y = 0.001)
NODE_BLOCK = 1 << 18


def _radial_nodes(ax, ay, n_rho):
    """Radial nodes ρ and weights (stretched slope units) of :func:`normal_quadrature`."""
    x, w = gl01(n_rho)
    amin = min(ax, ay)
    # radial segments in stretched slope units ρ (slope = (α_x ρ cos φ, α_y ρ sin φ)): geometric edges from
    # ρ = 1/8 until the slope reaches 8 (θ_m ≈ 83°), then a tail [ρ_K, ∞) mapped by ρ = ρ_K / t
    kmax = int(np.ceil(np.log2(8.0 / amin)))
    edges = 2.0 ** np.arange(-3, max(kmax, -2) + 1)
    # also an edge at slope 1 (θ_m = 45°), where the reflected direction of normal incidence meets the horizon
    # (a kink of the integrand of directional_albedo): it replaces the geometric edge closest to it
    k1 = 1.0 / max(ax, ay)
    if edges[0] < k1 < edges[-1]:
        edges[np.argmin(np.abs(np.log(edges / k1)))] = k1
    edges = np.concatenate([[0.0], np.sort(edges)])
    rho, wr = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        rho.append(a + (b - a) * x)
        wr.append((b - a) * w)
    rk = edges[-1]
    rho.append(rk / x)
    wr.append(rk / x ** 2 * w)
    return np.concatenate(rho), np.concatenate(wr)


def _node_blocks(ax, ay, n_rho, n_phi):
    """The nodes of :func:`normal_quadrature` in blocks of at most about :data:`NODE_BLOCK` (m (K, 3), w (K,))."""
    rho, wr = _radial_nodes(ax, ay, n_rho)
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    step = max(1, NODE_BLOCK // n_phi)
    for a in range(0, rho.size, step):
        R, P = np.meshgrid(rho[a:a + step], phi, indexing="ij")
        WR = np.broadcast_to(wr[a:a + step, None], R.shape)
        sx = ax * R * np.cos(P)
        sy = ay * R * np.sin(P)
        cz = 1.0 / np.sqrt(1.0 + sx * sx + sy * sy)
        m = np.stack([-sx * cz, -sy * cz, cz], axis=-1).reshape(-1, 3)
        # dω_m = cos³θ_m d²slope, d²slope = α_x α_y ρ dρ dφ
        yield m, (cz ** 3 * ax * ay * R * WR * (2 * np.pi / n_phi)).ravel()


@functools.lru_cache(maxsize=64)
def _normal_nodes(ax, ay, n_rho, n_phi):
    m, w = (np.concatenate(a) for a in zip(*_node_blocks(ax, ay, n_rho, n_phi)))
    m.setflags(write=False)
    w.setflags(write=False)
    return m, w


def _angular_nodes(ax, ay, n_phi):
    """φ nodes for a lobe of widths (α_x, α_y): far from an anisotropic lobe the φ integrand is peaked (width
    ~ α_min/α_max), so their number grows with the ratio (measured: Σ weights = 2π to 1e-8 up to a ratio of 100;
    an albedo at ratio 2000 within 1e-4 of a Monte Carlo estimate from the visible-normal sampler)."""
    ratio = max(ax, ay) / min(ax, ay)
    return int(n_phi) * max(1, int(np.ceil(ratio / 3.0)))


def normal_quadrature(alpha=1.0, alpha_y=None, *, n_rho=16, n_phi=64):
    """Quadrature nodes over the hemisphere of microfacet normals that resolve a lobe of width α.

    Slope space is sampled in polar coordinates stretched by (α_x, α_y): Gauss-Legendre (*n_rho* nodes) on
    geometrically growing radial segments from 1/8 α to slope 8, a mapped tail to infinite slope, and the
    midpoint rule (spectrally accurate for periodic integrands) with *n_phi* nodes in φ, multiplied by
    ⌈α_max/(3 α_min)⌉ for anisotropic lobes. dω = cos³θ d²slope.

    Parameters
    ----------
    alpha, alpha_y : float
        Lobe widths (slope units); the finer one sets the smallest segment. Floored at :data:`ALPHA_MIN`.

    Returns
    -------
    m : ndarray (K, 3)
        Unit normals with m_z > 0.
    weights : ndarray (K,)
        Solid-angle weights in sr (they sum to 2π).
    """
    ax = max(float(alpha), ALPHA_MIN)
    ay = ax if alpha_y is None else max(float(alpha_y), ALPHA_MIN)
    return _normal_nodes(ax, ay, int(n_rho), _angular_nodes(ax, ay, n_phi))


#: Gauss-Legendre points per slope axis in each bin of a slope table (:func:`table_nodes`)
TABLE_GL_ORDER = 2


@functools.lru_cache(maxsize=8)
def table_nodes(table):
    """Quadrature nodes over the normals whose slopes lie in the square [−L, L]² of a slope table
    (:class:`waveoptics.brdf.SlopeTable`), laid on its bins: :data:`TABLE_GL_ORDER`² Gauss-Legendre points per bin.

    A tabulated D(m) = P22 / cos⁴θ_m is piecewise constant in slope space, discontinuous at every bin edge; nodes
    placed by a smooth lobe's width (:func:`normal_quadrature`) straddle those edges, and their rule, exact for
    smooth integrands, is not for a step: on a measured table (Gaussian surface, 64² bins, α ≈ 0.066) the albedo
    of the F = 1 specular lobe came out 1.00127 at normal incidence, where it is 1 (∫ D cos θ_m dω = 1, Λ = 0).
    With a panel per bin the integrand is smooth on each panel (Davis & Rabinowitz §2.7): 1 to 1e-6.

    Returns
    -------
    m : ndarray (K, 3)
        Unit normals, K = (n bins × :data:`TABLE_GL_ORDER`)² (every bin of the square, empty ones too: the other
        terms of a BRDF still need nodes there).
    weights : ndarray (K,)
        Solid-angle weights in sr: dω_m = cos³θ_m d²slope.
    """
    x, w = gl01(TABLE_GL_ORDER)
    edges = -table.L + np.arange(table.n) * table.step
    s = (edges[:, None] + table.step * x[None, :]).ravel()
    ws = np.broadcast_to(table.step * w, (table.n, x.size)).ravel()
    SX, SY = np.meshgrid(s, s)
    cz = 1.0 / np.sqrt(1.0 + SX * SX + SY * SY)
    m = np.stack([-SX * cz, -SY * cz, cz], axis=-1).reshape(-1, 3)
    wm = (cz ** 3 * ws[None, :] * ws[:, None]).ravel()
    m.setflags(write=False)
    wm.setflags(write=False)
    return m, wm


def _outside_table(blocks, table):
    """The nodes of *blocks* (m, w) with the weights of the normals inside *table*'s slope square set to 0 (there
    :func:`table_nodes` integrate), so that both sets together cover the hemisphere once."""
    for m, wm in blocks:
        inside = (np.abs(m[:, 0]) < table.L * m[:, 2]) & (np.abs(m[:, 1]) < table.L * m[:, 2])
        yield m, np.where(inside, 0.0, wm)


def directional_albedo(f: Callable, wi, *, alpha=1.0, alpha_y=None, n_rho=16, n_phi=64, table=None):
    """Directional albedo E(wi) = ∫ f(wi, wo) cos θ_o dω_o by quadrature over half-vectors.

    The integral is written over h (wo = 2(wi·h)h − wi, dω_o = 4 (wi·h) dω_h) with the nodes of
    :func:`normal_quadrature`, which concentrate at the mirror direction with the lobe width α and still cover
    the whole hemisphere, so both a sharp lobe (α = 0.001) and a diffuse term are resolved. Nodes whose
    reflected direction is below the surface contribute 0; f cos θ_o is continuous there for physical BRDFs,
    so the error stays small (Lambert: |E − 1| < 1e-4 for α in [0.001, 1], ``tests/test_microfacet.py``).

    Parameters
    ----------
    f : callable
        f(wi, wo) -> BRDF (1/sr); called with wi of shape (n, 1, 3) and wo of shape (n, K, 3); it may add
        leading axes (e.g. wavelength), which are kept.
    wi : array_like (3,) or (n, 3)
        Incident unit direction(s), above the surface.
    alpha, alpha_y : float
        Width of the sharpest lobe of f (slope units), used to place the nodes.
    table : SlopeTable, optional
        The slope table of a tabulated NDF in f (``ndf="tabulated"``): the normals in its slope square take the
        nodes of :func:`table_nodes` instead (a panel per bin, where its D is constant).

    Returns
    -------
    ndarray
        E (dimensionless) of shape (..., n) (or (...) for a single wi).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14) (Jacobian of the reflection mapping).
    """
    wi_arr = as_dirs(wi, "wi")
    single = wi_arr.ndim == 1
    wi2 = wi_arr.reshape(-1, 3)
    ax = max(float(alpha), ALPHA_MIN)
    ay = ax if alpha_y is None else max(float(alpha_y), ALPHA_MIN)
    n_ang = _angular_nodes(ax, ay, n_phi)
    # small node sets are cached whole; large (strongly anisotropic) ones are made block by block, bounded memory
    blocks = ([_normal_nodes(ax, ay, int(n_rho), n_ang)]
              if _radial_nodes(ax, ay, int(n_rho))[0].size * n_ang <= NODE_BLOCK else None)
    out = []
    for w1 in wi2:
        acc = 0.0
        nodes = blocks if blocks is not None else _node_blocks(ax, ay, int(n_rho), n_ang)
        if table is not None:
            nodes = itertools.chain([table_nodes(table)], _outside_table(nodes, table))
        for m, wm in nodes:
            ih = m @ w1
            wo = reflect(w1, m)
            jac = np.where((ih > 0) & (wo[:, 2] > 0), 4.0 * ih * wm * np.maximum(wo[:, 2], 0.0), 0.0)
            vals = np.asarray(f(w1[None, :], wo))
            acc = acc + np.sum(np.where(jac > 0, vals, 0.0) * jac, axis=-1)
        out.append(acc)
    res = np.stack(out, axis=-1)
    return res[..., 0] if single else res


def albedo(wi, **kwargs):
    """Directional albedo ∫ f cos θ_o dω_o of :func:`brdf` with the given parameters (quadrature tuned to α).

    Parameters
    ----------
    wi : array_like (3,) or (n, 3)
        Incident unit direction(s).
    **kwargs
        Parameters of :func:`brdf` (``alpha`` required). Per-wavelength ``eta``/``F0``/``kd`` must have shape
        (n_λ, 1); the result then has shape (n_λ, n).
    """
    a = kwargs["alpha"]
    ay = kwargs.get("alpha_y")
    return directional_albedo(lambda a_, b_: brdf(a_, b_, **kwargs), wi, alpha=a, alpha_y=ay,
                              table=slope_table_of(kwargs.get("ndf"), kwargs.get("ndf_shape")))


def slope_table_of(ndf, ndf_shape):
    """The slope table of a tabulated NDF (its ``ndf_shape``), None for the other NDFs: what
    :func:`directional_albedo` takes as *table*."""
    return ndf_shape if ndf == "tabulated" else None
