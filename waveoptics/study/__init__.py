"""Studies of the simulator itself: what accuracy costs in time (accuracy_cost: one Kirchhoff configuration run at a
ladder of settings against a reference, the Pareto front and the cheapest setting meeting a target error). The
planner's own per-run cost model is :mod:`waveoptics.planning.costmodel`.
"""
from . import accuracy_cost  # noqa: F401

__all__ = []
