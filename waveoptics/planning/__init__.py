"""Scene files and the effect planner.

Files: scene (TOML scene files and their validation), decisions (the physics of each decision), costmodel (time
estimates calibrated on this machine), thresholds (the numbers the decisions compare against), force (overriding a
decision), colour_estimate (the coarse colour shift of diffraction), effects (the decisions on physical effects),
numerics (grid, directions, solver, precision), plan (the plan's data types), report (the plan as text), planner
(:func:`plan_scene`), runner (executing a plan), estimate (the time of a simulate or scatter request
before it runs).
"""
from .scene import (KEYS, CAMERAS, DEFAULT_DELTA_E, DEFAULT_LIGHT_DIRECTIONS, NanoSpec, MaterialSpec, LightSpec,
    ViewSpec, OutputSpec, Scene, parse, load, request_of)
from .decisions import (DE_PER_RELATIVE_Y, LSTAR_SLOPE_BLACK, LAMBDA_REF_NM, EPS32, scattered_fraction, lobe_width,
    diffraction_lobe_width, grid_step, float32_floor, weakest_level, grating_orders, ORDER_EFFICIENCY_MIN,
    first_order_g)
from .costmodel import (CostModel, fft_units, fft_solver_units, psd_terms, band_table_time, calibrate,
    calibrate_direct, machine_busy, calibration, direct_calibration)
from .thresholds import (ESTIMATE_RESOLUTION, ESTIMATE_RESOLUTION_MAX, ESTIMATE_STEP_NM, ESTIMATE_SPHERE_THETAS, ESTIMATE_SHARE, PSD_G_MAX,
    FLAT_SCATTER, PLAN_RESOLUTION_RANGE, PATCH_SIGMAS, F_FLAT_TOL, FLOOR_MARGIN, KIRCHHOFF_GRAZING_DEG,
    RAYLEIGH_RICE_G_MAX, FILM_NODES_PER_FRINGE)
from .force import (FORCEABLE, parse_force)
from .colour_estimate import (colour_shift, resolved_lobes)
from .report import (plan_table)
from .plan import (EntryPlan, Plan)
from .planner import (plan_scene)
from .runner import (entry_prefix, output_files, EntryResult, run_entry, view_values, execute)
from .estimate import (LONG_REQUEST_S, simulation_time, scatter_time, MAX_REQUEST_S, time_budget)
from . import scene, decisions, costmodel, thresholds, force, colour_estimate, effects, numerics, report, plan, planner, runner, estimate  # noqa: F401

__all__ = scene.__all__ + decisions.__all__ + costmodel.__all__ + thresholds.__all__ + force.__all__ + colour_estimate.__all__ + effects.__all__ + numerics.__all__ + report.__all__ + plan.__all__ + planner.__all__ + runner.__all__ + estimate.__all__
