"""The effect planner: decide from physics which effects a scene needs, simulate only those, say why.

For every (material, light) pair of a :class:`waveoptics.scene.Scene` the planner takes, in order:

``diffuse``
    Metals absorb the refracted light: no diffuse term. Dielectrics get the substrate's diffuse term (with the
    diffuse-specular trade-off of :mod:`waveoptics.microfacet`) unless their diffuse albedo is 0.
``diffraction``
    The nano surface reflects the fraction exp(−g), g = (4π σ cos θ_i / λ)², coherently and scatters the rest,
    TIS = F (1 − exp(−g)) (Davies 1954; Bennett & Porteus 1961; physics.md §2). Whether that scattered light
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
    (:func:`waveoptics.spectral.simulation_wavelengths`), refined for a periodic nano surface of period Λ so that
    neighbouring wavelengths of diffraction order m land no further apart than one grid cell, Δλ ≤ Λ du / m
    (grating equation, physics.md §5).
``solver``
    Statistics with g ≤ :data:`PSD_G_MAX`: the PSD series (:mod:`waveoptics.psd`; exact ensemble average for
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

Costs come from a calibration timed once per process on this machine (:func:`calibrate`): seconds per grid
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

import functools
import math
import re
import time
from dataclasses import dataclass, field

import numpy as np

from . import psd, spectral, surfaces, twoscale
from .diffraction import DirectionGrid
from .errors import WaveopticsError, unknown
from .materials import Material, get_material
from .scene import MaterialSpec, Scene
from .units import direction_from_angles, parse_length

# --- thresholds (docs/planning.md lists them with the decisions they drive) -------------------------------------

#: cells per side of the coarse grid on which the colour shift of diffraction is estimated
ESTIMATE_RESOLUTION = 32
#: wavelength step (nm) of the coarse estimate (line sources use their lines)
ESTIMATE_STEP_NM = 40.0
#: extra incidence angles (degrees) probed when a sphere camera sees every incidence
ESTIMATE_SPHERE_THETAS = (0.0, 45.0, 75.0)
#: diffraction runs when the estimated ΔE2000 exceeds this share of the target
ESTIMATE_SHARE = 0.5
#: largest g = (4πσ cosθ/λ)² for which the PSD series is trusted (psd.py: truncation loses energy beyond)
PSD_G_MAX = 30.0
#: scattered fractions below this are "flat" (no estimate is run)
FLAT_SCATTER = 1e-9
#: smallest and largest direction grid (cells per side) the planner picks
RESOLUTION_RANGE = (32, 256)
#: CIE L* slope dL*/dln Y at L* = 50 (Y = 0.1842): 116/3 · Y^(1/3) = 22.0 ΔE per unit relative luminance
DE_PER_RELATIVE_Y = 116.0 / 3.0 * ((50.0 + 16.0) / 116.0)
#: CIE L* = 903.3 Y near black: the luminance of a just-visible haze is ΔE / 903.3
LSTAR_SLOPE_BLACK = 903.3
#: view patches span this many lobe standard deviations around each view direction
PATCH_SIGMAS = 3.0
#: wavelength (nm) at which a wavelength-independent BRDF is evaluated
LAMBDA_REF_NM = 550.0
#: relative spread of F over the spectrum below which a material counts as wavelength-independent
F_FLAT_TOL = 1e-9
#: float32 unit round-off
EPS32 = 2.0**-24
#: float32 is fine while its noise floor stays below this share of the weakest light the target resolves
FLOOR_MARGIN = 0.1
#: diffraction orders with efficiency below this are ignored for the wavelength step of gratings
ORDER_EFFICIENCY_MIN = 1e-3

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
            raise unknown("--force effect", key, FORCEABLE)
        if key in ("diffraction", "diffuse"):
            if val not in _ON:
                raise WaveopticsError(f"--force {item!r}: {key} takes on or off")
            out[key] = _ON[val]
        elif val not in FORCEABLE[key]:
            raise WaveopticsError(f"--force {item!r} is not allowed; {key} takes {', '.join(FORCEABLE[key])}")
        else:
            out[key] = val
    return out


# ----------------------------------------------------------------------------------------------------------------
# Physics of the decisions (small pure functions)
# ----------------------------------------------------------------------------------------------------------------

def g_factor(sigma_m, cos_theta, wavelength_nm):
    """Roughness factor g = (4π σ cos θ / λ)² (physics.md §2); σ in m, λ in nm."""
    return (4 * np.pi * sigma_m * np.asarray(cos_theta) / (np.asarray(wavelength_nm) * 1e-9)) ** 2


def scattered_fraction(nano: twoscale.Nano, cos_theta, wavelength_nm) -> np.ndarray:
    """1 − A: the share of the specular light the nano surface scatters (1 − exp(−g) for Gaussian heights).

    References
    ----------
    .. [1] Davies 1954; Bennett & Porteus 1961 (TIS = F (1 − exp(−g))).
    """
    return 1.0 - np.asarray(nano.coherent_amplitude2(cos_theta, wavelength_nm), dtype=float)


def lobe_width(alpha: float, cos_theta_i: float) -> float:
    """Standard deviation (direction cosines) of a microfacet lobe of roughness α along its narrow axis.

    The facet tilt has rms α/√2 per axis and the reflected direction turns twice as far; along the plane of
    incidence the direction cosine is compressed by cos θ (floored at 0.5: beyond 60° no grid resolves it).
    """
    return math.sqrt(2.0) * alpha * max(cos_theta_i, 0.5)


def diffraction_lobe_width(model: psd.PSDModel, wavelength_nm: float) -> float:
    """Standard deviation (direction cosines) of the nano lobe: λ / (√2 π ℓ) for correlation length ℓ.

    For a Gaussian PSD π σ² T² exp(−π² T² f²) the spatial frequency has rms 1/(√2 π T) per axis, and a frequency
    f turns the light by λ f in direction cosines (physics.md §4).
    """
    return wavelength_nm * 1e-9 / (math.sqrt(2.0) * math.pi * model.length_scale)


def grid_step(width: float, delta_e: float) -> float:
    """Largest direction-cosine spacing that interpolates a lobe of std *width* within *delta_e* (ΔE2000).

    Linear interpolation errs by ≤ du² max|f''| / 8 = du² / (8 s²) of the peak of a Gaussian of std s (de Boor
    1978); ε relative luminance costs DE_PER_RELATIVE_Y · ε of ΔE2000 (CIE 015 L*, Luo et al. 2001).
    """
    return width * math.sqrt(8.0 * delta_e / DE_PER_RELATIVE_Y)


def float32_floor(n_samples: int, h_max_m: float, wavelength_nm: float) -> float:
    """Relative noise power of the float32 direct sum against the coherent peak (see the module notes)."""
    return EPS32**2 * (n_samples / 256.0 + (4 * np.pi * h_max_m / (wavelength_nm * 1e-9)) ** 2 / max(n_samples, 1))


def weakest_level(delta_e: float, patch_m: float, wavelength_nm: float) -> float:
    """BRDF of a just-visible haze, ΔE/(903.3 π), relative to the coherent spike F (L/λ)² of a patch of size L."""
    return delta_e / (LSTAR_SLOPE_BLACK * np.pi) * (wavelength_nm * 1e-9 / patch_m) ** 2


def grating_orders(amplitude_m: float, period_m: float, wavelength_nm: float) -> int:
    """Highest order m with Raman-Nath efficiency J_m²(4π a/λ) ≥ ORDER_EFFICIENCY_MIN that leaves the surface.

    References
    ----------
    .. [1] physics.md §5 (η_m = J_m²(4π a/λ) at normal incidence); Harvey & Pfisterer 2020.
    """
    from scipy.special import jv

    lam = wavelength_nm * 1e-9
    m_geo = int(math.floor(2 * period_m / lam))        # |sinθ_m − sinθ_i| ≤ 2
    x = 4 * math.pi * amplitude_m / lam
    m = [k for k in range(1, m_geo + 1) if jv(k, x) ** 2 >= ORDER_EFFICIENCY_MIN]
    return max(m) if m else 1


# ----------------------------------------------------------------------------------------------------------------
# Cost model, calibrated on this machine once per process
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class CostModel:
    """Seconds per unit of work, measured by :func:`calibrate` (``direct_term`` by :func:`calibrate_direct`)."""

    call: float             # per two-scale evaluation on one grid (set-up, micro albedo quadrature)
    cell: float             # per direction cell (micro geometry)
    cell_wl: float          # per cell and wavelength (Fresnel, coherent part)
    diffuse_cell_wl: float  # per cell and wavelength (diffuse term of dielectrics)
    psd_wl: float           # per grid and wavelength (nano lobe set-up)
    psd_cell_wl: float      # per cell and wavelength (nano lobe, micro convolution)
    psd_term: float         # per cell, wavelength and PSD series term
    fft_unit: float         # per chirp-z work unit (see fft_units)
    calibration_s: float

    def evaluation(self, cells, n_wl: int, *, diffuse: bool = False, psd_terms: int | None = None,
                   nano_lobe: bool = False) -> float:
        """Seconds of one two-scale evaluation over grids with *cells* cells each (a list), *n_wl* wavelengths.

        *psd_terms*: the PSD series' number of terms (PSD route); *nano_lobe*: a height-field lobe is convolved
        (its solver's own cost comes on top).
        """
        t = 0.0
        for c in cells:
            t += self.call + c * (self.cell + n_wl * (self.cell_wl + (self.diffuse_cell_wl if diffuse else 0.0)))
            if psd_terms is not None:
                t += n_wl * (self.psd_wl + c * (self.psd_cell_wl + psd_terms * self.psd_term))
            elif nano_lobe:
                t += n_wl * (self.psd_wl + c * self.psd_cell_wl)
        return t

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def _best(fn, repeat=3) -> float:
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def fft_units(n_samples_xy, n_cells_uv) -> float:
    """Work of one 2-D chirp-z transform (rows then columns, Bluestein lengths n + m): Σ n log2 n."""
    nx, ny = n_samples_xy
    nu, nv = n_cells_uv
    lx, ly = nx + nu, ny + nv
    return ny * lx * math.log2(lx) + nu * ly * math.log2(ly)


def psd_terms(sigma_m: float, wavelength_nm: float) -> int:
    """Series terms :func:`waveoptics.psd.scattered_lobe` sums: g + 8√g + 10 (at most 48), g ≤ (2kσ)²."""
    g = float(g_factor(sigma_m, 1.0, wavelength_nm))
    return int(min(48, math.ceil(g + 8 * math.sqrt(g) + 10)))


@functools.lru_cache(maxsize=1)
def calibrate() -> CostModel:
    """Time small runs of each code path (two-scale micro, diffuse, PSD lobe; a chirp-z transform) on this machine.

    Each cost is a non-negative least-squares fit (scipy ``nnls``) of timed runs on grids of 16² to 64² cells with
    1 to 6 wavelengths and 11 or 41 PSD series terms to the linear model of :meth:`CostModel.evaluation`; best of
    a few repeats each, so that a busy machine inflates the fit as little as possible.
    """
    from scipy.optimize import nnls

    from . import diffraction

    t0 = time.perf_counter()
    wi = direction_from_angles(30.0, 0.0)
    metal, diel = get_material("f0:0.9"), get_material("1.5")
    micro = twoscale.Micro(0.2, ndf="ggx")
    grids = {n: DirectionGrid.hemisphere(n) for n in (16, 32, 64)}
    wls = {k: np.linspace(420.0, 680.0, k) for k in (1, 3, 6)}

    def t(n, k, mat=metal, nano=None, repeat=3):
        f = lambda: twoscale.evaluate(wi, wls[k], mat, micro, nano, grids[n], kd=0.5)  # noqa: E731
        return _best(f, repeat)

    runs = [(16, 1), (64, 1), (64, 6), (32, 3)]
    mf = {r: t(*r) for r in runs}
    A = np.array([[1.0, n * n, n * n * k] for n, k in runs])
    (call, cell, cell_wl), _ = nnls(A, np.array([mf[r] for r in runs]))
    diffuse = max(t(64, 6, diel) - mf[(64, 6)], 0.0) / (6 * 64 * 64)
    # PSD lobe on top of the micro model: series tables built first (not timed)
    nanos = {sg: twoscale.Nano(model=psd.PSDModel("gaussian", sigma=sg, T=1e-6)) for sg in (0.2e-9, 100e-9)}
    for nano in nanos.values():
        t(16, 3, nano=nano, repeat=1)
    runs = [(16, 0.2e-9), (64, 0.2e-9), (64, 100e-9), (32, 100e-9)]
    rows, y = [], []
    for n, sg in runs:
        k = psd_terms(sg, 420.0)
        rows.append([3.0, 3.0 * n * n, 3.0 * n * n * k])
        y.append(max(t(n, 3, nano=nanos[sg], repeat=2) - t(n, 3, repeat=2), 0.0))
    (psd_wl, psd_cell_wl, psd_term), _ = nnls(np.array(rows), np.array(y))
    # fft: one chirp-z transform of a 128² patch onto a 32² grid
    hf = surfaces.generate("flat", size=128 * 100e-9, samples=128)
    smp = diffraction.samples(hf)
    t_fft = _best(lambda: diffraction.field_fft(smp, wi, grids[32], 550.0, order=0), 2)
    fft_unit = t_fft / fft_units((smp.nx, smp.ny), (32, 32))
    return CostModel(float(call), float(cell), float(cell_wl), diffuse, float(psd_wl), float(psd_cell_wl),
                     float(psd_term), fft_unit, time.perf_counter() - t0)


@functools.lru_cache(maxsize=4)
def calibrate_direct(device: str | None = None, precision: str = "float32") -> tuple[float | None, str]:
    """(seconds per sample·direction·wavelength of the OpenCL direct sum, "") or (None, why it is unavailable)."""
    from . import runtime

    if not runtime.opencl_available():
        return None, "no OpenCL platform"
    try:
        return _time_direct(runtime.get_runtime(device), precision), ""
    except WaveopticsError as exc:  # no device of that name, or the kernel does not build here
        return None, str(exc).splitlines()[0]


def _time_direct(rt, precision):
    from . import diffraction

    if precision == "float64" and not rt.fp64:
        precision = "float32"
    hf = surfaces.generate("sinusoid", amplitude=40e-9, period=1.6e-6, size=128 * 100e-9, samples=128)
    smp = diffraction.samples(hf)
    g = DirectionGrid.hemisphere(24)
    wo = g.directions()[g.inside]
    coef = diffraction.phase_coefficients(smp, direction_from_angles(30.0, 0.0), wo, [550.0])
    diffraction.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision)      # build + warm-up
    t = _best(lambda: diffraction.kirchhoff_U_cl(smp, coef, runtime=rt, precision=precision), 2)
    return t / (coef.size * smp.size)


# ----------------------------------------------------------------------------------------------------------------
# The plan
# ----------------------------------------------------------------------------------------------------------------

@dataclass
class EntryPlan:
    """Decisions for one (material, light) pair of a scene."""

    spec: MaterialSpec
    light_name: str
    spd: spectral.SPD
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

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def reasons(self) -> list:
        return [f"{d}: {v} — {r}" for d, v, r in self.decisions]

    @property
    def evaluations(self) -> int:
        from .simulate import SPHERE_THETAS_DEG

        return len(self.light_directions_deg) + (len(SPHERE_THETAS_DEG) if self.sphere else 0)

    def as_dict(self) -> dict:
        return {
            "name": self.name, "light": self.light_name, "material": self.material.name,
            "material_source": self.material.source, "category": self.material.category,
            "illuminant": self.spd.name, "effects": self.effects, "solver": self.solver,
            "resolution": self.resolution, "directions": self.directions,
            "light_directions_deg": [list(d) for d in self.light_directions_deg],
            "view_directions_deg": [list(d) for d in self.view_directions_deg],
            "wavelengths_nm": self.wavelengths_nm, "colour_wavelengths_nm": self.colour_wavelengths_nm,
            "evaluations": self.evaluations, "precision": self.precision,
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

def _proxy_model(spec: MaterialSpec, hf) -> psd.PSDModel:
    """PSD statistics standing in for a height field in the colour estimate (the generator's own when known)."""
    from .simulate import parse_nano

    n = spec.nano
    if n.kind == "statistics":
        model, p = parse_nano(n.text)
        return psd.PSDModel(model, sigma=p["sigma"], T=p.get("T"), B=p.get("B"), C=p.get("C"))
    p = n.params
    if n.kind == "generator" and p["model"] in psd.PSD_MODELS:
        sig = surfaces.rms_height(hf)
        if p["model"] == "abc":
            return psd.PSDModel("abc", sigma=sig, B=parse_length(p["B"], default_unit="m", name="B"), C=float(p["C"]))
        return psd.PSDModel(p["model"], sigma=sig, T=parse_length(p["corr_length"], default_unit="m",
                                                                  name="corr_length"))
    sigma = surfaces.rms_height(hf)
    T = surfaces.correlation_length(hf)
    if not np.isfinite(T) or T <= 0:
        T = max(hf.extent) / 2
    return psd.PSDModel("gaussian", sigma=max(sigma, 1e-15), T=float(T))


# ----------------------------------------------------------------------------------------------------------------
# Colour estimate of the diffraction's effect
# ----------------------------------------------------------------------------------------------------------------

def colour_shift(material, micro, model: psd.PSDModel, spd, light_dirs_deg, *, views_deg=(), hemisphere=True,
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
    from . import render

    w = spectral.spectral_grid(spd) if spd.lines else spectral.spectral_grid(spd, step_nm)
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
                vals.append(render.lookup(f[None], np.array([0.0]), grid, np.zeros(len(vd)), vd[:, 0], vd[:, 1]))
            q.append(np.pi * wi[2] * np.concatenate(vals))
        rgb = [spectral.reflectance_to_rgb(x, w, spd) for x in q]
        dE = spectral.delta_e2000(rgb[0], rgb[1])
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


def _plan_entry(scene: Scene, spec: MaterialSpec, light, force: dict, cm: CostModel, device,
                max_resolution: int | None) -> EntryPlan:
    from . import diffraction
    from .simulate import SPHERE_THETAS_DEG, make_nano

    mat = get_material(spec.material)
    spd = spectral.illuminant(light.spd)
    dE = scene.delta_e
    out = scene.output
    sphere = scene.view.camera == "sphere"
    views = scene.view.directions_deg
    decisions, metrics = [], {}
    micro = twoscale.Micro(alpha=spec.roughness, ndf=spec.ndf, shadowing=spec.shadowing)
    cos_i = [math.cos(math.radians(t)) for t, _ in light.directions_deg]
    cos_max = 1.0 if sphere else max(cos_i)
    w_colour = spectral.simulation_wavelengths(spd, dE)
    lam_min = float(np.min(w_colour))

    # --- diffuse -------------------------------------------------------------------------------------------------
    if mat.is_metal:
        if force.get("diffuse") is True:
            raise WaveopticsError(f"--force diffuse: material {spec.name!r} ({mat.name}) is a metal; metals absorb "
                                  "the refracted light and have no diffuse term")
        diffuse = False
        decisions.append(("diffuse", "off", f"{mat.name} is a metal: the refracted light is absorbed, no diffuse "
                                            "term"))
    elif "diffuse" in force:
        diffuse = force["diffuse"]
        decisions.append(("diffuse", "on" if diffuse else "off", "forced"))
    elif spec.diffuse_albedo == 0:
        diffuse = False
        decisions.append(("diffuse", "off", "diffuse_albedo = 0"))
    else:
        diffuse = True
        decisions.append(("diffuse", "on", f"{mat.category} substrate with diffuse albedo {spec.diffuse_albedo:g} "
                                           "(with the diffuse-specular trade-off)"))
    kd = spec.diffuse_albedo if diffuse else 0.0

    # --- diffraction ---------------------------------------------------------------------------------------------
    hf = None
    if spec.nano is None:
        if force.get("diffraction") or "solver" in force:
            raise WaveopticsError(f"--force diffraction: material {spec.name!r} has no nano surface "
                                  "(add [materials.nano] with statistics, generator or file)")
        diffraction_on = False
        decisions.append(("diffraction", "off", "no nano surface given: the microfacet model is the whole BRDF"))
    else:
        if spec.nano.kind != "statistics":
            hf = spec.nano.height_field(scene.seed)
        proxy = _proxy_model(spec, hf)
        probe = twoscale.Nano(surface=hf) if hf is not None else twoscale.Nano(model=proxy)
        s = float(np.max(scattered_fraction(probe, cos_max, lam_min)))
        Fmax = float(np.max(mat.F(np.array([cos_max]), w_colour)))
        g_max = float(g_factor(proxy.sigma, cos_max, lam_min))
        # the PSD series' own g = (kσ(cosθ_i + cosθ_o))² peaks towards the normal (physics.md §3)
        g_series = float(g_factor(proxy.sigma, (1.0 + cos_max) / 2, lam_min))
        metrics.update(sigma_nano_nm=proxy.sigma * 1e9, sigma_over_lambda=proxy.sigma / (lam_min * 1e-9),
                       g_max=g_max, g_series_max=g_series, scattered_fraction_max=s, tis_max=s * Fmax)
        why = (f"σ = {proxy.sigma * 1e9:.3g} nm, σ/λ_min = {proxy.sigma / (lam_min * 1e-9):.3g}, g ≤ {g_max:.3g}, "
               f"scattered fraction ≤ {s:.2g} (TIS ≤ {s * Fmax:.2g})")
        if force.get("diffraction") is not None or "solver" in force:
            diffraction_on = force.get("diffraction", True)
            decisions.append(("diffraction", "on" if diffraction_on else "off", f"forced ({why})"))
        elif s < FLAT_SCATTER:
            diffraction_on = False
            decisions.append(("diffraction", "off", f"{why}: the nano surface is flat at these wavelengths"))
        elif g_series > PSD_G_MAX:
            diffraction_on = True
            decisions.append(("diffraction", "on", f"{why}: g(θ_o = 0) = {g_series:.3g} > {PSD_G_MAX:g}, almost "
                                                   "no coherent reflection is left (and the PSD estimate does not "
                                                   "apply)"))
        else:
            hemi = sphere or out.rgb_images or out.spectral_brdf or not views
            dirs = list(light.directions_deg) + ([(t, 0.0) for t in ESTIMATE_SPHERE_THETAS] if sphere else [])
            est, info = colour_shift(mat, micro, proxy, spd, dirs, views_deg=views, hemisphere=hemi, kd=kd)
            metrics.update(estimated_delta_e=est, estimate_resolution=info["resolution"])
            diffraction_on = est > ESTIMATE_SHARE * dE
            proxy_note = "" if spec.nano.kind == "statistics" or spec.nano.params.get("model") in psd.PSD_MODELS \
                else " (height field through a Gaussian-statistics proxy)"
            cmp = ">" if diffraction_on else "≤"
            decisions.append(("diffraction", "on" if diffraction_on else "off",
                              f"{why}; coarse estimate{proxy_note}: ΔE2000 {est:.2g} {cmp} {ESTIMATE_SHARE:g} × "
                              f"target {dE:g}" + ("" if diffraction_on else ", so only the microfacet model runs")))

    # --- wavelengths ---------------------------------------------------------------------------------------------
    periodic = (diffraction_on and spec.nano.kind == "generator" and spec.nano.params["model"] == "sinusoid")
    if spd.lines:
        w_sim = spectral.simulation_wavelengths(spd)
        w_colour = w_sim
        lam_independent = (not diffraction_on) and _constant_over(mat, w_sim) and w_sim.size > 1
        if lam_independent:
            w_sim = np.array([])
            decisions.append(("wavelengths", "none (1 evaluation)",
                              f"line source {spd.name}, and the BRDF does not depend on λ (constant F, no "
                              "diffraction): one evaluation serves every line"))
        else:
            decisions.append(("wavelengths", _fmt_nm(w_sim), f"line source {spd.name}: only its visible lines carry "
                                                             "light"))
    elif not diffraction_on and _constant_over(mat, w_colour):
        lam_independent = True
        w_sim = np.array([])
        decisions.append(("wavelengths", "none (1 evaluation)",
                          f"pure geometric optics with a wavelength-independent Fresnel factor ({mat.source}): "
                          f"the BRDF is the same at every λ; evaluated once at {LAMBDA_REF_NM:g} nm, colour over "
                          f"{_fmt_nm(w_colour)}"))
    else:
        lam_independent = False
        w_sim = w_colour
        step = float(w_sim[1] - w_sim[0]) if w_sim.size > 1 else 0.0
        reason = (f"smooth spectra under {spd.name}: the coarsest grid whose colour error on smooth reflectances "
                  f"stays ≤ ΔE {dE:g}")
        decisions.append(("wavelengths", _fmt_nm(w_sim), reason))
    metrics["wavelength_count"] = int(max(w_sim.size, 1))

    # --- solver --------------------------------------------------------------------------------------------------
    nano_obj, solver = None, "none"
    if diffraction_on:
        statistical = spec.nano.kind == "statistics" or spec.nano.params.get("model") in psd.PSD_MODELS
        want = force.get("solver")
        if want == "psd" and not statistical:
            raise WaveopticsError(f"--force solver=psd: material {spec.name!r} has a {spec.nano.describe()} "
                                  "without Gaussian statistics; use fft or direct")
        if want == "psd" or (want is None and statistical and g_series <= PSD_G_MAX):
            solver = "psd"
            nano_obj = twoscale.Nano(model=proxy)
            decisions.append(("solver", "psd", "forced" if want else
                              f"Gaussian statistics with g ≤ {PSD_G_MAX:g}: the PSD series is the exact ensemble "
                              "average at the least cost (no height field, tables shared across the spectrum)"))
        else:
            if hf is None:
                hf = make_nano(spec.nano.text, w_colour, solver="fft", seed=scene.seed).surface
            nano_obj = twoscale.Nano(surface=hf)
            solver = want  # decided with the cost model below when None
    else:
        decisions.append(("solver", "none", "no diffraction: closed-form microfacet model"))

    # --- resolution ----------------------------------------------------------------------------------------------
    widths = {}
    if spec.roughness > 0:
        widths["micro lobe"] = lobe_width(spec.roughness, min(cos_i))
    if diffraction_on and nano_obj is not None and nano_obj.model is not None:
        widths["nano lobe"] = diffraction_lobe_width(nano_obj.model, lam_min)
    hi = min(RESOLUTION_RANGE[1], max_resolution or RESOLUTION_RANGE[1])
    lo = min(RESOLUTION_RANGE[0], hi)
    if out.resolution is not None or "resolution" in force:
        N = int(force.get("resolution", out.resolution))
        decisions.append(("resolution", N, "set by the scene's output.resolution"))
    else:
        need = {k: int(math.ceil(2.0 / grid_step(s, dE))) for k, s in widths.items() if s > 0}
        if hf is not None and diffraction_on:
            L = max(hf.extent)
            need["the height field's specular spike"] = int(math.ceil(2.0 * L / (lam_min * 1e-9)))
        if need:
            key = max(need, key=need.get)
            N = int(np.clip(need[key], lo, hi))
            note = f"{key} needs {need[key]} cells per side " + (
                f"(du ≤ λ_min/L, L = {L * 1e6:.3g} µm)" if key.startswith("the height") else
                f"(linear interpolation within ΔE {dE:g}: du ≤ {grid_step(widths[key], dE):.3g})")
            if need[key] > hi:
                note += f"; capped at {hi} (narrower lobes keep their energy and colour, not their shape)"
            elif need[key] < lo:
                note += f"; raised to the minimum {lo}"
        else:
            N, note = lo, "no lobe to resolve (mirror): the specular spike keeps its energy on any grid"
        decisions.append(("resolution", N, note))
    du = 2.0 / N
    if periodic and not spd.lines:
        # grating equation: order m moves by m Δλ / Λ in direction cosine; keep that within one cell
        period = parse_length(spec.nano.params["period"], default_unit="m", name="period")
        amp = parse_length(spec.nano.params["amplitude"], default_unit="m", name="amplitude")
        m = grating_orders(amp, period, lam_min)
        limit = period * du / m * 1e9
        step = next((s for s in spectral.STEPS_NM if s <= limit), spectral.STEPS_NM[-1])
        if w_sim.size < 2 or step < w_sim[1] - w_sim[0]:
            w_sim = w_colour = spectral.spectral_grid(spd, step)
            i = next(k for k, d in enumerate(decisions) if d[0] == "wavelengths")
            decisions[i] = ("wavelengths", _fmt_nm(w_sim),
                            f"periodic nano surface (Λ = {period * 1e6:.3g} µm, orders up to {m} with efficiency ≥ "
                            f"{ORDER_EFFICIENCY_MIN:g}): Δλ ≤ Λ du / m = {limit:.3g} nm keeps each order's "
                            "rainbow free of gaps on this grid")
            metrics["wavelength_count"] = int(w_sim.size)

    # --- directions and (height-field) solver, by cost ------------------------------------------------------------
    hemi_needed = sphere or out.rgb_images or out.spectral_brdf
    s_tot = math.sqrt(sum(s * s for s in widths.values())) if widths else 0.0
    half = PATCH_SIGMAS * s_tot + 2 * du
    hemi = DirectionGrid.hemisphere(N)
    options = {"hemisphere": [hemi]}
    if force.get("directions") == "views" and (hemi_needed or not views):
        raise WaveopticsError("--force directions=views needs view directions and outputs that show no "
                              "hemisphere (tables only, no camera)")
    if views and not hemi_needed and force.get("directions") != "hemisphere":
        options["views"] = _patch_grids(views, N, half)
    if force.get("directions") == "views":
        del options["hemisphere"]
    n_eval = len(light.directions_deg) + (len(SPHERE_THETAS_DEG) if sphere else 0)
    n_w = max(w_sim.size, 1)
    w_eval = w_sim if w_sim.size else np.array([LAMBDA_REF_NM])
    terms = psd_terms(nano_obj.model.sigma, lam_min) if solver == "psd" else None
    costs = {}                                     # (directions, solver) -> seconds
    hf_solvers = diffraction_on and solver in (None, "fft", "direct")
    if hf_solvers:
        smp = diffraction.samples(hf)
        direct_term, no_direct = calibrate_direct(device)
        has_cl = direct_term is not None
        wi0 = direction_from_angles(*light.directions_deg[0])
        # the height field's own coherent fraction (a histogram of its heights) is computed per grid and λ
        probe = twoscale.Nano(surface=hf)
        t_char = _best(lambda: probe.coherent_amplitude2(cos_max, lam_min), 1)
        metrics.update(height_field_samples=smp.size, opencl=has_cl, direct_term_s=direct_term,
                       coherent_fraction_s=t_char)
    for dname, grids in options.items():
        cells = [g.n_u * g.n_v for g in grids]
        base = n_eval * cm.evaluation(cells, n_w, diffuse=diffuse, psd_terms=terms, nano_lobe=hf_solvers)
        if dname == "views" and spec.roughness >= 0.75 * du:  # a patch normalizes its micro lobe on the whole grid
            base += n_eval * len(grids) * N * N * cm.cell
        if hf_solvers:
            base += n_eval * len(grids) * n_w * t_char
        if not hf_solvers:
            costs[(dname, solver)] = base
            continue
        # the incoherent lobe is U − χ U_flat: the height field's transforms plus one for the flat patch
        units = sum((1 + sum(K + 1 for _, K, _ in diffraction.fft_plan(smp, wi0, g, float(lam), "auto")))
                    * fft_units((smp.nx, smp.ny), (g.n_u, g.n_v)) for g in grids for lam in w_eval)
        costs[(dname, "fft")] = base + n_eval * units * cm.fft_unit
        if direct_term is not None:
            dirs = sum(int(g.inside.sum()) for g in grids)
            costs[(dname, "direct")] = base + n_eval * 2 * direct_term * smp.size * dirs * n_w
    if hf_solvers and solver == "direct" and not has_cl:
        raise WaveopticsError(f"--force solver=direct needs the OpenCL direct sum, unavailable here: {no_direct}")
    allowed = {k: v for k, v in costs.items() if solver in (None, k[1])}
    (directions, solver), t = min(allowed.items(), key=lambda kv: kv[1])
    metrics["costs_s"] = {f"{d}/{s_}": v for (d, s_), v in costs.items()}
    if force.get("directions"):
        decisions.append(("directions", directions, "forced"))
    elif hemi_needed:
        need = [n for n, on in (("sphere camera", sphere), ("RGB images", out.rgb_images),
                                ("spectral BRDF", out.spectral_brdf)) if on]
        decisions.append(("directions", "hemisphere", f"the outputs show it: {', '.join(need)}"))
    elif "views" in options:
        other = "hemisphere" if directions == "views" else "views"
        t_other = min(v for (d, _), v in allowed.items() if d == other)
        n_p = sum(g.n_u * g.n_v for g in options["views"])
        decisions.append(("directions", directions,
                          f"{len(views)} patches of ±{half:.2g} around the view directions ({n_p} cells): "
                          f"{_fmt_s(t if directions == 'views' else t_other)}; the hemisphere ({N * N} cells): "
                          f"{_fmt_s(t_other if directions == 'views' else t)}"))
    else:
        decisions.append(("directions", "hemisphere", "no view directions: the whole hemisphere"))
    if hf_solvers:
        if "solver" in force:
            decisions.append(("solver", solver, "forced"))
        else:
            alt = {s_: v for (d, s_), v in costs.items() if d == directions}
            why = (f"height field of {smp.nx}x{smp.ny} samples, both exact Kirchhoff: " +
                   ", ".join(f"{k} {_fmt_s(v)}" for k, v in sorted(alt.items(), key=lambda kv: kv[1])))
            if not has_cl:
                why += f" (direct sum unavailable: {no_direct})"
            if spec.nano.kind == "statistics":
                why = f"g(θ_o = 0) = {g_series:.3g} > {PSD_G_MAX:g} is beyond the PSD series; generated {why}"
            decisions.append(("solver", solver, why))
    patches = options.get("views", []) if directions == "views" else []

    # --- precision -----------------------------------------------------------------------------------------------
    if solver == "direct":
        h_max = float(np.max(np.abs(hf.heights - hf.heights.mean())))
        floor = float32_floor(hf.heights.size, h_max, lam_min)
        level = weakest_level(dE, max(hf.extent), lam_min)
        metrics.update(float32_floor=floor, weakest_level=level)
        if "precision" in force:
            precision = force["precision"]
            decisions.append(("precision", precision, "forced"))
        else:
            precision = "float64" if floor > FLOOR_MARGIN * level else "float32"
            cmp = ">" if precision == "float64" else "≤"
            decisions.append(("precision", precision, f"float32 noise floor {floor:.2g} {cmp} {FLOOR_MARGIN:g} × "
                                                      f"weakest visible level {level:.2g} of the peak"))
        if precision == "float64":
            from .runtime import get_runtime

            if not get_runtime(device).fp64:
                precision = "float32"
                decisions.append(("precision", "float32", "the OpenCL device has no fp64 (float64 was wanted)"))
    else:
        precision = "float64"
        decisions.append(("precision", "float64", "NumPy float64 throughout (no OpenCL kernel on this route)"))

    effects = {"specular": True, "diffraction": bool(diffraction_on), "diffuse": bool(diffuse),
               "spectral": not lam_independent, "sphere": sphere}
    return EntryPlan(spec=spec, light_name=light.name, spd=spd, material=mat,
                     light_directions_deg=light.directions_deg, micro=micro, nano=nano_obj, effects=effects,
                     solver=solver, resolution=N, directions=directions, view_directions_deg=views,
                     wavelengths_nm=w_sim, colour_wavelengths_nm=w_colour, precision=precision, kd=kd,
                     sphere=sphere, estimated_time_s=float(t), patches=patches, decisions=decisions, metrics=metrics,
                     forced=dict(force))


def plan_scene(scene: Scene, *, force: dict | None = None, device=None, max_resolution: int | None = None) -> Plan:
    """Plan a scene: decide, for every material under every light, the effects, solver, grid and wavelengths.

    Parameters
    ----------
    force : dict, optional
        Overrides from :func:`parse_force` (e.g. ``{"diffraction": True}``).
    device : str, optional
        OpenCL device for the direct solver's calibration.
    max_resolution : int, optional
        Cap on the direction grid (the scene's ``output.resolution`` is used as given).

    Returns
    -------
    Plan
    """
    t0 = time.perf_counter()
    force = dict(force or {})
    cm = calibrate()
    entries = [_plan_entry(scene, m, light, force, cm, device, max_resolution)
               for m in scene.materials for light in scene.lights]
    return Plan(scene=scene, entries=entries, cost_model=cm, planning_time_s=time.perf_counter() - t0, force=force)


# ----------------------------------------------------------------------------------------------------------------
# Executing a plan
# ----------------------------------------------------------------------------------------------------------------

def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "-", str(text)).strip("-") or "x"


def _tag(th: float, ph: float) -> str:
    return f"i{th:g}_{ph:g}".replace(".", "p").replace("-", "m")


def entry_prefix(e: EntryPlan, plan: Plan) -> str:
    """File-name prefix of an entry: the material, plus the light when the scene has several."""
    return _slug(e.name) if len(plan.scene.lights) == 1 else f"{_slug(e.name)}_{_slug(e.light_name)}"


def output_files(plan: Plan) -> list[str]:
    """Every file :func:`execute` writes for *plan* (checked before computing)."""
    out = plan.scene.output
    files = ["plan.json", "results.json"]
    for e in plan.entries:
        p = entry_prefix(e, plan)
        if e.directions == "hemisphere":
            for th, ph in e.light_directions_deg:
                t = _tag(th, ph)
                if out.spectral_brdf:
                    files.append(f"{p}_{t}_brdf_spectral.exr")
                if out.rgb_images:
                    files += [f"{p}_{t}_brdf_rgb.exr", f"{p}_{t}_brdf.png"]
            if e.sphere and out.rgb_images:
                files += [f"{p}_sphere.exr", f"{p}_sphere.png"]
        if out.tables:
            files.append(f"{p}_table.csv")
    return files


def _broadcast(L: twoscale.Lobes, w) -> twoscale.Lobes:
    """A λ-independent evaluation (one wavelength) copied onto the colour wavelengths *w*."""
    shape = (len(w),) + L.total.shape[1:]
    b = {k: np.broadcast_to(getattr(L, k), shape).copy() for k in ("coherent", "diffraction", "diffuse", "microfacet")}
    return twoscale.Lobes(grid=L.grid, wi=L.wi, wavelengths_nm=np.asarray(w, float), info=dict(L.info), **b)


@dataclass
class EntryResult:
    """What :func:`run_entry` computed: lobes per light direction (hemisphere or one per view patch)."""

    entry: EntryPlan
    lobes: dict                      # (θ, φ) -> Lobes (hemisphere) or list of Lobes (one per view)
    sphere_table: tuple | None       # (thetas_deg, total, microfacet)
    time_s: float


def run_entry(e: EntryPlan, *, device=None, progress=None) -> EntryResult:
    """Evaluate the planned two-scale (or microfacet) BRDF of one entry."""
    from .simulate import SPHERE_THETAS_DEG

    t0 = time.perf_counter()
    w = e.wavelengths_nm if e.wavelengths_nm.size else np.array([LAMBDA_REF_NM])
    kw = dict(solver=e.solver if e.nano is not None else "auto", kd=e.kd, diffuse="lambert" if e.kd > 0 else "none",
              device=device, precision=e.precision)
    nano = e.nano if e.effects["diffraction"] else None
    hemi = DirectionGrid.hemisphere(e.resolution)

    def ev(wi, grid):
        ref = None if grid is hemi else hemi            # view patches are normalized on the hemisphere grid
        L = twoscale.evaluate(wi, w, e.material, e.micro, nano, grid, reference_grid=ref, **kw)
        return L if e.wavelengths_nm.size else _broadcast(L, e.colour_wavelengths_nm)

    lobes = {}
    for th, ph in e.light_directions_deg:
        wi = direction_from_angles(th, ph)
        lobes[(th, ph)] = ev(wi, hemi) if e.directions == "hemisphere" else [ev(wi, g) for g in e.patches]
        if progress:
            progress(1)
    table = None
    if e.sphere:
        thetas = np.array(SPHERE_THETAS_DEG)
        tot, mf = [], []
        for th in thetas:
            L = ev(direction_from_angles(th, 0.0), hemi)
            tot.append(L.total)
            mf.append(L.microfacet)
            if progress:
                progress(1)
        table = (thetas, np.stack(tot), np.stack(mf))
    return EntryResult(e, lobes, table, time.perf_counter() - t0)


def view_values(res: EntryResult, which: str = "total") -> list[dict]:
    """BRDF spectra (1/sr) at every (light, view) pair of the entry, looked up bilinearly on its grid."""
    from . import render

    e = res.entry
    rows = []
    for (th, ph), L in res.lobes.items():
        for k, (vt, vp) in enumerate(e.view_directions_deg):
            lob = L if e.directions == "hemisphere" else L[k]
            d = direction_from_angles(vt, vp)
            f = render.lookup(getattr(lob, which)[None], np.array([0.0]), lob.grid, np.zeros(1), d[None, 0],
                              d[None, 1])[0]
            rows.append({"light_deg": [th, ph], "view_deg": [vt, vp], "brdf": np.maximum(f, 0.0),
                         "cos_i": math.cos(math.radians(th))})
    return rows


def _rgb_rows(rows, w, spd):
    if not rows:
        return np.zeros((0, 3))
    Q = np.array([np.pi * r["cos_i"] * r["brdf"] for r in rows])
    return spectral.reflectance_to_rgb(Q, w, spd)


def execute(plan: Plan, outdir, *, overwrite: bool = False, device=None, progress=None) -> dict:
    """Run a plan and write the outputs the scene asks for, ``plan.json`` (estimated and measured times) and
    ``results.json`` (colours at the directions of interest, albedos).

    Returns
    -------
    dict
        The content of ``plan.json``.
    """
    from . import io, render
    from .simulate import Simulation, render_spheres

    files = output_files(plan)
    out = io.prepare_outdir(outdir, overwrite=overwrite, expected=files)
    sc = plan.scene
    data = plan.as_dict()
    results = {"scene": sc.name, "materials": []}
    t_all = time.perf_counter()
    for e, ed in zip(plan.entries, data["materials"]):
        res = run_entry(e, device=device, progress=progress)
        t_out = time.perf_counter()
        p = entry_prefix(e, plan)
        w = e.colour_wavelengths_nm
        written, albedo = [], {}
        for (th, ph), L in res.lobes.items():
            t = _tag(th, ph)
            if e.directions == "hemisphere":
                albedo[t] = {"light_deg": [th, ph], "albedo": L.albedo("total"),
                             "rgb": spectral.reflectance_to_rgb(L.albedo("total"), w, e.spd)}
                hdr = {k: str(v) for k, v in L.grid.header().items()}
                hdr.update(waveoptics_incident_deg=f"{th:g} {ph:g}", waveoptics_material=e.material.name,
                           waveoptics_quantity="BRDF f (1/sr), not x cos", waveoptics_scene=sc.name)
                if sc.output.spectral_brdf:
                    name = f"{p}_{t}_brdf_spectral.exr"
                    io.write_spectral_exr(out / name, {float(lam): L.total[i] for i, lam in enumerate(w)},
                                          header=hdr, overwrite=True)
                    written.append(name)
                if sc.output.rgb_images:
                    rgb = spectral.reflectance_to_rgb(np.moveaxis(L.total, 0, -1), w, e.spd)
                    io.write_exr(out / f"{p}_{t}_brdf_rgb.exr", {"R": rgb[..., 0], "G": rgb[..., 1],
                                                                 "B": rgb[..., 2]}, header=hdr, overwrite=True)
                    img = np.where(L.grid.inside[..., None], render.tonemap(rgb), 0.0)[::-1]  # row 0 = top = +v
                    k = max(1, 256 // max(img.shape[:2]))                   # nearest-neighbour zoom for viewing
                    img = np.repeat(np.repeat(img, k, axis=0), k, axis=1)
                    render.save_png(out / f"{p}_{t}_brdf.png", img)
                    written += [f"{p}_{t}_brdf_rgb.exr", f"{p}_{t}_brdf.png"]
        sphere = None
        if res.sphere_table is not None and sc.output.rgb_images:
            thetas, tot, mf = res.sphere_table
            first = res.lobes[e.light_directions_deg[0]]
            sim = Simulation(lobes=first, table_thetas_deg=thetas, table_total=tot, table_microfacet=mf,
                             illuminant=e.spd, params={"incident_deg": list(e.light_directions_deg[0])})
            wave, mfimg, dEmap, mask = render_spheres(sim, sc.output.sphere_size)
            io.write_exr(out / f"{p}_sphere.exr", {"R": wave[..., 0], "G": wave[..., 1], "B": wave[..., 2]},
                         header={"waveoptics_scene": sc.name, "waveoptics_material": e.material.name}, overwrite=True)
            render.save_png(out / f"{p}_sphere.png", render.tonemap(wave))
            written += [f"{p}_sphere.exr", f"{p}_sphere.png"]
            sphere = {"delta_e2000_vs_microfacet": {"mean": float(dEmap[mask].mean()) if mask.any() else 0.0,
                                                    "max": float(dEmap[mask].max()) if mask.any() else 0.0}}
        rows = view_values(res)
        rows_mf = view_values(res, "microfacet")
        rgb = _rgb_rows(rows, w, e.spd)
        rgb_mf = _rgb_rows(rows_mf, w, e.spd)
        for r, c, cm_ in zip(rows, rgb, rgb_mf):
            r["rgb"] = c
            r["microfacet_rgb"] = cm_
            r["delta_e2000_vs_microfacet"] = float(spectral.delta_e2000(c, cm_))
        if sc.output.tables:
            name = f"{p}_table.csv"
            with io.atomic_path(out / name) as tmp:
                head = ["light_theta_deg", "light_phi_deg", "view_theta_deg", "view_phi_deg"] + \
                       [f"f_{lam:g}nm" for lam in w] + ["R", "G", "B"]
                lines = [",".join(head)]
                for r in rows:
                    vals = r["light_deg"] + r["view_deg"] + list(r["brdf"]) + list(r["rgb"])
                    lines.append(",".join(f"{v:.9g}" for v in vals))
                tmp.write_text("\n".join(lines) + "\n")
            written.append(name)
        t_written = time.perf_counter() - t_out
        ed.update(measured_time_s=res.time_s, outputs_time_s=t_written, files=written,
                  estimate_ratio=res.time_s / e.estimated_time_s if e.estimated_time_s > 0 else None)
        results["materials"].append({"name": e.name, "light": e.light_name, "wavelengths_nm": w,
                                     "views": [{k: v for k, v in r.items() if k != "cos_i"} for r in rows],
                                     "albedo": albedo, "sphere": sphere, "measured_time_s": res.time_s})
    data["measured_time_s"] = float(sum(m["measured_time_s"] for m in data["materials"]))
    data["run_time_s"] = time.perf_counter() - t_all
    data["files"] = files
    io.write_json(out / "results.json", results)
    io.write_json(out / "plan.json", data)
    return data
