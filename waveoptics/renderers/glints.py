"""Glint renders: a plane textured by a large height field, seen by a perspective camera under a small light, where
every pixel's footprint gives its own BRDF — in wave optics and in geometric optics, side by side (Yan et al. 2014,
2016, 2018).

Geometry (:data:`SHAPES`, ``shape=``):

* ``plane`` (world = the surface's frame): the height field lies on the plane z = 0 with its first sample at the
  origin, x along the grid's axis 1 and y along axis 0. The camera looks at the field's centre from elevation
  θ_v (from the normal) and azimuth φ_v; the light is a point at elevation θ_l, azimuth φ_l and the same
  distance.
* ``sphere``: a sphere of radius R = 0.9 min(W, H)/π at the origin, textured by the field through longitude γ
  and latitude β about the camera (u = W/2 + Rγ, v = H/2 + Rβ; the visible half maps inside the field). The
  shading frame at each point is (∂P/∂γ, ∂P/∂β, n) normalized; as with any latitude-longitude map the texture is
  compressed along γ by cos β away from the equator (footprints are measured in texture space). θ_v, φ_v and
  θ_l, φ_l are now directions from the sphere's centre in the world frame (z up).

For each pixel the ray through its centre meets the surface at texture point c; the pixel filter (a Gaussian of
``filter_px`` pixels) maps to the footprint Σ = J diag(s², s²) Jᵀ in texture space, with J the change of c per
pixel (finite differences): an ellipse that stretches along the view direction at oblique views (Yan et al. 2014,
§5). Pixels whose footprint box leaves the field, or whose ray misses the sphere, stay black.

Per pixel, with ω_i towards the light and ω_o towards the camera (both from the hit point, in its shading frame):

* wave optics: f = F(θ_d) K |Σ_j G_j e^{i k (ω_i + ω_o)·r_j} ΔxΔy|² / (λ² Σ_j G_j² ΔxΔy), the windowed
  Kirchhoff integral of the footprint (:mod:`waveoptics.scatter.pixel`) at this one direction pair;
* geometric optics: f = F(θ_d) D(h) / (4 cos θ_i cos θ_o) with D the footprint's facet-normal distribution, each
  facet smoothed by a Gaussian of rms slope ``intrinsic_slope`` per axis (Yan et al. 2016's intrinsic roughness:
  the histogram of a few hundred facets is otherwise a set of spikes), D = P22(s_h)/cos⁴θ_h (Heitz 2014); no
  shadowing (as Yan et al.).

The radiance is L = f cos θ_i I / d² for a point light of intensity I (W/sr per unit spectrum) at distance d; a
light of angular radius ρ (``light_radius_deg``, a disk seen from every point) gives L = (I / d²) ⟨f cos θ_i⟩
over the cone of ω_i about the direction to its centre (:mod:`waveoptics.renderers.light_cone`: a small product
rule, each of its directions one footprint query; directions below the horizon add nothing), the per-pixel
BRDF reported being ⟨f⟩ over the cone (the reflection integral of a uniform emitter, Kajiya 1986 [5]_). Radiance
is summed to
linear sRGB with the colour-matching functions (:func:`waveoptics.colour.reflectance_to_rgb_matrix`, the light's
spectrum white). Wavelengths are few (the glint's colour comes from diffraction's λ dependence).

Both BRDFs of all the pixels of a task come from one call of :func:`waveoptics.scatter.pixel_brdf` (an OpenCL
kernel summing every footprint's samples, float64 where the device has it), which reads one region of the field for
many footprints: the field may be any tiled field of :mod:`waveoptics.surfaces.tiled` (memory-mapped, chunked HDF5,
procedural), millimetres at 0.1 µm, never held in memory. :func:`estimate_glints` predicts the cost before a render.

Pixels are independent: rows of pixels are tasks, run in turn or by any ``concurrent.futures``-style executor
(``executor.map``; the command line passes a Dask client's executor for ``--workers N``). A memory-mapped field
travels to workers as its path, so each worker reads only its footprints' patches.

References
----------
.. [1] L.-Q. Yan, M. Hašan, W. Jakob, J. Lawrence, S. Marschner, R. Ramamoorthi, ACM TOG 33(4), 116, 2014.
.. [2] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, ACM TOG 35(4), 56, 2016 (intrinsic roughness).
.. [3] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, ACM TOG 37(4), 75, 2018.
.. [4] E. Heitz, JCGT 3(2), 2014 (D from the slope distribution).
.. [5] J. T. Kajiya, "The rendering equation", SIGGRAPH 1986, Computer Graphics 20(4), 143-150 (L_o = ∫ f L_e
   cos θ_i dω_i over the light's solid angle).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from .. import colour
from ..errors import FieldError, unknown
from ..materials import get_material
from ..scatter.pixel import PIXEL_BACKENDS, SUM_N_SIGMA, pixel_brdf
from ..surfaces.footprint import Footprint
from ..vocabulary import GLINT_SHAPES
from .light_cone import cone_directions

__all__ = ["SHAPES", "GlintSettings", "GlintRender", "GlintEstimate", "Geometry", "camera_rays", "geometry",
           "footprints", "render_glints", "estimate_glints"]


@dataclass(frozen=True)
class GlintSettings:
    """Camera, light and sampling of a glint render (angles in degrees, sizes in pixels).

    Parameters
    ----------
    size : int
        Image width and height (pixels).
    view_deg, view_azimuth_deg : float
        Camera elevation from the normal and azimuth.
    light_deg, light_azimuth_deg : float
        Light elevation and azimuth (a point light at the camera's distance).
    fov_deg : float
        Horizontal field of view; default: the field's width fills the image at the centre.
    filter_px : float
        Width (σ, pixels) of the Gaussian pixel filter that makes the footprint.
    intrinsic_slope : float
        rms slope per axis of each facet in the geometric NDF (Yan et al. 2016's intrinsic roughness).
    wavelengths_nm : tuple
        Wavelengths (nm) summed to RGB.
    shape : str
        What the field textures: ``plane`` or ``sphere`` (:data:`SHAPES`).
    coherence_m : float, m, optional
        Coherence width of the light (Yan et al. 2018); None: each footprint is coherent.
    light_radius_deg : float
        Angular radius ρ of the light, a disk seen from every point (degrees); 0: a point light. The BRDF is
        averaged over the cone of ω_i (:mod:`waveoptics.renderers.light_cone`).
    light_rings : int
        Rings of that average's rule (rings × (2 rings + 2) directions per pixel when ρ > 0).
    backend, precision : str
        Evaluator of the footprint sums (:func:`waveoptics.scatter.footprint_sums`): ``opencl`` (default; float64
        where the device has it unless *precision* says float32) or ``numpy``.
    """

    size: int = 64
    view_deg: float = 30.0
    view_azimuth_deg: float = 180.0
    light_deg: float = 30.0
    light_azimuth_deg: float = 0.0
    fov_deg: float | None = None
    filter_px: float = 0.5
    intrinsic_slope: float = 0.01
    wavelengths_nm: tuple = (450.0, 500.0, 550.0, 600.0, 650.0)
    shape: str = "plane"
    coherence_m: float | None = None
    light_radius_deg: float = 0.0
    light_rings: int = 2
    backend: str = "opencl"
    precision: str | None = None

    def __post_init__(self):
        if self.shape not in SHAPES:
            raise unknown("glint shape", self.shape, SHAPES, field="shape")
        if not (isinstance(self.size, (int, np.integer)) and 4 <= self.size <= 2048):
            raise FieldError(f"{{sphere_size}} {self.size!r} px is not allowed; give 4 to 2048", "sphere_size")
        for name in ("view_deg", "light_deg"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v < 89):
                raise FieldError(f"{name}={v!r} is not allowed; an elevation must be in [0, 89) degrees", name)
        if not (self.filter_px > 0 and self.intrinsic_slope > 0):
            raise FieldError("filter_px and intrinsic_slope must be > 0", "filter_px")
        if self.backend not in PIXEL_BACKENDS:
            raise unknown("footprint backend", self.backend, PIXEL_BACKENDS, field="backend")
        if self.precision not in (None, "float32", "float64"):
            raise FieldError(f"precision={self.precision!r} is not allowed; float32, float64 or None", "precision")
        if not (math.isfinite(self.light_radius_deg) and 0 <= self.light_radius_deg <= 30):
            raise FieldError(f"{{light_radius}} {self.light_radius_deg!r} degrees is not allowed; give 0 (a point "
                             "light) to 30 degrees", "light_radius")
        if not (isinstance(self.light_rings, (int, np.integer)) and 1 <= self.light_rings <= 16):
            raise FieldError(f"{{light_rings}} {self.light_rings!r} is not allowed; give 1 to 16", "light_rings")
        if self.coherence_m is not None and not (math.isfinite(self.coherence_m) and self.coherence_m > 0):
            raise FieldError(f"coherence_m={self.coherence_m!r} m is not allowed; it must be > 0", "coherence_m")


@dataclass
class GlintRender:
    """Linear sRGB images (size, size, 3) of the wave and geometric renders (saturated diffraction colours can lie
    outside the sRGB gamut: negative components), their radiance spectra (size, size, n_λ), the mask of pixels
    on the field, timings (s) and the median footprint widths (m); per pixel the BRDFs (1/sr, size, size, n_λ),
    the footprint (x, y, σ_1, σ_2, angle°: m, m, m, m, degrees) and the local directions (ω_i, ω_o)."""

    wave: np.ndarray
    geometric: np.ndarray
    on_field: np.ndarray
    timings_s: dict
    footprint_sigma_m: tuple
    wave_spectral: np.ndarray
    geometric_spectral: np.ndarray
    wave_brdf: np.ndarray | None = None
    geometric_brdf: np.ndarray | None = None
    footprints: np.ndarray | None = None
    directions: np.ndarray | None = None


def _dir(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def camera_rays(field, s: GlintSettings):
    """(camera position (3,), plane points c (size, size, 3), Jacobian dc/dpixel (size, size, 2, 2), distance) of
    the pinhole camera of *s* looking at the centre of the *field* plane (see the module doc)."""
    ny, nx = field.shape
    W, H = nx * field.dx, ny * field.dy
    centre = np.array([W / 2, H / 2, 0.0])
    dist = 1.5 * max(W, H)
    eye = centre + dist * _dir(s.view_deg, s.view_azimuth_deg)
    fov = math.radians(s.fov_deg) if s.fov_deg else 2 * math.atan(0.5 * min(W, H) / dist)
    ray = _pixel_rays(s, *_camera(eye, centre), math.tan(fov / 2))

    def hit(px, py):
        d = ray(px, py)
        return eye + (-eye[2] / d[..., 2])[..., None] * d

    px, py = _pixels(s)
    return eye, hit(px, py), _jacobian(hit, px, py)[..., :2, :], dist


@dataclass
class Geometry:
    """What the camera sees per pixel: ``hit`` (size, size) bool, texture points ``c`` (size, size, 2) in m from the
    field's first sample, their Jacobian ``J`` (size, size, 2, 2) per pixel, hit points ``P`` (size, size, 3),
    shading frames ``frame`` (size, size, 3, 3) whose rows are the tangent along texture x, along texture y and
    the normal, the camera ``eye`` and the ``light`` positions (3,), and the camera distance ``dist``."""

    hit: np.ndarray
    c: np.ndarray
    J: np.ndarray
    P: np.ndarray
    frame: np.ndarray
    eye: np.ndarray
    light: np.ndarray
    dist: float

    def take(self, rows) -> "Geometry":
        """The pixel rows *rows* only (what one task needs)."""
        r = np.asarray(list(rows))
        return Geometry(self.hit[r], self.c[r], self.J[r], self.P[r], np.asarray(self.frame[r]), self.eye,
                        self.light, self.dist)


def _camera(eye, target):
    """(forward, right, up) unit vectors of a camera at *eye* looking at *target* (z up)."""
    fwd = (target - eye) / np.linalg.norm(target - eye)
    up0 = np.array([0.0, 0.0, 1.0]) if abs(fwd[2]) < 0.999 else np.array([0.0, 1.0, 0.0])
    right = np.cross(fwd, up0)
    right /= np.linalg.norm(right)
    return fwd, right, np.cross(right, fwd)


def _pixel_rays(s: GlintSettings, fwd, right, up, half):
    """Ray directions (unnormalized) through pixel positions: d(px, py) for arrays of pixel coordinates."""
    def ray(px, py):
        x = ((px + 0.5) / s.size * 2 - 1) * half
        y = (1 - (py + 0.5) / s.size * 2) * half
        return fwd + x[..., None] * right + y[..., None] * up
    return ray


def _pixels(s: GlintSettings):
    py, px = np.meshgrid(np.arange(s.size, dtype=float), np.arange(s.size, dtype=float), indexing="ij")
    return px, py


def _jacobian(tex, px, py):
    """d(texture)/d(pixel) by central differences of *tex*(px, py) → (..., 2), as (..., 2, 2)."""
    return np.stack([tex(px + 0.5, py) - tex(px - 0.5, py), tex(px, py + 0.5) - tex(px, py - 0.5)], axis=-1)


def _plane_geometry(field, s: GlintSettings) -> Geometry:
    eye, c, J, dist = camera_rays(field, s)
    ny, nx = field.shape
    light = np.array([nx * field.dx / 2, ny * field.dy / 2, 0.0]) + dist * _dir(s.light_deg, s.light_azimuth_deg)
    frame = np.broadcast_to(np.eye(3), c.shape[:2] + (3, 3))
    return Geometry(np.ones(c.shape[:2], bool), c[..., :2], J, c, frame, eye, light, dist)


def _sphere_geometry(field, s: GlintSettings) -> Geometry:
    ny, nx = field.shape
    W, H = nx * field.dx, ny * field.dy
    R = 0.9 * min(W, H) / math.pi
    dist = 4.0 * R
    eye = dist * _dir(s.view_deg, s.view_azimuth_deg)
    light = dist * _dir(s.light_deg, s.light_azimuth_deg)
    fwd, right, up = _camera(eye, np.zeros(3))
    half = 1.05 * R / math.sqrt(dist * dist - R * R)      # the sphere's silhouette fills the image
    ray = _pixel_rays(s, fwd, right, up, half)
    back = -fwd

    def point(px, py):
        """Hit point on the sphere (nan where the ray misses): the nearer root of |eye + t d|² = R²."""
        d = ray(px, py)
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
        b = d @ eye
        disc = b * b - (eye @ eye - R * R)
        t = -b - np.sqrt(np.where(disc >= 0, disc, np.nan))
        return eye + t[..., None] * d

    def lon_lat(P):
        q = P / R
        return np.arctan2(q @ right, q @ back), np.arcsin(np.clip(q @ up, -1.0, 1.0))

    def tex(px, py):
        g, b = lon_lat(point(px, py))
        return np.stack([W / 2 + R * g, H / 2 + R * b], axis=-1)

    px, py = _pixels(s)
    P = point(px, py)
    g, b = lon_lat(P)
    hit = np.isfinite(P[..., 0])
    J = _jacobian(tex, px, py)
    hit &= np.all(np.isfinite(J), axis=(-1, -2))
    t = np.cos(g)[..., None] * right - np.sin(g)[..., None] * back                       # ∂P/∂γ, normalized
    n = np.where(hit[..., None], P / R, 0.0)
    bt = np.cross(n, t)                                                                  # ∂P/∂β, normalized
    frame = np.stack([t, bt, n], axis=-2)
    c = np.stack([W / 2 + R * g, H / 2 + R * b], axis=-1)
    return Geometry(hit, np.nan_to_num(c), np.nan_to_num(J), np.nan_to_num(P), frame, eye, light, dist)


#: what a glint render's height field textures, by name (``shape=``; ``render --glints --shape``)
SHAPES = {"plane": _plane_geometry, "sphere": _sphere_geometry}
assert tuple(SHAPES) == GLINT_SHAPES   # the command line's choices (kept import-light in waveoptics.vocabulary)


def geometry(field, s: GlintSettings) -> Geometry:
    """The per-pixel :class:`Geometry` of settings *s* over *field* (:data:`SHAPES`)."""
    return SHAPES[s.shape](field, s)


def footprints(geo: Geometry, filter_px: float):
    """Footprints of every pixel at once: (σ_1, σ_2, angle in degrees) (size, size) each, the principal axes of
    Σ = J diag(s², s²) Jᵀ (σ_1 the larger)."""
    C = (filter_px ** 2) * (geo.J @ np.swapaxes(geo.J, -1, -2))
    vals, vecs = np.linalg.eigh(C)
    angle = np.degrees(np.arctan2(vecs[..., 1, 1], vecs[..., 0, 1]))
    return np.sqrt(np.maximum(vals[..., 1], 0.0)), np.sqrt(np.maximum(vals[..., 0], 1e-30)), angle


def _local_directions(geo: Geometry, r, i, s: GlintSettings):
    """The light's directions ω_i (m, 3) over its cone (:func:`waveoptics.renderers.light_cone.cone_directions`;
    one for a point light) and their weights (m,), ω_o (3,) in the shading frame of pixel (r, i), and the falloff
    d²/|light − P|²."""
    p = geo.P[r, i]
    a, b = geo.light - p, geo.eye - p
    r2 = float(a @ a)
    d, w = cone_directions(a / math.sqrt(r2), math.radians(s.light_radius_deg), s.light_rings)
    return d[0] @ geo.frame[r, i].T, w, geo.frame[r, i] @ (b / np.linalg.norm(b)), geo.dist ** 2 / r2


def _render_rows(field, material, s: GlintSettings, geo: Geometry, rows, only: int | None = None) -> dict:
    """Render the pixel rows *rows* (a range) whose geometry is *geo* (:meth:`Geometry.take` of those rows): the
    BRDFs of both models per pixel averaged over the light's cone (:func:`waveoptics.scatter.pixel_brdf`, one
    batch for the task: every direction of the cone is one footprint query), their radiance factors
    Σ_k w_k f_k cos θ_k d²/r², the mask of pixels shown, the footprints and the time of reading the field and of
    the sums (one task of :func:`render_glints`; *only*: that pixel column alone)."""
    lam = np.asarray(s.wavelengths_nm, dtype=float)
    n, m = s.size, len(rows)
    out = {"rows": rows, "E": np.zeros((m, n)), "on": np.zeros((m, n), bool), "fp": np.zeros((m, n, 5)),
           "dirs": np.zeros((m, n, 6)), "t_read": 0.0, "t_sums": 0.0, "samples": 0, "queries": 0}
    for key in ("wave", "geo", "wave_rad", "geo_rad"):
        out[key] = np.zeros((m, n, lam.size))
    s1, s2, ang = footprints(geo, s.filter_px)
    nodes, fps, wis, wos = [], [], [], []
    for r in range(m):
        for i in range(n) if only is None else (only,):
            if not geo.hit[r, i]:
                continue
            wi, w, wo, fall = _local_directions(geo, r, i, s)
            fp = Footprint(float(geo.c[r, i, 0]), float(geo.c[r, i, 1]), float(s1[r, i]), float(s2[r, i]),
                           float(ang[r, i]))
            out["fp"][r, i] = (fp.x, fp.y, fp.sigma, fp.sigma_y, fp.angle_deg)
            centre = geo.frame[r, i] @ (geo.light - geo.P[r, i])
            out["dirs"][r, i] = np.concatenate([centre / np.linalg.norm(centre), wo])
            up = wi[:, 2] > 0                   # directions of the light below this point's horizon add nothing
            out["on"][r, i] = True
            if wo[2] <= 0 or not up.any():      # the light or the camera is below this point's horizon
                continue
            out["E"][r, i] = float(w[up] @ wi[up, 2]) * fall       # the cone's irradiance factor
            for k in np.flatnonzero(up):
                nodes.append((r, i, w[k], w[k] * wi[k, 2] * fall))
                fps.append(fp)
                wis.append(wi[k])
                wos.append(wo)
    if nodes:
        res = pixel_brdf(field, fps, np.array(wis), np.array(wos), lam, material, slope_sigma=s.intrinsic_slope,
                         coherence_m=s.coherence_m, backend=s.backend, precision=s.precision)
        for k, (r, i, w, wl) in enumerate(nodes):
            if res.ok[k]:
                out["wave"][r, i] += w * res.wave[k]
                out["geo"][r, i] += w * res.geometric[k]
                out["wave_rad"][r, i] += wl * res.wave[k]
                out["geo_rad"][r, i] += wl * res.geometric[k]
            else:                               # the footprint's box leaves the field: the pixel stays black
                out["on"][r, i] = False
        out["t_read"], out["t_sums"], out["samples"] = res.timings_s["read"], res.timings_s["sums"], res.samples
        out["queries"] = len(nodes)
    return out


#: pixel rows per task (a task of a 256² render is 1024 pixels, about 0.2-2 s)
ROWS_PER_TASK = 8


def render_glints(field, material, settings: GlintSettings = GlintSettings(), *, progress=None,
                  executor=None) -> GlintRender:
    """Render *field* (HeightField, memory-mapped LargeHeightField or any tiled field of
    :mod:`waveoptics.surfaces.tiled`) of *material* as described in the module doc; pixels whose footprint box
    leaves the field stay black (``on_field`` False).

    Parameters
    ----------
    progress : callable, optional
        Called with the number of pixel rows done after each task.
    executor : concurrent.futures.Executor, optional
        Runs the row tasks (``executor.map``), e.g. a Dask client's ``get_executor()``; default: in turn here.
    """
    get_material(material)
    lam = np.asarray(settings.wavelengths_nm, dtype=float)
    M = colour.reflectance_to_rgb_matrix(lam)
    geo = geometry(field, settings)
    n = settings.size
    f_wave, f_geo = np.zeros((n, n, len(lam))), np.zeros((n, n, len(lam)))
    wave, geo_img = np.zeros((n, n, len(lam))), np.zeros((n, n, len(lam)))
    E, on = np.zeros((n, n)), np.zeros((n, n), bool)
    fps, dirs = np.zeros((n, n, 5)), np.zeros((n, n, 6))
    t_read = t_sums = 0.0
    samples = queries = 0
    tasks = [range(j, min(j + ROWS_PER_TASK, n)) for j in range(0, n, ROWS_PER_TASK)]
    t_start, cpu_start = time.perf_counter(), time.process_time()
    parts = [geo.take(rows) for rows in tasks]
    if executor is None:
        results = (_render_rows(field, material, settings, g, rows) for g, rows in zip(parts, tasks))
    else:
        results = executor.map(_render_rows, [field] * len(tasks), [material] * len(tasks),
                               [settings] * len(tasks), parts, tasks)
    for res in results:
        rows = list(res["rows"])
        f_wave[rows], f_geo[rows], E[rows], on[rows] = res["wave"], res["geo"], res["E"], res["on"]
        wave[rows], geo_img[rows] = res["wave_rad"], res["geo_rad"]
        fps[rows], dirs[rows] = res["fp"], res["dirs"]
        t_read += res["t_read"]
        t_sums += res["t_sums"]
        samples += res["samples"]
        queries += res["queries"]
        if progress is not None:
            progress(len(rows))
    wall, cpu = time.perf_counter() - t_start, time.process_time() - cpu_start
    lit = on & (E > 0)
    if not lit.any():
        raise FieldError("no pixel's footprint lies inside the height field; use a larger field or image",
                         "surface")
    n_px = int(lit.sum())
    return GlintRender(wave=wave @ M, geometric=geo_img @ M, on_field=on,
                       timings_s={"read": t_read, "sums": t_sums, "pixels": n_px, "wall": wall, "cpu": cpu,
                                  "per_pixel": wall / n_px, "sums_per_pixel": t_sums / n_px,
                                  "footprints_per_s": queries / max(t_sums, 1e-12), "samples": samples,
                                  "footprints": queries},
                       footprint_sigma_m=(float(np.median(fps[lit][:, 2])), float(np.median(fps[lit][:, 3]))),
                       wave_spectral=wave, geometric_spectral=geo_img, wave_brdf=f_wave, geometric_brdf=f_geo,
                       footprints=fps, directions=dirs)


@dataclass
class GlintEstimate:
    """What a glint render will cost, before it starts: pixels on the surface, the median footprint (m), the
    samples its sums visit, the per-pixel time measured on a probe of pixels and the extrapolated wall time (s)."""

    pixels: int
    footprint_sigma_m: tuple
    samples: int
    probe_pixels: int
    per_pixel_s: float
    estimate_s: float

    def describe(self) -> str:
        return (f"{self.pixels} pixels, footprint σ ≈ {self.footprint_sigma_m[0] * 1e6:.3g} × "
                f"{self.footprint_sigma_m[1] * 1e6:.3g} µm, {self.samples / max(self.pixels, 1):.3g} samples/pixel; "
                f"probe of {self.probe_pixels} pixels: {self.per_pixel_s * 1e3:.3g} ms/pixel → about "
                f"{self.estimate_s:.0f} s")


def estimate_glints(field, material, settings: GlintSettings = GlintSettings(), *, probe_tasks: int = 2
                    ) -> GlintEstimate:
    """Estimate :func:`render_glints`'s cost before it starts: the footprint of every pixel (cheap), the samples
    of their boxes, and the time of *probe_tasks* whole row tasks (the same code, after one pixel that builds the
    kernel and pays the first-call costs) spread over the rows that meet the surface; the estimate is that time per sample times all
    samples (the field's reading scales with the same footprints)."""
    geo = geometry(field, settings)
    s1, s2, _ = footprints(geo, settings.filter_px)
    hit = geo.hit
    n_px = int(hit.sum())
    if n_px == 0:
        raise FieldError("no pixel of this view meets the surface", "surface")
    box = math.pi * SUM_N_SIGMA ** 2 * s1 * s2 / (field.dx * field.dy)    # samples of each ellipse (those summed)
    total = float(np.sum(box[hit]))
    # one pixel outside the clock: builds the kernel and pays every first-call cost (imports, material tables)
    j, i = np.argwhere(hit)[int(n_px // 2)]
    _render_rows(field, material, settings, geo.take([j]), range(j, j + 1), only=int(i))
    n = settings.size
    starts = [j for j in range(0, n, ROWS_PER_TASK) if hit[j:j + ROWS_PER_TASK].any()]
    pick = sorted({starts[int(k)] for k in np.linspace(0, len(starts) - 1, probe_tasks + 2)[1:-1].round()})
    t0 = time.perf_counter()
    probe_px = 0
    for j in pick:
        rows = range(j, min(j + ROWS_PER_TASK, n))
        probe_px += int(np.sum(_render_rows(field, material, settings, geo.take(rows), rows)["on"]))
    t = time.perf_counter() - t0
    probe_samples = float(sum(np.sum(box[j:j + ROWS_PER_TASK][hit[j:j + ROWS_PER_TASK]]) for j in pick))
    return GlintEstimate(n_px, (float(np.median(s1[hit])), float(np.median(s2[hit]))), int(total), probe_px,
                         t / max(probe_px, 1), t / max(probe_samples, 1.0) * total)
