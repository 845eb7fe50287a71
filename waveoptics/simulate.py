"""The main job: a two-scale surface simulated per wavelength, integrated to colour, compared with microfacets.

:func:`simulate` evaluates the two-scale BRDF (:mod:`waveoptics.brdf.twoscale`) and the plain microfacet BRDF of the
same micro roughness and material on a hemisphere grid at the scene's incident direction, and builds both as
functions of (ω_i, ω_o, λ) for sphere renders evaluated per pixel (:class:`waveoptics.brdf.TabulatedTwoScaleBRDF`,
:class:`waveoptics.brdf.MicrofacetBRDF`); :func:`write_outputs` writes the files of ``waveoptics simulate``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from matplotlib import colors
from scipy.ndimage import map_coordinates

from . import colour, io, scatter, surfaces
from .renderers import lighting, sphere as render
from .brdf import MicrofacetBRDF, TabulatedTwoScaleBRDF, twoscale
from .brdf.tabulated import PHI_NODES_ANISOTROPIC, THETA_NODES_DEG, light_azimuth_nodes
from .io import figures
from .io.figures import save_figure
from .errors import FieldError, renamed_keywords
from .materials import get_material, with_roughness_correlation
from .request import MAX_NANO_SAMPLES, SimulationRequest, crop, make_nano, parse_nano
from .scatter.grid import DirectionGrid, integrate
from .units import direction_from_angles

__all__ = ['SPHERE_THETAS_DEG', 'memory_estimate', 'check_request_memory', 'sphere_nodes', 'sphere_evaluations', 'sphere_steps', 'Simulation', 'simulate', 'run', 'nano_band', 'OUTPUT_FILES', 'SPHERE_FILES', 'ENVIRONMENT_FILES', 'SUMMARY_UNITS', 'output_files', 'nano_field',
           'render_spheres', 'plane_of_incidence', 'write_outputs']

#: incidence nodes (degrees) of the diffracted-lobe table of a surface whose lobe depends on the light's azimuth
#: (tabulated over :func:`waveoptics.brdf.tabulated.light_azimuth_nodes` azimuths as well, hence coarser in θ)
SPHERE_THETAS_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 78.0, 84.0, 88.0)


def sphere_nodes(micro, nano) -> tuple[tuple, int]:
    """(θ nodes in degrees, number of φ nodes) of the diffracted-lobe table behind sphere renders: the azimuths
    :class:`~waveoptics.brdf.TabulatedTwoScaleBRDF` chooses itself (:func:`~waveoptics.brdf.tabulated.
    light_azimuth_nodes`): the light's own azimuth and 5° steps for isotropic surfaces; 10° steps × 12 azimuths for
    an anisotropic analytic micro NDF with PSD statistics (read by the half-vector), × 4 for the others (height
    fields, slope tables). *nano*: a Nano, None or whether it is given by statistics (as
    :func:`~waveoptics.brdf.roughness_scales.isotropic`).

    Measured (scripts/sphere_light_azimuths.py: Al, Beckmann α 0.15 × 0.4, Gaussian σ 15 nm, T 1.5 µm, 450/550/650
    nm, 64², lights at φ_i 22.5° and 37.5°, diffracted part against :func:`waveoptics.brdf.evaluate` at that light,
    exits to θ_o 60° above 1 % of the peak; 90th percentile / max of |f / f_ref − 1|): with 4 azimuths 7.9 / 16 %
    at θ_i 30°, 9.9 / 18 % at 35° (between incidence nodes), 18 / 83 % at 60°; with 12, 1.1 / 4.2 %, 1.5 / 3.4 %,
    1.9 / 6.4 %. The table's build with its rim tables: 23.4 → 38.0 s, 1.6x (min of 6 in two rounds of 3, under
    load, one worker; 6 main lobes per θ computed in place of 2, the half-turn symmetry giving the rest, and the
    24 rim light azimuths either way)."""
    n_phi = light_azimuth_nodes(micro, nano)
    return (THETA_NODES_DEG if n_phi == 1 else SPHERE_THETAS_DEG), n_phi


def sphere_evaluations(micro, nano) -> int:
    """Lobe evaluations of the diffracted-lobe table behind sphere renders (:func:`sphere_nodes`; its entries: a
    table read by the half-vector computes half of them, the rest are its lobes turned by π)."""
    thetas, n_phi = sphere_nodes(micro, nano)
    return len(thetas) * n_phi


def _nano_statistics(req: SimulationRequest) -> bool:
    """Whether :func:`run` takes *req*'s nano-roughness as PSD statistics (:func:`waveoptics.request.make_nano`:
    a PSD model with the solver auto or psd), not as a height field."""
    return (req.surface is None and not req.split and parse_nano(req.nano)[0] in surfaces.PSD_MODELS
            and req.solver in ("auto", "psd"))


def _sphere_table_entries(req: SimulationRequest) -> int:
    """Incidences (θ, φ) of the diffracted-lobe table :func:`run` builds for *req* (:func:`sphere_nodes`)."""
    thetas, n_phi = sphere_nodes(req.micro(), _nano_statistics(req))
    return len(thetas) * n_phi


def sphere_steps(req: SimulationRequest, sphere: bool = True) -> int:
    """Lobe evaluations :func:`run` makes for *req* with sphere renders, or without them (for progress bars)."""
    return 1 + (_sphere_table_entries(req) if sphere else 0)

@dataclass
class Simulation:
    """Everything :func:`simulate` computed (arrays in 1/sr, wavelengths in nm)."""

    lobes: twoscale.Lobes
    brdf_wave: TabulatedTwoScaleBRDF | None
    brdf_microfacet: MicrofacetBRDF
    illuminant: str
    params: dict
    nano: twoscale.Nano | None = None
    timings_s: dict = field(default_factory=dict)
    band: dict = field(default_factory=dict)

    @property
    def wavelengths_nm(self):
        return self.lobes.wavelengths_nm

    @property
    def grid(self):
        return self.lobes.grid

    def rgb_lobe(self, which="total", space="sRGB"):
        """Linear RGB (n_v, n_u, 3) of the lobe f (1/sr) under the illuminant."""
        f = getattr(self.lobes, which)
        return colour.reflectance_to_rgb(np.moveaxis(f, 0, -1), self.wavelengths_nm, self.illuminant, space=space)

    def rgb_albedo(self, which="total", space="sRGB"):
        """Linear RGB of the directional albedo spectrum."""
        a = self.lobes.albedo(which)
        return colour.reflectance_to_rgb(a, self.wavelengths_nm, self.illuminant, space=space)


@renamed_keywords(accuracy="delta_e= (the colour accuracy, ΔE2000)")
def simulate(material=None, *, surface=None, incident=None, wavelengths=None, sphere=True, device=None,
             progress=None, **fields) -> Simulation:
    """Simulate a two-scale surface and the plain microfacet model (keyword form of :func:`run`).

    Every argument left out takes the default of its :class:`~waveoptics.request.SimulationRequest` field.

    Parameters
    ----------
    material : str or Material, optional
        Surface material (see :func:`waveoptics.materials.get_material`).
    surface : str, Path or HeightField, optional
        Nano height field (file or object); uses the fft/direct solvers.
    incident : (θ, φ) degrees, optional
        Direction of the light for the lobe outputs (and the sphere's light): the field *incident_deg*.
    wavelengths : array_like, nm, optional
        Wavelengths (the field *wavelengths_nm*); default chosen from the illuminant for *delta_e*.
    sphere : bool
        Also tabulate lobes over incidence angles for sphere renders.
    device : str, optional
        OpenCL device (see :func:`waveoptics.runtime.get_runtime`).
    progress : callable, optional
        Called with 1 after each lobe set.
    **fields
        Any other field of :class:`~waveoptics.request.SimulationRequest` (``nano``, ``micro_alpha``,
        ``alpha_y``, ``ndf``, ``shadowing``, ``illuminant``, ``delta_e``, ``resolution``, ``solver``, ``kd``,
        ``seed``, ``precision``, ``split``, ``diffraction``, ``polarization``, ``ndf_shape``, ``micro_surface``,
        ``multiple_scattering``), documented there.

    Returns
    -------
    Simulation
    """
    hf = surface if isinstance(surface, surfaces.HeightField) else None
    given = dict(fields)
    if material is not None:
        given["material"] = material if isinstance(material, str) else getattr(material, "name", str(material))
    if surface is not None:
        given["surface"] = "height field" if hf is not None else str(surface)
    if incident is not None:
        given["incident_deg"] = incident
    if wavelengths is not None:
        given["wavelengths_nm"] = tuple(np.atleast_1d(np.asarray(wavelengths, float)))
    if given.get("micro_surface") is not None:
        given["micro_surface"] = str(given["micro_surface"])
    req = SimulationRequest(**given)
    return run(req, surface=hf, material=None if material is None or isinstance(material, str) else material,
               sphere=sphere, device=device, progress=progress)


def _nano_of(req: SimulationRequest, w, surface, micro: twoscale.Micro):
    """(micro, nano, split information) of a request: the nano lobe's source and, for a split surface, the micro
    roughness measured from its long-period part."""
    if req.split:
        hf = surface if surface is not None else surfaces.load(req.surface)
        measured, nano_hf, split_info = twoscale.split_scales(hf, w, ndf=req.ndf, ndf_shape=req.ndf_shape)
        micro = twoscale.Micro(alpha=measured.alpha, alpha_y=measured.alpha_y, ndf=req.ndf, shadowing=req.shadowing,
                               ndf_shape=req.ndf_shape)
        return micro, twoscale.Nano(surface=crop(nano_hf, MAX_NANO_SAMPLES)), split_info
    if req.surface is not None and surface is None:
        surface = req.surface
    nano_obj = make_nano(req.nano, w, solver=req.solver, seed=req.seed, surface=surface)
    if nano_obj is not None and nano_obj.surface is not None:
        nano_obj = twoscale.Nano(surface=crop(nano_obj.surface, MAX_NANO_SAMPLES))
    return micro, nano_obj, None


def memory_estimate(req: SimulationRequest, *, sphere=True, n_lambda=None) -> float:
    """Bytes :func:`run` holds at its peak, estimated before any work: about a dozen (n_λ, n, n) float64 arrays
    for the lobes and their temporaries, plus the sphere renders' diffracted-lobe table and its sampling CDF
    (two float64 arrays per tabulated incidence: the request's own table, at least that of 4 azimuths × 10° steps
    of an anisotropic surface)."""
    n = int(req.resolution)
    nl = len(req.wavelengths()) if n_lambda is None else int(n_lambda)
    lobes = 12 * 8 * nl * n * n
    table = 16 * nl * n * n * max(len(THETA_NODES_DEG), len(SPHERE_THETAS_DEG) * PHI_NODES_ANISOTROPIC,
                                  _sphere_table_entries(req)) if sphere else 0
    return float(lobes + table + _nano_field_bytes(req))


def _nano_field_bytes(req: SimulationRequest) -> int:
    """Bytes of a nano height field and its transforms' buffers (about ten complex128 arrays of its samples, at
    most :data:`MAX_NANO_SAMPLES` per side after cropping): every nano kind that runs as a height field (a file,
    a split surface, sinusoid and scratches, statistics with the fft or direct solver); 0 for the PSD series."""
    return 0 if _nano_statistics(req) else 10 * 16 * MAX_NANO_SAMPLES ** 2


def check_request_memory(req: SimulationRequest, *, sphere=True, max_memory=None, sphere_needed=False) -> None:
    """Refuse *req* when its :func:`memory_estimate` is over budget (:func:`waveoptics.runtime.check_memory`), in
    one line offering to drop the sphere renders (field ``sphere``) unless there are none or the caller needs them."""
    from .runtime import check_memory

    drop = ", or drop the sphere renders ({sphere})" if sphere and not sphere_needed else ""
    check_memory(memory_estimate(req, sphere=sphere), "this simulation", "lower {resolution} or the number of "
                 "{wavelengths_nm}" + drop, max_memory, fields=("resolution", "wavelengths_nm", "sphere"),
                 python={"sphere": "sphere=False"})


def run(req: SimulationRequest, *, surface=None, material=None, sphere=True, device=None,
        progress=None, max_memory=None) -> Simulation:
    """Run one :class:`~waveoptics.request.SimulationRequest`.

    Parameters
    ----------
    req : SimulationRequest
    surface : HeightField, optional
        The nano height field itself (else *req.surface* is loaded as a file when given).
    material : Material, optional
        A material object standing for *req.material* (else it is looked up by name).
    sphere, device, progress
        As in :func:`simulate`.
    max_memory : int or str, optional
        Memory budget (bytes or ``"4GB"``); default :func:`waveoptics.runtime.memory_limit`. A request whose
        :func:`memory_estimate` exceeds it is refused before any work.
    """
    check_request_memory(req, sphere=sphere, max_memory=max_memory)
    t0 = time.perf_counter()
    mat = get_material(req.material if material is None else material)
    mat = with_roughness_correlation(mat, req.roughness_correlation)   # a stack's rough interfaces (rayleigh-rice)
    spd = colour.illuminant(req.illuminant)
    w = req.wavelengths()
    theta, phi = req.incident_deg
    micro, nano_obj, split_info = _nano_of(req, w, surface, req.micro())
    grid = DirectionGrid.hemisphere(req.resolution)
    timings = {"setup": time.perf_counter() - t0}

    def lobes_at(th, ph):
        return twoscale.evaluate(direction_from_angles(th, ph), w, mat, micro, nano_obj, grid, solver=req.solver,
                                 kd=req.kd, device=device, precision=req.precision, diffraction=req.diffraction,
                                 polarization=req.polarization, multiple_scattering=req.multiple_scattering)

    t = time.perf_counter()
    lobes = lobes_at(theta, phi)
    timings["lobe"] = time.perf_counter() - t
    if progress:
        progress(1)

    t = time.perf_counter()
    brdf_wave = None
    if sphere:   # the two-scale BRDF as a function of (ω_i, ω_o, λ): diffracted lobes tabulated over incidence
        thetas, n_phi = sphere_nodes(micro, nano_obj)
        brdf_wave = TabulatedTwoScaleBRDF(
            material=mat, micro=micro, nano=nano_obj, kd=req.kd, wavelengths_nm=tuple(w), resolution=req.resolution,
            thetas_deg=thetas, n_phi=n_phi, solver=req.solver, diffraction=req.diffraction, device=device,
            precision=req.precision, progress=progress, multiple_scattering=req.multiple_scattering)
    brdf_mf = MicrofacetBRDF(mat, micro, kd=req.kd, multiple_scattering=req.multiple_scattering)
    timings["sphere_table"] = time.perf_counter() - t
    params = {"material": mat.name, "material_source": mat.source,
              "nano": None if req.surface is not None else req.nano,
              "surface": req.surface if surface is None else None,
              "micro_alpha": None if req.micro_surface is not None else req.micro_alpha, "alpha_y": req.alpha_y,
              "ndf": micro.ndf,
              "micro_surface": req.micro_surface, "multiple_scattering": req.multiple_scattering,
              "shadowing": req.shadowing, "incident_deg": [theta, phi], "illuminant": spd.name,
              "resolution": req.resolution, "solver": lobes.info["solver"], "kd": 0.0 if mat.is_metal else req.kd,
              "precision": req.precision, "sigma_nano_m": lobes.info["sigma_nano_m"], "seed": req.seed,
              "split": split_info, "micro_alpha_used": [micro.alpha, micro.alpha_y], "diffraction": req.diffraction,
              "polarization": req.polarization, "roughness_correlation": req.roughness_correlation,
              "surface_info": None if nano_obj is None or nano_obj.surface is None else nano_obj.surface.provenance(),
              "sphere_render": {"light": "unpolarized", "diffraction_table": None if brdf_wave is None else {
                  "thetas_deg": list(brdf_wave.thetas_deg), "azimuths": int(brdf_wave.table.shape[0])}},
              # materials clamp their index outside the measured data (materials/database.py policy): say where
              "clamped_wavelengths_nm": [float(x) for x in w[mat.out_of_range(w)]]}
    return Simulation(lobes=lobes, brdf_wave=brdf_wave, brdf_microfacet=brdf_mf, illuminant=req.illuminant, params=params, timings_s=timings, nano=nano_obj,
                      band=nano_band(nano_obj, w, theta, phi))


def nano_field(nano: twoscale.Nano | None) -> dict | None:
    """The nano height field's σ, asked and realized, and the share of the asked σ² its grid cannot hold.

    ``sigma_realized_m`` is the rms of this realization's valid heights about their mean (what scatters);
    ``sigma_requested_m`` the generator's σ (from the field's ``meta``; null for a measured field). A generated
    field keeps S(f) exactly where its grid resolves it (docs/wave-optics.md § Height fields), so the rest of σ²
    is missing from it: ``variance_below_grid_share`` at wavelengths longer than the patch,
    ``variance_above_nyquist_share`` beyond the grid's Nyquist square (there, with spacing ≤ λ/4, it could not
    scatter), ``variance_beyond_grid_share`` their sum, each a share of σ_requested² (all three null, with
    σ_requested, for a measured field and for a cropped, split, summed or explicitly rescaled generated one). Heights
    are reported as they are: no field, generated, loaded or measured, is rescaled on the way to the solvers.
    None without a height field.
    """
    if nano is None or nano.surface is None:
        return None
    meta = nano.surface.meta
    generated = (meta.get("model") in surfaces.PSD_MODELS and "variance_below_grid_share" in meta
                 and not meta.get("renormalize") and not meta.get("exact_rms")
                 and "cropped_from" not in meta and "cropped" not in meta and "split_cutoff_period_m" not in meta)
    below = float(meta["variance_below_grid_share"]) if generated else None
    above = float(meta["variance_above_nyquist_share"]) if generated else None
    return {"sigma_requested_m": float(meta["sigma"]) if generated else None,
            "sigma_realized_m": float(nano.sigma),
            "variance_beyond_grid_share": None if below is None else below + above,
            "variance_below_grid_share": below, "variance_above_nyquist_share": above}


def nano_band(nano: twoscale.Nano | None, wavelengths_nm, theta_deg: float, phi_deg: float = 0.0) -> dict:
    """How much of the nano roughness can scatter at the incident direction, per wavelength (docs/physics.md §9).

    Returns ``sigma_m`` (rms height), ``sigma_relevant_m`` (the rms height inside the propagating band) and
    ``beyond_band_fraction`` ((σ² − σ_rel²)/σ²: the share of the variance in evanescent orders, which neither
    scatters nor reduces the specular light: the two-scale model leaves it out of both halves) and
    ``scattered_share`` (E: the share of the reflected light the nano lobe scatters with F = 1, Kirchhoff, whose
    complement is the coherent fraction; for a height field its own lobe's, :func:`waveoptics.brdf.twoscale.
    field_scattered_albedo`). For statistics also ``redistributed_share`` (the part of the scattered light that the multiple-order terms
    of the Kirchhoff series send beyond the band and the model returns to it,
    :meth:`waveoptics.scatter.BandSeries.redistributed_share`).
    """
    if nano is None:
        return {}
    s = math.sin(math.radians(theta_deg))
    out = {}
    if nano.model is not None:
        var = nano.model.sigma ** 2
        rel = [float(scatter.relevant_sigma2(nano.model, lam, s)) for lam in wavelengths_nm]
        series = [scatter.band_series(nano.model, lam) for lam in wavelengths_nm]
        c = 2 * math.cos(math.radians(theta_deg))
        out = {"scattered_share": [float(b.scattered_albedo(theta_deg)) for b in series],
               "redistributed_share": [b.redistributed_share(s, c) for b in series]}
    else:
        var = float(np.var(nano.surface.heights[nano.surface.valid]))
        rel = [scatter.relevant_variance_of_field(nano.surface, lam, s, phi_deg) for lam in wavelengths_nm]
        c = math.cos(math.radians(theta_deg))
        out = {"scattered_share": [1.0 - float(nano.coherent_fraction(c, lam, azimuth_deg=phi_deg))
                                   for lam in wavelengths_nm]}
    return {"incident_deg": [theta_deg, phi_deg], "sigma_m": math.sqrt(var),
            "sigma_relevant_m": [math.sqrt(max(r, 0.0)) for r in rel],
            "beyond_band_fraction": [scatter.beyond_band_fraction(var, r) for r in rel], **out}


OUTPUT_FILES = ("brdf_spectral.exr", "brdf_rgb.exr", "brdf.png", "sphere_wave.png", "sphere_microfacet.png",
                "sphere_wave.exr", "sphere_microfacet.exr", "sphere_diff.png", "lobes.png", "summary.json")
#: units of the quantities in ``summary.json`` (keys ending in _nm, _m, _deg, _s carry their unit in the name)
SUMMARY_UNITS = {
    "albedo": "1 (directional albedo: reflected / incident power)", "microfacet_albedo": "1",
    "diffraction_albedo": "1", "coherent_specular_fraction": "1 (share of the specular energy that stays coherent)",
    "rgb_albedo": "1, linear RGB of the albedo spectrum under the illuminant, white-balanced to the space white",
    "microfacet_rgb_albedo": "1, as rgb_albedo", "delta_e2000": "CIEDE2000 colour difference (1 ≈ just noticeable)",
    "brdf images": "1/sr (BRDF, not multiplied by cos theta_o)", "sphere images": "radiance; irradiance pi",
    "nano_polarized_albedo": "1 (albedo of each polarized Rayleigh-Rice nano lobe; a = incident, b = scattered)",
    "out_of_gamut": "RGB images whose colours lie outside their linear space's gamut: pixels, of (all pixels), min "
                    "(the most negative component, kept unclipped; the spectra are non-negative)",
}

#: the files of the sphere renders: absent from a run without them (*sphere* False, ``--no-spheres``)
SPHERE_FILES = tuple(f for f in OUTPUT_FILES if f.startswith("sphere_"))
#: the extra files of an environment-lit render (:func:`write_outputs` with *environment*)
ENVIRONMENT_FILES = ("sphere_env_wave.exr", "sphere_env_microfacet.exr", "sphere_env.png")
#: the extra file of a Rayleigh-Rice nano lobe: its four polarized BRDFs (ss, sp, ps, pp) as spectral layers
POLARIZED_FILES = ("nano_polarized.exr",)


def output_files(environment: bool = False, polarized: bool = False, sphere: bool = True) -> tuple:
    """Every file :func:`write_outputs` writes (with or without an environment-lit render, with *polarized* the
    Rayleigh-Rice nano lobe's polarized BRDFs, and without :data:`SPHERE_FILES` when *sphere* is False)."""
    base = OUTPUT_FILES if sphere else tuple(f for f in OUTPUT_FILES if f not in SPHERE_FILES)
    return base + (ENVIRONMENT_FILES if environment else ()) + (POLARIZED_FILES if polarized else ())


def nano_polarized(sim: Simulation) -> dict:
    """The Rayleigh-Rice nano lobe's four polarized BRDFs at the simulation's light, {ab: (n_λ, n_v, n_u)} in
    1/sr (a incident, b scattered polarization, s or p relative to the planes of incidence and scattering;
    :func:`waveoptics.scatter.rayleigh_rice_components`): the lobe before the micro facets spread it."""
    nano = sim.nano
    psd = nano.model if nano.model is not None else nano.periodogram()
    wo = sim.grid.directions()
    mat = sim.brdf_microfacet.material
    out = {c: np.zeros((sim.wavelengths_nm.size,) + wo.shape[:2]) for c in scatter.COMPONENTS}
    for i, lam in enumerate(sim.wavelengths_nm):
        # a thin-film stack stands for ε: Elson's rough-stack components (scatter.rough_stack_components)
        eps = mat if scatter.is_stack(mat) else scatter.permittivity(mat, lam)
        comps = scatter.rayleigh_rice_components(sim.lobes.wi[None, None, :], wo, lam, psd, eps)
        for c in scatter.COMPONENTS:
            out[c][i] = np.where(sim.grid.inside, comps[c], 0.0)
    return out


def render_spheres(sim: Simulation, size=256):
    """Linear sRGB sphere renders of both models (each pixel evaluates its BRDF function) and the per-pixel
    ΔE2000 (off-sphere pixels 0)."""
    theta, phi = sim.params["incident_deg"]
    # light direction in world space: θ from the viewing axis, in the plane given by φ
    light = direction_from_angles(theta, phi)
    if sim.brdf_wave is None:
        raise FieldError("this simulation was run without sphere renders (sphere=False)", "sphere")
    wave, mask = render.render_sphere(sim.brdf_wave, sim.wavelengths_nm, light, size=size, illuminant=sim.illuminant)
    mf, _ = render.render_sphere(sim.brdf_microfacet, sim.wavelengths_nm, light, size=size,
                                 illuminant=sim.illuminant)
    dE = np.zeros(mask.shape)
    dE[mask] = colour.delta_e2000(wave[mask], mf[mask])
    return wave, mf, dE, mask


def plane_of_incidence(sim: Simulation, which, n=721):
    """Signed θ_o (degrees, + towards the mirror side) and f (n_λ, n) along the plane of incidence."""
    theta, phi = sim.params["incident_deg"]
    f = getattr(sim.lobes, which)
    s = np.linspace(-0.9999, 0.9999, n)
    c, sn = math.cos(math.radians(phi)), math.sin(math.radians(phi))
    u, v = -s * c, -s * sn  # s > 0: the mirror side
    g = sim.grid
    fu = np.clip((u - g.u_range[0]) / g.du - 0.5, 0, g.n_u - 1)
    fv = np.clip((v - g.v_range[0]) / g.dv - 0.5, 0, g.n_v - 1)

    out = np.stack([map_coordinates(fl, [fv, fu], order=1, mode="nearest") for fl in f])
    return np.degrees(np.arcsin(s)), out


def write_outputs(sim: Simulation, outdir, *, overwrite=False, sphere_size=256, space="sRGB", environment=None,
                  spp=16, env_size=128, progress=None, no_sphere_reason="not asked (sphere=False)") -> dict:
    """Write the files of ``waveoptics simulate`` (see :func:`output_files`) and return the summary.

    *space* (``"sRGB"``, ``"ACEScg"``, ``"Display P3"``) is the linear RGB space of ``brdf_rgb.exr`` and of the
    summary's RGB albedos; PNG previews and sphere renders are always sRGB. *environment* (a name in
    :data:`waveoptics.renderers.lighting.PROCEDURAL`, an .exr map or a :class:`waveoptics.renderers.lighting.Environment`) adds both
    models' spheres lit by that map (*env_size* pixels, *spp* samples per technique and pixel, multiple importance
    sampling; :func:`waveoptics.renderers.sphere.render_sphere_environment`). Run without sphere renders (*sphere*
    False), it writes no :data:`SPHERE_FILES`; ``delta_e2000`` is null and ``skipped`` says why (*no_sphere_reason*).
    """
    spheres = sim.brdf_wave is not None
    if environment is not None and not spheres:
        raise FieldError("an environment render needs the sphere renders' table; this simulation was run without "
                         "them (sphere=False)", "environment")
    files = output_files(environment is not None, sim.params.get("diffraction") == "rayleigh-rice" and
                         sim.nano is not None, spheres)
    final = io.prepare_outdir(outdir, overwrite=overwrite, expected=files)
    env = None if environment is None else lighting.environment(environment)
    # the set is written into a hidden staging directory beside the outputs and moved into place only when every
    # file is whole (summary.json last): a run that fails or is interrupted leaves the earlier set untouched
    with io.staged_outputs(final, files, last="summary.json", members=output_files(True, True)) as out:
        return _write_outputs(sim, out, files, env, sphere_size, space, spp, env_size, progress, no_sphere_reason)


def _write_outputs(sim, out, files, env, sphere_size, space, spp, env_size, progress, no_sphere_reason) -> dict:
    t0 = time.perf_counter()
    L = sim.lobes
    g = sim.grid
    hdr = scatter.brdf_exr_header(g, sim.params["incident_deg"], sim.params["material"])
    io.write_spectral_exr(out / "brdf_spectral.exr", {float(lam): g.to_image(L.total[i]) for i, lam in
                                                      enumerate(sim.wavelengths_nm)}, header=hdr, overwrite=True)
    space = colour.space_name(space)
    rgb_out = sim.rgb_lobe("total", space)
    rgb = sim.rgb_lobe("total") if space != "sRGB" else rgb_out
    rgb_mf = sim.rgb_lobe("microfacet")
    gamut = {}   # RGB images with colours outside their space's gamut: kept unclipped, stated in file and summary
    gamut["brdf_rgb.exr"] = io.write_rgb_exr(
        out / "brdf_rgb.exr", g.to_image(np.moveaxis(rgb_out, -1, 0)).transpose(1, 2, 0), space=space,
        header={**hdr, "waveoptics_colourspace": f"linear {space}, white-balanced (CAT02) from "
                                                 f"{sim.params['illuminant']}"})
    _plot_hemispheres(rgb, rgb_mf, g, out / "brdf.png", sim)
    _plot_lobes(sim, out / "lobes.png")
    delta_e, env_time = (_write_spheres(sim, out, gamut, sphere_size, env, spp, env_size, progress)
                         if sim.brdf_wave is not None else (None, None))
    polarized = None
    if "nano_polarized.exr" in files:   # Rayleigh-Rice: the four polarized lobes as layers ss, sp, ps, pp
        lobes = nano_polarized(sim)
        chans = {f"{c}.{io.spectral_channel_name(lam)}": g.to_image(lobes[c][i])
                 for c in scatter.COMPONENTS for i, lam in enumerate(sim.wavelengths_nm)}
        io.write_exr(out / "nano_polarized.exr", chans, {
            **hdr, "spectralLayoutVersion": io.SPECTRAL_LAYOUT_VERSION,
            "waveoptics_quantity": "Rayleigh-Rice nano lobe f_ab (1/sr) at the light, before the micro facets spread "
                                   "it; layers ss, sp, ps, pp: a = incident, b = scattered polarization (s or p to "
                                   "the planes of incidence and scattering); unpolarized light sees (ss+sp+ps+pp)/2"},
            overwrite=True)
        polarized = {c: integrate(lobes[c], g) for c in scatter.COMPONENTS}
    timings = dict(sim.timings_s)
    timings["outputs"] = time.perf_counter() - t0
    if env_time is not None:
        timings["environment_render"] = env_time
    summary = {
        "wavelengths_nm": sim.wavelengths_nm,
        "albedo": L.albedo("total"),
        "microfacet_albedo": L.albedo("microfacet"),
        "coherent_specular_fraction": L.coherent_specular_fraction(),
        "diffraction_albedo": L.albedo("diffraction"),
        "rgb_albedo": sim.rgb_albedo("total", space),
        "microfacet_rgb_albedo": sim.rgb_albedo("microfacet", space),
        "colourspace": f"linear {space}",
        "out_of_gamut": {k: v for k, v in gamut.items() if v is not None},
        "delta_e2000": delta_e,
        "solver": sim.params["solver"],
        "nano_band": sim.band,
        **({"nano_field": nano_field(sim.nano)} if sim.nano is not None and sim.nano.surface is not None else {}),
        **({"nano_polarized_albedo": polarized} if polarized is not None else {}),
        **({"skipped": render.skipped_spheres(no_sphere_reason)} if delta_e is None else {}),
        "timings_s": timings,
        "parameters": sim.params,
        "files": list(files),
        "units": SUMMARY_UNITS,
    }
    io.write_json(out / "summary.json", summary)
    return summary


def _write_spheres(sim, out, gamut, sphere_size, env, spp, env_size, progress):
    """The sphere renders of both models (and, with *env*, lit by that environment) into *out*; their ΔE2000
    mean and max, and the environment render's time (s, None without one). *gamut* takes their out-of-gamut notes."""
    plt = figures.pyplot()
    wave, mf, dE, mask = render_spheres(sim, sphere_size)
    exposure = render.key_exposure(wave, mask)
    figures.save_png(out / "sphere_wave.png", render.tonemap(wave, exposure))
    figures.save_png(out / "sphere_microfacet.png", render.tonemap(mf, exposure))
    theta, phi = sim.params["incident_deg"]
    sphere_hdr = {"waveoptics_quantity": "radiance, linear sRGB (D65 white), of a sphere under a directional light "
                                         "of irradiance pi: a white Lambertian sphere facing the light is 1",
                  "waveoptics_camera": "orthographic, looking down -z; x right, y up; row 0 = top",
                  "waveoptics_light_deg": f"theta {theta:g} phi {phi:g} (from +z, azimuth from +x)",
                  "waveoptics_illuminant": str(sim.params["illuminant"]), "waveoptics_material": sim.params["material"]}
    for name, img, model in (("sphere_wave.exr", wave, "two-scale (wave optics)"),
                             ("sphere_microfacet.exr", mf, "microfacet (geometric optics)")):
        gamut[name] = io.write_rgb_exr(out / name, img, header={**sphere_hdr, "waveoptics_model": model})
    fig, ax = plt.subplots(figsize=(4.2, 3.6))
    im = ax.imshow(np.where(mask, dE, np.nan), cmap="magma", vmin=0)
    ax.set_title("ΔE2000: two-scale vs microfacet", fontsize=9)
    ax.axis("off")
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="ΔE2000")
    figures.save_figure(fig, out / "sphere_diff.png")
    env_time = None
    if env is not None:
        t_env = time.perf_counter()
        imgs = []
        for name, fn in (("sphere_env_wave.exr", sim.brdf_wave), ("sphere_env_microfacet.exr", sim.brdf_microfacet)):
            img, on = render.render_sphere_environment(fn, sim.wavelengths_nm, env, size=env_size, spp=spp,
                                                       illuminant=sim.illuminant, progress=progress)
            gamut[name] = io.write_rgb_exr(
                out / name, img, header={**sphere_hdr, "waveoptics_light_deg": f"environment {env.name}",
                                 "waveoptics_quantity": "radiance, linear sRGB (D65 white), of a sphere lit by the "
                                                        "environment map (white Lambertian in a constant map of 1: 1)",
                                 "waveoptics_environment": f"{env.name}, equirectangular, +y up, column 0 = -z",
                                 "waveoptics_samples": f"{spp} BRDF + {spp} environment samples per pixel (MIS)"})
            imgs.append(img)
        exp_env = render.key_exposure(imgs[0], on)
        render.plot_spheres([render.tonemap(i, exp_env) for i in imgs],
                            ["two-scale (diffraction)", "microfacet only"], out / "sphere_env.png",
                            exposure=exp_env, light_deg=None)
        env_time = time.perf_counter() - t_env
    d = dE[mask] if mask.any() else np.zeros(1)
    return {"mean": float(d.mean()), "max": float(d.max())}, env_time


def _plot_hemispheres(rgb, rgb_mf, grid, path, sim):
    plt = figures.pyplot()

    Y = colour.luminance(rgb)
    Ymf = colour.luminance(rgb_mf)
    top = max(float(Y.max()), float(Ymf.max()), 1e-6)
    lo = top * 1e-4
    fig, axes = plt.subplots(1, 2, figsize=(8.6, 4.0), constrained_layout=True)
    norm = colors.LogNorm(vmin=lo, vmax=top)
    ext = [grid.u_range[0], grid.u_range[1], grid.v_range[0], grid.v_range[1]]
    for ax, img, lum, title in ((axes[0], rgb, Y, "two-scale (wave optics)"), (axes[1], rgb_mf, Ymf, "microfacet")):
        # colour from the RGB chromaticity, brightness from log luminance (the colour bar's scale)
        chroma = np.where(lum[..., None] > 0, np.maximum(img, 0) / np.maximum(lum, 1e-30)[..., None], 0)
        bright = np.clip(norm(np.maximum(lum, lo)), 0, 1)
        disp = np.clip(chroma * bright[..., None] / max(1.0, float(np.max(chroma * bright[..., None]))), 0, 1)
        disp = np.where(grid.inside[..., None], disp, 1.0)
        ax.imshow(disp, origin="lower", extent=ext)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("u = sin θ cos φ")
        ax.set_ylabel("v = sin θ sin φ")
    sm = plt.cm.ScalarMappable(norm=norm, cmap="gray")
    fig.colorbar(sm, ax=axes, label="BRDF luminance Y (1/sr), log scale", shrink=0.85)
    th, ph = sim.params["incident_deg"]
    fig.suptitle(f"{sim.params['material']}, θi={th:g}°, φi={ph:g}°, {sim.params['illuminant']}", fontsize=10)

    save_figure(fig, path)


def _plot_lobes(sim, path, n_curves=4):
    plt = figures.pyplot()

    th, f = plane_of_incidence(sim, "total")
    _, fm = plane_of_incidence(sim, "microfacet")
    w = sim.wavelengths_nm
    idx = np.unique(np.linspace(0, w.size - 1, min(n_curves, w.size)).round().astype(int))
    fig, ax = plt.subplots(figsize=(7, 4.2))
    cmap = plt.get_cmap("turbo")
    for k, i in enumerate(idx):
        col = cmap((w[i] - 380) / 400)
        ax.semilogy(th, np.maximum(f[i], 1e-8), color=col, lw=1.5, label=f"two-scale {w[i]:.0f} nm")
        ax.semilogy(th, np.maximum(fm[i], 1e-8), color=col, lw=1, ls="--", label=f"microfacet {w[i]:.0f} nm")
    ax.set_xlabel("θo in the plane of incidence (deg, + = mirror side)")
    ax.set_ylabel("BRDF f (1/sr)")
    ax.set_ylim(max(1e-6, float(np.max(f)) * 1e-7), float(max(np.max(f), np.max(fm))) * 3)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    ax.set_title(f"Plane-of-incidence lobes: the diffraction tail ({sim.params['material']}, "
                 f"θi={sim.params['incident_deg'][0]:g}°)", fontsize=10)

    save_figure(fig, path)
