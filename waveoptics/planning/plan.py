"""What the planner decides: the plan of one (material, light) pair (:class:`EntryPlan`) and of a scene
(:class:`Plan`), as the runner executes them and ``waveoptics plan --json`` prints them.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import colour
from ..brdf import twoscale
from ..materials import Material
from ..request import SimulationRequest, request_default
from ..planning.scene import MaterialSpec, Scene
from ..simulate import sphere_evaluations
from .costmodel import CostModel
from .report import plan_table

__all__ = ['EntryPlan', 'Plan']


@dataclass
class EntryPlan:
    """Decisions for one (material, light) pair of a scene."""

    spec: MaterialSpec
    light_name: str
    spd: colour.SPD
    material: Material
    light_directions_deg: tuple
    micro: twoscale.Micro
    nano: twoscale.Nano | None               # what the solver uses (None: no diffraction)
    effects: dict
    solver: str
    resolution: int
    directions: str                          # "hemisphere" or "views"
    view_directions_deg: tuple
    wavelengths_nm: np.ndarray               # simulated wavelengths (empty: λ-independent, one evaluation)
    colour_wavelengths_nm: np.ndarray        # wavelengths the colour is integrated over
    precision: str
    kd: float
    sphere: bool
    estimated_time_s: float
    patches: list = field(default_factory=list)     # DirectionGrid per view direction (directions == "views")
    decisions: list = field(default_factory=list)  # (decision, value, reason)
    metrics: dict = field(default_factory=dict)
    forced: dict = field(default_factory=dict)
    diffraction: str = request_default("diffraction")   # diffraction model of the nano lobe
    request: SimulationRequest | None = None  # the scene's request with the decisions applied (the runner's input)

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def reasons(self) -> list:
        return [f"{d}: {v} — {r}" for d, v, r in self.decisions]

    @property
    def evaluations(self) -> int:

        return len(self.light_directions_deg) + (sphere_evaluations(self.micro, self.nano) if self.sphere else 0)

    def as_dict(self) -> dict:
        return {
            "name": self.name, "light": self.light_name, "material": self.material.name,
            "material_source": self.material.source, "category": self.material.category,
            "illuminant": self.spd.name, "effects": self.effects, "solver": self.solver,
            "resolution": self.resolution, "directions": self.directions,
            "light_directions_deg": [list(d) for d in self.light_directions_deg],
            "view_directions_deg": [list(d) for d in self.view_directions_deg],
            "wavelengths_nm": self.wavelengths_nm, "colour_wavelengths_nm": self.colour_wavelengths_nm,
            "evaluations": self.evaluations, "precision": self.precision, "diffraction": self.diffraction,
            "estimated_time_s": self.estimated_time_s, "reasons": self.reasons,
            "decisions": [{"decision": d, "value": v, "reason": r} for d, v, r in self.decisions],
            "metrics": self.metrics, "forced": self.forced,
        }


@dataclass
class Plan:
    """A scene's plan: one :class:`EntryPlan` per (material, light)."""

    scene: Scene
    entries: list
    cost_model: CostModel
    planning_time_s: float
    force: dict = field(default_factory=dict)

    @property
    def estimated_time_s(self) -> float:
        return float(sum(e.estimated_time_s for e in self.entries))

    def as_dict(self) -> dict:
        return {"scene": self.scene.name, "path": str(self.scene.path) if self.scene.path else None,
                "delta_e": self.scene.delta_e, "force": self.force,
                "materials": [e.as_dict() for e in self.entries],
                "estimated_time_s": self.estimated_time_s, "planning_time_s": self.planning_time_s,
                "cost_model": self.cost_model.as_dict()}

    def table(self) -> str:
        """The plan as a text table: every decision with its value and reason, and the estimated cost
        (:func:`waveoptics.planning.report.plan_table`)."""
        return plan_table(self)
