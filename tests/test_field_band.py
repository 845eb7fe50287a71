"""A height field's nano lobe takes only the roughness that scatters (issue 28): the field route band-limits the
heights to the propagating band before the Kirchhoff integral, as the PSD route's series takes the relevant
roughness (Krywonos, Harvey & Choi 2011).

Before, at σ = 40 nm the field's lobe and its scattered share were below the PSD route's by exp(−g_beyond),
g_beyond = (4π σ_beyond cosθ/λ)² the phase variance of the roughness beyond the band (measured E_field / E_PSD
= 0.836 ± 0.022 at 400 nm, 0.893 ± 0.024 at 550 nm, normal incidence, 8 fields of ABC C = 2.2); the method of
moments on a perfect conductor (1-D, tests/test_mom.py's solver) shows no such damping of the in-band lobe by
sub-wavelength roughness, while Kirchhoff on the same profiles does (report of branch h-fieldband).
"""
import math
import warnings

import numpy as np
import pytest

from waveoptics import brdf
from waveoptics.brdf import twoscale
from waveoptics.request import make_nano
from waveoptics.scatter.grid import DirectionGrid
from waveoptics.surfaces import HeightField, PSDModel
from waveoptics.units import direction_from_angles

SIG = 40e-9
SEEDS = range(8)
#: (nano text of the field route, the same statistics for the PSD route)
NANOS = {
    "abc B=2um C=2.2": ("abc:sigma=40nm,B=2um,C=2.2", PSDModel("abc", sigma=SIG, B=2e-6, C=2.2)),
    "abc B=4um C=2.2": ("abc:sigma=40nm,B=4um,C=2.2", PSDModel("abc", sigma=SIG, B=4e-6, C=2.2)),
    "abc B=2um C=2.6": ("abc:sigma=40nm,B=2um,C=2.6", PSDModel("abc", sigma=SIG, B=2e-6, C=2.6)),
    "abc B=4um C=2.6": ("abc:sigma=40nm,B=4um,C=2.6", PSDModel("abc", sigma=SIG, B=4e-6, C=2.6)),
    "gaussian T=0.4um": ("gaussian:sigma=40nm,corr_length=0.4um", PSDModel("gaussian", sigma=SIG, T=0.4e-6)),
}
#: rings of distance from the mirror direction (direction cosines): the mirror's neighbourhood holds the variance
#: below the grid's lowest frequency, which the PSD route scatters and a periodic field cannot
RINGS = [(0.07, 0.15), (0.15, 0.3), (0.3, 0.6), (0.6, 1.0), (1.0, 1.9)]


def _rings(lobe, grid, wi):
    d = grid.directions()
    r = np.hypot(d[..., 0] + wi[0], d[..., 1] + wi[1])
    return np.array([np.sum(lobe[(r >= a) & (r < b) & grid.inside]) * grid.du * grid.dv for a, b in RINGS])


F1 = lambda c, lam: np.ones(np.broadcast_shapes(np.shape(c), np.shape(lam)))  # noqa: E731


def _ensemble(name, wi, grid, rings=slice(None)):
    text, model = NANOS[name]
    E = []
    for seed in SEEDS:
        nano = make_nano(text, [500.0], solver="fft", seed=seed)
        assert nano.surface.shape == (128, 128)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")          # aliasing note: spacing λ/4 is the route's own choice
            E.append(_rings(brdf.nano_lobe(wi, [500.0], nano, grid, F1, solver="fft")[0], grid, wi)[rings])
    ref = _rings(brdf.nano_lobe(wi, [500.0], twoscale.Nano(model=model), grid, F1, solver="psd")[0], grid, wi)
    return np.array(E), ref[rings]


@pytest.mark.parametrize("name", sorted(NANOS))
def test_field_lobe_matches_psd_route_near_the_mirror_at_40nm(name):
    """8 fields (simulate's field route: 128² samples 125 nm apart at 500 nm, Kirchhoff fft solver) give, in the two
    rings 0.07 ≤ |Δ(u, v)| < 0.3 around the mirror direction at θ_i = 20° (most of the ABC lobes' light), the
    diffracted energy of the PSD series within 3 standard errors of the ensemble mean (measured within 0.8 SE;
    the outer rings: see the xfail test below)."""
    E, ref = _ensemble(name, direction_from_angles(20.0, 0.0), DirectionGrid.hemisphere(64), slice(0, 2))
    mean, se = E.mean(0), E.std(0, ddof=1) / math.sqrt(len(E))
    assert np.all(np.abs(mean - ref) < 3 * se), (mean / ref, (mean - ref) / se)


@pytest.mark.xfail(strict=True, reason="rings 0.3 <= |du| < 1.0 of the field route lie 0.89-0.94 x the PSD series at "
                   "sigma = 40 nm (2.4-4.3 SE), also for a Gaussian field with no roughness beyond the band: the "
                   "PSD series returns its multiple-order light that falls beyond the band to the band (BandSeries' "
                   "K; 5-6 % above the closed-form Beckmann series there), the field's Kirchhoff integral does not")
def test_field_lobe_matches_psd_route_in_every_ring_at_40nm():
    E, ref = _ensemble("gaussian T=0.4um", direction_from_angles(20.0, 0.0), DirectionGrid.hemisphere(64))
    keep = ref > 1e-3 * ref.sum()
    mean, se = E.mean(0), E.std(0, ddof=1) / math.sqrt(len(E))
    assert np.all(np.abs(mean - ref)[keep] < 3 * se[keep]), ((mean / ref)[keep], ((mean - ref) / se)[keep])


def test_without_the_band_limit_the_lobe_is_damped_by_the_roughness_beyond_the_band():
    """Paired, field by field (ABC B = 2 µm, C = 2.2, σ = 40 nm, normal incidence, 500 nm): the plain Kirchhoff lobe
    of the whole field over the band-limited one is exp(−g_beyond) in the inner rings, g_beyond = (4π σ_b/λ)²
    with σ_b² the field's periodogram beyond the band |f| ≤ 1/λ + 3/L (with its margin), summed here with numpy
    (measured 0.907 against 0.909 and 0.921 against 0.908; within 2 %)."""
    text, _ = NANOS["abc B=2um C=2.2"]
    wi = direction_from_angles(0.0, 0.0)
    grid = DirectionGrid.hemisphere(64)
    for seed in range(2):
        hf = make_nano(text, [500.0], solver="fft", seed=seed).surface
        ny, nx = hf.shape
        P = np.abs(np.fft.fft2(hf.heights - hf.heights.mean())) ** 2 / (nx * ny) ** 2
        f = np.hypot(np.fft.fftfreq(nx, hf.dx)[None, :], np.fft.fftfreq(ny, hf.dy)[:, None])
        edge = 1 / 500e-9 + brdf.BAND_MARGIN_BINS / (nx * hf.dx)     # the band and its margin (square patch)
        g_beyond = (4 * np.pi / 500e-9) ** 2 * np.sum(P[f > edge])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            full, limited = (_rings(brdf.kirchhoff_scattered_lobe(hf, wi, grid, [500.0], F1, band_limit=b)[0],
                                    grid, wi)[:2] for b in (False, True))
        assert np.sum(full) / np.sum(limited) == pytest.approx(math.exp(-g_beyond), rel=0.02)


def test_band_limit_keeps_the_scattering_frequencies_only():
    """Sinusoids written here: at λ = 500 nm and θ_i = 40° (band centred on −sin40°/λ, radius 1/λ), a component at
    f = 2.5/λ along x is outside D ∪ −D and is removed, one at 1.5/λ along x (inside D or −D, as the heights are
    real) and one at 0.7/λ along y are kept exactly; a mask stays."""
    lam, n, dx = 500e-9, 200, 25e-9                 # 5 µm: 10 wavelengths, so every frequency is on the grid
    x = np.arange(n) * dx
    X, Y = np.meshgrid(x, x)
    keep = 3e-9 * np.cos(2 * np.pi * 1.5 / lam * X + 0.3) + 2e-9 * np.sin(2 * np.pi * 0.7 / lam * Y)
    drop = 5e-9 * np.cos(2 * np.pi * 2.5 / lam * X)
    mask = np.ones((n, n), bool)
    hf = HeightField(keep + drop, dx)
    out = brdf.band_limited_field(hf, 500.0, direction_from_angles(40.0, 0.0))
    assert np.max(np.abs(out.heights - keep)) < 1e-20
    hm = HeightField(keep + drop, dx, mask=mask)
    assert brdf.band_limited_field(hm, 500.0, direction_from_angles(40.0, 0.0)).mask is not None
    # at normal incidence the band is the centred disc: 1.5/λ is removed too
    out0 = brdf.band_limited_field(hf, 500.0, direction_from_angles(0.0, 0.0))
    assert np.max(np.abs(out0.heights - (keep - 3e-9 * np.cos(2 * np.pi * 1.5 / lam * X + 0.3)))) < 1e-20
