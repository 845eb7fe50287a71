"""Kirchhoff (tangent-plane, scalar Huygens-Fresnel) scattering from a height-field patch, per wavelength.

With s = ω_i + ω_o (ω_i towards the light, ω_o towards the viewer), v = k s, a smooth window w(x, y) over the
patch and A_w = ∫ w² dx dy (docs/physics.md §1):

    U(ω_i, ω_o) = ∫ w(x, y) exp(i v · (x, y, h(x, y))) dx dy

    f(ω_i, ω_o) = F(θ_d) |s|⁴ / (4 λ² A_w cos θ_i cos θ_o (cos θ_i + cos θ_o)²) · |U|²      [sr⁻¹]

with F(θ_d) the Fresnel reflectance at the half-vector angle, cos θ_d = ω_i · s/|s| = |s|/2. On the grid the
integral is the sum over samples times dx dy and A_w = Σ w² dx dy.

Solvers (registry :data:`SOLVERS`):

``direct``
    The sum evaluated for every (outgoing direction, wavelength) pair on the OpenCL device
    (``kernels/kirchhoff.cl``, :func:`kirchhoff_U_cl`), or in NumPy (:func:`kirchhoff_U`, float64, the
    reference). Exact within the tangent-plane model; O(samples × directions × wavelengths).
``fft``
    The field on a regular grid of direction cosines by chirp-z transforms (:func:`scipy.signal.ZoomFFT`) of
    w · hⁿ · exp(i v_z0 h), which samples the patch's discrete-time Fourier transform exactly on each
    wavelength's part of the common (u, v) grid (no interpolation, no zero padding). The vertical component
    v_z = k (cos θ_i + cos θ_o) depends on the outgoing direction; ``order=0`` freezes it at the specular value
    v_z0 = 2 k cos θ_i (the paraxial / Harvey-Shack-style approximation: exact for a flat surface and at the
    specular direction, wrong away from it by a phase error (v_z − v_z0) h). ``order="auto"`` (default) removes
    that error: the outgoing directions are split into bands of v_z and in each band exp(i (v_z − v_zb) h) is
    expanded in a Taylor series, U = Σ_n (i Δv_z)ⁿ/n! · DTFT[w hⁿ exp(i v_zb h)], truncated where the Lagrange
    bound |Δv_z h|^(K+1)/(K+1)! falls below ``tol`` relative to Σ w. This is exact Kirchhoff to that tolerance
    at O(bands × terms × N log N) cost.

References
----------
.. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, Pergamon,
   1963, ch. 3 and 5 (Kirchhoff integral, obliquity factor, stationary-phase limit).
.. [2] Z. Dong, B. Walter, S. Marschner, D. P. Greenberg, "Predicting appearance from measured microgeometry of
   metal surfaces", ACM TOG 35(1), 2015 (windowed Kirchhoff BRDF of measured height fields, FFT evaluation).
.. [3] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 2018 (OHS/GHS obliquity variants).
.. [4] J. E. Harvey, R. N. Pfisterer, "Understanding diffraction grating behavior", Opt. Eng. 59(1) 017103, 2020
   (paraxial / generalized Harvey-Shack surface scatter).
.. [5] L. R. Rabiner, R. W. Schafer, C. M. Rader, "The chirp z-transform algorithm", IEEE Trans. Audio
   Electroacoustics 17(2), 1969 (scipy.signal.ZoomFFT).
.. [6] H. Davies, "The reflection of electromagnetic waves from a rough surface", Proc. IEE 101, 1954;
   H. E. Bennett, J. O. Porteus, "Relation between surface roughness and specular reflectance at normal
   incidence", JOSA 51(2), 1961 (coherent fraction exp(−g), TIS).
"""
from __future__ import annotations

import numpy as np

from .models import get_model
from .patch import Samples

__all__ = ['cos_theta_d', 'brdf_from_field', 'coherent_amplitude']


# ----------------------------------------------------------------------------------------------------------------
# The Kirchhoff factor and BRDF from a field
# ----------------------------------------------------------------------------------------------------------------

def cos_theta_d(wi, wo) -> np.ndarray:
    """cos θ_d = ω_i · h = |ω_i + ω_o| / 2, the Fresnel angle of the half vector."""
    return np.clip(0.5 * np.linalg.norm(np.asarray(wo) + np.asarray(wi), axis=-1), 0.0, 1.0)


def brdf_from_field(U, wi, wo, wavelengths_nm, area: float, F=None, diffraction="kirchhoff") -> np.ndarray:
    """BRDF f = F(θ_d) K |U|² / A_w, sr⁻¹, with the factor K of the *diffraction* model (Kirchhoff:
    |s|⁴ / (4 λ² cos θ_i cos θ_o (cos θ_i + cos θ_o)²); :mod:`waveoptics.scatter.models`).

    Parameters
    ----------
    U : ndarray (n_wl, ...), m²
        Field (including dx dy) for each wavelength and direction.
    wo : ndarray (..., 3)
    wavelengths_nm : ndarray (n_wl,), nm
    area : float, m²
        A_w.
    F : callable, optional
        F(cos θ_d, wavelength_nm); None → 1; an object with ``at(wi, wo, wavelength_nm)`` (polarized light,
        :class:`waveoptics.materials.PolarizedFresnel`) is evaluated per direction.
    diffraction : str or DiffractionModel
        A name in :data:`waveoptics.scatter.DIFFRACTION_MODELS`.
    """
    wl = np.asarray(wavelengths_nm, dtype=float)
    shape = (wl.size,) + (1,) * (np.ndim(wo) - 1)
    K = get_model(diffraction).K(np.asarray(wi, dtype=float), wo[None], wl.reshape(shape))
    out = K * np.abs(U) ** 2 / area
    if hasattr(F, "at"):   # polarized light: the facet's own s/p split needs both directions
        out = out * np.asarray(F.at(np.asarray(wi, dtype=float), wo[None], wl.reshape(shape)), dtype=float)
    elif F is not None:
        out = out * np.asarray(F(cos_theta_d(wi, wo)[None], wl.reshape(shape)), dtype=float)
    return out


# ----------------------------------------------------------------------------------------------------------------
# Coherent part
# ----------------------------------------------------------------------------------------------------------------

def coherent_amplitude(smp: Samples, wi, wavelength_nm, diffraction="kirchhoff") -> complex:
    """χ̂ = Σ w² exp(i v_z h) / Σ w², v_z = 2 k cos θ_i (2k for the OHS phase): the patch estimate of
    ⟨exp(i v_z h)⟩ at the mirror direction (docs/physics.md §2)

    The ensemble-mean field is ⟨U⟩ = χ · U_flat, so the coherent (specular) fraction is |χ|² = exp(−g) for
    Gaussian heights. The spatial average over the patch replaces the ensemble average (ergodicity); the w²
    weights make exp(i v_z h) − χ̂ orthogonal to w, so that the coherent and the scattered lobes add without a
    cross term in the albedo. One patch's |χ̂|² is biased high by about (1 − |χ|²) · A_c / A_w (A_c the
    correlation area); averaging χ̂ over realizations removes that bias. This is the complex amplitude; the power
    fractions are :func:`waveoptics.scatter.debye_waller` (exp(−g) of a height distribution's σ) and
    :meth:`waveoptics.brdf.Nano.coherent_fraction` (the two-scale model's A).

    References
    ----------
    .. [1] H. Davies, Proc. IEE 101, 1954; Beckmann & Spizzichino 1963, ch. 5 (coherent field ⟨exp(i v_z h)⟩).
    """
    cz = float(get_model(diffraction).specular_cos_sum(wi[2])) / (wavelength_nm * 1e-9)
    w2 = smp.w**2
    return complex(np.sum(w2 * np.exp(2j * np.pi * cz * smp.h)) / np.sum(w2))
