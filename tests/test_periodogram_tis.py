"""The first-order TIS of a height field's periodogram, the budget of its Rayleigh-Rice lobe (issue 28's "no guard
acts"): summed over the periodogram's own bins, at the light's azimuth.

Reference, written here: the Hann-windowed periodogram of the field by numpy's FFT (Jacobs, Junge & Pastewka 2017's
normalization, Σ S Δf_x Δf_y = the window-weighted variance), each bin sent to (u, v) = (λ f_x − u_i, λ f_y − v_i) by
the grating equation, f_RR = (16π²/λ⁴) cosθ_i cosθ_o Q S (Church, Jenkinson & Zavada 1979) with Q of
tests/twoscale_reference.py (Elson & Bennett 1979), summed with du dv = λ² Δf_x Δf_y (Stover 2012, §4.4).

Before, the TIS came from a polar quadrature of 48 azimuths about the mirror direction, which samples a scratched
field's narrow streaks by chance: 26 % low for the field below, and the energy guard cut its Rayleigh-Rice lobe by
25 % (α 0) to 29 % (α 0.1, 90°) to that budget.
"""
import warnings

import numpy as np
import pytest
from scipy.signal.windows import hann

import twoscale_reference as R
from waveoptics import brdf, scatter, surfaces
from waveoptics.brdf import Micro, Nano
from waveoptics.materials import get_material
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
FIELD = surfaces.scratches(40, 300e-9, 20e-9, 128 * LAM / 4 * 1e-9, 128, orientation_deg=0.0, seed=3)
AL = get_material("aluminium")


def _tis(theta_deg, phi_deg):
    h = FIELD.heights - FIELD.heights.mean()
    ny, nx = h.shape
    w = np.outer(hann(ny, sym=False), hann(nx, sym=False))
    S = np.abs(np.fft.fft2(w * h)) ** 2 * FIELD.dx * FIELD.dy / np.sum(w ** 2)
    FX, FY = np.meshgrid(np.fft.fftfreq(nx, FIELD.dx), np.fft.fftfreq(ny, FIELD.dy))
    lam = LAM * 1e-9
    wi = R.direction(theta_deg, phi_deg + 180.0) * np.array([-1, -1, 1])   # towards the light at azimuth φ
    u, v = lam * FX - wi[0], lam * FY - wi[1]
    ok = u * u + v * v < 1
    wo = np.stack([u[ok], v[ok], np.sqrt(1 - u[ok] ** 2 - v[ok] ** 2)], -1)
    eps = complex(scatter.permittivity(AL, LAM))
    Q = R.rayleigh_rice_Q_pol(np.broadcast_to(wi, wo.shape), wo, eps)
    f = 16 * np.pi ** 2 / lam ** 4 * wi[2] * wo[:, 2] * Q * S[ok]
    return float(np.sum(f) * lam ** 2 / (nx * FIELD.dx * ny * FIELD.dy)), wi


@pytest.mark.parametrize("theta, phi", [(30.0, 0.0), (30.0, 90.0), (60.0, 45.0)])
def test_tis_is_the_bin_sum_at_the_lights_azimuth(theta, phi):
    """The package's TIS of the field's periodogram at (θ, φ) is the bin sum written here within 1e-6 relative; the
    field is anisotropic (its TIS at 90° is 4 % above that at 0°), so the azimuth matters."""
    ref, _ = _tis(theta, phi)
    got = scatter.rayleigh_rice_tis(theta, LAM, Nano(surface=FIELD).periodogram(), AL, azimuth_deg=phi)
    assert got == pytest.approx(ref, rel=1e-6)
    assert _tis(30.0, 90.0)[0] > 1.03 * _tis(30.0, 0.0)[0]


@pytest.mark.parametrize("phi, alpha", [(0.0, 0.0), (90.0, 0.0), (90.0, 0.1)])
def test_no_guard_on_a_scratched_field_under_rayleigh_rice(phi, alpha):
    """The field's Rayleigh-Rice lobe (64² cells, light at 30°): the energy guard removes nothing, and at α 0 the
    lobe's albedo on the cells is the TIS written here within 2 % (the cells sample the periodogram's streaks
    bilinearly)."""
    ref, wi = _tis(30.0, phi)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scatter.DiffractionWarning)
        warnings.filterwarnings("error", message="two-scale energy guard", category=scatter.DiffractionWarning)
        L = brdf.evaluate(wi, [LAM], AL, Micro(alpha=alpha), Nano(surface=FIELD), DirectionGrid.hemisphere(64),
                          diffraction="rayleigh-rice")
    assert L.info["diffraction_energy_scale"] == [1.0]
    if alpha == 0.0:
        assert float(L.albedo("diffraction")[0]) == pytest.approx(ref, rel=0.02)
