"""Spectral pipeline: normalization, closed-form spectra (lasers, equal energy, Planck), CIE tables, colour-science
cross-checks, metamers, F0 colours against Hoffman's tables, CLI."""
import json

import colour
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from waveoptics import colour as wcolour
from waveoptics.cli import main
from waveoptics.errors import WaveopticsError
from waveoptics.materials import get_material

# --- tolerances (one place) -------------------------------------------------------------------------------
EXACT = 1e-12            # identities that hold to rounding
SRGB_WHITE = 5e-4        # IEC 61966-2-1's 4-decimal matrix maps D65 to RGB within 1.6e-4 of (1, 1, 1)
CIE_TABLE = 2.5e-4       # white points vs CIE 015 tables (Y = 1 scale); D/A tabulated at 5 nm, interpolated to 1 nm
HOFFMAN = 0.05           # F0 vs Hoffman's table when the optical-constant data sets differ
HOFFMAN_SAME_DATA = 0.02  # F0 vs Hoffman's table with a data set close to the one behind it
D2 = "CIE 1931 2 Degree Standard Observer"
D10 = "CIE 1964 10 Degree Standard Observer"


def _smooth_R(w):
    """A smooth, coloured test reflectance (nm -> [0.05, 0.95])."""
    return 0.5 + 0.45 * np.sin((np.asarray(w) - 380.0) / 70.0)


# --- white reflector and normalization ----------------------------------------------------------------------

def test_white_reflector_under_D65_is_Y1_and_srgb_white():
    w = np.arange(380.0, 781.0, 5.0)
    XYZ = wcolour.reflectance_to_XYZ(np.ones(w.size), w, "D65")
    assert XYZ[1] == pytest.approx(1.0, abs=EXACT)
    rgb = wcolour.reflectance_to_rgb(np.ones(w.size), w, "D65")
    np.testing.assert_allclose(rgb, 1.0, atol=SRGB_WHITE)
    np.testing.assert_allclose(wcolour.reflectance_to_rgb(np.ones(w.size), w, "D65", adapt=False), 1.0,
                               atol=SRGB_WHITE)


@pytest.mark.parametrize("space", ["ACEScg", "Display P3", "p3", "acescg"])
@pytest.mark.parametrize("illum", ["D65", "A", "F2", "blackbody:3000K", "rgb-laser"])
def test_white_reflector_adapts_to_space_white(space, illum):
    grid = wcolour.spectral_grid(illum, 10.0)
    rgb = wcolour.reflectance_to_rgb(np.ones(grid.size), grid, illum, space=space)
    np.testing.assert_allclose(rgb, 1.0, atol=1e-9)


def test_without_adaptation_illuminant_A_looks_orange():
    grid = wcolour.spectral_grid("A", 10.0)
    r, g, b = wcolour.reflectance_to_rgb(np.ones(grid.size), grid, "A", adapt=False)
    assert r > g > b and b < 0.5


@pytest.mark.parametrize("method", ["linear", "spline"])
@pytest.mark.parametrize("illum", ["D65", "A", "F2", "E", "blackbody:5500K"])
def test_normalization_independent_of_step(illum, method):
    white = wcolour.white_XYZ(illum)
    for step in (1.0, 5.0, 10.0, 20.0, 40.0):
        w = np.arange(380.0, 780.0 + step / 2, step)
        XYZ = wcolour.reflectance_to_XYZ(np.ones(w.size), w, illum, method=method)
        np.testing.assert_allclose(XYZ, white, atol=EXACT)
    w = np.array([377.0, 401.5, 450.0, 452.0, 530.0, 611.0, 700.0, 790.0])  # non-uniform grid
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(np.ones(w.size), w, illum, method=method), white,
                               atol=EXACT)


@pytest.mark.parametrize("step", [1.0, 5.0, 10.0, 20.0])
def test_linear_reflectance_is_exact_on_every_step(step):
    """Linear interpolation reproduces R = a + bλ exactly when the grid spans the CMF table (360-830 nm)."""
    fine = np.arange(360.0, 831.0)
    R = lambda w: 0.2 + 0.001 * (w - 360.0)  # noqa: E731
    ref = wcolour.reflectance_to_XYZ(R(fine), fine, "D65")
    w = np.arange(360.0, 830.0 + step, step)
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R(w), w, "D65"), ref, atol=EXACT)


@pytest.mark.parametrize("step", [5.0, 10.0, 20.0])
def test_cubic_reflectance_is_exact_with_spline_method(step):
    fine = np.arange(360.0, 831.0)
    R = lambda w: 0.3 + 1e-3 * (w - 360) - 3e-6 * (w - 360) ** 2 + 4e-9 * (w - 360) ** 3  # noqa: E731
    ref = wcolour.reflectance_to_XYZ(R(fine), fine, "A")
    w = np.arange(360.0, 830.0 + step, step)
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R(w), w, "A", method="spline"), ref, atol=1e-10)


@pytest.mark.parametrize("step,tol", [(5.0, 2e-4), (10.0, 1e-3), (20.0, 4e-3)])
def test_smooth_reflectance_converges_with_step(step, tol):
    fine = np.arange(360.0, 831.0)
    ref = wcolour.reflectance_to_XYZ(_smooth_R(fine), fine, "D65")
    w = np.arange(380.0, 780.0 + step / 2, step)
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(_smooth_R(w), w, "D65"), ref, atol=tol)


@pytest.mark.filterwarnings("ignore::colour.utilities.ColourRuntimeWarning")
def test_matches_colour_science_integration_at_1nm_and_astm_e308_at_10nm():
    cmfs = colour.MSDS_CMFS[D2]
    d65 = wcolour.illuminant("D65")
    S = colour.SpectralDistribution(d65(cmfs.wavelengths), cmfs.wavelengths)
    fine = np.arange(360.0, 831.0)
    R = _smooth_R(fine)
    ref = colour.sd_to_XYZ(colour.SpectralDistribution(R, fine), cmfs, S, method="Integration") / 100
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R, fine, d65), ref, atol=EXACT)
    w = np.arange(360.0, 831.0, 10.0)
    astm = colour.sd_to_XYZ(colour.SpectralDistribution(_smooth_R(w), w), cmfs, S, method="ASTM E308") / 100
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(_smooth_R(w), w, d65, method="ASTM E2022"), astm,
                               atol=1e-5)


@pytest.mark.parametrize("illum,observer,cie", [
    ("D65", D2, (95.047, 100.0, 108.883)), ("D65", D10, (94.811, 100.0, 107.304)),
    ("D50", D2, (96.422, 100.0, 82.521)), ("D50", D10, (96.720, 100.0, 81.427)),
    ("A", D2, (109.850, 100.0, 35.585)), ("A", D10, (111.144, 100.0, 35.200)),
])
def test_white_points_match_cie_tables(illum, observer, cie):
    """CIE 015:2004 Table T.3 (ASTM E308) white points of the perfect reflecting diffuser."""
    np.testing.assert_allclose(100 * wcolour.white_XYZ(illum, observer), cie, atol=100 * CIE_TABLE)


def test_n_dimensional_and_unsorted_grids():
    rng = np.random.default_rng(7)
    w = np.arange(380.0, 781.0, 20.0)
    R = rng.uniform(0, 1, size=(2, 3, 4, w.size))
    XYZ = wcolour.reflectance_to_XYZ(R, w, "D50")
    assert XYZ.shape == (2, 3, 4, 3)
    np.testing.assert_allclose(XYZ[1, 2, 3], wcolour.reflectance_to_XYZ(R[1, 2, 3], w, "D50"), atol=EXACT)
    perm = rng.permutation(w.size)
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R[..., perm], w[perm], "D50"), XYZ, atol=EXACT)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(st.floats(0.0, 1.0), min_size=3, max_size=30),
       st.lists(st.floats(0.5, 60.0), min_size=2, max_size=29))
def test_linear_weights_bound_xyz_between_min_and_max_reflectance(values, gaps):
    """Non-negative weights summing to the white: min(R)·white <= XYZ <= max(R)·white, never negative."""
    n = min(len(values), len(gaps) + 1)
    R = np.array(values[:n])
    w = 370.0 + np.concatenate([[0.0], np.cumsum(gaps[: n - 1])])
    XYZ = wcolour.reflectance_to_XYZ(R, w, "F11")
    white = wcolour.white_XYZ("F11")
    assert np.all(XYZ >= R.min() * white - 1e-12) and np.all(XYZ <= R.max() * white + 1e-12)


def test_bad_reflectance_inputs():
    w = np.arange(400.0, 701.0, 100.0)
    with pytest.raises(WaveopticsError, match="last axis must have one value per wavelength"):
        wcolour.reflectance_to_XYZ(np.ones(3), w)
    with pytest.raises(WaveopticsError, match="NaN or Inf"):
        wcolour.reflectance_to_XYZ([1.0, np.nan, 1.0, 1.0], w)
    with pytest.raises(WaveopticsError, match="repeated"):
        wcolour.reflectance_to_XYZ([1.0, 1.0], [500.0, 500.0])
    with pytest.raises(WaveopticsError, match="unknown tristimulus method 'cubic'"):
        wcolour.reflectance_to_XYZ(np.ones(4), w, method="cubic")
    with pytest.raises(WaveopticsError, match="ASTM E2022' needs a uniform integer-nm grid"):
        wcolour.reflectance_to_XYZ(np.ones(4), w + 0.5, method="ASTM E2022")


# --- closed-form spectra ---------------------------------------------------------------------------------------

def test_single_laser_line_has_spectral_locus_chromaticity():
    wl, c = wcolour.cmfs(D2)
    i = int(np.nonzero(wl == 532.0)[0][0])
    XYZ = wcolour.reflectance_to_XYZ([1.0], [532.0], "laser:532nm")
    np.testing.assert_allclose(XYZ, c[i] / c[i, 1], atol=EXACT)


def test_laser_lines_are_discrete_sums():
    lines, P = np.array([465.0, 532.0, 638.0]), np.array([2.0, 1.0, 3.0])
    src = wcolour.laser(lines, P)
    R = np.array([0.2, 0.9, 0.5])
    c = wcolour.cmf_at(lines, D2)
    expected = (P * R) @ c / (P @ c[:, 1])
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R, lines, src), expected, atol=EXACT)
    # R on another grid is linearly interpolated at the lines: exact for linear R
    grid = np.arange(400.0, 701.0, 50.0)
    lin = lambda w: 0.1 + 0.001 * (w - 400.0)  # noqa: E731
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(lin(grid), grid, src),
                               (P * lin(lines)) @ c / (P @ c[:, 1]), atol=EXACT)


def test_simulation_wavelengths_of_lasers_are_the_visible_lines():
    np.testing.assert_array_equal(wcolour.simulation_wavelengths("laser:638,465,532"), [465.0, 532.0, 638.0])
    np.testing.assert_array_equal(wcolour.simulation_wavelengths("laser:1064,532"), [532.0])
    with pytest.raises(WaveopticsError, match="no visible"):
        wcolour.simulation_wavelengths("laser:1064")


def test_equal_energy_white_is_achromatic_and_a_plain_cmf_sum():
    xy = colour.XYZ_to_xy(wcolour.white_XYZ("E"))
    np.testing.assert_allclose(xy, (1 / 3, 1 / 3), atol=1e-4)  # CIE 1931 CMF areas are equal to 1e-4
    wl, c = wcolour.cmfs(D2)
    R = _smooth_R(wl)
    np.testing.assert_allclose(wcolour.reflectance_to_XYZ(R, wl, "E"), R @ c / c[:, 1].sum(), atol=EXACT)


@pytest.mark.parametrize("T", [1500.0, 2856.0, 5500.0, 10000.0])
def test_blackbody_follows_planck(T):
    """Relative SPD equals Planck's law λ^-5 / (exp(c2/λT) - 1), c2 = 1.4388e-2 m·K (CIE 015)."""
    bb = wcolour.illuminant(f"blackbody:{T:g}K")
    lam = np.array([380.0, 450.0, 560.0, 650.0, 780.0])
    planck = lambda l: (l * 1e-9) ** -5 / np.expm1(1.4388e-2 / (l * 1e-9 * T))  # noqa: E731
    np.testing.assert_allclose(bb(lam), 100 * planck(lam) / planck(560.0), rtol=1e-9)


def test_blackbody_reproduces_cie_illuminant_A():
    """CIE A is Planckian at 2848 K with c2 = 1.435e-2, i.e. 2848·1.4388/1.435 K with today's c2."""
    bb = wcolour.blackbody(2848 * 1.4388 / 1.435)
    A = wcolour.illuminant("A")
    lam = np.arange(380.0, 781.0, 5.0)
    np.testing.assert_allclose(bb(lam), A(lam), rtol=2e-5)


# --- sources parsing --------------------------------------------------------------------------------------------

def test_illuminant_names_and_aliases():
    assert not wcolour.illuminant("D65").lines
    np.testing.assert_array_equal(wcolour.illuminant("F7").values, wcolour.illuminant("FL7").values)
    assert wcolour.illuminant("f12").name == "F12"
    assert wcolour.illuminant("rgb-laser").lines
    np.testing.assert_array_equal(wcolour.illuminant("rgb-laser").wavelengths_nm, sorted(wcolour.RGB_LASER_NM))
    assert wcolour.illuminant("laser:465, 532,638nm").wavelengths_nm.tolist() == [465.0, 532.0, 638.0]
    assert wcolour.illuminant("blackbody:6500").name == "blackbody 6500 K"


@pytest.mark.parametrize("spec,message", [
    ("D66", r"unknown illuminant 'D66' \(did you mean 'D65'\?\)"),
    ("blackbody:hot", "write blackbody:TEMPERATUREK"),
    ("blackbody:10K", "blackbody temperature 10.0 K is not allowed"),
    ("laser:green", "write laser:NM"),
    ("laser:-5", "laser line -5.0 nm is not allowed"),
    ("nosuch.csv", "SPD file 'nosuch.csv' does not exist"),
])
def test_bad_illuminants(spec, message):
    with pytest.raises(WaveopticsError, match=message):
        wcolour.illuminant(spec)


def test_observer_aliases():
    assert wcolour.observer_name("10") == D10
    with pytest.raises(WaveopticsError, match=r"unknown observer '11' \(did you mean '10'\?\)"):
        wcolour.observer_name("11")


def test_csv_spd_round_trip(tmp_path):
    d65 = wcolour.illuminant("D65")
    p = tmp_path / "lamp.csv"
    p.write_text("wavelength,lamp\n" + "\n".join(f"{w:g},{v:.6f}" for w, v in zip(d65.wavelengths_nm, d65.values)))
    lamp = wcolour.illuminant(str(p))
    np.testing.assert_allclose(wcolour.white_XYZ(lamp), wcolour.white_XYZ(d65), atol=1e-7)
    two = tmp_path / "two.csv"
    two.write_text("wavelength,a,b\n400,1,2\n500,1,2\n600,1,2\n700,1,2\n")
    with pytest.raises(WaveopticsError, match="has 2 spectra"):
        wcolour.illuminant(str(two))
    assert wcolour.illuminant(f"{two}:b").values.tolist() == [2.0] * 4
    with pytest.raises(WaveopticsError, match=r"unknown column of two.csv 'c'"):
        wcolour.illuminant(f"{two}:c")


# --- RGB, 8-bit, ΔE ----------------------------------------------------------------------------------------------

def test_rgb_to_srgb8():
    np.testing.assert_array_equal(wcolour.rgb_to_srgb8([0.0, 0.5, 1.0]), [0, 188, 255])
    np.testing.assert_array_equal(wcolour.rgb_to_srgb8([[1.2, -0.1, 0.0031308]]), [[255, 0, 10]])  # 12.92·x·255
    with pytest.raises(WaveopticsError, match="NaN"):
        wcolour.rgb_to_srgb8([np.nan, 0, 0])


def test_delta_e2000_matches_sharma_reference_pair():
    """Sharma, Wu, Dalal (2005) CIEDE2000 test data, pair 1: ΔE00 = 2.0425."""
    cs = colour.RGB_COLOURSPACES["sRGB"]
    white = cs.whitepoint
    lab = np.array([[50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485]])
    # invert colour's RGB->XYZ exactly (the IEC 61966-2-1 XYZ->RGB matrix is its inverse only to 4 decimals)
    rgb = np.linalg.solve(cs.matrix_RGB_to_XYZ, colour.Lab_to_XYZ(lab, white).T).T
    assert wcolour.delta_e2000(rgb[0], rgb[1]) == pytest.approx(2.0425, abs=1e-4)
    assert wcolour.delta_e2000(rgb, rgb).tolist() == [0.0, 0.0]


def test_unknown_space():
    with pytest.raises(WaveopticsError, match=r"unknown RGB space 'sRBG' \(did you mean 'sRGB'\?\)"):
        wcolour.XYZ_to_rgb([0.5, 0.5, 0.5], "sRBG")


# --- simulation grids -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("method", ["linear", "spline"])
@pytest.mark.parametrize("target", [0.2, 0.5, 1.0])
def test_simulation_wavelengths_meet_the_requested_accuracy(method, target):
    grid = wcolour.simulation_wavelengths("D65", target, method=method)
    step = float(np.diff(grid)[0])
    errors = wcolour.step_errors("D65", [step, step * 2], method=method)
    assert errors[step][0] <= target
    if step * 2 <= 40:  # the next coarser candidate would have failed
        assert errors[step * 2][0] > target
    assert 380.0 <= grid[0] and grid[-1] <= 780.0


def test_spline_needs_fewer_wavelengths_than_linear_for_smooth_spectra():
    assert wcolour.simulation_wavelengths("D65", 0.5, method="spline").size < \
        wcolour.simulation_wavelengths("D65", 0.5, method="linear").size


# --- metamers --------------------------------------------------------------------------------------------------

def test_laser_metamer_of_d65_has_equal_xyz_but_different_object_colours():
    lines = [465.0, 532.0, 638.0]
    P = wcolour.metamer_laser_weights("D65", lines)
    assert np.all(P > 0)
    mix = wcolour.laser(lines, P)
    np.testing.assert_allclose(wcolour.spd_to_XYZ(mix), wcolour.spd_to_XYZ("D65"), rtol=1e-12)
    # metameric failure: the same ColorChecker-like reflectance looks different under the two lights
    w = np.arange(380.0, 781.0, 5.0)
    R = 0.05 + 0.9 / (1.0 + np.exp(-(w - 600.0) / 15.0))
    under_d65 = wcolour.reflectance_to_rgb(R, w, "D65")
    under_lasers = wcolour.reflectance_to_rgb(R, w, mix)
    assert wcolour.delta_e2000(under_d65, under_lasers) > 2.0


def test_rgb_laser_projector_white_is_d65():
    np.testing.assert_allclose(wcolour.white_XYZ("rgb-laser"), wcolour.white_XYZ("D65"), atol=EXACT)


def test_laser_metamer_is_observer_dependent():
    """Calibrated for the 2° observer, the laser white is visibly off D65 for the 10° observer."""
    w10, d10 = wcolour.white_XYZ("rgb-laser", D10), wcolour.white_XYZ("D65", D10)
    assert wcolour.delta_e2000(wcolour.XYZ_to_rgb(w10), wcolour.XYZ_to_rgb(d10)) > 2.0


def test_metamer_errors():
    with pytest.raises(WaveopticsError, match="line 520 nm would need negative power"):
        wcolour.metamer_laser_weights("D65", [500.0, 520.0, 540.0])
    with pytest.raises(WaveopticsError, match="exactly 3 distinct laser lines"):
        wcolour.metamer_laser_weights("D65", [465.0, 532.0])


def test_plot_metamers_writes_png(tmp_path):
    out = tmp_path / "m.png"
    P = wcolour.metamer_laser_weights("D65", [465.0, 532.0, 638.0])
    wcolour.plot_metamers("D65", [465.0, 532.0, 638.0], P, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
    with pytest.raises(WaveopticsError, match="already exists"):
        wcolour.plot_metamers("D65", [465.0, 532.0, 638.0], P, out)


# --- F0 ------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("y,expected", [(0.02, ("dielectric", False)), (0.17, ("dielectric", False)),
                                        (0.2, ("semiconductor", True)), (0.35, ("semiconductor", True)),
                                        (0.45, ("metal", False)), (0.95, ("metal", False))])
def test_classify_f0(y, expected):
    assert wcolour.classify_f0(y) == expected


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan")])
def test_classify_f0_refuses_impossible_values(bad):
    with pytest.raises(WaveopticsError, match="F0 luminance"):
        wcolour.classify_f0(bad)


def test_constant_index_dielectric_f0_is_grey_fresnel():
    """n = 1.5 everywhere: F0 = ((n-1)/(n+1))^2 = 0.04 at every wavelength, hence RGB = 0.04·white."""
    d = wcolour.f0_colour(get_material("1.5"))
    np.testing.assert_allclose(d["f0_linear"], 0.04, atol=0.04 * SRGB_WHITE)
    assert d["category"] == "dielectric" and not d["forbidden_zone"]


# Hoffman, SIGGRAPH 2010-2013 PBS course "Background: Physically-Based Shading", Table 1 (from Real-Time
# Rendering 3rd ed.), linear F0. Our presets use other data sets (Johnson & Christy 1972 for the noble metals,
# Rakić 1995 for Al): the database's gold sets alone span 0.31-0.37 in blue, silver 0.80-0.98. Tolerances per entry:
@pytest.mark.parametrize("spec,reference,tol", [
    ("Cu", (0.95, 0.64, 0.54), HOFFMAN),
    ("Al", (0.91, 0.92, 0.92), HOFFMAN),
    ("Au", (1.00, 0.71, 0.29), (HOFFMAN, HOFFMAN, 0.08)),     # J&C gold: blue 0.365 (McPeak 0.343, Babar 0.307)
    ("Ag", (0.95, 0.93, 0.88), (HOFFMAN, 0.06, 0.10)),        # J&C silver: 0.99, 0.98, 0.98 (very high blue)
    ("main/Ag/Hagemann", (0.95, 0.93, 0.88), HOFFMAN_SAME_DATA),  # older data like the table's: agrees closely
])
def test_f0_of_metals_against_hoffman(spec, reference, tol):
    d = wcolour.f0_colour(get_material(spec))
    rgb = np.minimum(d["f0_linear"], 1.0)  # the table clips gold's red at 1.00
    assert np.all(np.abs(rgb - reference) <= np.asarray(tol)), (spec, d["f0_linear"])
    assert d["category"] == "metal"


def test_gold_red_is_out_of_gamut_and_not_clipped():
    d = wcolour.f0_colour(get_material("Au"))
    assert d["f0_linear"][0] > 1.0 and d["f0_srgb8"][0] == 255
    assert d["f0_linear"][2] < 0.45


def test_silicon_is_in_the_forbidden_zone():
    d = wcolour.f0_colour(get_material("Si"))
    assert d["category"] == "semiconductor" and d["forbidden_zone"]


# --- CLI -----------------------------------------------------------------------------------------------------

def test_cli_f0_json(capsys):
    assert main(["f0", "Au", "BK7", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["material"] for r in rows] == ["Au", "BK7"]
    for r in rows:
        assert set(r) == {"material", "f0_linear", "f0_srgb8", "category", "source"}
        assert all(isinstance(v, int) and 0 <= v <= 255 for v in r["f0_srgb8"])
    assert rows[0]["category"] == "metal" and rows[1]["category"] == "dielectric"
    assert "Johnson" in rows[0]["source"]


def test_cli_f0_text_and_errors(capsys):
    assert main(["f0", "Si", "--illuminant", "A", "--observer", "10"]) == 0
    out = capsys.readouterr().out
    assert "semiconductor" in out and "forbidden zone" in out and "CIE 1964" in out
    assert main(["f0", "Au", "--illuminant", "D66"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "did you mean 'D65'" in err[0]


def test_cli_metamer(tmp_path, capsys):
    png = tmp_path / "plot.png"
    assert main(["metamer", "--target", "D65", "--lines", "465,532,638", "-o", str(png), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert png.is_file() and data["plot"] == str(png)
    np.testing.assert_allclose(data["XYZ_mix"], data["XYZ_target"], rtol=1e-12)
    assert sum(data["power_fractions"]) == pytest.approx(1.0)
    assert main(["metamer", "--lines", "465,532,638", "-o", str(png)]) == 2
    assert "already exists" in capsys.readouterr().err
