"""Issue 28 for ANISOTROPIC nano height fields: a grating's lobe is carried by every micro facet in its own frame
(Walter et al. 2007's integral), from tables of the field's lobe over the local incidence's polar angle and azimuth
read in direction-cosine offsets from each node's mirror direction.

Reference: tests/twoscale_reference.py's Monte-Carlo facet integral (its own Beckmann sampling, Smith G2 and balance
heuristic) of the field's lobe computed at each facet's exact local incidence by the direct Kirchhoff sum
(:func:`waveoptics.scatter.direct.kirchhoff_U_cl`, tests/test_twoscale_heightfield_frame.py's ``_exact_lobe``): no
tables, no shift, no FFT. The field lies on each facet m with its x axis along the macro x axis projected onto the
facet plane, t1 = (x − (x·m) m)/|x − (x·m) m|, t2 = m × t1: :func:`field_axes` here, written apart from the
package's frame. Lobes are compared as averages over 8 × 8 cell blocks, as for an isotropic field.
"""
import functools

import numpy as np
import pytest

import twoscale_reference as R
from test_twoscale_heightfield_frame import _exact_lobe
from waveoptics import brdf, surfaces
from waveoptics.brdf import Micro, Nano
from waveoptics.materials import get_material
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
#: a sinusoidal grating along x, 8 periods of 1.1 µm (λ/Λ = 0.5: orders ±1 to ±3 on the hemisphere at 550 nm)
#: sampled at λ/4, amplitude 50 nm (first orders ~20 % of the light)
PERIOD = 1100.0
GRATING = surfaces.sinusoid(50e-9, PERIOD * 1e-9, 64 * LAM / 4 * 1e-9, 64)
#: the reference's half-vector technique spreads its normals over the first orders' facet tilts (λ/(2Λ) from h)
WIDTH = LAM / PERIOD
GRID = DirectionGrid.hemisphere(64)
BLOCK = 8
#: |package − reference| ≤ TOL × reference + K_SE standard errors, per block average
TOL, K_SE = 0.03, 3.0
AL = get_material("aluminium")
NANO = Nano(surface=GRATING)   # one object: its tables are built once for every case


def field_axes(w, m):
    """Directions *w* (..., 3) in the grating's axes on the facets *m* (..., 3): (w·t1, w·t2, w·m), t1 the macro x
    axis projected onto the facet plane, t2 = m × t1."""
    w, m = np.broadcast_arrays(np.asarray(w, float), np.asarray(m, float))
    t1 = np.array([1.0, 0.0, 0.0]) - m[..., :1] * m
    t1 = t1 / np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(m, t1)
    return np.stack([np.sum(w * t1, -1), np.sum(w * t2, -1), np.sum(w * m, -1)], axis=-1)


EXACT = _exact_lobe(GRATING)


def _f_nano(a, b, lam):
    h = a + b
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    return EXACT(a, b, lam) * AL.F(np.clip(np.sum(h * a, -1), 0, 1), lam)


def test_field_axes_keep_the_grating_on_a_facet_tilted_about_x():
    """A facet tilted about the x axis keeps the grating's x axis; the reference's lobe at normal incidence puts
    the first orders at u = ±λ/Λ (the grating equation)."""
    m = np.array([0.0, -np.sin(0.3), np.cos(0.3)])
    np.testing.assert_allclose(field_axes(np.array([1.0, 0.0, 0.0]), m), [1.0, 0.0, 0.0], atol=1e-12)
    wi = np.array([0.0, 0.0, 1.0])
    u = np.linspace(-0.8, 0.8, 161)
    lobe = EXACT(np.broadcast_to(wi, (u.size, 3)), np.stack([u, 0 * u, np.sqrt(1 - u * u)], -1), LAM)
    peaks = u[np.argsort(lobe)[-2:]]
    np.testing.assert_allclose(np.sort(peaks), [-LAM / PERIOD, LAM / PERIOD], atol=0.011)


def test_route_choice():
    """auto keeps the grating on the paraxial shift (the frame route's cost, in the reason); asked by name, the
    frame route takes it (it was refused)."""
    assert "anisotropic" in brdf.field_anisotropy(GRATING)
    assert brdf.facet_route(Micro(alpha=0.1), NANO, GRID, [LAM]) == "paraxial"
    assert "facet 'frame'" in brdf.paraxial_reason(Micro(alpha=0.1), NANO, GRID, [LAM])
    assert brdf.facet_route(Micro(alpha=0.1), NANO, GRID, [LAM], "frame") == "frame"


@functools.lru_cache(maxsize=None)
def _case(alpha, theta, phi=30.0):
    """(blocks' package means by route, reference means, reference s.e., the frame route's lobes) of 6 blocks of
    8 × 8 cells (θ_o ≤ 70°, the block's mean > 10 % of the largest block's) of the light at (θ, φ); the reference
    at every cell centre of the blocks, 400 normals a cell (α 0.1), 800 (α 0.3)."""
    wi = R.direction(theta, phi)
    lobes = {facet: brdf.evaluate(wi, [LAM], "aluminium", Micro(alpha=alpha, ndf="beckmann"), NANO, GRID,
                                  facet=facet) for facet in ("frame", "paraxial")}
    nb = GRID.n_u // BLOCK
    blocks = {k: L.diffraction[0].reshape(nb, BLOCK, nb, BLOCK) for k, L in lobes.items()}
    D = blocks["frame"]
    wo = GRID.directions().reshape(nb, BLOCK, nb, BLOCK, 3)
    Dm = D.mean(axis=(1, 3))
    ok = (wo[..., 2] > np.cos(np.radians(70))).all(axis=(1, 3)) & (Dm > 0.1 * Dm.max())
    cand = np.argwhere(ok)
    sel = cand[np.random.default_rng(5).choice(len(cand), min(6, len(cand)), replace=False)]
    wos = np.concatenate([wo[i, :, j, :].reshape(-1, 3) for i, j in sel])
    ref, se = R.facet_integral(_f_nano, np.broadcast_to(wi, wos.shape), wos, LAM, alpha, "beckmann",
                               nano_width=WIDTH, n_samples=400 if alpha < 0.2 else 800, seed=3,
                               frame=field_axes)
    ref_b = ref.reshape(len(sel), -1).mean(1)
    se_b = np.sqrt(np.sum(se.reshape(len(sel), -1) ** 2, axis=1)) / BLOCK ** 2
    got = {k: np.array([B[i, :, j, :].mean() for i, j in sel]) for k, B in blocks.items()}
    return got, ref_b, se_b, lobes["frame"]


@pytest.mark.parametrize("alpha,theta", [(0.1, 45.0), (0.3, 0.0), (0.3, 45.0)])
def test_grid_lobes_are_the_facet_frame_integral(alpha, theta):
    """evaluate's diffracted lobe (the frame route) averaged over up to 6 blocks of 8 × 8 cells within 3 % + 3
    s.e. of the reference, the light at 30° from the grating vector (measured 0.96-1.12 with 2.2-6.4 % s.e.; the
    paraxial shift on the same blocks 0.53-1.25, outside the tolerance in 3, 1, 5 of the blocks at α 0.1 / 45°,
    0.3 / 0°, 0.3 / 45°; at α 0.1 / 0°, left out for time, 0.96-1.03 against 0.91-0.97); the energy guard
    idle."""
    got, ref_b, se_b, L = _case(alpha, theta)
    assert L.info["facet_integration"] == "frame" and L.info["facet_integration_reason"] is None
    bad = np.abs(got["frame"] - ref_b) > TOL * ref_b + K_SE * se_b
    assert not bad.any(), (np.round(got["frame"] / ref_b, 3), np.round(se_b / ref_b, 3),
                           np.round(got["paraxial"] / ref_b, 3))
    assert L.info["diffraction_energy_scale"] == [1.0]


def test_paraxial_route_fails_the_same_assertion():
    """The paraxial shift (the route `auto` takes for anisotropic fields) on the same blocks: outside the tolerance."""
    got, ref_b, se_b, _ = _case(0.3, 45.0)
    assert np.any(np.abs(got["paraxial"] - ref_b) > TOL * ref_b + K_SE * se_b)
