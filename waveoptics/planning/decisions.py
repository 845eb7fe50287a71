"""The physics behind each planning decision, as small pure functions.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.special import jv

from .. import surfaces
from ..brdf import twoscale

__all__ = ['DE_PER_RELATIVE_Y', 'LSTAR_SLOPE_BLACK', 'LAMBDA_REF_NM', 'EPS32', 'scattered_fraction', 'lobe_width', 'diffraction_lobe_width', 'grid_step', 'float32_floor', 'weakest_level', 'grating_orders', 'ORDER_EFFICIENCY_MIN', 'first_order_g']

#: CIE L* slope dL*/dln Y at L* = 50 (Y = 0.1842): 116/3 · Y^(1/3) = 22.0 ΔE per unit relative luminance
DE_PER_RELATIVE_Y = 116.0 / 3.0 * ((50.0 + 16.0) / 116.0)
#: CIE L* = 903.3 Y near black: the luminance of a just-visible haze is ΔE / 903.3
LSTAR_SLOPE_BLACK = 903.3
#: wavelength (nm) at which a wavelength-independent BRDF is evaluated
LAMBDA_REF_NM = 550.0
#: float32 unit round-off
EPS32 = 2.0**-24


# ----------------------------------------------------------------------------------------------------------------
# Physics of the decisions (small pure functions)
# ----------------------------------------------------------------------------------------------------------------

def scattered_fraction(nano: twoscale.Nano, cos_theta, wavelength_nm) -> np.ndarray:
    """1 − A: the share of the specular light the nano surface scatters (1 − exp(−g) for Gaussian heights).

    References
    ----------
    .. [1] Davies 1954; Bennett & Porteus 1961 (TIS = F (1 − exp(−g))).
    """
    return 1.0 - np.asarray(nano.coherent_fraction(cos_theta, wavelength_nm), dtype=float)


def lobe_width(alpha: float, cos_theta_i: float) -> float:
    """Standard deviation (direction cosines) of a microfacet lobe of roughness α along its narrow axis.

    The facet tilt has rms α/√2 per axis and the reflected direction turns twice as far; along the plane of
    incidence the direction cosine is compressed by cos θ (floored at 0.5: beyond 60° no grid resolves it).
    """
    return math.sqrt(2.0) * alpha * max(cos_theta_i, 0.5)


def diffraction_lobe_width(model: surfaces.PSDModel, wavelength_nm: float) -> float:
    """Standard deviation (direction cosines) of the nano lobe: λ / (√2 π ℓ) for correlation length ℓ
    (:meth:`waveoptics.surfaces.PSDModel.lobe_width`, docs/physics.md §4)."""
    return model.lobe_width(wavelength_nm)


def grid_step(width: float, delta_e: float) -> float:
    """Largest direction-cosine spacing that interpolates a lobe of std *width* within *delta_e* (ΔE2000).

    Linear interpolation errs by ≤ du² max|f''| / 8 = du² / (8 s²) of the peak of a Gaussian of std s (de Boor
    1978); ε relative luminance costs DE_PER_RELATIVE_Y · ε of ΔE2000 (CIE 015 L*, Luo et al. 2001).
    """
    return width * math.sqrt(8.0 * delta_e / DE_PER_RELATIVE_Y)


def float32_floor(n_samples: int, h_max_m: float, wavelength_nm: float) -> float:
    """Relative noise power of the float32 direct sum against the coherent peak (see the module notes)."""
    return EPS32**2 * (n_samples / 256.0 + (4 * np.pi * h_max_m / (wavelength_nm * 1e-9)) ** 2 / max(n_samples, 1))


def weakest_level(delta_e: float, patch_m: float, wavelength_nm: float) -> float:
    """BRDF of a just-visible haze, ΔE/(903.3 π), relative to the coherent spike F (L/λ)² of a patch of size L."""
    return delta_e / (LSTAR_SLOPE_BLACK * np.pi) * (wavelength_nm * 1e-9 / patch_m) ** 2


def grating_orders(amplitude_m: float, period_m: float, wavelength_nm: float) -> int:
    """Highest order m with Raman-Nath efficiency J_m²(4π a/λ) ≥ ORDER_EFFICIENCY_MIN that leaves the surface.

    References
    ----------
    .. [1] docs/physics.md §5 (η_m = J_m²(4π a/λ) at normal incidence); Harvey & Pfisterer 2020.
    """

    lam = wavelength_nm * 1e-9
    m_geo = int(math.floor(2 * period_m / lam))        # |sinθ_m − sinθ_i| ≤ 2
    x = 4 * math.pi * amplitude_m / lam
    m = [k for k in range(1, m_geo + 1) if jv(k, x) ** 2 >= ORDER_EFFICIENCY_MIN]
    return max(m) if m else 1


#: diffraction orders with efficiency below this are ignored for the wavelength step of gratings
ORDER_EFFICIENCY_MIN = 1e-3


def first_order_g(model: surfaces.PSDModel, theta_deg, wavelength_nm: float) -> float:
    """The largest g = (k σ_rel (cosθ_i + cosθ_o))² over the outgoing directions (cosθ_o = 1) at each incidence
    *theta_deg* (degrees; the largest over them), σ_rel the roughness in the propagating band of that incidence:
    first-order perturbation theory (Rayleigh-Rice) holds where it is ≪ 1. Towards grazing incidence it falls to
    (k σ_rel)², a quarter of its normal-incidence value.

    References
    ----------
    .. [1] E. I. Thorsos, D. R. Jackson, JASA 86(1), 261–277, 1989 (domain of the perturbation approximation).
    .. [2] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 2011 (relevant roughness).
    """
    from ..scatter.band import relevant_sigma2

    t = np.radians(np.atleast_1d(np.asarray(theta_deg, dtype=float)))
    k = 2 * np.pi / (wavelength_nm * 1e-9)
    s2 = relevant_sigma2(model, wavelength_nm, np.sin(t))
    return float(np.max(k ** 2 * s2 * (np.cos(t) + 1.0) ** 2))
