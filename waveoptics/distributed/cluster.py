"""BRDF tables and parameter sweeps on Dask (``dask.distributed``): task split, run, resume, writers.

A measured-style BRDF table (incident directions × wavelengths × surface realizations) or a sweep over materials
and roughnesses is split into independent, deterministic tasks and run on a Dask cluster:

* **table** — one task per (realization r, incident angle θ_i, wavelength batch): :func:`compute_block`
  evaluates the two-scale BRDF (:func:`waveoptics.brdf.twoscale.evaluate`) of that batch on the hemisphere grid.
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
import logging
import time
from typing import Callable, NamedTuple

import dask
from distributed import Client, LocalCluster, as_completed
from distributed.diagnostics.plugin import WorkerPlugin

from .. import runtime
from ..errors import FieldError, WaveopticsError
from ..materials import get_material

#: retries of a task that raises (a task lost with its worker is recomputed by the scheduler anyway)
DEFAULT_RETRIES = 2

__all__ = ['LOOPBACK', 'dask_client', 'local_cluster', 'WarmWorker', 'DEFAULT_RETRIES']

# ----------------------------------------------------------------------------------------------------------------
# Dask plumbing shared by tables and sweeps
# ----------------------------------------------------------------------------------------------------------------

#: LocalCluster options that keep every socket on loopback. ``dashboard_address=None`` alone is not enough: the
#: scheduler and each worker still serve health/metrics over HTTP, on all interfaces (0.0.0.0:8787 and a random
#: port) unless given an address; the dashboard itself stays off.
LOOPBACK = dict(dashboard_address=None, worker_dashboard_address="127.0.0.1:0",
                scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                # a task's error reaches the user once, as the one-line error of the command; the workers' own
                # ERROR logs of it ("Compute Failed", 20 lines with a traceback per task) are noise
                silence_logs=logging.CRITICAL)


def check_cluster_args(workers, scheduler) -> None:
    if workers is not None and scheduler is not None:
        raise FieldError("give either {workers} N (a local cluster) or {scheduler} ADDRESS, not both", "workers", "scheduler")
    if scheduler is not None and "://" not in str(scheduler):
        raise FieldError(f"{{scheduler}} {scheduler!r} is not a scheduler address; write tcp://HOST:PORT", "scheduler")
    if workers is not None and (int(workers) != workers or workers < 1):
        raise FieldError(f"{{workers}} {workers!r} is not allowed; use an integer >= 1", "workers")


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

    check_cluster_args(workers, scheduler)
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

    if workers is None:  # in-process transport (inproc://), no host to bind
        return LocalCluster(n_workers=1, threads_per_worker=1, processes=False, **LOOPBACK)
    # Dask's nanny sets MALLOC_TRIM_THRESHOLD_=65536 in new workers by default (to return memory to the OS); that
    # also fixes glibc's mmap threshold at 128 KiB, so every array of a lobe is a fresh mmap with page faults, and
    # a table task takes about twice the CPU time (measured in docs/scaling.md). Not set here.

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

        get_material(self.material)
        if self.solver == "direct":
            runtime.get_runtime(self.device)

    def teardown(self, worker=None):
        pass


def warm_workers(client, cases, device) -> None:
    """Register :class:`WarmWorker` for each distinct (material, solver) of *cases*."""
    for material, solver in dict.fromkeys((c.material, c.solver) for c in cases):
        plugin = WarmWorker(material, solver, device)
        client.register_plugin(plugin, name=plugin.name)


class Job(NamedTuple):
    key: str
    fn: Callable
    args: tuple


def _run_jobs(client, jobs: list, on_result: Callable, *, retries: int = DEFAULT_RETRIES, progress=None) -> None:
    """Submit *jobs* and hand each result to ``on_result(job, result)`` in the client as soon as it is done.

    Keys are deterministic, so a task lost with its worker is recomputed under the same key. If a task still
    fails after *retries*, the remaining futures are cancelled and its exception is raised; everything handed to
    *on_result* before that is kept.
    """

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


def run_timed(client, workers, scheduler, needed: bool, submit, on_result, timings: dict, *, retries, progress):
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


