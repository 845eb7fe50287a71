"""The glint render job (``waveoptics render --glints``): a :class:`waveoptics.renderers.requests.GlintRequest`
in, the footprint render of :mod:`waveoptics.renderers.glints` written whole or not at all, the summary out.

Writes glints_wave.exr and glints_geometric.exr (linear sRGB radiance of a unit-intensity point light),
glints_layers.exr (per pixel: the footprint and the spectral radiance of both models), glints.png and summary.json
(last: it says the set is complete). Errors are :class:`waveoptics.errors.FieldError` naming the request's fields.

References
----------
.. [1] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering Specular Microgeometry with Wave
   Optics", ACM TOG 37(4):75, 2018 (the footprint BRDFs; :mod:`waveoptics.renderers.glints`).
.. [2] CIE 142-2001 (CIEDE2000, the colour difference of the two renders; :mod:`waveoptics.colour`).
"""
from __future__ import annotations

import contextlib
from dataclasses import dataclass
from pathlib import Path

from ..errors import FieldError
from .jobs import load_height_field
from .requests import GlintRequest

__all__ = ["GLINT_OUTPUTS", "GlintResult", "glint_field", "glint_settings", "glints_job"]

#: files of one glint render (summary.json last)
GLINT_OUTPUTS = ("glints_wave.exr", "glints_geometric.exr", "glints_layers.exr", "glints.png", "summary.json")


@dataclass(frozen=True)
class GlintResult:
    """What :func:`glints_job` did: its *summary* (the content of summary.json), the output directory, the
    render's timings in s and the cost estimate made before it (:class:`waveoptics.renderers.glints.
    GlintEstimate`)."""

    summary: dict
    outdir: Path
    timings_s: dict
    estimate: object


def _spacing_pair(text):
    """*text* (``D`` or ``DX,DY``, lengths with units) as (dx, dy) in m, or None."""
    from ..units import parse_length

    if text is None:
        return None
    parts = [parse_length(x, name="spacing") for x in str(text).split(",")]
    return parts[0], parts[-1]


def glint_field(request: GlintRequest):
    """The height field of a glint render: ``procedural:NAME:SIZE:SPACING[:SEED]``, a .h5 / .hdf5 (chunked), a .npy
    (memory-mapped), any other height-field file, or a field given as it is."""
    from .. import surfaces
    from ..units import parse_length

    if request.surface is None:
        raise FieldError("a glint render needs {surface} (the height field to render)", "surface")
    if not isinstance(request.surface, (str, Path)):
        return request.surface
    text = str(request.surface)
    if text.startswith("procedural:"):
        parts = text.split(":")
        if len(parts) not in (4, 5):
            raise FieldError(f"{{surface}} {text!r}: give procedural:NAME:SIZE:SPACING[:SEED], e.g. "
                             "procedural:brushed:2mm:0.1um", "surface")
        return surfaces.procedural(parts[1], parse_length(parts[2], name="surface"),
                                   parse_length(parts[3], name="surface"), int(parts[4]) if len(parts) > 4 else 0)
    if text.lower().endswith((".h5", ".hdf5")):
        return surfaces.HDF5Field(text)
    if text.lower().endswith(".npy") and request.channel is None:
        return surfaces.open_large(request.surface, spacing=_spacing_pair(request.spacing), units=request.units)
    return load_height_field(request.surface, request.spacing, request.units, request.channel)


def glint_settings(request: GlintRequest):
    """The :class:`waveoptics.renderers.glints.GlintSettings` of *request* (its directions and lengths parsed)."""
    from ..units import parse_angle, parse_direction, parse_length, parse_wavelengths
    from .glints import GlintSettings

    lt, lp = parse_direction(request.incident, name="incident")
    vt, vp = parse_direction(request.view, name="view")
    rho = 0.0 if request.light_radius is None else parse_angle(request.light_radius, name="light_radius")
    return GlintSettings(size=request.sphere_size, view_deg=vt, view_azimuth_deg=vp, light_deg=lt,
                         light_azimuth_deg=lp, wavelengths_nm=tuple(parse_wavelengths(request.wavelengths)),
                         shape=request.shape, coherence_m=None if request.coherence is None
                         else parse_length(request.coherence, name="coherence"), light_radius_deg=rho)


def glints_job(request: GlintRequest, output, *, overwrite: bool = False, progress=None, executor=None,
               on_estimate=None) -> GlintResult:
    """Render *request* into the directory *output* (see the module doc); the set of files is written whole or not
    at all (:func:`waveoptics.io.files.staged_outputs`), an existing set only with *overwrite*.

    Parameters
    ----------
    progress : callable, optional
        ``progress(total=N, desc=TEXT)`` returning a progress bar with ``update(k)`` and ``close()`` (tqdm's), made
        when the pixels start.
    executor : callable, optional
        A context manager factory: ``executor()`` enters into a :class:`concurrent.futures.Executor` the pixel rows
        run on (e.g. a Dask client's); None: this process.
    on_estimate : callable, optional
        Called with the cost estimate (:class:`waveoptics.renderers.glints.GlintEstimate`) before the render.
    """
    import numpy as np

    from .. import colour
    from ..io import files
    from . import glints

    outdir = files.prepare_outdir(output, overwrite=overwrite, expected=GLINT_OUTPUTS)
    settings = glint_settings(request)
    field = glint_field(request)
    est = glints.estimate_glints(field, request.material, settings)
    if on_estimate is not None:
        on_estimate(est)
    bar = None if progress is None else progress(total=settings.size, desc="glints")
    with contextlib.ExitStack() as stack:
        pool = stack.enter_context(executor()) if executor is not None else None
        r = glints.render_glints(field, request.material, settings, progress=None if bar is None else bar.update,
                                 executor=pool)
    if bar is not None:
        bar.close()
    de = np.where(r.on_field, colour.delta_e2000(r.wave, r.geometric), 0.0)
    with files.staged_outputs(outdir, GLINT_OUTPUTS, last="summary.json") as stage:
        _write_images(request, settings, r, de, stage)
        summary = _summary(request, settings, r, de, est)
        files.write_json(stage / "summary.json", summary)
    return GlintResult(summary, outdir, r.timings_s, est)


def _write_images(request, settings, r, de, stage) -> None:
    """The EXRs and the PNG of a glint render into *stage*."""
    from ..io import files
    from .sphere import percentile_exposure, plot_spheres, tonemap

    on = r.on_field
    exposure = percentile_exposure((r.wave, r.geometric), on)   # one exposure for both; glints are sparse
    for name, img in (("glints_wave.exr", r.wave), ("glints_geometric.exr", r.geometric)):
        files.write_rgb_exr(stage / name, img, {"waveoptics": "linear sRGB radiance of a unit-intensity point light"})
    files.write_exr(stage / "glints_layers.exr", _glint_layers(r, settings),
                    {"waveoptics": "per pixel: footprint (x, y, sigma1, sigma2 in m, angle in degrees) and "
                                   "spectral radiance per wavelength (wave., geometric.)"})
    name = Path(request.surface).name if isinstance(request.surface, (str, Path)) else "height field"
    lt, lp, vt, vp = (settings.light_deg, settings.light_azimuth_deg, settings.view_deg, settings.view_azimuth_deg)
    plot_spheres([tonemap(r.wave, exposure), tonemap(r.geometric, exposure)],
                 [f"wave optics (footprint Kirchhoff)\n{request.material}, {name}",
                  "geometric optics (footprint NDF)"], stage / "glints.png", diff=de,
                 diff_title=f"ΔE2000 (mean {float(de[on].mean()):.1f})", exposure=exposure,
                 caption=f"{settings.shape}; light at θ = {lt:g}°, φ = {lp:g}°; camera at θ = {vt:g}°, "
                         f"φ = {vp:g}°; footprint σ "
                         f"≈ {r.footprint_sigma_m[0] * 1e6:.3g} × {r.footprint_sigma_m[1] * 1e6:.3g} µm")


def _summary(request, settings, r, de, est) -> dict:
    """summary.json of a glint render."""
    on = r.on_field
    return {"surface": str(request.surface), "material": request.material, "size_px": settings.size,
            "shape": settings.shape, "workers": request.workers, "scheduler": request.scheduler,
            "light_deg": [settings.light_deg, settings.light_azimuth_deg],
            "view_deg": [settings.view_deg, settings.view_azimuth_deg],
            "light_radius_deg": settings.light_radius_deg, "wavelengths_nm": list(settings.wavelengths_nm), "footprint_sigma_m": list(r.footprint_sigma_m),
            "pixels_on_field": int(on.sum()), "delta_e2000_mean": float(de[on].mean()),
            "timings_s": {k: (round(v, 6) if isinstance(v, float) else v) for k, v in r.timings_s.items()},
            "estimate": {"pixels": est.pixels, "samples": est.samples, "per_pixel_s": est.per_pixel_s,
                         "estimate_s": est.estimate_s, "probe_pixels": est.probe_pixels},
            "outputs": list(GLINT_OUTPUTS)}


def _glint_layers(r, settings) -> dict:
    """EXR channels of a glint render: the footprint and the spectral radiance of both models per pixel."""
    ch = {f"footprint.{k}": r.footprints[..., n] for n, k in enumerate(("x", "y", "sigma1", "sigma2", "angle"))}
    for k, lam in enumerate(settings.wavelengths_nm):
        ch[f"wave.{lam:g}nm"] = r.wave_spectral[..., k]
        ch[f"geometric.{lam:g}nm"] = r.geometric_spectral[..., k]
    return ch
