"""Facet frames: the local frame of a micro facet and the fixed quadrature points over facet normals.

Each micro facet carries the nano-roughness in its own frame (z = the facet normal m): the two-scale model's
diffracted part is Walter et al.'s (2007) integral of the nano BRDF evaluated at the facet's local incidence and
exitance (docs/physics.md §7). These helpers give that frame (Duff et al. 2017's branch-free basis), the
invariants of a direction pair in it, the deterministic Sobol points the quadratures use, and the two node rules
of the facet-frame quadrature that the grid and pointwise forms share (:func:`ndf_nodes`, :func:`half_vector_nodes`:
laid out about each pair's half-vector, the same for ω_i and ω_o swapped).

References
----------
.. [1] T. Duff, J. Burgess, P. Christensen, C. Hery, A. Kensler, M. Liani, R. Villemin, "Building an
   Orthonormal Basis, Revisited", JCGT 6(1), 2017.
.. [2] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (a BRDF carried by each facet).
.. [3] I. M. Sobol', USSR Comput. Math. Math. Phys. 7(4):86-112, 1967.
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy.stats import qmc

from .. import scatter
from .anisotropy import STRETCH_EXPONENT, stretch_factors
from .directions import dot_last
from .sampling import sample_normal, sample_normal_dcos

__all__ = ['FACET_NODE_SPLIT', 'FACET_REFERENCE_NM', 'wide_micro_lobe', 'RADIAL_BINS', 'COS_LEVELS', 'unit_nodes', 'NanoRadial', 'facet_basis', 'meridian_basis', 'to_facet',
           'from_facet', 'ndf_node_base', 'ndf_nodes', 'half_vector_nodes', 'half_vector_base', 'quadrature_normals',
           'quadrature_density', 'sampler_normals', 'budget_nodes', 'BRIDGE_NODES', 'BRIDGE_GATE',
           'BRIDGE_STEPS', 'BRIDGE_SPREAD', 'BRIDGE_DENSITY',
           'bridge_point', 'bridge_offsets', 'bridge_nodes', 'bridge_density', 'with_bridge_density']

#: radial bins of the nano-lobe sampler (geometric in spatial frequency)
RADIAL_BINS = 384
#: levels of cos θ_i at which the nano-lobe sampler is tabulated (its Poisson weights depend on θ_i)
COS_LEVELS = 65


#: ratio 2α / w_n (the micro lobe's spread of mirror directions over the nano lobe's width λ/(π ℓ)) below which
#: a facet quadrature takes its narrow node set (:func:`wide_micro_lobe`)
FACET_NODE_SPLIT = 0.5
#: wavelength (nm) of the nano lobe's radial law that places the grid route's half-vector normals and of w_n in
#: :func:`wide_micro_lobe`: one for every wavelength, so that each wavelength's lobe does not depend on the others
FACET_REFERENCE_NM = 550.0


def wide_micro_lobe(alpha: float, length_scale_m: float) -> bool:
    """Whether a micro lobe of roughness *alpha* (the larger of α_x, α_y) spreads its mirror directions over at least
    :data:`FACET_NODE_SPLIT` widths of the nano lobe, w_n = λ / (π ℓ) at λ = :data:`FACET_REFERENCE_NM` with ℓ
    = *length_scale_m* (m, the PSD's correlation or inner scale): then the facet-frame integral is carried by
    normals about the half-vector as much as by the NDF's, and the quadratures take more of both
    (:func:`waveoptics.brdf.facet_nodes`, :class:`waveoptics.brdf.TwoScaleBRDF`).

    References
    ----------
    .. [1] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE (2012), §2.4 (the grating
       equation: a surface frequency f scatters to sin θ_o − sin θ_i = λ f, so a PSD of correlation length ℓ
       scatters over direction cosines ~λ / (π ℓ)).
    """
    w_n = FACET_REFERENCE_NM * 1e-9 / (math.pi * float(length_scale_m))
    return 2.0 * float(alpha) >= FACET_NODE_SPLIT * w_n


@functools.lru_cache(maxsize=8)
def unit_nodes(n: int) -> np.ndarray:
    """n points (n a power of two) of the unscrambled 2-D Sobol sequence, centred in their dyadic cells: (n, 2)
    in (0, 1)² (deterministic; Sobol' 1967)."""
    m = int(round(math.log2(n)))
    pts = qmc.Sobol(d=2, scramble=False).random_base2(m)
    return pts + 0.5 / n


class NanoRadial:
    """Radial sampler of the nano lobe about the mirror direction, for one PSD model and wavelength.

    Proposal density on the offset t = (ω_o − mirror)_xy of the direction-cosine plane: p(t) = k² ρ(k|t|) with
    ρ(q) ∝ Σ_m p_m(g_i) H_m(q) (per unit area of q), the series of :mod:`waveoptics.scatter.series` at the mirror
    roughness g_i = g(θ_i) without the obliquity and Fresnel factors, piecewise constant on :data:`RADIAL_BINS`
    annuli geometric in q and tabulated at :data:`COS_LEVELS` values of cos θ_i (nearest level used). Sampling and
    density use the same table, so they agree exactly.

    *floor* (direction cosines, 0: none) spreads the mass within that offset uniformly over the disc of the first
    annulus edge beyond it: the proposal of a lobe read from tables whose cells are *floor* wide, which hold a core
    narrower than a cell as its cell average (:func:`waveoptics.brdf.facet_tables.narrow_core_cells`). Nodes drawn
    inside the true core would read that average at the true core's density, and so count the light of the core
    times (core area / cell area): ABC B 200 µm, C 3, 450 nm on 128² tables lost 64 % of the diffracted light
    0.1-0.2 from the mirror (θ_i 30°, α 0.05) before the floor.
    """

    def __init__(self, model, wavelength_nm: float, diffraction, n_nodes: int = 128, floor: float = 0.0):
        self._n_nodes = int(n_nodes)
        self.k = 2 * np.pi / (wavelength_nm * 1e-9)
        q_hi = 2.0 * self.k
        q_max = 2.0 ** math.ceil(math.log2(q_hi * 1.001 + 1.0))
        tab = scatter.series_tables(model, q_max)
        q_lo = min(1e-2 / model.length_scale, 1e-3 * q_hi)
        self.edges = np.concatenate([[0.0], np.geomspace(q_lo, q_hi, RADIAL_BINS)])
        mid = np.concatenate([[0.5 * q_lo], np.sqrt(self.edges[1:-1] * self.edges[2:])])
        area = np.pi * np.diff(self.edges ** 2)
        dm = scatter.get_model(diffraction, perturbative=True)
        if dm.perturbative:   # a proposal only (its pdf is its own): the Kirchhoff series has the same lobe shape
            dm = scatter.get_model("kirchhoff")
        self.cos_levels = np.linspace(0.0, 1.0, COS_LEVELS)
        g = scatter.roughness_g(model.sigma, dm.specular_cos_sum(self.cos_levels), wavelength_nm)
        m_use = scatter.series_terms(float(g.max()))
        Hm = tab.Hm(mid)[:m_use]                                  # (M, bins)
        p = scatter.poisson_weights(g, m_use)                     # (M, levels)
        mass = (p.T @ Hm) * area[None, :]                         # (levels, bins)
        total = mass.sum(axis=1, keepdims=True)
        # a level with no scattered light (g = 0 at cos θ_i = 0 for the Kirchhoff phase) falls back to the m = 1
        # shape: it is only a proposal, and its density below stays consistent with it
        fallback = Hm[0] * area
        mass = np.where(total > 0, mass, fallback[None, :])
        if floor > 0:   # the lobe as a table holds it: no finer than its cells about the mirror (class doc)
            j = int(np.searchsorted(self.edges, self.k * floor))
            mass[:, :j] = mass[:, :j].sum(axis=1, keepdims=True) * area[None, :j] / (np.pi * self.edges[j] ** 2)
        self.cdf = np.cumsum(mass, axis=1)
        self.cdf /= self.cdf[:, -1:]
        self.density = (mass / mass.sum(axis=1, keepdims=True)) / area[None, :]   # per unit q area

    @functools.cached_property
    def node_radii(self):
        """Offset radii of the quadrature nodes' first coordinates at every cos θ_i level (levels, N)."""
        u = unit_nodes(self._n_nodes)[:, 0]
        return self.radius(np.arange(COS_LEVELS)[:, None], np.broadcast_to(u, (COS_LEVELS, u.size)))

    def level(self, cos_theta_i):
        return np.clip(np.rint(np.asarray(cos_theta_i) * (COS_LEVELS - 1)).astype(int), 0, COS_LEVELS - 1)

    def radius(self, level, u):
        """Offset radius |t| (direction-cosine units) for uniform u at each cos θ_i level (arrays broadcast)."""
        rows = self.cdf[level]
        b = np.sum(rows < u[..., None], axis=-1)
        b = np.minimum(b, RADIAL_BINS - 1)
        lo = np.where(b > 0, np.take_along_axis(rows, np.maximum(b - 1, 0)[..., None], -1)[..., 0], 0.0)
        hi = np.take_along_axis(rows, b[..., None], -1)[..., 0]
        frac = np.where(hi > lo, (u - lo) / np.where(hi > lo, hi - lo, 1.0), 0.5)
        q2 = self.edges[b] ** 2 + frac * (self.edges[b + 1] ** 2 - self.edges[b] ** 2)   # uniform over the annulus
        return np.sqrt(q2) / self.k

    def pdf_r(self, level, r):
        """Density per unit area of the direction-cosine plane at offsets of length *r* (arrays broadcast)."""
        q = self.k * np.asarray(r, dtype=float)
        b = np.searchsorted(self.edges, q, side="right") - 1
        ok = (b >= 0) & (b < RADIAL_BINS)
        return np.where(ok, self.density[level, np.clip(b, 0, RADIAL_BINS - 1)] * self.k ** 2, 0.0)

    def pdf_t(self, level, t):
        """Density per unit area of the direction-cosine plane of offsets t (..., 2)."""
        q = self.k * np.hypot(t[..., 0], t[..., 1])
        b = np.searchsorted(self.edges, q, side="right") - 1
        ok = (b >= 0) & (b < RADIAL_BINS)
        val = self.density[level, np.clip(b, 0, RADIAL_BINS - 1)]
        return np.where(ok, val * self.k ** 2, 0.0)


def facet_basis(m):
    """Tangent vectors (t, b) completing the unit normals *m* (..., 3) to a right-handed frame (t, b, m),
    continuous for m_z > −1 (Duff et al. 2017)."""
    m = np.asarray(m, dtype=float)
    sign = np.where(m[..., 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + m[..., 2])
    c = m[..., 0] * m[..., 1] * a
    t = np.stack([1.0 + sign * m[..., 0] ** 2 * a, sign * c, -sign * m[..., 0]], axis=-1)
    b = np.stack([c, sign + m[..., 1] ** 2 * a, -m[..., 1]], axis=-1)
    return t, b


def meridian_basis(h):
    """Tangent vectors (e1, e2) of the unit vectors *h* (..., 3) along and across their meridian:
    e1 = (cos θ cos φ, cos θ sin φ, −sin θ), e2 = (−sin φ, cos φ, 0) for h = (sin θ cos φ, sin θ sin φ, cos θ).

    Unlike :func:`facet_basis` it turns with h about the macro normal z (rotating h by ψ about z rotates e1, e2 by
    ψ), so a quadrature laid out in it is the same for every azimuth of a direction pair; a function of h alone, it
    is the same for ω_i and ω_o swapped when h is their half-vector (at h = z, φ = 0)."""
    h = np.asarray(h, dtype=float)
    phi = np.arctan2(h[..., 1], h[..., 0])
    cp, sp = np.cos(phi), np.sin(phi)
    sin_t = np.hypot(h[..., 0], h[..., 1])
    e1 = np.stack([h[..., 2] * cp, h[..., 2] * sp, -sin_t], axis=-1)
    e2 = np.stack([-sp, cp, np.zeros_like(cp)], axis=-1)
    return e1, e2


def to_facet(v, m):
    """Directions *v* (..., 3) (macro frame) in the frame (t, b, m) of :func:`facet_basis`: z = v·m."""
    t, b = facet_basis(m)
    return np.stack([dot_last(v, t), dot_last(v, b), dot_last(v, m)], axis=-1)


def from_facet(v_local, m):
    """Inverse of :func:`to_facet`: local directions (..., 3) of the facet *m* back to the macro frame."""
    t, b = facet_basis(m)
    return v_local[..., :1] * t + v_local[..., 1:2] * b + v_local[..., 2:3] * m


def local_pair(cos_i, cos_o, cos_io):
    """A pair of directions with the facet-frame cosines *cos_i*, *cos_o* (to the facet normal) and the mutual
    cosine *cos_io* = ω_i·ω_o, ω_i in the local x–z plane: every invariant of the pair in that frame (elevations,
    relative azimuth, |ω_i + ω_o|) without building the frame."""
    ci, co = np.broadcast_arrays(np.clip(cos_i, -1.0, 1.0), np.clip(cos_o, -1.0, 1.0))
    si = np.sqrt(np.maximum(1.0 - ci * ci, 0.0))
    so = np.sqrt(np.maximum(1.0 - co * co, 0.0))
    x = np.where(si > 1e-12, (cos_io - ci * co) / np.where(si > 1e-12, si, 1.0), 0.0)
    x = np.clip(x, -so, so)
    y = np.sqrt(np.maximum(so * so - x * x, 0.0))
    return (np.stack([si, np.zeros_like(si), ci], axis=-1), np.stack([x, y, co], axis=-1))




def ndf_node_base(n: int, *, ndf, ax, ay, c):
    """(m0 (n, 3), k_x, k_y): the *n* Sobol normals (:func:`unit_nodes`) with density D(m) cos θ_m of the isotropic
    law that *ndf* at (α_x, α_y) stretches (roughness ᾱ = √(α_x α_y)), and its slope stretches
    (:func:`waveoptics.brdf.anisotropy.stretch_factors`; 1, 1 and the NDF itself when α_x = α_y). Shared by
    :func:`ndf_nodes` and the kernel's host code (``kernels/facet_frame.cl``).

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, §5.3 (anisotropy by stretching the slopes).
    """
    if ay == ax:
        return sample_normal_dcos(unit_nodes(n), ndf=ndf, ax=ax, ay=ay, c=c), 1.0, 1.0
    base, kx, ky = stretch_factors(ax, ay, STRETCH_EXPONENT.get(ndf, 1.0))
    return sample_normal_dcos(unit_nodes(n), ndf=ndf, ax=float(base), ay=float(base), c=c), float(kx), float(ky)


def ndf_nodes(n: int, e2, *, ndf, ax, ay, c):
    """The NDF's normals of the facet-frame quadratures (:func:`waveoptics.brdf.facet_frame_diffraction`, the
    diffracted part of :class:`waveoptics.brdf.TwoScaleBRDF`): *n* Sobol points (:func:`unit_nodes`) drawn with
    density D(m) cos θ_m (:func:`waveoptics.brdf.sample_normal_dcos`), which does not depend on ω_i, so ω_i and ω_o
    swapped get the same nodes. For an isotropic NDF (*ax* = *ay*) they are turned about z to each direction pair's
    half-vector azimuth (*e2* (n_pairs, 3) = (−sin φ_h, cos φ_h, 0), :func:`meridian_basis` of h), so that a pair
    at any azimuth gets the same nodes relative to it (D(m) cos θ_m is unchanged by the turn). An anisotropic NDF,
    the stretch of an isotropic one (Heitz 2014 §5.3: slopes (k_x x̃, k_y ỹ) of the isotropic law of roughness
    ᾱ = √(α_x α_y), :func:`waveoptics.brdf.anisotropy.stretch_factors`), gets the isotropic law's nodes turned in
    its unstretched slope plane to the azimuth of h's unstretched slopes, atan2(sin φ_h / k_y, cos φ_h / k_x), and
    stretched: their density is D(m) cos θ_m still, and they depend on h alone (reciprocal). Fixed in the
    surface's frame they read the anisotropic facet-frame sum at exits 80-88° 0.89-1.25 of a Monte-Carlo facet
    integral (Beckmann α 0.15 × 0.4, tests/test_anisotropic_rim.py). Yields, node by node, (n_pairs, 3) normals
    (a slope table: (3,), fixed in the surface's frame). A slope table
    (``tabulated``) is never turned, whatever its α and α_y: its D, constant on square bins of slope space, is not
    unchanged by a turn, and turned nodes would not have the density D(m) cos θ_m the quadrature weights them by.

    Measured on the grid route against 4096 + 1024 normals (ABC σ = 10 nm, B = 2 µm, C = 2.6, Beckmann, 550 nm,
    20 pairs θ 3-65°): α = 0.1 with 64 + 16 normals rms 1.2 %, max 1.7 % (the earlier normals fixed in the
    surface's frame: 2.1 %, 4.9 %); α = 0.3 with 64 + 64 rms 1.0 %, max 3.5 % (0.5 %, 1.2 %). Rings of 8 evenly
    spaced azimuths instead were within 2.6 % and 2.0 % but lost 0.3 % of the albedo at 450 nm
    (tests/test_twoscale.py, Gaussian PSD).

    Parameters
    ----------
    n : int
        Number of normals (a power of two).
    e2 : ndarray (n_pairs, 3)
        The across-meridian tangent of each pair's half-vector (:func:`meridian_basis`); not used for a slope
        table.
    ndf, ax, ay, c
        The micro NDF's name, roughness along x and y and shape parameter (:func:`waveoptics.brdf.D`).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.3 (sampling D(m) cos θ_m).
    .. [2] I. M. Sobol', USSR Comput. Math. Math. Phys. 7(4):86-112, 1967.
    """
    if ndf == "tabulated":
        yield from sample_normal_dcos(unit_nodes(n), ndf=ndf, ax=ax, ay=ay, c=c)
        return
    m0, kx, ky = ndf_node_base(n, ndf=ndf, ax=ax, ay=ay, c=c)
    e2 = np.asarray(e2, dtype=float)
    cs, sn = e2[..., 1], -e2[..., 0]
    if ay != ax:   # turned in the unstretched slope plane, to h's azimuth there (module doc of .anisotropy)
        r = np.hypot(cs / kx, sn / ky)
        cs, sn = cs / kx / r, sn / ky / r
    for mx, my, mz in m0:
        m = np.stack([kx * (cs * mx - sn * my), ky * (sn * mx + cs * my), np.full(cs.shape, mz)], axis=-1)
        yield m / np.linalg.norm(m, axis=-1, keepdims=True) if ay != ax else m


def half_vector_nodes(rad: NanoRadial, level, n: int, cos_d, antithetic: bool = True):
    """The half-vector normals of the facet-frame quadratures (:func:`waveoptics.brdf.facet_frame_diffraction`,
    :class:`waveoptics.brdf.TwoScaleBRDF`): for each of *n* nodes the tilt s = sin(m, h) per pair (n_pairs,) and the
    cosine and sine of its azimuth about h in :func:`meridian_basis` (m = s cos φ e1 + s sin φ e2 + √(1 − s²) h;
    s ≥ 1: no node). A facet tilted from h by s sends ω_i to the grating vector q = 2k cos θ_d s of the nano lobe
    about its mirror direction, so s = t / (2 cos θ_d), t the radius drawn through the nano lobe's radial law
    *rad* at each pair's cos θ_d *level* (:meth:`NanoRadial.level`).

    Antithetic pairs: n/2 Sobol points (radius from u₁, azimuth 2π u₂), each at φ and φ + π, which cancels the
    integrand's odd harmonics in the azimuth about h (the facets tilted towards and away from the light along the
    meridian); the nodes depend on h and θ_d only, the same for ω_i and ω_o swapped. *antithetic* False: n Sobol
    points, each once (a height field's, in :func:`facet_basis` of h).

    Parameters
    ----------
    rad : NanoRadial
        The nano lobe's radial law.
    level : ndarray (n_pairs,) of int
        Its cos θ_d level of each pair.
    n : int
        Number of nodes (a power of two).
    cos_d : ndarray (n_pairs,)
        cos θ_d = ω_i·h of each pair.

    References
    ----------
    .. [1] J. M. Hammersley, K. W. Morton, "A new Monte Carlo technique: antithetic variates", Proc. Cambridge
       Philos. Soc. 52(3):449-475, 1956.
    .. [2] I. M. Sobol', USSR Comput. Math. Math. Phys. 7(4):86-112, 1967.
    """
    n_base, radii, phi = half_vector_base(rad, n, antithetic)
    radii = radii[level]
    for k in range(n):
        yield radii[..., k % n_base] / (2 * cos_d), np.cos(phi[k]), np.sin(phi[k])


def half_vector_base(rad: NanoRadial, n: int, antithetic: bool = True):
    """The data of :func:`half_vector_nodes` (shared with its OpenCL twin, ``kernels/facet_frame.cl``): n_base
    (n/2 antithetic pairs, else n), the offset radii (COS_LEVELS, n_base) of the n_base Sobol points through the
    nano lobe's radial law at every cos θ_d level (direction-cosine units), and the azimuths φ (n,) about h of the
    n nodes (node k: point k mod n_base at 2π u₂ + π ⌊k / n_base⌋).

    References
    ----------
    .. [1] J. M. Hammersley, K. W. Morton, Proc. Cambridge Philos. Soc. 52(3):449-475, 1956 (antithetic variates).
    """
    n_base = n // 2 if antithetic and n % 2 == 0 else n
    base = unit_nodes(n_base)
    radii = rad.radius(np.arange(COS_LEVELS)[:, None], np.broadcast_to(base[:, 0], (COS_LEVELS, n_base)))
    k = np.arange(n)
    return n_base, radii, 2 * np.pi * base[k % n_base, 1] + np.pi * (k // n_base)


#: normals of the facet-frame quadratures' third node set, about the bridge point (:func:`bridge_point`): where
#: a light-tailed micro NDF and a light-tailed nano lobe meet far from both their peaks (a lobe's deep tail), the
#: integrand D(m) f_nano peaks between the NDF's normals and the half-vector's, where neither set has nodes. Beckmann
#: α 0.15 × 0.4, Gaussian nano σ 15 nm, T 1.5 µm, 550 nm, θ_i 30° φ_i 52.5° → 85° φ_o 202.5° (1.44e-5 /sr, 5000x
#: below the lobe's peak): the grid route's 128 + 256 normals 1.32x a Monte-Carlo facet-frame integral (128²
#: tables), 0.99x with 64 bridge normals (32: 1.03x)
BRIDGE_NODES = 64
#: points of the search for the bridge point on the slope segment from the macro normal to h (:func:`bridge_point`)
BRIDGE_STEPS = 17
#: the bridge is sought where the NDF's density D(h) cos θ_h at the half-vector and the radial law's at the macro
#: normal are both below this share of their peaks (elsewhere one set's normals span the segment between them);
#: its weight β rises from 0 there to 1 a decade further (:func:`bridge_point`)
BRIDGE_GATE = 0.01
#: the bridge Gaussian's widths over those of the Laplace approximation: the product's mass spreads further than
#: its curvature at the peak says (the nano lobe's multiple-scattering orders are heavier-tailed than a Gaussian).
#: Beckmann α 0.15 × 0.4, Gaussian nano σ 15 nm, T 1.5 µm, 256² tables, 64 bridge normals, θ_i 30° φ_i 45-90° →
#: 80° at 240° from the light (1e-5-3e-8 /sr): the facet-frame sum 0.90-1.11 of a Monte-Carlo integral with 1.0,
#: 0.97-1.03 with 1.5, 1.01-1.06 with 2 (without a bridge: 0.84-0.97)
BRIDGE_SPREAD = 1.5
#: the bridge's weight β is 1 where the NDF's and the half-vector's normals have less than this many times the
#: bridge normals' density at the bridge point, 0 where ten times more (:func:`bridge_point`): Beckmann α 0.3-0.5,
#: Gaussian nano, θ_i 30-80°, tails 2e-5-6e-4 of the peak (where with 1 the bridge stayed off): the pointwise
#: diffracted part 1.04-1.14x a Monte-Carlo facet-frame integral with 1, 1.00-1.01x with 10
BRIDGE_DENSITY = 10.0


def _decade_ramp(x):
    """0 for x ≤ 1, 1 for x ≥ 10, linear in log10 x between (a weight that does not jump between cells)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(np.clip(np.log10(x), 0.0, 1.0), nan=0.0)


def bridge_point(h, cos_d, rad: NanoRadial, level, nodes, *, ndf, ax, ay, c):
    """Where the facet-frame integrand D(m) f_nano peaks between the NDF's normals and the half-vector's (a lobe's
    deep tail): the maximum of log D(m) + log p(t) (p the nano lobe's radial law *rad* at the pairs' cos θ_d
    *level*, t = 2 cos θ_d sin(m, h) the offset a facet tilted from h sends the light to) over
    :data:`BRIDGE_STEPS` normals on the segment of slope space from the macro normal (slope 0, the NDF's mode) to
    h (the lobe's centre), moved by a Newton step along and across the segment, and the widths of a Gaussian about
    it: :data:`BRIDGE_SPREAD` times those of the Laplace approximation (the log's curvature along and across).

    Returns (m_c (n_pairs, 3), s (n_pairs, 2), β (n_pairs,)): the bridge point, the Gaussian's widths (radians)
    towards h and across, and the bridge's weight β in [0, 1]: :data:`BRIDGE_NODES` β its normals' count in the
    balance heuristic, each normal's term times β (unbiased for any β: the weights of the three sets still sum to
    1), rising smoothly (:func:`_decade_ramp`) from 0 where no bridge is needed to 1: where the NDF's density at h
    and the radial law's at the normal fall below :data:`BRIDGE_GATE` of their peaks, and where the two sets'
    density at m_c (*nodes* = (N_a, N_b)) falls below :data:`BRIDGE_DENSITY` times that of the bridge normals at
    their centre. 0 also where the maximum lies at either end of the segment or the log is not concave there, and
    for a slope table (``tabulated``: a histogram, bounded, measured with analytic NDFs only). A function of h and
    cos θ_d alone: the same for ω_i and ω_o swapped.

    References
    ----------
    .. [1] P.-S. Laplace, Mémoire sur la probabilité des causes par les évènements, 1774 (a peak's Gaussian
       approximation by the curvature of its log).
    .. [2] E. Veach, PhD thesis, Stanford 1997, §9.2 (the balance heuristic: a technique for a region the others
       miss; any sample counts).
    """
    from .ndf import ndf_by_name

    D = ndf_by_name(ndf).D
    h = np.asarray(h, dtype=float)
    cos_d = np.asarray(cos_d, dtype=float)
    level = np.broadcast_to(np.asarray(level), cos_d.shape)
    mc, width, beta = h.copy(), np.zeros((h.shape[0], 2)), np.zeros(h.shape[0])
    if ndf == "tabulated":   # a slope table's histogram: no smooth peak to find, no tail beyond its largest slope
        return mc, width, beta
    z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), h.shape)
    t_n = 2.0 * cos_d * np.sqrt(np.maximum(1.0 - h[:, 2] ** 2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        far = (_decade_ramp(BRIDGE_GATE * D(z, ax, ay, c) / (D(h, ax, ay, c) * h[:, 2]))
               * _decade_ramp(BRIDGE_GATE * rad.pdf_r(level, np.zeros_like(t_n)) / rad.pdf_r(level, t_n)))
    sel = far > 0
    if sel.any():
        mc[sel], width[sel], need = _bridge_search(h[sel], cos_d[sel], rad, level[sel], nodes, D, (ax, ay, c))
        beta[sel] = far[sel] * need
    return mc, np.where(beta[:, None] > 0, width, 0.0), beta


def _bridge_search(h, cos_d, rad: NanoRadial, level, nodes, D, args):
    """(m_c, widths, the weight from the sets' density at m_c) of :func:`bridge_point` at pairs *h*, *cos_d*."""
    P, n = h.shape[0], BRIDGE_STEPS
    rows = np.arange(P)

    def log_p(m):   # log D(m) p(t) at normals m (P, k, 3)
        t = 2.0 * cos_d[:, None] * np.linalg.norm(np.cross(m, h[:, None, :]), axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.log(D(m, *args)) + np.log(rad.pdf_r(level[:, None], t))

    s = np.linspace(0.0, 1.0, n)
    seg = np.concatenate([s[None, :, None] * h[:, None, :2], np.broadcast_to(h[:, None, 2:], (P, n, 1))], axis=-1)
    seg /= np.linalg.norm(seg, axis=-1, keepdims=True)
    L = log_p(seg)
    k = np.argmax(np.where(np.isnan(L), -np.inf, L), axis=1)
    inner = (k > 0) & (k < n - 1)
    k = np.clip(k, 1, n - 2)
    mc, lo, hi = seg[rows, k], seg[rows, k - 1], seg[rows, k + 1]
    step = 0.5 * np.arccos(np.clip(np.sum(lo * hi, axis=-1), -1.0, 1.0))          # radians a step at m_c
    e_par = hi - lo
    e_par /= np.maximum(np.linalg.norm(e_par, axis=-1, keepdims=True), 1e-300)
    e_perp = np.cross(mc, e_par)
    across = np.stack([np.cos(step)[:, None] * mc + np.sin(step)[:, None] * sgn * e_perp for sgn in (-1.0, 1.0)],
                      axis=1)
    La = log_p(across)
    with np.errstate(invalid="ignore", divide="ignore"):
        c_par = -(L[rows, k + 1] - 2.0 * L[rows, k] + L[rows, k - 1])
        c_perp = -(La[:, 0] - 2.0 * L[rows, k] + La[:, 1])
        ok = inner & np.isfinite(L[rows, k]) & (c_par > 0) & (c_perp > 0)
        # a Newton step along and across (an anisotropic NDF's peak lies off the segment), at most one step
        d_par = np.nan_to_num(np.clip(0.5 * (L[rows, k + 1] - L[rows, k - 1]) / np.where(ok, c_par, np.inf), -1, 1))
        d_perp = np.nan_to_num(np.clip(0.5 * (La[:, 1] - La[:, 0]) / np.where(ok, c_perp, np.inf), -1, 1))
        width = BRIDGE_SPREAD * step[:, None] / np.sqrt(np.stack([np.where(ok, c_par, 1.0),
                                                                  np.where(ok, c_perp, 1.0)], axis=-1))
    mc = mc + (d_par * step)[:, None] * e_par + (d_perp * step)[:, None] * e_perp
    mc /= np.linalg.norm(mc, axis=-1, keepdims=True)
    mh = np.clip(np.sum(mc * h, axis=-1), 0.0, 1.0)
    t = 2.0 * cos_d * np.sqrt(np.maximum(1.0 - mh * mh, 0.0))
    na, nb = nodes
    have = na * D(mc, *args) * mc[:, 2] + nb * rad.pdf_r(level, t) * 4.0 * cos_d ** 2 * mh
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):   # a width 0 where not ok
        need = BRIDGE_NODES / (2.0 * np.pi * width[:, 0] * width[:, 1])
        weight = np.where(ok, _decade_ramp(BRIDGE_DENSITY * need / have), 0.0)
    return mc, np.minimum(width, 0.5), weight


def bridge_offsets(n: int | None = None) -> np.ndarray:
    """Offsets (n, 2) of the bridge normals in units of the Gaussian's widths: *n* (default
    :data:`BRIDGE_NODES`) Sobol points (:func:`unit_nodes`) through the 2-D unit normal law (radius
    √(−2 ln(1 − u₁)), azimuth 2π u₂; Box & Muller 1958). Shared with the kernel's host code
    (``kernels/facet_frame.cl``)."""
    u = unit_nodes(BRIDGE_NODES if n is None else n)
    r = np.sqrt(-2.0 * np.log1p(-u[:, 0]))
    return np.stack([r * np.cos(2 * np.pi * u[:, 1]), r * np.sin(2 * np.pi * u[:, 1])], axis=-1)


def _bridge_frame(mc, h):
    """(e_par, e_perp): tangents of the bridge points *mc* (P, 3) towards their half-vectors *h* and across."""
    e = h - np.sum(h * mc, axis=-1, keepdims=True) * mc
    n = np.linalg.norm(e, axis=-1, keepdims=True)
    e = np.where(n > 1e-12, e / np.where(n > 1e-12, n, 1.0), facet_basis(mc)[0])
    return e, np.cross(mc, e)


def bridge_nodes(mc, width, h, n: int | None = None):
    """The bridge normals (n_pairs, n, 3) and their validity (n_pairs, n): :func:`bridge_offsets` scaled by the
    widths *width* (n_pairs, 2) of :func:`bridge_point` along (towards h) and across, in the tangent plane of the
    bridge point *mc*, lifted onto the sphere (m = x e_par + y e_perp + √(1 − x² − y²) m_c); none where the
    width is 0 or the offset leaves the disc."""
    e1, e2 = _bridge_frame(mc, h)
    off = bridge_offsets(n)
    x, y = width[:, None, 0] * off[None, :, 0], width[:, None, 1] * off[None, :, 1]
    r2 = x * x + y * y
    ok = (width[:, None, 0] > 0) & (r2 < 1.0)
    z = np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))
    m = x[..., None] * e1[:, None] + y[..., None] * e2[:, None] + z[..., None] * mc[:, None]
    return m, ok


def bridge_density(m, mc, width, h):
    """Density (1/sr) of :func:`bridge_nodes` at normals *m* (n_pairs, N, 3): the 2-D normal law of the offsets
    (x, y) of m in the tangent plane of the bridge point *mc* (widths *width* (n_pairs, 2)) times m·m_c (the
    projection's Jacobian); 0 where the width is 0 or m·m_c ≤ 0."""
    on = width[:, 0] > 0
    sx, sy = (np.where(on, width[:, i], 1.0)[:, None] for i in (0, 1))
    x, y, mm = np.moveaxis(np.matmul(m, np.stack([*_bridge_frame(mc, h), mc], axis=-1)), -1, 0)   # m·e1, m·e2, m·mc
    g = np.exp(-0.5 * ((x / sx) ** 2 + (y / sy) ** 2)) / (2.0 * np.pi * sx * sy)
    return np.where(on[:, None] & (mm > 0), g * np.maximum(mm, 0.0), 0.0)


def with_bridge_density(den, m, at, beta, mc, width, h):
    """*den* (n,) (the other sets' density at the nodes *m* (3,) or (n, 3) of the pairs *at* (n,), 1/sr) plus the
    bridge normals' :data:`BRIDGE_NODES` β p_c (:func:`bridge_density`) in those pairs whose *beta* is > 0; *beta*,
    *mc*, *width*, *h* of all pairs (:func:`bridge_point`). The balance heuristic counts every set at every node
    (E. Veach, PhD thesis, Stanford 1997, §9.2)."""
    on = np.flatnonzero(beta[at] > 0)
    if on.size:
        c = at[on]
        den[on] += BRIDGE_NODES * beta[c] * bridge_density(np.broadcast_to(m, (at.size, 3))[on, None], mc[c],
                                                           width[c], h[c])[:, 0]
    return den


def quadrature_normals(h, cos_d, rad: NanoRadial, level, n: int, *, ndf, ax, ay, c):
    """The facet normals of the facet-frame quadrature for pairs with half-vectors *h* (n_pairs, 3), the grid
    route's reciprocal layout: *n* normals with density D(m) cos θ_m turned to h's azimuth (:func:`ndf_nodes`) and
    *n* antithetic normals about h through the nano lobe's radial law *rad* at the pairs' cos θ_d *level*
    (:func:`half_vector_nodes`), both in :func:`meridian_basis` of h, so the same for ω_i and ω_o swapped and for
    the pair turned about the normal. *cos_d* is half the length of the wave-vector sum whose tangential part the
    tilt sets (cos θ_d = ω_i·h in reflection). Returns the normals (n_pairs, 2n, 3) and their validity
    (n_pairs, 2n).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.3; J. M. Hammersley, K. W. Morton 1956 (antithetic variates).
    """
    e1, e2 = meridian_basis(h)
    ma = np.stack([np.broadcast_to(m, h.shape) for m in ndf_nodes(n, e2, ndf=ndf, ax=ax, ay=ay, c=c)], axis=1)
    s, cp, sp = zip(*half_vector_nodes(rad, level, n, cos_d))
    s, cp, sp = np.stack(s, axis=1), np.asarray(cp), np.asarray(sp)
    ok = s < 1.0                    # a tilt s from h sends ω_i to the grating vector q = 2k cosθ_d s
    s = np.where(ok, s, 0.0)
    mb = ((s * cp)[..., None] * e1[:, None, :] + (s * sp)[..., None] * e2[:, None, :]
          + np.sqrt(1.0 - s ** 2)[..., None] * h[:, None, :])
    return np.concatenate([ma, mb], axis=1), np.concatenate([np.ones(ma.shape[:2], bool), ok], axis=1)


def quadrature_density(m, D, h, cos_d, rad: NanoRadial, level, n: int):
    """The balance heuristic's denominator n p_a(m) + n p_b(m) (1/sr) at the normals *m* (n_pairs, N, 3) of
    :func:`quadrature_normals` with NDF values *D* (n_pairs, N): p_a = D(m) cos θ_m and p_b the radial law's
    density of the tilt from *h* mapped to normals, p(t) (2 cos θ_d)² cos(m, h) with t = 2 cos θ_d sin(m, h).

    References
    ----------
    .. [1] E. Veach, PhD thesis, Stanford, 1997, §9.2 (the balance heuristic).
    """
    pa = D * m[..., 2]
    mh = np.clip(dot_last(m, h[:, None, :]), 0.0, 1.0)
    t = 2.0 * cos_d[:, None] * np.sqrt(np.maximum(1.0 - mh ** 2, 0.0))
    pb = np.where(mh > 0, rad.pdf_r(level[:, None], t) * 4.0 * cos_d[:, None] ** 2 * mh, 0.0)
    return n * pa + n * pb


def sampler_normals(wi, n: int, *, ndf, ax, ay, c):
    """The sampler's facet normals for each ω_i (n_i, 3) above the surface: the micro NDF's sampler
    (:func:`waveoptics.brdf.sample_normal`) at *n* fixed Sobol points (:func:`unit_nodes`), computed once per
    distinct ω_i. Returns (n_i, n, 3).

    References
    ----------
    .. [1] E. Heitz, JCGT 7(4), 2018 (visible normals); B. Walter et al., EGSR 2007, §5.3.
    """
    uniq, inv = np.unique(wi, axis=0, return_inverse=True)
    u = unit_nodes(n)
    wi_b = np.broadcast_to(uniq[:, None, :], (uniq.shape[0], u.shape[0], 3))
    m = sample_normal(wi_b, np.broadcast_to(u, wi_b.shape[:-1] + (2,)), ndf=ndf, ax=ax, ay=ay, c=c)
    return m[inv.reshape(-1)]


def budget_nodes(wi, n: int, *, ndf, ax, ay, c):
    """Facet normals m (K, 3) and weights w (K,) of ∫ g(m) D(m) dω_m ≈ Σ w g(m) for the energy budget of
    :func:`waveoptics.brdf.facet_frame_diffraction`: the micro NDF's sampler for *wi* at *n* Sobol points
    (:func:`unit_nodes`), w = D / (n p); for a slope table (``tabulated``) its bins instead,
    :func:`waveoptics.brdf.table_nodes` (Gauss-Legendre points per bin, w = D dω): the table is a discrete law, whose
    average over the facets the light sees is then a sum, not an estimate. With 64 nodes of its sampler the budget's
    scattered share of a measured table (Au, Gaussian nano σ 8 nm ℓ 1 µm, 550 nm) was 0.25 % below the sum over its
    bins at θ_i = 60°, 0.9 % at 80°, 2 % at 88°, where the closed-form Beckmann NDF's nodes are within 0.1 %.

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.3 (sampling normals); E. Heitz, JCGT 3(2), 2014, eq. (38) (the visible
       normals' density, ∝ (ω_i·m)⁺ D(m)).
    """
    from .ndf import ndf_by_name
    from .quadrature import table_nodes
    from .sampling import pdf_normal

    D = ndf_by_name(ndf).D
    if ndf == "tabulated":
        m, w = table_nodes(c)
        d = D(m, ax, ay, c)
        keep = (d > 0) & (m @ np.asarray(wi, float) > 0)
        return m[keep], (d * w)[keep]
    wb = np.broadcast_to(np.asarray(wi, float), (n, 3))
    m = sample_normal(wb, unit_nodes(n), ndf=ndf, ax=ax, ay=ay, c=c)
    p = pdf_normal(wb, m, ndf=ndf, ax=ax, ay=ay, c=c)
    return m, D(m, ax, ay, c) / (n * np.where(p > 0, p, np.inf))
