"""A rigorous reference for shallow 1-D gratings: the Rayleigh-Fourier method for a sinusoidal profile.

The grating z = h(x) = a cos(Kx), K = 2π/d, separates vacuum (above) from a substrate of relative permittivity ε.
Light of wavenumber k = 2π/λ comes from above at θ in the x–z plane, s (TE: E along the grooves, y) or p (TM:
H along y) polarized. With α_n = k sinθ + nK, β_n = √(k² − α_n²) and γ_n = √(εk² − α_n²) (Im ≥ 0) the field is

    above:  u = e^{i(α_0 x − β_0 z)} + Σ R_n e^{i(α_n x + β_n z)},      below:  u = Σ T_n e^{i(α_n x − γ_n z)}

(the Rayleigh hypothesis: these expansions hold down to the surface, true for a sinusoid while Ka < 0.448,
Millar 1971). u and ∂u/∂N (TE) or u and ε⁻¹ ∂u/∂N (TM) are continuous on z = h(x), N = (−h′, 1). Projected onto
e^{iα_m x} over a period, with ⟨e^{i(n−m)Kx} e^{ibh}⟩ = i^{m−n} J_{m−n}(ab) =: M_mn(b) and the normal derivative
of each plane wave ⟨e^{−iα_m x} ∂_N e^{i(α_n x + bz)}⟩ = i (k_j² − α_n α_m) / b · M_mn(b) (integration by parts of
h′e^{ibh}), the conditions are 2(2N + 1) linear equations in R_n, T_n. The efficiencies are
η_n^R = |R_n|² Re β_n / β_0 and η_n^T = |T_n|² Re(γ_n / ε^τ) / β_0 (τ = 0 for TE, 1 for TM); for a lossless
substrate they add up to 1.

Checked (tests/test_rigorous.py): a flat surface gives the Fresnel coefficients; a lossless dielectric grating
conserves energy (Σ η = 1 to 1e-9); the efficiencies are reciprocal (order m at θ equals order −m at the
diffracted angle, to 1e-7). docs/validity.md compares the Kirchhoff, GHS and Rayleigh-Rice efficiencies with it.

References
----------
.. [1] Lord Rayleigh, "On the dynamical theory of gratings", Proc. R. Soc. A 79, 399–416, 1907.
.. [2] R. F. Millar, "On the Rayleigh assumption in scattering by a periodic surface II", Proc. Camb. Phil. Soc.
   69, 217–225, 1971 (validity: Ka < 0.448 for a sinusoid).
.. [3] R. Petit (ed.), *Electromagnetic Theory of Gratings*, Springer 1980, ch. 3 (the Rayleigh method).
.. [4] D. Maystre, "Rigorous vector theories of diffraction gratings", Progress in Optics 21, 1–67, 1984.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import special

from ..errors import FieldError

__all__ = ["RAYLEIGH_HYPOTHESIS_KA", "GratingEfficiencies", "rayleigh_fourier"]

#: largest K a (K = 2π/period, a the amplitude) at which the Rayleigh expansion of a sinusoid converges (Millar)
RAYLEIGH_HYPOTHESIS_KA = 0.448


@dataclass(frozen=True)
class GratingEfficiencies:
    """Orders n, their directions θ_n (degrees from the normal, towards +x; NaN if evanescent) and the reflected and
    transmitted efficiencies (shares of the incident power; 0 for evanescent orders)."""

    orders: np.ndarray
    theta_deg: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray

    def order(self, n: int) -> float:
        """Reflected efficiency of order *n*."""
        return float(self.reflected[list(self.orders).index(n)])


def _sqrt_up(z):
    """√z on the branch with Im ≥ 0 (Re ≥ 0 for real positive z): outgoing or decaying waves."""
    r = np.sqrt(np.asarray(z, dtype=np.complex128))
    return np.where(r.imag < 0, -r, r)


def rayleigh_fourier(wavelength_nm: float, period_m: float, amplitude_m: float, theta_deg: float, eps,
                     polarization: str = "s", n_orders: int | None = None) -> GratingEfficiencies:
    """Efficiencies of the sinusoidal grating a cos(2πx/d) by the Rayleigh-Fourier method (module doc).

    Parameters
    ----------
    wavelength_nm : float, nm
    period_m, amplitude_m : float, m
        Period d and amplitude a (half the peak-to-valley depth).
    theta_deg : float, degrees
        Incidence in the plane across the grooves, in [0, 90).
    eps : complex
        Relative permittivity of the substrate, (n + iκ)².
    polarization : {'s', 'p'}
        TE (E along the grooves) or TM.
    n_orders : int, optional
        Orders −N..N kept (default: the propagating ones plus 12 evanescent each side).
    """
    k = 2 * math.pi / (wavelength_nm * 1e-9)
    K = 2 * math.pi / period_m
    if polarization not in ("s", "p"):
        raise FieldError(f"{{polarization}} {polarization!r} is not allowed here; use s or p", "polarization")
    if K * amplitude_m > RAYLEIGH_HYPOTHESIS_KA:
        raise FieldError(f"{{amplitude_m}} {amplitude_m:g} m with period {period_m:g} m gives K a = "
                         f"{K * amplitude_m:.3g} > {RAYLEIGH_HYPOTHESIS_KA}, where the Rayleigh expansion "
                         "diverges (Millar 1971)", "amplitude_m")
    a0 = k * math.sin(math.radians(theta_deg))
    N = n_orders if n_orders is not None else int(math.ceil(2 * k / K)) + 12
    n = np.arange(-N, N + 1)
    alpha = a0 + n * K
    e = complex(eps)
    beta = _sqrt_up(k * k - alpha ** 2)
    gamma = _sqrt_up(e * k * k - alpha ** 2)
    b0 = beta[N]
    grazing = np.abs(beta) < 1e-9 * k
    if np.any(grazing):   # a Rayleigh anomaly: an order leaves along the surface and the expansion is singular
        raise FieldError(f"order {int(n[grazing][0])} leaves along the surface at θ = {theta_deg:g}° (a Rayleigh "
                         "anomaly, where the Rayleigh-Fourier expansion is singular); move θ or the period slightly",
                         "theta_deg")
    m = n[:, None]
    p = m - n[None, :]                                                      # m − n

    def M(b):                                                              # (m, n): i^{m−n} J_{m−n}(a b_n)
        return (1j ** p) * special.jv(p, amplitude_m * np.broadcast_to(b, (n.size,))[None, :])

    def dN(k2, b):                                                         # i (k² − α_n α_m) / b_n
        return 1j * (k2 - alpha[None, :] * alpha[:, None]) / b[None, :]

    tau = 1.0 if polarization == "s" else 1.0 / e                          # TM: ε⁻¹ ∂u/∂N below
    Mi = M(np.full(n.size, -b0))[:, N]                                     # incident wave, n = 0
    dMi = (1j * (k * k - alpha[N] * alpha) / (-b0)) * Mi
    A = np.zeros((2 * n.size, 2 * n.size), dtype=np.complex128)
    A[:n.size, :n.size] = M(beta)
    A[:n.size, n.size:] = -M(-gamma)
    A[n.size:, :n.size] = dN(k * k, beta) * M(beta)
    A[n.size:, n.size:] = -tau * dN(e * k * k, -gamma) * M(-gamma)
    rhs = -np.concatenate([Mi, dMi])
    x = np.linalg.solve(A, rhs)
    R, T = x[:n.size], x[n.size:]
    prop = np.abs(beta.imag) < 1e-12 * k
    eta_r = np.where(prop, np.abs(R) ** 2 * beta.real / b0.real, 0.0)
    eta_t = np.abs(T) ** 2 * np.real(gamma * tau) / b0.real
    eta_t = np.where(np.abs(gamma.imag) < 1e-12 * k, eta_t, 0.0)
    with np.errstate(invalid="ignore"):
        th = np.where(prop, np.degrees(np.arcsin(np.clip(alpha / k, -1, 1))), np.nan)
    return GratingEfficiencies(orders=n, theta_deg=th, reflected=eta_r, transmitted=eta_t)
