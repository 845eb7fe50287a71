"""Issue 28 (the energy guard acts only in a documented domain, with a warning): a grating carried by the paraxial
route at an incidence where all its orders are evanescent but propagate for tilted micro facets. The route shifts
the macro incidence's lobe, which then holds only the window's leakage (2e-7 of the light), to every facet and
scales it by up to 3.6e5: its diffracted light follows no grid (64² cells: 1.21x the budget, the guard removed
17.6 %). It must say so in one line; where an order propagates at the macro incidence it must not, and the guard
stays idle. A table of lobes over incidence says the guard once, not once per incidence.

Reference: the grating equation written here (order m leaves at u = u_i + m λ/Λ, v = v_i; it propagates where
u² + v² < 1), not the library's shares.
"""
import warnings

import numpy as np
import pytest

from waveoptics import brdf, surfaces
from waveoptics.brdf import Micro, Nano
from waveoptics.scatter.grid import DirectionGrid

LAM, PERIOD = 550.0, 500.0
GRATING = surfaces.sinusoid(20e-9, PERIOD * 1e-9, 128 * LAM / 4 * 1e-9, 128)   # grating vector along x
GRID = DirectionGrid.hemisphere(32)


def _propagating_orders(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    ui, vi = np.sin(t) * np.cos(p), np.sin(t) * np.sin(p)
    return [m for m in (-2, -1, 1, 2) if (ui + m * LAM / PERIOD) ** 2 + vi ** 2 < 1]


def _evaluate(theta_deg, phi_deg):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    wi = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        L = brdf.evaluate(wi, [LAM], "aluminium", Micro(alpha=0.05, ndf="beckmann"), Nano(surface=GRATING), GRID,
                          kd=0.0)
    assert L.info["facet_integration"] == "paraxial"
    return L, [str(w.message) for w in caught if str(w.message).startswith("paraxial route")]


@pytest.mark.parametrize("theta", [0.0, 10.0])
def test_evanescent_orders_at_the_macro_incidence_warn(theta):
    assert _propagating_orders(theta, 90.0) == []   # every order evanescent at the macro incidence
    _, lines = _evaluate(theta, 90.0)
    assert len(lines) == 1 and "evanescent" in lines[0], lines


def test_propagating_order_does_not_warn():
    assert _propagating_orders(30.0, 0.0) == [-1]
    L, lines = _evaluate(30.0, 0.0)
    assert lines == []
    assert L.info["diffraction_energy_scale"] == [1.0]   # the energy guard idle


def test_a_table_says_the_energy_guard_once():
    """A table of lobes over incidence (the sphere's) says the guard once for all of them: on 32² cells it acts at
    78° (the documented coarse-grid case; none on 40²-128², measured) at two of the four azimuths."""
    from waveoptics.brdf import TabulatedTwoScaleBRDF
    from waveoptics.materials import get_material

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        T = TabulatedTwoScaleBRDF(material=get_material("aluminium"), micro=Micro(alpha=0.05, ndf="beckmann"),
                                  nano=Nano(surface=GRATING), kd=0.0, wavelengths_nm=(LAM,), resolution=32,
                                  thetas_deg=(30.0, 78.0), n_phi=4)
    lines = [str(w.message) for w in caught if str(w.message).startswith("two-scale energy guard")]
    scale = np.asarray(T._table["energy_scale"])
    assert int(np.sum(scale < 1.0)) == 2 and len(lines) == 1, lines
    assert "in 2 of 8 incidences" in lines[0] and "theta_i = 78 deg" in lines[0] and "resolution 64" in lines[0]
