"""The angles of a scattering geometry: incidence, scattering and the scattering azimuth from the specular side of
the plane of incidence (the coordinates of Rayleigh-Rice's polarization factors, docs/physics.md §4).

References
----------
.. [1] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997 (the angles θ_i, θ_s, φ_s of the q factors).
"""
from __future__ import annotations

import numpy as np

__all__ = ["scattering_angles"]


def scattering_angles(wi, wo):
    """(cosθ_i, sinθ_i, cosθ_o, sinθ_o, cosφ_s, sinφ_s) of unit directions (..., 3), φ_s measured from the specular
    side of the plane of incidence (φ_s = 0 at the mirror direction). At normal incidence the plane of incidence
    is taken as the x–z plane; for an outgoing direction along the normal, φ_s = 0 (the unpolarized sums do not
    depend on it there)."""
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    ci, co = wi[..., 2], wo[..., 2]
    si = np.hypot(wi[..., 0], wi[..., 1])
    so = np.hypot(wo[..., 0], wo[..., 1])
    # guard: an undefined azimuth (normal incidence / normal outgoing) gets the x axis / φ_s = 0
    ex = np.where(si > 0, wi[..., 0] / np.where(si > 0, si, 1.0), 1.0)
    ey = np.where(si > 0, wi[..., 1] / np.where(si > 0, si, 1.0), 0.0)
    ox = np.where(so > 0, wo[..., 0] / np.where(so > 0, so, 1.0), -ex)
    oy = np.where(so > 0, wo[..., 1] / np.where(so > 0, so, 1.0), -ey)
    # the specular side is −(e_x, e_y): cosφ_s = −e·o, sinφ_s = (−e) × o
    cos_phi = -(ex * ox + ey * oy)
    sin_phi = -(ex * oy - ey * ox)
    return ci, si, co, so, cos_phi, sin_phi
