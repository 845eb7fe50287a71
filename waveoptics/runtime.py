"""OpenCL runtime: device choice, contexts, queues and the program cache.

This module is the only one that creates OpenCL contexts or builds programs. Everything else asks it for
a :class:`Runtime` (context + queue + device facts) and for built programs.

Device choice
-------------
``select_device(spec)`` takes *spec* from the argument, else the ``WAVEOPTICS_DEVICE`` environment variable,
else ``PYOPENCL_TEST`` (the pyopencl test-suite convention), and matches it as a case-insensitive substring
of ``"<platform name> <device name>"``; a spec of the form ``P:D`` picks platform index P, device index D.
With no spec the first GPU wins, else the PoCL CPU device, else any device.

Programs
--------
Kernel sources live in the repository's top-level ``kernels/`` folder (``*.cl``, ``*.h``), shipped in the wheel as
``waveoptics/kernels``.
:func:`build_program` builds each (context, file, options) once and keeps it; the kernel directory is on the
include path so kernels can ``#include "wo_common.h"``, and pyopencl adds its own include directory so
``#include <pyopencl-complex.h>`` works. A failed build raises with the kernel file name and the build log.
"""
from __future__ import annotations

import functools
import hashlib
import os
import threading
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from .errors import FieldError, NoOpenCLError, WaveopticsError

__all__ = ['INSTALL_HINT', 'kernel_dir', 'kernel_source', 'platforms', 'opencl_available', 'device_spec_from_env', 'select_device', 'has_fp64', 'Runtime', 'get_runtime', 'build_options', 'build_program', 'program_kernel', 'program_cache_size', 'pocl_version', 'describe', 'cpu_workers', 'MEMORY_FRACTION', 'parse_size',
           'memory_limit', 'check_memory', 'parallel_map', 'parallel_imap']

INSTALL_HINT = ("no OpenCL platform found; install a CPU runtime with 'apt-get install pocl-opencl-icd' "
                "(or 'pip install pocl-binary-distribution'), or run 'make demo' which does it")


def kernel_dir() -> Path:
    """Directory holding the ``.cl`` and ``.h`` sources.

    They live in the repository's top-level ``kernels/`` folder; the wheel carries them inside the package as
    ``waveoptics/kernels`` (hatch ``force-include``), found with :func:`importlib.resources.files` as pyopencl and
    silx find theirs. A source checkout or an editable install reads ``kernels/`` beside the package directory.
    """
    packaged = Path(str(resources.files("waveoptics") / "kernels"))
    if packaged.is_dir():
        return packaged
    checkout = Path(__file__).resolve().parent.parent / "kernels"
    if checkout.is_dir():
        return checkout
    raise WaveopticsError(f"kernel sources not found: neither {packaged} (installed package) nor {checkout} "
                          "(source checkout) exists")


def kernel_source(filename: str) -> str:
    """Text of one kernel file, e.g. ``kernel_source("fresnel.cl")``."""
    path = kernel_dir() / filename
    if not path.is_file():
        raise WaveopticsError(f"kernel file {filename!r} not found in {kernel_dir()}")
    return path.read_text()


def _cl():
    try:
        import pyopencl as cl
    except ImportError as exc:  # pragma: no cover - dependency is mandatory
        raise NoOpenCLError(f"pyopencl is not importable ({exc}); reinstall with 'make demo'") from None
    return cl


def platforms():
    """All OpenCL platforms, or ``[]`` when there is no ICD loader or no platform."""
    cl = _cl()
    try:
        return cl.get_platforms()
    except cl.Error:  # PLATFORM_NOT_FOUND_KHR when no ICD is registered
        return []


def opencl_available() -> bool:
    """Whether at least one OpenCL device exists."""
    return any(_devices(p) for p in platforms())


def _devices(platform):
    cl = _cl()
    try:
        return platform.get_devices()
    except cl.Error:
        return []


def _device_label(platform, device) -> str:
    return f"{platform.name.strip()} {device.name.strip()}"


def device_spec_from_env() -> str | None:
    """The device request from ``WAVEOPTICS_DEVICE`` or ``PYOPENCL_TEST``, if any."""
    return os.environ.get("WAVEOPTICS_DEVICE") or os.environ.get("PYOPENCL_TEST") or None


def select_device(spec: str | None = None):
    """Choose an OpenCL device.

    Parameters
    ----------
    spec : str, optional
        Substring of ``"<platform> <device>"`` (case-insensitive) or ``"P:D"`` indices.
        Defaults to the environment (see module docstring).

    Returns
    -------
    pyopencl.Device
    """
    cl = _cl()
    spec = spec if spec else device_spec_from_env()
    plats = platforms()
    pairs = [(p, d) for p in plats for d in _devices(p)]
    if not pairs:
        raise NoOpenCLError(INSTALL_HINT)
    if spec:
        s = spec.strip()
        if ":" in s and all(part.isdigit() for part in s.split(":", 1)):
            pi, di = (int(x) for x in s.split(":", 1))
            try:
                return _devices(plats[pi])[di]
            except IndexError:
                pass
        else:
            for p, d in pairs:
                if s.lower() in _device_label(p, d).lower():
                    return d
        labels = "; ".join(_device_label(p, d) for p, d in pairs)
        raise NoOpenCLError(f"no OpenCL device matches {spec!r}; available: {labels}")
    for p, d in pairs:
        if d.type & cl.device_type.GPU:
            return d
    for p, d in pairs:
        if "portable computing language" in p.name.lower() or "pocl" in p.name.lower():
            return d
    return pairs[0][1]


def has_fp64(device) -> bool:
    """Whether *device* supports double precision (``cl_khr_fp64`` or a non-zero double FP config)."""
    try:
        if device.double_fp_config:
            return True
    except Exception:  # noqa: BLE001 - some drivers raise instead of returning 0
        pass
    return "cl_khr_fp64" in device.extensions


@dataclass(frozen=True)
class Runtime:
    """A context, an in-order queue and facts about the device."""

    context: object
    queue: object
    device: object
    fp64: bool

    @property
    def name(self) -> str:
        return self.device.name.strip()

    def require_fp64(self, what: str) -> None:
        """Raise a clear error when *what* needs float64 and the device lacks it."""
        if not self.fp64:
            raise FieldError(f"{what} needs float64, but device {self.name!r} has no fp64 support; use "
                             "precision='float32' or choose another {device}", "device")

    def real_dtype(self, precision: str):
        """numpy dtype for 'float32'/'float64', checking fp64 support."""
        if precision in ("float64", "double", "fp64"):
            self.require_fp64("precision float64")
            return np.float64
        if precision in ("float32", "single", "fp32"):
            return np.float32
        raise WaveopticsError(f"precision {precision!r} is not allowed; use float32 or float64")


_lock = threading.RLock()
_runtimes: dict = {}


def get_runtime(device: str | None = None) -> Runtime:
    """The process-wide :class:`Runtime` for a device spec (created once and kept)."""
    cl = _cl()
    dev = select_device(device)
    key = (dev.platform.name, dev.name, dev.int_ptr)
    with _lock:
        rt = _runtimes.get(key)
        if rt is None:
            ctx = cl.Context([dev])
            rt = Runtime(ctx, cl.CommandQueue(ctx), dev, has_fp64(dev))
            _runtimes[key] = rt
        return rt


_programs: dict = {}
_building: dict = {}   # key -> the lock of its build in progress


def build_options(precision_dtype=np.float32, extra=()) -> tuple[str, ...]:
    """Standard ``-D`` options: ``WO_DOUBLE`` for float64 builds, plus *extra*."""
    opts = []
    if np.dtype(precision_dtype) == np.float64:
        opts.append("-DWO_DOUBLE=1")
    opts.extend(extra)
    return tuple(opts)


def build_program(runtime: Runtime, filename: str, options=()):
    """Build kernel file *filename* for *runtime* with *options*, once; later calls return the same program.

    Raises
    ------
    WaveopticsError
        With the kernel file name and the compiler's build log when the build fails.
    """
    cl = _cl()
    src = kernel_source(filename)
    opts = tuple(options) + (f"-I{kernel_dir()}",)
    # headers included by the file count in the key so that an edited header rebuilds
    digest = hashlib.sha1(src.encode())
    for hdr in sorted(kernel_dir().glob("*.h")):
        digest.update(hdr.read_bytes())
    key = (id(runtime.context), filename, digest.hexdigest(), opts)
    with _lock:
        prg = _programs.get(key)
        if prg is not None:
            return prg
        building = _building.setdefault(key, threading.Lock())
    # one build per key, outside the process-wide lock: a program built in the background (a compiler run of
    # 0.5-2 s on PoCL) holds up neither get_runtime nor the build of another program
    with building:
        with _lock:
            prg = _programs.get(key)
        if prg is not None:
            return prg
        try:
            prg = cl.Program(runtime.context, src).build(options=list(opts))
        except cl.RuntimeError as exc:
            raise WaveopticsError(f"OpenCL build of kernels/{filename} failed on {runtime.name!r} "
                                  f"with options {' '.join(opts)}:\n{exc}") from None
        with _lock:
            _programs[key] = prg
            _building.pop(key, None)
        return prg


_thread_kernels = threading.local()


def program_kernel(program, name: str):
    """The kernel *name* of *program* for the calling thread, retrieved once per thread.

    A ``pyopencl.Kernel`` holds its arguments: a call sets them and then enqueues, so two threads calling one
    kernel object can enqueue each other's arguments (wrong buffers, reads out of bounds). Every OpenCL call is
    thread-safe except ``clSetKernelArg`` on one kernel object from several threads at once, whose result the
    specification leaves undefined (OpenCL 1.2, appendix A.2), so each thread keeps its own kernel objects; a
    kernel is retrieved once per thread (pyopencl warns on repeated retrieval through ``program.name``).

    References
    ----------
    .. [1] Khronos OpenCL Working Group, *The OpenCL Specification*, version 1.2, 2012, appendix A.2
       (multiple host threads).
    """
    cache = getattr(_thread_kernels, "cache", None)
    if cache is None:
        cache = _thread_kernels.cache = {}
    key = (id(program), name)
    hit = cache.get(key)
    if hit is None or hit[0] is not program:
        hit = cache[key] = (program, _cl().Kernel(program, name))
    return hit[1]


def program_cache_size() -> int:
    """Number of programs built so far (used by tests of the build-once rule)."""
    return len(_programs)


@functools.lru_cache(maxsize=1)
def pocl_version() -> str | None:
    """PoCL version string from its platform, if PoCL is present."""
    for p in platforms():
        if "portable computing language" in p.name.lower():
            return p.version
    return None


def describe() -> dict:
    """Platforms and devices as plain data (used by ``waveoptics info``)."""
    out = []
    for p in platforms():
        devs = []
        for d in _devices(p):
            devs.append({
                "name": d.name.strip(),
                "type": _cl().device_type.to_string(d.type),
                "compute_units": int(d.max_compute_units),
                "fp64": bool(has_fp64(d)),
                "max_work_group_size": int(d.max_work_group_size),
                "global_mem_bytes": int(d.global_mem_size),
                "opencl_version": d.version.strip(),
            })
        out.append({"name": p.name.strip(), "vendor": p.vendor.strip(), "version": p.version.strip(),
                    "devices": devs})
    return {"platforms": out}


def cpu_workers(workers: int | None = None) -> int:
    """Threads for CPU solvers: *workers* if given (>= 1), else ``WAVEOPTICS_WORKERS``, else the cores this process
    may run on (``os.sched_getaffinity``; a CI container's quota, not the host's core count)."""
    if workers is None:
        env = os.environ.get("WAVEOPTICS_WORKERS")
        if env:
            try:
                workers = int(env)
            except ValueError:
                raise FieldError(f"WAVEOPTICS_WORKERS={env!r} is not allowed; give a whole number >= 1",
                                 "workers") from None
    if workers is None:
        try:
            return max(1, len(os.sched_getaffinity(0)))
        except AttributeError:  # not on Linux
            return max(1, os.cpu_count() or 1)
    if int(workers) != workers or workers < 1:
        raise FieldError(f"workers={workers!r} is not allowed; give a whole number >= 1", "workers")
    return int(workers)


_pool_thread = threading.local()


def parallel_imap(fn, items, workers: int | None = None):
    """``fn(item)`` for each of *items*, yielded in the order of *items*, computed by a pool of
    :func:`cpu_workers` (*workers*) threads: for independent pieces of work that spend their time in NumPy, SciPy
    or OpenCL calls, which release the GIL (per-wavelength or per-incidence tables). With one worker, or one item,
    in the calling thread, one after the other. An exception of ``fn`` is raised when its item's turn comes; the
    items not started by then are cancelled.

    *fn* must not depend on the order in which items are computed, only on its item (each result is then the one a
    serial loop gives, bit for bit); results shared between items (caches) must be safe to fill from several
    threads. A call made by an item of another call runs serially in that item's thread: the outer call keeps the
    workers busy, and pools inside pools would multiply the threads (workers² on a many-core machine).
    """
    items = list(items)
    n = min(cpu_workers(workers), len(items))
    if n <= 1 or getattr(_pool_thread, "active", False):
        for item in items:
            yield fn(item)
        return
    from concurrent.futures import ThreadPoolExecutor

    def run(item):
        _pool_thread.active = True   # a thread of the pool: the calls its items make run serially
        return fn(item)

    pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix="waveoptics")
    try:
        futures = [pool.submit(run, item) for item in items]
        for fut in futures:
            yield fut.result()
    finally:   # on an exception, or a caller that stops early: the items not started are dropped
        pool.shutdown(wait=True, cancel_futures=True)


def parallel_map(fn, items, workers: int | None = None) -> list:
    """``[fn(item) for item in items]`` computed by :func:`parallel_imap` (threads; the same list, in order)."""
    return list(parallel_imap(fn, items, workers))


#: share of the machine's (or the container's) memory a request may plan to use unless told otherwise
MEMORY_FRACTION = 0.5

_SIZE_UNITS = {"b": 1, "kb": 1e3, "mb": 1e6, "gb": 1e9, "tb": 1e12, "kib": 2 ** 10, "mib": 2 ** 20, "gib": 2 ** 30,
               "tib": 2 ** 40}


def parse_size(text, *, name: str = "max_memory") -> int:
    """Bytes from ``"4GB"``, ``"500MiB"``, ``"2e9"`` (a bare number is bytes); finite and > 0."""
    import re

    m = re.fullmatch(r"\s*([0-9.]+(?:[eE][-+]?[0-9]+)?)\s*([A-Za-z]*)\s*", str(text))
    unit = (m.group(2) or "b").lower() if m else None
    if not m or unit not in _SIZE_UNITS:
        raise FieldError(f"{{{name}}} {text!r} is not a size; write e.g. 4GB, 500MiB", name)
    value = float(m.group(1)) * _SIZE_UNITS[unit]
    if not value > 0 or value == float("inf"):
        raise FieldError(f"{{{name}}} {text!r} is not allowed; it must be > 0", name)
    return int(value)


def _physical_memory() -> int:
    """Bytes of memory this process may use: the cgroup limit when a container sets one, else the RAM."""
    try:
        txt = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if txt.isdigit():
            return int(txt)
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 8 * 2 ** 30


def memory_limit(max_memory=None) -> int:
    """The memory budget of one request in bytes: *max_memory* (bytes or a size text), else
    ``WAVEOPTICS_MAX_MEMORY``, else :data:`MEMORY_FRACTION` of the machine's memory."""
    if max_memory is None:
        max_memory = os.environ.get("WAVEOPTICS_MAX_MEMORY")
    if max_memory is None:
        return int(MEMORY_FRACTION * _physical_memory())
    return parse_size(max_memory) if isinstance(max_memory, str) else int(max_memory)


def check_memory(estimate_bytes: float, what: str, advice: str, max_memory=None, fields=(), python=None) -> None:
    """Refuse, before any work, a request whose estimated memory exceeds the budget (:func:`memory_limit`): one
    line with the estimate, the budget and what to reduce (*advice* may name *fields* as ``{field}``; *python*: how
    the library writes a field whose plain name would read badly, as in :class:`~waveoptics.errors.FieldError`)."""
    limit = memory_limit(max_memory)
    if estimate_bytes > limit:
        raise FieldError(f"{what} needs about {estimate_bytes / 1e9:.3g} GB, above the {{max_memory}} budget of "
                         f"{limit / 1e9:.3g} GB; {advice}", "max_memory", *fields, python=python)

