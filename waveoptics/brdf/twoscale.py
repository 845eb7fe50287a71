"""Two-scale BRDF: microfacets (geometric optics) carrying nano-roughness (diffraction).

Structure (Holzschuch & Pacanowski 2017; docs/physics.md §7). Micro-geometry, much larger than λ, is described by a
microfacet NDF D with roughness α; each microfacet carries nano-roughness of rms height σ_nano about λ or smaller.
Per microfacet the light splits into

* a coherent part, the fraction A(λ, θ_d) of the Fresnel-reflected light that keeps the microfacet specular
  lobe, f_c = A · F G D / (4 cosθ_i cosθ_o): on a conductor what the facet's nano lobe leaves, 1 − E(θ_d) (E the
  share of the reflected light that lobe scatters; Davies' exp(−(4π σ_rel cos θ_d / λ)²) while it is paraxial,
  σ_rel the roughness inside the propagating band); on a dielectric that Debye-Waller factor itself, the scattered
  light keeping its own albedo (:meth:`Nano.coherent_fraction`, docs/physics.md §9);
* a diffracted part, the nano-roughness scattering lobe f_n (PSD series or a Kirchhoff solver on a nano height
  field) carried by each microfacet in the facet's own frame: Walter et al.'s integral of a facet BRDF,
  f_diff = ∫ |ω_i·m||ω_o·m| / (|ω_i·n||ω_o·n|) f_n(ω_i^m, ω_o^m) G D(m) dm (docs/physics.md §7);
* for dielectrics, a diffuse term with the diffuse-specular trade-off (metals have none).

Evaluation on the direction-cosine plane
----------------------------------------
Lobes live on a :class:`waveoptics.scatter.DirectionGrid` over (u, v) = (sinθ cosφ, sinθ sinφ), where
cosθ_o dω_o = du dv. For PSD statistics the diffracted part is the facet integral itself
(:func:`facet_frame_diffraction`): per cell, a balance-heuristic quadrature over facet normals drawn from the micro
NDF and about the cell's half-vector, each facet's nano lobe read from tables over local incidence
(:data:`waveoptics.brdf.FACET_THETAS_DEG`) in that facet's frame; so it is for a statistically isotropic nano height
field, whose tables are its own lobe by the FFT solver at azimuth 0, and asked by name (``facet="frame"``) for an
anisotropic one, whose tables run over the azimuth of incidence too (:func:`waveoptics.brdf.anisotropic_field_stack`).
By default for an anisotropic height field, and for a PSD
lobe narrower than the cells, it is the paraxial form (:func:`facet_route`; ``facet="paraxial"`` by name): the nano lobe
at the macro incidence is convolved with the *micro kernel* K, the F = 1 microfacet lobe f_mf(ω_i, ·) du dv re-centred on the
mirror direction, i.e. shifted to each facet's mirror direction instead of being turned with the facet (accurate
where each facet's lobe is narrow; docs/physics.md §7 gives its error on wide lobes). Both limits hold on the grid:
σ_nano → 0 gives A = 1 and f_n = 0 (the microfacet model), and α → 0 gives the pure nano lobe. Light a facet's lobe
sends below the macro horizon, or that is masked on its way out, is reported
(``info["diffraction_beyond_horizon"]``).

A specular lobe narrower than the grid (α ≲ du) cannot be sampled: its energy F·A·ρ_mf is deposited in the
mirror cell as a spike of height E/(du dv), which keeps albedo and colour exact on the grid.

Modules
-------
:mod:`~waveoptics.brdf.roughness_scales` (:class:`Micro`, :class:`Nano`, the coherent fraction),
:mod:`~waveoptics.brdf.twoscale_coherent` (coherent part), :mod:`~waveoptics.brdf.nano_grid` (the nano lobe on the
grid), :mod:`~waveoptics.brdf.twoscale_paraxial` and :mod:`~waveoptics.brdf.twoscale_frame` (the two facet routes of
the diffracted part), :mod:`~waveoptics.brdf.field_lobe` (a height field's lobe), :mod:`~waveoptics.brdf.scale_split`
(:func:`waveoptics.brdf.split_scales`); this module composes them (:func:`evaluate`).

References
----------
.. [1] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 66, 2017.
.. [2] B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet models for refraction through rough surfaces",
   EGSR 2007 (microfacet BRDF of a general facet BRDF, eq. 14).
.. [3] H. Davies, Proc. IEE 101, 209 (1954) (coherent fraction).
.. [4] E. Veach, PhD thesis, Stanford 1997, §9.2 (balance heuristic).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import scatter
from ..errors import WaveopticsError
from ..materials import Material, fresnel_function, get_material
from ..scatter.grid import DirectionGrid, integrate
from ..units import check_wavelengths
from .diffuse import DIFFUSES, diffuse_tradeoff
from .quadrature import directional_albedo
from .roughness_scales import Micro, Nano
from .scale_split import split_scales  # noqa: F401 (re-exported: twoscale.split_scales)
from .twoscale_coherent import coherent_lobe
from .twoscale_frame import facet_frame_diffraction, facet_route, paraxial_reason
from .twoscale_grid import sharp_micro_lobe
from .twoscale_paraxial import paraxial_diffraction

#: Micro, Nano and split_scales are re-exported: ``twoscale.Micro`` etc. are the documented spellings
__all__ = ['Lobes', 'CAP_TOLERANCE', 'diffracted_lobe', 'diffuse_lobe', 'multiple_scattering_lobe', 'evaluate']


@dataclass
class Lobes:
    """A two-scale evaluation for one incident direction on a direction grid.

    Arrays are (n_λ, n_v, n_u) in 1/sr: ``coherent`` (micro specular × A), ``diffraction`` (the nano lobe carried
    by the micro facets), ``diffuse`` (dielectrics), ``multiple`` (the multiple-scattering compensation lobe, or
    None when it is off), ``total``; ``microfacet`` is the plain microfacet model (same micro roughness,
    material, diffuse term and compensation lobe; no nano-roughness) for comparison.
    """

    grid: DirectionGrid
    wi: np.ndarray
    wavelengths_nm: np.ndarray
    coherent: np.ndarray
    diffraction: np.ndarray
    diffuse: np.ndarray
    microfacet: np.ndarray
    info: dict = field(default_factory=dict)
    diffuse_albedo: np.ndarray | None = None
    multiple: np.ndarray | None = None
    multiple_albedo: np.ndarray | None = None

    @property
    def total(self) -> np.ndarray:
        t = self.coherent + self.diffraction + self.diffuse
        return t if self.multiple is None else t + self.multiple

    def albedo(self, part: str = "total") -> np.ndarray:
        """Directional albedo per wavelength of a part (``total``, ``coherent``, ``diffraction``, ``multiple``,
        ...).

        The diffuse term's and the compensation lobe's shares are their exact albedos (``diffuse_albedo``, a
        quadrature of the closed form; ``multiple_albedo`` = (1 − E(μ_i)) F_ms by construction), not the grid
        sums: cells straddling the rim of the projected disc are counted whole by the grid sum, which over-counts
        a lobe that reaches the horizon (Lambert, kd = 1: 1.005 at 8² cells, 0.984 at 16², 0.961 at 128²,
        against 0.9615 exactly). Sharp lobes are the grid's own (they are normalized on it)."""
        if part == "multiple" and self.multiple is None:
            return np.zeros(self.wavelengths_nm.size)
        a = integrate(getattr(self, part), self.grid)
        if self.diffuse_albedo is not None and part in ("total", "microfacet", "diffuse"):
            a = a - integrate(self.diffuse, self.grid) + self.diffuse_albedo
        if self.multiple is not None and self.multiple_albedo is not None and part in ("total", "microfacet",
                                                                                      "multiple"):
            a = a - integrate(self.multiple, self.grid) + self.multiple_albedo
        return a

    def coherent_specular_fraction(self) -> np.ndarray:
        """Share of the specularly reflected energy that stays coherent: E_c / (E_c + E_diffraction)."""
        c, d = self.albedo("coherent"), self.albedo("diffraction")
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(c + d > 0, c / (c + d), 1.0)


#: the diffracted lobes may exceed their budget by this share before :func:`cap_to_coherent_loss` acts: the two
#: are integrated by different quadratures (the paraxial lobe on the evaluation grid against E¹ on a polar grid:
#: < 2e-3; the facet-frame lobe's per-cell quadrature of 64 + 16 normals against the budget's average over the NDF
#: nodes: up to 2 %, measured on glass at α = 0.1, tests/test_dielectric_energy.py)
CAP_TOLERANCE = 3e-2


#: how the energy guard's lines begin (:func:`cap_to_coherent_loss`; a table of lobes says it once for all of
#: them, :class:`waveoptics.brdf.TabulatedTwoScaleBRDF`)
ENERGY_GUARD_PREFIX = "two-scale energy guard"


def energy_guard_cause(grid: DirectionGrid) -> str:
    """The end of the energy guard's line: what it found on *grid* and the resolution to try."""
    return (f"the nano lobe held more than its energy budget on {grid.n_u}x{grid.n_v} direction cells (where cells "
            f"too coarse for the lobe or the facets' incidences cause it, try resolution "
            f"{2 * max(grid.n_u, grid.n_v)})")


def cap_to_coherent_loss(diffraction, lost, grid: DirectionGrid, budget=None, *, wi=None, wavelengths_nm=None):
    """Scale the diffracted lobes down where they hold more light than the coherent lobe gave up.

    guard: on a conductor the coherent fraction is the complement of the nano lobe's own albedo (energy
    conservation, :meth:`waveoptics.brdf.Nano.coherent_fraction`), so the two halves agree to quadrature accuracy
    and this step does not act (it lets through up to :data:`CAP_TOLERANCE`; measured at θ_i ≤ 70° on Gaussian,
    exponential and ABC PSDs with C from 2.2 to 4, σ up to λ/10, micro α up to 0.3: the lobe exceeds its budget by
    ≤ 2e-3; with no micro roughness up to 89.5°, tests/test_grazing.py; a rough film stack under Rayleigh-Rice,
    Al|Al2O3:300nm, GGX α = 0.05, θ_i 80–89°, 32² and 64² cells: ≤ 1.8 %, tests/test_stack_grazing_energy.py).
    On a dielectric the budget is all the light the facets receive and do not reflect coherently (the scattered
    light also draws on the transmitted beam), which the lobe does not approach (tests/test_dielectric_energy.py:
    glass, s, p and unpolarized, 30–75° and Brewster's angle). Between 70° and 80° of local incidence or exit the
    tangent-plane lobe hands over to first-order perturbation theory's lobe (:mod:`waveoptics.scatter.tangent_blend`),
    so its obliquity does not make it grow without bound.
    A height field's lobe is averaged over cells coarser than its speckle and kept inside the field's sampled band
    (:func:`waveoptics.brdf.field_cell_averages`, :func:`waveoptics.brdf.nyquist_band`): point-sampled, the
    brushed-aluminium scene's scratches on 16² cells held 1.95x their budget at 380 nm and this step removed 49 %
    (tests/test_field_cells.py). Where it does act (a grid too coarse for the lobe or for the facets' incidences;
    Au, ABC σ 8 nm, B 2 µm, Beckmann α 0.1 on 32² cells at θ_i = 60° was one, 6.2 % removed at 450 nm, until a
    conductor's budget was what its facets scatter alone: the other bound, the light they reflect less the coherent
    lobe's grid sum, acted through that sum's cell-centre error, :func:`diffracted_lobe`) it warns in one
    line with the share it removed, the wavelength and incidence (given *wi* and *wavelengths_nm*) and the
    resolution to try, and reports the factor (``diffraction_energy_scale``). The 500 nm sinusoid (20 nm, Al,
    Beckmann α 0.05) at 550 nm is one: 3.3 % at 78° on 32² cells, none on 40², 48², 64², 96², 128²; its 17.6 % on
    64² at 10° in the grooves' plane is the paraxial route carrying a lobe the macro incidence hardly has
    (:func:`waveoptics.brdf.carried_share_warning` says so in its own line). A film stack's lobe at
    the shortest wavelengths is another: Al|Al2O3:120nm, ABC σ 15 nm B 2 µm C 2.6, GGX α 0.05, Rayleigh-Rice,
    θ_i = 60°, 380 nm held 1.066x its budget on 32² cells, 1.034x on 40², 0.999x on 48², 1.005x on 64², 0.992x on
    128² (the budget 0.0600 on every grid, within 0.6 % of the microfacet lobe minus the coherent lobe; 400 to
    780 nm within 1 % on 32²; the 32² and 64² cases in tests/test_example_scene_guard.py). Not the grid: aluminium,
    Beckmann α 0.15 / α_y 0.4, Gaussian σ 15 nm ℓ 1.5 µm, θ_i = 88° held 1.078x its budget at 830 nm, φ_i = 90°,
    and 1.037x at 360 nm, φ_i = 0°, on 64² to 192² cells alike: the budget's 64 normals read it up to 7.7 % low
    there (now 4096, :data:`waveoptics.brdf.FACET_BUDGET_NODES`; none acts, tests/test_facet_budget.py). Au under a
    measured slope table (α ≈ 0.066, Gaussian σ 8 nm ℓ 1 µm, 550 nm) held 1.033x at 0°, 1.045x at 30°, 1.15x at
    60° on 32² to 128², the guard removing up to 68 % at 70°: the table's numbers, not the grid (issue 28: its
    albedo quadrature across the bin edges, its 64-node budget, cell-centre reads of its histogram;
    :func:`waveoptics.brdf.table_nodes`, :func:`waveoptics.brdf.facet.budget_nodes`,
    :mod:`waveoptics.brdf.twoscale_coherent`); now the lobe holds 1.000-1.007x its budget at θ_i 0-70° on 32² to
    128² and none acts to 88° on 32² and 64² (tests/test_slope_table_energy.py).

    Parameters
    ----------
    diffraction, lost : ndarray (n_λ, n_v, n_u), 1/sr
        The diffracted lobes and the microfacet lobe minus the coherent lobe.
    budget : ndarray (n_λ,), optional
        The light the lobes may hold instead of the integral of *lost*: the facet route's light scattered by the
        facets before masking on the way out (:func:`waveoptics.brdf.facet_frame_diffraction`). A facet whose mirror direction is
        masked or below the horizon still sends part of its diffracted lobe out, so in Walter's integral the
        diffracted part can exceed the coherent part's loss; it cannot exceed what the facets scatter.
    wi : array_like (3,), optional
        The incident direction, named in the warning.
    wavelengths_nm : array_like (n_λ,), nm, optional
        Named in the warning (else the wavelength's index).

    Returns
    -------
    diffraction : ndarray (n_λ, n_v, n_u)
    scale : ndarray (n_λ,)
        The factor applied per wavelength (1 where the lobe was within its share).
    """
    got = integrate(diffraction, grid)
    budget = np.maximum(integrate(lost, grid) if budget is None else np.asarray(budget, dtype=float), 0.0)
    scale = np.where(got > budget * (1.0 + CAP_TOLERANCE), budget / np.where(got > 0, got, 1.0), 1.0)
    if np.any(scale < 1.0):
        i = int(np.argmin(scale))
        where = f"wavelength index {i}" if wavelengths_nm is None else f"{float(wavelengths_nm[i]):.4g} nm"
        if wi is not None:
            where += f", theta_i = {np.degrees(np.arccos(np.clip(wi[2], -1.0, 1.0))):.3g} deg"
        scatter.solvers.warn_or_collect(f"{ENERGY_GUARD_PREFIX} removed {100 * (1 - scale[i]):.3g}% of the "
                                        f"diffracted light ({got[i] - budget[i]:.3g} of the incident light) at "
                                        f"{where}: {energy_guard_cause(grid)}")
    return diffraction * scale[:, None, None], scale


def diffracted_lobe(route, wi, w, mat, micro, nano, grid, F, dm, polarization, reference_grid, lost, coherent, *,
                    solver, device, precision):
    """:func:`evaluate`'s diffracted lobes by *route* (``frame``, ``paraxial`` or ``none``): (lobes (n_λ, n_v, n_u)
    in 1/sr, the solver used, the energy guard's factor per wavelength, the light masked or sent beyond the
    horizon (n_λ,)). *lost* is the budget of the paraxial route (microfacet minus coherent lobe), *coherent* the
    coherent part (see :func:`evaluate`)."""
    inside = grid.inside
    if route == "none":
        z = np.zeros(w.size)
        return np.zeros((w.size, grid.n_v, grid.n_u)), "none", np.ones(w.size), z
    if route == "frame":   # Walter's integral: each facet's nano lobe in its own frame
        diffraction, scattered, reflected = facet_frame_diffraction(
            wi, w, mat, micro, nano, grid, F, diffraction=dm, polarization=polarization, table_grid=reference_grid,
            device=device, precision=precision)
        diffraction = np.where(inside, diffraction, 0.0)
        # the light the facets scatter that is masked on its way out or leaves below the macro horizon
        beyond = np.maximum(scattered - integrate(diffraction, grid), 0.0)
        # guard: not more than the facets scatter (on a dielectric neither more than they receive and do not
        # reflect coherently, the scattered light also drawing on the transmitted beam). A conductor's facets
        # reflect F and scatter F (1 − A) of it, so the reflected light less the coherent part's (masked on its way
        # out) is never below what they scatter: that bound, taken with the coherent lobe's grid sum, only ever
        # acted through the grid's error in the coherent lobe (Au, Beckmann α 0.066, Gaussian σ 8 nm ℓ 1 µm,
        # 550 nm, 70° on 32² cells: its cell centres held 0.80615 against 0.80469 of the cells' averages, and 41 %
        # of the diffracted light was removed for it); *reflected* stays for the record (tests/test_facet_budget.py)
        budget = scattered if scatter.is_conductor(mat) else np.minimum(scattered, integrate(lost, grid))
    else:
        diffraction, beyond = paraxial_diffraction(wi, w, mat, micro, nano, grid, F, dm, polarization, solver=solver,
                                                   device=device, precision=precision)
        budget = None
    if reference_grid is None:
        diffraction, energy_scale = cap_to_coherent_loss(diffraction, lost, grid, budget, wi=wi, wavelengths_nm=w)
    else:
        energy_scale = np.ones(w.size)
    used = solver if solver != "auto" else ("psd" if nano.model is not None else "fft")
    if route == "frame" and nano.surface is not None:   # a height field's facet tables come from the fft solver
        used = "fft"
    return diffraction, used, energy_scale, beyond


def diffuse_lobe(wi, wo, wavelengths_nm, material: Material, kd=0.5, diffuse: str = "lambert", inside=None):
    """(lobe (n_λ, ...) in 1/sr, albedo (n_λ,)) of a dielectric's diffuse substrate at the directions *wo*
    (..., 3), with the diffuse-specular trade-off (:func:`waveoptics.brdf.diffuse_tradeoff`); zero for metals, for
    kd = 0 and for *diffuse* ``none``. The albedo is the closed form's quadrature
    (:func:`waveoptics.brdf.directional_albedo`), not the grid sum. *inside*: mask of *wo* that exist (others 0).

    References
    ----------
    .. [1] C. Kelemen, L. Szirmay-Kalos, "A microfacet based coupled specular-matte BRDF model with importance
       sampling", Eurographics 2001 (the diffuse-specular trade-off).
    """
    w = np.asarray(wavelengths_nm, dtype=float)
    shape = (w.size,) + np.shape(wo)[:-1]
    diff_albedo = np.zeros(w.size)
    if material.is_metal or np.all(np.asarray(kd) == 0) or diffuse == "none":
        return np.zeros(shape), diff_albedo
    kd_arr = np.broadcast_to(np.asarray(kd, dtype=float), (w.size,))
    diff = np.empty(shape)
    inside = np.ones(shape[1:], bool) if inside is None else inside
    for i, lam in enumerate(w):
        def f_d(a, b, i=i, lam=lam):
            return (DIFFUSES[diffuse][0](a, b, kd_arr[i], 0.0)
                    * diffuse_tradeoff(a, b, lambda c: material.F(c, lam)))
        diff[i] = np.where(inside, f_d(wi[None, None, :], wo), 0.0)
        diff_albedo[i] = float(directional_albedo(f_d, wi, alpha=1.0))
    return diff, diff_albedo


def evaluate(wi, wavelengths_nm, material, micro: Micro, nano: Nano | None, grid: DirectionGrid, *,
             solver: str = "auto", kd=0.5, diffuse: str = "lambert", device=None, precision="float32",
             reference_grid: DirectionGrid | None = None, diffraction: str = "kirchhoff",
             polarization: str = "unpolarized", multiple_scattering: bool = False, facet: str = "auto") -> Lobes:
    """Two-scale BRDF for one incident direction on *grid* at each wavelength, plus the plain microfacet BRDF.

    Parameters
    ----------
    wi : array_like (3,)
        Unit vector towards the light (z = macro normal, wi_z > 0).
    wavelengths_nm : array_like
        Wavelengths in nm.
    material : str or Material
        Surface material (metals get no diffuse term).
    micro : Micro
        Micro roughness (α = 0 allowed: a mirror-like micro surface).
    nano : Nano or None
        Nano roughness; None (or σ = 0) gives the microfacet model exactly.
    grid : DirectionGrid
        Output directions.
    kd : float or array (n_λ,)
        Diffuse albedo of a dielectric's substrate (ignored for metals).
    reference_grid : DirectionGrid, optional
        When *grid* is a patch of a larger grid (same cells, e.g. around a view direction), that grid: the micro
        lobe is normalized on it, so the patch holds the same values as the larger grid at its cells. The
        coherent-loss cap needs the whole lobe and is not applied on a patch (it only acts near grazing incidence).
    diffraction : str
        Diffraction model of the nano lobe and of the coherent fraction, a name in
        :data:`waveoptics.scatter.DIFFRACTION_MODELS` (default ``kirchhoff``).
    polarization : {'unpolarized', 's', 'p'}
        Of the incident light relative to the macro plane of incidence: every facet (micro and nano) reflects its
        own s/p split (:func:`waveoptics.materials.fresnel.F_facet_polarized`), and each micro facet's scattered
        light and coherent fraction are the same mix of its own s and p ones
        (:mod:`waveoptics.brdf.facet_polarization`); the diffuse substrate is unpolarized.
    multiple_scattering : bool
        Add Kulla & Conty's (2017) compensation lobe of the micro NDF (:mod:`waveoptics.brdf.multiscatter`) to
        both models, as :class:`waveoptics.brdf.TwoScaleBRDF` does: nano-roughness only redistributes singly
        scattered light in direction, so the light lost to bounces between micro facets is the microfacet
        model's. Its Fresnel average F_ms is of the unpolarized F (also for s or p light).
    facet : {'auto', 'frame', 'paraxial'}
        How the facets carry the nano lobe (:func:`facet_route`): ``frame`` evaluates each facet's lobe in its own
        frame (:func:`facet_frame_diffraction`), ``paraxial`` shifts the macro-incidence lobe to each facet's
        mirror direction (an FFT convolution, fast; docs/two-scale.md gives its error); ``auto`` (default) takes
        ``frame`` for PSD statistics and isotropic height fields whose lobe the grid resolves. The route taken is
        ``info["facet_integration"]``, and why it is paraxial ``info["facet_integration_reason"]`` (None for the
        frame route). A height field's frame route costs 21 field lobes per wavelength once (its tables, on a grid
        fine enough for the patch's speckle) and a quadrature of 64 + 128 normals per cell per incidence
        (:data:`waveoptics.brdf.FACET_NODES_FIELD`): about 1.3 s per incidence on 96² cells and 3 wavelengths,
        where the paraxial convolution takes 0.1 s. An anisotropic height field takes the frame route by name only:
        1 + 13 × 6 field lobes per wavelength (:data:`waveoptics.brdf.ANISOTROPIC_THETAS_DEG`) and 256 + 512
        normals per cell (:data:`waveoptics.brdf.FACET_NODES_ANISOTROPIC_FIELD`), ~5x the isotropic field's time.

    Returns
    -------
    Lobes
    """
    dm = scatter.get_model(diffraction, perturbative=True)
    mat: Material = get_material(material)
    w = check_wavelengths(wavelengths_nm)
    wi = np.asarray(wi, dtype=float)
    wi = wi / np.linalg.norm(wi)
    if not wi[2] > 0:
        raise WaveopticsError("the incident direction must be above the surface (θ_i < 90°)")
    wo = grid.directions()
    inside = grid.inside

    if polarization == "unpolarized":
        def F(cos_d, lam):
            return mat.F(cos_d, lam)
    else:   # each facet reflects its own s/p split of the macro polarization (needs both directions)
        F = fresnel_function(mat, polarization)
    sigma_nano = 0.0 if nano is None else nano.sigma
    # the micro specular lobe with F (plain microfacet), with F = 1, and its coherent part A f_mf
    mf, mf_one, coherent = coherent_lobe(wi, w, F, micro, nano, grid, dm, mat, polarization, reference_grid)
    # the nano lobe carried by the facets: a conductor's lobe holds the coherent lobe's loss; a dielectric's at
    # most all the light the facets receive and do not reflect coherently (it also draws on the transmitted beam)
    route = facet_route(micro, nano, grid, w, facet) if sigma_nano > 0 else "none"
    lost = (mf if scatter.is_conductor(mat) else mf_one) - coherent
    diffraction, used, energy_scale, beyond = diffracted_lobe(
        route, wi, w, mat, micro, nano, grid, F, dm, polarization, reference_grid, lost, coherent,
        solver=solver, device=device, precision=precision)
    diff, diff_albedo = diffuse_lobe(wi, wo, w, mat, kd, diffuse, inside)
    multiple = multiple_albedo = None
    mf_total = mf + diff
    if multiple_scattering:   # between micro facets (optional, both models)
        multiple, multiple_albedo = multiple_scattering_lobe(wi, wo, w, mat, micro)
        multiple = np.where(inside, multiple, 0.0)
        mf_total = mf_total + multiple
    return Lobes(grid=grid, wi=wi, wavelengths_nm=w, coherent=coherent, diffraction=diffraction, diffuse=diff,
                 diffuse_albedo=diff_albedo if reference_grid is None else None,
                 multiple=multiple, multiple_albedo=multiple_albedo if reference_grid is None else None,
                 microfacet=mf_total,
                 info={"solver": used, "sigma_nano_m": sigma_nano, "micro": micro.__dict__,
                       "material": mat.name, "sharp_micro_lobe": sharp_micro_lobe(micro, grid),
                       "diffraction_energy_scale": energy_scale.tolist(),
                       "diffraction_beyond_horizon": (beyond if reference_grid is None
                                                      else np.full(w.size, np.nan)).tolist(),
                       "diffraction_model": dm.name, "facet_integration": route,
                       "facet_integration_reason": _route_reason(route, facet, micro, nano, grid, w),
                       "polarization": polarization, "multiple_scattering": bool(multiple_scattering)})


def _route_reason(route, facet, micro, nano, grid, w) -> str | None:
    """Why :func:`evaluate` carried the nano lobe paraxially (``info["facet_integration_reason"]``), None otherwise."""
    if route != "paraxial":
        return None
    if facet == "paraxial":
        return "asked by name (facet 'paraxial')"
    return paraxial_reason(micro, nano, grid, w)


def multiple_scattering_lobe(wi, wo, wavelengths_nm, material, micro: Micro):
    """(lobe (n_λ, ...) in 1/sr, albedo (n_λ,)) of Kulla & Conty's compensation for the micro NDF at the
    directions *wo* (..., 3): f_ms(μ_i, μ_o) F_ms(λ) and its albedo (1 − E(μ_i)) F_ms(λ), from the same tables
    as :class:`waveoptics.brdf.MicrofacetBRDF` (one code path; :mod:`waveoptics.brdf.multiscatter`).

    References
    ----------
    .. [1] C. Kulla, A. Conty, "Revisiting Physically Based Shading at Imageworks", SIGGRAPH 2017 course.
    """
    from .protocol import MicrofacetBRDF

    b = MicrofacetBRDF(material, micro, multiple_scattering=True)
    wo = np.asarray(wo, dtype=float)
    flat = wo.reshape(-1, 3)
    wi_b = np.broadcast_to(np.asarray(wi, dtype=float), flat.shape)
    lobe = np.stack([b._f_ms(wi_b, flat, lam).reshape(wo.shape[:-1]) for lam in wavelengths_nm])
    albedo = np.array([(1.0 - float(b._ms_table()(wi[2]))) * b._F_ms(lam) for lam in wavelengths_nm])
    return lobe, albedo
