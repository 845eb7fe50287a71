"""The direction grid: cells of the direction-cosine plane (u, v) = sinθ (cosφ, sinφ), on which
cosθ dω = du dv (docs/physics.md §1), and integration over it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import WaveopticsError
from ..units import check_theta, direction_from_angles

__all__ = ['HORIZON_SIN', 'DirectionGrid', 'integrate', 'COS_I_MIN']

#: sinθ_o above which a direction counts as "near the horizon" (1/cosθ_o > 3.2) in the reported horizon share
HORIZON_SIN = 0.95


# ----------------------------------------------------------------------------------------------------------------
# Direction-cosine grid
# ----------------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class DirectionGrid:
    """A regular grid of cell centres in the direction-cosine plane (u, v) = (sin θ cos φ, sin θ sin φ).

    cos θ_o dω_o = du dv, so a directional albedo is Σ f du dv over the cells inside the unit disc. Cells are
    centred (u_j = u0 + (j + ½) du), so no cell sits exactly on the horizon. Row index = v, column index = u.

    Parameters
    ----------
    n_u, n_v : int
        Cells along u (columns) and v (rows).
    u_range, v_range : (float, float)
        Edges of the covered rectangle; the whole projected hemisphere is (−1, 1) × (−1, 1).

    References
    ----------
    .. [1] Beckmann & Spizzichino 1963; docs/physics.md §1 (projected solid angle).
    """

    n_u: int
    n_v: int
    u_range: tuple = (-1.0, 1.0)
    v_range: tuple = (-1.0, 1.0)

    def __post_init__(self):
        for name, n in (("n_u", self.n_u), ("n_v", self.n_v)):
            if int(n) != n or n < 1 or n > 16384:
                raise WaveopticsError(f"direction grid {name}={n!r} is not allowed; use an integer in 1..16384")
        for name, (a, b) in (("u_range", self.u_range), ("v_range", self.v_range)):
            if not (np.isfinite(a) and np.isfinite(b) and -1 <= a < b <= 1):
                raise WaveopticsError(f"direction grid {name}=({a}, {b}) is not allowed; need -1 <= a < b <= 1")
        object.__setattr__(self, "n_u", int(self.n_u))
        object.__setattr__(self, "n_v", int(self.n_v))
        object.__setattr__(self, "u_range", (float(self.u_range[0]), float(self.u_range[1])))
        object.__setattr__(self, "v_range", (float(self.v_range[0]), float(self.v_range[1])))

    @classmethod
    def hemisphere(cls, resolution: int) -> "DirectionGrid":
        """The whole projected hemisphere, *resolution* × *resolution* cells."""
        return cls(int(resolution), int(resolution))

    @property
    def du(self) -> float:
        return (self.u_range[1] - self.u_range[0]) / self.n_u

    @property
    def dv(self) -> float:
        return (self.v_range[1] - self.v_range[0]) / self.n_v

    @property
    def u(self) -> np.ndarray:
        """Cell centres along u, (n_u,)."""
        return self.u_range[0] + (np.arange(self.n_u) + 0.5) * self.du

    @property
    def v(self) -> np.ndarray:
        """Cell centres along v, (n_v,)."""
        return self.v_range[0] + (np.arange(self.n_v) + 0.5) * self.dv

    @property
    def sin_theta(self) -> np.ndarray:
        """sin θ_o = √(u² + v²) per cell, (n_v, n_u)."""
        return np.hypot(self.u[None, :], self.v[:, None])

    @property
    def inside(self) -> np.ndarray:
        """True for cells whose centre lies inside the unit disc (above the horizon), (n_v, n_u)."""
        return self.sin_theta < 1.0

    @property
    def cos_theta(self) -> np.ndarray:
        """cos θ_o per cell (0 outside the disc), (n_v, n_u)."""
        return np.sqrt(np.clip(1.0 - self.sin_theta**2, 0.0, 1.0))

    def directions(self) -> np.ndarray:
        """Unit vectors ω_o (n_v, n_u, 3); z = 0 outside the disc."""
        U, V = np.meshgrid(self.u, self.v)
        return np.stack([U, V, self.cos_theta], axis=-1)

    def bilinear(self, u, v):
        """Cell-centred bilinear stencil of points (u, v): lower corner (row k0, column j0), weights (av, au) of
        the upper neighbours, and whether the point lies on the grid (within half a cell of its edge cells)."""
        u = np.asarray(u, dtype=float)
        v = np.asarray(v, dtype=float)
        fu = (u - self.u_range[0]) / self.du - 0.5
        fv = (v - self.v_range[0]) / self.dv - 0.5
        ok = (fu > -0.5) & (fu < self.n_u - 0.5) & (fv > -0.5) & (fv < self.n_v - 0.5)
        j0 = np.clip(np.floor(fu).astype(int), 0, self.n_u - 2)
        k0 = np.clip(np.floor(fv).astype(int), 0, self.n_v - 2)
        return k0, j0, np.clip(fv - k0, 0.0, 1.0), np.clip(fu - j0, 0.0, 1.0), ok

    def interpolate(self, lobes, u, v):
        """Bilinear interpolation of cell-centred values *lobes* (..., n_v, n_u) at points (u, v) of any shape:
        result (..., *u.shape); 0 outside the grid (clamped to the edge cells within half a cell of it)."""
        k0, j0, av, au, ok = self.bilinear(u, v)
        lobes = np.asarray(lobes)
        val = ((1 - av) * ((1 - au) * lobes[..., k0, j0] + au * lobes[..., k0, j0 + 1])
               + av * ((1 - au) * lobes[..., k0 + 1, j0] + au * lobes[..., k0 + 1, j0 + 1]))
        return np.where(ok, val, 0.0)

    @staticmethod
    def to_image(values):
        """Rows of cell values (..., n_v, n_u) in image order, top row first (the highest v): how EXR files and
        pictures store a lobe, so that viewers show +v up. :meth:`from_image` undoes it."""
        return np.asarray(values)[..., ::-1, :]

    from_image = to_image

    def header(self) -> dict:
        """The parametrization as string attributes (for image headers)."""
        return {
            "parametrization": "direction cosines: u = sin(theta_o) cos(phi_o) along columns (x), "
                               "v = sin(theta_o) sin(phi_o) along rows (y); cell centres; row 0 = highest v "
                               "(the top row, as image viewers show it; arrays in memory run from the lowest v)",
            "u_range": f"{self.u_range[0]:.17g} {self.u_range[1]:.17g}",
            "v_range": f"{self.v_range[0]:.17g} {self.v_range[1]:.17g}",
            "n_u": str(self.n_u), "n_v": str(self.n_v),
            "measure": "cos(theta_o) d(omega_o) = du dv; albedo = sum(f) du dv over cells with u^2 + v^2 < 1",
        }


def integrate(f, grid: DirectionGrid, *, region=None) -> np.ndarray:
    """Directional albedo ∫ f cos θ_o dω_o = Σ f du dv over the disc (optionally also a boolean *region*).

    Parameters
    ----------
    f : ndarray (..., n_v, n_u), sr⁻¹
        BRDF on *grid*.

    Returns
    -------
    ndarray (...)
    """
    m = grid.inside if region is None else grid.inside & region
    return np.sum(np.where(m, f, 0.0), axis=(-2, -1)) * grid.du * grid.dv


def incident_dirs(wi) -> np.ndarray:
    """ω_i from (θ, φ) in degrees or a 3-vector; validated, cos θ_i floored at COS_I_MIN."""
    a = np.asarray(wi, dtype=float).ravel()
    if a.size == 2 or a.size == 1:
        theta, phi = float(a[0]), float(a[1]) if a.size == 2 else 0.0
        check_theta(theta, name="incident")
        w = direction_from_angles(theta, phi)
    elif a.size == 3:
        n = np.linalg.norm(a)
        if not np.isfinite(n) or n == 0 or a[2] < 0:
            raise WaveopticsError(f"incident direction {tuple(a)} is not allowed; it must be finite, non-zero "
                                  "and above the surface (z >= 0)")
        w = a / n
    else:
        raise WaveopticsError(f"incident direction {wi!r} is not allowed; give (theta_deg, phi_deg) or (x, y, z)")
    # guard: a grazing light has cos θ_i -> 0 and the BRDF's 1/cos θ_i diverges; floor it
    if w[2] < COS_I_MIN:
        w = np.array([w[0], w[1], 0.0])
        w[:2] *= math.sqrt(1 - COS_I_MIN**2) / max(np.hypot(w[0], w[1]), 1e-300)
        w[2] = COS_I_MIN
    return w


def outgoing_dirs(wo) -> np.ndarray:
    a = np.asarray(wo, dtype=float)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != 3 or not np.all(np.isfinite(a)):
        raise WaveopticsError(f"outgoing directions must be finite (n, 3) unit vectors, got shape {a.shape}")
    n = np.linalg.norm(a, axis=1, keepdims=True)
    if np.any(n == 0):
        raise WaveopticsError("outgoing direction (0, 0, 0) is not allowed")
    return a / n


#: the incident cosine is floored here: at exactly θ_i = 90° the BRDF's 1/cos θ_i has no finite limit
COS_I_MIN = 1e-4
