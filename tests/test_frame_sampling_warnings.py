"""Issue 28, promise 3 (say what is skipped): a nano height field on the facet-frame route says, as the paraxial
route and the fft solver do, that its sample spacing cannot resolve the light it scatters: one line per run,
the same text for every facet table and incidence, and none for a field sampled at λ/4 or finer.

Reference: the sampling condition written here from the Kirchhoff sum's period (its sum over samples is periodic
in (u_i + u_o) dx / λ with period 1, so the facet tables, whose local incidences and exits reach |u_i + u_o| ≈ 2,
alias unless dx ≤ λ/4; Shannon 1949), not the library's check. The facet tables are computed in a pool of threads:
the lines must come through with two workers as with one, and leave the process's warning filters as they were
(``warnings.catch_warnings`` in pool threads restored one another's "ignore" filter, and every later
DiffractionWarning of the run, the energy guard's included, was lost).
"""
import warnings

import numpy as np
import pytest

from waveoptics import brdf, surfaces
from waveoptics.brdf import Micro, Nano
from waveoptics.scatter.grid import DirectionGrid

LAM = 550.0
GRID = DirectionGrid.hemisphere(32)


def _field(dx_nm, n=32):
    return surfaces.gaussian(sigma=20e-9, corr_length=1e-6, size=n * dx_nm * 1e-9, samples=n, seed=1)


def _lines(hf, thetas, wavelengths=(LAM,)):
    """The distinct warning texts of evaluate at each incidence θ_i (degrees), all warnings recorded."""
    filters = list(warnings.filters)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for th in thetas:
            t = np.radians(th)
            L = brdf.evaluate(np.array([np.sin(t), 0.0, np.cos(t)]), list(wavelengths), "aluminium",
                              Micro(alpha=0.1), Nano(surface=hf), GRID)
            assert L.info["facet_integration"] == "frame"
    assert warnings.filters == filters
    return {str(w.message) for w in caught}


@pytest.mark.parametrize("workers", ["1", "2"])
def test_coarse_field_warns_aliasing_once(monkeypatch, workers):
    """500 nm spacing at 550 nm (> λ/4 = 137.5 nm): one aliasing line for two incidences, two wavelengths and
    every facet table, naming the spacing and the λ/4 of the shortest wavelength."""
    monkeypatch.setenv("WAVEOPTICS_WORKERS", workers)
    dx = 500.0
    assert dx > LAM / 4   # the independent condition: the tables' |u_i + u_o| ≈ 2 needs dx ≤ λ/4
    lines = [m for m in _lines(_field(dx), (20.0, 40.0), (LAM, 650.0)) if m.startswith("aliasing")]
    assert len(lines) == 1, lines
    assert "500 x 500 nm" in lines[0] and f"lambda/4 = {LAM / 4:.4g} nm" in lines[0]


def test_field_at_quarter_wavelength_does_not_warn():
    """dx = λ/4 (and finer) resolves every facet's exit: no aliasing line."""
    for dx in (LAM / 4, LAM / 5):
        assert dx <= LAM / 4
        assert not [m for m in _lines(_field(dx, 64), (40.0,)) if m.startswith("aliasing")]


def test_paraxial_route_says_it_once_too():
    """An anisotropic field (a grating: the paraxial route) at 250 nm spacing, 450 and 650 nm (> λ/4 for both):
    one aliasing line, the shortest wavelength's, not one per wavelength."""
    hf = surfaces.sinusoid(20e-9, 2e-6, 64 * 250e-9, 64)
    assert 250.0 > 650.0 / 4
    filters = list(warnings.filters)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        L = brdf.evaluate(np.array([0.5, 0.0, np.sqrt(0.75)]), [450.0, 650.0], "aluminium", Micro(alpha=0.1),
                          Nano(surface=hf), GRID)
    assert L.info["facet_integration"] == "paraxial" and warnings.filters == filters
    lines = {str(w.message) for w in caught if str(w.message).startswith("aliasing")}
    assert len(lines) == 1 and "lambda/4 = 112.5 nm" in lines.pop()


@pytest.mark.parametrize("field, route", [("isotropic", "frame"), ("grating", "paraxial")])
def test_rayleigh_rice_says_it_too(field, route):
    """Under Rayleigh-Rice the lobe is the field's periodogram's, whose samples coarser than λ/4 fold the band as
    the Kirchhoff sum aliases: the same one line on both routes (it said nothing), none at λ/4."""
    coarse = {"isotropic": _field(500.0), "grating": surfaces.sinusoid(20e-9, 2e-6, 64 * 250e-9, 64)}[field]
    assert 500.0 > LAM / 4 and 250.0 > LAM / 4

    def lines(hf):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            L = brdf.evaluate(np.array([0.5, 0.0, np.sqrt(0.75)]), [LAM], "aluminium", Micro(alpha=0.1),
                              Nano(surface=hf), GRID, diffraction="rayleigh-rice")
        assert L.info["facet_integration"] == route
        return {str(w.message) for w in caught if str(w.message).startswith("aliasing")}

    got = lines(coarse)
    assert len(got) == 1 and f"lambda/4 = {LAM / 4:.4g} nm" in got.pop()
    if field == "isotropic":
        assert not lines(_field(LAM / 4, 64))
