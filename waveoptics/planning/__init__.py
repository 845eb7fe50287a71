"""Scene files and the effect planner.

Files: scene (TOML scene files and their validation), decisions (the physics of each decision), costmodel (time
estimates calibrated on this machine), planner (:func:`plan_scene`), runner (executing a plan), estimate (the time of a simulate or scatter request
before it runs).
"""
from .scene import *  # noqa: F401,F403
from .decisions import *  # noqa: F401,F403
from .costmodel import *  # noqa: F401,F403
from .planner import *  # noqa: F401,F403
from .runner import *  # noqa: F401,F403
from .estimate import *  # noqa: F401,F403
from . import scene, decisions, costmodel, planner, runner, estimate  # noqa: F401

__all__ = scene.__all__ + decisions.__all__ + costmodel.__all__ + planner.__all__ + runner.__all__ + estimate.__all__
