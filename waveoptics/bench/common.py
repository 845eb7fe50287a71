"""What every benchmark shares: the wavelength, the timer (best of several repeats after a warm-up), the record
of the machine the numbers depend on, and the test problem (a Gaussian patch and directions over the hemisphere).
"""
from __future__ import annotations

import os
import platform
import time

import numpy as np

from .. import scatter
from ..surfaces.heightfield import HeightField
from ..units import direction_from_angles

__all__ = ['WAVELENGTH_NM', 'best_time', 'machine']

#: nm, the benchmark wavelength
WAVELENGTH_NM = 500.0


def best_time(fn, repeat: int = 3, min_time: float = 0.0) -> float:
    """Best wall time (s) of *fn()* over *repeat* calls (more while the total is below *min_time*), after one
    warm-up call."""
    fn()
    times = []
    t_all = time.perf_counter()
    while len(times) < repeat or (time.perf_counter() - t_all < min_time and len(times) < 50):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def machine(rt=None) -> dict:
    """CPU, core count, load and the OpenCL device (what the numbers depend on)."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    out = {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__}
    try:
        out["load_average_1min"] = os.getloadavg()[0]
    except OSError:
        pass
    if rt is not None:
        out["device"] = rt.name
        out["platform"] = rt.device.platform.version.strip()
        out["fp64"] = bool(rt.fp64)
    return out


def bench_problem(n: int, n_dir: int, seed: int = 1):
    """An n × n Gaussian patch (σ = 60 nm, dx = λ/4) and n_dir directions spread over the hemisphere."""
    rng = np.random.default_rng(seed)
    hf = HeightField(rng.normal(0.0, 60e-9, (n, n)), WAVELENGTH_NM * 1e-9 / 4)
    smp = scatter.samples(hf)
    wi = scatter.grid.incident_dirs((30.0, 0.0))
    wo = direction_from_angles(np.degrees(np.arcsin(np.sqrt(rng.uniform(0, 0.98, n_dir)))),
                               rng.uniform(0, 360, n_dir))
    return smp, wi, wo
