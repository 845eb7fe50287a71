"""BRDF tables and parameter sweeps on Dask (``dask.distributed``): task split, run, resume, writers.

A measured-style BRDF table (incident directions × wavelengths × surface realizations) or a sweep over materials
and roughnesses is split into independent, deterministic tasks and run on a Dask cluster:

* **table** — one task per (realization r, incident angle θ_i, wavelength batch): :func:`compute_block`
  evaluates the two-scale BRDF (:func:`waveoptics.twoscale.evaluate`) of that batch on the hemisphere grid.
  The result is one HDF5 file with coordinates (see :data:`TABLE_LAYOUT` and ``docs/scaling.md``).
* **sweep** — one task per point of the Cartesian product of ``--vary`` lists: :func:`sweep_point` runs
  :func:`waveoptics.simulate.simulate` and reduces it to a row of summaries (albedo, ΔE2000 vs microfacet, cost).

Where it runs (:func:`dask_client`)
-----------------------------------
* default: an *embedded* in-process cluster, ``LocalCluster(processes=False, n_workers=1, threads_per_worker=1)``
  (in-process transport, no network, one worker thread). It is the same code path as a real cluster — futures,
  retries, streaming writes — so what is tested in-process is what runs distributed; the cost is ~10 ms of start-up.
  One thread because OpenCL queues and NumPy's FFTs gain nothing from sharing a process on this kind of work.
* ``workers=N``: a local multi-process cluster on loopback only (``host="127.0.0.1"``), one thread per worker.
* ``scheduler="tcp://HOST:PORT"``: an existing cluster (workers need waveoptics installed; surface files are
  loaded by the client and shipped once with ``Client.scatter``).

Each worker process builds its OpenCL context once (:func:`waveoptics.runtime.get_runtime` caches it per process)
and generated nano height fields once (:func:`_nano`, cached per process).

Fault tolerance and resume
--------------------------
Tasks are pure: a task's key is derived from the run's parameter token and its indices, so a task lost with a
worker is recomputed by the scheduler (``allowed-failures``), and one that raises is retried (``retries=2``).
Results stream from the client to a *partial store* next to the output, ``OUT.partial/``, as futures complete
(``distributed.as_completed``): each finished block is written atomically (temporary name, then rename, via
:func:`waveoptics.io.atomic_path`), so a block file exists if and only if its task is done — a crash, a lost
worker or Ctrl-C loses only the tasks in flight, never leaves a half-written block that counts as done, and a
rerun with ``resume=True`` computes only the missing blocks. When every block is present the final file is
assembled under a temporary name, renamed to OUT, and the partial store is removed. The store records the run's
parameters; resuming with different parameters is refused.

Why block files rather than one HDF5 file with a "done" mask: HDF5 does not journal, so a process killed during a
write can leave the whole file unreadable and lose every finished block; an atomic rename per block cannot.

References
----------
.. [1] Dask Development Team, "Dask: Library for dynamic task scheduling", https://dask.org (2016);
   ``distributed`` documentation: futures, ``as_completed``, resilience (task retries and lost workers).
.. [2] The HDF Group, "HDF5 Dimension Scale Specification and Design Notes" (dimension scales as coordinates).
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import inspect
import itertools
import json
import math
import os
import shutil
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
from distributed.diagnostics.plugin import WorkerPlugin

from . import io, simulate, spectral, surfaces, twoscale
from .diffraction import DirectionGrid, split_patch
from .errors import OutputExistsError, WaveopticsError, unknown
from .materials import get_material
from .units import LENGTH_UNITS, check_theta, direction_from_angles, parse_length, parse_number_list

#: version of the table file layout written by :func:`run_table`
TABLE_FORMAT = "waveoptics-brdf-table"
TABLE_VERSION = 1

#: wavelengths per table task unless told otherwise
DEFAULT_BATCH = 8

#: retries of a task that raises (a task lost with its worker is recomputed by the scheduler anyway)
DEFAULT_RETRIES = 2

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
    "albedo": "(theta_i, wavelength) float64 — directional albedo of brdf (sum f du dv over the disc)",
    "microfacet_albedo": "(theta_i, wavelength) float64",
    "rgb": "(theta_i, v, u, channel) float32, 1/sr — linear sRGB of brdf under the illuminant (D65 white)",
    "microfacet_rgb": "(theta_i, v, u, channel) float32",
    "albedo_rgb": "(theta_i, channel) float64 — linear sRGB of the directional albedo spectrum",
    "microfacet_albedo_rgb": "(theta_i, channel) float64",
    "task_cost_s": "(realization, theta_i, batch) float64, s — wall time of each task on its worker",
    "task_cpu_s": "(realization, theta_i, batch) float64, s — CPU time of each task's thread on its worker",
}


# ----------------------------------------------------------------------------------------------------------------
# What one simulation computes
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Case:
    """One two-scale configuration (the parameters of :func:`waveoptics.simulate.simulate`).

    Lengths inside *nano* carry units (``abc:sigma=10nm,B=2um,C=2.6``); *surface* is the path of a nano height
    field (then *nano* is ignored). ``wavelengths_nm`` None means: chosen from the illuminant for *accuracy_dE*.
    ``incident_deg`` is used by sweeps; tables take their own list of incident angles.
    """

    material: str = "Al"
    nano: str | None = simulate.DEFAULT_NANO
    surface: str | None = None
    micro_alpha: float = 0.05
    ndf: str = "beckmann"
    shadowing: str = "smith-correlated"
    incident_deg: tuple = (30.0, 0.0)
    illuminant: str = "D65"
    wavelengths_nm: tuple | None = None
    accuracy_dE: float = 1.0
    resolution: int = 128
    solver: str = "auto"
    kd: float = 0.5
    precision: str = "float32"
    seed: int = 0

    def __post_init__(self):
        if self.wavelengths_nm is not None:
            object.__setattr__(self, "wavelengths_nm", tuple(float(x) for x in self.wavelengths_nm))
        object.__setattr__(self, "incident_deg", tuple(float(x) for x in self.incident_deg))
        if not (self.micro_alpha >= 0 and math.isfinite(self.micro_alpha)):
            raise WaveopticsError(f"micro_alpha {self.micro_alpha!r} is not allowed; α must be finite and >= 0")
        if not (8 <= int(self.resolution) <= 2048):
            raise WaveopticsError(f"resolution {self.resolution!r} is not allowed; use 8..2048")
        if not (0 <= self.kd <= 1):
            raise WaveopticsError(f"kd {self.kd!r} is not allowed; the diffuse albedo must be in [0, 1]")
        if self.solver not in ("auto", "psd", "fft", "direct"):
            raise unknown("solver", self.solver, ("auto", "psd", "fft", "direct"))
        if self.surface is None and self.nano is None:
            raise WaveopticsError("a case needs nano roughness: a height-field file or --nano MODEL:params")

    def validate(self) -> "Case":
        """Resolve names (material, illuminant, NDF, shadowing, nano text) in the client, so that a typo is one
        clear error before any task runs rather than a task failure on a worker."""
        from . import microfacet

        get_material(self.material)
        spectral.illuminant(self.illuminant)
        if self.ndf not in microfacet.NDFS:
            raise unknown("NDF", self.ndf, microfacet.NDFS)
        if self.shadowing not in microfacet.SHADOWINGS:
            raise unknown("shadowing", self.shadowing, microfacet.SHADOWINGS)
        if self.surface is None:
            simulate.parse_nano(self.nano)
        return self

    def wavelengths(self) -> np.ndarray:
        """Wavelengths in nm (given, or picked from the illuminant and accuracy like ``simulate``)."""
        if self.wavelengths_nm is not None:
            return np.asarray(self.wavelengths_nm, dtype=float)
        return spectral.simulation_wavelengths(spectral.illuminant(self.illuminant), self.accuracy_dE)

    def resolved(self) -> "Case":
        """This case with its wavelength list fixed (picked once in the client, not again on every worker)."""
        if self.wavelengths_nm is not None:
            return self
        return dataclasses.replace(self, wavelengths_nm=tuple(float(x) for x in self.wavelengths()))

    def micro(self) -> twoscale.Micro:
        return twoscale.Micro(alpha=self.micro_alpha, ndf=self.ndf, shadowing=self.shadowing)

    def params(self) -> dict:
        """Parameters as plain data (JSON-able), with the resolved wavelength list."""
        d = dataclasses.asdict(self)
        d["wavelengths_nm"] = [float(x) for x in self.wavelengths()]
        d["incident_deg"] = list(self.incident_deg)
        if self.surface is not None:
            d["nano"] = None
        return d


#: the documented way to say "no nano roughness" to :func:`waveoptics.simulate.make_nano` (σ = 0)
NO_NANO = "gaussian:sigma=0nm,T=1um"


def case_from_scene(sc, *, material: str | None = None, light: str | None = None, **overrides):
    """A :class:`Case` (and its nano height field, if any) from a scene of :mod:`waveoptics.scene`.

    Parameters
    ----------
    sc : waveoptics.scene.Scene
        A validated scene (``scene.load(path)``).
    material, light : str, optional
        Names of the scene material and light to use; default the first of each. The light gives the
        illuminant and the incident direction (its first one); the scene's ``accuracy.delta_e``,
        ``output.resolution`` and ``seed`` are used too.
    **overrides
        Case fields that replace the scene's values (e.g. ``resolution=32``); None values are ignored.

    Returns
    -------
    (Case, HeightField or None)
        The height field of a nano ``file`` or ``generator`` (loaded or generated here, in the client, with the
        scene's seed); statistics stay text and run on the PSD route.
    """
    mat = sc.material(material) if material is not None else sc.materials[0]
    if light is None:
        li = sc.lights[0]
    else:
        found = [x for x in sc.lights if x.name == light]
        if not found:
            raise WaveopticsError(f"scene {sc.name!r} has no light {light!r}; it has "
                                  f"{', '.join(x.name for x in sc.lights)}")
        li = found[0]
    kw = dict(material=mat.material, micro_alpha=mat.roughness, ndf=mat.ndf, shadowing=mat.shadowing,
              kd=mat.diffuse_albedo, illuminant=li.spd, incident_deg=tuple(li.directions_deg[0]),
              accuracy_dE=sc.delta_e, seed=sc.seed, nano=NO_NANO, surface=None)
    if sc.output.resolution is not None:
        kw["resolution"] = sc.output.resolution
    hf = None
    where = f"{sc.path or sc.name}: material {mat.name!r} nano"
    if mat.nano is not None and mat.nano.kind == "statistics":
        kw["nano"] = mat.nano.text
    elif mat.nano is not None and mat.nano.kind == "file":
        hf = surfaces.load(mat.nano.path, **mat.nano.params)
        kw.update(nano=None, surface=str(mat.nano.path))
    elif mat.nano is not None:
        params = dict(mat.nano.params)
        model = params.pop("model")
        if "seed" in inspect.signature(surfaces.GENERATORS[model]).parameters:
            params.setdefault("seed", sc.seed)
        hf = surfaces.generate(model, **params)
        kw.update(nano=None, surface=f"{where} {mat.nano.describe()}")
    kw.update({k: v for k, v in overrides.items() if v is not None})
    return Case(**kw), hf


def _token(data) -> str:
    """Deterministic short hash of JSON-able *data* (the identity of a run, used in task keys and on resume)."""
    return hashlib.sha1(io.to_json(data, sort_keys=True).encode()).hexdigest()[:16]


def surface_digest(hf: surfaces.HeightField) -> str:
    """sha1 of a height field's samples, spacing and mask (so a resumed run uses the same surface)."""
    h = hashlib.sha1(np.ascontiguousarray(hf.heights, dtype=np.float64).tobytes())
    h.update(repr((hf.dx, hf.dy)).encode())
    if hf.mask is not None:
        h.update(np.ascontiguousarray(hf.mask).tobytes())
    return h.hexdigest()[:16]


@functools.lru_cache(maxsize=16)
def _generated_nano(spec: str, wavelengths_nm: tuple, solver: str, seed: int):
    # cached per worker process: tasks of the same realization share the generated height field
    return simulate.make_nano(spec, np.asarray(wavelengths_nm), solver=solver, seed=seed)


def _nano(case: Case, r: int, wavelengths_nm: np.ndarray, surface=None) -> twoscale.Nano | None:
    """The nano roughness of realization *r*: the given height-field tile, or *case.nano* (seed ``seed + r``).

    Generated height fields are sized from the *whole* wavelength list, never a task's batch, so every batch of
    a realization sees the same surface.
    """
    if surface is not None:
        return simulate.make_nano(None, wavelengths_nm, solver=case.solver, surface=surface)
    return _generated_nano(case.nano, tuple(float(x) for x in wavelengths_nm), case.solver, int(case.seed) + int(r))


# ----------------------------------------------------------------------------------------------------------------
# Dask plumbing shared by tables and sweeps
# ----------------------------------------------------------------------------------------------------------------

#: LocalCluster options that keep every socket on loopback. ``dashboard_address=None`` alone is not enough: the
#: scheduler and each worker still serve health/metrics over HTTP, on all interfaces (0.0.0.0:8787 and a random
#: port) unless given an address; the dashboard itself stays off.
LOOPBACK = dict(dashboard_address=None, worker_dashboard_address="127.0.0.1:0",
                scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"})


def _check_cluster_args(workers, scheduler) -> None:
    if workers is not None and scheduler is not None:
        raise WaveopticsError("give either --workers N (a local cluster) or --scheduler ADDRESS, not both")
    if scheduler is not None and "://" not in str(scheduler):
        raise WaveopticsError(f"--scheduler {scheduler!r} is not a scheduler address; write tcp://HOST:PORT")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise WaveopticsError(f"--workers {workers!r} is not allowed; use an integer >= 1")


@contextlib.contextmanager
def dask_client(workers: int | None = None, scheduler: str | None = None):
    """A ``distributed.Client``: embedded in-process (default), local processes (*workers*) or *scheduler*.

    Parameters
    ----------
    workers : int, optional
        Start a local cluster of this many single-threaded worker processes on loopback (127.0.0.1).
    scheduler : str, optional
        Address of an existing scheduler, ``tcp://HOST:PORT``.
    """
    from distributed import Client

    _check_cluster_args(workers, scheduler)
    if scheduler is not None:
        try:
            client = Client(str(scheduler), timeout="20s")
        except (OSError, TimeoutError) as exc:
            raise WaveopticsError(f"cannot reach the Dask scheduler at {scheduler!r} ({exc})") from None
        with client:
            yield client
        return
    with local_cluster(workers) as cluster, Client(cluster) as client:
        yield client


def local_cluster(workers: int | None = None):
    """The ``LocalCluster`` behind :func:`dask_client`: *workers* single-threaded processes on 127.0.0.1, or (None)
    one in-process worker thread; no dashboard, every socket on loopback (:data:`LOOPBACK`)."""
    from distributed import LocalCluster

    if workers is None:  # in-process transport (inproc://), no host to bind
        return LocalCluster(n_workers=1, threads_per_worker=1, processes=False, **LOOPBACK)
    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in new workers by default (to return memory to the OS); that
    # also fixes glibc's mmap threshold at 128 KiB, so every array of a lobe is a fresh mmap with page faults, and
    # a table task takes about twice the CPU time (measured in docs/scaling.md). Not set here.
    import dask

    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        return LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True, host="127.0.0.1",
                            **LOOPBACK)


class WarmWorker(WorkerPlugin):
    """Dask worker plugin: per worker process, before its first task, import the numerical modules, load the
    material's optical constants and — for the OpenCL ``direct`` solver — create the OpenCL context
    (:func:`waveoptics.runtime.get_runtime` keeps it for the life of the process). Runs again on a worker that
    replaces a lost one. Keeps that one-off cost out of the task timings."""

    idempotent = True

    def __init__(self, material: str, solver: str, device: str | None):
        self.material, self.solver, self.device = material, solver, device
        self.name = f"waveoptics-warm-{material}-{solver}-{device}"

    def setup(self, worker=None):
        from . import runtime

        get_material(self.material)
        if self.solver == "direct":
            runtime.get_runtime(self.device)

    def teardown(self, worker=None):
        pass


def _warm(client, cases, device) -> None:
    """Register :class:`WarmWorker` for each distinct (material, solver) of *cases*."""
    for material, solver in dict.fromkeys((c.material, c.solver) for c in cases):
        plugin = WarmWorker(material, solver, device)
        client.register_plugin(plugin, name=plugin.name)


class _Job(NamedTuple):
    key: str
    fn: Callable
    args: tuple


def _run_jobs(client, jobs: list, on_result: Callable, *, retries: int = DEFAULT_RETRIES, progress=None) -> None:
    """Submit *jobs* and hand each result to ``on_result(job, result)`` in the client as soon as it is done.

    Keys are deterministic, so a task lost with its worker is recomputed under the same key. If a task still
    fails after *retries*, the remaining futures are cancelled and its exception is raised; everything handed to
    *on_result* before that is kept.
    """
    from distributed import as_completed

    if not jobs:
        return
    by_key = {}
    futures = []
    for job in jobs:
        fut = client.submit(job.fn, *job.args, key=job.key, retries=retries, pure=False)
        by_key[fut.key] = job
        futures.append(fut)
    try:
        for fut in as_completed(futures):
            result = fut.result()
            on_result(by_key[fut.key], result)
            fut.release()  # free the worker's copy as soon as it is on disk
            if progress is not None:
                progress(1)
    except BaseException:
        client.cancel(futures)
        raise


def _refuse_or_prepare(final: Path, partial: Path, *, resume: bool, overwrite: bool) -> None:
    """Apply the rules on existing outputs before any work (see :func:`run_table`)."""
    parent = final.parent if str(final.parent) else Path(".")
    if not parent.is_dir():
        raise WaveopticsError(f"output directory {str(parent)!r} does not exist")
    if final.exists() and not overwrite and not resume:
        raise OutputExistsError(f"output {str(final)!r} already exists; pass --overwrite to replace it")
    if partial.exists() and not any((partial / "items").glob("[!.]*")):
        shutil.rmtree(partial)  # a run that stopped before its first result: nothing to resume
    if partial.exists() and not resume:
        if not overwrite:
            raise OutputExistsError(f"{str(partial)!r} holds an interrupted run; pass --resume to continue it or "
                                    "--overwrite to start over")
        shutil.rmtree(partial)


class _Store:
    """The partial store ``OUT.partial/``: ``run.json`` (parameters) and one atomically written file per task."""

    def __init__(self, root: Path, run: dict, *, resume: bool):
        self.root = Path(root)
        self.items = self.root / "items"
        meta = self.root / "run.json"
        if self.root.exists():
            try:
                old = json.loads(meta.read_text())
            except (OSError, ValueError):
                raise WaveopticsError(f"{str(self.root)!r} is not a waveoptics partial run (no readable run.json); "
                                      "remove it or pass --overwrite") from None
            if old.get("token") != run["token"]:
                diff = [k for k in sorted(set(old.get("parameters", {})) | set(run["parameters"]))
                        if old.get("parameters", {}).get(k) != run["parameters"].get(k)]
                raise WaveopticsError(f"--resume: {str(self.root)!r} was started with different parameters "
                                      f"({', '.join(diff) or 'surface'}); pass --overwrite to start over")
        else:
            self.items.mkdir(parents=True)
            io.write_json(meta, run)
        self.items.mkdir(exist_ok=True)

    def path(self, name: str, suffix: str) -> Path:
        return self.items / f"{name}{suffix}"

    def has(self, name: str, suffix: str) -> bool:
        return self.path(name, suffix).is_file()

    def remove(self) -> None:
        shutil.rmtree(self.root)


# ----------------------------------------------------------------------------------------------------------------
# Tables
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class TableSpec:
    """A BRDF table: *case* evaluated at every incident zenith angle (degrees, azimuth *phi_deg*) and wavelength.

    *realizations* > 1 averages over surface realizations: tiles of a height-field file
    (:func:`waveoptics.diffraction.split_patch`) or generated surfaces with seeds ``seed .. seed + n − 1``.
    *batch* is the number of wavelengths per task.
    """

    case: Case
    thetas_deg: tuple
    phi_deg: float = 0.0
    realizations: int = 1
    batch: int = DEFAULT_BATCH
    surface_digest: str | None = None

    def __post_init__(self):
        object.__setattr__(self, "case", self.case.resolved())
        th = tuple(float(t) for t in np.atleast_1d(self.thetas_deg))
        object.__setattr__(self, "thetas_deg", th)
        if not th:
            raise WaveopticsError("--incident-angles: no angles given")
        check_theta(th, name="--incident-angles")
        if max(th) >= 90:
            raise WaveopticsError(f"--incident-angles θ={max(th):g}° is not allowed; the light must be above the "
                                  "horizon (θ < 90)")
        if len(set(th)) != len(th):
            raise WaveopticsError("--incident-angles: an angle appears twice")
        if not math.isfinite(self.phi_deg):
            raise WaveopticsError(f"--phi {self.phi_deg!r} is not finite")
        if int(self.realizations) != self.realizations or self.realizations < 1:
            raise WaveopticsError(f"--realizations {self.realizations!r} is not allowed; use an integer >= 1")
        if int(self.batch) != self.batch or self.batch < 1:
            raise WaveopticsError(f"--batch {self.batch!r} is not allowed; use an integer >= 1 (wavelengths per task)")

    @property
    def n_batches(self) -> int:
        return math.ceil(len(self.case.wavelengths()) / self.batch)

    def params(self) -> dict:
        return {**self.case.params(), "incident_theta_deg": list(self.thetas_deg), "incident_phi_deg": self.phi_deg,
                "realizations": int(self.realizations), "batch": int(self.batch),
                "surface_digest": self.surface_digest}

    def token(self) -> str:
        return _token({**self.params(), "format_version": TABLE_VERSION})


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
    return [TableTask(r, t, b, int(edges[b]), int(edges[b + 1]))
            for r in range(spec.realizations) for t in range(len(spec.thetas_deg)) for b in range(nb)]


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
    t0, c0 = time.perf_counter(), time.thread_time()
    case = spec.case
    w = case.wavelengths()
    nano = _nano(case, task.r, w, surface)
    wi = direction_from_angles(spec.thetas_deg[task.t], spec.phi_deg)
    grid = DirectionGrid.hemisphere(case.resolution)
    L = twoscale.evaluate(wi, w[task.lo:task.hi], get_material(case.material), case.micro(), nano, grid,
                          solver=case.solver, kd=case.kd, device=device, precision=case.precision)
    total, mf = L.total, L.microfacet
    for name, a in (("two-scale", total), ("microfacet", mf)):
        # the promise of the project: never NaN, Inf or negative
        if not np.all(np.isfinite(a)) or np.any(a < 0):
            raise WaveopticsError(f"table task {task.name} (θi={spec.thetas_deg[task.t]:g}°, "
                                  f"{w[task.lo]:g}-{w[task.hi - 1]:g} nm): the {name} BRDF has NaN, Inf or "
                                  "negative values")
    return {"total": total.astype(np.float32), "microfacet": mf.astype(np.float32), "albedo": L.albedo("total"),
            "microfacet_albedo": L.albedo("microfacet"), "solver": L.info["solver"],
            "cost_s": time.perf_counter() - t0, "cpu_s": time.thread_time() - c0, "host": socket.gethostname(),
            "pid": os.getpid()}


def _table_surface(case: Case, realizations: int):
    """(tiles or None, digest): the height-field tiles a table needs, loaded in the client."""
    if case.surface is None:
        return None, None
    hf = case.surface if isinstance(case.surface, surfaces.HeightField) else surfaces.load(case.surface)
    tiles = split_patch(hf, realizations) if realizations > 1 else [hf]
    return tiles, surface_digest(hf)


def _check_realizations(case: Case, realizations: int) -> None:
    if realizations > 1 and case.surface is None:
        nano = simulate.make_nano(case.nano, case.wavelengths(), solver=case.solver, seed=case.seed)
        if nano is None or nano.model is not None:
            raise WaveopticsError(f"--realizations {realizations} needs height fields (a SURFACE file, or --nano "
                                  "with --solver fft/direct); the PSD route is already the ensemble mean")


def partial_path(output) -> Path:
    """The partial store of an output: ``OUT.partial`` (a directory)."""
    p = Path(output)
    return p.with_name(p.name + ".partial")


def run_table(spec: TableSpec, output, *, surface=None, workers: int | None = None, scheduler: str | None = None,
              client=None, resume: bool = False, overwrite: bool = False, device: str | None = None,
              progress=None, retries: int = DEFAULT_RETRIES, task_fn: Callable = compute_block) -> dict:
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

    Returns
    -------
    dict
        ``output``, ``tasks`` (total), ``computed`` (this run), ``skipped`` (already done), ``written`` (task
        names in the order they were stored), ``wall_s``, ``task_cost_s`` (sum of the tasks' wall times),
        ``task_costs_s`` / ``task_cpu_s`` (per task computed now, in storage order: wall and CPU seconds on the
        worker), ``timings_s`` (client side: ``start_s``, ``compute_s``, ``store_s``, ``stop_s``, ``assemble_s``)
        and ``complete`` (True).
    """
    t0 = time.perf_counter()
    final = Path(output)
    partial = partial_path(final)
    if resume and final.exists() and not partial.exists():
        info = table_info(final)
        if info.get("token") != _table_token(spec, surface):
            raise WaveopticsError(f"--resume: {str(final)!r} is complete but was made with different parameters; "
                                  "pass --overwrite to recompute it")
        n = len(table_tasks(spec))
        return {"output": str(final), "tasks": n, "computed": 0, "skipped": n, "written": [],
                "wall_s": time.perf_counter() - t0, "task_cost_s": 0.0, "task_costs_s": [], "task_cpu_s": [],
                "timings_s": {}, "complete": True}
    case = spec.case.validate()
    _check_realizations(case, spec.realizations)
    _check_cluster_args(workers, scheduler)
    _refuse_or_prepare(final, partial, resume=resume, overwrite=overwrite)
    if surface is not None:
        tiles = split_patch(surface, spec.realizations) if spec.realizations > 1 else [surface]
        digest = surface_digest(surface)
    else:
        tiles, digest = _table_surface(case, spec.realizations)
    spec = dataclasses.replace(spec, surface_digest=digest)
    token = spec.token()
    store = _Store(partial, {"kind": "table", "token": token, "parameters": spec.params()}, resume=resume)
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
        _warm(cl, [case], device)
        tile_refs = cl.scatter(tiles, broadcast=False, hash=False) if tiles is not None else None
        return [_Job(f"wo-table-{token}-{t.name}", task_fn,
                     (spec, t, None if tile_refs is None else tile_refs[t.r], device)) for t in todo]

    _run_timed(client, workers, scheduler, bool(todo), submit, on_result, timings, retries=retries,
               progress=progress)
    t = time.perf_counter()
    _assemble_table(spec, token, store, final, overwrite=overwrite or resume)
    store.remove()
    timings["assemble_s"] = time.perf_counter() - t
    return {"output": str(final), "tasks": len(tasks), "computed": len(written), "skipped": len(tasks) - len(todo),
            "written": written, "wall_s": time.perf_counter() - t0, "task_cost_s": float(sum(costs)),
            "task_costs_s": costs, "task_cpu_s": cpus, "timings_s": timings, "complete": True}


def _run_timed(client, workers, scheduler, needed: bool, submit, on_result, timings: dict, *, retries, progress):
    """Open a client (unless *client* is given), build the jobs with ``submit(client)``, run them, close; record
    ``start_s`` (cluster start, worker warm-up, scatter), ``compute_s`` (first submit to last stored result) and
    ``stop_s`` (cluster shutdown) in *timings*."""
    if not needed:
        return
    t = time.perf_counter()
    with contextlib.ExitStack() as stack:
        cl = client if client is not None else stack.enter_context(dask_client(workers, scheduler))
        jobs = submit(cl)
        t1 = time.perf_counter()
        timings["start_s"] = t1 - t
        _run_jobs(cl, jobs, on_result, retries=retries, progress=progress)
        t = time.perf_counter()
        timings["compute_s"] = t - t1
    timings["stop_s"] = time.perf_counter() - t


def table_plan(spec: TableSpec, output, *, resume: bool = False) -> dict:
    """How many tasks a run of *spec* into *output* has in all and still to do (for progress bars)."""
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


def _assemble_table(spec: TableSpec, token: str, store: _Store, final: Path, *, overwrite: bool) -> None:
    """Write the HDF5 table from the block files (streaming one (θ, batch) at a time), atomically."""
    import h5py

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
            acc = None
            for task in group:
                with np.load(store.path(task.name, ".npz")) as z:
                    tot = z["total"]
                    acc = tot.astype(np.float64) if acc is None else acc + tot
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
        rgb = f.create_dataset("rgb", (n_t, grid.n_v, grid.n_u, 3), np.float32, chunks=(1, grid.n_v, grid.n_u, 3),
                               **comp)
        rgb_mf = f.create_dataset("microfacet_rgb", rgb.shape, np.float32, chunks=rgb.chunks, **comp)
        for it in range(n_t):  # RGB needs the whole spectrum: one incident angle at a time
            rgb[it] = spectral.reflectance_to_rgb(np.moveaxis(d_brdf[it], 0, -1), w, case.illuminant)
            rgb_mf[it] = spectral.reflectance_to_rgb(np.moveaxis(d_mf[it], 0, -1), w, case.illuminant)
        f.create_dataset("albedo", data=alb)
        f.create_dataset("microfacet_albedo", data=alb_mf)
        f.create_dataset("albedo_rgb", data=spectral.reflectance_to_rgb(alb, w, case.illuminant))
        f.create_dataset("microfacet_albedo_rgb", data=spectral.reflectance_to_rgb(alb_mf, w, case.illuminant))
        f.create_dataset("task_cost_s", data=cost).attrs["units"] = "s"
        f.create_dataset("task_cpu_s", data=cpu).attrs["units"] = "s"
        f.attrs["solver"] = ",".join(sorted(solvers))
        dims = {"brdf": ("theta_i", "wavelength", "v", "u"), "microfacet": ("theta_i", "wavelength", "v", "u"),
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


def table_info(path) -> dict:
    """The attributes of a table file (``format``, ``token``, ``parameters`` as a dict, ...)."""
    import h5py

    p = Path(path)
    if not p.is_file():
        raise WaveopticsError(f"table {str(p)!r} does not exist")
    try:
        with h5py.File(p, "r") as f:
            attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
    except OSError as exc:
        raise WaveopticsError(f"{str(p)!r} is not a readable HDF5 file ({exc})") from None
    if attrs.get("format") != TABLE_FORMAT:
        raise WaveopticsError(f"{str(p)!r} is not a waveoptics BRDF table (format attribute {attrs.get('format')!r})")
    attrs["parameters"] = json.loads(attrs["parameters"])
    return attrs


def read_table(path) -> BRDFTable:
    """Load a table written by :func:`run_table` into memory."""
    import h5py

    info = table_info(path)
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
                         params=info["parameters"], attrs=info, brdf_realizations=get("brdf_realizations"))


# ----------------------------------------------------------------------------------------------------------------
# Sweeps
# ----------------------------------------------------------------------------------------------------------------

def _split_values(text: str) -> list[str]:
    # ';' separates values that may contain commas themselves (f0:0.9,0.6,0.3)
    sep = ";" if ";" in text else ","
    vals = [v.strip() for v in text.split(sep) if v.strip()]
    if not vals:
        raise WaveopticsError(f"--vary: no values in {text!r}")
    return vals


def parse_length_list(text: str, *, name: str = "length") -> list[float]:
    """Lengths in metres from ``"1nm,5nm"`` or ``"1nm:20nm:5"`` (START:STOP:STEP, a bare STEP takes START's
    unit, STOP included when on the grid; see :func:`waveoptics.units.parse_number_list`)."""
    s = str(text).strip()
    if ":" not in s:
        return [parse_length(p, name=name, allow_zero=True) for p in _split_values(s)]
    parts = [p.strip() for p in s.split(":")]
    if len(parts) != 3:
        raise WaveopticsError(f"{name} {text!r} is not a length list; write 1nm:20nm:5 or 1nm,5nm,10nm")
    unit = next((u for u in sorted(LENGTH_UNITS, key=len, reverse=True) if parts[0].endswith(u)), None)
    if unit is None:
        raise WaveopticsError(f"{name} {text!r}: START needs a unit (e.g. 1nm:20nm:5)")
    nums = [parse_length(p, default_unit=unit, name=name, allow_zero=True) / LENGTH_UNITS[unit] for p in parts]
    vals = parse_number_list(":".join(f"{x:.17g}" for x in nums), name=name)
    return [float(v) * LENGTH_UNITS[unit] for v in vals]


def _set_nano_param(case: Case, key: str, value) -> Case:
    if case.surface is not None:
        raise WaveopticsError(f"--vary {key}: the nano roughness is a height-field file; vary --nano parameters "
                              "only with --nano MODEL:params")
    model, p = simulate.parse_nano(case.nano)
    key = simulate._ALIASES.get(key, key)
    if key not in simulate.NANO_PARAMS[model]:
        raise WaveopticsError(f"--vary nano.{key}: {model} has no parameter {key!r}; allowed: "
                              f"{', '.join(simulate.NANO_PARAMS[model])}")
    p[key] = value
    kinds = simulate.NANO_PARAMS[model]
    text = ",".join(f"{k}={v:.17g}m" if kinds[k] == "length" else f"{k}={v:.17g}" for k, v in p.items())
    return dataclasses.replace(case, nano=f"{model}:{text}")


def _vary_nano(key: str):
    def parse(text, model_kind):
        if model_kind == "length":
            return parse_length_list(text, name=f"--vary nano.{key}")
        return [float(v) for v in parse_number_list(text, name=f"--vary nano.{key}")]
    return parse


#: --vary NAME -> (help, parser of the value list, setter (case, value) -> case)
VARY = {
    "material": ("material names (';' separates values that contain commas)",
                 lambda s: _split_values(s), lambda c, v: dataclasses.replace(c, material=v)),
    "sigma_nano": ("rms height of the nano roughness, lengths (1nm:20nm:5 or 2nm,5nm)",
                   lambda s: parse_length_list(s, name="--vary sigma_nano"),
                   lambda c, v: _set_nano_param(c, "sigma", v)),
    "micro_alpha": ("micro NDF roughness α", lambda s: [float(x) for x in parse_number_list(s, name="--vary "
                                                                                                  "micro_alpha")],
                    lambda c, v: dataclasses.replace(c, micro_alpha=v)),
    "theta": ("incident zenith angle, degrees", lambda s: [float(x) for x in parse_number_list(s, name="--vary theta")],
              lambda c, v: dataclasses.replace(c, incident_deg=(v, c.incident_deg[1]))),
    "kd": ("diffuse albedo of a dielectric", lambda s: [float(x) for x in parse_number_list(s, name="--vary kd")],
           lambda c, v: dataclasses.replace(c, kd=v)),
    "ndf": ("micro NDF name (ggx, beckmann)", lambda s: _split_values(s), lambda c, v: dataclasses.replace(c, ndf=v)),
    "illuminant": ("light source (';' separates values that contain commas)", lambda s: _split_values(s),
                   lambda c, v: dataclasses.replace(c, illuminant=v)),
}


def parse_vary(text: str, base: Case | None = None) -> tuple[str, list]:
    """Parse one ``--vary NAME=VALUES`` into (name, values); names: :data:`VARY` or ``nano.KEY``."""
    name, eq, values = str(text).partition("=")
    name = name.strip()
    if not eq or not values.strip():
        raise WaveopticsError(f"--vary {text!r} is not NAME=VALUES (e.g. material=Au,Ag,Cu or sigma_nano=1nm:20nm:5)")
    if name.startswith("nano."):
        key = simulate._ALIASES.get(name[5:], name[5:])
        model = simulate.parse_nano(base.nano)[0] if base is not None and base.nano else None
        kind = simulate.NANO_PARAMS.get(model, {}).get(key, "length" if key in ("sigma", "T", "B") else "number")
        vals = _vary_nano(key)(values, kind)
    elif name in VARY:
        vals = VARY[name][1](values)
    else:
        raise unknown("--vary parameter", name, [*VARY, "nano.KEY"])
    if not vals:
        raise WaveopticsError(f"--vary {text!r} gives no values")
    return name, vals


def apply_vary(case: Case, name: str, value) -> Case:
    """*case* with parameter *name* set to *value*."""
    if name.startswith("nano."):
        return _set_nano_param(case, name[5:], value)
    return VARY[name][2](case, value)


def sweep_points(base: Case, varies: list[tuple[str, list]]) -> list[tuple[dict, Case]]:
    """The Cartesian product of the *varies* lists applied to *base*: [(values by name, case), ...]."""
    names = [n for n, _ in varies]
    if len(set(names)) != len(names):
        raise WaveopticsError("--vary: a parameter is given twice; list all its values in one --vary")
    out = []
    for combo in itertools.product(*(vals for _, vals in varies)):
        case = base
        for n, v in zip(names, combo):
            case = apply_vary(case, n, v)
        out.append((dict(zip(names, combo)), case.resolved()))
    return out


def sweep_point(case: Case, *, surface=None, sphere_size: int = 64, device=None) -> dict:
    """Simulate one sweep point on a worker and reduce it to summaries.

    *surface* (HeightField) replaces loading ``case.surface`` on the worker.

    Returns
    -------
    dict
        ``albedo_{R,G,B}`` and ``microfacet_albedo_{R,G,B}`` (linear sRGB of the directional albedo at the
        incident direction), ``albedo_mean`` / ``microfacet_albedo_mean`` (mean over wavelengths),
        ``dE_albedo`` (CIEDE2000 between the two albedo colours), ``dE_sphere_mean`` / ``dE_sphere_max``
        (per-pixel CIEDE2000 of sphere renders of both models, 0 with *sphere_size* 0), ``coherent_fraction``
        (mean over wavelengths), ``sigma_nano_m``, ``solver``, ``n_wavelengths``, ``cost_s`` (wall time, s).
    """
    t0 = time.perf_counter()
    sim = simulate.simulate(case.material, nano=case.nano,
                            surface=surface if surface is not None else case.surface, micro_alpha=case.micro_alpha,
                            ndf=case.ndf, shadowing=case.shadowing, incident=case.incident_deg,
                            illuminant=case.illuminant, wavelengths=case.wavelengths(),
                            resolution=case.resolution, solver=case.solver, kd=case.kd, sphere=sphere_size > 0,
                            seed=case.seed, device=device, precision=case.precision)
    rgb, rgb_mf = sim.rgb_albedo("total"), sim.rgb_albedo("microfacet")
    row = {f"albedo_{c}": float(rgb[i]) for i, c in enumerate("RGB")}
    row.update({f"microfacet_albedo_{c}": float(rgb_mf[i]) for i, c in enumerate("RGB")})
    row["albedo_mean"] = float(np.mean(sim.lobes.albedo("total")))
    row["microfacet_albedo_mean"] = float(np.mean(sim.lobes.albedo("microfacet")))
    row["dE_albedo"] = float(spectral.delta_e2000(rgb, rgb_mf))
    if sphere_size > 0:
        _, _, dE, mask = simulate.render_spheres(sim, sphere_size)
        row["dE_sphere_mean"] = float(dE[mask].mean()) if mask.any() else 0.0
        row["dE_sphere_max"] = float(dE[mask].max()) if mask.any() else 0.0
    else:
        row["dE_sphere_mean"] = row["dE_sphere_max"] = 0.0
    row["coherent_fraction"] = float(np.mean(sim.lobes.coherent_specular_fraction()))
    row["sigma_nano_m"] = float(sim.params["sigma_nano_m"])
    row["solver"] = sim.params["solver"]
    row["n_wavelengths"] = int(sim.wavelengths_nm.size)
    row["cost_s"] = time.perf_counter() - t0
    return row


#: columns of a sweep table after the varied parameters
SWEEP_COLUMNS = ("albedo_R", "albedo_G", "albedo_B", "microfacet_albedo_R", "microfacet_albedo_G",
                 "microfacet_albedo_B", "albedo_mean", "microfacet_albedo_mean", "dE_albedo", "dE_sphere_mean",
                 "dE_sphere_max", "coherent_fraction", "sigma_nano_m", "solver", "n_wavelengths", "cost_s")


def _is_length(name: str) -> bool:
    key = name[5:] if name.startswith("nano.") else None
    return name == "sigma_nano" or any(kinds.get(key) == "length" for kinds in simulate.NANO_PARAMS.values())


def value_text(name: str, v) -> str:
    """A swept value as written in the table: lengths with a unit (``6nm``, ``1.5um``), numbers with 6 digits."""
    if _is_length(name) and isinstance(v, float):
        return f"{v * 1e9:.6g}nm" if abs(v) < 1e-6 else f"{v * 1e6:.6g}um"
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def run_sweep(base: Case, varies: list[tuple[str, list]], output, *, surface=None, sphere_size: int = 64,
              workers: int | None = None, scheduler: str | None = None, client=None, resume: bool = False,
              overwrite: bool = False, device: str | None = None, progress=None,
              retries: int = DEFAULT_RETRIES, task_fn: Callable = sweep_point) -> dict:
    """Run a parameter sweep on Dask and write a table of summaries (CSV, or JSON if *output* ends in .json).

    One task per sweep point; finished rows stream into ``OUT.partial/`` exactly like table blocks (see
    :func:`run_table` for *surface*, *resume*, *overwrite*, *workers*, *scheduler*, *client*, *retries*).

    Returns
    -------
    dict
        ``output``, ``rows`` (list of dicts, in sweep order), ``points``, ``computed``, ``skipped``, ``wall_s``.
    """
    t0 = time.perf_counter()
    final = Path(output)
    if final.suffix.lower() not in (".csv", ".json"):
        raise WaveopticsError(f"sweep output {str(final)!r}: use a .csv or .json file name")
    points = sweep_points(base, varies)
    partial = partial_path(final)
    for _, case in points:
        case.validate()
    params = {"base": base.params(), "vary": [[n, list(vals)] for n, vals in varies],
              "sphere_size": int(sphere_size)}
    hf = surface
    if hf is None and base.surface is not None:
        hf = surfaces.load(base.surface)
    if hf is not None:
        params["surface_digest"] = surface_digest(hf)
    token = _token(params)
    if resume and final.exists() and not partial.exists():
        return {"output": str(final), "rows": read_sweep(final), "points": len(points), "computed": 0,
                "skipped": len(points), "wall_s": time.perf_counter() - t0}
    _check_cluster_args(workers, scheduler)
    _refuse_or_prepare(final, partial, resume=resume, overwrite=overwrite)
    store = _Store(partial, {"kind": "sweep", "token": token, "parameters": params}, resume=resume)
    names = [f"p{i:05d}" for i in range(len(points))]
    todo = [i for i, n in enumerate(names) if not store.has(n, ".json")]
    computed = []
    timings = dict.fromkeys(("start_s", "compute_s", "store_s", "stop_s"), 0.0)

    def on_result(job, row):
        t = time.perf_counter()
        i = job.args[0]
        io.write_json(store.path(names[i], ".json"), row)
        computed.append(names[i])
        timings["store_s"] += time.perf_counter() - t

    def submit(cl):
        _warm(cl, [c for _, c in points], device)
        hf_ref = cl.scatter(hf, broadcast=False, hash=False) if hf is not None else None
        return [_Job(f"wo-sweep-{token}-{names[i]}", _sweep_task,
                     (i, points[i][1], task_fn, hf_ref, sphere_size, device)) for i in todo]

    _run_timed(client, workers, scheduler, bool(todo), submit, on_result, timings, retries=retries,
               progress=progress)
    rows = []
    for i, (vals, case) in enumerate(points):
        row = json.loads(store.path(names[i], ".json").read_text())
        rows.append({"point": i, **{n: value_text(n, v) for n, v in vals.items()}, **row})
    _write_rows(rows, final, [n for n, _ in varies], overwrite=overwrite or resume)
    store.remove()
    return {"output": str(final), "rows": rows, "points": len(points), "computed": len(computed),
            "skipped": len(points) - len(todo), "wall_s": time.perf_counter() - t0, "timings_s": timings}


def _sweep_task(i, case, task_fn, surface, sphere_size, device):
    # i is unused by the computation; it ties the result to its point in on_result
    return task_fn(case, surface=surface, sphere_size=sphere_size, device=device)


def _write_rows(rows, final: Path, varied: list[str], *, overwrite: bool) -> None:
    if final.suffix.lower() == ".json":
        io.write_json(final, rows, overwrite=overwrite)
        return
    import csv

    cols = ["point", *varied, *SWEEP_COLUMNS]
    with io.atomic_path(final, overwrite=overwrite) as tmp, open(tmp, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=cols, extrasaction="ignore")
        wr.writeheader()
        for r in rows:
            wr.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in r.items()})


def read_sweep(path) -> list[dict]:
    """Rows of a sweep table (CSV values as text, JSON as written)."""
    p = Path(path)
    if p.suffix.lower() == ".json":
        return json.loads(p.read_text())
    import csv

    with open(p, newline="") as fh:
        return list(csv.DictReader(fh))
