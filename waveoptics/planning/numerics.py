"""The planner's numerical decisions for one (material, light) pair, taken after the physical ones: the direction
grid that resolves the narrowest lobe, the direction set and height-field solver the cost model finds cheapest, and
the floating-point precision of the direct sum. The rules are described in :mod:`waveoptics.planning.planner`.

References
----------
.. [1] C. de Boor, *A Practical Guide to Splines*, 1978, ch. 2 (linear interpolation error h² max|f''| / 8).
.. [2] CIE 015:2018 Colorimetry, §8.2.1 (L* = 903.3 Y below Y = 0.008856).
"""
from __future__ import annotations

import math

import numpy as np

from .. import scatter
from ..brdf.field_lobe import field_scattered_albedo
from ..brdf.twoscale_paraxial import field_albedo_evaluations
from ..errors import FieldError
from ..runtime import get_runtime
from ..scatter.grid import DirectionGrid
from ..simulate import sphere_evaluations
from ..units import direction_from_angles
from .costmodel import best_of, band_table_time, direct_calibration, fft_solver_units, psd_terms
from .decisions import LAMBDA_REF_NM, diffraction_lobe_width, float32_floor, grid_step, lobe_width, weakest_level
from .effects import Entry
from .report import fmt_s
from .thresholds import FLOOR_MARGIN, PATCH_SIGMAS, PSD_G_MAX, PLAN_RESOLUTION_RANGE

#: the decisions are private steps of :func:`waveoptics.planning.plan_scene`
__all__ = []


def _patch_grids(views_deg, resolution: int, half_width: float) -> list[DirectionGrid]:
    """Sub-grids of the *resolution*² hemisphere grid around each view direction, ±*half_width* wide.

    The patches keep the hemisphere's cell edges, so a patch evaluates exactly the cells the hemisphere would.
    """
    du = 2.0 / resolution
    out = []
    for th, ph in views_deg:
        d = direction_from_angles(th, ph)
        rng = []
        for c in (d[0], d[1]):
            i0 = max(0, int(math.floor((c - half_width + 1.0) / du)))
            i1 = min(resolution, max(int(math.ceil((c + half_width + 1.0) / du)), i0 + 2))
            i0 = min(i0, i1 - 2)
            rng.append((-1.0 + i0 * du, -1.0 + i1 * du, i1 - i0))
        (ua, ub, nu), (va, vb, nv) = rng
        out.append(DirectionGrid(nu, nv, (ua, ub), (va, vb)))
    return out



def decide_resolution(e: Entry) -> None:
    """The grid resolves the narrowest lobe within the colour target (or the height field's specular spike)."""
    if e.micro.alpha > 0:
        e.widths["micro lobe"] = lobe_width(min(e.micro.alpha, e.micro.alpha_y or e.micro.alpha), min(e.cos_i))
    if e.diffracts and e.nano is not None and e.nano.model is not None:
        e.widths["nano lobe"] = diffraction_lobe_width(e.nano.model, e.lam_min)
    hi = min(PLAN_RESOLUTION_RANGE[1], e.max_resolution or PLAN_RESOLUTION_RANGE[1])
    lo = min(PLAN_RESOLUTION_RANGE[0], hi)
    if e.scene.output.resolution is not None or "resolution" in e.force:
        e.resolution = int(e.force.get("resolution", e.scene.output.resolution))
        e.decide("resolution", e.resolution, "set by the scene's output.resolution")
        return
    need = {k: int(math.ceil(2.0 / grid_step(s, e.delta_e))) for k, s in e.widths.items() if s > 0}
    if e.hf is not None and e.diffracts:
        L = max(e.hf.extent)
        need["the height field's specular spike"] = int(math.ceil(2.0 * L / (e.lam_min * 1e-9)))
    if not need:
        e.resolution = lo
        e.decide("resolution", lo, "no lobe to resolve (mirror): the specular spike keeps its energy on any grid")
        return
    key = max(need, key=need.get)
    e.resolution = int(np.clip(need[key], lo, hi))
    note = f"{key} needs {need[key]} cells per side " + (
        f"(du ≤ λ_min/L, L = {L * 1e6:.3g} µm)" if key.startswith("the height") else
        f"(linear interpolation within ΔE {e.delta_e:g}: du ≤ {grid_step(e.widths[key], e.delta_e):.3g})")
    if need[key] > hi:
        note += f"; capped at {hi} (narrower lobes keep their energy and colour, not their shape)"
    elif need[key] < lo:
        note += f"; raised to the minimum {lo}"
    e.decide("resolution", e.resolution, note)



def _direction_options(e: Entry) -> tuple[dict, float]:
    """Candidate direction sets: the hemisphere, and patches around the view directions when no output needs the
    hemisphere; with the patches' half-width."""
    out = e.scene.output
    hemi_needed = e.sphere or out.rgb_images or out.spectral_brdf
    du = 2.0 / e.resolution
    s_tot = math.sqrt(sum(s * s for s in e.widths.values())) if e.widths else 0.0
    half = PATCH_SIGMAS * s_tot + 2 * du
    options = {"hemisphere": [DirectionGrid.hemisphere(e.resolution)]}
    if e.force.get("directions") == "views" and (hemi_needed or not e.views):
        raise FieldError("{force} directions=views needs view directions and outputs that show no hemisphere "
                         "(tables only, no camera)", "force")
    if e.views and not hemi_needed and e.force.get("directions") != "hemisphere":
        options["views"] = _patch_grids(e.views, e.resolution, half)
    if e.force.get("directions") == "views":
        del options["hemisphere"]
    return options, half


def _costs(e: Entry, options: dict) -> tuple[dict, dict]:
    """Estimated seconds of every (directions, solver) option, and facts about the height-field solvers."""
    n_eval = len(e.light.directions_deg) + (sphere_evaluations(e.micro, e.nano) if e.sphere else 0)
    n_w = max(e.w_sim.size, 1)
    w_eval = e.w_sim if e.w_sim.size else np.array([LAMBDA_REF_NM])
    terms = psd_terms(e.nano.model.sigma, e.lam_min) if e.solver == "psd" else None
    if terms is not None:
        t_band = band_table_time(e.nano.model, e.lam_min, e.mat, e.light.directions_deg[0][0])
        e.metrics.update(band_table_s=t_band)
    hf_solvers = e.diffracts and e.solver in (None, "fft", "direct")
    hf_info = {"hf_solvers": hf_solvers}
    if hf_solvers:
        smp = scatter.samples(e.hf)
        direct_term, no_direct = direct_calibration(e.device)
        wi0 = direction_from_angles(*e.light.directions_deg[0])
        # the height field's coherent fraction is what its own lobe leaves: one fft lobe on a grid of λ/(3L) cells
        # per wavelength and incidence (the macro ones, and the facet table's nodes under a micro lobe)
        theta0 = e.light.directions_deg[0][0]
        t_char = best_of(lambda: field_scattered_albedo(e.hf, theta0, e.lam_min), 2)
        hf_info.update(smp=smp, direct_term=direct_term, no_direct=no_direct)
        e.metrics.update(height_field_samples=smp.size, opencl=direct_term is not None, direct_term_s=direct_term,
                         coherent_fraction_s=t_char)
    costs = {}
    N = e.resolution
    for dname, grids in options.items():
        cells = [g.n_u * g.n_v for g in grids]
        base = n_eval * e.cm.evaluation(cells, n_w, diffuse=e.diffuse, psd_terms=terms, nano_lobe=hf_solvers)
        if terms is not None:   # the band tables, once per wavelength for the whole entry, timed on this model
            base += n_w * t_band
        if dname == "views" and e.micro.alpha >= 0.75 * 2.0 / N:  # a patch normalizes its micro lobe on the grid
            base += n_eval * len(grids) * N * N * e.cm.cell
        if not hf_solvers:
            costs[(dname, e.solver)] = base
            continue
        n_field = field_albedo_evaluations(
            e.micro, grids[0], direction_from_angles(*np.asarray(e.light.directions_deg, dtype=float).T),
            extra=n_eval - len(e.light.directions_deg))
        base += n_field * n_w * t_char
        # the incoherent lobe is U − χ U_flat: the height field's transforms plus one for the flat patch
        costs[(dname, "fft")] = base + n_eval * fft_solver_units(smp, wi0, grids, w_eval) * e.cm.fft_unit
        if direct_term is not None:
            dirs = sum(int(g.inside.sum()) for g in grids)
            costs[(dname, "direct")] = base + n_eval * 2 * direct_term * smp.size * dirs * n_w
    return costs, hf_info


def decide_directions(e: Entry) -> None:
    """The cheapest direction set (and height-field solver) that the outputs allow, by the cost model."""
    options, half = _direction_options(e)
    costs, hf = _costs(e, options)
    if hf["hf_solvers"] and e.solver == "direct" and hf["direct_term"] is None:
        raise FieldError(f"{{force}} solver=direct needs the OpenCL direct sum, unavailable here: {hf['no_direct']}",
                         "force")
    allowed = {k: v for k, v in costs.items() if e.solver in (None, k[1])}
    (e.directions, e.solver), e.time_s = min(allowed.items(), key=lambda kv: kv[1])
    e.metrics["costs_s"] = {f"{d}/{s_}": v for (d, s_), v in costs.items()}
    out = e.scene.output
    if e.force.get("directions"):
        e.decide("directions", e.directions, "forced")
    elif e.sphere or out.rgb_images or out.spectral_brdf:
        need = [n for n, on in (("sphere camera", e.sphere), ("RGB images", out.rgb_images),
                                ("spectral BRDF", out.spectral_brdf)) if on]
        e.decide("directions", "hemisphere", f"the outputs show it: {', '.join(need)}")
    elif "views" in options:
        other = "hemisphere" if e.directions == "views" else "views"
        t_other = min(v for (d, _), v in allowed.items() if d == other)
        t_views, t_hemi = (e.time_s, t_other) if e.directions == "views" else (t_other, e.time_s)
        n_p = sum(g.n_u * g.n_v for g in options["views"])
        e.decide("directions", e.directions,
                 f"{len(e.views)} patches of ±{half:.2g} around the view directions ({n_p} cells): "
                 f"{fmt_s(t_views)}; the hemisphere ({e.resolution ** 2} cells): {fmt_s(t_hemi)}")
    else:
        e.decide("directions", "hemisphere", "no view directions: the whole hemisphere")
    if hf["hf_solvers"]:
        _explain_solver(e, costs, hf)
    e.patches = options.get("views", []) if e.directions == "views" else []


def _explain_solver(e: Entry, costs: dict, hf: dict) -> None:
    """The reason for the height-field solver the cost model chose."""
    if "solver" in e.force:
        e.decide("solver", e.solver, "forced")
        return
    alt = {s_: v for (d, s_), v in costs.items() if d == e.directions}
    smp = hf["smp"]
    why = (f"height field of {smp.nx}x{smp.ny} samples, both exact Kirchhoff: " +
           ", ".join(f"{k} {fmt_s(v)}" for k, v in sorted(alt.items(), key=lambda kv: kv[1])))
    if hf["direct_term"] is None:
        why += f" (direct sum unavailable: {hf['no_direct']})"
    if e.spec.nano.kind == "statistics":
        why = f"g(θ_o = 0) = {e.g_series:.3g} > {PSD_G_MAX:g} is beyond the PSD series; generated {why}"
    e.decide("solver", e.solver, why)


def decide_precision(e: Entry) -> None:
    """float32 for the direct sum unless its noise floor comes near the weakest visible level of the lobe."""
    if e.solver != "direct":
        e.precision = "float64"
        e.decide("precision", "float64", "NumPy float64 throughout (no OpenCL kernel on this route)")
        return
    h_max = float(np.max(np.abs(e.hf.heights - e.hf.heights.mean())))
    floor = float32_floor(e.hf.heights.size, h_max, e.lam_min)
    level = weakest_level(e.delta_e, max(e.hf.extent), e.lam_min)
    e.metrics.update(float32_floor=floor, weakest_level=level)
    if "precision" in e.force:
        e.precision = e.force["precision"]
        e.decide("precision", e.precision, "forced")
    else:
        e.precision = "float64" if floor > FLOOR_MARGIN * level else "float32"
        cmp = ">" if e.precision == "float64" else "≤"
        e.decide("precision", e.precision, f"float32 noise floor {floor:.2g} {cmp} {FLOOR_MARGIN:g} × weakest "
                                           f"visible level {level:.2g} of the peak")
    if e.precision == "float64" and not get_runtime(e.device).fp64:
        e.precision = "float32"
        e.decide("precision", "float32", "the OpenCL device has no fp64 (float64 was wanted)")

