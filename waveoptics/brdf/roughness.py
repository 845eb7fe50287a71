"""Roughness conventions: the NDF width α from the perceptual roughness r (α = r²) and from a Blinn-Phong exponent.

References
----------
.. [1] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes (α = r²).
.. [2] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, "Microfacet Models for Refraction through Rough
   Surfaces", EGSR 2007, §5.2 (Blinn-Phong exponent from α).
"""
from __future__ import annotations

import numpy as np

from ..errors import WaveopticsError

__all__ = ['alpha_from_roughness', 'roughness_from_alpha', 'blinn_phong_exponent', 'alpha_from_blinn_phong']


def alpha_from_roughness(roughness):
    """NDF width α from the perceptual roughness r of Burley (2012): α = r².

    Parameters
    ----------
    roughness : array_like
        Perceptual roughness in [0, 1] (dimensionless).

    References
    ----------
    .. [1] B. Burley, "Physically-Based Shading at Disney", SIGGRAPH 2012 course notes, §5.4.
    """
    r = np.asarray(roughness, dtype=float)
    if np.any(~np.isfinite(r) | (r < 0)):
        bad = r[~np.isfinite(r) | (r < 0)].ravel()[0] if r.ndim else r
        raise WaveopticsError(f"roughness={float(bad)!r} is not allowed; the perceptual roughness r must be >= 0 "
                              "(α = r²)")
    return r ** 2


def roughness_from_alpha(alpha):
    """Perceptual roughness r = √α, inverse of :func:`alpha_from_roughness`."""
    return np.sqrt(np.asarray(alpha, dtype=float))


def blinn_phong_exponent(alpha):
    """Blinn-Phong exponent α_p = 2/α² − 2 equivalent to a Beckmann NDF of rms slope α.

    The two NDFs agree to second order in θ_m around the normal; the exponent is what :data:`NDFS`'s
    ``"blinn-phong"`` uses for a given α.

    References
    ----------
    .. [1] B. Walter et al., "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007, §5.2.
    """
    a = np.asarray(alpha, dtype=float)
    return 2.0 / (a * a) - 2.0


def alpha_from_blinn_phong(exponent):
    """Beckmann α = √(2 / (α_p + 2)) equivalent to Blinn-Phong exponent α_p (inverse of
    :func:`blinn_phong_exponent`).

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, §5.2.
    """
    return np.sqrt(2.0 / (np.asarray(exponent, dtype=float) + 2.0))
