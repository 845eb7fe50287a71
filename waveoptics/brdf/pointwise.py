"""The two-scale BRDF evaluated at any (ω_i, ω_o, λ), with importance sampling.

:class:`TwoScaleBRDF` is the model of :mod:`waveoptics.brdf.twoscale` (Holzschuch & Pacanowski 2017; docs/physics.md
§7) written as a function instead of lobes on a grid, so that nothing is interpolated between incidences:

    f = A(θ_d) f_mf(ω_i, ω_o) + f_diff(ω_i, ω_o) + f_diffuse(ω_i, ω_o),

* coherent part: the microfacet specular term with F, times the coherent fraction A(θ_d) of each facet
  (:meth:`waveoptics.brdf.Nano.coherent_amplitude2`: on a conductor 1 − E(θ_d), the complement of the light its
  nano lobe scatters; on a dielectric the Debye-Waller factor exp(−g_rel(θ_d)); docs/physics.md §9);
* diffuse substrate of dielectrics (closed form, as the microfacet model);
* diffracted part: the nano lobe f_n (the PSD series, :func:`waveoptics.scatter.scattered_lobe`, with its own F)
  carried by every facet, i.e. the paraxial convolution on the direction-cosine plane (P the (u, v) of ω_o, m the
  mirror point −ω_i,xy)

      f_diff(P) = ∫ f_mf¹(ω_i, m + s) W(s) f_n(ω_i, P − s) d²s,   W = (1 − A(θ_d(s))) / (1 − A(θ_i)),

  with f_mf¹ the F = 1 microfacet lobe and W each facet's own scattered share (:func:`waveoptics.brdf.
  facet_scatter_weights`; 1 − A on a conductor, the lobe's own albedo on a dielectric). The integral is a fixed quadrature on N points (:data:`QUADRATURE_NODES`, a Sobol
  set): nodes s_k drawn through the micro lobe's own sampler (weights f cos θ / pdf) when it is the narrower
  lobe, else nodes t_k = P − s drawn through the nano lobe's radial sampler; each node carries an exact,
  analytic evaluation of the other lobe, so the result is a smooth function of ω_o at every ω_i.

Beyond the tangent plane's validity (θ_i > 75°) the nano lobe carries its albedo at 75° continued with first-order
perturbation theory's incidence dependence (:meth:`waveoptics.scatter.BandSeries.scattered_albedo`), as the grid
model's does, so the white furnace (F = 1) holds up to grazing incidence without the grid model's energy guard
(:func:`waveoptics.brdf.twoscale._cap_to_coherent_loss`, which needs the whole lobe and is not applied here):
≤ 1.01 at θ_i up to 89.5° (tests/test_grazing.py; 1.149 at 89° before).

Sampling is a mixture of the three parts in proportion F(θ_i)A(θ_i) : F(θ_i)(1 − A(θ_i)) : kd(1 − F(θ_i));
the diffracted part picks one of the micro nodes s_k and adds a radial nano offset, so its density
(1/N) Σ_k p_n(P − m − s_k) cos θ_o is exact.

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale model).
.. [2] P. Beckmann, A. Spizzichino, 1963, ch. 5 (the series of the nano lobe).
.. [3] B. Walter et al., EGSR 2007, eq. (14) (the microfacet BRDF of facets carrying a BRDF).
.. [4] I. M. Sobol', USSR Comput. Math. Math. Phys. 7(4):86-112, 1967 (the quadrature points).
.. [5] E. Veach, PhD thesis, 1997, §9.2 (mixture sampling).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import qmc

from .. import scatter
from ..errors import FieldError, WaveopticsError
from .protocol import TwoScaleParts
from .sampling import sample_normal
from .ndf import reflect
from .twoscale import SERIES_MIN_CAPTURED

__all__ = ['QUADRATURE_NODES', 'RADIAL_BINS', 'COS_LEVELS', 'TwoScaleBRDF', 'unit_nodes', 'NanoRadial']

#: quadrature points of the facet convolution (a power of two: an unscrambled Sobol set)
QUADRATURE_NODES = 256
#: radial bins of the nano-lobe sampler (geometric in spatial frequency)
RADIAL_BINS = 384
#: levels of cos θ_i at which the nano-lobe sampler is tabulated (its Poisson weights depend on θ_i)
COS_LEVELS = 65
_CHUNK = 2048


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
    """

    def __init__(self, model, wavelength_nm: float, diffraction, n_nodes: int = QUADRATURE_NODES):
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

    def pdf_t(self, level, t):
        """Density per unit area of the direction-cosine plane of offsets t (..., 2)."""
        q = self.k * np.hypot(t[..., 0], t[..., 1])
        b = np.searchsorted(self.edges, q, side="right") - 1
        ok = (b >= 0) & (b < RADIAL_BINS)
        val = self.density[level, np.clip(b, 0, RADIAL_BINS - 1)]
        return np.where(ok, val * self.k ** 2, 0.0)


def _lift(uv):
    """Unit direction above the surface with direction cosines uv (..., 2), and whether it exists."""
    s2 = uv[..., 0] ** 2 + uv[..., 1] ** 2
    ok = s2 < 1.0
    z = np.sqrt(np.maximum(1.0 - s2, 0.0))
    return np.concatenate([uv, z[..., None]], axis=-1), ok & (z > 0)


@dataclass(frozen=True)
class TwoScaleBRDF(TwoScaleParts):
    """Two-scale BRDF (micro NDF carrying PSD nano-roughness) as a function (see the module doc).

    Parameters
    ----------
    material, micro, kd, diffuse, fresnel, ndf_shape
        As :class:`waveoptics.brdf.MicrofacetBRDF`.
    nano : Nano or None
        Nano-roughness statistics (:class:`waveoptics.surfaces.PSDModel`); None or σ = 0 gives the microfacet
        model exactly. Height fields are evaluated on a direction grid (:func:`waveoptics.brdf.evaluate`).
    diffraction : str
        Diffraction model of the nano lobe and the coherent fraction (:data:`waveoptics.scatter.
        DIFFRACTION_MODELS`).
    nodes : int
        Quadrature points of the facet convolution (power of two).
    """

    nodes: int = QUADRATURE_NODES

    def __post_init__(self):
        super().__post_init__()
        scatter.get_model(self.diffraction, perturbative=True)
        if self.nano is not None and self.nano.model is None:
            raise FieldError("the two-scale BRDF function needs nano statistics (a PSD model); a nano height "
                             "field is evaluated on a direction grid by simulate", "nano")
        n = int(self.nodes)
        if n < 16 or n & (n - 1):
            raise FieldError(f"nodes={self.nodes!r} is not allowed; use a power of two >= 16", "nodes")

    # -- nano pieces ---------------------------------------------------------------------------------------
    @functools.cached_property
    def _radial(self):
        return functools.lru_cache(maxsize=64)(lambda lam: NanoRadial(self.nano.model, lam, self.diffraction,
                                                                             self.nodes))

    def _check_series(self, lam):
        """Refuse nano-roughness the truncated series cannot hold (as :func:`waveoptics.brdf.nano_lobe`)."""
        g = scatter.roughness_g(self.nano.model.sigma, 2.0, lam)
        m_use = scatter.series_terms(g)
        captured = float(scatter.poisson_weights(g, m_use).sum() / -np.expm1(-g)) if g > 0 else 1.0
        if captured < SERIES_MIN_CAPTURED:
            raise WaveopticsError(
                f"nano-roughness sigma = {self.nano.model.sigma * 1e9:.4g} nm is too rough for the PSD series at "
                f"{lam:g} nm (it holds only {100 * captured:.3g}% of the scattered light); describe roughness this "
                "large by the micro NDF (alpha)")

    def _f_nano(self, wi, wo, lam):
        """The nano lobe f_n (1/sr) with its own Fresnel factor at the half-vector angle."""
        h = wi + wo
        h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
        cos_d = np.clip(np.sum(h * wi, axis=-1), 0.0, 1.0)
        dm = scatter.get_model(self.diffraction, perturbative=True)
        if dm.perturbative:   # Rayleigh-Rice: its own polarization factor Q in place of F (F = 1: a perfect conductor)
            mat = self.material if self.fresnel == "exact" else None
            return scatter.rayleigh_rice_lobe(wi, wo, lam, self.nano.model, mat)
        F = self._F(lam)(cos_d)
        # the series of the roughness inside the propagating band, as the grid model's (docs/physics.md §9)
        total = scatter.band_series(self.nano.model, lam)(wi, wo, dm.cos_sum(wi, wo))
        # beyond the tangent plane's validity the lobe carries the continued albedo (BandSeries.scattered_albedo)
        total = total * self.nano.lobe_energy_scale(wi[..., 2], lam, dm,
                                                    self.material if self.fresnel == "exact" else None)
        return np.where((wi[..., 2] > 0) & (wo[..., 2] > 0), F * dm.K(wi, wo, lam) * total, 0.0)

    def _facet_weight(self, wi, m, lam):
        """W = (1 − A(ω_i·m)) / (1 − A(θ_i)): a facet's scattered share relative to the macro incidence."""
        lost_i = self._share(wi[..., 2], lam)
        lost = self._share(np.clip(np.sum(wi * m, axis=-1), 0.0, 1.0), lam)
        return np.where(lost_i > 1e-12, lost / np.where(lost_i > 1e-12, lost_i, 1.0), 1.0)

    def _micro_nodes(self, wi, lam):
        """:meth:`_micro_nodes_of` computed once per distinct ω_i (a renderer's batch often shares them)."""
        uniq, inv = np.unique(wi, axis=0, return_inverse=True)
        if uniq.shape[0] == wi.shape[0]:
            return self._micro_nodes_of(wi, lam)
        s, w, ok = self._micro_nodes_of(uniq, lam)
        inv = inv.reshape(-1)
        return s[inv], w[inv], ok[inv]

    def _micro_nodes_of(self, wi, lam):
        """Micro nodes for each ω_i (n, 3): offsets s (n, N, 2) from the mirror point, quadrature weights
        f¹ cos θ / (N pdf) × W (n, N), validity (n, N)."""
        u = unit_nodes(self.nodes)
        ndf, ax, ay = self._micro_args()
        wi_b = np.broadcast_to(wi[:, None, :], (wi.shape[0], u.shape[0], 3))
        m = sample_normal(wi_b, np.broadcast_to(u, wi_b.shape[:-1] + (2,)), ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)
        wo = reflect(wi_b, m)
        ok = wo[..., 2] > 0
        wo_ok = np.where(ok[..., None], wo, np.array([0.0, 0.0, 1.0]))
        one = lambda c: np.ones_like(np.asarray(c, dtype=float))  # noqa: E731
        f1 = self._f_specular(wi_b, wo_ok, one)
        p = self._pdf_specular(wi_b, wo_ok)
        ok &= p > 0
        w = np.where(ok, f1 * wo_ok[..., 2] / np.where(ok, p, 1.0), 0.0) / u.shape[0]
        w = w * self._facet_weight(wi_b, m, lam)
        s = wo_ok[..., :2] + wi_b[..., :2]
        return s, w, ok

    def _f_diffraction(self, wi, wo, lam):
        if not self._rough:
            return np.zeros(wi.shape[0])
        self._check_series(lam)
        out = np.zeros(wi.shape[0])
        for a in range(0, wi.shape[0], _CHUNK):
            sl = slice(a, a + _CHUNK)
            out[sl] = self._f_diffraction_chunk(wi[sl], wo[sl], lam)
        return np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), out, 0.0)

    def _f_diffraction_chunk(self, wi, wo, lam):
        s, w, ok = self._micro_nodes(wi, lam)
        rad = self._radial(lam)
        level = rad.level(wi[:, 2])
        u = unit_nodes(self.nodes)
        # widths: median micro offset vs median nano offset radius
        w_micro = np.median(np.where(ok, np.hypot(s[..., 0], s[..., 1]), np.inf), axis=1)
        r_nano = rad.node_radii[level]
        w_nano = np.median(r_nano, axis=1)
        nano_nodes = w_nano < w_micro
        out = np.zeros(wi.shape[0])
        P = wo[:, :2]
        wi_b = np.broadcast_to(wi[:, None, :], s.shape[:-1] + (3,))
        if np.any(~nano_nodes):   # nodes on the micro lobe, the nano lobe evaluated exactly
            sel = ~nano_nodes
            d, inside = _lift(P[sel, None, :] - s[sel])
            fn = self._f_nano(wi_b[sel], np.where(inside[..., None], d, [0.0, 0.0, 1.0]), lam)
            out[sel] = np.sum(np.where(inside & ok[sel], w[sel] * fn, 0.0), axis=1)
        if np.any(nano_nodes):    # nodes on the nano lobe, the micro lobe evaluated exactly
            sel = nano_nodes
            phi = 2 * np.pi * u[:, 1]
            t = r_nano[sel][..., None] * np.stack([np.cos(phi), np.sin(phi)], axis=-1)[None]
            mirror = -wi[sel, None, :2]
            dn, in_n = _lift(mirror + t)
            wi_s = wi_b[sel]
            fn = self._f_nano(wi_s, np.where(in_n[..., None], dn, [0.0, 0.0, 1.0]), lam)
            pt = rad.pdf_t(level[sel][:, None], t)
            dm_, in_m = _lift(P[sel, None, :] - t)
            dm_ = np.where(in_m[..., None], dm_, [0.0, 0.0, 1.0])
            one = lambda c: np.ones_like(np.asarray(c, dtype=float))  # noqa: E731
            f1 = self._f_specular(wi_s, dm_, one)
            h = wi_s + dm_
            h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
            W = self._facet_weight(wi_s, h, lam)
            good = in_n & in_m & (pt > 0)
            val = fn * f1 * W / np.where(good, pt, 1.0)
            out[sel] = np.sum(np.where(good, val, 0.0), axis=1) / u.shape[0]
        return out

    def _pdf_diffraction(self, wi, wo, lam):
        out = np.zeros(wi.shape[0])
        rad = self._radial(lam)
        for a in range(0, wi.shape[0], _CHUNK):
            sl = slice(a, a + _CHUNK)
            s, _, ok = self._micro_nodes(wi[sl], lam)
            t = wo[sl, None, :2] + wi[sl, None, :2] - s
            pt = rad.pdf_t(rad.level(wi[sl, 2])[:, None], t)
            out[sl] = np.mean(np.where(ok, pt, 0.0), axis=1) * np.maximum(wo[sl, 2], 0.0)
        return out

    def _sample_diffraction(self, wi, u, lam):
        n = self.nodes
        k = np.minimum((u[:, 0] * n).astype(int), n - 1)
        u0 = np.clip(u[:, 0] * n - k, 0.0, np.nextafter(1.0, 0.0))
        s, _, ok = self._micro_nodes(wi, lam)
        rows = np.arange(k.size)
        rad = self._radial(lam)
        r = rad.radius(rad.level(wi[:, 2]), u0)
        phi = 2 * np.pi * u[:, 1]
        uv = -wi[:, :2] + s[rows, k] + r[:, None] * np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        d, inside = _lift(uv)
        return np.where((inside & ok[rows, k])[:, None], d, [0.0, 0.0, -1.0])

    def _diffraction_width(self, lam):
        """The nano lobe's width ~ λ/(π ℓ) in direction cosines (ℓ the PSD's length scale)."""
        return lam * 1e-9 / (np.pi * self.nano.model.length_scale)
