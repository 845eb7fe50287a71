"""The roughness α of any NDF that matches a height field's slopes.

A Gaussian surface has Gaussian slopes, and the Beckmann NDF with α = √2 × rms slope per axis is its exact
slope law (docs/physics.md §1). Other NDFs have other slope laws, and several have no finite second moment
(GGX's slope density falls as |s|⁻⁴: its rms slope is infinite), so an rms match is meaningless for them. Every
NDF has a median slope, though: the slope magnitude |s| = tan θ_m below which half of the projected facet area
lies,

    P(|s| ≤ t) = ∫_{|s| ≤ t} P22(s) d²s = 2π ∫₀ᵗ P22(s) s ds,   P22(s) = D(m) cos⁴θ_m  (Heitz 2014, §2.3),

so :func:`alpha_for_median_slope` finds the α whose median equals the surface's (closed forms: GGX α = t_med,
Beckmann α = t_med / √ln 2; others by quadrature and root finding). Per axis, for the anisotropic GGX, the
marginal of s_x has median α_x / √3.

References
----------
.. [1] E. Heitz, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs", JCGT 3(2), 2014,
   §2.3 (slope distribution) and §5.3 (GGX's slope law).
.. [2] B. Walter et al., EGSR 2007 (GGX).
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy import optimize

from ..errors import FieldError
from .ndf import ALPHA_MAX, NDFS, ndf_by_name

__all__ = ["slope_magnitude_cdf", "alpha_for_median_slope", "GGX_AXIS_MEDIAN"]

#: median of |s_x| for the GGX slope law of α_x = 1 (its marginal CDF is s / √(1 + s²))
GGX_AXIS_MEDIAN = 1.0 / math.sqrt(3.0)

@functools.lru_cache(maxsize=1)
def _legendre_256():
    """Gauss-Legendre nodes and weights of order 256, computed on first use (an eigenvalue problem: 0.2-0.5 s at
    import time otherwise, paid by every command)."""
    return np.polynomial.legendre.leggauss(256)


def slope_magnitude_cdf(ndf: str, alpha: float, t: float, shape=None) -> float:
    """P(|s| ≤ t): the share of projected facet area with slope magnitude at most *t* (isotropic NDF *ndf* of
    roughness *alpha*), by Gauss-Legendre quadrature of 2π P22(s) s on [0, t] split geometrically."""
    spec = ndf_by_name(ndf)
    if t <= 0:
        return 0.0
    edges = np.concatenate([[0.0], t * np.geomspace(1e-4, 1.0, 24)])
    total = 0.0
    nodes, weights = _legendre_256()
    for a, b in zip(edges[:-1], edges[1:]):
        s = 0.5 * (b - a) * nodes + 0.5 * (a + b)
        c = 1.0 / np.sqrt(1.0 + s * s)
        m = np.stack([-s * c, np.zeros_like(s), c], axis=-1)           # a normal of slope s along x
        p22 = spec.D(m, alpha, alpha, shape) * c ** 4
        total += 0.5 * (b - a) * float(np.sum(weights * 2 * np.pi * p22 * s))
    return total


def alpha_for_median_slope(ndf: str, median_slope: float, shape=None) -> float:
    """α of the isotropic NDF *ndf* (shape parameter *shape*, default the NDF's) whose median slope magnitude is
    *median_slope* (see the module doc)."""
    if not (np.isfinite(median_slope) and median_slope > 0):
        raise FieldError(f"median slope {median_slope!r} is not allowed; it must be > 0", "median_slope")
    if ndf == "ggx":
        return float(median_slope)
    if ndf == "beckmann":
        return float(median_slope / math.sqrt(math.log(2.0)))
    spec = NDFS[ndf] if ndf in NDFS else ndf_by_name(ndf)
    if spec.name == "tabulated":
        raise FieldError("a tabulated NDF has no α to fit; it is the slope law itself", "ndf")
    c = spec.shape_default if shape is None else shape

    def gap(log_a):
        return slope_magnitude_cdf(ndf, math.exp(log_a), median_slope, c) - 0.5

    lo, hi = math.log(1e-4), math.log(ALPHA_MAX if ndf != "blinn-phong" else 1.0)
    if gap(lo) < 0 or gap(hi) > 0:
        raise FieldError(f"no {ndf} roughness in [1e-4, {math.exp(hi):g}] has median slope {median_slope:g}",
                         "median_slope")
    return float(math.exp(optimize.brentq(gap, lo, hi, xtol=1e-10)))
