"""BRDF tables (incident angles × wavelengths × directions) computed on Dask, stored as HDF5, resumable.
"""
from __future__ import annotations

import dataclasses
import json
import math
import os
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, NamedTuple

import h5py
import numpy as np

from .. import colour, io, surfaces
from ..brdf import twoscale
from ..errors import FieldError, WaveopticsError
from ..materials import get_material, with_roughness_correlation
from ..request import SimulationRequest, make_nano
from ..scatter.grid import DirectionGrid
from ..scatter.solvers import split_patch
from ..units import check_theta, direction_from_angles
from .cases import case_nano, case_token, surface_digest
from .cluster import DEFAULT_RETRIES, check_cluster_args, Job, run_timed, warm_workers
from .glass_table import (GLASS_TABLE_FORMAT, assemble_glass_table, compute_glass_block, glass_incidences,
                          glass_models, open_glass_table)
from .store import refuse_or_prepare, Store, check_resume_overwrite, partial_path

__all__ = ['TABLE_FORMAT', 'TABLE_VERSION', 'DEFAULT_BATCH', 'TABLE_LAYOUT', 'TableSpec', 'TableTask', 'table_tasks', 'compute_block', 'table_size', 'check_table_size', 'run_table', 'table_plan', 'BRDFTable', 'table_info', 'read_table', 'open_table']

#: version of the table file layout written by :func:`run_table`
TABLE_FORMAT = "waveoptics-brdf-table"
TABLE_VERSION = 3

#: wavelengths per table task unless told otherwise
DEFAULT_BATCH = 8


#: on-disk layout of a table (also documented in docs/scaling.md)
TABLE_LAYOUT = {
    "theta_i": "(n_theta,) float64, deg — incident zenith angles (dimension scale)",
    "wavelength": "(n_lambda,) float64, nm (dimension scale)",
    "v": "(n_v,) float64 — direction cosine sin(theta_o) sin(phi_o) of the cell centres, rows (dimension scale)",
    "u": "(n_u,) float64 — direction cosine sin(theta_o) cos(phi_o) of the cell centres, columns (dimension scale)",
    "realization": "(n_r,) int — surface realization index (dimension scale)",
    "brdf": "(theta_i, wavelength, v, u) float32, 1/sr — two-scale BRDF f, mean over realizations; 0 outside "
            "the unit disc",
    "brdf_realizations": "(realization, theta_i, wavelength, v, u) float32, 1/sr — only when n_r > 1",
    "microfacet": "(theta_i, wavelength, v, u) float32, 1/sr — plain microfacet BRDF of the same micro roughness",
    "diffraction": "(theta_i, wavelength, v, u) float32, 1/sr — the diffracted part of brdf alone (mean over "
                   "realizations): what waveoptics.open_table interpolates between incidences relative to the "
                   "specular direction (the coherent and diffuse parts are closed forms of the parameters)",
    "diffraction_rim": "(theta_i, wavelength, cos_theta_o, phi_o) float32, 1/sr — the diffracted part near the "
                       "horizon in the light's frame (azimuth 0) on waveoptics.brdf.tabulated_rim's nodes (cos "
                       "theta_o from cos 63 deg to 0, phi_o -180 to 180 deg), which open_table reads beyond theta_o "
                       "65-69 deg; only for PSD statistics, unpolarized, isotropic micro roughness (version 3 on)",
    "albedo": "(theta_i, wavelength) float64 — directional albedo of brdf (sum f du dv over the disc)",
    "microfacet_albedo": "(theta_i, wavelength) float64",
    "rgb": "(theta_i, v, u, channel) float32, 1/sr — linear sRGB of brdf under the illuminant (D65 white)",
    "microfacet_rgb": "(theta_i, v, u, channel) float32",
    "albedo_rgb": "(theta_i, channel) float64 — linear sRGB of the directional albedo spectrum",
    "microfacet_albedo_rgb": "(theta_i, channel) float64",
    "task_cost_s": "(realization, theta_i, batch) float64, s — wall time of each task on its worker",
    "task_cpu_s": "(realization, theta_i, batch) float64, s — CPU time of each task's thread on its worker",
}


# -- tables ------------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TableSpec:
    """A BRDF table: *case* evaluated at every incident zenith angle (degrees, azimuth *phi_deg*) and wavelength.

    *realizations* > 1 averages over surface realizations: tiles of a height-field file
    (:func:`waveoptics.scatter.split_patch`) or generated surfaces with seeds ``seed .. seed + n − 1``.
    *batch* is the number of wavelengths per task. *transmission*: the rough glass's BSDF over the sphere instead
    (:mod:`waveoptics.distributed.glass_table`; its nano lobes in *nano_frame*, its angles *refine*-d).
    """

    case: SimulationRequest
    thetas_deg: tuple
    phi_deg: float = 0.0
    realizations: int = 1
    batch: int = DEFAULT_BATCH
    surface_digest: str | None = None
    transmission: bool = False
    nano_frame: str = "macro"
    refine: bool = True

    def __post_init__(self):
        object.__setattr__(self, "case", self.case.resolved())
        th = tuple(float(t) for t in np.atleast_1d(self.thetas_deg))
        object.__setattr__(self, "thetas_deg", th)
        if not th:
            raise FieldError("{thetas_deg}: no angles given", 'thetas_deg')
        check_theta(th, name="thetas_deg")
        if max(th) >= 90:
            raise FieldError(f"{{thetas_deg}} θ={max(th):g}° is not allowed; the light must be above the "
                                  "horizon (θ < 90)", 'thetas_deg')
        if len(set(th)) != len(th):
            raise FieldError("{thetas_deg}: an angle appears twice", 'thetas_deg')
        if not math.isfinite(self.phi_deg):
            raise FieldError(f"{{phi_deg}} {self.phi_deg!r} is not finite", 'phi_deg')
        if int(self.realizations) != self.realizations or self.realizations < 1:
            raise FieldError(f"{{realizations}} {self.realizations!r} is not allowed; use an integer >= 1", 'realizations')
        if self.transmission and self.realizations != 1:
            raise FieldError("{realizations}: a glass table ({transmission}) is of nano statistics, one realization",
                             "realizations", "transmission")
        if int(self.batch) != self.batch or self.batch < 1:
            raise FieldError(f"{{batch}} {self.batch!r} is not allowed; use an integer >= 1 (wavelengths per task)", 'batch')

    @property
    def n_batches(self) -> int:
        return math.ceil(len(self.case.wavelengths()) / self.batch)

    def params(self) -> dict:
        return {**self.case.params(), "incident_theta_deg": list(self.thetas_deg), "incident_phi_deg": self.phi_deg,
                "realizations": int(self.realizations), "batch": int(self.batch),
                "surface_digest": self.surface_digest,
                **({"transmission": True, "nano_frame": self.nano_frame, "refine": bool(self.refine)}
                   if self.transmission else {})}

    def token(self) -> str:
        return case_token({**self.params(), "format_version": TABLE_VERSION})


class TableTask(NamedTuple):
    """Indices of one table task: realization, incident angle, wavelength batch and its slice [lo, hi)."""

    r: int
    t: int
    b: int
    lo: int
    hi: int

    @property
    def name(self) -> str:
        return f"r{self.r:04d}_t{self.t:04d}_b{self.b:04d}"


def table_tasks(spec: TableSpec) -> list[TableTask]:
    """All tasks of a table: realizations × incident angles × wavelength batches (batch sizes balanced)."""
    n = len(spec.case.wavelengths())
    nb = spec.n_batches
    edges = np.linspace(0, n, nb + 1).round().astype(int)
    n_t = len(glass_incidences(spec)) if spec.transmission else len(spec.thetas_deg)
    return [TableTask(r, t, b, int(edges[b]), int(edges[b + 1]))
            for r in range(spec.realizations) for t in range(n_t) for b in range(nb)]


def compute_block(spec: TableSpec, task: TableTask, surface=None, device=None) -> dict:
    """Evaluate one table task on a worker: the two-scale and microfacet BRDFs of one wavelength batch.

    Parameters
    ----------
    spec : TableSpec
    task : TableTask
    surface : HeightField, optional
        The nano height-field tile of realization ``task.r`` (height-field route); None: from ``spec.case.nano``.
    device : str, optional
        OpenCL device spec (the worker's runtime is created once per process).

    Returns
    -------
    dict
        ``total`` and ``microfacet`` (n_batch, n_v, n_u) float32 in 1/sr, their albedos (n_batch,) float64,
        ``cost_s`` (wall time, s), ``cpu_s`` (CPU time of the task's thread, s), ``solver`` and the worker's
        ``host``/``pid``.
    """
    if spec.transmission:
        return compute_glass_block(spec, task, device)
    t0, c0 = time.perf_counter(), time.thread_time()
    case = spec.case
    w = case.wavelengths()
    nano = case_nano(case, task.r, w, surface)
    wi = direction_from_angles(spec.thetas_deg[task.t], spec.phi_deg)
    grid = DirectionGrid.hemisphere(case.resolution)
    mat = with_roughness_correlation(get_material(case.material), case.roughness_correlation)
    L = twoscale.evaluate(wi, w[task.lo:task.hi], mat, case.micro(), nano, grid,
                          solver=case.solver, kd=case.kd, device=device, precision=case.precision,
                          diffraction=case.diffraction, polarization=case.polarization)
    total, mf = L.total, L.microfacet
    rim = _task_rim(spec, task, L, mat, nano, grid, device)
    for name, a in (("two-scale", total), ("microfacet", mf)):
        # the promise of the project: never NaN, Inf or negative
        if not np.all(np.isfinite(a)) or np.any(a < 0):
            raise WaveopticsError(f"table task {task.name} (θi={spec.thetas_deg[task.t]:g}°, "
                                  f"{w[task.lo]:g}-{w[task.hi - 1]:g} nm): the {name} BRDF has NaN, Inf or "
                                  "negative values")
    return {"total": total.astype(np.float32), "microfacet": mf.astype(np.float32),
            "diffraction": L.diffraction.astype(np.float32), "albedo": L.albedo("total"),
            "microfacet_albedo": L.albedo("microfacet"), "solver": L.info["solver"],
            "cost_s": time.perf_counter() - t0, "cpu_s": time.thread_time() - c0, "host": socket.gethostname(),
            "pid": os.getpid(), **({} if rim is None else {"rim": rim.astype(np.float32)})}


def _task_rim(spec: TableSpec, task: TableTask, L, mat, nano, grid, device):
    """The rim tables (n_batch, n_cos, n_φ) of a task (:func:`waveoptics.brdf.tabulated_rim.rim_lobes`, light at
    azimuth 0, times the lobes' energy-guard factor), where :class:`waveoptics.brdf.TabulatedTwoScaleBRDF` builds
    them: the facet-frame route, unpolarized light, an isotropic surface; else None."""
    from ..brdf.roughness_scales import isotropic
    from ..brdf.tabulated_rim import rim_lobes

    case = spec.case
    if (L.info["facet_integration"] != "frame" or case.polarization != "unpolarized"
            or not isotropic(case.micro(), nano)):
        return None
    return rim_lobes(direction_from_angles(spec.thetas_deg[task.t], 0.0), L.wavelengths_nm, mat, case.micro(), nano,
                     grid, diffraction=case.diffraction, energy_scale=L.info["diffraction_energy_scale"],
                     device=device, precision=case.precision)


def _table_surface(case: SimulationRequest, realizations: int):
    """(tiles or None, digest): the height-field tiles a table needs, loaded in the client."""
    if case.surface is None:
        return None, None
    hf = case.surface if isinstance(case.surface, surfaces.HeightField) else surfaces.load(case.surface)
    tiles = split_patch(hf, realizations) if realizations > 1 else [hf]
    return tiles, surface_digest(hf)


def _check_realizations(case: SimulationRequest, realizations: int) -> None:
    if realizations > 1 and case.surface is None:
        nano = make_nano(case.nano, case.wavelengths(), solver=case.solver, seed=case.seed)
        if nano is None or nano.model is not None:
            raise FieldError(f"{{realizations}} {realizations} needs height fields (a SURFACE file, or {{nano}} "
                                  "with {solver} fft/direct); the PSD route is already the ensemble mean", 'realizations', 'nano', 'solver')


#: file name endings of an HDF5 table
TABLE_SUFFIXES = (".h5", ".hdf5", ".he5")


def _check_table_path(output) -> None:
    if Path(output).suffix.lower() not in TABLE_SUFFIXES:
        raise FieldError(f"{{output}} {str(output)!r} is not allowed; a table is an HDF5 file: name it "
                         f"{', '.join('*' + x for x in TABLE_SUFFIXES)}", "output")


def table_size(spec: TableSpec) -> dict:
    """What a table request costs before any work: ``memory_bytes`` at the peak of one task (a wavelength batch on
    the direction grid, :func:`waveoptics.simulate.memory_estimate` without sphere renders), ``file_bytes`` of the
    uncompressed float32 datasets (brdf, microfacet, diffraction, and per realization when there are several)."""
    from ..simulate import memory_estimate

    n = int(spec.case.resolution)
    n_l = len(spec.case.wavelengths())
    per = len(spec.thetas_deg) * n_l * n * n * 4.0
    # a glass table: 2 sides × 4 datasets on its nodes (refined, at least the angles asked for)
    datasets = 8 if spec.transmission else 3 + (spec.realizations if spec.realizations > 1 else 0)
    return {"memory_bytes": memory_estimate(spec.case, sphere=False, n_lambda=min(spec.batch, n_l)),
            "file_bytes": per * datasets}


def check_table_size(spec: TableSpec, output, max_memory=None) -> None:
    """Refuse, in one line and before any work, a table whose task exceeds the memory budget
    (:func:`waveoptics.runtime.check_memory`) or whose datasets would not fit on the output's file system."""
    import shutil

    from ..runtime import check_memory

    size = table_size(spec)
    check_memory(size["memory_bytes"], "one task of this table", "lower {resolution} or {batch}", max_memory,
                 fields=("resolution", "batch"))
    parent = Path(output).resolve().parent
    try:
        free = shutil.disk_usage(parent if parent.is_dir() else Path.cwd()).free
    except OSError:
        return
    if size["file_bytes"] > free:
        raise FieldError(f"{{output}}: the table needs up to {size['file_bytes'] / 1e9:.3g} GB and "
                         f"{str(parent)!r} has {free / 1e9:.3g} GB free; lower {{resolution}}, the number of "
                         "{wavelengths_nm} or of {thetas_deg}", "output", "resolution", "wavelengths_nm", "thetas_deg")


def run_table(spec: TableSpec, output, *, surface=None, workers: int | None = None, scheduler: str | None = None,
              client=None, resume: bool = False, overwrite: bool = False, device: str | None = None,
              progress=None, retries: int = DEFAULT_RETRIES, task_fn: Callable = compute_block,
              max_memory=None) -> dict:
    """Compute a BRDF table on Dask and write it to *output* (HDF5, layout :data:`TABLE_LAYOUT`).

    Parameters
    ----------
    spec : TableSpec
    output : str or Path
        Final ``.h5`` file; work in progress lives in ``OUT.partial/`` (see module docstring).
    surface : HeightField, optional
        Use this height field instead of loading ``spec.case.surface`` (which then only names it).
    workers, scheduler : see :func:`dask_client`; *client* : an existing ``distributed.Client`` to use instead.
    resume : bool
        Continue ``OUT.partial`` (parameters must match); if *output* is already complete, do nothing.
    overwrite : bool
        Replace an existing output and discard an existing partial run.
    progress : callable, optional
        Called with 1 after each finished task (size a bar with :func:`table_plan`).
    retries : int
        Retries of a task that raises.
    task_fn : callable
        The task function (default :func:`compute_block`; tests inject faults through it).
    max_memory : int or str, optional
        Memory budget of one task (:func:`check_table_size`, default :func:`waveoptics.runtime.memory_limit`).

    Returns
    -------
    dict
        ``output``, ``tasks`` (total), ``computed`` (this run), ``skipped`` (already done), ``written`` (task
        names in the order they were stored), ``wall_s``, ``task_cost_s`` (sum of the tasks' wall times),
        ``task_costs_s`` / ``task_cpu_s`` (per task computed now, in storage order: wall and CPU seconds on the
        worker), ``timings_s`` (client side: ``start_s``, ``compute_s``, ``store_s``, ``stop_s``, ``assemble_s``)
        and ``complete`` (True).
    """
    _check_table_path(output)
    t0 = time.perf_counter()
    final = Path(output)
    partial = partial_path(final)
    check_resume_overwrite(resume, overwrite)
    if resume and final.exists() and not partial.exists():
        info = table_info(final)
        if info.get("token") != _table_token(spec, surface):
            raise FieldError(f"{{resume}}: {str(final)!r} is complete but was made with different parameters; "
                                  "pass {overwrite} to recompute it", 'resume', 'overwrite',
                             python={'resume': 'resume=True', 'overwrite': 'overwrite=True'})
        n = len(table_tasks(spec))
        return {"output": str(final), "tasks": n, "computed": 0, "skipped": n, "written": [],
                "wall_s": time.perf_counter() - t0, "task_cost_s": 0.0, "task_costs_s": [], "task_cpu_s": [],
                "timings_s": {}, "complete": True}
    case = spec.case.validate()
    _check_realizations(case, spec.realizations)
    if spec.transmission:
        glass_models(case, spec.nano_frame)   # refuses what a glass table does not take, before any work
    check_cluster_args(workers, scheduler)
    check_table_size(spec, final, max_memory)
    refuse_or_prepare(final, partial, resume=resume, overwrite=overwrite)
    if surface is not None:
        tiles = split_patch(surface, spec.realizations) if spec.realizations > 1 else [surface]
        digest = surface_digest(surface)
    else:
        tiles, digest = _table_surface(case, spec.realizations)
    spec = dataclasses.replace(spec, surface_digest=digest)
    token = spec.token()
    store = Store(partial, {"kind": "table", "token": token, "parameters": spec.params()}, resume=resume)
    tasks = table_tasks(spec)
    todo = [t for t in tasks if not store.has(t.name, ".npz")]
    written: list[str] = []
    costs: list[float] = []
    cpus: list[float] = []
    timings = dict.fromkeys(("start_s", "compute_s", "store_s", "stop_s", "assemble_s"), 0.0)

    def on_result(job, block):
        t = time.perf_counter()
        task = job.args[1]
        with io.atomic_path(store.path(task.name, ".npz")) as tmp:
            np.savez(tmp, **{k: v for k, v in block.items() if k not in ("solver", "host")},
                     solver=np.array(block["solver"]), host=np.array(block["host"]))
        written.append(task.name)
        costs.append(float(block["cost_s"]))
        cpus.append(float(block["cpu_s"]))
        timings["store_s"] += time.perf_counter() - t

    def submit(cl):
        warm_workers(cl, [case], device)
        tile_refs = cl.scatter(tiles, broadcast=False, hash=False) if tiles is not None else None
        return [Job(f"wo-table-{token}-{t.name}", task_fn,
                     (spec, t, None if tile_refs is None else tile_refs[t.r], device)) for t in todo]

    run_timed(client, workers, scheduler, bool(todo), submit, on_result, timings, retries=retries,
               progress=progress)
    t = time.perf_counter()
    _assemble_table(spec, token, store, final, overwrite=overwrite or resume)
    store.remove()
    timings["assemble_s"] = time.perf_counter() - t
    return {"output": str(final), "tasks": len(tasks), "computed": len(written), "skipped": len(tasks) - len(todo),
            "written": written, "wall_s": time.perf_counter() - t0, "task_cost_s": float(sum(costs)),
            "task_costs_s": costs, "task_cpu_s": cpus, "timings_s": timings, "complete": True}


def table_plan(spec: TableSpec, output, *, resume: bool = False) -> dict:
    """How many tasks a run of *spec* into *output* has in all and still to do (for progress bars)."""
    _check_table_path(output)
    tasks = table_tasks(spec)
    store = partial_path(output) / "items"
    todo = [t for t in tasks if not (resume and (store / f"{t.name}.npz").is_file())]
    if resume and Path(output).exists() and not partial_path(output).exists():
        todo = []
    return {"tasks": len(tasks), "todo": len(todo), "batches": spec.n_batches,
            "wavelengths": len(spec.case.wavelengths())}


def _table_token(spec: TableSpec, surface=None) -> str:
    digest = spec.surface_digest
    if surface is not None:
        digest = surface_digest(surface)
    elif spec.case.surface is not None and digest is None:
        digest = _table_surface(spec.case, 1)[1]
    return dataclasses.replace(spec, surface_digest=digest).token()


def _assemble_table(spec: TableSpec, token: str, store: Store, final: Path, *, overwrite: bool) -> None:
    """Write the HDF5 table from the block files (streaming one (θ, batch) at a time), atomically."""
    if spec.transmission:
        return assemble_glass_table(spec, token, store, table_tasks(spec), final, overwrite=overwrite)

    case = spec.case
    w = case.wavelengths()
    grid = DirectionGrid.hemisphere(case.resolution)
    n_t, n_l, n_r, nb = len(spec.thetas_deg), w.size, spec.realizations, spec.n_batches
    shape = (n_t, n_l, grid.n_v, grid.n_u)
    chunks = (1, 1, grid.n_v, grid.n_u)
    comp = {"compression": "gzip", "compression_opts": 4, "shuffle": True}
    tasks = table_tasks(spec)
    params = spec.params()
    solvers = set()
    with io.atomic_path(final, overwrite=overwrite) as tmp, h5py.File(tmp, "w") as f:
        f.attrs.update({"format": TABLE_FORMAT, "format_version": TABLE_VERSION, "token": token,
                        "quantity": "BRDF f (1/sr) on the direction-cosine plane; not multiplied by cos(theta_o)",
                        "parameters": io.to_json(params, sort_keys=True), "material": case.material,
                        "illuminant": case.illuminant, "incident_phi_deg": spec.phi_deg,
                        "realizations": n_r, "layout": io.to_json(TABLE_LAYOUT)})
        f.attrs.update({f"grid_{k}": v for k, v in grid.header().items()})
        scales = {"theta_i": (np.asarray(spec.thetas_deg), "deg"), "wavelength": (w, "nm"),
                  "v": (grid.v, "1"), "u": (grid.u, "1"), "realization": (np.arange(n_r), "1"),
                  "channel": (np.arange(3), "R, G, B")}
        for name, (vals, unit) in scales.items():
            d = f.create_dataset(name, data=vals)
            d.attrs["units"] = unit
            d.make_scale(name)
        d_brdf = f.create_dataset("brdf", shape, np.float32, chunks=chunks, **comp)
        d_mf = f.create_dataset("microfacet", shape, np.float32, chunks=chunks, **comp)
        d_diff = f.create_dataset("diffraction", shape, np.float32, chunks=chunks, **comp)
        d_rim = None
        d_real = (f.create_dataset("brdf_realizations", (n_r,) + shape, np.float32, chunks=(1,) + chunks, **comp)
                  if n_r > 1 else None)
        alb = np.zeros((n_t, n_l))
        alb_mf = np.zeros((n_t, n_l))
        cost = np.zeros((n_r, n_t, nb))
        cpu = np.zeros((n_r, n_t, nb))
        by_tb = {}
        for t in tasks:
            by_tb.setdefault((t.t, t.b), []).append(t)
        for (it, ib), group in sorted(by_tb.items()):
            acc = acc_d = None
            for task in group:
                with np.load(store.path(task.name, ".npz")) as z:
                    tot = z["total"]
                    acc = tot.astype(np.float64) if acc is None else acc + tot
                    acc_d = z["diffraction"].astype(np.float64) if acc_d is None else acc_d + z["diffraction"]
                    if "rim" in z.files:   # PSD statistics: one realization
                        if d_rim is None:
                            d_rim = f.create_dataset("diffraction_rim", (n_t, n_l) + z["rim"].shape[1:], np.float32)
                            d_rim.attrs["description"] = TABLE_LAYOUT["diffraction_rim"]
                        d_rim[it, task.lo:task.hi] = z["rim"]
                    if d_real is not None:
                        d_real[task.r, it, task.lo:task.hi] = tot
                    alb[it, task.lo:task.hi] += z["albedo"] / n_r
                    cost[task.r, it, ib] = float(z["cost_s"])
                    cpu[task.r, it, ib] = float(z["cpu_s"])
                    solvers.add(str(z["solver"]))
                    if task.r == 0:  # the microfacet model does not depend on the nano realization
                        d_mf[it, task.lo:task.hi] = z["microfacet"]
                        alb_mf[it, task.lo:task.hi] = z["microfacet_albedo"]
            d_brdf[it, group[0].lo:group[0].hi] = (acc / n_r).astype(np.float32)
            d_diff[it, group[0].lo:group[0].hi] = (acc_d / n_r).astype(np.float32)
        rgb = f.create_dataset("rgb", (n_t, grid.n_v, grid.n_u, 3), np.float32, chunks=(1, grid.n_v, grid.n_u, 3),
                               **comp)
        rgb_mf = f.create_dataset("microfacet_rgb", rgb.shape, np.float32, chunks=rgb.chunks, **comp)
        for it in range(n_t):  # RGB needs the whole spectrum: one incident angle at a time
            rgb[it] = colour.reflectance_to_rgb(np.moveaxis(d_brdf[it], 0, -1), w, case.illuminant)
            rgb_mf[it] = colour.reflectance_to_rgb(np.moveaxis(d_mf[it], 0, -1), w, case.illuminant)
        f.create_dataset("albedo", data=alb)
        f.create_dataset("microfacet_albedo", data=alb_mf)
        f.create_dataset("albedo_rgb", data=colour.reflectance_to_rgb(alb, w, case.illuminant))
        f.create_dataset("microfacet_albedo_rgb", data=colour.reflectance_to_rgb(alb_mf, w, case.illuminant))
        f.create_dataset("task_cost_s", data=cost).attrs["units"] = "s"
        f.create_dataset("task_cpu_s", data=cpu).attrs["units"] = "s"
        f.attrs["solver"] = ",".join(sorted(solvers))
        dims = {"brdf": ("theta_i", "wavelength", "v", "u"), "microfacet": ("theta_i", "wavelength", "v", "u"),
                "diffraction": ("theta_i", "wavelength", "v", "u"),
                "brdf_realizations": ("realization", "theta_i", "wavelength", "v", "u"),
                "albedo": ("theta_i", "wavelength"), "microfacet_albedo": ("theta_i", "wavelength"),
                "rgb": ("theta_i", "v", "u", "channel"), "microfacet_rgb": ("theta_i", "v", "u", "channel"),
                "albedo_rgb": ("theta_i", "channel"), "microfacet_albedo_rgb": ("theta_i", "channel"),
                "task_cost_s": ("realization", "theta_i", None), "task_cpu_s": ("realization", "theta_i", None)}
        for name, axes in dims.items():
            if name not in f:
                continue
            d = f[name]
            d.attrs["description"] = TABLE_LAYOUT[name]
            for i, ax in enumerate(axes):
                if ax is not None:
                    d.dims[i].label = ax
                    d.dims[i].attach_scale(f[ax])
                else:
                    d.dims[i].label = "batch"


@dataclass
class BRDFTable:
    """A table read back by :func:`read_table` (arrays as in :data:`TABLE_LAYOUT`)."""

    thetas_deg: np.ndarray
    wavelengths_nm: np.ndarray
    grid: DirectionGrid
    brdf: np.ndarray
    microfacet: np.ndarray
    albedo: np.ndarray
    microfacet_albedo: np.ndarray
    rgb: np.ndarray
    microfacet_rgb: np.ndarray
    albedo_rgb: np.ndarray
    microfacet_albedo_rgb: np.ndarray
    task_cost_s: np.ndarray
    params: dict
    attrs: dict = field(default_factory=dict)
    brdf_realizations: np.ndarray | None = None
    diffraction: np.ndarray | None = None
    diffraction_rim: np.ndarray | None = None


def table_info(path) -> dict:
    """The attributes of a table file (``format``, ``token``, ``parameters`` as a dict, ...)."""

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"table {str(p)!r} does not exist")
    try:
        with h5py.File(p, "r") as f:
            attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    except OSError as exc:
        raise WaveopticsError(f"{str(p)!r} is not a readable HDF5 file ({exc})") from None
    if attrs.get("format") not in (TABLE_FORMAT, GLASS_TABLE_FORMAT):
        raise WaveopticsError(f"{str(p)!r} is not a waveoptics BRDF table (format attribute {attrs.get('format')!r})")
    attrs["parameters"] = json.loads(attrs["parameters"])
    return attrs


def read_table(path) -> BRDFTable:
    """Load a table written by :func:`run_table` into memory."""

    info = table_info(path)
    if info["format"] == GLASS_TABLE_FORMAT:
        raise FieldError(f"{str(path)!r} is a glass table (layout GLASS_TABLE_LAYOUT); read it with open_table", "table")
    with h5py.File(path, "r") as f:
        def get(name):
            return f[name][()] if name in f else None

        n_u, n_v = int(info["grid_n_u"]), int(info["grid_n_v"])
        ur = tuple(float(x) for x in str(info["grid_u_range"]).split())
        vr = tuple(float(x) for x in str(info["grid_v_range"]).split())
        return BRDFTable(thetas_deg=get("theta_i"), wavelengths_nm=get("wavelength"),
                         grid=DirectionGrid(n_u, n_v, ur, vr), brdf=get("brdf"), microfacet=get("microfacet"),
                         albedo=get("albedo"), microfacet_albedo=get("microfacet_albedo"), rgb=get("rgb"),
                         microfacet_rgb=get("microfacet_rgb"), albedo_rgb=get("albedo_rgb"),
                         microfacet_albedo_rgb=get("microfacet_albedo_rgb"), task_cost_s=get("task_cost_s"),
                         params=info["parameters"], attrs=info, brdf_realizations=get("brdf_realizations"),
                         diffraction=get("diffraction"), diffraction_rim=get("diffraction_rim"))


def open_table(path, *, surface=None):
    """A table file as a BRDF function (:class:`waveoptics.brdf.TabulatedTwoScaleBRDF`): ``eval``, ``pdf``,
    ``sample`` and ``albedo`` at any (ω_i, ω_o) and at the table's wavelengths.

    The coherent and diffuse parts are rebuilt in closed form from the table's parameters (material, micro
    roughness, nano statistics or height field); the stored diffracted lobes are interpolated between incidences
    relative to the specular direction. A table holds one light azimuth: its lobes are rotated with the light's
    azimuth, which is exact for isotropic surfaces only (a height field's lobes then turn with the light).

    Parameters
    ----------
    path : str or Path
        A table written by ``waveoptics table`` (format version 2 or later; from version 3 with the rim tables
        of PSD statistics, :mod:`waveoptics.brdf.tabulated_rim`, which a version 2 file lacks: its model reads
        the direction-cosine lobes up to the horizon, reciprocal only within 1.7-5.5 % at 80°).
    surface : HeightField, optional
        The nano height field, when the table was made from one given in memory (not from a file or generator).
    """
    from ..brdf import TabulatedTwoScaleBRDF

    if table_info(path)["format"] == GLASS_TABLE_FORMAT:
        return open_glass_table(path)
    t = read_table(path)
    if t.diffraction is None:
        raise FieldError(f"table {str(path)!r} was written by an older waveoptics (format version "
                         f"{t.attrs.get('format_version')}) without its diffracted part; compute it again", "table")
    p = dict(t.params)
    case = SimulationRequest(**{k: p[k] for k in SimulationRequest.__dataclass_fields__ if k in p})
    w = np.asarray(t.wavelengths_nm, dtype=float)
    nano = make_nano(case.nano, w, solver=case.solver, seed=case.seed,
                     surface=surface if surface is not None else case.surface)
    order = np.argsort(t.thetas_deg)
    lobes = np.asarray(t.diffraction, dtype=float)[order][None]
    rim = None if t.diffraction_rim is None else np.asarray(t.diffraction_rim, dtype=float)[order]
    mat = with_roughness_correlation(get_material(case.material), case.roughness_correlation)
    return TabulatedTwoScaleBRDF(material=mat, micro=case.micro(), nano=nano, kd=case.kd,
                                 wavelengths_nm=tuple(w), thetas_deg=tuple(np.asarray(t.thetas_deg)[order]),
                                 diffraction=case.diffraction, table_lobes=lobes, table_grid=t.grid,
                                 table_phis_deg=(float(p.get("incident_phi_deg", 0.0)),), table_rim=rim)
