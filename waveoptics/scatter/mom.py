"""A rigorous reference for 1-D random rough surfaces: the method of moments (boundary integral equations).

The surface z = h(x) (ridges along y) separates vacuum (above, wavenumber k) from a medium of refractive index n
(below, k₂ = n k), or bounds a perfect conductor. ψ is E_y (s, TE) or H_y (p, TM); the time factor is e^{−iωt} and
the incident wave comes from above towards +x, as in :mod:`waveoptics.scatter.rigorous`. All lengths are in
wavelengths (λ = 1, k = 2π). With the unnormalized normal N = (−h′, 1), φ(x) = ∂ψ/∂N = (−h′∂ₓ + ∂_z)ψ on the
surface and G_j = (i/4) H₀⁽¹⁾(k_j r), Green's theorem in each medium, taken to the surface (Maradudin et al.
1990), gives

    ½ ψ(x) − P∫ dx′ [ψ(x′) ∂_{N′}G₁ − G₁ φ(x′)] = ψ_inc(x, h(x))
    ½ ψ(x) + P∫ dx′ [ψ(x′) ∂_{N′}G₂ − κ G₂ φ(x′)] = 0,              κ = 1 (s) or n² (p),

and for a perfect conductor ∫ G₁ φ dx′ = ψ_inc (s, Dirichlet) or ½ψ − P∫ ψ ∂_{N′}G₁ dx′ = ψ_inc (p, Neumann)
(Thorsos 1988). ∂_{N′}G = −(ik/4) H₁⁽¹⁾(kR) [h(x′) − h(x) − h′(x′)(x′ − x)] / R.

Discretization (Nyström on N equally spaced points, Δx = λ / points_per_wavelength):

* medium 1 (and a medium 2 that is not strongly absorbing on the scale Δx): the midpoint rule with the
  logarithmic singularity of H₀ corrected to fifth order. G = a(u) ln|u| + b(u) with a(0) = −1/2π; the punctured
  trapezoidal rule misses Δx ln(Δx/2π) a(0)φ(0) (Navot 1961) and −ζ′(−2)Δx³(aφ)″(0), removed by the diagonal
  weight Δx [b(0) − ln(Δx/2π)/2π] and the Kapur-Rokhlin-type weights ζ′(−2)Δx at the two neighbours (the same
  correction is applied to the log part (k/2π) J₁(kR) N/R of ∂_{N′}G). The diagonal of the double layer is its
  limit Δx h″/(4π(1 + h′²)) (as in Maradudin et al. 1990);
* a strongly absorbing medium 2 (a metal: Im k₂ Δx ≥ 1, where G₂ decays within a cell and the correction above
  does not hold): product integration: ψ and φ are interpolated quadratically through three neighbouring nodes,
  the surface is its local Taylor parabola, and each cell's integral of G₂ and ∂_{N′}G₂ against 1, u, u² is done
  by Gauss-Legendre quadrature (the self cell with u = s³ to absorb the logarithm), over the band of cells where
  |G₂| > 10⁻¹⁰ of its value at one cell (beyond: e^{−Im k₂ r} < 10⁻¹⁰, left out).

Incident field: Thorsos' tapered plane wave (Thorsos 1988)

    ψ_inc = exp{ik(x sinθᵢ − z cosθᵢ)(1 + w)} exp{−(x + z tanθᵢ)²/g²},  w = [2(x + z tanθᵢ)²/g² − 1]/(kg cosθᵢ)²,

which satisfies the Helmholtz equation only approximately (the worse, the smaller kg cosθᵢ and the nearer
grazing) and carries the power (per unit length along y, through a horizontal line) P_inc = g √(π/2) cosθᵢ [1 − (1 + 2tan²θᵢ)/(2k²g²cos²θᵢ)]. Its angular
spectrum (1/(kg cosθᵢ) wide) must stay clear of grazing, kg cos²θᵢ ≫ 1: what reaches grazing runs along the
surface to its truncated ends. On a flat conductor at 70° the specular reflectance is off by 3·10⁻³ at
kg cos²θᵢ = 2.9 and by 6·10⁻⁵ at 7.3; below :data:`MIN_TAPER_PARAMETER` the request is refused. The surface must
also be several g long: at L = 5g (taper e^{−6.25} at the ends) the flat-surface reflectance is off by about
8·10⁻⁴, at L = 8g by less than 10⁻⁴ (3·10⁻⁸ on a conductor, 3·10⁻⁵ on aluminium in p; measured,
tests/test_mom.py and docs/validity-map.md).

Far field: ψ_sc → (i/4) √(2/(πkr)) e^{i(kr − π/4)} A(θₛ) with
A(θₛ) = ∫ dx e^{−ik(x sinθₛ + h cosθₛ)} [−ik(cosθₛ − h′ sinθₛ) ψ − φ]. The **scattering coefficient** (the 1-D
bistatic coefficient of Thorsos 1988; the in-plane BRDF times cosθₛ, per radian)

    σ(θₛ) = |A(θₛ)|² / (8π k P_inc)                       (dimensionless, per radian of θₛ)

is the power scattered into dθₛ over the incident power, so that ∫_{−π/2}^{π/2} σ dθₛ is the reflectance (the
albedo: 1 for a perfect conductor). θₛ is measured from the normal, positive towards +x: the specular direction
is θₛ = θᵢ. The 1-D BRDF is f = σ / cosθₛ (per radian). See docs/physics.md § 13.

Cost (one core, single-threaded BLAS, 10 points per wavelength, three incidences solved together, measured on
the shared development machine): a 40 λ surface takes about 0.07–0.15 s per realization for a perfect conductor
(400 unknowns), 0.2–0.4 s for glass and 0.25–0.5 s for aluminium (800 unknowns); a 100 λ surface 0.45 s for a
perfect conductor, 1.5 s for glass and 1.4 s for aluminium. The fill is O(N²) Bessel evaluations, the dense
solve O(N³); a multi-threaded BLAS on a loaded machine can be several times slower than one thread.

Known limit: the Neumann problem (p on a perfect conductor; also p on a metal, where roughness launches surface
plasmons) loses the waves that run along the truncated surface: 0.3–1 % of the energy at kℓ ≈ 3, falling as
about 1/L; Dirichlet (s) surfaces conserve energy to 10⁻⁴.

References
----------
.. [1] E. I. Thorsos, "The validity of the Kirchhoff approximation for rough surface scattering using a Gaussian
   roughness spectrum", J. Acoust. Soc. Am. 83(1), 78–92, 1988.
.. [2] A. A. Maradudin, T. Michel, A. R. McGurn, E. R. Méndez, "Enhanced backscattering of light from a random
   grating", Ann. Phys. 203, 255–307, 1990.
.. [3] E. I. Chaikina, A. G. Navarrete, E. R. Méndez, A. Martínez, A. A. Maradudin, "Coherent scattering by
   one-dimensional randomly rough metallic surfaces", Appl. Opt. 37(6), 1110–1121, 1998.
.. [4] J. Navot, "An extension of the Euler-Maclaurin summation formula to functions with a branch singularity",
   J. Math. Phys. 40, 271–276, 1961.
.. [5] S. Kapur, V. Rokhlin, "High-order corrected trapezoidal quadrature rules for singular functions",
   SIAM J. Numer. Anal. 34(4), 1331–1356, 1997.
"""
from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass

import numpy as np
from scipy import linalg, special

from ..errors import FieldError

__all__ = ["MIN_TAPER_PARAMETER", "MomRequest", "MomResult", "ProfileSolution", "gaussian_profile",
           "mom_scatter", "solve_profile", "thorsos_beam", "thorsos_incident_power"]

K = 2 * math.pi                       # wavenumber of vacuum in units of 1/λ
ZETA_PRIME_M2 = -0.030448457058393270  # ζ′(−2) = −ζ(3)/(4π²), the Δx³ term of the punctured trapezoidal rule
#: smallest k g cos²θᵢ accepted: the taper's error terms are of order 1/(k g cos²θᵢ)²
MIN_TAPER_PARAMETER = 2.0
_PRODUCT_ABSORPTION = 1.0             # Im k₂ Δx from which medium 2 is integrated by the product rule
_GL = np.polynomial.legendre.leggauss(12)


def thorsos_beam(x, z, theta_deg: float, beam_width_wl: float):
    """Thorsos' tapered incident wave ψ_inc(x, z) (module doc; Thorsos 1988), x, z in wavelengths.

    References
    ----------
    .. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988.
    """
    t = math.radians(theta_deg)
    g = beam_width_wl
    xi = np.asarray(x) + np.asarray(z) * math.tan(t)
    w = (2 * xi ** 2 / g ** 2 - 1) / (K * g * math.cos(t)) ** 2
    return np.exp(1j * K * (np.asarray(x) * math.sin(t) - np.asarray(z) * math.cos(t)) * (1 + w)
                  - xi ** 2 / g ** 2)


def thorsos_incident_power(theta_deg: float, beam_width_wl: float) -> float:
    """Power of the tapered wave through a horizontal line, in wavelengths (a unit plane wave carries cosθᵢ per
    unit length): g √(π/2) cosθᵢ [1 − (1 + 2tan²θᵢ)/(2k²g²cos²θᵢ)].

    References
    ----------
    .. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988.
    """
    t = math.radians(theta_deg)
    g = beam_width_wl
    return g * math.sqrt(math.pi / 2) * math.cos(t) * (
        1 - (1 + 2 * math.tan(t) ** 2) / (2 * (K * g * math.cos(t)) ** 2))


def gaussian_profile(n: int, dx_wl: float, rms_wl: float, corr_wl: float, rng):
    """A periodic Gaussian random profile of n points spaced dx_wl with correlation σ² exp(−τ²/ℓ²): (h, h′, h″).

    Spectral synthesis: white noise filtered by √(2π W(K)/Δx) with the two-sided PSD
    W(K) = σ²ℓ/(2√π) exp(−K²ℓ²/4), so that ⟨h²⟩ = Σ W ΔK = σ²; the derivatives are the same sum times iK, −K².

    References
    ----------
    .. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988.
    """
    kk = 2 * math.pi * np.fft.fftfreq(n, dx_wl)
    w = rms_wl ** 2 * corr_wl / (2 * math.sqrt(math.pi)) * np.exp(-(kk * corr_wl) ** 2 / 4)
    spec = np.fft.fft(rng.standard_normal(n)) * np.sqrt(2 * math.pi * w / dx_wl)
    return tuple(np.fft.ifft(spec * f).real for f in (1.0, 1j * kk, -kk ** 2))


def _hankels(k, kr):
    """H₀⁽¹⁾(kr), H₁⁽¹⁾(kr) (the fast real Bessel functions for a real wavenumber)."""
    if abs(np.imag(k)) == 0:
        kr = np.real(kr)
        return special.j0(kr) + 1j * special.y0(kr), special.j1(kr) + 1j * special.y1(kr)
    return special.hankel1(0, kr), special.hankel1(1, kr)


def _nystrom(k, x, h, dh, d2h, dx):
    """Single- and double-layer matrices S, D (weights included) by the corrected midpoint rule (module doc)."""
    X = x[None, :] - x[:, None]                       # x′ − x_m: columns are the sources
    Z = h[None, :] - h[:, None]
    R = np.hypot(X, Z)
    np.fill_diagonal(R, 1.0)                          # the diagonal is replaced below
    H0, H1 = _hankels(k, k * R)
    NR = (Z - dh[None, :] * X) / R
    S = dx * 0.25j * H0
    D = dx * (-0.25j * k) * H1 * NR
    gam = np.sqrt(1 + dh ** 2)
    b0 = 0.25j - (np.log(k * gam / 2) + np.euler_gamma) / (2 * math.pi)
    idx = np.arange(x.size)
    S[idx, idx] = dx * (b0 - math.log(dx / (2 * math.pi)) / (2 * math.pi)) + dx * ZETA_PRIME_M2 / math.pi
    D[idx, idx] = dx * d2h / (4 * math.pi * gam ** 2)
    for s in (-1, 1):                                 # Kapur-Rokhlin-type weights on the log part at ±Δx
        m = idx[max(0, -s):x.size - max(0, s)]
        r = R[m, m + s]
        aS = -_bessel(0, k * r) / (2 * math.pi)
        aD = k / (2 * math.pi) * _bessel(1, k * r) * NR[m, m + s]
        S[m, m + s] += dx * ZETA_PRIME_M2 * aS
        D[m, m + s] += dx * ZETA_PRIME_M2 * aD
    return S, D


def _bessel(order, z):
    return special.jv(order, z)


def _product(k, x, h, dh, d2h, dx):
    """S, D for a strongly absorbing medium by product integration over the band where G does not vanish."""
    n = x.size
    band = int(math.ceil(math.log(1e10) / (np.imag(k) * dx))) + 1
    t, wt = _GL
    u_reg, w_reg = t * dx / 2, wt * dx / 2
    s = (t + 1) / 2
    u_half = dx / 2 * s ** 3
    w_half = wt / 2 * 1.5 * dx * s ** 2
    u_self, w_self = np.concatenate([-u_half, u_half]), np.concatenate([w_half, w_half])
    S = np.zeros((n, n), complex)
    D = np.zeros((n, n), complex)
    for d in range(-min(band, n - 1), min(band, n - 1) + 1):
        m = np.arange(max(0, -d), min(n, n - d))
        c = m + d                                      # the source cell
        u, w = (u_self, w_self) if d == 0 else (u_reg, w_reg)
        xp = x[c, None] + u
        hp = h[c, None] + dh[c, None] * u + 0.5 * d2h[c, None] * u ** 2
        dhp = dh[c, None] + d2h[c, None] * u
        X = xp - x[m, None]
        Z = hp - h[m, None]
        R = np.hypot(X, Z)
        H0, H1 = _hankels(k, k * R)
        for kern, out in ((0.25j * H0, S), (-0.25j * k * H1 * (Z - dhp * X) / R, D)):
            i0, i1, i2 = ((kern * w * u ** p).sum(axis=1) for p in (0, 1, 2))
            inner = (c > 0) & (c < n - 1)              # end cells keep a constant (pulse) unknown
            out[m, c] += np.where(inner, i0 - i2 / dx ** 2, i0)
            mi, ci = m[inner], c[inner]
            out[mi, ci - 1] += -i1[inner] / (2 * dx) + i2[inner] / (2 * dx ** 2)
            out[mi, ci + 1] += i1[inner] / (2 * dx) + i2[inner] / (2 * dx ** 2)
    return S, D


def _layers(k, x, h, dh, d2h, dx):
    if np.imag(k) * dx >= _PRODUCT_ABSORPTION:
        return _product(k, x, h, dh, d2h, dx)
    if abs(k) * dx > math.pi / 2:
        raise FieldError(f"{{points_per_wavelength}} {1 / dx:g} gives fewer than 4 points per wavelength inside "
                         f"the medium (|n| = {abs(k) / K:.3g}); raise it", "points_per_wavelength")
    return _nystrom(k, x, h, dh, d2h, dx)


@dataclass(frozen=True)
class ProfileSolution:
    """The solution on one profile for several incidences.

    Attributes
    ----------
    theta_deg : (n_i,) degrees, incidences.
    scatter_deg : (n_s,) degrees, scattering angles θₛ (specular at θₛ = θᵢ).
    amplitude : (n_i, n_s) complex, far-field amplitude A(θₛ) (module doc), in wavelengths⁰ (λ = 1 units).
    sigma : (n_i, n_s), scattering coefficient σ(θₛ) = |A|²/(8πkP_inc), per radian.
    albedo : (n_i,), ∫ σ dθₛ over (−90°, 90°) by Gauss-Legendre quadrature: the reflectance.
    gl_amplitude : (n_i, n_gl) complex, A at the Gauss-Legendre angles ``gl_deg`` (weights ``gl_weights``, rad).
    incident_power : (n_i,), P_inc in wavelengths.
    psi, phi : (N, n_i) complex, ψ and ∂ψ/∂N on the nodes.
    """

    theta_deg: np.ndarray
    scatter_deg: np.ndarray
    amplitude: np.ndarray
    sigma: np.ndarray
    albedo: np.ndarray
    gl_deg: np.ndarray
    gl_weights: np.ndarray
    gl_amplitude: np.ndarray
    incident_power: np.ndarray
    psi: np.ndarray
    phi: np.ndarray


@functools.lru_cache(maxsize=8)
def _gauss_legendre(n):
    return special.roots_legendre(n)


def _far_field(x, h, dh, dx, psi, phi, theta_s):
    """A(θₛ) for every incidence: (n_i, n_s)."""
    s, c = np.sin(theta_s)[:, None], np.cos(theta_s)[:, None]
    E = np.exp(-1j * K * (x[None, :] * s + h[None, :] * c))
    A = -1j * K * c * (E @ psi) + 1j * K * s * (E @ (dh[:, None] * psi)) - E @ phi
    return (dx * A).T


def _check_beam(theta_deg, beam_width_wl, length_wl):
    for t in np.atleast_1d(theta_deg):
        if not -90 < t < 90:
            raise FieldError(f"{{theta_deg}} {t:g} is outside (−90, 90)", "theta_deg")
        tp = K * beam_width_wl * math.cos(math.radians(t)) ** 2
        if tp < MIN_TAPER_PARAMETER:
            raise FieldError(f"{{beam_width_wl}} {beam_width_wl:g} at θᵢ = {t:g}° gives k g cos²θᵢ = {tp:.3g} < "
                             f"{MIN_TAPER_PARAMETER:g}, where Thorsos' tapered wave is not a solution of the wave "
                             "equation; widen the beam (and the surface)", "beam_width_wl", "theta_deg")
    if length_wl < 4 * beam_width_wl * (1 - 1e-9):
        raise FieldError(f"{{length_wl}} {length_wl:g} is shorter than 4 beam widths ({4 * beam_width_wl:g}): the "
                         "taper would not vanish at the ends of the surface", "length_wl", "beam_width_wl")


def solve_profile(x_wl, h_wl, dh, d2h, theta_deg, polarization: str = "s", refractive_index=None,
                  beam_width_wl: float | None = None, scatter_deg=None) -> ProfileSolution:
    """Solve the boundary integral equations (module doc) on one profile for the incidences *theta_deg*.

    Parameters
    ----------
    x_wl : (N,) float, wavelengths
        Equally spaced nodes, centred on the beam (x = 0); spacing Δx = x[1] − x[0].
    h_wl, dh, d2h : (N,) float
        Heights h (wavelengths), slopes h′ and curvatures h″ (1/wavelength) at the nodes.
    theta_deg : float or sequence, degrees
        Incidences in (−90, 90), towards +x for θᵢ > 0 (the specular direction is θₛ = θᵢ).
    polarization : {'s', 'p'}
        s: ψ = E_y (TE); p: ψ = H_y (TM).
    refractive_index : complex or None
        n of the lower medium (n = n′ + iκ, κ ≥ 0); None for a perfect conductor.
    beam_width_wl : float, wavelengths, optional
        Taper g (default a quarter of the surface length).
    scatter_deg : sequence, degrees, optional
        θₛ at which A and σ are returned (default 179 angles from −89° to 89°).
    """
    x = np.asarray(x_wl, float)
    h, dh, d2h = (np.asarray(a, float) for a in (h_wl, dh, d2h))
    dx = float(x[1] - x[0])
    length = dx * x.size
    g = length / 4 if beam_width_wl is None else float(beam_width_wl)
    theta = np.atleast_1d(np.asarray(theta_deg, float))
    _check_beam(theta, g, length)
    if polarization not in ("s", "p"):
        raise FieldError(f"{{polarization}} {polarization!r} is not allowed here; use s or p", "polarization")
    ts = np.radians(np.linspace(-89, 89, 179) if scatter_deg is None else np.asarray(scatter_deg, float))
    rhs = np.stack([thorsos_beam(x, h, t, g) for t in theta], axis=1)
    S1, D1 = _layers(K, x, h, dh, d2h, dx)
    half = 0.5 * np.eye(x.size)
    if refractive_index is None:
        if polarization == "s":
            phi, psi = linalg.solve(S1, rhs), np.zeros_like(rhs)
        else:
            psi, phi = linalg.solve(half - D1, rhs), np.zeros_like(rhs)
    else:
        n = complex(refractive_index)
        if n.imag < 0:
            raise FieldError(f"{{refractive_index}} {n} has a negative extinction coefficient", "refractive_index")
        S2, D2 = _layers(K * n, x, h, dh, d2h, dx)
        kappa = 1.0 if polarization == "s" else n * n
        A = np.block([[half - D1, S1], [half + D2, -kappa * S2]])
        sol = linalg.solve(A, np.concatenate([rhs, np.zeros_like(rhs)]))
        psi, phi = sol[:x.size], sol[x.size:]
    p_inc = np.array([thorsos_incident_power(t, g) for t in theta])
    tg, wg = _gauss_legendre(int(K * length) + 64)
    amp = _far_field(x, h, dh, dx, psi, phi, ts)
    gl_amp = _far_field(x, h, dh, dx, psi, phi, tg * math.pi / 2)
    norm = 8 * math.pi * K * p_inc[:, None]
    albedo = (np.abs(gl_amp) ** 2 / norm) @ (wg * math.pi / 2)
    return ProfileSolution(theta, np.degrees(ts), amp, np.abs(amp) ** 2 / norm, albedo,
                           np.degrees(tg * math.pi / 2), wg * math.pi / 2, gl_amp, p_inc, psi, phi)


@dataclass(frozen=True)
class MomRequest:
    """A Monte-Carlo method-of-moments run on Gaussian-correlated 1-D surfaces. Lengths are in wavelengths.

    Attributes
    ----------
    rms_height_wl : float, wavelengths
        σ, the rms height.
    correlation_length_wl : float, wavelengths
        ℓ, the 1/e length of the Gaussian correlation σ² exp(−τ²/ℓ²).
    theta_deg : tuple of float, degrees
        Incidences (solved together on each realization).
    polarization : {'s', 'p'}
    refractive_index : complex or None
        n of the lower medium; None for a perfect conductor.
    length_wl : float, wavelengths
        L, the length of the surface.
    beam_width_wl : float, wavelengths, optional
        g, the taper (default L/4).
    points_per_wavelength : float
        Nodes per vacuum wavelength (10 is the usual choice).
    n_realizations : int
    seed : int
        Seed of ``numpy.random.default_rng``.
    scatter_deg : tuple of float, degrees, optional
        θₛ of the returned σ (default 179 angles from −89° to 89°).
    """

    rms_height_wl: float
    correlation_length_wl: float
    theta_deg: tuple = (0.0,)
    polarization: str = "s"
    refractive_index: complex | None = None
    length_wl: float = 40.0
    beam_width_wl: float | None = None
    points_per_wavelength: float = 10.0
    n_realizations: int = 10
    seed: int = 0
    scatter_deg: tuple | None = None

    def __post_init__(self):
        for name in ("rms_height_wl", "correlation_length_wl", "length_wl", "points_per_wavelength"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0) and not (
                    name == "rms_height_wl" and v == 0):
                raise FieldError(f"{{{name}}} {v!r} must be a positive number", name)
        if int(self.n_realizations) < 1:
            raise FieldError(f"{{n_realizations}} {self.n_realizations!r} must be at least 1", "n_realizations")


@dataclass(frozen=True)
class MomResult:
    """The Monte-Carlo mean of a :class:`MomRequest`.

    Attributes
    ----------
    theta_deg : (n_i,) degrees; scatter_deg : (n_s,) degrees (specular at θₛ = θᵢ).
    sigma, sigma_se : (n_i, n_s)
        Mean scattering coefficient ⟨σ(θₛ)⟩ (per radian; module doc) and its standard error over realizations.
    sigma_incoherent : (n_i, n_s)
        (M/(M−1)) (⟨|A|²⟩ − |⟨A⟩|²)/(8πkP_inc) for M realizations (unbiased; equal to sigma when M = 1);
        sigma_incoherent_se its standard error (the spread of the M terms (M/(M−1))|A_j − ⟨A⟩|² over √M);
        sigma_incoherent_samples (M, n_i, n_s) those terms (their mean is sigma_incoherent), for binned statistics.
    albedo, albedo_se : (n_i,)
        Mean reflectance ∫σ dθₛ and its standard error; albedo_incoherent: the same of sigma_incoherent.
    seconds_per_realization : float, s (fill, solve and far field).
    n_unknowns : int, the size of the dense system.
    taper_parameter : (n_i,), k g cos²θᵢ.
    """

    request: MomRequest
    theta_deg: np.ndarray
    scatter_deg: np.ndarray
    sigma: np.ndarray
    sigma_se: np.ndarray
    sigma_incoherent: np.ndarray
    sigma_incoherent_se: np.ndarray
    sigma_incoherent_samples: np.ndarray
    albedo: np.ndarray
    albedo_se: np.ndarray
    albedo_incoherent: np.ndarray
    seconds_per_realization: float
    n_unknowns: int
    taper_parameter: np.ndarray


def _incoherent(amps, m):
    """Per-realization terms (M/(M−1))|A_j − ⟨A⟩|² (first axis) whose mean is the unbiased incoherent
    (M/(M−1))(⟨|A|²⟩ − |⟨A⟩|²); |A_j|² when M = 1."""
    if m == 1:
        return np.abs(amps) ** 2
    return m / (m - 1) * np.abs(amps - np.mean(amps, axis=0)) ** 2


def mom_scatter(request: MomRequest) -> MomResult:
    """Mean scattering coefficient of Gaussian surfaces over ``request.n_realizations`` seeded realizations.

    See the module docstring for the equations, the normalization of σ and the cost.

    References
    ----------
    .. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988.
    .. [2] A. A. Maradudin, T. Michel, A. R. McGurn, E. R. Méndez, Ann. Phys. 203, 255–307, 1990.
    """
    r = request
    n = int(round(r.length_wl * r.points_per_wavelength))
    dx = r.length_wl / n
    x = -r.length_wl / 2 + (np.arange(n) + 0.5) * dx
    g = r.length_wl / 4 if r.beam_width_wl is None else r.beam_width_wl
    rng = np.random.default_rng(r.seed)
    amps, gl_amps, sig, alb = [], [], [], []
    t0 = time.perf_counter()
    for _ in range(int(r.n_realizations)):
        h, dh, d2h = gaussian_profile(n, dx, r.rms_height_wl, r.correlation_length_wl, rng)
        sol = solve_profile(x, h, dh, d2h, r.theta_deg, r.polarization, r.refractive_index, g, r.scatter_deg)
        amps.append(sol.amplitude)
        gl_amps.append(sol.gl_amplitude)
        sig.append(sol.sigma)
        alb.append(sol.albedo)
    seconds = (time.perf_counter() - t0) / r.n_realizations
    m = len(sig)
    sig, alb = np.array(sig), np.array(alb)
    norm = 8 * math.pi * K * sol.incident_power[:, None]
    se = (lambda a: np.std(a, axis=0, ddof=1) / math.sqrt(m) if m > 1 else np.full(a.shape[1:], np.nan))
    inc = _incoherent(np.array(amps), m) / norm
    inc_gl = _incoherent(np.array(gl_amps), m).mean(axis=0) / norm
    return MomResult(r, sol.theta_deg, sol.scatter_deg, sig.mean(axis=0), se(sig), inc.mean(axis=0), se(inc), inc,
                     alb.mean(axis=0), se(alb), inc_gl @ sol.gl_weights, seconds,
                     n * (1 if r.refractive_index is None else 2), K * g * np.cos(np.radians(sol.theta_deg)) ** 2)
