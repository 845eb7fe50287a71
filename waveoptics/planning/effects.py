"""The planner's decisions on the physical effects of one (material, light) pair, in the order they are taken:
diffuse term, diffraction (and its model), simulated wavelengths (refined for gratings), the nano surface's route,
multiple scattering. Each reads the :class:`Entry` and records its outcome and reason there; the rules are
described in :mod:`waveoptics.planning.planner`.

References
----------
.. [1] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 209 (1954);
   H. E. Bennett, J. O. Porteus, JOSA 51, 123 (1961) (coherent fraction, TIS).
.. [2] J. E. Harvey, R. N. Pfisterer, Opt. Eng. 59(1) 017103, 2020 (grating equation, orders).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import colour, surfaces
from ..brdf import twoscale
from ..errors import FieldError
from ..materials import Material
from ..planning.scene import MaterialSpec, Scene
from ..request import make_nano, request_default
from ..scatter.series import roughness_g
from ..units import parse_length
from .colour_estimate import proxy_model, colour_shift
from .costmodel import CostModel
from .decisions import LAMBDA_REF_NM, ORDER_EFFICIENCY_MIN, first_order_g, grating_orders, scattered_fraction
from .report import fmt_nm
from .thresholds import (ESTIMATE_SHARE, ESTIMATE_SPHERE_THETAS, F_FLAT_TOL, FILM_NODES_PER_FRINGE, FLAT_SCATTER,
                         KIRCHHOFF_GRAZING_DEG, PSD_G_MAX, RAYLEIGH_RICE_G_MAX)

#: the decisions are private steps of :func:`waveoptics.planning.plan_scene`
__all__ = []


def _constant_over(mat: Material, w) -> bool:
    """True when F(cos θ, λ) is the same at every λ of *w* (constant index or grey F0)."""
    c = np.array([1.0, 0.7, 0.4, 0.1])[:, None]
    F = np.asarray(mat.F(c, np.asarray(w, dtype=float)[None, :]), dtype=float)
    return bool(np.all(np.ptp(F, axis=1) <= F_FLAT_TOL * np.maximum(F.max(axis=1), 1e-300)))


@dataclass
class Entry:
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
    diffracts: bool = False                  # the decision: the nano lobe is computed
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
    diffraction: str = request_default("diffraction")   # the nano lobe's model (the request field)
    roughness_correlation: object = request_default("roughness_correlation")   # of a stack's interfaces, as used

    @property
    def delta_e(self) -> float:
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


def decide_diffuse(e: Entry) -> None:
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


def decide_multiple_scattering(e: Entry) -> None:
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


def decide_diffraction(e: Entry) -> None:
    """Diffraction runs when the nano surface scatters enough light to change the colour by a visible amount
    (a coarse estimate against the scene's ΔE target), or when almost no coherent reflection is left."""
    if e.spec.nano is None:
        if e.force.get("diffraction") or "solver" in e.force:
            raise FieldError(f"{{force}} diffraction: material {e.spec.name!r} has no nano surface "
                             "(add [materials.nano] with statistics, generator or file)", "force")
        e.diffracts = False
        e.decide("diffraction", "off", "no nano surface given: the microfacet model is the whole BRDF")
        return
    if e.spec.nano.kind != "statistics":
        e.hf = e.spec.nano.height_field(e.scene.seed)
    e.proxy = proxy_model(e.spec, e.hf)
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
        e.diffracts = e.force.get("diffraction", True)
        e.decide("diffraction", "on" if e.diffracts else "off", f"forced ({why})")
    elif s < FLAT_SCATTER:
        e.diffracts = False
        e.decide("diffraction", "off", f"{why}: the nano surface is flat at these wavelengths")
    elif e.g_series > PSD_G_MAX:
        e.diffracts = True
        e.decide("diffraction", "on", f"{why}: g(θ_o = 0) = {e.g_series:.3g} > {PSD_G_MAX:g}, almost no coherent "
                                      "reflection is left (and the PSD estimate does not apply)")
    else:
        out = e.scene.output
        hemi = e.sphere or out.rgb_images or out.spectral_brdf or not e.views
        dirs = list(e.light.directions_deg) + ([(t, 0.0) for t in ESTIMATE_SPHERE_THETAS] if e.sphere else [])
        est, info = colour_shift(e.mat, e.micro, e.proxy, e.spd, dirs, views_deg=e.views, hemisphere=hemi,
                                 kd=e.kd)
        e.metrics.update(estimated_delta_e=est, estimate_resolution=info["resolution"])
        e.diffracts = est > ESTIMATE_SHARE * e.delta_e
        proxy_note = "" if e.statistical else " (height field through a Gaussian-statistics proxy)"
        cmp = ">" if e.diffracts else "≤"
        e.decide("diffraction", "on" if e.diffracts else "off",
                 f"{why}; coarse estimate{proxy_note}: ΔE2000 {est:.2g} {cmp} {ESTIMATE_SHARE:g} × target {e.delta_e:g}"
                 + ("" if e.diffracts else ", so only the microfacet model runs"))



def decide_diffraction_model(e: Entry) -> None:
    """The scene's model when it names one; else Kirchhoff, the model whose limits are measured (flat patch = F,
    exp(−g), grating orders, the Beckmann limit), with a note when the light comes near grazing incidence, where
    its factor K grows as 1/cosθ_i (docs/physics.md §10; docs/wave-optics.md compares the models)."""
    if not e.diffracts:
        return
    if e.spec.diffraction != "auto":
        e.diffraction = e.spec.diffraction
        e.decide("diffraction model", e.spec.diffraction, "set by the scene")
        return
    e.diffraction = request_default("diffraction")
    thetas = [t for t, _ in e.light.directions_deg] if not e.sphere else list(np.linspace(0.0, 88.0, 45))
    theta_max = max(thetas)
    # first order holds at an incidence while g = (k σ_rel (cosθ_i + 1))², the largest over its outgoing directions,
    # is small: the sphere's facets see every incidence (normal included), a grazing light only its own
    g_any = (first_order_g(e.proxy, thetas, e.lam_min) if e.spec.nano.kind == "statistics"
             else float(roughness_g(e.proxy.sigma, 2.0, e.lam_min)))
    if theta_max > KIRCHHOFF_GRAZING_DEG and e.spec.nano.kind == "statistics" and g_any <= RAYLEIGH_RICE_G_MAX:
        e.diffraction = "rayleigh-rice"
        e.decide("diffraction model", "rayleigh-rice",
                 f"light up to θ_i = {theta_max:g}° > {KIRCHHOFF_GRAZING_DEG:g}° on a surface smooth at these "
                 f"incidences (g = (kσ_rel(cosθ_i + 1))² ≤ {g_any:.2g} ≤ {RAYLEIGH_RICE_G_MAX:g}, first-order "
                 "perturbation theory's domain): beyond 70-80° the tangent-plane lobe is outside its validity and "
                 "hands over to the Rayleigh-Rice lobe (docs/physics.md §9), while Rayleigh-Rice with its "
                 "polarization factor Q gives the lobe's shape at every angle and agrees with Kirchhoff within 1 % "
                 "up to 60°")
        return
    why = ("tangent-plane Kirchhoff: the model held against the flat-patch, exp(−g), grating and Beckmann limits; "
           "RGHS differs from it by ~1 % on a rough surface, OHS/ROHS by 36 % at θ_i = 30°")
    if e.spec.nano.kind == "statistics":
        choice = _map_choice(e, thetas)
        if choice.model == "rayleigh-rice" and g_any <= RAYLEIGH_RICE_G_MAX:
            e.diffraction = "rayleigh-rice"
            e.decide("diffraction model", "rayleigh-rice",
                     "first-order perturbation theory measured closer to the rigorous solution than Kirchhoff by more "
                     f"than the map's noise, and the surface is smooth at these incidences (g ≤ {g_any:.2g}): "
                     + choice.note())
            return
        why += "; " + choice.note()
    if theta_max > KIRCHHOFF_GRAZING_DEG:
        why += (f"; light up to θ_i = {theta_max:g}° > {KIRCHHOFF_GRAZING_DEG:g}°, beyond the tangent plane's "
                "validity: between 70° and 80° of incidence or exit its lobe hands over to first-order "
                "perturbation theory's lobe (docs/physics.md §9)")
    e.decide("diffraction model", "kirchhoff", why)


def decide_roughness_correlation(e: Entry) -> None:
    """A thin-film stack's interface-roughness correlation enters only Rayleigh-Rice's nano lobe (first-order scatter
    from every interface, Elson 1979; Elson, Rahn & Bennett 1983). A correlation the scene sets is used when the
    plan runs that lobe; otherwise (no diffraction, or a Kirchhoff-family model) it is skipped and the plan says so
    in one line."""
    value = e.spec.roughness_correlation
    if e.diffracts and e.diffraction == "rayleigh-rice":
        e.roughness_correlation = value
        return
    e.roughness_correlation = request_default("roughness_correlation")
    if value == e.roughness_correlation:
        return
    why = ("no nano lobe is simulated" if not e.diffracts else
           f"the {e.diffraction} lobe scatters from the stack's top surface only; the correlation of its interfaces "
           "enters only rayleigh-rice's first-order scatter from every interface (Elson 1979)")
    e.decide("roughness correlation", "skipped", f"roughness_correlation = {value!r} is not used: {why}")


def _map_choice(e: Entry, thetas):
    """The validity map's verdict (:func:`waveoptics.planning.validity.choose_model`) for the entry's nano statistics
    at its shortest wavelength: k σ_rel (the relevant roughness, largest over the incidences) and k ℓ (the PSD's
    length scale standing in for the Gaussian correlation length of the map's surfaces)."""
    from ..scatter.band import relevant_sigma2
    from .validity import choose_model

    k = 2 * np.pi / (e.lam_min * 1e-9)
    s2 = relevant_sigma2(e.proxy, e.lam_min, np.sin(np.radians(np.asarray(thetas, dtype=float))))
    return choose_model(e.mat, k * float(np.sqrt(np.max(s2))), k * float(e.proxy.length_scale), thetas)


def film_step(e: Entry):
    """(step nm, reason) of the grid that puts :data:`FILM_NODES_PER_FRINGE` nodes on each interference fringe of
    a thin-film stack: step None when the colour grid already does; None without films.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §7.5.1 (fringe spacing Δλ ≈ λ²/(2 n d cos θ)).
    """
    spacing = getattr(e.mat, "fringe_spacing_nm", None)
    if spacing is None or e.w_colour.size < 2:
        return None
    lam = float(np.min(e.w_colour))          # the closest fringes are at the shortest wavelength
    fringe = float(np.min(spacing(e.w_colour)))
    limit = fringe / FILM_NODES_PER_FRINGE
    current = float(e.w_colour[1] - e.w_colour[0])
    opd = float(np.max(e.mat.optical_thickness_nm(lam)))
    why = (f"thin-film stack (optical thickness Σ n d = {opd:.4g} nm at {lam:g} nm): its fringes lie "
           f"Δλ ≈ λ²/(2 n d cos θ_t) ≥ {fringe:.3g} nm apart, and {FILM_NODES_PER_FRINGE} nodes per fringe need a "
           f"step ≤ {limit:.3g} nm")
    if limit >= current:
        return None, f"{why}, which the colour grid's {current:g} nm meets"
    step = next((s for s in colour.STEPS_NM if s <= limit), limit)
    return step, f"{why} (the colour grid's {current:g} nm would alias them): step {step:g} nm"


def decide_wavelengths(e: Entry) -> None:
    """Only the lines of a line source; one evaluation when nothing depends on λ; else the coarsest grid that
    meets the colour target on smooth spectra, refined for the fringes of a thin-film stack (:func:`film_step`)."""
    film = None if e.spd.lines else film_step(e)
    if film is not None and film[0] is not None:
        e.w_colour = colour.spectral_grid(e.spd, film[0])
        e.lam_min = float(np.min(e.w_colour))
    if e.spd.lines:
        e.w_sim = e.w_colour = colour.simulation_wavelengths(e.spd)
        e.lam_independent = (not e.diffracts) and _constant_over(e.mat, e.w_sim) and e.w_sim.size > 1
        if e.lam_independent:
            e.w_sim = np.array([])
            e.decide("wavelengths", "none (1 evaluation)",
                     f"line source {e.spd.name}, and the BRDF does not depend on λ (constant F, no diffraction): "
                     "one evaluation serves every line")
        else:
            e.decide("wavelengths", fmt_nm(e.w_sim), f"line source {e.spd.name}: only its visible lines carry light")
    elif not e.diffracts and _constant_over(e.mat, e.w_colour):
        e.lam_independent = True
        e.w_sim = np.array([])
        e.decide("wavelengths", "none (1 evaluation)",
                 f"pure geometric optics with a wavelength-independent Fresnel factor ({e.mat.source}): the BRDF is "
                 f"the same at every λ; evaluated once at {LAMBDA_REF_NM:g} nm, colour over {fmt_nm(e.w_colour)}")
    elif film is not None and film[0] is not None:
        e.lam_independent = False
        e.w_sim = e.w_colour
        e.decide("wavelengths", fmt_nm(e.w_sim), f"{film[1]} under {e.spd.name}")
    else:
        e.lam_independent = False
        e.w_sim = e.w_colour
        e.decide("wavelengths", fmt_nm(e.w_sim), f"smooth spectra under {e.spd.name}: the coarsest grid whose "
                                                  f"colour error on smooth reflectances stays ≤ ΔE {e.delta_e:g}"
                                                  + (f"; {film[1]}" if film is not None else ""))
    e.metrics["wavelength_count"] = int(max(e.w_sim.size, 1))


def decide_nano_route(e: Entry) -> None:
    """The PSD series for Gaussian statistics within its range; a height field (fft or direct, chosen by cost
    later) otherwise."""
    e.nano, e.solver = None, "none"
    if not e.diffracts:
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



def refine_wavelengths_for_grating(e: Entry) -> None:
    """A periodic nano surface under a continuous source: its orders move by m Δλ / Λ in direction cosine; keep
    that within one grid cell so the rainbow has no gaps (grating equation, docs/physics.md §5)."""
    periodic = e.diffracts and e.spec.nano.kind == "generator" and e.spec.nano.params["model"] == "sinusoid"
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
        e.decisions[i] = ("wavelengths", fmt_nm(e.w_sim),
                          f"periodic nano surface (Λ = {period * 1e6:.3g} µm, orders up to {m} with efficiency ≥ "
                          f"{ORDER_EFFICIENCY_MIN:g}): Δλ ≤ Λ du / m = {limit:.3g} nm keeps each order's rainbow "
                          "free of gaps on this grid")
        e.metrics["wavelength_count"] = int(e.w_sim.size)
