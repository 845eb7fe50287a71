"""The two-scale BRDF as a function from diffracted lobes tabulated over incidence, interpolated relative to the
specular direction.

:class:`TabulatedTwoScaleBRDF` evaluates the two-scale model (docs/physics.md §7) for *any* nano-roughness (PSD
statistics or a height field, any diffraction model) at any (ω_i, ω_o) and at the wavelengths it was built for:

* the coherent part A(θ_d) f_mf and the diffuse substrate are closed forms, evaluated exactly per pair (A, what
  the nano lobe leaves, from tables over θ_d of the nano statistics or of the height field's own lobe:
  :meth:`waveoptics.brdf.Nano.coherent_fraction`);
* the diffracted part is computed by :func:`waveoptics.brdf.evaluate` on a direction grid at incidence angles
  θ_k (azimuth 0; each facet's nano lobe in its own frame for PSD statistics, docs/physics.md §7) and
  interpolated between them *relative to the specular direction*: at θ_i between θ_a and θ_b, an isotropic table
  reads each node at ω_o turned about the axis normal to the plane of incidence by θ_i − θ_k (which takes ω_i's
  mirror direction to θ_k's, as a tilted facet turns its lobe), and the two values are blended linearly in θ_i;
  the blend moves the lobe with the incidence instead of cross-fading two lobes at different places. Reads within
  a cell of the horizon take the cells beyond the rim as the mean of their neighbours inside it (the lobe rises
  towards the horizon, where zeros would pull it down). Beyond θ_o 65-69° the read hands over to rim tables
  (:mod:`waveoptics.brdf.tabulated_rim`: the same facet-frame sum on nodes 1.5° × 5° apart in (θ_o, φ_o) from
  63° to the horizon), read at ω_o itself and blended linearly in θ_i, where a direction-cosine cell spans 5.7°
  at 78° and the turn by θ_i − θ_k reads the concave lobe up and down the horizon's slope.
* Surfaces whose nano lobe depends on the light's azimuth (height fields, gratings, anisotropic micro NDFs) are
  tabulated in the surface's frame over azimuth φ_k too (:data:`PHI_NODES_ANISOTROPIC`) and read at each node's
  mirror point plus the offset Δ = (u_o, v_o) − (mirror point of ω_i) in direction cosines, blended in θ_i and
  φ_i (never rotated: a grating's orders stay where the grating puts them, and they shift in direction cosines,
  the Harvey-Shack picture, docs/physics.md §11). The lobe of an anisotropic analytic micro NDF with PSD
  statistics changes its shape with the light's azimuth as D(h) does, which the shift does not follow: between
  nodes 90° apart (Al, Beckmann α 0.15 × 0.4, 64², exits to 60° where the lobe is above 1 % of its peak, φ_i
  every 7.5°) it read the lobe up to 58 % off at the 90th percentile and 4.1x at most at θ_i 30°, 200 % and 13x
  at 60°. Such tables are held at :data:`PHI_NODES_ANISOTROPIC_NDF` (12) light azimuths and each node is read at
  the exit whose half-vector with the node's light is (ω_i, ω_o)'s, times cos θ cos θ' / (cos θ_i cos θ_o)
  (:func:`waveoptics.brdf.tabulated_reads.half_vector_exit`: the microfacet lobe at the same D(h)), blended
  linearly in θ_i and φ_i: 90th percentile / max 1.7 / 5.2 % at θ_i 30°, 3.4 / 8.6 % at 60° (midway between
  incidence nodes 10° apart too: 2.3 / 5.8 %, 4.0 / 9.5 %). Turned with the light instead (the NDF's axes turned
  under it), 24 nodes read in log f as the rim tables are still read it 7-13 / 33-38 % off
  (scripts/aniso_light_azimuth.py; tests/test_anisotropic_rim.py). The sampler keeps the nearest node's lobe
  shifted to ω_i's mirror point. An anisotropic micro NDF with PSD statistics has rim tables at
  :data:`waveoptics.brdf.tabulated_rim.RIM_LIGHT_AZIMUTHS` (24) light azimuths (the main nodes among them), each
  held in its light's frame and read turned with the light, interpolated across the light's azimuth in log f (at
  the nodes within 1.4 % of the facet-frame sum at 80-88°, where the shifted direction-cosine cells read 2.0-2.4x
  it; near the horizon the lobe changes by orders of magnitude with the light's azimuth, and the former linear
  blend of the 4 main nodes' rim tables read it up to 7.2x at φ_i 45°: tests/test_anisotropic_rim.py). The 12
  main azimuths cost 1.6x the CPU time of 4 to build (64², rim tables, under load: 3 wavelengths 30 → 49 s, 25
  wavelengths 48 → 77 s): the facet-frame kernel's time per incidence (3 wavelengths: 0.21 s per main lobe, 0.09 s
  per rim table) dominates.

Measured (``tests/test_brdf_tabulated.py``): on the nodes it equals the grid lobes up to θ_o 65° (beyond, to the
rim tables' interpolation: within 0.6 % to 80°, 1 % to 85°); between 10° nodes the
diffracted part's peak is within 1 % and its energy within 2 % of a direct evaluation at that incidence. Reciprocal
for PSD statistics: f(ω_i, ω_o)/f(ω_o, ω_i) − 1 ≤ 0.5 % at θ ≤ 65° on and between the nodes (α 0.05-0.1, 96²
cells; ``tests/test_twoscale_facet_frame.py``), because the facet route's quadrature is laid out about each cell's
half-vector in a frame turning with it (:func:`waveoptics.brdf.facet_frame_diffraction`), so the tables at azimuth
0 read turned hold the same sum for the pair and its swap. With an end at 70-80° (facets' nano lobes handed over to
first order, :mod:`waveoptics.scatter.tangent_blend`), over 400 seeded pairs in and out of the plane, on and between
the nodes, max |f(ω_i, ω_o)/f(ω_o, ω_i) − 1| with both angles ≤ 75 / 78 / 80° (``tests/test_tabulated_rim.py``,
96², under load): Beckmann α 0.05: 1.4 / 1.5 / 1.8 %, α 0.1: 1.0 / 1.4 / 1.3 %, α 0.3: 0.5 / 0.5 / 0.6 %; GGX α
0.05: 0.7 / 0.8 / 0.8 % (before the facet tables held first-order lobes as g / cos²θ_o on incidence nodes 2° apart
from 0°: 1.3 / 1.3 / 1.6 %, 1.1 / 1.2 / 1.1 %, 0.4 / 0.6 / 0.8 %, 0.7 / 0.7 / 0.8 %; without the rim tables 1.4 / 4.0 / 5.5 %, 0.9 / 1.3 / 4.4 %, 1.1 at 80°, 0.6 / 1.3 /
1.7 %: the direction-cosine cells' read near the horizon, 1.7-5.5 % below the facet-frame sum at θ_o 78-80°; before
the facet tables held the hand-over's two lobes apart, on an equal-area grid, with incidence nodes 2° apart,
:func:`waveoptics.brdf.facet_frame_diffraction`: 5.2 / 7.8 / 8.5 %, 3.8 / 4.9 / 10.2 %, 2.9 / 3.3 / 9.1 %, 2.4 /
3.7 / 3.7 %). The rim tables cost 17-21 % more CPU time per table and 10 % more memory (96², 3 wavelengths).

References
----------
.. [1] J. E. Harvey, "Light-scattering characteristics of optical surfaces", PhD thesis, University of Arizona,
   1976 (shift-invariance of scattering in direction cosines).
.. [2] N. Holzschuch, R. Pacanowski, ACM TOG 36(4), 66, 2017 (two-scale model).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import scatter
from ..errors import FieldError
from ..scatter.grid import DirectionGrid
from .protocol import TwoScaleParts
from .roughness_scales import isotropic
from .tabulated_reads import (PHI_NODES_ANISOTROPIC, PHI_NODES_ANISOTROPIC_NDF, filled_beyond_rim, half_vector_exit,
                              light_azimuth_nodes, reads_by_half_vector)
from .tabulated_rim import rim_across_light_azimuth, rim_light_azimuths, rim_lobes, rim_weight
from .twoscale import ENERGY_GUARD_PREFIX, energy_guard_cause, evaluate

__all__ = ['THETA_NODES_DEG', 'PHI_NODES_ANISOTROPIC', 'PHI_NODES_ANISOTROPIC_NDF', 'light_azimuth_nodes',
           'reads_by_half_vector', 'TabulatedTwoScaleBRDF']

#: default incidence nodes (degrees): 5° steps, denser towards grazing where lobes change fastest
THETA_NODES_DEG = tuple(float(t) for t in (*range(0, 75, 5), 75, 78, 81, 84, 86, 88))


def _rotate(w, phi):
    """Rotate vectors (n, 3) about z by −phi (n,)."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([c * w[:, 0] + s * w[:, 1], -s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=-1)


def _unrotate(w, phi):
    return _rotate(w, -phi)


def _bracket(nodes, x):
    """Indices (a, b) of the nodes around x and the weight of b (linear); clamped at the ends."""
    f = np.interp(x, nodes, np.arange(nodes.size))
    a = np.clip(np.floor(f).astype(int), 0, nodes.size - 1)
    b = np.clip(a + 1, 0, nodes.size - 1)
    return a, b, f - a


@dataclass(frozen=True, eq=False)
class TabulatedTwoScaleBRDF(TwoScaleParts):
    """Two-scale BRDF with its diffracted part tabulated over incidence (see the module doc).

    Parameters
    ----------
    material, micro, kd, diffuse, fresnel, ndf_shape
        As :class:`waveoptics.brdf.MicrofacetBRDF`. The lobes are tabulated for :attr:`lobe_material` (with
        ``fresnel="one"`` the reflector of F = 1, as the coherent part).
    nano : Nano or None
        PSD statistics or a height field.
    wavelengths_nm : tuple of float
        Wavelengths (nm) the table holds; ``eval`` accepts these.
    resolution : int
        Direction-grid cells per axis of each tabulated lobe.
    thetas_deg : tuple of float
        Incidence nodes (degrees, increasing, in [0, 90)).
    n_phi : int or None
        Azimuth nodes; None chooses :func:`light_azimuth_nodes` (1 for isotropic surfaces,
        :data:`PHI_NODES_ANISOTROPIC_NDF` for an anisotropic analytic micro NDF with PSD statistics
        (:attr:`half_vector_read`) and :data:`PHI_NODES_ANISOTROPIC` otherwise), as the sphere renders of
        :func:`waveoptics.simulate.run` do.
    solver, diffraction, device, precision
        As :func:`waveoptics.brdf.evaluate`.
    lobes_at : callable, optional
        wi (3,) → :class:`waveoptics.brdf.Lobes` on a hemisphere grid at ``wavelengths_nm``: how to compute the
        tabulated lobes (default: :func:`waveoptics.brdf.evaluate` with the fields above).
    rim : bool
        Build rim tables (:mod:`waveoptics.brdf.tabulated_rim`: the facet-frame sum near the horizon on a grid in
        (cos θ_o, φ_o), read beyond θ_o 65-69°) where the lobes come from the facet-frame route: at one light
        azimuth (an isotropic table of PSD statistics or an isotropic height field) or, for an anisotropic micro
        NDF with PSD statistics, at :func:`waveoptics.brdf.tabulated_rim.rim_light_azimuths` light azimuths 2π/n_q
        apart from 0 (24 for 4 azimuth nodes; the main nodes among them).
    table_lobes, table_grid, table_phis_deg : optional
        Lobes computed elsewhere (n_φ, n_θ, n_λ, n_v, n_u) in 1/sr on *table_grid*, at the light azimuths
        *table_phis_deg* (evenly spaced, or one azimuth for an isotropic table): nothing is computed
        (:func:`waveoptics.open_table`).
    table_rim : optional
        The rim tables (n_θ, n_λ, n_cos, n_φ) in 1/sr computed with *table_lobes* (:attr:`rim_table`), or
        (n_q, n_θ, n_λ, n_cos, n_φ) at n_q light azimuths 2π/n_q apart from 0, or None.
    progress : callable, optional
        Called with 1 after each tabulated incidence.
    """

    wavelengths_nm: tuple = (550.0,)
    resolution: int = 128
    thetas_deg: tuple = THETA_NODES_DEG
    n_phi: int | None = None
    solver: str = "auto"
    device: object = None
    precision: str = "float32"
    progress: object = None
    lobes_at: object = None
    rim: bool = True
    table_lobes: object = None
    table_grid: object = None
    table_phis_deg: tuple = (0.0,)
    table_rim: object = None
    _table: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        super().__post_init__()
        th = np.asarray(self.thetas_deg, dtype=float)
        if th.ndim != 1 or th.size < 1 or np.any(np.diff(th) <= 0) or th[0] < 0 or th[-1] >= 90:
            raise FieldError(f"thetas_deg={self.thetas_deg!r} is not allowed; give increasing angles in "
                             "[0, 90) degrees", "thetas_deg")
        object.__setattr__(self, "wavelengths_nm", tuple(float(x) for x in np.atleast_1d(self.wavelengths_nm)))
        self._build()

    # -- table --------------------------------------------------------------------------------------------
    @property
    def isotropic(self) -> bool:
        """Whether the lobe depends on θ_i only: PSD statistics (isotropic) and an isotropic micro NDF."""
        return isotropic(self.micro, self.nano)

    @property
    def half_vector_read(self) -> bool:
        """Whether the tables are read by the half-vector (:func:`waveoptics.brdf.tabulated_reads.
        half_vector_exit`): an anisotropic analytic micro NDF with PSD statistics, whose lobe changes its shape with
        the light's azimuth as D(h) does."""
        return reads_by_half_vector(self.micro, self.nano)

    def _build(self):
        if self.table_lobes is not None:
            diff = np.asarray(self.table_lobes, dtype=float)
            phis = np.radians(np.asarray(self.table_phis_deg, dtype=float))
            if diff.ndim != 5 or diff.shape[:3] != (phis.size, len(self.thetas_deg), len(self.wavelengths_nm)):
                raise FieldError(f"table_lobes of shape {diff.shape} do not match {phis.size} azimuths, "
                                 f"{len(self.thetas_deg)} angles and {len(self.wavelengths_nm)} wavelengths",
                                 "table_lobes")
            rim = None if self.table_rim is None else np.asarray(self.table_rim, dtype=float)
            if rim is not None and rim.ndim == 4:   # one light azimuth
                rim = rim[None]
            if rim is not None and (rim.ndim != 5 or rim.shape[1:3] != diff.shape[1:3]):
                raise FieldError(f"table_rim of shape {rim.shape} does not match {len(self.thetas_deg)} angles and "
                                 f"{len(self.wavelengths_nm)} wavelengths", "table_rim")
            self._table.update(grid=self.table_grid, thetas=np.radians(np.asarray(self.thetas_deg, dtype=float)),
                               phis=phis, diffraction=diff, rim=rim,
                               energy_scale=np.ones((1, diff.shape[2])))
            return
        grid = DirectionGrid.hemisphere(int(self.resolution))
        thetas = np.radians(np.asarray(self.thetas_deg, dtype=float))
        n_phi = light_azimuth_nodes(self.micro, self.nano) if self.n_phi is None else int(self.n_phi)
        phis = 2 * np.pi * np.arange(n_phi) / n_phi
        w = np.asarray(self.wavelengths_nm)
        diff = rim = None
        rough = self.nano is not None and self.nano.sigma > 0
        warm = self._warm_kernel(grid, w) if rough and self.lobes_at is None else None
        scale = []
        # an analytic NDF with PSD statistics: the light at φ + π sees the lobe at φ turned by π (D(−m) = D(m))
        half = n_phi // 2 if self._half_turn_symmetric(n_phi) else n_phi
        lobes = self._incidence_lobes(grid, w, [np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
                                                for ph in phis[:half] for th in thetas] if rough else [], n_phi)
        for p, ph in enumerate(phis):
            for t, th in enumerate(thetas):
                if rough and p >= half:   # (u, v) → (−u, −v) of the node at φ − π; its rim tables, in the light's
                    diff[p, t] = diff[p - half, t][..., ::-1, ::-1]   # frame, are the same
                    if rim is not None:
                        rim[p, t] = rim[p - half, t]
                elif rough:
                    L, r = next(lobes)
                    if self.lobes_at is not None:
                        grid = L.grid
                    if diff is None:
                        diff = np.zeros((n_phi, thetas.size, w.size, grid.n_v, grid.n_u))
                    diff[p, t] = L.diffraction
                    scale.append(L.info["diffraction_energy_scale"])
                    if r is not None:
                        rim = np.zeros((n_phi, thetas.size) + r.shape) if rim is None else rim
                        rim[p, t] = r
                if self.progress is not None:
                    self.progress(1)
        if warm is not None:
            warm.join()
        scale = scale + scale if half < n_phi and scale else scale
        if rim is not None and not self.isotropic and self.micro.ndf != "tabulated":
            rim = self._rim_at_light_azimuths(rim, grid, thetas, phis, np.asarray(scale).reshape(n_phi, thetas.size,
                                                                                                 w.size))
        if diff is None:
            diff = np.zeros((n_phi, thetas.size, w.size, grid.n_v, grid.n_u))
        self._table.update(grid=grid, thetas=thetas, phis=phis, diffraction=diff, rim=rim,
                           energy_scale=np.asarray(scale) if scale else np.ones((1, w.size)))
        if scale and np.min(scale) < 1.0:   # the energy guard's one line for the table (_incidence_lobes)
            s = np.asarray(scale).reshape(n_phi, thetas.size, w.size)
            p, t, j = np.unravel_index(int(np.argmin(s)), s.shape)
            scatter.solvers.warn_or_collect(
                f"{ENERGY_GUARD_PREFIX} removed up to {100 * (1 - s[p, t, j]):.3g}% of the diffracted light in "
                f"{int(np.sum(s.min(axis=-1) < 1.0))} of {n_phi * thetas.size} incidences of the diffraction table "
                f"(at {float(w[j]):.4g} nm, theta_i = {np.degrees(thetas[t]):.3g} deg, phi_i = "
                f"{np.degrees(phis[p]):.3g} deg): {energy_guard_cause(grid)}")

    def _half_turn_symmetric(self, n_phi) -> bool:
        """Whether the table at light azimuth φ + π is the one at φ turned by π about the normal, (u, v) → (−u, −v):
        an anisotropic analytic micro NDF (a function of the stretched slope radius, D(−m) = D(m)) with PSD
        statistics (isotropic), lobes computed here, an even number of azimuth nodes. The facet-frame sums turn
        with the half-vector's azimuth: the lobes so taken at 180° and 270° equal those computed there within
        7e-16 (Al, Beckmann α 0.15 × 0.4, 64²). Half the main lobes are computed."""
        return (not self.isotropic and self.lobes_at is None and self.nano is not None
                and self.nano.model is not None and self.micro.ndf != "tabulated" and n_phi % 2 == 0)

    def _rim_at(self, wi, L, n_phi):
        """The rim table (n_λ, n_cos, n_φ) of the incidence node *wi* (:func:`waveoptics.brdf.tabulated_rim.
        rim_lobes`, made with *L*'s facet tables and energy-guard factor), or None where no rim is built: not
        asked, lobes from ``lobes_at``, a height field at several azimuth nodes (its tables are shifted, not
        turned) or a lobe by the paraxial route. An anisotropic micro NDF with PSD statistics has one per light
        azimuth node: without them its grid read at exits 85-88° was 2.4-9x the pointwise form
        (tests/test_tabulated_rim.py)."""
        if (not self.rim or self.lobes_at is not None or (n_phi != 1 and self.nano.model is None)
                or L.info["facet_integration"] != "frame"):
            return None
        return rim_lobes(wi, self.wavelengths_nm, self.lobe_material, self.micro, self.nano, L.grid,
                         diffraction=self.diffraction, energy_scale=L.info["diffraction_energy_scale"],
                         device=self.device, precision=self.precision)

    def _rim_at_light_azimuths(self, rim, grid, thetas, phis, scale):
        """The rim tables (n_q, n_θ, n_λ, n_cos, n_φ) of an anisotropic micro NDF at
        :func:`waveoptics.brdf.tabulated_rim.rim_light_azimuths` light azimuths 2π/n_q apart from 0: those of the
        main azimuth nodes *phis* as built with their lobes (*rim*), the others computed here (in parallel threads),
        each times the energy-guard factor interpolated linearly in azimuth between the main nodes' (*scale*,
        (n_φ, n_θ, n_λ); 1 where the guard did not act). An analytic NDF (a function of the stretched slope radius,
        D(−m) = D(m)) with PSD statistics looks the same from the light at φ + π in the light's frame (the
        facet-frame sums agree to 4e-16): only the light azimuths in [0, π) are computed (10 of the 20 extra ones
        for 4 main nodes). A measured slope table keeps the main nodes' rim tables only (:meth:`_build`): its rim
        varies with the light's azimuth by its histogram's noise, which more nodes do not resolve (a Gaussian
        field's table, α 0.066 × 0.065, Au, θ_i 40°, 32²: max/min over φ_i 1.10 at the median exit; against 24
        azimuths, 12 read in log f are within 24 % max / 7.4 % at the 99th percentile, the 4 main ones read
        linearly 23 % / 10 %). The mirror symmetry (−φ, with
        φ_o → −φ_o) holds for the integral but not for the sums' quadrature (up to 25 % apart where the rim lobe is
        1e-3 of its peak, Beckmann α 0.15 × 0.4 at exits 80-85°): it is not used."""
        from ..runtime import parallel_imap

        n_phi = phis.size
        n_q = rim_light_azimuths(n_phi)
        per = n_q // n_phi
        out = np.zeros((n_q,) + rim.shape[1:])
        out[::per] = rim
        half = n_q // 2 if n_q % 2 == 0 else n_q
        targets = [q for q in range(n_q) if q % per]
        computed = sorted({q % half for q in targets})

        def one(qk):
            q, k = qk
            ph, th = 2 * np.pi * q / n_q, thetas[k]
            wi = np.array([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
            return rim_lobes(wi, self.wavelengths_nm, self.lobe_material, self.micro, self.nano, grid,
                             diffraction=self.diffraction, device=self.device, precision=self.precision)

        jobs = [(q, k) for q in computed for k in range(thetas.size)]
        base = dict(zip(jobs, parallel_imap(one, jobs)))
        for q in targets:
            p0, f = divmod(q, per)
            s = (1 - f / per) * scale[p0] + f / per * scale[(p0 + 1) % n_phi]     # (n_θ, n_λ)
            for k in range(thetas.size):
                out[q, k] = base[(q % half, k)] * s[k][:, None, None]
        return out

    def _incidence_lobes(self, grid, w, wis, n_phi):
        """(:class:`waveoptics.brdf.Lobes`, rim table or None, :meth:`_rim_at`) at each light direction of *wis*
        (the table's nodes), in their order: by ``lobes_at`` one after the other, or by
        :func:`waveoptics.brdf.evaluate` on *grid* at the wavelengths *w*. For PSD statistics the first incidence
        alone (it builds what all of them share: the band series, albedo and facet tables), the others in parallel
        threads (:func:`waveoptics.runtime.parallel_imap`), each the same as built alone (the NumPy of one
        incidence overlaps the facet-frame kernel of another). A height field's incidences stay in order: its
        coherent fraction interpolates between incidence nodes computed as the incidences ask for them
        (:meth:`waveoptics.brdf.Nano.coherent_fraction`), a cache whose content depends on the order."""
        from ..runtime import parallel_imap

        def one(wi):
            held = []   # the energy guard's lines: one for the whole table (_build), the others passed on
            with scatter.diffraction_warnings_held(held):
                L = self.lobes_at(wi) if self.lobes_at is not None else evaluate(
                    wi, w, self.lobe_material, self.micro, self.nano, grid, solver=self.solver, kd=0.0,
                    device=self.device, precision=self.precision, diffraction=self.diffraction)
            for msg in held:
                if not msg.startswith(ENERGY_GUARD_PREFIX):
                    scatter.solvers.warn_or_collect(msg)
            return L, self._rim_at(wi, L, n_phi)

        if not wis:
            return
        if self.lobes_at is not None or self.nano.model is None:
            yield from map(one, wis)
            return
        yield one(wis[0])
        yield from parallel_imap(one, wis[1:])

    def _warm_kernel(self, grid, w):
        """The thread of :func:`waveoptics.brdf.facet_frame_cl.warm_facet_frame_kernel` building the facet-frame
        kernel while the first incidence's NumPy work runs, where the lobes take the frame route; else None."""
        from .. import scatter
        from .facet_frame_cl import warm_facet_frame_kernel
        from .twoscale_frame import facet_route

        if facet_route(self.micro, self.nano, grid, w, "auto") != "frame":
            return None
        return warm_facet_frame_kernel(self.micro, self.nano, scatter.get_model(self.diffraction, perturbative=True),
                                       device=self.device, precision=self.precision)

    def _cdf(self) -> np.ndarray:
        """The cumulative sums of each tabulated lobe over its cells (n_φ, n_θ, n_λ, n_v n_u), for sampling; made on
        first use (a model only evaluated, such as an exported table, never needs them)."""
        if "cdf" not in self._table:
            diff = self._table["diffraction"]
            self._table["cdf"] = diff.reshape(diff.shape[:3] + (-1,)).cumsum(axis=-1)
        return self._table["cdf"]

    @property
    def grid(self) -> DirectionGrid:
        return self._table["grid"]

    @property
    def table(self) -> np.ndarray:
        """The tabulated diffracted lobes (n_φ, n_θ, n_λ, n_v, n_u) in 1/sr (φ, θ the light's direction)."""
        return self._table["diffraction"]

    @property
    def rim_table(self) -> np.ndarray | None:
        """The rim tables (n_θ, n_λ, n_cos, n_φ) in 1/sr (:mod:`waveoptics.brdf.tabulated_rim`) of a table at one
        light azimuth, (n_q, n_θ, n_λ, n_cos, n_φ) of one at n_q light azimuths 2π/n_q apart from 0 (an anisotropic
        micro NDF), or None."""
        rim = self._table.get("rim")
        return rim[0] if rim is not None and rim.shape[0] == 1 else rim

    def _wavelength_index(self, lam):
        w = np.asarray(self.wavelengths_nm)
        i = int(np.argmin(np.abs(w - lam)))
        if not np.isclose(w[i], lam, rtol=1e-9, atol=1e-9):
            raise FieldError(f"wavelength {lam:g} nm is not in this table; it holds {', '.join(f'{x:g}' for x in w)} "
                             "nm", "wavelength_nm")
        return i

    # -- the diffracted part ------------------------------------------------------------------------------
    def _frame(self, wi):
        """Azimuth of each ω_i and the bracketing φ nodes with their weights."""
        phi_i = np.arctan2(wi[:, 1], wi[:, 0])
        phis = self._table["phis"]
        if phis.size == 1:
            z = np.zeros(wi.shape[0], int)
            return phi_i, [(z, np.ones(wi.shape[0]))]
        step = phis[1] - phis[0]
        f = np.mod(phi_i, 2 * np.pi) / step
        a = np.floor(f).astype(int) % phis.size
        t = f - np.floor(f)
        return phi_i, [(a, 1 - t), ((a + 1) % phis.size, t)]

    def _table_rotation(self, wi):
        """Azimuth by which directions are rotated into the table's frame: for an isotropic surface from the light's
        own azimuth to the table's one azimuth; none for other surfaces, whose lobes are tabulated in the surface's
        frame and only shifted with the specular direction (their diffraction pattern, e.g. a grating's orders,
        keeps its orientation on the surface whatever the light's azimuth)."""
        if self._table["phis"].size == 1 and self.isotropic:
            return np.arctan2(wi[:, 1], wi[:, 0]) - self._table["phis"][0]
        return np.zeros(wi.shape[0])

    def _node_mirror(self, p, k):
        """Mirror point (u, v) of the table's light direction at φ node p, θ node k (per point)."""
        th, ph = self._table["thetas"][k], self._table["phis"][p]
        return -np.sin(th) * np.cos(ph), -np.sin(th) * np.sin(ph)

    def _node_light(self, p, k):
        """Light direction (3 component arrays) of the table at φ node p, θ node k (per point)."""
        th, ph = self._table["thetas"][k], self._table["phis"][p]
        return np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)

    def _f_diffraction(self, wi, wo, lam):
        return self._f_diffraction_nodes(wi, wo, [lam])[:, 0]

    def _f_diffraction_nodes(self, wi, wo, wavelengths_nm):
        """The diffracted part (n, n_λ) at the table's wavelengths *wavelengths_nm*: the geometry of the
        look-up once for all of them."""
        j = np.array([self._wavelength_index(lam) for lam in wavelengths_nm])
        thetas = self._table["thetas"]
        theta_i = np.arccos(np.clip(wi[:, 2], -1.0, 1.0))
        a, b, t = _bracket(thetas, theta_i)
        phi_i, phi_nodes = self._frame(wi)
        rot = self._table_rotation(wi)
        wo_r, wi_r = _rotate(wo, rot), _rotate(wi, rot)
        delta = wo_r[:, :2] + wi_r[:, :2]   # (u, v) − mirror point of ω_i
        rotate = self._table["phis"].size == 1 and self.isotropic
        half = not rotate and self.half_vector_read
        num = np.zeros((wi.shape[0], j.size))
        den = np.zeros(wi.shape[0])
        for p_idx, w_p in phi_nodes:
            for k, w_k in ((a, 1 - t), (b, t)):
                scale = 1.0
                if rotate:   # ω_o turned about the table's y axis by θ_i − θ_k: ω_i's mirror onto θ_k's
                    beta = theta_i - thetas[k]
                    cb, sb = np.cos(beta), np.sin(beta)
                    uu = wo_r[:, 0] * cb + wo_r[:, 2] * sb
                    vv = wo_r[:, 1]
                    inside = -wo_r[:, 0] * sb + wo_r[:, 2] * cb > 0
                elif half:   # the node's exit with (ω_i, ω_o)'s half-vector
                    uu, vv, zz, scale = half_vector_exit(wi.T, wo.T, self._node_light(p_idx, k))
                    inside = zz > 0
                else:        # shifted with the specular direction in the direction-cosine plane
                    mu, mv = self._node_mirror(p_idx, k)
                    uu, vv = mu + delta[:, 0], mv + delta[:, 1]
                    inside = uu * uu + vv * vv < 1.0
                # a node whose point lies beyond its horizon holds no data there: it drops out of the blend; only
                # the points a node weighs read its table (ω_i on a θ node gives the next node the weight 0)
                wt = w_p * w_k
                r = np.flatnonzero(inside & (wt > 0))
                num[r] += (wt * scale)[r, None] * self._lookup(np.broadcast_to(p_idx, wt.shape)[r], k[r], j, uu[r],
                                                               vv[r])
                den += wt * inside
        den = den[:, None]
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
        if self._table.get("rim") is not None:   # towards the horizon: the rim tables, in the light's frame
            wo_l = wo_r if rotate else _rotate(wo, np.arctan2(wi[:, 1], wi[:, 0]))
            out = self._with_rim(out, a, t, j, wo_l, phi_i)
        return np.where(((wi[:, 2] > 0) & (wo[:, 2] > 0))[:, None], out, 0.0)

    def _with_rim(self, val, a, t, j, wo, phi_i):
        """*val* (n, n_j), the main tables' read, blended by :func:`waveoptics.brdf.tabulated_rim.rim_weight` of θ_o
        with the rim tables of the incidence nodes around θ_i (a, b and the next two outwards) read at *wo* (n, 3)
        itself (in the light's frame: azimuths from the light's) and interpolated at the fraction t of the
        interval a-b by the monotone cubic
        of :func:`waveoptics.brdf.tabulated_rim.rim_across_incidence` (linear in θ_i it read the lobe up to 4 %
        high at θ_o 85° forward, where it rises steeply towards the exit's mirror angle). Not turned as the main tables are read: near the horizon the lobe
        changes fastest with θ_o, and a turn by θ_i − θ_k reads it up to half a node spacing higher and lower,
        whose mean lies below the lobe where it is concave (Beckmann α 0.05, exit 72-80°, incidence midway
        between nodes: turned 0.975-1.031 of the facet-frame sum, read at ω_o 0.991-1.009). An anisotropic micro
        NDF has rim tables at :func:`waveoptics.brdf.tabulated_rim.rim_light_azimuths` light azimuths, each held
        in its light's frame and read turned with the light (the forward peak stays forward; the NDF's axes turn
        by the light's offset from the node), interpolated across the light azimuth φ_i by the monotone cubic of
        log f (:func:`waveoptics.brdf.tabulated_rim.rim_across_light_azimuth`)."""
        W = rim_weight(wo[:, 2])
        sel = W > 0
        if not sel.any():
            return val
        r = rim_across_light_azimuth(self._table["rim"], self._table["thetas"], phi_i[sel], a[sel], t[sel], j,
                                     wo[sel, 0], wo[sel, 1], wo[sel, 2])
        out = val.copy()
        out[sel] = (1 - W[sel])[:, None] * val[sel] + W[sel][:, None] * r
        return out

    def _lookup_table(self):
        """The tabulated lobes with each cell beyond the rim of the disc given the mean of its neighbours inside
        it (two passes), for bilinear reads within a cell of the horizon, which would otherwise blend in zeros;
        sampling and its density keep the lobes as computed."""
        if "lookup" not in self._table:
            self._table["lookup"] = filled_beyond_rim(self._table["diffraction"], self._table["grid"].inside)
        return self._table["lookup"]

    def _lookup(self, p, k, j, u, v):
        """Bilinear values (n, n_j) at (u, v) (n,) of the lobes of φ nodes p and θ nodes k (per point), at the
        wavelength indices j (n_j,)."""
        lob = self._lookup_table()
        k0, j0, av, au, ok = (x[:, None] for x in self._table["grid"].bilinear(u, v))
        p = np.broadcast_to(p, u.shape)[:, None]
        k = np.broadcast_to(k, u.shape)[:, None]
        j = np.asarray(j)[None, :]
        val = ((1 - av) * ((1 - au) * lob[p, k, j, k0, j0] + au * lob[p, k, j, k0, j0 + 1])
               + av * ((1 - au) * lob[p, k, j, k0 + 1, j0] + au * lob[p, k, j, k0 + 1, j0 + 1]))
        return np.where(ok, val, 0.0)

    # -- sampling of the diffracted part: the nearest node's lobe as a piecewise-constant density ----------
    def _nearest(self, wi):
        thetas, phis = self._table["thetas"], self._table["phis"]
        theta_i = np.arccos(np.clip(wi[:, 2], -1.0, 1.0))
        k = np.argmin(np.abs(theta_i[:, None] - thetas[None, :]), axis=1)
        if phis.size == 1:
            return k, np.zeros(wi.shape[0], int)
        phi_i = np.arctan2(wi[:, 1], wi[:, 0])
        p = np.rint(np.mod(phi_i, 2 * np.pi) / (phis[1] - phis[0])).astype(int) % phis.size
        return k, p

    def _sample_diffraction(self, wi, u, lam):
        j = self._wavelength_index(lam)
        grid = self._table["grid"]
        k, p = self._nearest(wi)
        rot = self._table_rotation(wi)
        cell = np.zeros(wi.shape[0], int)
        fu = np.full(wi.shape[0], 0.5)
        total = np.zeros(wi.shape[0])
        pk = np.stack([p, k], axis=-1)
        for pp, kk in np.unique(pk, axis=0):          # one CDF per node: binary search, not a scan per sample
            sel = (p == pp) & (k == kk)
            cdf = self._cdf()[pp, kk, j]
            target = u[sel, 0] * cdf[-1]
            c = np.minimum(np.searchsorted(cdf, target, side="left"), cdf.size - 1)
            lo = np.where(c > 0, cdf[np.maximum(c - 1, 0)], 0.0)
            hi = cdf[c]
            cell[sel] = c
            fu[sel] = np.where(hi > lo, (target - lo) / np.where(hi > lo, hi - lo, 1.0), 0.5)
            total[sel] = cdf[-1]
        row, col = np.divmod(cell, grid.n_u)
        uu = grid.u_range[0] + (col + fu) * grid.du
        vv = grid.v_range[0] + (row + u[:, 1]) * grid.dv
        mu, mv = self._node_mirror(p, k)
        wi_r = _rotate(wi, rot)
        uv = np.stack([uu - mu - wi_r[:, 0], vv - mv - wi_r[:, 1]], axis=-1)   # shifted to ω_i's mirror
        s2 = np.sum(uv * uv, axis=-1)
        good = (total > 0) & (s2 < 1.0)
        wo_r = np.concatenate([uv, np.sqrt(np.maximum(1.0 - s2, 0.0))[:, None]], axis=-1)
        return np.where(good[:, None], _unrotate(wo_r, rot), [0.0, 0.0, -1.0])

    def _pdf_diffraction(self, wi, wo, lam):
        j = self._wavelength_index(lam)
        grid = self._table["grid"]
        k, p = self._nearest(wi)
        rot = self._table_rotation(wi)
        wi_r, wo_r = _rotate(wi, rot), _rotate(wo, rot)
        mu, mv = self._node_mirror(p, k)
        uu = wo_r[:, 0] + wi_r[:, 0] + mu
        vv = wo_r[:, 1] + wi_r[:, 1] + mv
        col = np.floor((uu - grid.u_range[0]) / grid.du).astype(int)
        row = np.floor((vv - grid.v_range[0]) / grid.dv).astype(int)
        ok = (col >= 0) & (col < grid.n_u) & (row >= 0) & (row < grid.n_v) & (wo[:, 2] > 0)
        total = self._cdf()[p, k, j, -1]
        val = self._table["diffraction"][p, k, j, np.clip(row, 0, grid.n_v - 1), np.clip(col, 0, grid.n_u - 1)]
        dens = np.where(ok & (total > 0), val / np.where(total > 0, total, 1.0), 0.0) / (grid.du * grid.dv)
        return dens * np.maximum(wo[:, 2], 0.0)

    def _diffraction_width(self, lam):
        """The tabulated lobe is resolved to a few grid cells: place the quadrature nodes no finer than that."""
        return 4.0 * self._table["grid"].du
