"""BRDF tables and parameter sweeps on Dask.

Files: cases (a simulation request as a task), cluster (Dask client and job loop), store (resumable partial
results), table (HDF5 BRDF tables), sweep (parameter sweeps to CSV).
"""
from .cases import *  # noqa: F401,F403
from .cluster import *  # noqa: F401,F403
from .store import *  # noqa: F401,F403
from .table import *  # noqa: F401,F403
from .sweep import *  # noqa: F401,F403
from . import cases, cluster, store, table, sweep  # noqa: F401

__all__ = cases.__all__ + cluster.__all__ + store.__all__ + table.__all__ + sweep.__all__
