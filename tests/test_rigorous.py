"""The Rayleigh-Fourier reference for sinusoidal gratings (issue 13), validated as a rigorous solver must be: the
Fresnel coefficients of a flat surface (written here), energy conservation on a lossless grating, reciprocity of
the efficiencies, convergence in the number of orders, and the refusal beyond the Rayleigh hypothesis."""
from __future__ import annotations

import math

import numpy as np
import pytest

from waveoptics.scatter.rigorous import rayleigh_fourier

GLASS = 2.25
AL = (0.96 + 6.69j) ** 2       # aluminium near 550 nm (Rakić 1995)


@pytest.mark.parametrize("eps", [GLASS, AL])
@pytest.mark.parametrize("theta", [0.0, 35.0, 70.0])
def test_flat_surface_gives_fresnel(eps, theta):
    c, s = math.cos(math.radians(theta)), math.sin(math.radians(theta))
    g = np.sqrt(complex(eps) - s * s)
    rs = abs((c - g) / (c + g)) ** 2
    rp = abs((eps * c - g) / (eps * c + g)) ** 2
    for pol, want in (("s", rs), ("p", rp)):
        r = rayleigh_fourier(550.0, 2e-6, 0.0, theta, eps, pol)
        assert r.order(0) == pytest.approx(want, rel=1e-10)
        assert np.sum(r.reflected) == pytest.approx(want, rel=1e-10)


@pytest.mark.parametrize("pol", ["s", "p"])
@pytest.mark.parametrize("period_um,amp_nm,theta", [(2.0, 100.0, 30.0), (1.0, 50.0, 0.0), (4.0, 250.0, 60.0)])
def test_lossless_grating_conserves_energy(pol, period_um, amp_nm, theta):
    r = rayleigh_fourier(633.0, period_um * 1e-6, amp_nm * 1e-9, theta, GLASS, pol)
    assert np.sum(r.reflected) + np.sum(r.transmitted) == pytest.approx(1.0, abs=1e-9)
    assert np.count_nonzero(r.reflected > 1e-6) > 2          # a real grating, not a mirror


@pytest.mark.parametrize("pol", ["s", "p"])
def test_efficiencies_are_reciprocal(pol):
    """Order m at θ has the efficiency of order −m lit from that order's direction (reciprocity; Petit 1980)."""
    lam, d, a = 550.0, 2e-6, 80e-9
    r = rayleigh_fourier(lam, d, a, 20.0, AL, pol)
    for m in (-2, -1, 1):
        th = r.theta_deg[list(r.orders).index(m)]
        back = rayleigh_fourier(lam, d, a, abs(th), AL, pol)
        mm = -m if th >= 0 else m
        assert back.order(mm) == pytest.approx(r.order(m), rel=1e-7), m


def test_converged_in_the_number_of_orders():
    a = rayleigh_fourier(550.0, 2e-6, 100e-9, 30.0, AL, "p")
    b = rayleigh_fourier(550.0, 2e-6, 100e-9, 30.0, AL, "p", n_orders=40)
    for m in range(-4, 2):
        assert a.order(m) == pytest.approx(b.order(m), abs=1e-9)


def test_refuses_beyond_the_rayleigh_hypothesis():
    with pytest.raises(ValueError, match="K a = 0.628 > 0.448"):
        rayleigh_fourier(550.0, 1e-6, 100e-9, 0.0, AL, "s")


def test_refuses_a_rayleigh_anomaly():
    with pytest.raises(ValueError, match="Rayleigh anomaly"):
        rayleigh_fourier(550.0, 3 * 550e-9, 10e-9, 0.0, AL, "s")
