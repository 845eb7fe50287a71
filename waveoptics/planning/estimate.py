"""How long a request will take, before it runs: the planner's cost model (:mod:`waveoptics.planning.costmodel`,
timed once per machine) applied to a ``simulate``/``compare`` request or a ``scatter`` run, so that the command
line can warn before a long wait (issue 17: "long ones warn with the estimate").

The estimates use the same terms as the planner's (docs/planning.md measures them against run times: within 3×, 1.1–1.2× on the scenes that diffract
on this machine's example scenes); they cover the lobes and the sphere table, not the writing of images.
"""
from __future__ import annotations

import math

import numpy as np

from .. import scatter
from ..brdf.field_lobe import FIELD_GRID_OVERSAMPLING
from ..brdf.twoscale_paraxial import field_albedo_evaluations
from ..materials import get_material
from ..request import SimulationRequest, make_nano
from ..scatter.grid import DirectionGrid
from ..simulate import sphere_evaluations
from ..units import direction_from_angles
from .costmodel import calibration, direct_calibration, fft_solver_units, psd_terms

__all__ = ["LONG_REQUEST_S", "MAX_REQUEST_S", "time_budget", "simulation_time", "scatter_time"]

#: a request estimated to take longer than this (s) is announced with its estimate before it starts
LONG_REQUEST_S = 60.0

#: the default time budget (s): a request estimated beyond it is refused before it starts, as one beyond the memory
#: budget is (``WAVEOPTICS_MAX_TIME`` sets another: seconds, or a number with s, min, h or d)
MAX_REQUEST_S = 24 * 3600.0

_TIME_UNITS = {"": 1.0, "s": 1.0, "min": 60.0, "m": 60.0, "h": 3600.0, "d": 86400.0}


def time_budget(text=None) -> float:
    """Seconds a request may be estimated to take: *text* (``"3600"``, ``"90min"``, ``"12h"``), else
    ``WAVEOPTICS_MAX_TIME``, else :data:`MAX_REQUEST_S`."""
    import os
    import re

    from ..errors import FieldError

    text = os.environ.get("WAVEOPTICS_MAX_TIME") if text is None else text
    if text is None:
        return MAX_REQUEST_S
    m = re.fullmatch(r"\s*([0-9.]+(?:[eE][-+]?[0-9]+)?)\s*([a-z]*)\s*", str(text).lower())
    value = float(m.group(1)) * _TIME_UNITS[m.group(2)] if m and m.group(2) in _TIME_UNITS else math.nan
    if not (math.isfinite(value) and value > 0):
        raise FieldError(f"{{max_time}} {text!r} is not a time budget; write seconds > 0 or e.g. 90min, 12h",
                         "max_time")
    return value


def simulation_time(req: SimulationRequest, *, sphere: bool = True, surface=None) -> float:
    """Estimated seconds of :func:`waveoptics.simulate.run` for *req* (its lobes at the light, and with *sphere* the
    diffracted lobes tabulated over incidence), from this machine's cost model."""
    cm = calibration()
    w = req.wavelengths()
    micro = req.micro()
    nano = make_nano(req.nano, w, solver=req.solver, seed=req.seed,
                     surface=surface if surface is not None else req.surface) if not req.split else None
    n_eval = 1 + (sphere_evaluations(micro, nano) if sphere else 0)
    cells = [req.resolution ** 2]
    diffuse = req.kd > 0 and not get_material(req.material).is_metal   # metals have no diffuse term
    if nano is None or nano.model is not None:
        terms = psd_terms(nano.model.sigma, float(w.min())) if nano is not None else None
        return (n_eval * cm.evaluation(cells, w.size, diffuse=diffuse, psd_terms=terms)
                + (cm.band_tables(w.size) if terms is not None else 0.0))
    base = n_eval * cm.evaluation(cells, w.size, diffuse=diffuse, nano_lobe=True)
    smp = scatter.samples(nano.surface)
    wi = direction_from_angles(*req.incident_deg)
    grid = DirectionGrid.hemisphere(req.resolution)
    # the coherent fraction: the field's lobe on a grid of λ/(3L) cells per wavelength and incidence
    per_incidence = sum(fft_solver_units(smp, wi, [DirectionGrid.hemisphere(int(np.ceil(
        FIELD_GRID_OVERSAMPLING * max(smp.extent) / (lam * 1e-9))))], [lam]) for lam in w)
    coherent = field_albedo_evaluations(micro, grid, wi, extra=n_eval - 1) * per_incidence
    return base + (n_eval * fft_solver_units(smp, wi, [grid], w) + coherent) * cm.fft_unit


def scatter_time(field, incident_deg, wavelengths_nm, resolution: int, solver: str = "fft", *, realizations=1,
                 device=None, precision="float32") -> float:
    """Estimated seconds of :func:`waveoptics.scatter.scatter` on a height field (fft: its chirp-z transforms;
    direct: the OpenCL sum, timed once per device; NaN where the device cannot run it)."""
    cm = calibration()
    smp = scatter.samples(field)
    grid = DirectionGrid.hemisphere(resolution)
    wi = direction_from_angles(*incident_deg)
    n_r = max(1, int(realizations))
    if solver == "direct":
        term, _ = direct_calibration(device, precision)
        if term is None:
            return math.nan
        return n_r * 2 * term * smp.size * int(grid.inside.sum()) * len(wavelengths_nm)
    return n_r * fft_solver_units(smp, wi, [grid], wavelengths_nm) * cm.fft_unit
