"""The effect planner: decide from physics which effects a scene needs, simulate only those, say why.

For every (material, light) pair of a :class:`waveoptics.planning.scene.Scene` the planner takes, in order:

``diffuse``
    Metals absorb the refracted light: no diffuse term. Dielectrics get the substrate's diffuse term (with the
    diffuse-specular trade-off of :mod:`waveoptics.brdf`) unless their diffuse albedo is 0.
``diffraction``
    The nano surface reflects the fraction exp(−g), g = (4π σ cos θ_i / λ)², coherently and scatters the rest,
    TIS = F (1 − exp(−g)) (Davies 1954; Bennett & Porteus 1961; docs/physics.md §2). Whether that scattered light
    changes what the scene shows is decided on the colour it produces: both models (two-scale and plain
    microfacet) are evaluated on a coarse grid (:data:`ESTIMATE_RESOLUTION` cells, :data:`ESTIMATE_STEP_NM`
    wavelength step) through the PSD route, at the scene's light directions and directions of interest, and the
    largest CIEDE2000 difference of the rendered radiance π f cos θ_i is compared with the target. Diffraction
    runs when that estimate exceeds :data:`ESTIMATE_SHARE` of the target (the rest of the budget covers the
    estimate's own error), or when g exceeds :data:`PSD_G_MAX` (no coherent reflection is left at all).
    Height fields without known statistics are estimated through a Gaussian-statistics proxy with their rms
    height and correlation length.
``wavelengths``
    Line sources (lasers): their lines only. No diffraction and a Fresnel factor that is the same at every
    wavelength (constant index, grey F0): the BRDF does not depend on λ, so it is evaluated once and used for the
    whole spectrum. Otherwise the coarsest uniform grid that keeps smooth reflectance spectra within the target
    (:func:`waveoptics.colour.simulation_wavelengths`), refined for a periodic nano surface of period Λ so that
    neighbouring wavelengths of diffraction order m land no further apart than one grid cell, Δλ ≤ Λ du / m
    (grating equation, docs/physics.md §5).
``solver``
    Statistics with g ≤ :data:`PSD_G_MAX`: the PSD series (:mod:`waveoptics.scatter.series`; exact ensemble average for
    Gaussian heights, cheapest). Height fields (and statistics beyond the PSD range, for which a height field is
    generated): the cheaper of ``fft`` and ``direct`` by the calibrated cost model (both are exact Kirchhoff to
    their tolerance; ``direct`` only computes the directions it is asked for).
``resolution``
    The direction grid must resolve the narrowest simulated lobe: bilinear interpolation of a lobe of standard
    deviation s (direction cosines) at spacing du errs by at most du² / (8 s²) of its peak, and a relative
    luminance error ε moves CIEDE2000 by about :data:`DE_PER_RELATIVE_Y` · ε at mid grey, so
    du ≤ s √(8 ΔE / DE_PER_RELATIVE_Y). Height-field solvers also need du ≤ λ_min / L to sample the specular
    spike of a patch of length L. The result is clipped to :data:`RESOLUTION_RANGE`.
``directions``
    The whole hemisphere when the outputs show it (images, spectral BRDF, sphere camera); otherwise only
    patches around the view directions (:data:`PATCH_SIGMAS` lobe widths wide, so that the micro-facet
    convolution still sees every contribution) when that is fewer directions than the hemisphere.
``precision``
    Only the ``direct`` OpenCL solver has a float32 path. Its round-off leaves a relative noise floor
    ε₃₂² (n / 256 + (4π h_max/λ)² / n) in |U|² against the coherent peak (two-level summation over n samples,
    float32 rounding of the height phase), while the weakest light the target asks to see — a haze of luminance
    ΔE / 903.3 (CIE L* slope near black) — sits at (ΔE / 903.3 / π) (λ/L)² of the peak. float64 is chosen
    when the floor exceeds :data:`FLOOR_MARGIN` of that level (large patches, tall heights).

Costs come from a calibration timed once per machine and cached (:func:`calibration`; ``waveoptics plan
--recalibrate`` times it again): seconds per grid
cell, per cell and wavelength, per PSD series term, per chirp-z work unit and per direct-sum term.

References
----------
.. [1] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 209 (1954);
   H. E. Bennett, J. O. Porteus, JOSA 51, 123 (1961) (coherent fraction, TIS).
.. [2] N. Holzschuch, R. Pacanowski, "A two-scale microfacet reflectance model combining reflection and
   diffraction", ACM TOG 36(4), 66, 2017 (which scale matters when).
.. [3] CIE 015:2018 Colorimetry, §8.2.1 (L* = 903.3 Y below Y = 0.008856; L* = 116 Y^{1/3} − 16 above).
.. [4] M. R. Luo, G. Cui, B. Rigg, "The development of the CIE 2000 colour-difference formula: CIEDE2000",
   Color Res. Appl. 26(5), 2001.
.. [5] C. de Boor, *A Practical Guide to Splines*, 1978, ch. 2 (linear interpolation error h² max|f''| / 8).
.. [6] J. E. Harvey, R. N. Pfisterer, Opt. Eng. 59(1) 017103, 2020 (grating equation, orders).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .. import colour, scatter, surfaces
from ..brdf import twoscale
from ..errors import FieldError, unknown
from ..materials import Material, get_material
from ..planning.scene import MaterialSpec, Scene
from ..request import make_nano, parse_nano
from ..runtime import get_runtime
from ..scatter.grid import DirectionGrid
from ..scatter.series import roughness_g
from ..simulate import sphere_evaluations
from ..units import direction_from_angles, parse_length
from .costmodel import CostModel, _best, band_table_time, calibration, direct_calibration, fft_solver_units, psd_terms
from .decisions import (
    LAMBDA_REF_NM,
    ORDER_EFFICIENCY_MIN,
    diffraction_lobe_width,
    first_order_g,
    float32_floor,
    grating_orders,
    grid_step,
    lobe_width,
    scattered_fraction,
    weakest_level,
)

__all__ = ['ESTIMATE_RESOLUTION', 'ESTIMATE_STEP_NM', 'ESTIMATE_SPHERE_THETAS', 'ESTIMATE_SHARE', 'PSD_G_MAX', 'FLAT_SCATTER', 'RESOLUTION_RANGE', 'PATCH_SIGMAS', 'F_FLAT_TOL', 'FLOOR_MARGIN', 'FORCEABLE', 'parse_force', 'EntryPlan', 'Plan', 'colour_shift', 'plan_scene']

# --- thresholds (docs/planning.md lists them with the decisions they drive) -------------------------------------

#: cells per side of the coarse grid on which the colour shift of diffraction is estimated
ESTIMATE_RESOLUTION = 32
#: wavelength step (nm) of the coarse estimate (line sources use their lines)
ESTIMATE_STEP_NM = 40.0
#: extra incidence angles (degrees) probed when a sphere camera sees every incidence
ESTIMATE_SPHERE_THETAS = (0.0, 45.0, 75.0)
#: diffraction runs when the estimated ΔE2000 exceeds this share of the target
ESTIMATE_SHARE = 0.5
#: largest g = (4πσ cosθ/λ)² for which the PSD series is trusted (scatter/series.py: truncation loses energy beyond)
PSD_G_MAX = 30.0
#: scattered fractions below this are "flat" (no estimate is run)
FLAT_SCATTER = 1e-9
#: smallest and largest direction grid (cells per side) the planner picks
RESOLUTION_RANGE = (32, 256)
#: view patches span this many lobe standard deviations around each view direction
PATCH_SIGMAS = 3.0
#: relative spread of F over the spectrum below which a material counts as wavelength-independent
F_FLAT_TOL = 1e-9
#: float32 is fine while its noise floor stays below this share of the weakest light the target resolves
FLOOR_MARGIN = 0.1

FORCEABLE = {"diffraction": ("on", "off"), "diffuse": ("on", "off"), "solver": ("psd", "fft", "direct"),
             "precision": ("float32", "float64"), "directions": ("hemisphere", "views")}
_ON = {"on": True, "true": True, "yes": True, "1": True, "off": False, "false": False, "no": False, "0": False}


def parse_force(items) -> dict:
    """``["diffraction", "diffuse=off", "solver=direct"]`` -> {"diffraction": True, "diffuse": False, ...}."""
    out = {}
    for item in items or ():
        key, eq, val = str(item).partition("=")
        key, val = key.strip().lower(), (val.strip().lower() if eq else "on")
        if key not in FORCEABLE:
            raise unknown("effect", key, FORCEABLE, field='force')
        if key in ("diffraction", "diffuse"):
            if val not in _ON:
                raise FieldError(f"{{force}} {item!r}: {key} takes on or off", 'force')
            out[key] = _ON[val]
        elif val not in FORCEABLE[key]:
            raise FieldError(f"{{force}} {item!r} is not allowed; {key} takes {', '.join(FORCEABLE[key])}", 'force')
        else:
            out[key] = val
    return out


# ----------------------------------------------------------------------------------------------------------------
# The plan
# ----------------------------------------------------------------------------------------------------------------

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
    diffraction: str = "kirchhoff"           # diffraction model of the nano lobe

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
                "accuracy_delta_e": self.scene.delta_e, "force": self.force,
                "materials": [e.as_dict() for e in self.entries],
                "estimated_time_s": self.estimated_time_s, "planning_time_s": self.planning_time_s,
                "cost_model": self.cost_model.as_dict()}

    def table(self) -> str:
        """The plan as a text table: every decision with its value and reason, and the estimated cost."""
        sc = self.scene
        lines = [f"scene {sc.name}" + (f" ({sc.path})" if sc.path else "") + f": accuracy ΔE2000 ≤ {sc.delta_e:g}"]
        for e in self.entries:
            lines.append("")
            lines.append(f"{e.name} ({e.material.name}, {e.material.category}) under {e.light_name} ({e.spd.name}): "
                         f"estimated {_fmt_s(e.estimated_time_s)}")
            w = max(len(d) for d, _, _ in e.decisions)
            v = min(24, max(len(str(val)) for _, val, _ in e.decisions))
            for d, val, r in e.decisions:
                lines.append(f"  {d:<{w}}  {str(val):<{v}}  {r}")
        lines.append("")
        lines.append(f"total estimated {_fmt_s(self.estimated_time_s)} (planning took {_fmt_s(self.planning_time_s)}; "
                     f"cost model calibrated in {_fmt_s(self.cost_model.calibration_s)})")
        return "\n".join(lines)


def _fmt_s(t: float) -> str:
    return f"{t * 1e3:.0f} ms" if t < 1 else f"{t:.1f} s"


def _fmt_nm(w) -> str:
    w = np.asarray(w, dtype=float)
    if w.size == 0:
        return "none"
    if w.size > 4 and np.allclose(np.diff(w), w[1] - w[0]):
        return f"{w.size} ({w[0]:g}-{w[-1]:g} nm step {w[1] - w[0]:g})"
    return ", ".join(f"{x:g}" for x in w) + " nm"


# ----------------------------------------------------------------------------------------------------------------
# Nano surfaces: the object the solver uses and a PSD proxy for the estimate
# ----------------------------------------------------------------------------------------------------------------

def _proxy_model(spec: MaterialSpec, hf) -> surfaces.PSDModel:
    """PSD statistics standing in for a height field in the colour estimate (the generator's own when known)."""

    n = spec.nano
    if n.kind == "statistics":
        model, p = parse_nano(n.text)
        return surfaces.PSDModel(model, sigma=p["sigma"], T=p.get("T"), B=p.get("B"), C=p.get("C"))
    p = n.params
    if n.kind == "generator" and p["model"] in surfaces.PSD_MODELS:
        sig = surfaces.rms_height(hf)
        if p["model"] == "abc":
            return surfaces.PSDModel("abc", sigma=sig, B=parse_length(p["B"], default_unit="m", name="B"), C=float(p["C"]))
        return surfaces.PSDModel(p["model"], sigma=sig, T=parse_length(p["corr_length"], default_unit="m",
                                                                  name="corr_length"))
    sigma = surfaces.rms_height(hf)
    T = surfaces.correlation_length(hf)
    if not np.isfinite(T) or T <= 0:
        T = max(hf.extent) / 2
    return surfaces.PSDModel("gaussian", sigma=max(sigma, 1e-15), T=float(T))


# ----------------------------------------------------------------------------------------------------------------
# Colour estimate of the diffraction's effect
# ----------------------------------------------------------------------------------------------------------------

def colour_shift(material, micro, model: surfaces.PSDModel, spd, light_dirs_deg, *, views_deg=(), hemisphere=True,
                 kd=0.0, resolution=ESTIMATE_RESOLUTION, step_nm=ESTIMATE_STEP_NM) -> tuple[float, dict]:
    """Largest CIEDE2000 between the two-scale and the microfacet radiance π f cos θ_i, on a coarse grid.

    Parameters
    ----------
    light_dirs_deg : sequence of (θ, φ), degrees
        Incident directions to probe.
    views_deg : sequence of (θ, φ), degrees
        View directions (looked up bilinearly); with *hemisphere* every cell of the disc counts too.
    kd : float
        Diffuse albedo (0: none), so that a diffuse background masks a faint haze as it does in the image.

    Returns
    -------
    (ΔE_max, info) with the direction where it occurs.
    """

    w = colour.spectral_grid(spd) if spd.lines else colour.spectral_grid(spd, step_nm)
    grid = DirectionGrid.hemisphere(resolution)
    nano = twoscale.Nano(model=model)
    best, where = 0.0, None
    for th, ph in light_dirs_deg:
        wi = direction_from_angles(th, ph)
        L = twoscale.evaluate(wi, w, material, micro, nano, grid, solver="psd", kd=kd,
                              diffuse="lambert" if kd > 0 else "none")
        q = []
        for f in (L.total, L.microfacet):
            vals = []
            if hemisphere:
                vals.append(np.moveaxis(f, 0, -1)[grid.inside])
            if len(views_deg):
                vd = np.array([direction_from_angles(t, p) for t, p in views_deg])
                vals.append(np.moveaxis(grid.interpolate(f, vd[:, 0], vd[:, 1]), 0, -1))
            q.append(np.pi * wi[2] * np.concatenate(vals))
        rgb = [colour.reflectance_to_rgb(x, w, spd) for x in q]
        dE = colour.delta_e2000(rgb[0], rgb[1])
        i = int(np.argmax(dE))
        if dE[i] > best:
            best, where = float(dE[i]), {"light_deg": [th, ph], "index": i}
    return best, {"wavelengths_nm": w, "at": where, "resolution": resolution}


# ----------------------------------------------------------------------------------------------------------------
# Planning one (material, light) pair
# ----------------------------------------------------------------------------------------------------------------

def _constant_over(mat: Material, w) -> bool:
    """True when F(cos θ, λ) is the same at every λ of *w* (constant index or grey F0)."""
    c = np.array([1.0, 0.7, 0.4, 0.1])[:, None]
    F = np.asarray(mat.F(c, np.asarray(w, dtype=float)[None, :]), dtype=float)
    return bool(np.all(np.ptp(F, axis=1) <= F_FLAT_TOL * np.maximum(F.max(axis=1), 1e-300)))


def _patch_grids(views_deg, resolution: int, half_width: float) -> list[DirectionGrid]:
    """Sub-grids of the *resolution*² hemisphere grid around each view direction, ±*half_width* wide.

    The patches keep the hemisphere's cell edges, so a patch evaluates exactly the cells the hemisphere would.
    """
    du = 2.0 / resolution
    out = []
    for th, ph in views_deg:
        d = direction_from_angles(th, ph)
        rng = []
        for c in (d[0], d[1]):
            i0 = max(0, int(math.floor((c - half_width + 1.0) / du)))
            i1 = min(resolution, max(int(math.ceil((c + half_width + 1.0) / du)), i0 + 2))
            i0 = min(i0, i1 - 2)
            rng.append((-1.0 + i0 * du, -1.0 + i1 * du, i1 - i0))
        (ua, ub, nu), (va, vb, nv) = rng
        out.append(DirectionGrid(nu, nv, (ua, ub), (va, vb)))
    return out


@dataclass
class _Entry:
    """The state of planning one (material, light) pair: inputs, then each decision's outcome in turn."""

    scene: Scene
    spec: MaterialSpec
    light: object
    force: dict
    cm: CostModel
    device: object
    max_resolution: int | None
    mat: Material = None
    spd: colour.SPD = None
    micro: twoscale.Micro = None
    cos_i: list = field(default_factory=list)
    cos_max: float = 1.0
    w_colour: np.ndarray = None
    lam_min: float = 0.0
    decisions: list = field(default_factory=list)
    metrics: dict = field(default_factory=dict)
    # outcomes
    diffuse: bool = False
    kd: float = 0.0
    hf: object = None
    proxy: object = None
    diffraction: bool = False
    g_series: float = 0.0
    w_sim: np.ndarray = None
    lam_independent: bool = False
    nano: twoscale.Nano | None = None
    solver: str | None = "none"
    widths: dict = field(default_factory=dict)
    resolution: int = 0
    directions: str = "hemisphere"
    patches: list = field(default_factory=list)
    time_s: float = 0.0
    precision: str = "float64"
    diffraction_model: str = "kirchhoff"

    @property
    def dE(self) -> float:
        return self.scene.delta_e

    @property
    def sphere(self) -> bool:
        return self.scene.view.camera == "sphere"

    @property
    def views(self) -> tuple:
        return self.scene.view.directions_deg

    @property
    def statistical(self) -> bool:
        """The nano surface has Gaussian statistics (a PSD model) the series can use."""
        n = self.spec.nano
        return n is not None and (n.kind == "statistics" or n.params.get("model") in surfaces.PSD_MODELS)

    def decide(self, name: str, value, reason: str) -> None:
        self.decisions.append((name, value, reason))


def _decide_diffuse(e: _Entry) -> None:
    """Metals have no diffuse term; dielectrics have one unless their diffuse albedo is 0."""
    if e.mat.is_metal:
        if e.force.get("diffuse") is True:
            raise FieldError(f"{{force}} diffuse: material {e.spec.name!r} ({e.mat.name}) is a metal; metals absorb "
                             "the refracted light and have no diffuse term", "force")
        e.diffuse = False
        e.decide("diffuse", "off", f"{e.mat.name} is a metal: the refracted light is absorbed, no diffuse term")
    elif "diffuse" in e.force:
        e.diffuse = e.force["diffuse"]
        e.decide("diffuse", "on" if e.diffuse else "off", "forced")
    elif e.spec.diffuse_albedo == 0:
        e.diffuse = False
        e.decide("diffuse", "off", "diffuse_albedo = 0")
    else:
        e.diffuse = True
        e.decide("diffuse", "on", f"{e.mat.category} substrate with diffuse albedo {e.spec.diffuse_albedo:g} "
                                  "(with the diffuse-specular trade-off)")
    e.kd = e.spec.diffuse_albedo if e.diffuse else 0.0


def _decide_multiple_scattering(e: _Entry) -> None:
    """The Kulla-Conty compensation lobe runs when the scene asks for it (``multiple_scattering = true``); the
    reason states the share of the light single scattering loses at the light's directions, which it returns."""
    if not e.spec.multiple_scattering:
        e.decide("multiple scattering", "off", "not asked (multiple_scattering = true adds the light single "
                                               "scattering loses between micro facets)")
        return
    from ..brdf import MicrofacetBRDF

    table = MicrofacetBRDF(e.mat, e.micro, multiple_scattering=True)._ms_table()   # the table the run uses
    lost = [1.0 - float(table(c)) for c in e.cos_i]
    e.metrics["multiple_scattering_share"] = lost
    e.decide("multiple scattering", "on", "set by the scene: returns the " + ", ".join(f"{x:.1%}" for x in lost)
             + " of the light that single scattering loses at the light's direction(s) (Kulla & Conty 2017)")


def _decide_diffraction(e: _Entry) -> None:
    """Diffraction runs when the nano surface scatters enough light to change the colour by a visible amount
    (a coarse estimate against the scene's ΔE target), or when almost no coherent reflection is left."""
    if e.spec.nano is None:
        if e.force.get("diffraction") or "solver" in e.force:
            raise FieldError(f"{{force}} diffraction: material {e.spec.name!r} has no nano surface "
                             "(add [materials.nano] with statistics, generator or file)", "force")
        e.diffraction = False
        e.decide("diffraction", "off", "no nano surface given: the microfacet model is the whole BRDF")
        return
    if e.spec.nano.kind != "statistics":
        e.hf = e.spec.nano.height_field(e.scene.seed)
    e.proxy = _proxy_model(e.spec, e.hf)
    probe = twoscale.Nano(surface=e.hf) if e.hf is not None else twoscale.Nano(model=e.proxy)
    s = float(np.max(scattered_fraction(probe, e.cos_max, e.lam_min)))
    F_max = float(np.max(e.mat.F(np.array([e.cos_max]), e.w_colour)))
    sigma = e.proxy.sigma
    g_max = float(roughness_g(sigma, 2 * e.cos_max, e.lam_min))
    # the PSD series' own g = (kσ(cosθ_i + cosθ_o))² peaks towards the normal (docs/physics.md §3)
    e.g_series = float(roughness_g(sigma, 1.0 + e.cos_max, e.lam_min))
    e.metrics.update(sigma_nano_nm=sigma * 1e9, sigma_over_lambda=sigma / (e.lam_min * 1e-9), g_max=g_max,
                     g_series_max=e.g_series, scattered_fraction_max=s, tis_max=s * F_max)
    why = (f"σ = {sigma * 1e9:.3g} nm, σ/λ_min = {sigma / (e.lam_min * 1e-9):.3g}, g ≤ {g_max:.3g}, "
           f"scattered fraction ≤ {s:.2g} (TIS ≤ {s * F_max:.2g})")
    if e.force.get("diffraction") is not None or "solver" in e.force:
        e.diffraction = e.force.get("diffraction", True)
        e.decide("diffraction", "on" if e.diffraction else "off", f"forced ({why})")
    elif s < FLAT_SCATTER:
        e.diffraction = False
        e.decide("diffraction", "off", f"{why}: the nano surface is flat at these wavelengths")
    elif e.g_series > PSD_G_MAX:
        e.diffraction = True
        e.decide("diffraction", "on", f"{why}: g(θ_o = 0) = {e.g_series:.3g} > {PSD_G_MAX:g}, almost no coherent "
                                      "reflection is left (and the PSD estimate does not apply)")
    else:
        out = e.scene.output
        hemi = e.sphere or out.rgb_images or out.spectral_brdf or not e.views
        dirs = list(e.light.directions_deg) + ([(t, 0.0) for t in ESTIMATE_SPHERE_THETAS] if e.sphere else [])
        est, info = colour_shift(e.mat, e.micro, e.proxy, e.spd, dirs, views_deg=e.views, hemisphere=hemi,
                                 kd=e.kd)
        e.metrics.update(estimated_delta_e=est, estimate_resolution=info["resolution"])
        e.diffraction = est > ESTIMATE_SHARE * e.dE
        proxy_note = "" if e.statistical else " (height field through a Gaussian-statistics proxy)"
        cmp = ">" if e.diffraction else "≤"
        e.decide("diffraction", "on" if e.diffraction else "off",
                 f"{why}; coarse estimate{proxy_note}: ΔE2000 {est:.2g} {cmp} {ESTIMATE_SHARE:g} × target {e.dE:g}"
                 + ("" if e.diffraction else ", so only the microfacet model runs"))


#: incidence beyond which the tangent-plane factor's excess over the light the coherent lobe gives up is large
#: (measured with the height-field route: the coherent-loss guard trims < 0.2 % below 60°, 40 % at 80°;
#: waveoptics.brdf.twoscale._cap_to_coherent_loss)
KIRCHHOFF_GRAZING_DEG = 75.0
#: largest (4πσ/λ)² (the g of normal incidence and backscatter, the largest over all directions) at which the
#: planner trusts first-order Rayleigh-Rice (its domain is g ≪ 1)
RAYLEIGH_RICE_G_MAX = 0.05


def _decide_diffraction_model(e: _Entry) -> None:
    """The scene's model when it names one; else Kirchhoff, the model whose limits are measured (flat patch = F,
    exp(−g), grating orders, the Beckmann limit), with a note when the light comes near grazing incidence, where
    its factor K grows as 1/cosθ_i (docs/physics.md §10; docs/wave-optics.md compares the models)."""
    if not e.diffraction:
        return
    if e.spec.diffraction != "auto":
        e.diffraction_model = e.spec.diffraction
        e.decide("diffraction model", e.spec.diffraction, "set by the scene")
        return
    e.diffraction_model = "kirchhoff"
    thetas = [t for t, _ in e.light.directions_deg] if not e.sphere else list(np.linspace(0.0, 88.0, 45))
    theta_max = max(thetas)
    # first order holds at an incidence while g = (k σ_rel (cosθ_i + 1))², the largest over its outgoing directions,
    # is small: the sphere's facets see every incidence (normal included), a grazing light only its own
    g_any = (first_order_g(e.proxy, thetas, e.lam_min) if e.spec.nano.kind == "statistics"
             else float(roughness_g(e.proxy.sigma, 2.0, e.lam_min)))
    if theta_max > KIRCHHOFF_GRAZING_DEG and e.spec.nano.kind == "statistics" and g_any <= RAYLEIGH_RICE_G_MAX:
        e.diffraction_model = "rayleigh-rice"
        e.decide("diffraction model", "rayleigh-rice",
                 f"light up to θ_i = {theta_max:g}° > {KIRCHHOFF_GRAZING_DEG:g}° on a surface smooth at these "
                 f"incidences (g = (kσ_rel(cosθ_i + 1))² ≤ {g_any:.2g} ≤ {RAYLEIGH_RICE_G_MAX:g}, first-order "
                 "perturbation theory's domain): beyond 75° the tangent-plane lobe is outside its validity and "
                 "only carries an albedo continued with Rayleigh-Rice's incidence dependence (docs/physics.md §9), "
                 "while Rayleigh-Rice with its polarization factor Q gives the lobe's shape there too and agrees "
                 "with Kirchhoff within 1 % up to 60°")
        return
    why = ("tangent-plane Kirchhoff: the model held against the flat-patch, exp(−g), grating and Beckmann limits; "
           "RGHS differs from it by ~1 % on a rough surface, OHS/ROHS by 36 % at θ_i = 30°")
    if theta_max > KIRCHHOFF_GRAZING_DEG:
        why += (f"; light up to θ_i = {theta_max:g}° > {KIRCHHOFF_GRAZING_DEG:g}°, beyond the tangent plane's "
                "validity: there its lobe carries its 75° albedo continued with first-order perturbation theory's "
                "incidence dependence (docs/physics.md §9)")
    e.decide("diffraction model", "kirchhoff", why)


def _decide_wavelengths(e: _Entry) -> None:
    """Only the lines of a line source; one evaluation when nothing depends on λ; else the coarsest grid that
    meets the colour target on smooth spectra."""
    if e.spd.lines:
        e.w_sim = e.w_colour = colour.simulation_wavelengths(e.spd)
        e.lam_independent = (not e.diffraction) and _constant_over(e.mat, e.w_sim) and e.w_sim.size > 1
        if e.lam_independent:
            e.w_sim = np.array([])
            e.decide("wavelengths", "none (1 evaluation)",
                     f"line source {e.spd.name}, and the BRDF does not depend on λ (constant F, no diffraction): "
                     "one evaluation serves every line")
        else:
            e.decide("wavelengths", _fmt_nm(e.w_sim), f"line source {e.spd.name}: only its visible lines carry light")
    elif not e.diffraction and _constant_over(e.mat, e.w_colour):
        e.lam_independent = True
        e.w_sim = np.array([])
        e.decide("wavelengths", "none (1 evaluation)",
                 f"pure geometric optics with a wavelength-independent Fresnel factor ({e.mat.source}): the BRDF is "
                 f"the same at every λ; evaluated once at {LAMBDA_REF_NM:g} nm, colour over {_fmt_nm(e.w_colour)}")
    else:
        e.lam_independent = False
        e.w_sim = e.w_colour
        e.decide("wavelengths", _fmt_nm(e.w_sim), f"smooth spectra under {e.spd.name}: the coarsest grid whose "
                                                  f"colour error on smooth reflectances stays ≤ ΔE {e.dE:g}")
    e.metrics["wavelength_count"] = int(max(e.w_sim.size, 1))


def _decide_nano_route(e: _Entry) -> None:
    """The PSD series for Gaussian statistics within its range; a height field (fft or direct, chosen by cost
    later) otherwise."""
    e.nano, e.solver = None, "none"
    if not e.diffraction:
        e.decide("solver", "none", "no diffraction: closed-form microfacet model")
        return
    want = e.force.get("solver")
    if want == "psd" and not e.statistical:
        raise FieldError(f"{{force}} solver=psd: material {e.spec.name!r} has a {e.spec.nano.describe()} "
                         "without Gaussian statistics; use fft or direct", "force")
    if want == "psd" or (want is None and e.statistical and e.g_series <= PSD_G_MAX):
        e.solver = "psd"
        e.nano = twoscale.Nano(model=e.proxy)
        e.decide("solver", "psd", "forced" if want else
                 f"Gaussian statistics with g ≤ {PSD_G_MAX:g}: the PSD series is the exact ensemble average at the "
                 "least cost (no height field, tables shared across the spectrum)")
        return
    if e.hf is None:
        e.hf = make_nano(e.spec.nano.text, e.w_colour, solver="fft", seed=e.scene.seed).surface
    e.nano = twoscale.Nano(surface=e.hf)
    e.solver = want  # decided with the cost model (_decide_directions) when None


def _decide_resolution(e: _Entry) -> None:
    """The grid resolves the narrowest lobe within the colour target (or the height field's specular spike)."""
    if e.micro.alpha > 0:
        e.widths["micro lobe"] = lobe_width(min(e.micro.alpha, e.micro.alpha_y or e.micro.alpha), min(e.cos_i))
    if e.diffraction and e.nano is not None and e.nano.model is not None:
        e.widths["nano lobe"] = diffraction_lobe_width(e.nano.model, e.lam_min)
    hi = min(RESOLUTION_RANGE[1], e.max_resolution or RESOLUTION_RANGE[1])
    lo = min(RESOLUTION_RANGE[0], hi)
    if e.scene.output.resolution is not None or "resolution" in e.force:
        e.resolution = int(e.force.get("resolution", e.scene.output.resolution))
        e.decide("resolution", e.resolution, "set by the scene's output.resolution")
        return
    need = {k: int(math.ceil(2.0 / grid_step(s, e.dE))) for k, s in e.widths.items() if s > 0}
    if e.hf is not None and e.diffraction:
        L = max(e.hf.extent)
        need["the height field's specular spike"] = int(math.ceil(2.0 * L / (e.lam_min * 1e-9)))
    if not need:
        e.resolution = lo
        e.decide("resolution", lo, "no lobe to resolve (mirror): the specular spike keeps its energy on any grid")
        return
    key = max(need, key=need.get)
    e.resolution = int(np.clip(need[key], lo, hi))
    note = f"{key} needs {need[key]} cells per side " + (
        f"(du ≤ λ_min/L, L = {L * 1e6:.3g} µm)" if key.startswith("the height") else
        f"(linear interpolation within ΔE {e.dE:g}: du ≤ {grid_step(e.widths[key], e.dE):.3g})")
    if need[key] > hi:
        note += f"; capped at {hi} (narrower lobes keep their energy and colour, not their shape)"
    elif need[key] < lo:
        note += f"; raised to the minimum {lo}"
    e.decide("resolution", e.resolution, note)


def _refine_wavelengths_for_grating(e: _Entry) -> None:
    """A periodic nano surface under a continuous source: its orders move by m Δλ / Λ in direction cosine; keep
    that within one grid cell so the rainbow has no gaps (grating equation, docs/physics.md §5)."""
    periodic = e.diffraction and e.spec.nano.kind == "generator" and e.spec.nano.params["model"] == "sinusoid"
    if not periodic or e.spd.lines:
        return
    du = 2.0 / e.resolution
    period = parse_length(e.spec.nano.params["period"], default_unit="m", name="period")
    amp = parse_length(e.spec.nano.params["amplitude"], default_unit="m", name="amplitude")
    m = grating_orders(amp, period, e.lam_min)
    limit = period * du / m * 1e9
    step = next((s for s in colour.STEPS_NM if s <= limit), colour.STEPS_NM[-1])
    if e.w_sim.size < 2 or step < e.w_sim[1] - e.w_sim[0]:
        e.w_sim = e.w_colour = colour.spectral_grid(e.spd, step)
        i = next(k for k, d in enumerate(e.decisions) if d[0] == "wavelengths")
        e.decisions[i] = ("wavelengths", _fmt_nm(e.w_sim),
                          f"periodic nano surface (Λ = {period * 1e6:.3g} µm, orders up to {m} with efficiency ≥ "
                          f"{ORDER_EFFICIENCY_MIN:g}): Δλ ≤ Λ du / m = {limit:.3g} nm keeps each order's rainbow "
                          "free of gaps on this grid")
        e.metrics["wavelength_count"] = int(e.w_sim.size)


def _direction_options(e: _Entry) -> tuple[dict, float]:
    """Candidate direction sets: the hemisphere, and patches around the view directions when no output needs the
    hemisphere; with the patches' half-width."""
    out = e.scene.output
    hemi_needed = e.sphere or out.rgb_images or out.spectral_brdf
    du = 2.0 / e.resolution
    s_tot = math.sqrt(sum(s * s for s in e.widths.values())) if e.widths else 0.0
    half = PATCH_SIGMAS * s_tot + 2 * du
    options = {"hemisphere": [DirectionGrid.hemisphere(e.resolution)]}
    if e.force.get("directions") == "views" and (hemi_needed or not e.views):
        raise FieldError("{force} directions=views needs view directions and outputs that show no hemisphere "
                         "(tables only, no camera)", "force")
    if e.views and not hemi_needed and e.force.get("directions") != "hemisphere":
        options["views"] = _patch_grids(e.views, e.resolution, half)
    if e.force.get("directions") == "views":
        del options["hemisphere"]
    return options, half


def _costs(e: _Entry, options: dict) -> tuple[dict, dict]:
    """Estimated seconds of every (directions, solver) option, and facts about the height-field solvers."""
    n_eval = len(e.light.directions_deg) + (sphere_evaluations(e.micro, e.nano) if e.sphere else 0)
    n_w = max(e.w_sim.size, 1)
    w_eval = e.w_sim if e.w_sim.size else np.array([LAMBDA_REF_NM])
    terms = psd_terms(e.nano.model.sigma, e.lam_min) if e.solver == "psd" else None
    if terms is not None:
        t_band = band_table_time(e.nano.model, e.lam_min, e.mat, e.light.directions_deg[0][0])
        e.metrics.update(band_table_s=t_band)
    hf_solvers = e.diffraction and e.solver in (None, "fft", "direct")
    hf_info = {"hf_solvers": hf_solvers}
    if hf_solvers:
        smp = scatter.samples(e.hf)
        direct_term, no_direct = direct_calibration(e.device)
        wi0 = direction_from_angles(*e.light.directions_deg[0])
        # the height field's coherent fraction is what its own lobe leaves: one fft lobe on a grid of λ/(3L) cells
        # per wavelength and incidence (the macro ones, and the facet table's nodes under a micro lobe)
        theta0 = e.light.directions_deg[0][0]
        t_char = _best(lambda: twoscale.field_scattered_albedo(e.hf, theta0, e.lam_min), 2)
        hf_info.update(smp=smp, direct_term=direct_term, no_direct=no_direct)
        e.metrics.update(height_field_samples=smp.size, opencl=direct_term is not None, direct_term_s=direct_term,
                         coherent_fraction_s=t_char)
    costs = {}
    N = e.resolution
    for dname, grids in options.items():
        cells = [g.n_u * g.n_v for g in grids]
        base = n_eval * e.cm.evaluation(cells, n_w, diffuse=e.diffuse, psd_terms=terms, nano_lobe=hf_solvers)
        if terms is not None:   # the band tables, once per wavelength for the whole entry, timed on this model
            base += n_w * t_band
        if dname == "views" and e.micro.alpha >= 0.75 * 2.0 / N:  # a patch normalizes its micro lobe on the grid
            base += n_eval * len(grids) * N * N * e.cm.cell
        if not hf_solvers:
            costs[(dname, e.solver)] = base
            continue
        n_field = twoscale.field_albedo_evaluations(
            e.micro, grids[0], direction_from_angles(*np.asarray(e.light.directions_deg, dtype=float).T),
            extra=n_eval - len(e.light.directions_deg))
        base += n_field * n_w * t_char
        # the incoherent lobe is U − χ U_flat: the height field's transforms plus one for the flat patch
        costs[(dname, "fft")] = base + n_eval * fft_solver_units(smp, wi0, grids, w_eval) * e.cm.fft_unit
        if direct_term is not None:
            dirs = sum(int(g.inside.sum()) for g in grids)
            costs[(dname, "direct")] = base + n_eval * 2 * direct_term * smp.size * dirs * n_w
    return costs, hf_info


def _decide_directions(e: _Entry) -> None:
    """The cheapest direction set (and height-field solver) that the outputs allow, by the cost model."""
    options, half = _direction_options(e)
    costs, hf = _costs(e, options)
    if hf["hf_solvers"] and e.solver == "direct" and hf["direct_term"] is None:
        raise FieldError(f"{{force}} solver=direct needs the OpenCL direct sum, unavailable here: {hf['no_direct']}",
                         "force")
    allowed = {k: v for k, v in costs.items() if e.solver in (None, k[1])}
    (e.directions, e.solver), e.time_s = min(allowed.items(), key=lambda kv: kv[1])
    e.metrics["costs_s"] = {f"{d}/{s_}": v for (d, s_), v in costs.items()}
    out = e.scene.output
    if e.force.get("directions"):
        e.decide("directions", e.directions, "forced")
    elif e.sphere or out.rgb_images or out.spectral_brdf:
        need = [n for n, on in (("sphere camera", e.sphere), ("RGB images", out.rgb_images),
                                ("spectral BRDF", out.spectral_brdf)) if on]
        e.decide("directions", "hemisphere", f"the outputs show it: {', '.join(need)}")
    elif "views" in options:
        other = "hemisphere" if e.directions == "views" else "views"
        t_other = min(v for (d, _), v in allowed.items() if d == other)
        t_views, t_hemi = (e.time_s, t_other) if e.directions == "views" else (t_other, e.time_s)
        n_p = sum(g.n_u * g.n_v for g in options["views"])
        e.decide("directions", e.directions,
                 f"{len(e.views)} patches of ±{half:.2g} around the view directions ({n_p} cells): "
                 f"{_fmt_s(t_views)}; the hemisphere ({e.resolution ** 2} cells): {_fmt_s(t_hemi)}")
    else:
        e.decide("directions", "hemisphere", "no view directions: the whole hemisphere")
    if hf["hf_solvers"]:
        _explain_solver(e, costs, hf)
    e.patches = options.get("views", []) if e.directions == "views" else []


def _explain_solver(e: _Entry, costs: dict, hf: dict) -> None:
    """The reason for the height-field solver the cost model chose."""
    if "solver" in e.force:
        e.decide("solver", e.solver, "forced")
        return
    alt = {s_: v for (d, s_), v in costs.items() if d == e.directions}
    smp = hf["smp"]
    why = (f"height field of {smp.nx}x{smp.ny} samples, both exact Kirchhoff: " +
           ", ".join(f"{k} {_fmt_s(v)}" for k, v in sorted(alt.items(), key=lambda kv: kv[1])))
    if hf["direct_term"] is None:
        why += f" (direct sum unavailable: {hf['no_direct']})"
    if e.spec.nano.kind == "statistics":
        why = f"g(θ_o = 0) = {e.g_series:.3g} > {PSD_G_MAX:g} is beyond the PSD series; generated {why}"
    e.decide("solver", e.solver, why)


def _decide_precision(e: _Entry) -> None:
    """float32 for the direct sum unless its noise floor comes near the weakest visible level of the lobe."""
    if e.solver != "direct":
        e.precision = "float64"
        e.decide("precision", "float64", "NumPy float64 throughout (no OpenCL kernel on this route)")
        return
    h_max = float(np.max(np.abs(e.hf.heights - e.hf.heights.mean())))
    floor = float32_floor(e.hf.heights.size, h_max, e.lam_min)
    level = weakest_level(e.dE, max(e.hf.extent), e.lam_min)
    e.metrics.update(float32_floor=floor, weakest_level=level)
    if "precision" in e.force:
        e.precision = e.force["precision"]
        e.decide("precision", e.precision, "forced")
    else:
        e.precision = "float64" if floor > FLOOR_MARGIN * level else "float32"
        cmp = ">" if e.precision == "float64" else "≤"
        e.decide("precision", e.precision, f"float32 noise floor {floor:.2g} {cmp} {FLOOR_MARGIN:g} × weakest "
                                           f"visible level {level:.2g} of the peak")
    if e.precision == "float64" and not get_runtime(e.device).fp64:
        e.precision = "float32"
        e.decide("precision", "float32", "the OpenCL device has no fp64 (float64 was wanted)")


#: the decisions, in the order they are taken (each reads the outcomes of those before it)
DECISIONS = (_decide_diffuse, _decide_diffraction, _decide_diffraction_model, _decide_wavelengths,
             _decide_nano_route, _decide_resolution, _refine_wavelengths_for_grating, _decide_directions,
             _decide_precision, _decide_multiple_scattering)


def _plan_entry(scene: Scene, spec: MaterialSpec, light, force: dict, cm: CostModel, device,
                max_resolution: int | None) -> EntryPlan:
    """Plan one (material, light) pair: take every decision of :data:`DECISIONS` in turn."""
    e = _Entry(scene, spec, light, force, cm, device, max_resolution)
    e.mat = get_material(spec.material)
    e.spd = colour.illuminant(light.spd)
    e.micro = spec.micro()
    e.cos_i = [math.cos(math.radians(t)) for t, _ in light.directions_deg]
    e.cos_max = 1.0 if e.sphere else max(e.cos_i)
    e.w_colour = colour.simulation_wavelengths(e.spd, e.dE)
    e.lam_min = float(np.min(e.w_colour))
    for decide in DECISIONS:
        decide(e)
    effects = {"specular": True, "diffraction": bool(e.diffraction), "diffuse": bool(e.diffuse),
               "multiple_scattering": bool(e.spec.multiple_scattering),
               "spectral": not e.lam_independent, "sphere": e.sphere}
    return EntryPlan(spec=spec, light_name=light.name, spd=e.spd, material=e.mat,
                     light_directions_deg=light.directions_deg, micro=e.micro, nano=e.nano, effects=effects,
                     solver=e.solver, resolution=e.resolution, directions=e.directions, view_directions_deg=e.views,
                     wavelengths_nm=e.w_sim, colour_wavelengths_nm=e.w_colour, precision=e.precision, kd=e.kd,
                     sphere=e.sphere, estimated_time_s=float(e.time_s), patches=e.patches, decisions=e.decisions,
                     metrics=e.metrics, forced=dict(force), diffraction=e.diffraction_model)


def plan_scene(scene: Scene, *, force: dict | None = None, device=None, max_resolution: int | None = None,
               recalibrate: bool = False) -> Plan:
    """Plan a scene: decide, for every material under every light, the effects, solver, grid and wavelengths.

    Parameters
    ----------
    force : dict, optional
        Overrides from :func:`parse_force` (e.g. ``{"diffraction": True}``).
    device : str, optional
        OpenCL device for the direct solver's calibration.
    max_resolution : int, optional
        Cap on the direction grid (the scene's ``output.resolution`` is used as given).
    recalibrate : bool
        Time the cost model again instead of using this machine's cached calibration (:func:`calibration`).

    Returns
    -------
    Plan
    """
    t0 = time.perf_counter()
    force = dict(force or {})
    cm = calibration(recalibrate=recalibrate)
    entries = [_plan_entry(scene, m, light, force, cm, device, max_resolution)
               for m in scene.materials for light in scene.lights]
    return Plan(scene=scene, entries=entries, cost_model=cm, planning_time_s=time.perf_counter() - t0, force=force)
