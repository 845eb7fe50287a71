"""Diffraction models: the same |U|² structure with different obliquity factors and vertical phase (docs/physics.md
§1, §10).

Every model writes the BRDF of a windowed patch as

    f(ω_i, ω_o) = F(θ_d) · K(ω_i, ω_o, λ) · |U|² / A_w,    U = ∫ w exp(i (k s_xy · (x, y) + v_z h)) dx dy

and differs in the factor K (m⁻²) and in the vertical phase v_z:

============  =====================================================  ==============================
model         K                                                      v_z
============  =====================================================  ==============================
kirchhoff     |s|⁴ / (4 λ² cosθ_i cosθ_o (cosθ_i + cosθ_o)²)          k (cosθ_i + cosθ_o)
ghs           cosθ_o / (λ² cosθ_i)                                    k (cosθ_i + cosθ_o)
rghs          (cosθ_i + cosθ_o)² / (4 λ² cosθ_i cosθ_o)                k (cosθ_i + cosθ_o)
ohs           cosθ_o / (λ² cosθ_i)                                    2 k
rohs          (cosθ_i + cosθ_o)² / (4 λ² cosθ_i cosθ_o)                2 k
============  =====================================================  ==============================

(s = ω_i + ω_o, k = 2π/λ.) All K equal 1/λ² at the mirror direction, so a flat patch reflects F(θ_i) in every
model; they part away from it. Kirchhoff (Beckmann & Spizzichino 1963) is the tangent-plane result; the
Harvey-Shack family (original OHS with the normal-incidence phase 2k, and ``ghs`` with the true v_z) comes from the
linear-systems treatment of scatter (Harvey 1976; Krywonos, Harvey & Choi 2011). ``ghs`` here is the form in the
reference code of Yan et al. 2018: the GHS phase and obliquity cosθ_o/cosθ_i *without* the renormalization
constant K of Krywonos, Harvey & Choi 2011, which rescales the scattered light to what the propagating directions
can carry; without it the F = 1 lobe does not conserve energy (albedo 0.953 at normal incidence, measured in
issue 28). ROHS and RGHS are the variants with the symmetric obliquity in the same code. Measured differences on one surface: docs/
wave-optics.md. Rayleigh-Rice (``rayleigh-rice``), the smooth-surface perturbation model with the polarization
factor Q, is registered here too (``perturbative``): it has no K and no vertical phase, its lobe comes from the
PSD (:mod:`waveoptics.scatter.perturbation`), and only the two-scale model takes it as a nano lobe.

Where each breaks: OHS and ROHS freeze v_z at its normal-incidence value and fail away from normal incidence
(the coherent reduction becomes exp(−(4πσ/λ)²) at every angle); Kirchhoff's factor grows as 1/cosθ_i and does not
conserve energy towards grazing incidence; GHS's cosθ_o/cosθ_i does the same and vanishes at the horizon of the
outgoing side.

References
----------
.. [1] P. Beckmann, A. Spizzichino, *The Scattering of Electromagnetic Waves from Rough Surfaces*, 1963.
.. [2] J. E. Harvey, "Light-scattering characteristics of optical surfaces", PhD thesis, Univ. of Arizona, 1976
   (original Harvey-Shack).
.. [3] A. Krywonos, J. E. Harvey, N. Choi, JOSA A 28(6), 1121, 2011 (generalized Harvey-Shack).
.. [4] L.-Q. Yan, M. Hašan, B. Walter, S. Marschner, R. Ramamoorthi, "Rendering specular microgeometry with wave
   optics", ACM TOG 37(4), 2018 (OHS, GHS, ROHS, RGHS, Kirchhoff in one code).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import FieldError, unknown
from .grid import COS_I_MIN

__all__ = ["DiffractionModel", "DIFFRACTION_MODELS", "get_model", "K_kirchhoff", "K_harvey_shack",
           "K_symmetric"]


def _cosines(wi, wo):
    """(cosθ_i floored at COS_I_MIN, cosθ_o, cosθ_o with the horizon replaced by 1, mask of cosθ_o > 0)."""
    wi = np.asarray(wi, dtype=float)
    wo = np.asarray(wo, dtype=float)
    ci = np.maximum(wi[..., 2], COS_I_MIN)
    co = wo[..., 2]
    up = (co > 0) & (wi[..., 2] > 0)
    # guard: directions at or below the horizon do not reflect (and would divide by zero)
    return ci, co, np.where(up, co, 1.0), up


def K_kirchhoff(wi, wo, wavelength_nm):
    """Kirchhoff (tangent-plane) factor |s|⁴ / (4 λ² cosθ_i cosθ_o (cosθ_i + cosθ_o)²), m⁻²."""
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    ci, _, co, up = _cosines(wi, wo)
    s2 = np.sum((np.asarray(wo, dtype=float) + np.asarray(wi, dtype=float)) ** 2, axis=-1)
    return np.where(up, s2 ** 2 / (4.0 * lam ** 2 * ci * co * (ci + co) ** 2), 0.0)


def K_harvey_shack(wi, wo, wavelength_nm):
    """Harvey-Shack (OHS, GHS) factor cosθ_o / (λ² cosθ_i), m⁻²."""
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    ci, _, co, up = _cosines(wi, wo)
    return np.where(up, co / (lam ** 2 * ci), 0.0)


def K_symmetric(wi, wo, wavelength_nm):
    """Symmetric (ROHS, RGHS) factor (cosθ_i + cosθ_o)² / (4 λ² cosθ_i cosθ_o), m⁻²."""
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    ci, _, co, up = _cosines(wi, wo)
    return np.where(up, (ci + co) ** 2 / (4.0 * lam ** 2 * ci * co), 0.0)


@dataclass(frozen=True)
class DiffractionModel:
    """One diffraction model: its factor K(ω_i, ω_o, λ) (m⁻²) and its vertical phase.

    ``frozen_cos_sum`` None means v_z = k (cosθ_i + cosθ_o) per direction; a number c means v_z = k c for every
    direction (2: the normal-incidence phase of the original Harvey-Shack theory).
    """

    name: str
    K: Callable | None
    frozen_cos_sum: float | None
    description: str
    perturbative: bool = False   # not a |U|² model: first-order perturbation theory of PSD statistics (no K, no v_z)

    def cos_sum(self, wi, wo):
        """cosθ_i + cosθ_o as this model's vertical phase uses it (v_z = k · cos_sum)."""
        if self.frozen_cos_sum is not None:
            return np.broadcast_to(float(self.frozen_cos_sum), np.shape(np.asarray(wo))[:-1])
        return np.asarray(wi, dtype=float)[..., 2] + np.asarray(wo, dtype=float)[..., 2]

    def specular_cos_sum(self, cos_theta_i):
        """cos_sum at the mirror direction (2 cosθ_i, or the frozen value): the coherent field's v_z / k."""
        if self.frozen_cos_sum is not None:
            return np.broadcast_to(float(self.frozen_cos_sum), np.shape(cos_theta_i))
        return 2 * np.asarray(cos_theta_i, dtype=float)


#: the diffraction models, by name (``diffraction=`` in the API, ``--diffraction`` on the command line)
DIFFRACTION_MODELS = {
    "kirchhoff": DiffractionModel("kirchhoff", K_kirchhoff, None,
                                  "tangent-plane Kirchhoff (Beckmann & Spizzichino 1963)"),
    "ghs": DiffractionModel("ghs", K_harvey_shack, None, "generalized Harvey-Shack phase and obliquity as in Yan et "
                            "al. 2018, without the renormalization K of Krywonos, Harvey & Choi 2011"),
    "rghs": DiffractionModel("rghs", K_symmetric, None, "GHS phase with the symmetric obliquity (Yan et al. 2018)"),
    "ohs": DiffractionModel("ohs", K_harvey_shack, 2.0, "original Harvey-Shack: normal-incidence phase 2k"),
    "rohs": DiffractionModel("rohs", K_symmetric, 2.0, "OHS phase with the symmetric obliquity (Yan et al. 2018)"),
    "rayleigh-rice": DiffractionModel("rayleigh-rice", None, None, "first-order vector perturbation theory with the "
                                      "polarization factor Q (Rice 1951; Elson & Bennett 1979)", perturbative=True),
}


def get_model(name, *, perturbative: bool = False) -> DiffractionModel:
    """The :class:`DiffractionModel` *name* (a model object is returned as it is).

    *perturbative*: whether the caller can use a perturbation model (``rayleigh-rice``: a lobe from PSD statistics,
    :mod:`waveoptics.scatter.perturbation`). The Kirchhoff field solvers cannot, and refuse it in one line.
    """
    dm = name if isinstance(name, DiffractionModel) else DIFFRACTION_MODELS.get(name)
    if dm is None:   # the allowed names are those this caller can use
        raise unknown("diffraction model", name, [k for k, v in DIFFRACTION_MODELS.items()
                                                  if perturbative or not v.perturbative], field="diffraction")
    if dm.perturbative and not perturbative:
        raise FieldError(f"{{diffraction}} {dm.name!r} is first-order perturbation theory of a surface's PSD, not a "
                         "Kirchhoff field; here use one of " + ", ".join(k for k, v in DIFFRACTION_MODELS.items()
                                                                        if not v.perturbative)
                         + " (rayleigh-rice is a nano lobe of the two-scale model only)", "diffraction")
    return dm
