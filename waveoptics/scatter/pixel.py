"""Per-pixel footprint BRDFs: the wave (Kirchhoff) and geometric (patch NDF) BRDF of a Gaussian footprint at the
one direction pair (ω_i, ω_o) a pixel of a point-light render needs, per wavelength, for many pixels at once.

For a footprint G (:class:`waveoptics.surfaces.Footprint`) truncated to its ellipse of :data:`SUM_N_SIGMA` = 3√2
widths, (x − c)ᵀ Σ⁻¹ (x − c) ≤ 18 (:data:`Q_MAX`; G ≥ e⁻⁹: the window keeps all but e⁻⁹ = 1.23e-4 of its mass, as
the ±4σ box of :func:`waveoptics.surfaces.footprint_box` keeps all but 1.27e-4 of a round one's, on ~12 % fewer
samples, and far fewer for an oblique ellipse, whose box is much larger than it; the box of that radius is what is
read), and s = ω_i + ω_o in the surface's frame:

* wave optics (the windowed Kirchhoff integral, Beckmann & Spizzichino 1963 ch. 3; Yan et al. 2018 eq. 6):
  f = F(θ_d) K |U|² / (Σ_j G_j² ΔxΔy),  U = ΔxΔy Σ_j G_j e^{i k s·(x_j − c, h_j)},  K = |s|⁴ / (4 λ² cos θ_i cos θ_o
  (cos θ_i + cos θ_o)²) — the form of :func:`waveoptics.renderers.glints` and :mod:`waveoptics.scatter.footprint`;
  with a coherence width σ_c smaller than the footprint (Yan et al. 2018 §4) f = Σ_k w_k f_k over Gaussian
  windows of width σ_c centred on the lattice of :func:`waveoptics.scatter.coherence_centres`, w_k = G(c_k)
  normalized;
* geometric optics (Yan et al. 2016's patch NDF with intrinsic roughness σ_s): D(h) = P22(t)/cos⁴θ_h with
  P22(t) = Σ_j G_j N(∇h_j − t; σ_s²) / Σ_j G_j, t = (−h_x/h_z, −h_y/h_z) the half vector's slope, ∇h by central
  differences, or the field's own slopes where it gives them (``region_slopes``, e.g.
  :class:`waveoptics.surfaces.tiled.FlakeField`, or a file stored with a label map and plane slopes,
  :mod:`waveoptics.surfaces.regions`: each flake's plane, where a difference across the step between two flakes
  would count a facet that is not there) (Heitz 2014 for D from P22), f = F(θ_d) D / (4 cos θ_i
  cos θ_o), no shadowing.

The sums run in one OpenCL kernel (``kernels/footprint.cl``, ``footprint_sums``; twin :func:`footprint_sums_numpy`)
over regions of the field that each hold the boxes of many footprints: :func:`pixel_brdf` sorts the footprints,
reads one region per group (at most :data:`MAX_REGION_SAMPLES` samples, plus a margin of one sample for the
central differences) and never holds more of the field.

References
----------
.. [1] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 75, 2018.
.. [2] L.-Q. Yan, M. Hašan, S. Marschner, R. Ramamoorthi, "Position-normal distributions for efficient rendering of
   specular microstructure", ACM TOG 35(4), 56, 2016.
.. [3] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, 1963, ch. 3.
.. [4] E. Heitz, "Understanding the masking-shadowing function in microfacet-based BRDFs", JCGT 3(2), 2014.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..errors import FieldError
from ..materials import get_material
from ..surfaces.footprint import Footprint, footprint_box
from ..surfaces.heightfield import HeightField
from .footprint import coherence_centres

__all__ = ["SUM_N_SIGMA", "Q_MAX", "PIXEL_BACKENDS", "MAX_REGION_SAMPLES", "PixelBRDF", "footprint_sums",
           "footprint_sums_numpy", "ellipse_samples", "pixel_brdf", "footprint_brdf"]

#: the footprint's truncation radius in widths (module doc): G ≥ e⁻⁹ on the ellipse
SUM_N_SIGMA = 3 * math.sqrt(2)
#: samples with (x − c)ᵀ Σ⁻¹ (x − c) ≤ Q_MAX count: SUM_N_SIGMA² = 18 and a margin of 1e-9 so that a sample on the
#: ellipse itself (a lattice point there, e.g. (3, 3) widths from a centre on the grid) counts whatever the rounding
#: of q (float64: 1e-15; the q of lattice samples about a round footprint differ by at least (Δx/σ)², 1e-5 at
#: σ = 30 µm on a 0.1 µm grid)
Q_MAX = 18 * (1 + 1e-9)
#: evaluators of the footprint sums
PIXEL_BACKENDS = ("opencl", "numpy")
#: largest region (samples) read at once: 8 M samples, 64 MB in float64
MAX_REGION_SAMPLES = 2 ** 23
#: work-items the OpenCL launch aims for (a footprint's rows are split into chunks to reach it)
_TARGET_ITEMS = 64
_GEO = 12
#: samples per SIMD step of the kernel's rows
_VW = 8


@dataclass
class PixelBRDF:
    """BRDFs (1/sr) of n footprints at their direction pairs: ``wave`` and ``geometric`` (n, n_λ), ``ok`` (n,) False
    where a footprint's box leaves the field (both NaN there), ``samples`` the samples summed (all windows),
    ``timings_s`` the time (s) of reading the field (``read``) and of the sums (``sums``)."""

    wave: np.ndarray
    geometric: np.ndarray
    ok: np.ndarray
    samples: int
    timings_s: dict


def _geometry(fp: Footprint, box, s, t, dx, dy) -> np.ndarray:
    """The kernel's 12 per-footprint numbers (``kernels/footprint.cl``): centre from the box origin, Σ⁻¹, s, t and
    the truncation :data:`Q_MAX`."""
    Ci = np.linalg.inv(fp.covariance)
    return np.array([fp.x - box[0] * dx, fp.y - box[1] * dy, Ci[0, 0], Ci[0, 1], Ci[1, 1],
                     s[0], s[1], s[2], t[0], t[1], Q_MAX, 0.0])


def footprint_sums_numpy(h, dx, dy, box, geo, wavelengths_nm, slope_sigma, slopes=None) -> np.ndarray:
    """NumPy twin (float64, np.sin/np.cos) of the ``footprint_sums`` kernel.

    Parameters
    ----------
    h : ndarray (ny, nx), m
        Region heights; every box lies at least one sample inside it.
    dx, dy : float, m
    box : ndarray of int (n, 4)
        (i0, j0, i1, j1) of each footprint in region samples.
    geo : ndarray (n, 12)
        As the kernel (module ``kernels/footprint.cl``).
    wavelengths_nm : array (n_λ,), nm
    slope_sigma : float
        Intrinsic slope σ_s.
    slopes : tuple of ndarray (ny, nx), optional
        (∂h/∂x, ∂h/∂y) of every region sample; None: central differences of *h*.

    Returns
    -------
    ndarray (n, 2 n_λ + 3)
        Re U_l, Im U_l (without ΔxΔy), Σ G², Σ G, Σ G N-kernel (unnormalized).
    """
    inv_lam = 1.0 / (np.asarray(wavelengths_nm, dtype=float) * 1e-9)
    nl = inv_lam.size
    out = np.zeros((len(box), 2 * nl + 3))
    for p, ((i0, j0, i1, j1), g) in enumerate(zip(np.asarray(box), np.asarray(geo))):
        rx = np.arange(i1 - i0) * dx - g[0]
        ry = (np.arange(j1 - j0) * dy - g[1])[:, None]
        q = g[2] * rx * rx + 2 * g[3] * rx * ry + g[4] * ry * ry
        G = np.where(q <= g[10], np.exp(-0.5 * q), 0.0)          # truncated to the ellipse q <= q_max
        hp = h[j0:j1, i0:i1]
        if slopes is None:
            gx = (h[j0:j1, i0 + 1:i1 + 1] - h[j0:j1, i0 - 1:i1 - 1]) / (2 * dx) - g[8]
            gy = (h[j0 + 1:j1 + 1, i0:i1] - h[j0 - 1:j1 - 1, i0:i1]) / (2 * dy) - g[9]
        else:
            gx, gy = slopes[0][j0:j1, i0:i1] - g[8], slopes[1][j0:j1, i0:i1] - g[9]
        base = g[5] * rx + g[6] * ry + g[7] * hp
        for l, il in enumerate(inv_lam):
            ph = 2 * np.pi * base * il
            out[p, 2 * l] = np.sum(G * np.cos(ph))
            out[p, 2 * l + 1] = np.sum(G * np.sin(ph))
        out[p, 2 * nl] = np.sum(G * G)
        out[p, 2 * nl + 1] = np.sum(G)
        out[p, 2 * nl + 2] = np.sum(G * np.exp(-0.5 * (gx * gx + gy * gy) / slope_sigma ** 2))
    return out


def footprint_sums(h, dx, dy, box, geo, wavelengths_nm, slope_sigma, *, slopes=None, backend: str = "opencl",
                   precision: str | None = None, runtime=None) -> np.ndarray:
    """The footprint sums of :func:`footprint_sums_numpy` by *backend* (``opencl``: ``kernels/footprint.cl`` in
    *precision*, default float64 where the device has it, else float32); *slopes* as there."""
    if backend == "numpy":
        return footprint_sums_numpy(h, dx, dy, box, geo, wavelengths_nm, slope_sigma, slopes)
    if backend != "opencl":
        raise FieldError(f"footprint backend {backend!r} is not known; one of {', '.join(PIXEL_BACKENDS)}",
                         "backend")
    import pyopencl as cl
    import pyopencl.array as cla

    from ..runtime import build_options, build_program, get_runtime
    from .direct import default_local_size, sincos_options

    rt = runtime if runtime is not None else get_runtime()
    precision = precision or ("float64" if rt.fp64 else "float32")
    dt = rt.real_dtype(precision)
    nl = len(wavelengths_nm)
    pname = "float64" if dt == np.float64 else "float32"
    given = ("-DWO_GIVEN_SLOPES",) if slopes is not None else ()
    prg = build_program(rt, "footprint.cl", build_options(dt, (f"-DWO_NL={nl}", f"-DWO_VW={_VW}") + given
                                                          + sincos_options(pname)))
    box = np.ascontiguousarray(box, dtype=np.int32)
    n = len(box)
    rows = int(np.max(box[:, 3] - box[:, 1]))
    n_chunks = max(1, min(rows, -(-_TARGET_ITEMS // n)))
    q = rt.queue
    h = np.pad(np.asarray(h, dtype=dt), ((0, 0), (0, _VW)))       # vector reads past a box stay in the row
    d_h = cla.to_device(q, np.ascontiguousarray(h))
    if slopes is None:
        d_hx = d_hy = d_h                                       # not read without WO_GIVEN_SLOPES
    else:
        d_hx, d_hy = (cla.to_device(q, np.ascontiguousarray(np.pad(np.asarray(g, dtype=dt), ((0, 0), (0, _VW)))))
                      for g in slopes)
    d_box = cla.to_device(q, box)
    d_geo = cla.to_device(q, np.ascontiguousarray(geo, dtype=dt))
    d_lam = cla.to_device(q, (1.0 / (np.asarray(wavelengths_nm, dtype=float) * 1e-9)).astype(dt))
    d_out = cla.empty(q, n * n_chunks * (2 * nl + 3), dt)
    lsz = default_local_size(rt)
    cl.Kernel(prg, "footprint_sums")(q, (n * n_chunks,), None if lsz is None else (lsz,), d_h.data, d_hx.data, d_hy.data, np.int32(h.shape[1]), dt(dx), dt(dy),
                                     d_box.data, d_geo.data, d_lam.data, dt(1.0 / slope_sigma ** 2), np.int32(n),
                                     np.int32(n_chunks), d_out.data)
    return d_out.get().astype(np.float64).reshape(n, n_chunks, 2 * nl + 3).sum(axis=1)


def _groups(boxes, max_samples):
    """Indices of footprints in groups whose union box holds at most *max_samples*, and at most 4 times the
    samples of its boxes once past 2¹⁶ (scattered footprints do not read the field between them): sorted by x,
    then greedy."""
    order = np.lexsort((boxes[:, 1], boxes[:, 0]))
    groups, cur, u, covered = [], [], None, 0
    for k in order:
        b = boxes[k]
        area = int((b[2] - b[0] + 2) * (b[3] - b[1] + 2))
        nu = b.copy() if u is None else np.array([min(u[0], b[0]), min(u[1], b[1]), max(u[2], b[2]),
                                                  max(u[3], b[3])])
        union = int((nu[2] - nu[0] + 2) * (nu[3] - nu[1] + 2))
        if cur and (union > max_samples or (union > 2 ** 16 and union > 4 * (covered + area))):
            groups.append(cur)
            cur, nu, covered = [], b.copy(), 0
        cur.append(k)
        u = nu
        covered += area
    if cur:
        groups.append(cur)
    return groups


def _items(fps, coherence_m):
    """Per footprint item: (pixel index, weight, wave?, geometric?, footprint); coherence windows are wave-only."""
    items = []
    for p, fp in enumerate(fps):
        coherent = coherence_m is None or coherence_m >= max(fp.sigma, fp.sigma_y or fp.sigma)
        items.append((p, 1.0, coherent, True, fp))
        if not coherent:
            centres, w = coherence_centres(fp, coherence_m)
            items += [(p, float(wk), True, False, Footprint(float(cx), float(cy), float(coherence_m)))
                      for (cx, cy), wk in zip(centres, w)]
    return items


def pixel_brdf(field, footprints, wi, wo, wavelengths_nm, material=None, *, slope_sigma: float = 0.01,
               coherence_m: float | None = None, backend: str = "opencl", precision: str | None = None,
               max_region_samples: int = MAX_REGION_SAMPLES, runtime=None) -> PixelBRDF:
    """Wave and geometric BRDFs of *footprints* on *field* at their direction pairs (module doc).

    Parameters
    ----------
    field : HeightField, LargeHeightField or a tiled field (:mod:`waveoptics.surfaces.tiled`)
    footprints : sequence of Footprint (n)
    wi, wo : array (n, 3) or (3,)
        Unit directions towards the light and the camera in each footprint's surface frame (z up).
    wavelengths_nm : array (n_λ,), nm
    material : str, optional
        Fresnel factor F(θ_d) of this material; None: F = 1.
    slope_sigma : float
        Intrinsic slope σ_s of the geometric NDF (per axis).
    coherence_m : float, m, optional
        Coherence width σ_c (module doc); None: the whole footprint is coherent.
    backend, precision
        As :func:`footprint_sums`.
    """
    lam = np.asarray(wavelengths_nm, dtype=float)
    n = len(footprints)
    wi = np.broadcast_to(np.asarray(wi, dtype=float), (n, 3))
    wo = np.broadcast_to(np.asarray(wo, dtype=float), (n, 3))
    if not (slope_sigma > 0):
        raise FieldError(f"slope_sigma={slope_sigma!r} is not allowed; it must be > 0", "slope_sigma")
    if np.any(wi[:, 2] <= 0) or np.any(wo[:, 2] <= 0):
        raise FieldError("every ω_i and ω_o must lie above the surface (z > 0)", "directions")
    items = _items(footprints, coherence_m)
    ny, nx = field.shape
    boxes = np.array([footprint_box(it[4], field.dx, field.dy, SUM_N_SIGMA) for it in items],
                     dtype=np.int64).reshape(-1, 4)
    inside = (boxes[:, 0] >= 1) & (boxes[:, 1] >= 1) & (boxes[:, 2] <= nx - 1) & (boxes[:, 3] <= ny - 1)
    ok = np.ones(n, bool)
    for (p, *_), good in zip(items, inside):
        ok[p] &= bool(good)
    sums = np.full((len(items), 2 * lam.size + 3), np.nan)
    use = np.flatnonzero(inside & ok[[it[0] for it in items]])
    s_all, t_all = _half_vectors(wi, wo)
    t_read = t_sums = 0.0
    for grp in _groups(boxes[use], max_region_samples):
        idx = use[grp]
        b = boxes[idx]
        ri0, rj0 = int(b[:, 0].min()) - 1, int(b[:, 1].min()) - 1
        t0 = time.perf_counter()
        region, slopes = _region(field, ri0, rj0, int(b[:, 2].max()) + 1, int(b[:, 3].max()) + 1)
        t1 = time.perf_counter()
        t_read += t1 - t0
        geo = np.array([_geometry(items[k][4], boxes[k], s_all[items[k][0]], t_all[items[k][0]],
                                  field.dx, field.dy) for k in idx])
        sums[idx] = footprint_sums(region, field.dx, field.dy, b - [ri0, rj0, ri0, rj0], geo, lam, slope_sigma,
                                   slopes=slopes, backend=backend, precision=precision, runtime=runtime)
        t_sums += time.perf_counter() - t1
    wave, geometric = _finish(sums, items, n, wi, wo, lam, material, slope_sigma, field.dx * field.dy)
    wave[~ok], geometric[~ok] = np.nan, np.nan
    samples = int(np.sum(ellipse_samples([items[k][4] for k in use], field.dx, field.dy)))
    return PixelBRDF(wave, geometric, ok, samples, {"read": t_read, "sums": t_sums})


def ellipse_samples(footprints, dx: float, dy: float) -> np.ndarray:
    """The samples of each footprint's truncated ellipse (q ≤ :data:`Q_MAX`, what the sums add) on a grid of spacing
    *dx*, *dy* (m) whose first sample is at the origin, counted row by row from the ellipse's chords."""
    n = len(footprints)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    box = np.array([footprint_box(fp, dx, dy, SUM_N_SIGMA) for fp in footprints], dtype=np.int64)
    Ci = np.linalg.inv(np.array([fp.covariance for fp in footprints]))
    a, b, c = Ci[:, 0, 0, None], Ci[:, 0, 1, None], Ci[:, 1, 1, None]
    x, y = (np.array([[fp.x, fp.y] for fp in footprints]).T)[:, :, None]
    j = box[:, 1, None] + np.arange(int(np.max(box[:, 3] - box[:, 1])))[None, :]
    ry = j * dy - y
    d = (b * b - a * c) * ry * ry + a * Q_MAX
    ok = (d >= 0) & (j < box[:, 3, None])
    sq = np.sqrt(np.where(ok, d, 0.0))
    lo = np.maximum(np.ceil(((-b * ry - sq) / a + x) / dx), box[:, 0, None])
    hi = np.minimum(np.floor(((-b * ry + sq) / a + x) / dx), box[:, 2, None] - 1)
    return np.sum(np.where(ok, np.maximum(hi - lo + 1, 0), 0), axis=1).astype(np.int64)


def _region(field, i0, j0, i1, j1):
    """(heights (m), slopes) of samples [j0:j1, i0:i1] of a HeightField or of any field with ``region``; slopes
    are (∂h/∂x, ∂h/∂y) where the field gives them (``gives_slopes``, ``region_slopes``), else None (central
    differences)."""
    if isinstance(field, HeightField):
        return field.heights[j0:j1, i0:i1], None
    if getattr(field, "gives_slopes", False):
        h, hx, hy = field.region_slopes(i0, j0, i1, j1)
        return h, (hx, hy)
    if hasattr(field, "region_heights"):
        return field.region_heights(i0, j0, i1, j1), None
    return field.region(i0, j0, i1, j1).heights, None


def _half_vectors(wi, wo):
    s = wi + wo
    hv = s / np.linalg.norm(s, axis=1, keepdims=True)
    return s, np.column_stack([-hv[:, 0] / hv[:, 2], -hv[:, 1] / hv[:, 2]])


def _finish(sums, items, n, wi, wo, lam_nm, material, slope_sigma, dA):
    """BRDFs (n, n_λ) from the sums of every item (module doc)."""
    nl = lam_nm.size
    lam = lam_nm * 1e-9
    s = wi + wo
    ci, co = wi[:, 2], wo[:, 2]
    hv = s / np.linalg.norm(s, axis=1, keepdims=True)
    cos_d = np.clip(np.sum(wi * hv, axis=1), 0.0, 1.0)      # clamp cos θ_d to [0, 1] before Fresnel
    F = np.ones((n, nl)) if material is None else get_material(material).F(cos_d[:, None], lam_nm[None, :])
    K = (np.sum(s * s, axis=1) ** 2 / (4 * ci * co * (ci + co) ** 2))[:, None] / lam[None, :] ** 2
    wave, geometric = np.zeros((n, nl)), np.zeros((n, nl))
    for k, (p, w, is_wave, is_geo, _) in enumerate(items):
        S = sums[k]
        if is_wave:
            U2 = (S[0:2 * nl:2] ** 2 + S[1:2 * nl:2] ** 2) * dA * dA
            wave[p] += w * F[p] * K[p] * U2 / (S[2 * nl] * dA)
        if is_geo:
            P22 = S[2 * nl + 2] / (S[2 * nl + 1] * 2 * math.pi * slope_sigma ** 2)
            geometric[p] = F[p] * P22 / hv[p, 2] ** 4 / (4 * ci[p] * co[p])
    return wave, geometric


def footprint_brdf(field, fp: Footprint, wi, wo, wavelengths_nm, material=None, **kw) -> tuple[np.ndarray,
                                                                                                np.ndarray]:
    """(wave, geometric) BRDFs (n_λ,) in 1/sr of one footprint at one direction pair (:func:`pixel_brdf`).

    Raises
    ------
    FieldError
        When the footprint's box (and a margin of one sample) leaves the field.
    """
    r = pixel_brdf(field, [fp], np.asarray(wi, float)[None], np.asarray(wo, float)[None], wavelengths_nm, material,
                   **kw)
    if not r.ok[0]:
        raise FieldError(f"footprint at ({fp.x * 1e6:.6g}, {fp.y * 1e6:.6g}) um with its box leaves the field",
                         "footprint")
    return r.wave[0], r.geometric[0]
