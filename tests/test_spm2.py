"""The second-order (SPM2) mean field of a rough interface: the coherent reflection and transmission losses
(waveoptics.scatter.spm2, issue 33).

References held against the code:
* the rigorous Rayleigh-method grating solve of tests/rr_grating.py (Maxwell's boundary conditions with Bessel
  harmonics, solved at a finite amplitude, nothing of the library): its specular losses ΔR₀, ΔT₀ of one grating
  (conical mounts, air → glass, glass → air beyond the critical angle, evanescent ±1 orders) against the kernels,
  and integrated over a Gaussian PSD (ℓ = 1 µm and 0.3 µm) and an ABC PSD against the random surface's losses,
  reflected and transmitted shares separately, s and p;
* the optical theorem: ΔR + ΔT equals the first-order scatter TIS_R + TIS_T of
  :mod:`waveoptics.scatter.transmission` (Elson's dipole sheet integrated over the directions, a different route);
* reciprocity of the coherent transmittance: T̄ from air at θ₁ equals T̄ from glass at θ₂ (the Snell pair).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from rr_grating import integrated_losses, specular_losses
from waveoptics.errors import FieldError
from waveoptics.scatter import coherent_losses, rr_tis_reflection, rr_tis_transmission, spm2_kernel
from waveoptics.surfaces import PSDModel

LAM_NM = 500.0
LAM = LAM_NM * 1e-9
TOL_GRATING = 1e-5     # kernels vs the rigorous grating at k a = 1e-3 (its O((k a)²) terms: measured ≤ 2.5e-6)
TOL_RANDOM = 2e-2      # the brief's target; the reference's own quadrature (20 × 14 nodes, no cut at the Rayleigh
#                        anomalies) is the larger error: measured ≤ 1.3e-2 here, ≤ 3.8e-3 at 56 × 40 nodes
TOL_THEOREM = 1e-3     # ΔR + ΔT vs TIS_R + TIS_T (measured ≤ 1.5e-5 at the default nodes)
TOL_RECIPROCITY = 1e-3  # T̄ from either side (measured ≤ 1e-9)
REF_NODES = (20, 14)

# (n_i, n_o, θ_i in the incidence medium, deg): the brief's angles, from air and from glass (60°: beyond θ_c)
CASES = [(1.0, 1.5, 20.0), (1.0, 1.5, 50.0), (1.0, 1.5, 70.0), (1.0, 1.5, 85.0), (1.5, 1.0, 20.0),
         (1.5, 1.0, 40.0), (1.5, 1.0, 60.0)]


def _wi(th):
    t = math.radians(th)
    return np.array([math.sin(t), 0.0, math.cos(t)])


class TaperedABC:
    """ABC PSD A / (1 + (B f)²)^{C/2} rolled off by exp(−(f / f_t)²) so that the reference grid of
    :func:`integrated_losses` (|f| ≤ 4 f_t) holds all of it; σ by quadrature."""

    def __init__(self, A, B, C, f_t):
        self.A, self.B, self.C, self.f_t = A, B, C, f_t
        self.length_scale = B / (2 * math.pi)
        self.sigma = math.sqrt(integrate.quad(lambda f: 2 * math.pi * f * self.S(f), 0, 40 * f_t, limit=200)[0])

    def S(self, f):
        f = np.asarray(f, dtype=float)
        return self.A / (1 + (self.B * f) ** 2) ** (self.C / 2) * np.exp(-(f / self.f_t) ** 2)


# (n_i, n_o, θ_i, grating |K| / k₀, azimuth of K from the plane of incidence, deg)
GRATINGS = [(1.0, 1.5, 30.0, 0.7, 17.0), (1.0, 1.5, 70.0, 1.9, 40.0), (1.0, 1.5, 50.0, 0.3, 0.0),
            (1.5, 1.0, 25.0, 3.0, 100.0), (1.5, 1.0, 60.0, 1.2, 10.0), (1.5, 1.0, 35.0, 0.4, 150.0)]


@pytest.mark.parametrize("case", GRATINGS)
def test_kernels_are_the_rigorous_grating_loss(case):
    """One grating a cos(K·r): the specular amplitudes change by a² [P(K) + P(−K) + D/4]; the losses
    −2 Re(r₀* Δr) and −2 (γ₂/γ₁) Re(t₀* Δt) per a²/4 against the rigorous solve (specular_losses)."""
    n_i, n_o, th, kap, psi = case
    k0 = 2 * math.pi / LAM
    K = np.array([[kap * math.cos(math.radians(psi)), kap * math.sin(math.radians(psi))]])
    kx = -n_i * math.sin(math.radians(th))             # the incident lateral wave vector is −n_i ω_i,xy
    plus, minus = spm2_kernel(kx, K, n_i, n_o), spm2_kernel(kx, -K, n_i, n_o)
    g1, g2 = plus["g"]
    cross = (g2.real / g1.real) if abs(g2.imag) < 1e-12 else 0.0
    for j, pol in enumerate("sp"):
        x0, P, D = plus[pol]
        dx = [4 * k0 ** 2 * (P[i][0] + minus[pol][1][i][0] + D[i] / 4) for i in range(4)]
        dR = -2 * np.real(np.conj(x0[j]) * dx[j])
        dT = -2 * cross * np.real(np.conj(x0[j + 2]) * dx[j + 2])
        ref = specular_losses(n_i, n_o, _wi(th), K[0, 0] / LAM, K[0, 1] / LAM, LAM, pol, ka=1e-3)
        scale = abs(ref[0]) + abs(ref[1])
        assert abs(dR - ref[0]) < TOL_GRATING * scale and abs(dT - ref[1]) < TOL_GRATING * scale, (pol, dR, dT, ref)


@pytest.mark.parametrize("ell", [1e-6, 0.3e-6])
@pytest.mark.parametrize("n_i, n_o, th", CASES)
def test_random_surface_losses_against_rigorous_grating(ell, n_i, n_o, th):
    """Gaussian PSD (σ = 1 nm): ΔR and ΔT of s and p light, each against ∫ S(f) L(f) d²f of the rigorous grating
    losses L (the Debye-Waller split this replaces was 17 % off in ΔR at 70° from air, ℓ = 1 µm)."""
    psd = PSDModel("gaussian", 1e-9, T=ell)
    got = coherent_losses(math.cos(math.radians(th)), n_i, n_o, psd, LAM_NM)
    for pol in "sp":
        ref = integrated_losses(n_i, n_o, _wi(th), psd.S, psd.T, LAM, pol, *REF_NODES)
        assert got["dR"][pol] == pytest.approx(ref[0], rel=TOL_RANDOM), (pol, "R")
        if ref[1] == 0.0:                               # beyond the critical angle: no transmitted light
            assert got["dT"][pol] == 0.0 and got["T0"][pol] == 0.0
        else:
            assert got["dT"][pol] == pytest.approx(ref[1], rel=TOL_RANDOM), (pol, "T")


@pytest.mark.parametrize("n_i, n_o, th", [(1.0, 1.5, 50.0), (1.5, 1.0, 30.0)])
def test_abc_losses_against_rigorous_grating(n_i, n_o, th):
    """An ABC PSD (B = 1 µm, C = 3: a slow f⁻³ tail, with evanescent ±1 orders of most of its σ²) rolled off
    above 1.3 µm⁻¹, against the rigorous grating losses integrated over it."""
    psd = TaperedABC(1e-30, 1e-6, 3.0, 1 / (math.pi * 0.25e-6))
    got = coherent_losses(math.cos(math.radians(th)), n_i, n_o, psd, LAM_NM)
    for pol in "sp":
        ref = integrated_losses(n_i, n_o, _wi(th), psd.S, 0.25e-6, LAM, pol, *REF_NODES)
        assert got["dR"][pol] == pytest.approx(ref[0], rel=TOL_RANDOM), (pol, "R")
        assert got["dT"][pol] == pytest.approx(ref[1], rel=TOL_RANDOM), (pol, "T")


@pytest.mark.parametrize("psd", [PSDModel("gaussian", 2e-9, T=0.3e-6), PSDModel("gaussian", 2e-9, T=1e-6),
                                 PSDModel("abc", 2e-9, B=2e-6, C=2.5)], ids=["gauss0.3", "gauss1", "abc2.5"])
def test_optical_theorem(psd):
    """ΔR + ΔT = TIS_R + TIS_T per polarization (the first-order scatter of scatter.transmission integrated over
    the directions), from air and from glass, below and beyond the critical angle."""
    for n_i, n_o, th in [(1.0, 1.5, 35.0), (1.0, 1.5, 80.0), (1.5, 1.0, 25.0), (1.5, 1.0, 55.0)]:
        above = n_i == 1.0
        n1, n2 = (n_i, n_o) if above else (n_o, n_i)
        got = coherent_losses(math.cos(math.radians(th)), n_i, n_o, psd, LAM_NM)
        for pol in "sp":
            tis = (rr_tis_reflection(th, LAM_NM, psd, n1, n2, pol, from_above=above, method="hemisphere")
                   + rr_tis_transmission(th, LAM_NM, psd, n1, n2, pol, from_above=above, method="hemisphere"))
            assert got["dR"][pol] + got["dT"][pol] == pytest.approx(tis, rel=TOL_THEOREM), (n_i, th, pol)


@pytest.mark.parametrize("ell", [1e-6, 0.3e-6])
def test_coherent_transmittance_is_reciprocal(ell):
    """T̄ = T₀ − ΔT from air at θ₁ equals T̄ from glass at θ₂ with sinθ₁ = 1.5 sinθ₂, per polarization (the flat
    T₀ agree to rounding; the losses are what is tested)."""
    psd = PSDModel("gaussian", 2e-9, T=ell)
    for th1 in (15.0, 50.0, 75.0):
        th2 = math.degrees(math.asin(math.sin(math.radians(th1)) / 1.5))
        a = coherent_losses(math.cos(math.radians(th1)), 1.0, 1.5, psd, LAM_NM)
        b = coherent_losses(math.cos(math.radians(th2)), 1.5, 1.0, psd, LAM_NM)
        for pol in "sp":
            assert a["T0"][pol] == pytest.approx(b["T0"][pol], rel=1e-12)
            assert a["dT"][pol] == pytest.approx(b["dT"][pol], rel=TOL_RECIPROCITY), (th1, pol)


def test_bad_inputs():
    psd = PSDModel("gaussian", 1e-9, T=1e-6)
    with pytest.raises(FieldError, match="mu"):
        coherent_losses(0.0, 1.0, 1.5, psd, LAM_NM)
    with pytest.raises(FieldError, match="n_o"):
        coherent_losses(0.5, 1.0, -1.5, psd, LAM_NM)
    with pytest.raises(FieldError, match="wavelength_nm"):
        coherent_losses(0.5, 1.0, 1.5, psd, 0.0)


def test_normal_incidence_has_no_polarization():
    """At μ = 1 s and p are the same light: equal losses, from either side (to the azimuthal quadrature: ≤ 4e-7)."""
    psd = PSDModel("gaussian", 2e-9, T=0.5e-6)
    for n_i, n_o in ((1.0, 1.5), (1.5, 1.0)):
        c = coherent_losses(1.0, n_i, n_o, psd, LAM_NM)
        assert c["dR"]["s"] == pytest.approx(c["dR"]["p"], rel=1e-5)
        assert c["dT"]["s"] == pytest.approx(c["dT"]["p"], rel=1e-5)


@pytest.mark.parametrize("n_i, n_o, th", [(1.0, 1.5, 40.0), (1.5, 1.0, 25.0), (1.5, 1.0, 70.0)])
def test_slow_psd_tail_converges(n_i, n_o, th):
    """ABC with C = 2.2 (∫ S |f| d²f infinite): the p kernels grow as |K| cosψ, which the azimuth cancels; the
    losses converge (default nodes against 4 times as many in each direction) and keep the optical theorem."""
    psd = PSDModel("abc", 2e-9, B=2e-6, C=2.2)
    mu = math.cos(math.radians(th))
    a = coherent_losses(mu, n_i, n_o, psd, LAM_NM)
    b = coherent_losses(mu, n_i, n_o, psd, LAM_NM, nodes=(48, 40))
    above = n_i == 1.0
    n1, n2 = (n_i, n_o) if above else (n_o, n_i)
    for pol in "sp":
        total = b["dR"][pol] + b["dT"][pol]
        assert abs(a["dR"][pol] - b["dR"][pol]) < 1e-4 * total and abs(a["dT"][pol] - b["dT"][pol]) < 1e-4 * total
        tis = (rr_tis_reflection(th, LAM_NM, psd, n1, n2, pol, from_above=above)
               + rr_tis_transmission(th, LAM_NM, psd, n1, n2, pol, from_above=above))
        assert total == pytest.approx(tis, rel=TOL_THEOREM), (pol, total, tis)
