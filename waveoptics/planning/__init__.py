"""Scene files and the effect planner.

Files: scene (TOML scene files and their validation), decisions (the physics of each decision), costmodel (time
estimates calibrated on this machine), thresholds (the numbers the decisions compare against), force (overriding a
decision), colour_estimate (the coarse colour shift of diffraction), effects (the decisions on physical effects),
numerics (grid, directions, solver, precision), plan (the plan's data types), report (the plan as text), planner
(:func:`plan_scene`), runner (executing a plan), estimate (the time of a simulate or scatter request
before it runs).
"""
from .scene import *  # noqa: F401,F403
from .decisions import *  # noqa: F401,F403
from .costmodel import *  # noqa: F401,F403
from .thresholds import *  # noqa: F401,F403
from .force import *  # noqa: F401,F403
from .colour_estimate import *  # noqa: F401,F403
from .effects import *  # noqa: F401,F403
from .numerics import *  # noqa: F401,F403
from .report import *  # noqa: F401,F403
from .plan import *  # noqa: F401,F403
from .planner import *  # noqa: F401,F403
from .runner import *  # noqa: F401,F403
from .estimate import *  # noqa: F401,F403
from . import scene, decisions, costmodel, thresholds, force, colour_estimate, effects, numerics, report, plan, planner, runner, estimate  # noqa: F401

__all__ = scene.__all__ + decisions.__all__ + costmodel.__all__ + thresholds.__all__ + force.__all__ + colour_estimate.__all__ + effects.__all__ + numerics.__all__ + report.__all__ + plan.__all__ + planner.__all__ + runner.__all__ + estimate.__all__
