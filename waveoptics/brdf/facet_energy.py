"""The energy budget of the facet-frame two-scale lobe (:func:`waveoptics.brdf.facet_frame_diffraction`): the light
the micro facets reflect and scatter, averaged over the facets the light sees.

With Smith's masking, G1(ω_i, m) = χ⁺(ω_i·m) / (1 + Λ(ω_i)), the facets the light sees have the visible-normal
density D(m) (ω_i·m)⁺ G1 / cos θ_i (Heitz 2014, eq. 38): the budget averages each facet's scattered share and
reflectance over it, by :data:`FACET_BUDGET_NODES` normals of the NDF's sampler for ω_i weighted by D / p and
normalized by their sum (1 in expectation).

References
----------
.. [1] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014, §2-3
   (the visible normals' distribution).
.. [2] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (a BRDF carried by each facet).
"""
from __future__ import annotations

import numpy as np

from .. import scatter
from ..materials import cos2_eta_i
from ..runtime import parallel_map
from .facet import budget_nodes
from .facet_polarization import facet_scattered_share
from .roughness_scales import Micro, Nano

__all__ = ['FACET_BUDGET_NODES', 'FACET_BUDGET_NODES_FIELD', 'facet_budget']

#: NDF normals of the energy budget of :func:`waveoptics.brdf.facet_frame_diffraction` (the light the facets scatter and reflect,
#: one facet lobe albedo per normal and wavelength; visible normals of ω_i, Sobol points), independent of the
#: quadrature's nodes. Measured against 65 536 normals (Al, Gaussian σ 15 nm, T 1.5 µm, Beckmann α 0.15 × 0.4,
#: 0.3 and 0.05, θ_i 30-89°): 64 normals read the budget up to 7.7 % low and 9.4 % high at θ_i 88-89° for α ≥ 0.3
#: along the light (the guard then removed 4-7 % of a right lobe, on every grid), within 0.2 % up to 70°; 4096
#: within 0.18 % everywhere, at ~1 ms a wavelength (tests/test_facet_budget.py holds it against a slope-space
#: quadrature). A height field keeps 64 (:data:`FACET_BUDGET_NODES_FIELD`): each facet incidence its budget reaches
#: costs one lobe of the field per wavelength (:func:`waveoptics.brdf.field_albedo_evaluations`), and 4096 normals
#: reach tail incidences the micro lobe hardly lights (11 instead of 9 lobes a wavelength, Beckmann α 0.3, 40°)
FACET_BUDGET_NODES = 4096
FACET_BUDGET_NODES_FIELD = 64


def facet_budget(wi, w, micro: Micro, nano: Nano, F, dm, material, polarization):
    """(scattered, reflected) (n_λ,) each of :func:`waveoptics.brdf.facet_frame_diffraction` for light from *wi*
    at the wavelengths *w* (nm): the facets' scattered light (F (1 − A) per facet on a conductor, the lobe's own
    absolute albedo on a dielectric) and their reflectance F, averaged over the visible normals of *micro*'s NDF
    (:data:`FACET_BUDGET_NODES` Sobol points through its sampler for ω_i, :data:`FACET_BUDGET_NODES_FIELD` for a
    height field; a measured slope table's own bins: :func:`waveoptics.brdf.facet.budget_nodes`). *F* (cos, λ)
    → reflectance, or an object with ``at(wi, wo, λ)``; *dm* the diffraction model.

    References
    ----------
    .. [1] E. Heitz, JCGT 3(2), 2014, eq. (38) (visible normals); Walter et al., EGSR 2007, §5.3 (weights D / p).
    """
    kw = micro.kw()
    ndf, ax, c = kw["ndf"], kw["alpha"], kw["ndf_shape"]
    ay = kw["alpha_y"] if kw["alpha_y"] is not None else ax
    nu = FACET_BUDGET_NODES if nano.surface is None else FACET_BUDGET_NODES_FIELD
    m_u, w_u = budget_nodes(wi, nu, ndf=ndf, ax=ax, ay=ay, c=c)
    return _budget_sums(wi, np.asarray(w, dtype=float), m_u, w_u, nano, F, dm, material, polarization)


def _budget_sums(wi, w, m_a, w_a, nano: Nano, F, dm, material, polarization):
    """(scattered, reflected) of :func:`waveoptics.brdf.facet_frame_diffraction` (n_λ,) each: the facets'
    scattered light and reflectance averaged over the NDF nodes *m_a* (n, 3), weighted by (ω_i·m)⁺ w_a (*w_a*:
    weights of ∫ · D dω_m, :func:`waveoptics.brdf.facet.budget_nodes`) normalized by their sum. For s or p light
    each facet takes the mix of its own s and p light (:func:`waveoptics.brdf.facet_scattered_share`), as its F at
    the mirror direction does."""
    na = m_a.shape[0]
    im_a = m_a @ wi
    node_w = np.where(im_a > 0, im_a * w_a / wi[2], 0.0)
    mirror = 2 * im_a[:, None] * m_a - wi
    c2_a = cos2_eta_i(wi, m_a)   # each NDF facet's rotation of the macro s/p basis into its own
    scattered, reflected = np.zeros(w.size), np.zeros(w.size)

    def one(i):   # the wavelengths in parallel threads (a dielectric's first incidence builds its albedo tables here)
        lam = w[i]
        Fm = (F.at(np.broadcast_to(wi, (na, 3)), mirror, lam) if hasattr(F, "at")
              else F(np.clip(im_a, 0.0, 1.0), lam)) * np.ones(na)
        # per facet: F (1 − A) on a conductor, the lobe's own absolute albedo on a dielectric
        share = np.asarray(facet_scattered_share(nano, np.clip(im_a, 0.0, 1.0), c2_a, lam, dm, material,
                                                 polarization))
        lost = Fm * share if scatter.is_conductor(material) else share * np.ones(na)
        # Σ node_w G1 estimates ∫ G1 (ω_i·m) D dm / cos θ_i = 1 (Smith); normalized by it, so that near grazing
        # incidence, where few NDF nodes face the light, the facets' share is not over-counted
        total_w = float(np.sum(node_w))
        scattered[i] = float(np.sum(node_w * lost) / total_w) if total_w > 0 else 0.0
        reflected[i] = float(np.sum(node_w * Fm) / total_w) if total_w > 0 else 0.0

    parallel_map(one, range(w.size))
    return scattered, reflected
