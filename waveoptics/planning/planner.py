"""The effect planner: decide from physics which effects a scene needs, simulate only those, say why.

For every (material, light) pair of a :class:`waveoptics.planning.scene.Scene` the planner takes, in order:

``diffuse``
    Metals absorb the refracted light: no diffuse term. Dielectrics get the substrate's diffuse term (with the
    diffuse-specular trade-off of :mod:`waveoptics.brdf`) unless their diffuse albedo is 0.
``diffraction``
    The nano surface reflects the fraction exp(−g), g = (4π σ cos θ_i / λ)², coherently and scatters the rest,
    TIS = F (1 − exp(−g)) (Davies 1954; Bennett & Porteus 1961; docs/physics.md §2). Whether that scattered light
    changes what the scene shows is decided on the colour it produces: both models (two-scale and plain
    microfacet) are evaluated on a coarse grid (:data:`ESTIMATE_RESOLUTION` cells, refined by doubling up to
    :data:`ESTIMATE_RESOLUTION_MAX` where the energy guard would act on it, :data:`ESTIMATE_STEP_NM`
    wavelength step) through the PSD route, at the scene's light directions and directions of interest, and the
    largest CIEDE2000 difference of the rendered radiance π f cos θ_i is compared with the target. Diffraction
    runs when that estimate exceeds :data:`ESTIMATE_SHARE` of the target (the rest of the budget covers the
    estimate's own error), or when g exceeds :data:`PSD_G_MAX` (no coherent reflection is left at all).
    Height fields without known statistics are estimated through a Gaussian-statistics proxy with their rms
    height and correlation length.
``roughness correlation``
    A thin-film stack's interface correlation (the scene key ``roughness_correlation``) enters only Rayleigh-Rice's
    first-order scatter from every interface; when the plan runs another model, or no diffraction, a correlation the
    scene sets is skipped with one line saying so.
``wavelengths``
    Line sources (lasers): their lines only. No diffraction and a Fresnel factor that is the same at every
    wavelength (constant index, grey F0): the BRDF does not depend on λ, so it is evaluated once and used for the
    whole spectrum. Otherwise the coarsest uniform grid that keeps smooth reflectance spectra within the target
    (:func:`waveoptics.colour.simulation_wavelengths`), refined for a periodic nano surface of period Λ so that
    neighbouring wavelengths of diffraction order m land no further apart than one grid cell, Δλ ≤ Λ du / m
    (grating equation, docs/physics.md §5).
``solver``
    Statistics with g ≤ :data:`PSD_G_MAX`: the PSD series (:mod:`waveoptics.scatter.series`; exact ensemble average for
    Gaussian heights, cheapest). Height fields (and statistics beyond the PSD range, for which a height field is
    generated): the cheaper of ``fft`` and ``direct`` by the calibrated cost model (both are exact Kirchhoff to
    their tolerance; ``direct`` only computes the directions it is asked for).
``resolution``
    The direction grid must resolve the narrowest simulated lobe: bilinear interpolation of a lobe of standard
    deviation s (direction cosines) at spacing du errs by at most du² / (8 s²) of its peak, and a relative
    luminance error ε moves CIEDE2000 by about :data:`DE_PER_RELATIVE_Y` · ε at mid grey, so
    du ≤ s √(8 ΔE / DE_PER_RELATIVE_Y). Height-field solvers also need du ≤ λ_min / L to sample the specular
    spike of a patch of length L. The result is clipped to :data:`PLAN_RESOLUTION_RANGE`.
``directions``
    The whole hemisphere when the outputs show it (images, spectral BRDF, sphere camera); otherwise only
    patches around the view directions (:data:`PATCH_SIGMAS` lobe widths wide, so that the micro-facet
    convolution still sees every contribution) when that is fewer directions than the hemisphere.
``precision``
    Only the ``direct`` OpenCL solver has a float32 path. Its round-off leaves a relative noise floor
    ε₃₂² (n / 256 + (4π h_max/λ)² / n) in |U|² against the coherent peak (two-level summation over n samples,
    float32 rounding of the height phase), while the weakest light the target asks to see — a haze of luminance
    ΔE / 903.3 (CIE L* slope near black) — sits at (ΔE / 903.3 / π) (λ/L)² of the peak. float64 is chosen
    when the floor exceeds :data:`FLOOR_MARGIN` of that level (large patches, tall heights).

Costs come from a calibration timed once per machine and cached (:func:`calibration`; ``waveoptics plan
--recalibrate`` times it again): seconds per grid
cell, per cell and wavelength, per PSD series term, per chirp-z work unit and per direct-sum term.

References
----------
.. [1] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 209 (1954);
   H. E. Bennett, J. O. Porteus, JOSA 51, 123 (1961) (coherent fraction, TIS).
.. [2] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 66, 2017 (which scale matters when).
.. [3] CIE 015:2018 Colorimetry, §8.2.1 (L* = 903.3 Y below Y = 0.008856; L* = 116 Y^{1/3} − 16 above).
.. [4] M. R. Luo, G. Cui, B. Rigg, "The development of the CIE 2000 colour-difference formula: CIEDE2000",
   Color Res. Appl. 26(5), 2001.
.. [5] C. de Boor, *A Practical Guide to Splines*, 1978, ch. 2 (linear interpolation error h² max|f''| / 8).
.. [6] J. E. Harvey, R. N. Pfisterer, Opt. Eng. 59(1) 017103, 2020 (grating equation, orders).
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from .. import colour
from ..materials import get_material
from ..planning.scene import MaterialSpec, Scene, request_of
from ..request import request_default
from ..vocabulary import NANO_SOLVERS
from .costmodel import CostModel, calibration
from .effects import (decide_diffraction, decide_diffraction_model, decide_diffuse, decide_multiple_scattering,
                      decide_nano_route, decide_roughness_correlation, decide_wavelengths, Entry,
                      refine_wavelengths_for_grating)
from .numerics import decide_directions, decide_precision, decide_resolution
from .plan import EntryPlan, Plan

__all__ = ['plan_scene']


#: the decisions, in the order they are taken (each reads the outcomes of those before it)
DECISIONS = (decide_diffuse, decide_diffraction, decide_diffraction_model, decide_roughness_correlation,
             decide_wavelengths, decide_nano_route, decide_resolution, refine_wavelengths_for_grating,
             decide_directions, decide_precision, decide_multiple_scattering)


def _plan_entry(scene: Scene, spec: MaterialSpec, light, force: dict, cm: CostModel, device,
                max_resolution: int | None) -> EntryPlan:
    """Plan one (material, light) pair: take every decision of :data:`DECISIONS` in turn."""
    # the interface correlation is the planner's to apply (decide_roughness_correlation): the model comes later
    req = request_of(scene, spec.name, light.name, roughness_correlation=request_default("roughness_correlation"))
    e = Entry(scene, spec, light, force, cm, device, max_resolution)
    e.mat = get_material(req.material)
    e.spd = colour.illuminant(req.illuminant)
    e.micro = spec.micro()
    e.cos_i = [math.cos(math.radians(t)) for t, _ in light.directions_deg]
    e.cos_max = 1.0 if e.sphere else max(e.cos_i)
    e.w_colour = colour.simulation_wavelengths(e.spd, e.delta_e)
    e.lam_min = float(np.min(e.w_colour))
    for decide in DECISIONS:
        decide(e)
    decided = dataclasses.replace(   # the request the runner evaluates: the scene's, with the decisions applied
        req, solver=e.solver if e.solver in NANO_SOLVERS else "auto", kd=float(e.kd), precision=e.precision,
        diffraction=e.diffraction, roughness_correlation=e.roughness_correlation, resolution=int(e.resolution),
        wavelengths_nm=tuple(float(x) for x in (e.w_sim if e.w_sim.size else e.w_colour)))
    effects = {"specular": True, "diffraction": bool(e.diffracts), "diffuse": bool(e.diffuse),
               "multiple_scattering": bool(e.spec.multiple_scattering),
               "spectral": not e.lam_independent, "sphere": e.sphere}
    return EntryPlan(spec=spec, light_name=light.name, spd=e.spd, material=e.mat,
                     light_directions_deg=light.directions_deg, micro=e.micro, nano=e.nano, effects=effects,
                     solver=e.solver, resolution=e.resolution, directions=e.directions, view_directions_deg=e.views,
                     wavelengths_nm=e.w_sim, colour_wavelengths_nm=e.w_colour, precision=e.precision, kd=e.kd,
                     sphere=e.sphere, estimated_time_s=float(e.time_s), patches=e.patches, decisions=e.decisions,
                     metrics=e.metrics, forced=dict(force), diffraction=e.diffraction, request=decided)


def plan_scene(scene: Scene, *, force: dict | None = None, device=None, max_resolution: int | None = None,
               recalibrate: bool = False) -> Plan:
    """Plan a scene: decide, for every material under every light, the effects, solver, grid and wavelengths.

    Parameters
    ----------
    force : dict, optional
        Overrides from :func:`parse_force` (e.g. ``{"diffraction": True}``).
    device : str, optional
        OpenCL device for the direct solver's calibration.
    max_resolution : int, optional
        Cap on the direction grid (the scene's ``output.resolution`` is used as given).
    recalibrate : bool
        Time the cost model again instead of using this machine's cached calibration (:func:`calibration`).

    Returns
    -------
    Plan
    """
    t0 = time.perf_counter()
    force = dict(force or {})
    cm = calibration(recalibrate=recalibrate)
    entries = [_plan_entry(scene, m, light, force, cm, device, max_resolution)
               for m in scene.materials for light in scene.lights]
    return Plan(scene=scene, entries=entries, cost_model=cm, planning_time_s=time.perf_counter() - t0, force=force)
