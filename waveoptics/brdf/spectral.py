"""A BRDF known at wavelength nodes, evaluated at any wavelength of their range and in linear RGB.

Renderers ask for the BRDF at wavelengths of their own: a spectral renderer draws a few continuous wavelengths per
path (Mitsuba 3 draws four in 360–830 nm), an RGB renderer asks for three channels. Models that are built per
wavelength (:class:`waveoptics.brdf.TabulatedTwoScaleBRDF`, whose lobes are computed on a direction grid at given
wavelengths) or that are costly per wavelength answer both through :class:`SpectralNodes`:

* ``eval(wi, wo, λ)`` interpolates f linearly in λ between the two nodes that bracket λ (exact at a node);
* ``pdf`` and ``sample`` at λ use the node nearest λ (they only have to agree with each other: any density that
  is positive where f is gives an unbiased estimator, Veach 1997 §9.2);
* ``eval_rgb(wi, wo)`` = Σ_j f(λ_j) M_j, with M the reflectance-to-linear-RGB map of the nodes under an illuminant
  (:func:`waveoptics.colour.reflectance_to_rgb_matrix`; a white reflector gives (1, 1, 1));
* ``pdf_rgb`` / ``sample_rgb`` use the equal-weight mixture of the nodes' densities, so sampling covers the lobe
  of every wavelength (the diffracted lobe widens with λ).

The error of the linear interpolation in λ is measured in ``tests/test_renderers.py`` against the exact model at
wavelengths half-way between nodes.

References
----------
.. [1] E. Veach, *Robust Monte Carlo Methods for Light Transport Simulation*, PhD thesis, Stanford, 1997, §9.2
   (mixture densities).
.. [2] W. Jakob et al., Mitsuba 3, 2022 (spectral rendering with four wavelengths per path, hero-wavelength
   sampling: A. Wilkie et al., "Hero Wavelength Spectral Sampling", EGSR 2014).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .. import colour
from ..errors import FieldError
from .protocol import BRDF, BRDFSample, broadcast_pair, check_uniform, lobe_choice
from .directions import as_dirs

__all__ = ['SpectralNodes']


@dataclass(frozen=True, eq=False)
class SpectralNodes(BRDF):
    """The BRDF *base* at the wavelengths *wavelengths_nm* (nm, increasing), evaluated at any λ between the first
    and the last node and in linear RGB (see the module doc).

    Parameters
    ----------
    base : BRDF
        Model evaluated at the nodes only.
    wavelengths_nm : tuple of float
        Nodes (nm), strictly increasing, at least one.
    illuminant, space : str
        Illuminant and RGB space of :meth:`eval_rgb` (the RGB of a reflectance under that light, white-balanced).
    """

    base: BRDF
    wavelengths_nm: tuple
    illuminant: str = "D65"
    space: str = "sRGB"

    def __post_init__(self):
        w = np.atleast_1d(np.asarray(self.wavelengths_nm, dtype=float))
        if w.ndim != 1 or w.size < 1 or np.any(~np.isfinite(w)) or np.any(np.diff(w) <= 0):
            raise FieldError(f"wavelengths_nm={self.wavelengths_nm!r} is not allowed; give increasing "
                             "wavelengths in nm", "wavelengths_nm")
        object.__setattr__(self, "wavelengths_nm", tuple(float(x) for x in w))

    @property
    def nodes(self) -> np.ndarray:
        return np.asarray(self.wavelengths_nm)

    @functools.cached_property
    def rgb_matrix(self) -> np.ndarray:
        """M (n_nodes, 3): linear RGB = Σ_j f(λ_j) M_j."""
        return colour.reflectance_to_rgb_matrix(self.nodes, self.illuminant, self.space)

    # -- wavelength bookkeeping ----------------------------------------------------------------------------
    def _check_range(self, lam):
        lo, hi = self.nodes[0], self.nodes[-1]
        if not lo <= lam <= hi:
            raise FieldError(f"wavelength {lam:g} nm is outside the nodes {lo:g}-{hi:g} nm of this BRDF",
                             "wavelength_nm")

    def _bracket(self, lam):
        """(index a, index b, weight of b) of the nodes around λ."""
        self._check_range(lam)
        w = self.nodes
        b = int(np.clip(np.searchsorted(w, lam), 1, max(w.size - 1, 1))) if w.size > 1 else 0
        a = max(b - 1, 0)
        t = 0.0 if a == b else (lam - w[a]) / (w[b] - w[a])
        return a, b, float(t)

    def _nearest(self, lam):
        self._check_range(lam)
        return float(self.nodes[np.argmin(np.abs(self.nodes - lam))])

    def _brackets(self, lam):
        """Arrays (a, b, t) of :meth:`_bracket` for every wavelength of *lam* (n,)."""
        w = self.nodes
        bad = (lam < w[0]) | (lam > w[-1]) | ~np.isfinite(lam)
        if np.any(bad):
            self._check_range(float(lam[bad][0]))
        if w.size == 1:
            z = np.zeros(lam.size, dtype=int)
            return z, z, np.zeros(lam.size)
        b = np.clip(np.searchsorted(w, lam), 1, w.size - 1)
        a = b - 1
        return a, b, (lam - w[a]) / (w[b] - w[a])

    def _nearest_index(self, lam):
        bad = (lam < self.nodes[0]) | (lam > self.nodes[-1]) | ~np.isfinite(lam)
        if np.any(bad):
            self._check_range(float(lam[bad][0]))
        return np.argmin(np.abs(self.nodes[None, :] - lam[:, None]), axis=1)

    # -- protocol on flat arrays: one call of the base model per node, not per wavelength --------------------
    def _eval_flat(self, wi, wo, lam):
        """f linear in λ between the bracketing nodes."""
        a, b, t = self._brackets(lam)
        out = np.zeros(lam.size)
        for j in np.unique(np.concatenate([a, b])):
            weight = np.where(a == j, 1.0 - t, 0.0) + np.where((b == j) & (b != a), t, 0.0)
            sel = weight > 0
            if np.any(sel):
                out[sel] += weight[sel] * self.base._eval1(wi[sel], wo[sel], self.wavelengths_nm[j])
        return out

    def _pdf_flat(self, wi, wo, lam):
        """The base model's density at the node nearest λ."""
        near = self._nearest_index(lam)
        out = np.zeros(lam.size)
        for j in np.unique(near):
            sel = near == j
            out[sel] = self.base._pdf1(wi[sel], wo[sel], self.wavelengths_nm[j])
        return out

    def _sample_flat(self, wi, u, lam):
        """The base model's sampler at the node nearest λ."""
        near = self._nearest_index(lam)
        wo = np.zeros_like(wi)
        for j in np.unique(near):
            sel = near == j
            wo[sel] = self.base._sample1(wi[sel], u[sel].copy(), self.wavelengths_nm[j])
        return wo

    # -- one wavelength (albedo) ---------------------------------------------------------------------------
    def _eval1(self, wi, wo, lam):
        a, b, t = self._bracket(lam)
        fa = self.base._eval1(wi, wo, self.wavelengths_nm[a])
        if t == 0.0:
            return fa
        fb = self.base._eval1(wi, wo, self.wavelengths_nm[b])
        return (1.0 - t) * fa + t * fb

    def _pdf1(self, wi, wo, lam):
        return self.base._pdf1(wi, wo, self._nearest(lam))

    def _sample1(self, wi, u, lam):
        return self.base._sample1(wi, u, self._nearest(lam))

    def _albedo_parts(self, lam):
        _, width_x, width_y = self.base._albedo_parts(self._nearest(lam))[-1]
        return [(lambda a, b: self._eval1(a.reshape(-1, 3), b.reshape(-1, 3), lam).reshape(b.shape[:-1]),
                 width_x, width_y)]

    # -- RGB -----------------------------------------------------------------------------------------------
    def eval_spectrum(self, wi, wo):
        """f at every node: (..., n_nodes) in 1/sr."""
        wi, wo, _, shape = broadcast_pair(wi, wo, self.nodes[0])
        return self.base._eval_nodes(wi, wo, self.wavelengths_nm).reshape(shape + (self.nodes.size,))

    def eval_rgb(self, wi, wo):
        """Linear RGB BRDF (..., 3) in 1/sr (see the module doc)."""
        return self.eval_spectrum(wi, wo) @ self.rgb_matrix

    def pdf_rgb(self, wi, wo):
        """Density (1/sr over ω_o) of :meth:`sample_rgb`: the mean of the nodes' densities."""
        wi, wo, _, shape = broadcast_pair(wi, wo, self.nodes[0])
        return np.mean([self.base._pdf1(wi, wo, lam) for lam in self.wavelengths_nm], axis=0).reshape(shape)

    def sample_rgb(self, wi, u) -> BRDFSample:
        """Sample ω_o from the node mixture: u[..., 0] picks a node uniformly and is remapped (pbrt-v4 §2.4) for
        that node's own sampler. The weight is RGB (..., 3): f_rgb cos θ_o / pdf_rgb."""
        u = check_uniform(u)
        wi = as_dirs(wi, "wi")
        shape = np.broadcast_shapes(wi.shape[:-1], u.shape[:-1])
        wi_f = np.broadcast_to(wi, shape + (3,)).reshape(-1, 3)
        u_f = np.broadcast_to(u, shape + (2,)).reshape(-1, 2).copy()
        n = self.nodes.size
        idx, u_f[:, 0] = lobe_choice(u_f[:, 0], [np.full(u_f.shape[0], 1.0 / n)] * n)
        wo = self._sample_flat(wi_f, u_f, self.nodes[idx])
        up = (wi_f[:, 2] > 0) & (wo[:, 2] > 0)
        wo_ok = np.where(up[:, None], wo, np.array([0.0, 0.0, 1.0]))
        p = self.pdf_rgb(wi_f, wo_ok)
        ok = up & (p > 0)
        f = self.eval_rgb(wi_f, wo_ok)
        weight = np.where(ok[:, None], f * (wo_ok[:, 2] / np.where(ok, p, 1.0))[:, None], 0.0)
        return BRDFSample(wo=wo.reshape(shape + (3,)), weight=weight.reshape(shape + (3,)),
                          pdf=np.where(ok, p, 0.0).reshape(shape))
