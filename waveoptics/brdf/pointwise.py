"""The two-scale BRDF evaluated at any (ω_i, ω_o, λ), with importance sampling.

:class:`TwoScaleBRDF` is the model of :mod:`waveoptics.brdf.twoscale` (Holzschuch & Pacanowski 2017; docs/physics.md
§7) written as a function instead of lobes on a grid, so that nothing is interpolated between incidences:

    f = A(θ_d) f_mf(ω_i, ω_o) + f_diff(ω_i, ω_o) + f_diffuse(ω_i, ω_o),

* coherent part: the microfacet specular term with F, times the coherent fraction A(θ_d) of each facet
  (:meth:`waveoptics.brdf.Nano.coherent_fraction`: on a conductor 1 − E(θ_d), the complement of the light its
  nano lobe scatters; on a dielectric the Debye-Waller factor exp(−g_rel(θ_d)); docs/physics.md §9);
* diffuse substrate of dielectrics (closed form, as the microfacet model);
* diffracted part: Walter et al.'s integral of the nano lobe carried by every facet in the facet's own frame,

      f_diff(ω_i, ω_o) = ∫ |ω_i·m| |ω_o·m| / (|ω_i·n| |ω_o·n|) f_n(ω_i^m, ω_o^m) G(ω_i, ω_o, m) D(m) dm,

  f_n the PSD series (:mod:`waveoptics.scatter.band`, or Rayleigh-Rice) with its own F(θ_d) at the facet's local
  directions (:meth:`TwoScaleBRDF.facet_nano_brdf`), whose albedo at local incidence θ is F(θ)(1 − A(θ)) on a
  conductor (each facet scatters what its coherent part gives up) and its own absolute albedo on a dielectric. The
  integral is a fixed quadrature over facet normals, the balance heuristic of N/2 normals with density D(m) cos θ_m
  at fixed Sobol points (:func:`waveoptics.brdf.facet.ndf_nodes`; good where the micro lobe is the narrower) and
  N/2 antithetic normals about the half-vector h drawn through the nano lobe's radial law
  (:func:`waveoptics.brdf.facet.half_vector_nodes`, :class:`NanoRadial`: a tilt s from h moves the lobe's grating
  vector by q = 2k cosθ_d |s|; good where the nano lobe is the narrower, and it reaches a heavy-tailed NDF's far
  facets). Both sets are the grid route's (:func:`waveoptics.brdf.facet_frame_diffraction`), laid out about h in a
  frame that turns with h about the normal (:func:`waveoptics.brdf.facet.meridian_basis`): they depend on h and
  θ_d only, so the sum is the same for ω_i and ω_o swapped and for the pair turned about the normal (the integrand
  is; tests/test_pointwise_reciprocity.py). The nodes move smoothly with ω_o, so the result is a smooth function of
  ω_o at every ω_i.

Beyond the tangent plane's validity (a facet's local θ_i or θ_o past 70°) its nano lobe hands over to the first-order
Rayleigh-Rice lobe of the same PSD, W f_K + (1 − W) f_RR with W = w(θ_i) w(θ_o) (w from 1 at 70° to 0 at 80°;
:mod:`waveoptics.scatter.tangent_blend`): reciprocal, and its albedo is the one the coherent fraction is the
complement of (:meth:`waveoptics.scatter.BandSeries.scattered_albedo`), as the grid model's, so the white furnace (F = 1) holds up to grazing incidence without the grid model's energy
guard (:func:`waveoptics.brdf.twoscale.cap_to_coherent_loss`, which needs the whole lobe and is not applied here):
≤ 1.01 at θ_i up to 89.5° (tests/test_grazing.py).

Sampling is a mixture of the three parts in proportion F(θ_i)A(θ_i) : F(θ_i)(1 − A(θ_i)) : kd(1 − F(θ_i));
the diffracted part picks one of N/2 normals m_k drawn by the micro NDF's sampler for ω_i at fixed Sobol points (a
proposal of its own: the quadrature's nodes depend on h, hence on ω_o) and draws ω_o in that facet's frame (its
local mirror direction plus a radial nano offset at its local incidence), so its density
(2/N) Σ_k p_n(t_k(ω_o)) (ω_o·m_k) is exact, t_k the offset of ω_o from facet k's local mirror direction.

References
----------
.. [1] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale model).
.. [2] P. Beckmann, A. Spizzichino, 1963, ch. 5 (the series of the nano lobe).
.. [3] B. Walter et al., EGSR 2007, eq. (14) (the microfacet BRDF of facets carrying a BRDF).
.. [4] I. M. Sobol', USSR Comput. Math. Math. Phys. 7(4):86-112, 1967 (the quadrature points).
.. [5] E. Veach, PhD thesis, 1997, §9.2 (mixture sampling, balance heuristic).
.. [6] T. Duff et al., JCGT 6(1), 2017 (the facet frame).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import scatter
from ..scatter.tangent_blend import blend_with_first_order
from ..errors import FieldError
from .protocol import TwoScaleParts
from .ndf import ndf_by_name
from .shadowing import shadowing_by_name
from .facet import (BRIDGE_NODES, bridge_density, bridge_nodes, bridge_point)
from .facet import (wide_micro_lobe, COS_LEVELS, RADIAL_BINS, NanoRadial, local_pair, facet_basis, from_facet, quadrature_density,
                    quadrature_normals, sampler_normals, to_facet, unit_nodes)
from .directions import dot_last
from .roughness_scales import check_series

__all__ = ['QUADRATURE_NODES', 'QUADRATURE_NODES_WIDE', 'QUADRATURE_WIDE_ALPHA', 'wide_micro_lobe', 'RADIAL_BINS', 'COS_LEVELS', 'TwoScaleBRDF', 'unit_nodes', 'NanoRadial', 'facet_basis',
           'to_facet', 'from_facet']

#: quadrature points of the facet convolution (a power of two: an unscrambled Sobol set), for a micro lobe narrower
#: than :data:`waveoptics.brdf.FACET_NODE_SPLIT` nano lobe widths and for a wider one
#: (:func:`waveoptics.brdf.wide_micro_lobe`). Measured against a seeded Monte-Carlo facet-frame integral
#: (scripts/facet_frame_sweep.py; Al, ABC σ 10 nm, B 2 µm, C 2.6, 550 nm, Beckmann, θ_o up to 85°): at θ_i = 80°,
#: α 0.3 / 0.5, 256 nodes 3.2 / 6.1 % off at θ_o 85° (reference s.e. 0.7 / 0.9 %), 512 nodes 2.0 / 2.7 %,
#: 2048 nodes 0.8 / 1.2 %; at 60° and below every node count is within 1 % (256: 0.7 %); at α 0.05 / 0.1 256 nodes
#: are within 0.5 / 1.7 % at every θ_i of the sweep. 512 nodes cost ~2x 256, so they are taken for a wide lobe whose
#: α is also at least :data:`QUADRATURE_WIDE_ALPHA` (its NDF normals, drawn with D(m) cos θ_m whatever the light,
#: face away from grazing light: the deficit grows with α, not with the nano lobe's width)
QUADRATURE_NODES, QUADRATURE_NODES_WIDE = 256, 512
QUADRATURE_WIDE_ALPHA = 0.2
_CHUNK = 2048


def _lift(uv):
    """Unit direction above the surface with direction cosines uv (..., 2), and whether it exists."""
    s2 = uv[..., 0] ** 2 + uv[..., 1] ** 2
    ok = s2 < 1.0
    z = np.sqrt(np.maximum(1.0 - s2, 0.0))
    return np.concatenate([uv, z[..., None]], axis=-1), ok & (z > 0)


def _unit(v):
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


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
    nodes : int or None
        Quadrature points over facet normals per evaluation (power of two ≥ 16): half with density D(m) cos θ_m,
        half about the half-vector through the nano lobe's radial law (module doc); the sampler draws from half as
        many normals of the micro NDF's sampler. None: :data:`QUADRATURE_NODES`, or :data:`QUADRATURE_NODES_WIDE`
        for a micro lobe wide against the nano lobe (:func:`waveoptics.brdf.wide_micro_lobe`) with α ≥
        :data:`QUADRATURE_WIDE_ALPHA`.
    """

    nodes: int | None = None

    def __post_init__(self):
        super().__post_init__()
        scatter.get_model(self.diffraction, perturbative=True)
        if self.nano is not None and self.nano.model is None:
            raise FieldError("the two-scale BRDF function needs nano statistics (a PSD model); a nano height "
                             "field is evaluated on a direction grid by simulate", "nano")
        if self.nodes is None:
            kw = self.micro.kw()
            a = max(kw["alpha"], kw["alpha_y"] or 0.0)
            wide = (self.nano is not None and a >= QUADRATURE_WIDE_ALPHA
                    and wide_micro_lobe(a, self.nano.model.length_scale))
            object.__setattr__(self, "nodes", QUADRATURE_NODES_WIDE if wide else QUADRATURE_NODES)
        n = int(self.nodes)
        if n < 16 or n & (n - 1):
            raise FieldError(f"nodes={self.nodes!r} is not allowed; use a power of two >= 16", "nodes")

    # -- nano pieces ---------------------------------------------------------------------------------------
    @functools.cached_property
    def _radial(self):
        return functools.lru_cache(maxsize=64)(lambda lam: NanoRadial(self.nano.model, lam, self.diffraction,
                                                                             self.nodes // 2))

    def _check_series(self, lam):
        """Refuse nano-roughness the truncated series cannot hold (:func:`waveoptics.brdf.roughness_scales.check_series`)."""
        check_series(self.nano.model, lam)

    def _f_nano(self, wi, wo, lam, F=None):
        """The nano lobe f_n (1/sr) of directions given in the nano surface's own frame, with its own Fresnel
        factor at the half-vector angle (*F*, broadcast with the pairs, where the caller has it: θ_d is the same in
        every frame); 0 where either direction is at or below that surface."""
        up = (wi[..., 2] > 0) & (wo[..., 2] > 0)
        dm = scatter.get_model(self.diffraction, perturbative=True)
        if dm.perturbative:   # Rayleigh-Rice: its own polarization factor Q in place of F (F = 1: a perfect conductor)
            mat = self.material if self.fresnel == "exact" else None
            return np.where(up, scatter.rayleigh_rice_lobe(wi, wo, lam, self.nano.model, mat), 0.0)
        if F is None:
            h = wi + wo
            h = h / np.maximum(np.linalg.norm(h, axis=-1, keepdims=True), 1e-300)
            F = self._F(lam)(np.clip(dot_last(h, wi), 0.0, 1.0))
        # the series of the roughness inside the propagating band, as the grid model's (docs/physics.md §9)
        total = scatter.band_series(self.nano.model, lam)(wi, wo, dm.cos_sum(wi, wo))
        # beyond the tangent plane's validity the lobe hands over to first order, W f_K + (1 − W) f_RR with
        # W = w(θ_i) w(θ_o) symmetric: reciprocal (waveoptics.scatter.tangent_blend; its albedo is the tables')
        lobe = blend_with_first_order(dm.K(wi, wo, lam) * total, wi, wo, lam, self.nano.model,
                                      self.material if self.fresnel == "exact" else None, "unpolarized", F)
        return np.where(up, F * lobe, 0.0)

    def facet_nano_brdf(self, wi, wo, wavelength_nm):
        """The BRDF (1/sr) of one micro facet's nano-roughness in that facet's own frame.

        Parameters
        ----------
        wi, wo : array_like (N, 3)
            Paired unit vectors towards the light and the viewer in the facet's local frame (z = facet normal).
        wavelength_nm : float or array_like (N,)
            Wavelength(s) in nm.

        Returns
        -------
        ndarray (N,)
            f_nano(ω_i, ω_o; λ): the PSD series lobe of the *diffraction* model (or Rayleigh-Rice's), with the
            Fresnel factor F(θ_d) this BRDF applies (1 with ``fresnel="one"``); 0 where either z ≤ 0 and without
            nano-roughness. Its albedo at incidence θ is F(θ)(1 − A(θ)) on a conductor, the light the facet's
            coherent part gives up (:meth:`waveoptics.brdf.Nano.coherent_fraction`), and its own on a dielectric. The diffracted part of :meth:`eval` is Walter's
            integral of this function over the micro NDF's facets (module doc).

        References
        ----------
        .. [1] B. Walter et al., EGSR 2007, eq. (14) (a BRDF carried by each facet).
        """
        wi = np.atleast_2d(np.asarray(wi, dtype=float))
        wo = np.atleast_2d(np.asarray(wo, dtype=float))
        lam = np.broadcast_to(np.asarray(wavelength_nm, dtype=float), wi.shape[:1])
        out = np.zeros(wi.shape[0])
        if not self._rough:
            return out
        for val in np.unique(lam):
            sel = lam == val
            self._check_series(float(val))
            out[sel] = self._f_nano(wi[sel], wo[sel], float(val))
        return out

    # -- facet normals -------------------------------------------------------------------------------------
    def _ndf_normals(self, wi):
        """The sampler's facet normals for each ω_i (n, N/2, 3) (:func:`waveoptics.brdf.facet.sampler_normals`).
        Only :meth:`_sample_diffraction` and :meth:`_pdf_diffraction` use them (eval's quadrature lays its nodes
        about h: :func:`waveoptics.brdf.facet.quadrature_normals`)."""
        ndf, ax, ay = self._micro_args()
        return sampler_normals(wi, self.nodes // 2, ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)

    def _f_diffraction(self, wi, wo, lam):
        if not self._rough:
            return np.zeros(wi.shape[0])
        self._check_series(lam)
        out = np.zeros(wi.shape[0])
        step = max(1, (_CHUNK * 256) // self.nodes)
        for a in range(0, wi.shape[0], step):
            sl = slice(a, a + step)
            out[sl] = self._f_diffraction_chunk(wi[sl], wo[sl], lam)
        return np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), out, 0.0)

    def _f_diffraction_chunk(self, wi, wo, lam):
        """Walter's integral over facet normals m by the balance heuristic of two node sets (module doc) and, in a
        lobe's deep tail, the bridge normals (:func:`waveoptics.brdf.facet.bridge_point`): evaluated in the pairs
        whose weight β is > 0 only, as is their density at the other sets' normals."""
        up = (wi[:, 2] > 0) & (wo[:, 2] > 0)
        wi = np.where(up[:, None], wi, [0.0, 0.0, 1.0])
        wo = np.where(up[:, None], wo, [0.0, 0.0, 1.0])
        na = self.nodes // 2
        ndf, ax, ay = self._micro_args()
        rad = self._radial(lam)
        h = _unit(wi + wo)
        # cos θ_d = ω_i·h = ω_o·h, taken as their mean so that ω_i and ω_o swapped give it to the last bit
        cos_d = np.maximum(0.5 * (dot_last(wi, h) + dot_last(wo, h)), 1e-6)
        level = rad.level(cos_d)
        m, valid = quadrature_normals(h, cos_d, rad, level, na, ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)
        # a third set about the bridge point where the integrand peaks between both sets' normals (a lobe's deep
        # tail): counted β N_c times in the balance heuristic, each of its terms times β
        mc, bw, beta = bridge_point(h, cos_d, rad, level, (na, na), ndf=ndf, ax=ax, ay=ay, c=self.ndf_shape)
        on = np.flatnonzero(beta > 0)
        extra = np.zeros(m.shape[:2])
        if on.size:
            extra[on] = BRIDGE_NODES * beta[on, None] * bridge_density(m[on], mc[on], bw[on], h[on])
        out = self._facet_sum(wi, wo, h, cos_d, level, m, valid, extra, lam)
        if on.size:
            mb, okb = bridge_nodes(mc[on], bw[on], h[on])
            extra = BRIDGE_NODES * beta[on, None] * bridge_density(mb, mc[on], bw[on], h[on])
            out[on] += beta[on] * self._facet_sum(wi[on], wo[on], h[on], cos_d[on], level[on], mb, okb, extra, lam)
        return np.where(up, out / (np.maximum(wi[:, 2], 1e-300) * np.maximum(wo[:, 2], 1e-300)), 0.0)

    def _facet_sum(self, wi, wo, h, cos_d, level, m, valid, extra, lam):
        """Σ_k |ω_i·m_k| |ω_o·m_k| f_nano(ω_i^m, ω_o^m) G D(m_k) / den(m_k) over the normals *m* (n_pairs, N, 3)
        where *valid*: den the balance heuristic's denominator, both sets' densities
        (:func:`waveoptics.brdf.facet.quadrature_density`) plus *extra* (n_pairs, N) (the bridge set's, 1/sr)."""
        ndf, ax, ay = self._micro_args()
        spec = ndf_by_name(ndf)
        wi_b = np.broadcast_to(wi[:, None, :], m.shape)
        wo_b = np.broadcast_to(wo[:, None, :], m.shape)
        im = dot_last(wi_b, m)
        om = dot_last(wo_b, m)
        D = spec.D(m, ax, ay, self.ndf_shape)
        # densities of the node sets at every node, symmetric in ω_i and ω_o: D(m) cos θ_m and the radial law
        den = quadrature_density(m, D, h, cos_d, self._radial(lam), level, self.nodes // 2) + extra
        # the integrand |i·m||o·m| / (|i·n||o·n|) f_nano(i_m, o_m) G(i, o, m) D(m)
        ok = valid & (im > 0) & (om > 0) & (den > 0)
        li, lo = local_pair(im, om, dot_last(wi, wo)[:, None])
        # F(θ_d) once per pair: a pair's θ_d is the same in every facet's frame
        fn = self._f_nano(li, lo, lam, F=self._F(lam)(np.clip(cos_d, 0.0, 1.0))[:, None])
        Li, Lo = spec.Lambda(wi, ax, ay, self.ndf_shape), spec.Lambda(wo, ax, ay, self.ndf_shape)
        shape = m.shape[:2]
        gfn, _ = shadowing_by_name(self.micro.shadowing)
        G = gfn(wi_b, wo_b, m, lambda w: np.broadcast_to((Li if w is wi_b else Lo)[:, None], shape))
        val = im * om * fn * G * D / np.where(ok, den, 1.0)
        return np.sum(np.where(ok, val, 0.0), axis=1)

    # -- sampling: a facet normal from the NDF's nodes, then the nano lobe in that facet's frame ---------------
    def _pdf_diffraction(self, wi, wo, lam):
        out = np.zeros(wi.shape[0])
        rad = self._radial(lam)
        for a in range(0, wi.shape[0], _CHUNK):
            sl = slice(a, a + _CHUNK)
            m = self._ndf_normals(wi[sl])
            li = to_facet(np.broadcast_to(wi[sl, None, :], m.shape), m)
            lo = to_facet(np.broadcast_to(wo[sl, None, :], m.shape), m)
            ok = (li[..., 2] > 0) & (lo[..., 2] > 0)
            pt = rad.pdf_t(rad.level(np.clip(li[..., 2], 0.0, 1.0)), lo[..., :2] + li[..., :2])
            out[sl] = np.mean(np.where(ok, pt * lo[..., 2], 0.0), axis=1) * (wo[sl, 2] > 0)
        return out

    def _sample_diffraction(self, wi, u, lam):
        n = self.nodes // 2
        k = np.minimum((u[:, 0] * n).astype(int), n - 1)
        u0 = np.clip(u[:, 0] * n - k, 0.0, np.nextafter(1.0, 0.0))
        m = self._ndf_normals(wi)[np.arange(k.size), k]
        li = to_facet(wi, m)
        rad = self._radial(lam)
        r = rad.radius(rad.level(np.clip(li[:, 2], 0.0, 1.0)), u0)
        phi = 2 * np.pi * u[:, 1]
        lo, inside = _lift(-li[:, :2] + r[:, None] * np.stack([np.cos(phi), np.sin(phi)], axis=-1))
        wo = from_facet(lo, m)
        good = inside & (li[:, 2] > 0) & (wo[:, 2] > 0)
        return np.where(good[:, None], wo, [0.0, 0.0, -1.0])

    def _diffraction_width(self, lam):
        """The nano lobe's width ~ λ/(π ℓ) in direction cosines (ℓ the PSD's length scale)."""
        return lam * 1e-9 / (np.pi * self.nano.model.length_scale)
