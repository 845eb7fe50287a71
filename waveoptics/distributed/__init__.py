"""BRDF tables and parameter sweeps on Dask.

Files: cases (a simulation request as a task), cluster (Dask client and job loop), store (resumable partial
results), table (HDF5 BRDF tables), glass_table (BSDF tables of a rough glass over the sphere), sweep (parameter sweeps to CSV).
"""
from .cases import (case_from_scene, surface_digest)
from .cluster import (LOOPBACK, dask_client, local_cluster, WarmWorker, DEFAULT_RETRIES)
from .store import (partial_path, check_resume_overwrite)
from .table import (TABLE_FORMAT, TABLE_VERSION, DEFAULT_BATCH, TABLE_LAYOUT, TableSpec, TableTask, table_tasks,
    compute_block, table_size, check_table_size, run_table, table_plan, BRDFTable, table_info, read_table,
    open_table)
from .glass_table import (GLASS_TABLE_FORMAT, GLASS_TABLE_VERSION, GLASS_TABLE_LAYOUT, REFINE_RESOLUTION, glass_models,
    check_glass_case, glass_nodes, glass_incidences, compute_glass_block, assemble_glass_table, open_glass_table)
from .sweep import (MAX_SWEEP_POINTS, parse_length_list, VARY, parse_vary, apply_vary, sweep_points, sweep_point,
    SWEEP_COLUMNS, value_text, run_sweep, read_sweep)
from . import cases, cluster, store, table, glass_table, sweep  # noqa: F401

__all__ = cases.__all__ + cluster.__all__ + store.__all__ + table.__all__ + glass_table.__all__ + sweep.__all__
