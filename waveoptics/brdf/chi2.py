"""Pearson χ² goodness-of-fit test of a direction sampler against its density, the method of Mitsuba 3's ``chi2``.

Samples drawn by ``sample(u)`` are binned on the sphere in (φ, cos θ) (equal-area cells, dω = dφ d cos θ); the
expected count of each cell is N ∫_cell pdf dω, integrated with the trapezoid rule on ires × ires points. Cells
with expected count below 5 are pooled (Pearson's rule), a sample in a cell of expected count 0 fails the test
outright, and the statistic Σ (O − E)² / E is compared with the χ² law of (cells − 1) degrees of freedom; the
sampler is rejected when the p-value is below the significance level (Šidák-corrected for several tests).

Mitsuba 3's own ``mitsuba.chi2.ChiSquareTest`` needs Mitsuba (an optional extra) and one of its JIT (LLVM)
variants with LLVM >= 17 (Debian 12's LLVM 15 and 16 abort: "Cannot select: fmaximum"), so the library's samplers
are tested with the same procedure written here in NumPy; the Mitsuba plugin (:mod:`waveoptics.renderers.mitsuba`)
is tested with Mitsuba's own.

References
----------
.. [1] W. Jakob et al., Mitsuba 3, ``src/python/python/chi2.py`` (the procedure followed here).
.. [2] K. Pearson, "On the criterion that a given system of deviations ...", Phil. Mag. 50(302), 1900.
.. [3] Z. Šidák, "Rectangular confidence regions for the means of multivariate normal distributions",
   JASA 62(318), 1967.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy import stats

__all__ = ['Chi2Result', 'chi2_test', 'reflected_samples']

#: cells with fewer expected samples are pooled
MIN_EXPECTED = 5.0


@dataclass(frozen=True)
class Chi2Result:
    """Outcome: ``passed``, ``p_value``, ``statistic``, ``dof``, ``pdf_integral`` (∫ pdf dω over the sphere),
    ``valid_fraction`` (share of samples that are directions) and a one-line ``message``."""

    passed: bool
    p_value: float
    statistic: float
    dof: int
    pdf_integral: float
    valid_fraction: float
    message: str


def _frame(pole):
    """Rotation R whose third row is the unit *pole* (R d gives coordinates about that pole)."""
    z = np.asarray(pole, dtype=float)
    z = z / np.linalg.norm(z)
    a = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z])


def _cells(d, res):
    phi = np.arctan2(d[:, 1], d[:, 0])
    z = np.clip(d[:, 2], -1.0, 1.0)
    ix = np.clip(((phi + np.pi) / (2 * np.pi) * 2 * res).astype(int), 0, 2 * res - 1)
    iy = np.clip(((z + 1.0) / 2.0 * res).astype(int), 0, res - 1)
    return iy * 2 * res + ix


def chi2_test(sample: Callable, pdf: Callable, *, sample_count: int = 200_000, res: int = 51, ires: int = 4,
              seed: int = 0, significance: float = 0.01, test_count: int = 1, pole=(0.0, 1.0, 0.0)) -> Chi2Result:
    """Test *sample* (u (n, 2) → directions (n, 3), invalid ones with a non-finite or zero vector, or with z
    outside the expected domain) against *pdf* (directions (n, 3) → 1/sr).

    Parameters
    ----------
    sample_count : int
        Samples drawn (seeded PCG64 uniform numbers).
    res : int
        Cells in cos θ (2·res in φ); odd keeps the horizon off a cell edge.
    ires : int
        Trapezoid points per cell side for the expected counts.
    significance : float
        Rejection level before the Šidák correction for *test_count* tests.
    pole : (3,) array_like
        Axis of the (φ, cos θ) cells, in the sampler's frame. Cells are slivers near the poles, where a peaked
        density is integrated poorly; the default (the y axis) keeps lobes of incidences in the xz plane on its
        equator. Solid angle, hence every count, is unchanged by the choice.
    """
    R = _frame(pole)
    rng = np.random.default_rng(seed)
    u = rng.random((sample_count, 2))
    d = np.asarray(sample(u), dtype=float)
    norm = np.linalg.norm(d, axis=-1)
    valid = np.isfinite(norm) & (norm > 0.5)
    d = (d[valid] / norm[valid, None]) @ R.T
    observed = np.bincount(_cells(d, res), minlength=2 * res * res).astype(float)

    # expected counts: trapezoid rule on each cell of the (φ, z) rectangle
    nx, ny = 2 * res, res
    dx, dy = 2 * np.pi / nx, 2.0 / ny
    t = np.linspace(0.0, 1.0, ires)
    wt = np.full(ires, 1.0 / (ires - 1))
    wt[0] = wt[-1] = 0.5 / (ires - 1)
    cx = -np.pi + (np.arange(nx)[:, None] + t[None, :]) * dx      # (nx, ires)
    cy = -1.0 + (np.arange(ny)[:, None] + t[None, :]) * dy        # (ny, ires)
    PHI = cx[None, :, None, :]
    Z = np.clip(cy[:, None, :, None], -1.0, 1.0)
    S = np.sqrt(np.maximum(1.0 - Z * Z, 0.0))
    dirs = np.stack(np.broadcast_arrays(S * np.cos(PHI), S * np.sin(PHI), Z), axis=-1)
    p = np.asarray(pdf(dirs.reshape(-1, 3) @ R), dtype=float).reshape(dirs.shape[:-1])
    W = wt[:, None] * wt[None, :]
    integral = np.einsum("yxab,ab->yx", p, W) * dx * dy
    expected = integral.reshape(-1) * sample_count
    pdf_integral = float(integral.sum())

    zero_hit = (expected <= 0) & (observed > 0)
    if np.any(zero_hit):
        n = int(observed[zero_hit].sum())
        return Chi2Result(False, 0.0, np.inf, 0, pdf_integral, float(valid.mean()),
                          f"{n} samples fell in cells where the pdf is 0")
    order = np.argsort(expected)
    e, o = expected[order], observed[order]
    small = e < MIN_EXPECTED
    pooled_e, pooled_o = e[small].sum(), o[small].sum()
    e, o = e[~small], o[~small]
    if pooled_e > 0:
        e = np.append(e, pooled_e)
        o = np.append(o, pooled_o)
    keep = e > 0
    stat = float(np.sum((o[keep] - e[keep]) ** 2 / e[keep]))
    dof = int(keep.sum()) - 1
    p_value = float(stats.chi2.sf(stat, dof)) if dof > 0 else 1.0
    level = 1.0 - (1.0 - significance) ** (1.0 / test_count)
    passed = p_value >= level
    msg = (f"chi2 = {stat:.1f} with {dof} dof, p = {p_value:.3g} ({'accepted' if passed else 'rejected'} at "
           f"{level:.3g}); pdf integral {pdf_integral:.4f}, valid samples {valid.mean():.4f}")
    return Chi2Result(bool(passed), p_value, stat, dof, pdf_integral, float(valid.mean()), msg)


def reflected_samples(brdf, wi, wavelength_nm) -> Callable:
    """The sampler of a BRDF for :func:`chi2_test`: u (n, 2) → the directions ``brdf.sample_wo`` draws for ω_i =
    *wi* at *wavelength_nm* (nm), NaN where one is not above the surface (an invalid sample). The directions alone:
    the samples' weights f cos θ_o / p, which :meth:`sample` also computes, play no part in the test (a sample where
    f = 0 but p > 0 is counted, as the density says it is drawn)."""
    def sample(u):
        wo = np.asarray(brdf.sample_wo(wi, wavelength_nm, u), dtype=float)
        return np.where((wo[..., 2] > 0)[..., None], wo, np.nan)
    return sample

