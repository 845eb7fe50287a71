"""What accuracy costs in time: run one Kirchhoff configuration at a ladder of settings against a reference.

A *configuration* is a surface (a height-field file, or a generator model with a seed per realization), a
material, an incident direction and an illuminant. A *setting* is what a user chooses: the solver (``fft`` with
the banded Taylor series in v_z, ``fft0`` with v_z frozen at the specular value, ``direct`` on the OpenCL device),
the direction-grid resolution, the wavelengths (the grid :func:`waveoptics.colour.simulation_wavelengths`
chooses for a colour accuracy ΔE), the number of realizations and, for ``direct``, the precision. Each setting runs
:func:`waveoptics.scatter.scatter` once and is compared with a reference computed once at the finest
resolution, a denser wavelength grid and (for random surfaces) more realizations, by default with the direct
solver in float64:

``error_rel_l2``
    ‖E − E_ref‖₂ / ‖E_ref‖₂ over wavelengths × cells of the reflected energy per cell E = f du dv (the lobe as the
    grid sees it, cos θ_o dω_o = du dv). The reference is summed over blocks of cells onto the setting's grid and
    the setting is interpolated linearly in λ onto the reference wavelengths, so a coarse grid or a sparse
    spectrum is charged for what it misses.
``error_albedo``
    max over λ of |ρ − ρ_ref| of the directional albedo ρ = Σ f du dv (linear in λ as above).
``delta_e2000``
    CIEDE2000 between the linear-sRGB colours of the albedo spectra, each integrated over its own wavelengths
    under the illuminant (:func:`waveoptics.colour.reflectance_to_rgb`, :func:`waveoptics.colour.delta_e2000`).

The wall time of each setting is measured around the whole ``scatter`` call (lobes, albedo, coherent part).
The Pareto front holds the settings that no other setting beats in both time and the chosen error metric, and the
recommendation is the fastest setting whose error meets the target.

Random surfaces: the reference is run per realization (seeds seed .. seed + n_ref − 1) and a setting with n
realizations uses the first n of the same seeds, so the three errors above measure the numerical error of the
setting (solver, grid, spectrum, precision) on the same surfaces. ``ensemble_rel_l2`` compares it with the mean over
all n_ref reference realizations instead: that adds the speckle of averaging only n patches, i.e. what more
realizations buy. ``reference["noise_rel_l2"]`` is the relative standard error of the reference's own ensemble mean;
ensemble errors below it are not resolved. The relative L2 error of a smooth surface is dominated by its specular
spike; ``error_albedo`` and ``delta_e2000`` weigh the whole lobe by energy instead.

References
----------
.. [1] V. Pareto, *Manuale di economia politica*, 1906 (non-dominated set); K. Deb, *Multi-Objective Optimization
   using Evolutionary Algorithms*, Wiley, 2001, ch. 2 (dominance, the Pareto-optimal front).
.. [2] M. R. Luo, G. Cui, B. Rigg, "The development of the CIE 2000 colour-difference formula: CIEDE2000",
   Color Res. Appl. 26(5), 2001.
.. [3] docs/physics.md §1 (Kirchhoff BRDF, direction-cosine grid), §8 (colour).
"""
from __future__ import annotations

import dataclasses
import inspect
import itertools
import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import colour, scatter, surfaces
from ..errors import WaveopticsError, unknown
from ..io import figures
from ..io.figures import save_figure
from ..io.files import atomic_path, prepare_outdir, write_json
from ..request import NANO_RENAMED, nano_key
from ..runtime import get_runtime
from ..surfaces.heightfield import HeightField
from ..units import split_spec
from ..vocabulary import COST_BUDGET_S, COST_DELTA_E, COST_TARGET_ERROR

__all__ = ['STUDY_SOLVERS', 'METRICS', 'PRECISIONS', 'DEFAULT_SOLVERS', 'DEFAULT_RESOLUTIONS', 'DEFAULT_DELTA_E', 'DEFAULT_PRECISIONS', 'REFERENCE_REALIZATIONS', 'REFERENCE_SOLVERS', 'DEFAULT_TARGET_ERROR', 'DEFAULT_BUDGET_S', 'Config', 'model_config', 'parse_model', 'Setting', 'ladder', 'Run', 'errors', 'pareto_front', 'recommend', 'reference_setting', 'study', 'table', 'plot', 'FILES', 'write']

#: setting solver name -> keyword arguments of :func:`waveoptics.scatter.scatter`
STUDY_SOLVERS = {
    "fft0": {"solver": "fft", "order": 0},
    "fft": {"solver": "fft", "order": "auto"},
    "direct": {"solver": "direct"},
}
#: error metrics a Pareto front and a recommendation can be based on
METRICS = ("error_rel_l2", "error_albedo", "delta_e2000")
PRECISIONS = ("float32", "float64")
#: default ladder
DEFAULT_SOLVERS = ("fft0", "fft", "direct")
DEFAULT_RESOLUTIONS = (32, 64, 128)
DEFAULT_DELTA_E = COST_DELTA_E
DEFAULT_PRECISIONS = ("float32", "float64")
#: realizations of the reference for random surfaces (at least twice the ladder's largest)
REFERENCE_REALIZATIONS = 4
#: the command line's defaults (:mod:`waveoptics.vocabulary`, where the parser reads them without this module)
DEFAULT_TARGET_ERROR, DEFAULT_BUDGET_S = COST_TARGET_ERROR, COST_BUDGET_S


@dataclass(frozen=True)
class Config:
    """The configuration the study runs.

    Parameters
    ----------
    surface : HeightField or callable seed -> HeightField
        A fixed patch (realizations > 1 split it into tiles) or a generator of independent realizations.
    material : see :func:`waveoptics.materials.fresnel_function`
    incident : (θ, φ), degrees
    illuminant : str
        Light source (:func:`waveoptics.colour.illuminant`).
    random : bool
        Whether realizations are independent draws (a generator); only then do the ladder and the reference
        use more than one realization.
    seed : int
    name : str
    """

    surface: object
    material: object = None
    incident: tuple = (30.0, 0.0)
    illuminant: str = "D65"
    random: bool = False
    seed: int = 0
    name: str = "surface"

    def describe(self) -> dict:
        hf = self.surface(self.seed) if callable(self.surface) else self.surface
        return {"name": self.name, "material": None if self.material is None else str(self.material),
                "incident_deg": list(self.incident), "illuminant": str(self.illuminant), "random": self.random,
                "samples": list(hf.shape), "spacing_m": [hf.dx, hf.dy], "seed": self.seed}


def model_config(model: str, size="12.8um", samples=128, *, material=None, incident=(30.0, 0.0),
                 illuminant="D65", seed: int = 0, name: str | None = None) -> Config:
    """A :class:`Config` from a generator spec ``MODEL:key=value,...`` of :func:`waveoptics.surfaces.generate`.

    Models with a ``seed`` parameter are random: realization r is ``generate(..., seed=seed + r)``.
    Example: ``model_config("gaussian:sigma=20nm,corr_length=1um", "12.8um", 128)``.
    """
    kind, params = parse_model(model)
    fn = surfaces.GENERATORS.get(kind)
    if fn is None:
        raise unknown("surface model", kind, surfaces.GENERATORS)
    random = "seed" in inspect.signature(fn).parameters
    base = dict(params, size=size, samples=samples)
    surfaces.generate(kind, **base, **({"seed": seed} if random else {}))     # validate now, one clear error
    if random:
        def surface(s, _kind=kind, _base=base):
            return surfaces.generate(_kind, **_base, seed=int(s))
    else:
        surface = surfaces.generate(kind, **base)
    return Config(surface, material, tuple(incident), illuminant, random, seed, name or model)


def parse_model(text: str) -> tuple[str, dict]:
    """``MODEL:key=value,...`` -> (model, {key: value}); values stay strings where they carry units. The old
    spelling ``T`` of ``corr_length`` is accepted with a one-line warning, as in nano text."""
    kind, items = split_spec(text)
    params = {}
    for key, val, item in items:
        if not key:
            raise WaveopticsError(f"surface model parameter {item!r} is not allowed; write key=value, e.g. "
                                  "gaussian:sigma=20nm,corr_length=1um")
        key = nano_key(key) if key in NANO_RENAMED else _GENERATOR_ALIASES.get(key, key)
        try:
            params[key] = float(val)
        except ValueError:
            params[key] = val
    return kind, params


#: other spellings of generator parameters, as in nano text (old → new; ``T`` is retired: request.NANO_RENAMED)
_GENERATOR_ALIASES = {"corr": "corr_length", "corr-length": "corr_length"}


@dataclass(frozen=True)
class Setting:
    """One rung of the ladder (see the module docstring)."""

    solver: str = "fft"
    resolution: int = 64
    delta_e: float = 1.0
    realizations: int = 1
    precision: str = "float32"

    def __post_init__(self):
        if self.solver not in STUDY_SOLVERS:
            raise unknown("solver", self.solver, STUDY_SOLVERS)
        if self.precision not in PRECISIONS:
            raise unknown("precision", self.precision, PRECISIONS)
        for name, v in (("resolution", self.resolution), ("realizations", self.realizations)):
            if isinstance(v, bool) or int(v) != v or v < 1:
                raise WaveopticsError(f"{name}={v!r} is not allowed; it must be an integer >= 1")
        if not (math.isfinite(self.delta_e) and self.delta_e > 0):
            raise WaveopticsError(f"colour accuracy {self.delta_e!r} is not allowed; it must be > 0 (ΔE2000)")

    def scatter_kwargs(self) -> dict:
        kw = dict(STUDY_SOLVERS[self.solver], resolution=int(self.resolution), realizations=int(self.realizations))
        if self.solver == "direct":
            kw["precision"] = self.precision
        return kw

    def label(self) -> str:
        p = f" {self.precision}" if self.solver == "direct" else ""
        r = f" x{self.realizations}" if self.realizations > 1 else ""
        return f"{self.solver}{p} {self.resolution}² ΔE{self.delta_e:g}{r}"

    def sentence(self) -> str:
        """The setting in words (for the recommendation a user acts on)."""
        solver = {"fft0": "the fft solver at Taylor order 0 (frozen v_z)",
                  "fft": "the fft solver (banded Taylor series)"}.get(self.solver, f"the {self.solver} solver")
        p = f" in {self.precision}" if self.solver == "direct" else ""
        r = f", averaged over {self.realizations} surface realizations" if self.realizations > 1 else ""
        return (f"{solver}{p}, resolution {self.resolution} ({self.resolution}² directions), wavelengths spaced "
                f"for a colour error below ΔE2000 {self.delta_e:g}{r}")


def ladder(solvers=DEFAULT_SOLVERS, resolutions=DEFAULT_RESOLUTIONS, delta_e=DEFAULT_DELTA_E,
           realizations=(1,), precisions=DEFAULT_PRECISIONS) -> list[Setting]:
    """All combinations of the given choices; the precision varies only for the ``direct`` solver (the ``fft``
    solvers run in float64 on the host), float64 ``direct`` only at the densest wavelength grid."""
    out = []
    finest = min(delta_e)
    for s, r, d, n in itertools.product(solvers, resolutions, delta_e, realizations):
        if s == "direct":
            out += [Setting(s, r, d, n, p) for p in precisions if p == "float32" or d == finest]
        else:
            out.append(Setting(s, r, d, n, "float64"))
    return out


@dataclass
class Run:
    """One scatter run: energy per cell E (n_λ, n_v, n_u), albedo (n_λ,), RGB of the albedo, wall time."""

    wavelengths_nm: np.ndarray
    grid: scatter.DirectionGrid
    energy: np.ndarray
    albedo: np.ndarray
    rgb: np.ndarray
    time_s: float
    warnings: list = field(default_factory=list)


def _run(cfg: Config, setting: Setting, wavelengths_nm, seed: int, runtime=None, realizations=None) -> Run:
    kw = setting.scatter_kwargs()
    if realizations is not None:
        kw["realizations"] = realizations
    n = kw["realizations"]
    if not cfg.random:
        surf = cfg.surface
    else:
        surf = [cfg.surface(seed + r) for r in range(n)]     # generated outside the timed call
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", scatter.DiffractionWarning)
        res = scatter.scatter(surf, cfg.incident, wavelengths_nm, cfg.material, runtime=runtime, **kw)
    dt = time.perf_counter() - t0
    g = res.grid
    E = res.brdf * (g.du * g.dv)
    rgb = colour.reflectance_to_rgb(res.albedo, res.wavelengths_nm, cfg.illuminant)
    msgs = sorted({str(w.message) for w in caught})
    return Run(res.wavelengths_nm, g, E, res.albedo, np.asarray(rgb, float), dt, msgs)


def _mean(runs: list[Run], illuminant) -> Run:
    """The ensemble mean of runs on the same grid and wavelengths (times and warnings add up)."""
    if len(runs) == 1:
        return runs[0]
    A = np.mean([r.albedo for r in runs], axis=0)
    w = runs[0].wavelengths_nm
    return Run(w, runs[0].grid, np.mean([r.energy for r in runs], axis=0), A,
               np.asarray(colour.reflectance_to_rgb(A, w, illuminant), float), float(sum(r.time_s for r in runs)),
               sorted({m for r in runs for m in r.warnings}))


def _warm_up(settings, runtime) -> None:
    """Build the direct kernels used by *settings* before anything is timed (builds are cached)."""
    precisions = {s.precision for s in settings if s.solver == "direct"}
    if not precisions:
        return
    hf = HeightField(np.zeros((4, 4)), 1e-7)
    smp = scatter.samples(hf, "boxcar")
    coef = scatter.phase_coefficients(smp, np.array([0.0, 0.0, 1.0]), np.array([[0.0, 0.0, 1.0]]), [500.0])
    for p in precisions:
        scatter.kirchhoff_U_cl(smp, coef, runtime=runtime, precision=p)


def _pool(E: np.ndarray, factor: int) -> np.ndarray:
    """Sum (n_λ, n, n) energies over factor × factor blocks of cells."""
    n_l, n_v, n_u = E.shape
    return E.reshape(n_l, n_v // factor, factor, n_u // factor, factor).sum(axis=(2, 4))


def _interp_wavelengths(values: np.ndarray, w_from: np.ndarray, w_to: np.ndarray) -> np.ndarray:
    """Linear interpolation along axis 0 from wavelengths *w_from* to *w_to* (clamped at the ends)."""
    if w_from.size == 1:
        return np.repeat(values[:1], w_to.size, axis=0)
    j = np.clip(np.searchsorted(w_from, w_to) - 1, 0, w_from.size - 2)
    t = np.clip((w_to - w_from[j]) / (w_from[j + 1] - w_from[j]), 0.0, 1.0)
    t = t.reshape((-1,) + (1,) * (values.ndim - 1))
    return (1 - t) * values[j] + t * values[j + 1]


def errors(run: Run, ref: Run) -> dict:
    """The three errors of *run* against *ref* (see the module docstring)."""
    factor = ref.grid.n_u // run.grid.n_u
    if factor * run.grid.n_u != ref.grid.n_u or ref.grid.n_u != ref.grid.n_v or run.grid.n_u != run.grid.n_v:
        raise WaveopticsError(f"resolution {run.grid.n_u} does not divide the reference resolution {ref.grid.n_u}")
    Er = _pool(ref.energy, factor)
    Es = _interp_wavelengths(run.energy, run.wavelengths_nm, ref.wavelengths_nm)
    norm = float(np.sqrt(np.sum(Er**2)))
    l2 = float(np.sqrt(np.sum((Es - Er) ** 2)) / norm) if norm > 0 else float(np.sqrt(np.sum(Es**2)))
    A = _interp_wavelengths(run.albedo, run.wavelengths_nm, ref.wavelengths_nm)
    return {"error_rel_l2": l2, "error_albedo": float(np.max(np.abs(A - ref.albedo))),
            "delta_e2000": float(colour.delta_e2000(run.rgb, ref.rgb))}


def pareto_front(times, errs) -> list[int]:
    """Indices of the non-dominated points of (time, error), both minimized, sorted by time.

    A point is dominated when another is no worse in both and strictly better in one (Deb 2001, def. 2.5).
    NaN errors (failed or skipped) never belong to the front.
    """
    t = np.asarray(times, dtype=float)
    e = np.asarray(errs, dtype=float)
    ok = np.isfinite(t) & np.isfinite(e)
    front = []
    for i in np.nonzero(ok)[0]:
        better_eq = ok & (t <= t[i]) & (e <= e[i])
        strictly = better_eq & ((t < t[i]) | (e < e[i]))
        if not strictly.any():
            front.append(int(i))
    return sorted(front, key=lambda i: (t[i], e[i]))


def recommend(rows: list[dict], target: float, metric: str = "error_rel_l2") -> int | None:
    """Index of the fastest row whose *metric* is ≤ *target*, or None."""
    if metric not in METRICS:
        raise unknown("metric", metric, METRICS)
    ok = [i for i, r in enumerate(rows) if r.get(metric) is not None and np.isfinite(r[metric])
          and r[metric] <= target and r.get("time_s") is not None]
    return min(ok, key=lambda i: rows[i]["time_s"]) if ok else None


def _units(s: Setting, n_wl: int) -> float:
    """Work proxy of a setting (cells × wavelengths × realizations) for the time prediction."""
    return float(s.resolution) ** 2 * n_wl * s.realizations


#: solvers the reference may use: ``fft`` (order auto, float64: exact Kirchhoff to 1e-8 Σw against the direct
#: sum, docs/wave-optics.md) is the default; ``direct`` (float64 on the OpenCL device) is the independent check,
#: about 20× slower on a CPU device
REFERENCE_SOLVERS = ("fft", "direct")


def reference_setting(settings, cfg: Config, solver: str = "fft", precision: str = "float64",
                      runtime=None) -> Setting:
    """The reference: the finest resolution of the ladder, half the ladder's finest colour accuracy ΔE (a denser
    wavelength grid), :data:`REFERENCE_REALIZATIONS` (or twice the ladder's largest) for random surfaces, with
    *solver* (:data:`REFERENCE_SOLVERS`). ``direct`` needs OpenCL; float64 falls back to the ``fft`` solver where
    the device has no fp64."""
    if solver not in REFERENCE_SOLVERS:
        raise unknown("reference solver", solver, REFERENCE_SOLVERS)
    res = max(s.resolution for s in settings)
    de = min(s.delta_e for s in settings) / 2
    n = max(REFERENCE_REALIZATIONS, 2 * max(s.realizations for s in settings)) if cfg.random else 1
    if solver == "direct" and precision == "float64" and runtime is not None and not runtime.fp64:
        solver = "fft"
    return Setting(solver, res, de, n, precision)


def _reference_run(cfg: Config, ref_s: Setting, wl_ref, runtime):
    """(the reference's runs, their mean, its row of :func:`study`): one run per realization for a random surface (settings
    are compared with the mean over the same seeds), with the relative standard error of that ensemble mean, its own
    speckle noise (``noise_rel_l2``)."""
    if cfg.random:
        ref_runs = [_run(cfg, ref_s, wl_ref, cfg.seed + r, runtime, realizations=1)
                    for r in range(ref_s.realizations)]
    else:
        ref_runs = [_run(cfg, ref_s, wl_ref, cfg.seed, runtime)]
    ref = _mean(ref_runs, cfg.illuminant)
    ref_row = {**dataclasses.asdict(ref_s), "wavelengths": int(ref.wavelengths_nm.size),
               "wavelengths_nm": ref.wavelengths_nm, "time_s": ref.time_s, "albedo": ref.albedo,
               "rgb": ref.rgb, "warnings": ref.warnings, "noise_rel_l2": None}
    if len(ref_runs) >= 2:
        E = np.stack([r.energy for r in ref_runs])
        var = np.var(E, axis=0, ddof=1) / len(ref_runs)
        norm = float(np.sqrt(np.sum(ref.energy ** 2)))
        ref_row["noise_rel_l2"] = float(np.sqrt(np.sum(var)) / norm) if norm > 0 else None
    return ref_runs, ref, ref_row


def study(cfg: Config, settings: list[Setting] | None = None, *, budget_s: float | None = None,
          target_error: float | None = None, metric: str = "error_rel_l2", reference: Setting | None = None,
          reference_solver: str = "fft", runtime=None, progress=None) -> dict:
    """Run the accuracy–cost study (see the module docstring).

    Parameters
    ----------
    cfg : Config
    settings : list of Setting, optional
        Default :func:`ladder` (with realizations 1 and 2 for random surfaces).
    budget_s : float, optional, s
        Time allowed for the ladder (after the reference): settings run cheapest first, and one whose predicted
        time (from the measured seconds per cell·wavelength·realization of its solver) would overrun is skipped.
    target_error : float, optional
        Recommend the fastest setting whose *metric* is ≤ this.
    metric : str
        One of :data:`METRICS`; used for the Pareto front and the recommendation.
    reference : Setting, optional
        Default :func:`reference_setting` with *reference_solver*.
    reference_solver : {'fft', 'direct'}
        Solver of the default reference (:data:`REFERENCE_SOLVERS`).
    progress : callable, optional
        Called with 1 after the reference and after each setting.

    Returns
    -------
    dict
        ``{"config", "reference", "settings": [...], "pareto": [indices], "metric", "target_error",
        "recommendation", "skipped": [...], "budget_s", "time_s"}``; each setting row holds ``solver``,
        ``resolution``, ``wavelengths`` (count), ``wavelengths_nm``, ``delta_e``, ``realizations``,
        ``precision``, ``error_rel_l2``, ``error_albedo``, ``delta_e2000``, ``time_s``, ``warnings``,
        ``same_as_reference`` (the reference's own solver, precision, grid and wavelengths: error 0 by
        construction, so never on the Pareto front nor recommended), ``skipped`` (why, or None), and for random
        surfaces ``ensemble_rel_l2``.
    """
    t_start = time.perf_counter()
    if metric not in METRICS:
        raise unknown("metric", metric, METRICS)
    if budget_s is not None and not (budget_s > 0):
        raise WaveopticsError(f"budget {budget_s!r} s is not allowed; it must be > 0")
    if target_error is not None and not (target_error > 0):
        raise WaveopticsError(f"target error {target_error!r} is not allowed; it must be > 0")
    if settings is None:
        settings = ladder(realizations=(1, 2) if cfg.random else (1,))
    settings = list(settings)
    if not settings:
        raise WaveopticsError("the ladder is empty; give at least one solver, resolution and colour accuracy")
    if runtime is None and (reference_solver == "direct"
                            or any(s.solver == "direct" for s in settings + [reference] if s is not None)):

        runtime = get_runtime()
    ref_s = reference or reference_setting(settings, cfg, reference_solver, runtime=runtime)
    for s in settings:
        if ref_s.resolution % s.resolution:
            raise WaveopticsError(f"resolution {s.resolution} does not divide the reference resolution "
                                  f"{ref_s.resolution}; use resolutions that divide the largest one")
    wl_of = {}

    def wavelengths(de):
        if de not in wl_of:
            wl_of[de] = colour.simulation_wavelengths(cfg.illuminant, de)
        return wl_of[de]

    _warm_up(settings + [ref_s], runtime)
    wl_ref = wavelengths(ref_s.delta_e)
    ref_runs, ref, ref_row = _reference_run(cfg, ref_s, wl_ref, runtime)
    if progress is not None:
        progress(1)

    order = sorted(range(len(settings)), key=lambda i: (settings[i].solver != "fft0", settings[i].solver == "direct",
                                                        _units(settings[i], wavelengths(settings[i].delta_e).size)))
    rows: list[dict] = [None] * len(settings)
    rate: dict = {}
    skipped = []
    spent = 0.0
    for i in order:
        s = settings[i]
        wl = wavelengths(s.delta_e)
        row = {**dataclasses.asdict(s), "wavelengths": int(wl.size), "wavelengths_nm": wl}
        # a setting that computes what the reference computes has error 0 by construction: it is timed, but kept
        # out of the Pareto front and the recommendation
        row["same_as_reference"] = bool((s.solver, s.precision, s.resolution) == (ref_s.solver, ref_s.precision,
                                                                                   ref_s.resolution)
                                        and wl.size == wl_ref.size and np.allclose(wl, wl_ref))
        key = (s.solver, s.precision)
        units = _units(s, wl.size)
        predicted = rate[key] * units if key in rate else None
        if budget_s is not None and predicted is not None and spent + predicted > budget_s:
            row.update(error_rel_l2=None, error_albedo=None, delta_e2000=None, time_s=None, warnings=[],
                       ensemble_rel_l2=None,
                       skipped=f"predicted {predicted:.3g} s would exceed the budget")
            skipped.append(i)
        else:
            r = _run(cfg, s, wl, cfg.seed, runtime)
            spent += r.time_s
            rate[key] = max(rate.get(key, 0.0), r.time_s / units)
            same = _mean(ref_runs[:s.realizations], cfg.illuminant) if cfg.random else ref
            row.update(errors(r, same), time_s=r.time_s, warnings=r.warnings, skipped=None)
            if cfg.random:
                row["ensemble_rel_l2"] = errors(r, ref)["error_rel_l2"]
        rows[i] = row
        if progress is not None:
            progress(1)
    nan = float("nan")
    times = [r["time_s"] if r["time_s"] is not None else nan for r in rows]
    errs = [r[metric] if r[metric] is not None and not r["same_as_reference"] else nan for r in rows]
    front = pareto_front(times, errs)
    rec = None
    if target_error is not None:
        k = recommend([r if not r["same_as_reference"] else {} for r in rows], target_error, metric)
        if k is None:
            done = [i for i in range(len(rows)) if np.isfinite(errs[i])]
            best = min(done, key=lambda i: errs[i]) if done else None
            rec = {"index": None, "reason": f"no setting reaches {metric} <= {target_error:g}"
                   + (f"; the most accurate is #{best} ({settings[best].label()}, {errs[best]:.3g})"
                      if best is not None else "")}
        else:
            rec = {"index": k, "setting": settings[k].label(), "in_words": settings[k].sentence(),
                   metric: rows[k][metric], "time_s": rows[k]["time_s"],
                   "reason": f"fastest setting with {metric} <= {target_error:g}"}
    return {"config": cfg.describe(), "reference": ref_row, "settings": rows, "pareto": front, "metric": metric,
            "target_error": target_error, "recommendation": rec, "skipped": skipped, "budget_s": budget_s,
            "time_s": time.perf_counter() - t_start}


def table(result: dict) -> str:
    """The study as a Markdown table (Pareto members marked ★, the recommendation ►, the reference's own setting
    "= reference")."""
    rec = (result.get("recommendation") or {}).get("index")
    lines = ["| # | solver | precision | resolution | wavelengths | realizations | rel. L2 | albedo err. | ΔE2000 "
             "| time (s) | |", "|---|---|---|---|---|---|---|---|---|---|---|"]

    def f(v, fmt):
        return "—" if v is None else format(v, fmt)

    for i, r in enumerate(result["settings"]):
        mark = ("►" if i == rec else "") + ("★" if i in result["pareto"] else "") + \
            ("= reference" if r.get("same_as_reference") else "")
        prec = r["precision"] if r["solver"] == "direct" else "float64"
        lines.append(f"| {i} | {r['solver']} | {prec} | {r['resolution']} | {r['wavelengths']} | {r['realizations']} "
                     f"| {f(r['error_rel_l2'], '.2e')} | {f(r['error_albedo'], '.2e')} | {f(r['delta_e2000'], '.3f')} "
                     f"| {f(r['time_s'], '.3g')} | {mark} |")
    return "\n".join(lines)


def plot(result: dict, path, *, overwrite: bool = True, title: str | None = None) -> None:
    """PNG: error (the study's metric) vs wall time, log-log, one marker per solver, the Pareto front joined."""
    plt = figures.pyplot()


    metric = result["metric"]
    rows = result["settings"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    styles = (("fft0", "float64", "s", "C0", "fft0"), ("fft", "float64", "o", "C1", "fft"),
              ("direct", "float32", "^", "C2", "direct float32"), ("direct", "float64", "v", "C3", "direct float64"))
    for solver, prec, mk, col, lab in styles:
        pts = [(r["time_s"], r[metric]) for r in rows if r["solver"] == solver and r["time_s"] is not None
               and (solver != "direct" or r["precision"] == prec)]
        if pts:
            t, e = zip(*pts)
            ax.scatter(t, np.maximum(e, 1e-16), marker=mk, color=col, label=lab, s=28, alpha=0.85)
    fr = result["pareto"]
    if fr:
        ax.plot([rows[i]["time_s"] for i in fr], [max(rows[i][metric], 1e-16) for i in fr], "k--", lw=1,
                label="Pareto front")
    if result.get("target_error"):
        ax.axhline(result["target_error"], color="r", lw=0.8, ls=":", label="target")
    rec = (result.get("recommendation") or {}).get("index")
    if rec is not None:
        ax.scatter([rows[rec]["time_s"]], [max(rows[rec][metric], 1e-16)], s=160, facecolors="none",
                   edgecolors="r", label="recommended")
    noise = result["reference"].get("noise_rel_l2")
    if noise and metric == "error_rel_l2":
        ax.axhline(noise, color="gray", lw=0.8, label="reference noise")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel({"error_rel_l2": "relative L2 error of the lobe", "error_albedo": "albedo error (abs.)",
                   "delta_e2000": "ΔE2000 of the albedo colour"}[metric])
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax.set_title(title or result["config"]["name"], fontsize=9)
    save_figure(fig, path, overwrite=overwrite)


#: files written by :func:`write`
FILES = ("cost.json", "cost.png", "cost.md")


def write(result: dict, outdir, *, overwrite: bool = False) -> dict:
    """Write ``cost.json``, ``cost.png`` (error vs time) and ``cost.md`` (the table) into *outdir*."""

    out = prepare_outdir(outdir, overwrite=overwrite, expected=FILES)
    paths = {"cost.json": write_json(out / "cost.json", result, overwrite=overwrite)}
    plot(result, out / "cost.png", overwrite=overwrite)
    paths["cost.png"] = out / "cost.png"
    with atomic_path(out / "cost.md", overwrite=overwrite) as tmp:
        tmp.write_text(table(result) + "\n")
    paths["cost.md"] = out / "cost.md"
    return paths
