"""Executing a plan: each entry simulated with the decisions it carries, its files written, estimated time
beside measured time in plan.json.
"""
from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

import numpy as np

from .. import colour, io, scatter
from ..renderers import sphere as render
from ..brdf import twoscale
from ..io import figures
from ..scatter.grid import DirectionGrid
from ..brdf import MicrofacetBRDF, TabulatedTwoScaleBRDF
from ..simulate import Simulation, render_spheres, sphere_nodes
from ..units import direction_from_angles
from .decisions import LAMBDA_REF_NM
from .plan import EntryPlan, Plan

__all__ = ['entry_prefix', 'output_files', 'EntryResult', 'run_entry', 'view_values', 'execute']

# ----------------------------------------------------------------------------------------------------------------
# Executing a plan
# ----------------------------------------------------------------------------------------------------------------

def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", str(text)).strip("-") or "x"


def _tag(th: float, ph: float) -> str:
    return f"i{th:g}_{ph:g}".replace(".", "p").replace("-", "m")


def entry_prefix(e: EntryPlan, plan: Plan) -> str:
    """File-name prefix of an entry: the material, plus the light when the scene has several."""
    return _slug(e.name) if len(plan.scene.lights) == 1 else f"{_slug(e.name)}_{_slug(e.light_name)}"


def output_files(plan: Plan) -> list[str]:
    """Every file :func:`execute` writes for *plan* (checked before computing)."""
    out = plan.scene.output
    files = ["plan.json", "results.json"]
    for e in plan.entries:
        p = entry_prefix(e, plan)
        if e.directions == "hemisphere":
            for th, ph in e.light_directions_deg:
                t = _tag(th, ph)
                if out.spectral_brdf:
                    files.append(f"{p}_{t}_brdf_spectral.exr")
                if out.rgb_images:
                    files += [f"{p}_{t}_brdf_rgb.exr", f"{p}_{t}_brdf.png"]
            if e.sphere and out.rgb_images:
                files += [f"{p}_sphere.exr", f"{p}_sphere.png"]
        if out.tables:
            files.append(f"{p}_table.csv")
    return files


def _broadcast(L: twoscale.Lobes, w) -> twoscale.Lobes:
    """A λ-independent evaluation (one wavelength) copied onto the colour wavelengths *w*."""
    shape = (len(w),) + L.total.shape[1:]
    b = {k: np.broadcast_to(getattr(L, k), shape).copy() for k in ("coherent", "diffraction", "diffuse", "microfacet")}
    if L.multiple is not None:
        b["multiple"] = np.broadcast_to(L.multiple, shape).copy()

    def per_w(a):
        return None if a is None else np.broadcast_to(a, (len(w),)).copy()
    return twoscale.Lobes(grid=L.grid, wi=L.wi, wavelengths_nm=np.asarray(w, float), info=dict(L.info),
                          diffuse_albedo=per_w(L.diffuse_albedo), multiple_albedo=per_w(L.multiple_albedo), **b)


@dataclass
class EntryResult:
    """What :func:`run_entry` computed: lobes per light direction (hemisphere or one per view patch)."""

    entry: EntryPlan
    lobes: dict                      # (θ, φ) -> Lobes (hemisphere) or list of Lobes (one per view)
    sphere_brdfs: tuple | None       # (two-scale BRDF function, microfacet BRDF function)
    time_s: float


def run_entry(e: EntryPlan, *, device=None, progress=None) -> EntryResult:
    """Evaluate the planned two-scale (or microfacet) BRDF of one entry: its request (the scene's, with the
    planner's decisions applied) on the entry's directions."""

    t0 = time.perf_counter()
    req = e.request
    w = e.wavelengths_nm if e.wavelengths_nm.size else np.array([LAMBDA_REF_NM])
    kw = dict(solver=req.solver if e.nano is not None else "auto", kd=req.kd,
              diffuse="lambert" if req.kd > 0 else "none", device=device, precision=req.precision,
              diffraction=req.diffraction, multiple_scattering=req.multiple_scattering)
    nano = e.nano if e.effects["diffraction"] else None
    hemi = DirectionGrid.hemisphere(e.resolution)

    def ev(wi, grid):
        ref = None if grid is hemi else hemi            # view patches are normalized on the hemisphere grid
        L = twoscale.evaluate(wi, w, e.material, e.micro, nano, grid, reference_grid=ref, **kw)
        return L if e.wavelengths_nm.size else _broadcast(L, e.colour_wavelengths_nm)

    lobes = {}
    for th, ph in e.light_directions_deg:
        wi = direction_from_angles(th, ph)
        lobes[(th, ph)] = ev(wi, hemi) if e.directions == "hemisphere" else [ev(wi, g) for g in e.patches]
        if progress:
            progress(1)
    brdfs = None
    if e.sphere:   # BRDF functions for per-pixel renders: diffracted lobes tabulated over incidence by ev
        thetas, n_phi = sphere_nodes(e.micro, nano)
        wave = TabulatedTwoScaleBRDF(material=e.material, micro=e.micro, nano=nano, kd=req.kd,
                                     diffuse=kw["diffuse"],
                                     wavelengths_nm=tuple(e.colour_wavelengths_nm), thetas_deg=thetas, n_phi=n_phi,
                                     diffraction=req.diffraction, lobes_at=lambda wi: ev(wi, hemi),
                                     progress=progress, multiple_scattering=kw["multiple_scattering"])
        brdfs = (wave, MicrofacetBRDF(e.material, e.micro, kd=req.kd, diffuse=kw["diffuse"],
                                      multiple_scattering=kw["multiple_scattering"]))
    return EntryResult(e, lobes, brdfs, time.perf_counter() - t0)


def view_values(res: EntryResult, which: str = "total") -> list[dict]:
    """BRDF spectra (1/sr) at every (light, view) pair of the entry, looked up bilinearly on its grid."""

    e = res.entry
    rows = []
    for (th, ph), L in res.lobes.items():
        for k, (vt, vp) in enumerate(e.view_directions_deg):
            lob = L if e.directions == "hemisphere" else L[k]
            d = direction_from_angles(vt, vp)
            f = lob.grid.interpolate(getattr(lob, which), d[0], d[1])
            rows.append({"light_deg": [th, ph], "view_deg": [vt, vp], "brdf": np.maximum(f, 0.0),
                         "cos_i": math.cos(math.radians(th))})
    return rows


def _rgb_rows(rows, w, spd):
    if not rows:
        return np.zeros((0, 3))
    Q = np.array([np.pi * r["cos_i"] * r["brdf"] for r in rows])
    return colour.reflectance_to_rgb(Q, w, spd)


def execute(plan: Plan, outdir, *, overwrite: bool = False, device=None, progress=None) -> dict:
    """Run a plan and write the outputs the scene asks for, ``plan.json`` (estimated and measured times) and
    ``results.json`` (colours at the directions of interest, albedos).

    Returns
    -------
    dict
        The content of ``plan.json``.
    """

    files = output_files(plan)
    out = io.prepare_outdir(outdir, overwrite=overwrite, expected=files)
    sc = plan.scene
    data = plan.as_dict()
    results = {"scene": sc.name, "materials": []}
    # the whole set is staged and moved into place at the end, plan.json (the manifest) last: a run that fails or
    # is killed leaves the earlier set, or no manifest and a journal the next run completes (io.staged_outputs)
    with io.staged_outputs(out, files, last="plan.json") as stage:
        t_all = time.perf_counter()
        for e, ed in zip(plan.entries, data["materials"]):
            res = run_entry(e, device=device, progress=progress)
            t_out = time.perf_counter()
            p = entry_prefix(e, plan)
            w = e.colour_wavelengths_nm
            written, albedo = [], {}
            for (th, ph), L in res.lobes.items():
                t = _tag(th, ph)
                if e.directions == "hemisphere":
                    albedo[t] = {"light_deg": [th, ph], "albedo": L.albedo("total"),
                                 "rgb": colour.reflectance_to_rgb(L.albedo("total"), w, e.spd)}
                    hdr = scatter.brdf_exr_header(L.grid, (th, ph), e.material.name, scene=sc.name)
                    if sc.output.spectral_brdf:
                        name = f"{p}_{t}_brdf_spectral.exr"
                        io.write_spectral_exr(stage / name, {float(lam): L.grid.to_image(L.total[i])
                                                           for i, lam in enumerate(w)},
                                              header=hdr, overwrite=True)
                        written.append(name)
                    if sc.output.rgb_images:
                        rgb = colour.reflectance_to_rgb(np.moveaxis(L.total, 0, -1), w, e.spd)
                        io.write_rgb_exr(stage / f"{p}_{t}_brdf_rgb.exr",
                                         L.grid.to_image(np.moveaxis(rgb, -1, 0)).transpose(1, 2, 0), header=hdr)
                        img = np.where(L.grid.inside[..., None], render.tonemap(rgb), 0.0)[::-1]  # row 0 = top = +v
                        k = max(1, 256 // max(img.shape[:2]))                   # nearest-neighbour zoom for viewing
                        img = np.repeat(np.repeat(img, k, axis=0), k, axis=1)
                        figures.save_png(stage / f"{p}_{t}_brdf.png", img)
                        written += [f"{p}_{t}_brdf_rgb.exr", f"{p}_{t}_brdf.png"]
            sphere = None
            if res.sphere_brdfs is not None and sc.output.rgb_images:
                first = res.lobes[e.light_directions_deg[0]]
                sim = Simulation(lobes=first, brdf_wave=res.sphere_brdfs[0], brdf_microfacet=res.sphere_brdfs[1],
                                 illuminant=e.spd, params={"incident_deg": list(e.light_directions_deg[0])})
                wave, mfimg, dEmap, mask = render_spheres(sim, sc.output.sphere_size)
                io.write_rgb_exr(stage / f"{p}_sphere.exr", wave,
                                 header={"waveoptics_scene": sc.name, "waveoptics_material": e.material.name})
                figures.save_png(stage / f"{p}_sphere.png", render.tonemap(wave))
                written += [f"{p}_sphere.exr", f"{p}_sphere.png"]
                sphere = {"delta_e2000_vs_microfacet": {"mean": float(dEmap[mask].mean()) if mask.any() else 0.0,
                                                        "max": float(dEmap[mask].max()) if mask.any() else 0.0}}
            rows = view_values(res)
            rows_mf = view_values(res, "microfacet")
            rgb = _rgb_rows(rows, w, e.spd)
            rgb_mf = _rgb_rows(rows_mf, w, e.spd)
            for r, c, cm_ in zip(rows, rgb, rgb_mf):
                r["rgb"] = c
                r["microfacet_rgb"] = cm_
                r["delta_e2000_vs_microfacet"] = float(colour.delta_e2000(c, cm_))
            if sc.output.tables:
                name = f"{p}_table.csv"
                with io.atomic_path(stage / name) as tmp:
                    # units in every header; RGB is linear sRGB of the BRDF under the light, white-balanced to the
                    # light (a white reflector is grey under a 532 nm laser too): said in the header, not assumed
                    light = str(getattr(e.spd, "name", e.light_name)).replace(",", ";")
                    wb = f"linear sRGB 1/sr white-balanced to {light}"
                    head = ["light_theta_deg", "light_phi_deg", "view_theta_deg", "view_phi_deg"] + \
                           [f"f_{lam:g}nm_per_sr" for lam in w] + [f"{c} ({wb})" for c in "RGB"]
                    lines = [",".join(head)]
                    for r in rows:
                        vals = r["light_deg"] + r["view_deg"] + list(r["brdf"]) + list(r["rgb"])
                        lines.append(",".join(f"{v:.9g}" for v in vals))
                    tmp.write_text("\n".join(lines) + "\n")
                written.append(name)
            t_written = time.perf_counter() - t_out
            ed.update(measured_time_s=res.time_s, outputs_time_s=t_written, files=written,
                      estimate_ratio=res.time_s / e.estimated_time_s if e.estimated_time_s > 0 else None)
            results["materials"].append({"name": e.name, "light": e.light_name, "wavelengths_nm": w,
                                         "views": [{k: v for k, v in r.items() if k != "cos_i"} for r in rows],
                                         "albedo": albedo, "sphere": sphere, "measured_time_s": res.time_s})
        data["measured_time_s"] = float(sum(m["measured_time_s"] for m in data["materials"]))
        data["run_time_s"] = time.perf_counter() - t_all
        data["files"] = files
        io.write_json(stage / "results.json", results)
        io.write_json(stage / "plan.json", data)
    return data
