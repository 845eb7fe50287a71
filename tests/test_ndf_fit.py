"""The α of any NDF that matches a surface's slopes (issue 16): the median slope of each NDF against a quadrature
of D written here (scipy.integrate.quad over θ_m), the closed forms of GGX and Beckmann, and split_scales on a
Gaussian surface, whose slopes are Beckmann's law exactly."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from waveoptics import brdf, surfaces
from waveoptics.brdf import twoscale


def cdf_by_quad(ndf, alpha, t, shape=None):
    """∫_{θ_m ≤ atan t} D(m) cos θ_m dω_m, the projected facet area within slope magnitude t."""
    def f(theta):
        m = np.array([[math.sin(theta), 0.0, math.cos(theta)]])
        return float(brdf.D(m, alpha, ndf=ndf, ndf_shape=shape)[0]) * math.cos(theta) * math.sin(theta) * 2 * math.pi
    return integrate.quad(f, 0.0, math.atan(t), limit=400, epsabs=1e-12, epsrel=1e-10)[0]


@pytest.mark.parametrize("ndf,shape", [("ggx", None), ("beckmann", None), ("epd", 0.6), ("epd", 2.0),
                                       ("sgd", 0.8), ("abc", 2.5), ("blinn-phong", None)])
@pytest.mark.parametrize("t", [0.05, 0.3])
def test_median_slope_of_every_ndf(ndf, shape, t):
    a = brdf.alpha_for_median_slope(ndf, t, shape)
    assert cdf_by_quad(ndf, a, t, shape) == pytest.approx(0.5, abs=2e-5)


def test_closed_forms():
    assert brdf.alpha_for_median_slope("ggx", 0.17) == pytest.approx(0.17)
    assert brdf.alpha_for_median_slope("beckmann", 0.17) == pytest.approx(0.17 / math.sqrt(math.log(2)))


def test_split_scales_maps_gaussian_slopes_to_each_ndf():
    """Gaussian slopes: Beckmann's rms α, EPD with p = 1 (Beckmann's law) from the median within 3 %, GGX's median
    α = √ln2 × Beckmann's (the same median slope)."""
    hf = surfaces.generate("gaussian", sigma="100nm", corr_length="3um", size="60um", samples=512, seed=1)
    a_b = twoscale.split_scales(hf, [550.0], ndf="beckmann")[0].alpha
    a_e = twoscale.split_scales(hf, [550.0], ndf="epd", ndf_shape=1.0)[0].alpha
    a_g = twoscale.split_scales(hf, [550.0], ndf="ggx")[0].alpha
    assert a_e == pytest.approx(a_b, rel=0.03)
    assert a_g == pytest.approx(math.sqrt(math.log(2)) * a_b, rel=0.03)
