"""BSDF tables of a rough glass over the sphere (``waveoptics table --transmission``): the cells of
:mod:`waveoptics.brdf.tabulated_glass` for light from the air and from inside, reflected and transmitted, per
incidence node and wavelength, computed as the tasks of :func:`waveoptics.distributed.run_table` and stored as HDF5.

The incidence nodes are the requested angles refined where the read between nodes would miss the light of either
exit hemisphere by more than :data:`waveoptics.brdf.tabulated_glass.NODE_TOLERANCE`
(:func:`waveoptics.brdf.tabulated_glass.refined_incidence_nodes`, on at most :data:`REFINE_RESOLUTION`² cells at
the first and last wavelengths, with the nano lobes about the macro normal whatever the table's frame), the same for
both sides. Each task is one (side, node) and a batch of wavelengths.

References
----------
.. [1] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007 (the model).
.. [2] J. E. Harvey, PhD thesis, University of Arizona, 1976 (the read relative to the specular direction).
"""
from __future__ import annotations

import os
import socket
import time
from pathlib import Path

import h5py
import numpy as np

from .. import colour, io
from ..errors import FieldError, WaveopticsError
from ..request import psd_statistics
from ..scatter.grid import DirectionGrid

__all__ = ['GLASS_TABLE_FORMAT', 'GLASS_TABLE_VERSION', 'GLASS_TABLE_LAYOUT', 'REFINE_RESOLUTION', 'glass_models',
           'check_glass_case', 'glass_nodes', 'glass_incidences', 'compute_glass_block', 'assemble_glass_table',
           'open_glass_table']

#: format of a glass table file (a different layout from the BRDF table's)
GLASS_TABLE_FORMAT = "waveoptics-bsdf-table"
GLASS_TABLE_VERSION = 1
#: cells per axis (at most) of the incidence-node refinement
REFINE_RESOLUTION = 64

_CELLS = "(side, theta_i, wavelength, v, u) float32, 1/sr"
#: on-disk layout of a glass table (also documented in docs/scaling.md)
GLASS_TABLE_LAYOUT = {
    "side": "(2,) str — where the light comes from: air (z > 0) or dielectric (inside, z < 0) (dimension scale)",
    "theta_i": "(n_theta,) float64, deg — incidence nodes, from the normal of the light's side (dimension scale)",
    "wavelength": "(n_lambda,) float64, nm (dimension scale)",
    "v": "(n_v,) float64 — direction cosine of the exit's cell centres, rows (dimension scale)",
    "u": "(n_u,) float64 — direction cosine of the exit's cell centres, columns (dimension scale)",
    "eta": "(n_lambda,) float64 — the glass's real index",
    "reflection": f"{_CELLS} — averages of the BSDF f into the light's hemisphere over each cell's part inside "
                  "the unit disc (its light: the average times that area, waveoptics.brdf.cells_light)",
    "transmission": f"{_CELLS} — cell averages of f (radiance convention, with its η_o² factor) into the other "
                    "hemisphere",
    "microfacet_reflection": f"{_CELLS} — the same of the rough dielectric without nano-roughness",
    "microfacet_transmission": f"{_CELLS}",
    "albedo_reflection": "(side, theta_i, wavelength) float64 — R: the cells' light Σ f du dv",
    "albedo_transmission": "(side, theta_i, wavelength) float64 — T: the cells' sum",
    "model_albedo_reflection": "(side, theta_i, wavelength) float64 — R of the model's own quadrature "
                               "(albedo_parts), against which the cells' sums are checked",
    "model_albedo_transmission": "(side, theta_i, wavelength) float64 — T of the model's own quadrature",
    "rgb_reflection": "(side, theta_i, v, u, channel) float32, 1/sr — linear sRGB of reflection (D65 white)",
    "rgb_transmission": "(side, theta_i, v, u, channel) float32, 1/sr — linear sRGB of transmission",
    "task_cost_s": "(side, theta_i, batch) float64, s — wall time of each task on its worker",
}


def check_glass_case(case) -> None:
    """Refuse, naming fields, what a glass table does not take: height fields, an anisotropic or file micro
    roughness (a table holds one light azimuth and turns it), several realizations."""
    if case.surface is not None:
        raise FieldError("{transmission}: a glass table takes nano statistics ({nano}), not a height-field file",
                         "transmission", "nano")
    if case.alpha_y is not None or case.micro_surface is not None:
        raise FieldError("{transmission}: a glass table is of an isotropic surface (its lobes turn with the "
                         "light's azimuth); drop {alpha_y}", "transmission", "alpha_y")


def glass_models(case, nano_frame: str = "macro"):
    """(the nano-rough glass, the rough dielectric without nano-roughness, the nano statistics or None) of a
    request (:class:`~waveoptics.request.SimulationRequest`: material, micro roughness, nano statistics,
    multiple scattering)."""
    from .. import brdf

    check_glass_case(case)
    micro = case.micro()
    psd = None if case.nano is None else psd_statistics(case.nano, "a glass table")
    plain = brdf.RoughDielectricBSDF(case.material, micro, multiple_scattering=case.multiple_scattering)
    model = plain if psd is None else brdf.nano_rough_glass(case.material, micro, psd,
                                                            multiple_scattering=case.multiple_scattering,
                                                            nano_frame=nano_frame)
    return model, plain, psd


#: refined incidence nodes by (request, angles asked for), once per process
_NODES: dict = {}


def glass_nodes(spec, progress=None) -> tuple:
    """The incidence nodes (degrees) of a glass table: the spec's angles, refined (module doc; once per process,
    *progress* called with 1 per interval tested) unless ``spec.refine`` is False."""
    from ..brdf.tabulated_glass import refined_incidence_nodes

    if not spec.refine:
        return tuple(sorted(spec.thetas_deg))
    key = (spec.case, tuple(spec.thetas_deg))
    if key not in _NODES:
        # the nano lobes about the macro normal stand in for the facet frame's (~200x the cost per evaluation):
        # the nodes follow R(θ), T(θ) and the lobes at the horizon, which the micro facets set
        model, _, psd = glass_models(spec.case, "macro")
        grid = DirectionGrid.hemisphere(min(int(spec.case.resolution), REFINE_RESOLUTION))
        _NODES[key] = refined_incidence_nodes(model, key[1], spec.case.wavelengths(), grid, psd, progress=progress)
    return _NODES[key]


def glass_incidences(spec) -> list:
    """(side, θ) of every task index t: the light from the air at each node, then from inside."""
    from ..brdf.tabulated_glass import GLASS_SIDES

    return [(side, t) for side in GLASS_SIDES for t in glass_nodes(spec)]


def compute_glass_block(spec, task, device=None) -> dict:
    """One glass-table task on a worker: the cells of the model and of the plain rough dielectric for one (side,
    node) and wavelength batch (:func:`waveoptics.brdf.tabulated_glass.glass_cells`), with the model's own R and
    T; ``cost_s``, ``cpu_s``, ``host``, ``pid``, ``solver``."""
    from ..brdf.tabulated_glass import GLASS_HEMISPHERES, cells_light, glass_cells, incident_direction

    t0, c0 = time.perf_counter(), time.thread_time()
    case = spec.case
    lam = case.wavelengths()[task.lo:task.hi]
    side, theta = glass_incidences(spec)[task.t]
    model, plain, psd = glass_models(case, spec.nano_frame)
    grid = DirectionGrid.hemisphere(case.resolution)
    cells = glass_cells(model, side, theta, lam, grid, psd)
    plain_cells = glass_cells(plain, side, theta, lam, grid)
    parts = model.albedo_parts(incident_direction(side, theta), lam)
    out = {"eta": cells["eta"], "solver": "rough-dielectric", "cost_s": 0.0, "cpu_s": 0.0,
           "host": socket.gethostname(), "pid": os.getpid()}
    for h in GLASS_HEMISPHERES:
        for name, a in ((h, cells[h]), (f"microfacet_{h}", plain_cells[h])):
            if not np.all(np.isfinite(a)) or np.any(a < 0):   # the promise of the project
                raise WaveopticsError(f"glass table task {task.name} ({side}, θi={theta:g}°): the {name} cells "
                                      "have NaN, Inf or negative values")
            out[name] = a.astype(np.float32)
        out[f"albedo_{h}"] = cells_light(cells[h], grid)
        out[f"model_albedo_{h}"] = sum(v for k, v in parts.items() if k.endswith(h))
    out["cost_s"], out["cpu_s"] = time.perf_counter() - t0, time.thread_time() - c0
    return out


def assemble_glass_table(spec, token: str, store, tasks, final: Path, *, overwrite: bool) -> None:
    """Write the HDF5 glass table (layout :data:`GLASS_TABLE_LAYOUT`) from the task files, atomically."""
    from ..brdf.tabulated_glass import GLASS_HEMISPHERES, GLASS_SIDES

    case = spec.case
    w = case.wavelengths()
    grid = DirectionGrid.hemisphere(case.resolution)
    nodes = glass_nodes(spec)
    n_t, n_l = len(nodes), w.size
    shape = (2, n_t, n_l, grid.n_v, grid.n_u)
    comp = {"compression": "gzip", "compression_opts": 4, "shuffle": True, "chunks": (1, 1, 1, grid.n_v, grid.n_u)}
    with io.atomic_path(final, overwrite=overwrite) as tmp, h5py.File(tmp, "w") as f:
        f.attrs.update({"format": GLASS_TABLE_FORMAT, "format_version": GLASS_TABLE_VERSION, "token": token,
                        "quantity": "BSDF f (1/sr, radiance convention) averaged over direction-cosine cells",
                        "parameters": io.to_json(spec.params(), sort_keys=True), "material": case.material,
                        "illuminant": case.illuminant, "layout": io.to_json(GLASS_TABLE_LAYOUT)})
        f.attrs.update({f"grid_{k}": v for k, v in grid.header().items()})
        for name, vals in (("side", np.array(GLASS_SIDES, dtype="S")), ("theta_i", np.asarray(nodes)),
                           ("wavelength", w), ("v", grid.v), ("u", grid.u)):
            f.create_dataset(name, data=vals).make_scale(name)
        names = [*GLASS_HEMISPHERES, *(f"microfacet_{h}" for h in GLASS_HEMISPHERES)]
        data = {k: f.create_dataset(k, shape, np.float32, **comp) for k in names}
        sums = {k: np.zeros(shape[:3]) for h in GLASS_HEMISPHERES for k in (f"albedo_{h}", f"model_albedo_{h}")}
        cost = np.zeros((2, n_t, spec.n_batches))
        eta = np.zeros(n_l)
        for task in tasks:
            s, k = divmod(task.t, n_t)
            with np.load(store.path(task.name, ".npz")) as z:
                for name in names:
                    data[name][s, k, task.lo:task.hi] = z[name]
                for name in sums:
                    sums[name][s, k, task.lo:task.hi] = z[name]
                eta[task.lo:task.hi] = z["eta"]
                cost[s, k, task.b] = float(z["cost_s"])
        for name, a in sums.items():
            f.create_dataset(name, data=a)
        f.create_dataset("eta", data=eta)
        for h in GLASS_HEMISPHERES:
            rgb = f.create_dataset(f"rgb_{h}", (2, n_t, grid.n_v, grid.n_u, 3), np.float32)
            for s in range(2):
                for k in range(n_t):
                    rgb[s, k] = colour.reflectance_to_rgb(np.moveaxis(data[h][s, k], 0, -1), w, case.illuminant)
        f.create_dataset("task_cost_s", data=cost).attrs["units"] = "s"
        for name, text in GLASS_TABLE_LAYOUT.items():
            f[name].attrs["description"] = text


def open_glass_table(path):
    """A glass table file as a BSDF over the sphere (:class:`waveoptics.brdf.TabulatedGlassBSDF`)."""
    from ..brdf.tabulated_glass import TabulatedGlassBSDF

    with h5py.File(path, "r") as f:
        attrs = dict(f.attrs)
        n_u, n_v = int(attrs["grid_n_u"]), int(attrs["grid_n_v"])
        ur = tuple(float(x) for x in str(attrs["grid_u_range"]).split())
        vr = tuple(float(x) for x in str(attrs["grid_v_range"]).split())
        return TabulatedGlassBSDF(wavelengths_nm=tuple(f["wavelength"][()]), thetas_deg=tuple(f["theta_i"][()]),
                                  grid=DirectionGrid(n_u, n_v, ur, vr), eta=f["eta"][()],
                                  reflection=f["reflection"][()].astype(float),
                                  transmission=f["transmission"][()].astype(float))
