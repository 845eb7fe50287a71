"""The main job: a two-scale surface simulated per wavelength, integrated to colour, compared with microfacets.

:func:`simulate` evaluates the two-scale BRDF (:mod:`waveoptics.twoscale`) and the plain microfacet BRDF of the
same micro roughness and material on a hemisphere grid at the scene's incident direction, and on a table of
incidence angles for sphere renders; :func:`write_outputs` writes the files of ``waveoptics simulate``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from . import psd, spectral, surfaces, twoscale
from .diffraction import DirectionGrid
from .errors import WaveopticsError, unknown
from .materials import get_material
from .units import direction_from_angles, parse_length

#: incidence angles (degrees) of the lobe table used for sphere renders
SPHERE_THETAS_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 78.0, 84.0, 88.0)

#: parameter names accepted by --nano MODEL:... (lengths take units)
NANO_PARAMS = {
    "gaussian": {"sigma": "length", "T": "length"},
    "exponential": {"sigma": "length", "T": "length"},
    "abc": {"sigma": "length", "B": "length", "C": "number"},
    "sinusoid": {"amplitude": "length", "period": "length", "orientation": "number"},
    "scratches": {"count": "number", "width": "length", "depth": "length", "orientation": "number",
                  "spread": "number"},
}
_ALIASES = {"corr": "T", "corr_length": "T", "corr-length": "T", "a": "amplitude", "amp": "amplitude",
            "period": "period", "b": "B", "c": "C", "rms": "sigma"}

DEFAULT_NANO = "abc:sigma=10nm,B=2um,C=2.6"

#: nano height fields larger than this per side are cropped to a central tile for the solvers (the statistics of
#: a stationary surface are the same on the tile; the cost is not)
MAX_NANO_SAMPLES = 512


def crop(hf: surfaces.HeightField, n: int) -> surfaces.HeightField:
    """The central tile of at most n × n samples of *hf* (unchanged if already that small)."""
    ny, nx = hf.shape
    if ny <= n and nx <= n:
        return hf
    y0, x0 = max(0, (ny - n) // 2), max(0, (nx - n) // 2)
    sl = (slice(y0, y0 + min(n, ny)), slice(x0, x0 + min(n, nx)))
    meta = {k: v for k, v in hf.meta.items() if k != "periodic"}  # a tile of a periodic field is not periodic
    meta["cropped_from"] = [ny, nx]
    return surfaces.HeightField(hf.heights[sl], hf.dx, hf.dy, None if hf.mask is None else hf.mask[sl], meta)


def parse_nano(text: str) -> tuple[str, dict]:
    """Parse ``MODEL:key=value,...`` (e.g. ``abc:sigma=10nm,B=5um,C=3``) into (model, params in SI units)."""
    s = str(text).strip()
    model, _, rest = s.partition(":")
    model = model.strip().lower()
    if model not in NANO_PARAMS:
        raise unknown("nano model", model, NANO_PARAMS)
    params = {}
    for item in filter(None, (p.strip() for p in rest.split(","))):
        key, eq, val = item.partition("=")
        key = _ALIASES.get(key.strip(), key.strip())
        if not eq or key not in NANO_PARAMS[model]:
            raise WaveopticsError(f"--nano {text!r}: parameter {item!r} is not allowed for {model}; "
                                  f"use {', '.join(k + '=...' for k in NANO_PARAMS[model])}")
        if key in params:
            raise WaveopticsError(f"--nano {text!r}: parameter {key!r} is given twice")
        kind = NANO_PARAMS[model][key]
        if kind == "length":
            params[key] = parse_length(val, name=f"--nano {key}", allow_zero=(key in ("sigma", "depth", "amplitude")))
        else:
            try:
                params[key] = float(val)
            except ValueError:
                raise WaveopticsError(f"--nano {key}={val!r} is not a number") from None
    missing = [k for k in NANO_PARAMS[model] if k not in params and k not in ("orientation", "spread")]
    if missing:
        raise WaveopticsError(f"--nano {text!r} lacks {', '.join(missing)} (units: 5nm, 1.2um)")
    return model, params


def nano_surface_size(wavelengths_nm, length_scale_m, *, max_samples=512):
    """Patch size (m) and samples for a generated nano height field.

    The spacing is ≤ λ_min/4 (no aliasing over the whole hemisphere, physics.md §1) and the patch spans ≥ 16
    correlation lengths (statistics) and ≥ 24 λ_max (the specular spike is ~λ/L wide), within *max_samples*.
    """
    lmin = float(np.min(wavelengths_nm)) * 1e-9
    lmax = float(np.max(wavelengths_nm)) * 1e-9
    dx = lmin / 4
    L = max(16 * length_scale_m, 24 * lmax)
    n = int(min(max_samples, 2 ** math.ceil(math.log2(max(L / dx, 64)))))
    return n * dx, n


def make_nano(spec, wavelengths_nm, *, solver="auto", seed=0, surface=None) -> twoscale.Nano | None:
    """A :class:`twoscale.Nano` from ``--nano`` text or a height field; None for σ = 0 (no nano-roughness)."""
    if surface is not None:
        hf = surface if isinstance(surface, surfaces.HeightField) else surfaces.load(surface)
        if solver == "psd":
            raise WaveopticsError("solver 'psd' needs nano statistics (--nano MODEL:...), not a height field")
        return twoscale.Nano(surface=hf)
    model, p = parse_nano(spec)
    if p.get("sigma", p.get("amplitude", p.get("depth", 1.0))) == 0:
        return None
    if model in psd.PSD_MODELS and solver in ("auto", "psd"):
        return twoscale.Nano(model=psd.PSDModel(model, sigma=p["sigma"], T=p.get("T"), B=p.get("B"),
                                                C=p.get("C")))
    if solver == "psd":
        raise WaveopticsError(f"solver 'psd' has no formula for {model!r}; use fft or direct")
    scale = p.get("T") or p.get("period") or (p.get("B", 0) / (2 * np.pi)) or p.get("width") or 1e-6
    size, n = nano_surface_size(wavelengths_nm, scale)
    gen = {"gaussian": dict(sigma=p.get("sigma"), corr_length=p.get("T")),
           "exponential": dict(sigma=p.get("sigma"), corr_length=p.get("T")),
           "abc": dict(sigma=p.get("sigma"), B=p.get("B"), C=p.get("C")),
           "sinusoid": dict(amplitude=p.get("amplitude"), period=p.get("period"),
                            orientation_deg=p.get("orientation", 0.0)),
           "scratches": dict(count=p.get("count", 10), width=p.get("width"), depth=p.get("depth"),
                             orientation_deg=p.get("orientation", 0.0), spread_deg=p.get("spread", 0.0))}[model]
    if model not in ("sinusoid",):
        gen["seed"] = seed
    hf = surfaces.generate(model, size=size, samples=n, **gen)
    return twoscale.Nano(surface=hf)


@dataclass
class Simulation:
    """Everything :func:`simulate` computed (arrays in 1/sr, wavelengths in nm)."""

    lobes: twoscale.Lobes
    table_thetas_deg: np.ndarray
    table_total: np.ndarray  # (n_θ, n_λ, n_v, n_u)
    table_microfacet: np.ndarray
    illuminant: str
    params: dict
    nano: twoscale.Nano | None = None
    timings_s: dict = field(default_factory=dict)

    @property
    def wavelengths_nm(self):
        return self.lobes.wavelengths_nm

    @property
    def grid(self):
        return self.lobes.grid

    def rgb_lobe(self, which="total", space="sRGB"):
        """Linear RGB (n_v, n_u, 3) of the lobe f (1/sr) under the illuminant."""
        f = getattr(self.lobes, which)
        return spectral.reflectance_to_rgb(np.moveaxis(f, 0, -1), self.wavelengths_nm, self.illuminant, space=space)

    def rgb_albedo(self, which="total", space="sRGB"):
        """Linear RGB of the directional albedo spectrum."""
        a = self.lobes.albedo(which)
        return spectral.reflectance_to_rgb(a, self.wavelengths_nm, self.illuminant, space=space)


def simulate(material="Al", *, nano=DEFAULT_NANO, surface=None, micro_alpha=0.05, ndf="beckmann",
             shadowing="smith-correlated", incident=(30.0, 0.0), illuminant="D65", wavelengths=None,
             accuracy_dE=1.0, resolution=128, solver="auto", kd=0.5, sphere=True, seed=0, device=None,
             precision="float32", progress=None, split=False) -> Simulation:
    """Simulate a two-scale surface and the plain microfacet model.

    Parameters
    ----------
    material : str or Material
        Surface material (see :func:`waveoptics.materials.get_material`).
    nano : str
        ``MODEL:params`` nano-roughness (ignored when *surface* is given); σ = 0 disables it.
    surface : str, Path or HeightField, optional
        Nano height field (file or object); uses the fft/direct solvers.
    micro_alpha : float
        Micro NDF roughness α (≥ 0). ndf, shadowing: see :mod:`waveoptics.microfacet`.
    incident : (θ, φ) degrees
        Direction of the light for the lobe outputs (and the sphere's light).
    illuminant : str
        Light source (see :func:`waveoptics.spectral.illuminant`).
    wavelengths : array_like, optional
        Wavelengths in nm; default chosen from the illuminant for *accuracy_dE*.
    resolution : int
        Direction grid cells per axis over the projected hemisphere.
    solver : {"auto", "psd", "fft", "direct"}
    kd : float
        Diffuse albedo of a dielectric substrate (metals have none).
    sphere : bool
        Also tabulate lobes over incidence angles for sphere renders.
    split : bool
        *surface* holds both scales: split it (:func:`waveoptics.twoscale.split_scales`); the micro NDF's α comes
        from the long-period part's slopes (*micro_alpha* is ignored) and the short-period part diffracts.

    Returns
    -------
    Simulation
    """
    t0 = time.perf_counter()
    mat = get_material(material)
    spd = spectral.illuminant(illuminant)
    w = (np.asarray(wavelengths, dtype=float) if wavelengths is not None
         else spectral.simulation_wavelengths(spd, accuracy_dE))
    theta, phi = incident
    if not (0 <= theta < 90):
        raise WaveopticsError(f"incident θ={theta!r}° is not allowed; use 0 <= θ < 90 degrees")
    if solver not in ("auto", "psd", "fft", "direct"):
        raise unknown("solver", solver, ("auto", "psd", "fft", "direct"))
    micro = twoscale.Micro(alpha=micro_alpha, ndf=ndf, shadowing=shadowing)
    split_info = None
    if split:
        if surface is None:
            raise WaveopticsError("--split needs --surface FILE holding both scales")
        hf = surface if isinstance(surface, surfaces.HeightField) else surfaces.load(surface)
        micro, nano_hf, split_info = twoscale.split_scales(hf, w, ndf=ndf)
        micro = twoscale.Micro(alpha=micro.alpha, alpha_y=micro.alpha_y, ndf=ndf, shadowing=shadowing)
        nano_obj = twoscale.Nano(surface=crop(nano_hf, MAX_NANO_SAMPLES))
    else:
        nano_obj = make_nano(nano, w, solver=solver, seed=seed, surface=surface)
        if nano_obj is not None and nano_obj.surface is not None:
            nano_obj = twoscale.Nano(surface=crop(nano_obj.surface, MAX_NANO_SAMPLES))
    grid = DirectionGrid.hemisphere(resolution)
    timings = {"setup": time.perf_counter() - t0}

    t = time.perf_counter()
    wi = direction_from_angles(theta, phi)
    lobes = twoscale.evaluate(wi, w, mat, micro, nano_obj, grid, solver=solver, kd=kd, device=device,
                              precision=precision)
    timings["lobe"] = time.perf_counter() - t
    if progress:
        progress(1)

    t = time.perf_counter()
    thetas = np.array(SPHERE_THETAS_DEG if sphere else (theta,))
    tab_total = np.empty((thetas.size, w.size, grid.n_v, grid.n_u))
    tab_mf = np.empty_like(tab_total)
    for i, th in enumerate(thetas):
        L = twoscale.evaluate(direction_from_angles(th, 0.0), w, mat, micro, nano_obj, grid, solver=solver, kd=kd,
                              device=device, precision=precision)
        tab_total[i], tab_mf[i] = L.total, L.microfacet
        if progress:
            progress(1)
    timings["sphere_table"] = time.perf_counter() - t
    params = {"material": mat.name, "material_source": mat.source, "nano": None if surface is not None else nano,
              "surface": str(surface) if surface is not None and not isinstance(surface, surfaces.HeightField)
              else None, "micro_alpha": micro_alpha, "ndf": ndf, "shadowing": shadowing,
              "incident_deg": [theta, phi], "illuminant": spd.name, "resolution": resolution,
              "solver": lobes.info["solver"], "kd": 0.0 if mat.is_metal else kd, "precision": precision,
              "sigma_nano_m": lobes.info["sigma_nano_m"], "seed": seed, "split": split_info,
              "micro_alpha_used": [micro.alpha, micro.alpha_y],
              # materials clamp their index outside the measured data (materials.py policy): say where
              "clamped_wavelengths_nm": [float(x) for x in w[mat.out_of_range(w)]]}
    return Simulation(lobes=lobes, table_thetas_deg=thetas, table_total=tab_total, table_microfacet=tab_mf,
                      illuminant=illuminant, params=params, timings_s=timings, nano=nano_obj)


OUTPUT_FILES = ("brdf_spectral.exr", "brdf_rgb.exr", "brdf.png", "sphere_wave.png", "sphere_microfacet.png",
                "sphere_diff.png", "lobes.png", "summary.json")


def render_spheres(sim: Simulation, size=256):
    """Linear sRGB sphere renders of both models and the per-pixel ΔE2000 (off-sphere pixels 0)."""
    thetas = np.radians(sim.table_thetas_deg)
    theta, phi = sim.params["incident_deg"]
    # light direction in world space: θ from the viewing axis, in the plane given by φ
    light = direction_from_angles(theta, phi)
    from . import render

    wave, mask = render.render_sphere(sim.table_total, thetas, sim.grid, sim.wavelengths_nm, light, size=size,
                                      illuminant=sim.illuminant)
    mf, _ = render.render_sphere(sim.table_microfacet, thetas, sim.grid, sim.wavelengths_nm, light, size=size,
                                 illuminant=sim.illuminant)
    dE = np.zeros(mask.shape)
    dE[mask] = spectral.delta_e2000(wave[mask], mf[mask])
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
    from scipy.ndimage import map_coordinates

    out = np.stack([map_coordinates(fl, [fv, fu], order=1, mode="nearest") for fl in f])
    return np.degrees(np.arcsin(s)), out


def write_outputs(sim: Simulation, outdir, *, overwrite=False, sphere_size=256, space="sRGB") -> dict:
    """Write the files of ``waveoptics simulate`` (see :data:`OUTPUT_FILES`) and return the summary.

    *space* (``"sRGB"``, ``"ACEScg"``, ``"Display P3"``) is the linear RGB space of ``brdf_rgb.exr`` and of the
    summary's RGB albedos; PNG previews and sphere renders are always sRGB.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from . import io, render

    out = io.prepare_outdir(outdir, overwrite=overwrite, expected=OUTPUT_FILES)
    t0 = time.perf_counter()
    L = sim.lobes
    g = sim.grid
    hdr = {k: str(v) for k, v in g.header().items()}
    hdr.update({"waveoptics_incident_deg": " ".join(map(str, sim.params["incident_deg"])),
                "waveoptics_material": sim.params["material"], "waveoptics_quantity": "BRDF f (1/sr), not x cos"})
    io.write_spectral_exr(out / "brdf_spectral.exr", {float(lam): L.total[i] for i, lam in
                                                      enumerate(sim.wavelengths_nm)}, header=hdr, overwrite=True)
    space = spectral.space_name(space)
    rgb_out = sim.rgb_lobe("total", space)
    rgb = sim.rgb_lobe("total") if space != "sRGB" else rgb_out
    rgb_mf = sim.rgb_lobe("microfacet")
    io.write_exr(out / "brdf_rgb.exr", {"R": rgb_out[..., 0], "G": rgb_out[..., 1], "B": rgb_out[..., 2]},
                 header={**hdr, "waveoptics_colourspace": f"linear {space}, white-balanced (CAT02) from "
                                                          f"{sim.params['illuminant']}"}, overwrite=True)
    _plot_hemispheres(rgb, rgb_mf, g, out / "brdf.png", sim)
    wave, mf, dE, mask = render_spheres(sim, sphere_size)
    exposure = None
    pos = (wave @ np.array([0.2126, 0.7152, 0.0722]))[mask]
    pos = pos[pos > 1e-8]
    if pos.size:
        exposure = min(0.18 / float(np.exp(np.mean(np.log(pos)))), 4.0)
    render.save_png(out / "sphere_wave.png", render.tonemap(wave, exposure))
    render.save_png(out / "sphere_microfacet.png", render.tonemap(mf, exposure))
    fig, ax = plt.subplots(figsize=(4.2, 3.6))
    im = ax.imshow(np.where(mask, dE, np.nan), cmap="magma", vmin=0)
    ax.set_title("ΔE2000: two-scale vs microfacet", fontsize=9)
    ax.axis("off")
    fig.colorbar(im, ax=ax, fraction=0.046, pad=0.04, label="ΔE2000")
    render.save_figure(fig, out / "sphere_diff.png")
    _plot_lobes(sim, out / "lobes.png")
    timings = dict(sim.timings_s)
    timings["outputs"] = time.perf_counter() - t0
    summary = {
        "wavelengths_nm": sim.wavelengths_nm,
        "albedo": L.albedo("total"),
        "microfacet_albedo": L.albedo("microfacet"),
        "coherent_specular_fraction": L.coherent_specular_fraction(),
        "diffraction_albedo": L.albedo("diffraction"),
        "rgb_albedo": sim.rgb_albedo("total", space),
        "microfacet_rgb_albedo": sim.rgb_albedo("microfacet", space),
        "colourspace": f"linear {space}",
        "delta_e2000": {"mean": float(dE[mask].mean()) if mask.any() else 0.0,
                        "max": float(dE[mask].max()) if mask.any() else 0.0},
        "solver": sim.params["solver"],
        "timings_s": timings,
        "parameters": sim.params,
        "files": list(OUTPUT_FILES),
    }
    io.write_json(out / "summary.json", summary)
    return summary


def _plot_hemispheres(rgb, rgb_mf, grid, path, sim):
    import matplotlib.pyplot as plt
    from matplotlib import colors

    Y = rgb @ np.array([0.2126, 0.7152, 0.0722])
    Ymf = rgb_mf @ np.array([0.2126, 0.7152, 0.0722])
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
    from .render import save_figure

    save_figure(fig, path)


def _plot_lobes(sim, path, n_curves=4):
    import matplotlib.pyplot as plt

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
    from .render import save_figure

    save_figure(fig, path)
