"""The wave-optics BRDF of one pixel footprint on a large height field (Yan et al. 2018).

The footprint's Gaussian G (:class:`waveoptics.surfaces.Footprint`) is the window of the Kirchhoff integral over
its local patch (docs/physics.md §1):

    f(ω_i, ω_o) = F K / (λ² A_w) · |Σ_j G_j e^{i v·r_j} Δx Δy|²,   A_w = Σ_j G_j² Δx Δy,

computed by :func:`waveoptics.scatter.scatter` on the patch with the weights G (fft or direct solver, any
diffraction model). The cost is that of the patch (about (8σ/Δx)² samples), not of the field.

A **coherence area** smaller than the footprint (Yan et al. 2018, §4: light of limited spatial coherence adds the
intensities of regions farther apart than its coherence length) gives the incoherent sum

    f = Σ_k G(c_k) f_k / Σ_k G(c_k),

of the windowed Kirchhoff BRDFs f_k of Gaussian coherence windows of width σ_c centred at c_k, on a square lattice
of spacing σ_c that covers the footprint out to two widths.

References
----------
.. [1] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 75, 2018 (Gaussian footprints and coherence areas as diffraction windows).
.. [2] P. Beckmann, A. Spizzichino, 1963, ch. 3 (the Kirchhoff integral).
"""
from __future__ import annotations

import numpy as np

from ..errors import FieldError
from ..surfaces.footprint import Footprint, footprint_patch
from .solvers import scatter

__all__ = ["footprint_scatter", "coherence_centres", "incoherent_sum"]


def coherence_centres(fp: Footprint, coherence_m: float, reach: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Centres (n, 2) in m of the coherence windows of width *coherence_m* covering footprint *fp* out to *reach*
    widths, and their weights G(c_k) normalized to sum 1."""
    if not (np.isfinite(coherence_m) and coherence_m > 0):
        raise FieldError(f"coherence width {coherence_m!r} m is not allowed; it must be > 0", "coherence")
    hx, hy = fp.half_extent(reach)
    nx, ny = int(np.floor(hx / coherence_m)), int(np.floor(hy / coherence_m))
    if nx * ny > 4096:
        raise FieldError(f"coherence width {coherence_m * 1e9:.4g} nm asks for {(2 * nx + 1) * (2 * ny + 1)} "
                         "windows over this footprint; give at most 4096 (a wider coherence area)", "coherence")
    gx, gy = np.meshgrid(fp.x + coherence_m * np.arange(-nx, nx + 1), fp.y + coherence_m * np.arange(-ny, ny + 1))
    c = np.stack([gx.ravel(), gy.ravel()], axis=-1)
    w = fp.weights(c[:, 0], c[:, 1])
    return c, w / w.sum()


def footprint_scatter(field, fp: Footprint, wi, wavelengths_nm, material=None, *, coherence_m: float | None = None,
                      **kw):
    """The Kirchhoff BRDF of footprint *fp* on *field* (see the module doc).

    Parameters
    ----------
    field : HeightField or waveoptics.surfaces.LargeHeightField
        The surface; positions are metres from its first sample.
    fp : Footprint
    wi, wavelengths_nm, material
        As :func:`waveoptics.scatter.scatter`.
    coherence_m : float, optional
        Width (m) of the coherence area; None: the whole footprint is coherent.
    **kw
        Passed to :func:`waveoptics.scatter.scatter` (solver, resolution, grid, diffraction, ...; not window_name
        or realizations).

    Returns
    -------
    ScatterResult
        With ``info["footprint"]`` (centre, widths in m, patch samples, coherence windows).
    """
    for bad in ("window_name", "realizations", "surface"):
        if bad in kw:
            raise FieldError(f"{bad} is set by the footprint; do not pass it", bad)
    if coherence_m is None or coherence_m >= max(fp.sigma, fp.sigma_y or fp.sigma):
        patch, G = footprint_patch(field, fp)
        res = scatter(patch, wi, wavelengths_nm, material, window_name=G, **kw)
        res.info["footprint"] = _describe(fp, patch, 1)
        return res
    centres, weights = coherence_centres(fp, coherence_m)
    results, patch = [], None
    for cx, cy in centres:
        patch, G = footprint_patch(field, Footprint(float(cx), float(cy), float(coherence_m)))
        results.append(scatter(patch, wi, wavelengths_nm, material, window_name=G, **kw))
    out = incoherent_sum(results, weights)
    out.info["footprint"] = _describe(fp, patch, len(centres), coherence_m)
    return out


def _describe(fp, patch, n_windows, coherence_m=None) -> dict:
    return {"x_m": fp.x, "y_m": fp.y, "sigma_m": fp.sigma, "sigma_y_m": fp.sigma_y or fp.sigma,
            "angle_deg": fp.angle_deg, "patch_samples": list(patch.shape[::-1]), "coherence_windows": n_windows,
            "coherence_m": coherence_m}


def incoherent_sum(results, weights):
    """The ScatterResult of windows that add as intensities: every lobe and albedo is the *weights*-mean (weights
    sum to 1); the coherent fraction is Σ w_k |χ̂_k|² a_k / Σ w_k a_k with a_k the flat-patch albedos, so that
    albedo − coherent · flat stays the scattered part."""
    from dataclasses import replace

    w = np.asarray(weights, dtype=float)

    def mean(name):
        return sum(wk * np.asarray(getattr(r, name), dtype=float) for wk, r in zip(w, results))

    flat = mean("flat_albedo")
    coh_flat = sum(wk * r.coherent_specular_fraction * r.flat_albedo for wk, r in zip(w, results))
    first = results[0]
    return replace(first, brdf=mean("brdf"), albedo=mean("albedo"), albedo_inner=mean("albedo_inner"),
                   flat_albedo=flat, coherent_specular_fraction=coh_flat / np.where(flat > 0, flat, 1.0),
                   scattered_fraction=mean("scattered_fraction"),
                   timings_s={k: sum(r.timings_s.get(k, 0.0) for r in results) for k in first.timings_s},
                   warnings=sorted({m for r in results for m in r.warnings}), info=dict(first.info))
