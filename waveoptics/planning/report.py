"""The plan as text: every decision with its value and reason, and the estimated cost (``waveoptics plan``).
"""
from __future__ import annotations

import numpy as np

__all__ = ['plan_table']


def plan_table(plan) -> str:
    """The :class:`~waveoptics.planning.plan.Plan` *plan* as a text table: every decision with its value and reason,
    and the estimated cost."""
    sc = plan.scene
    lines = [f"scene {sc.name}" + (f" ({sc.path})" if sc.path else "") + f": accuracy ΔE2000 ≤ {sc.delta_e:g}"]
    for e in plan.entries:
        lines.append("")
        lines.append(f"{e.name} ({e.material.name}, {e.material.category}) under {e.light_name} ({e.spd.name}): "
                     f"estimated {fmt_s(e.estimated_time_s)}")
        w = max(len(d) for d, _, _ in e.decisions)
        v = min(24, max(len(str(val)) for _, val, _ in e.decisions))
        for d, val, r in e.decisions:
            lines.append(f"  {d:<{w}}  {str(val):<{v}}  {r}")
    lines.append("")
    lines.append(f"total estimated {fmt_s(plan.estimated_time_s)} (planning took {fmt_s(plan.planning_time_s)}; "
                 f"cost model calibrated in {fmt_s(plan.cost_model.calibration_s)})")
    return "\n".join(lines)


def fmt_s(t: float) -> str:
    return f"{t * 1e3:.0f} ms" if t < 1 else f"{t:.1f} s"


def fmt_nm(w) -> str:
    w = np.asarray(w, dtype=float)
    if w.size == 0:
        return "none"
    if w.size > 4 and np.allclose(np.diff(w), w[1] - w[0]):
        return f"{w.size} ({w[0]:g}-{w[-1]:g} nm step {w[1] - w[0]:g})"
    return ", ".join(f"{x:g}" for x in w) + " nm"
