"""Issue 34: inputs the file formats and conventions of the field allow are accepted with their meaning; the
meaningless or ambiguous ones stay refused in one line naming the field.

References for the expected values are written here, not read from the library: the SI factors (BIPM SI Brochure,
9th ed., 2019, tables 5, 7, 8; the ångström 1e-10 m, ISO 80000-3), the micron (1e-6 m, the micrometre's name until
the 13th CGPM, 1967), CSV (RFC 4180) and its common variants, TOML v1.0.0, Python's complex() grammar and the
IEEE 280 engineering order j before the number. The scattered fraction is checked against Parseval's sum over the
patch, written in the test (J. W. Goodman, *Introduction to Fourier Optics*, 3rd ed., §2.1.2).
"""
import math

import numpy as np
import pytest

from waveoptics.errors import FieldError, WaveopticsError
from waveoptics.units import parse_angle, parse_direction, parse_length, parse_number_list, parse_wavelengths

#: metres per unit, written here from the SI (and the micron, ångström)
M = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "µm": 1e-6, "nm": 1e-9, "pm": 1e-12, "Å": 1e-10}


# ------------------------------------------------------------------------------------------------------------
# Lengths, wavelengths, angles


@pytest.mark.parametrize("text, metres", [
    ("5 nm", 5 * M["nm"]), ("5NM", 5 * M["nm"]), ("1.2 µm", 1.2 * M["µm"]), ("1.2 \u03bcm", 1.2 * M["µm"]),
    ("1.2UM", 1.2 * M["µm"]), ("2 micron", 2 * M["µm"]), ("2 Microns", 2 * M["µm"]), ("3Å", 3 * M["Å"]),
    ("3 \u212b", 3 * M["Å"]), ("3A", 3 * M["Å"]), ("4 angstrom", 4 * M["Å"]), ("1cm", M["cm"]),
    ("7 nanometres", 7 * M["nm"]), ("7 nanometer", 7 * M["nm"]), ("+5e0nm", 5 * M["nm"]), ("1.5E-3mm", 1.5e-6),
    ("0.5 millimetre", 0.5 * M["mm"]), ("\t5nm ", 5 * M["nm"])])
def test_unit_spellings_the_si_and_the_field_use_are_lengths(text, metres):
    assert parse_length(text) == pytest.approx(metres, rel=1e-14)


@pytest.mark.parametrize("text, needle", [
    ("5", "needs a unit"),            # deliberate: a bare number could be m or nm
    ("-5nm", "negative"), ("nan nm", "is not a length"), ("inf nm", "is not a length"),
    ("1,5nm", "is not a length"),      # a decimal comma or a list: ambiguous
    ("5M", "unknown unit"),           # a single letter keeps its SI case: M is the mega prefix, no unit
    ("5a", "unknown unit"), ("5 furlong", "unknown unit"), ("5nm.", "unknown unit")])
def test_meaningless_lengths_stay_refused_naming_the_field(text, needle):
    with pytest.raises(FieldError, match=needle) as err:
        parse_length(text, name="sigma")
    assert err.value.field == "sigma" and "\n" not in str(err.value)


@pytest.mark.parametrize("text, nm", [
    ("450, 550", [450, 550]), (" 450 ,550 ", [450, 550]), ("4.5e2,5.5E2", [450, 550]), ("+450", [450]),
    ("0.45 \u03bcm, 0.55µm", [450, 550]), ("450 NM", [450]), ("5500A, 6000Å", [550, 600]),
    ("0.5 micron", [500]), ("400nm:700nm:100nm", [400, 500, 600, 700])])
def test_wavelength_lists_with_blanks_units_and_scientific_notation(text, nm):
    np.testing.assert_allclose(parse_wavelengths(text), nm, rtol=1e-14)


def test_an_upper_case_or_greek_mu_unit_is_never_read_as_nm():
    # before issue 34 the suffix matched case-insensitively but its factor was looked up exactly: 500UM was 500 nm
    np.testing.assert_allclose(parse_wavelengths("500UM"), [5e5], rtol=1e-14)
    with pytest.raises(FieldError, match="below 100 nm"):   # 0.045 µm = 45 nm: refused as 45 nm, not 0.045 nm
        parse_wavelengths("0.045\u03bcm")


@pytest.mark.parametrize("text", ["450;550", "450 550", "nan", "450,,550", "450 furlong"])
def test_ambiguous_wavelength_lists_stay_refused(text):
    with pytest.raises(FieldError) as err:
        parse_wavelengths(text)
    assert err.value.field == "wavelengths_nm" and "\n" not in str(err.value)


@pytest.mark.parametrize("text, want", [
    ("30", (30.0, 0.0)), ("30deg", (30.0, 0.0)), ("30 °", (30.0, 0.0)), ("30°,45°", (30.0, 45.0)),
    ("30 degrees, 45 DEG", (30.0, 45.0)), ("3e1, +45", (30.0, 45.0)), (f"{math.pi / 6!r}rad", (30.0, 0.0))])
def test_angles_carry_deg_degree_or_degree_sign_or_radians(text, want):
    assert parse_direction(text) == pytest.approx(want, rel=1e-12)


def test_angle_lists_and_single_angles_take_the_same_suffixes():
    from waveoptics.units import ANGLE_UNITS

    np.testing.assert_allclose(parse_number_list("0°:60°:30°", units=ANGLE_UNITS), [0, 30, 60])
    assert parse_angle("12.5 deg") == 12.5
    for bad in ("30 furlong", "nan°", "thirty"):
        with pytest.raises(FieldError):
            parse_angle(bad, name="phi_deg")
    with pytest.raises(FieldError, match="outside the allowed range"):
        parse_direction("95°")


# ------------------------------------------------------------------------------------------------------------
# Height-field files


def _write(path, text: str, newline="\n"):
    path.write_bytes(text.replace("\n", newline).encode("utf-8"))
    return path


GRID = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]


@pytest.mark.parametrize("header, body, scale, dx", [
    ("# units = nm\n# dx = 50 nm\n", "1 2 3\n4 5 6\n", 1e-9, 50e-9),           # spacing with its unit
    ("# units = nm\n# dx = 0.05um\n", "1 2 3\n4 5 6\n", 1e-9, 50e-9),
    ("# units = micron\n# dx = 0.05\n", "1 2 3\n4 5 6\n", 1e-6, 0.05e-6),       # unit names in metadata
    ("# units = Å\n# dx = 500\n", "1 2 3\n4 5 6\n", 1e-10, 500e-10),
    ("# Units = NM\n# DX = 50\n", "1\t2\t3\n4\t5\t6\n", 1e-9, 50e-9),             # tabs, upper case
    ("# units = nm\n# dx = 5e1\n", "1;2;3 # first row\n4;5;6\n\n\n", 1e-9, 50e-9)])  # ';', comments, blank end
def test_text_height_files_with_units_comments_and_separators(tmp_path, header, body, scale, dx):
    from waveoptics.surfaces import load

    for newline in ("\n", "\r\n"):
        hf = load(_write(tmp_path / "h.txt", "\ufeff" + header + body, newline))
        np.testing.assert_allclose(hf.heights, np.array(GRID) * scale, rtol=1e-14)
        assert hf.dx == pytest.approx(dx, rel=1e-14) and hf.dy == pytest.approx(dx, rel=1e-14)


@pytest.mark.parametrize("arrays, dx, dy", [
    (dict(heights=GRID, spacing=5e-8), 5e-8, 5e-8),
    (dict(heights=GRID, spacing=[5e-8, 6e-8]), 5e-8, 6e-8),
    (dict(heights=GRID, spacing="50nm"), 50e-9, 50e-9),                   # text with a unit
    (dict(heights=GRID, dx="50 nm", dy="0.06um"), 50e-9, 60e-9),
    (dict(heights=GRID, dx=0.05, units="micron"), 0.05e-6, 0.05e-6),
    (dict(z=GRID, dx=5e-8), 5e-8, 5e-8),                                  # the one array besides metadata
    (dict(Z=GRID, x=[0.0, 5e-8, 10e-8], y=[0.0, 6e-8]), 5e-8, 6e-8)])      # np.meshgrid-style coordinates
def test_npz_spacing_as_scalar_pair_text_or_coordinates(tmp_path, arrays, dx, dy):
    from waveoptics.surfaces import load

    np.savez(tmp_path / "h.npz", **{k: np.asarray(v) for k, v in arrays.items()})
    hf = load(tmp_path / "h.npz")
    scale = 1e-6 if arrays.get("units") == "micron" else 1.0
    np.testing.assert_allclose(hf.heights, np.array(GRID) * scale, rtol=1e-14)
    assert (hf.dx, hf.dy) == pytest.approx((dx, dy), rel=1e-12)


def test_npy_sidecar_spacing_with_a_unit(tmp_path):
    import json

    from waveoptics.surfaces import load

    np.save(tmp_path / "h.npy", np.array(GRID))
    (tmp_path / "h.npy.json").write_text(json.dumps({"units": "nm", "dx": "0.05 micron", "dy": 60}))
    hf = load(tmp_path / "h.npy")
    np.testing.assert_allclose(hf.heights, np.array(GRID) * 1e-9, rtol=1e-14)
    assert (hf.dx, hf.dy) == pytest.approx((50e-9, 60e-9), rel=1e-12)


def test_npz_integer_mask_of_zeros_and_ones_is_the_valid_samples(tmp_path):
    from waveoptics.surfaces import load

    mask = np.array([[1, 1, 0], [1, 0, 1]], dtype=np.uint8)
    np.savez(tmp_path / "m.npz", heights=np.array(GRID), mask=mask, dx=5e-8)
    hf = load(tmp_path / "m.npz")
    np.testing.assert_array_equal(hf.mask, mask == 1)
    np.savez(tmp_path / "bad.npz", heights=np.array(GRID), mask=mask * 2, dx=5e-8)   # 2 means nothing
    with pytest.raises(WaveopticsError, match="0/1 integers"):
        load(tmp_path / "bad.npz")


@pytest.mark.parametrize("arrays, needle", [
    (dict(a=GRID, b=GRID, dx=5e-8), "no 'heights'"),                       # two candidates: ambiguous
    (dict(heights=GRID, x=[0.0, 5e-8, 7e-8], y=[0.0, 6e-8]), "regular grid"),
    (dict(heights=GRID, spacing="fifty"), "not a number or a length"),
    (dict(heights=GRID, spacing="-5nm"), "not a number or a length")])
def test_npz_meaningless_metadata_stays_refused(tmp_path, arrays, needle):
    from waveoptics.surfaces import load

    np.savez(tmp_path / "h.npz", **{k: np.asarray(v) for k, v in arrays.items()})
    with pytest.raises(WaveopticsError, match=needle) as err:
        load(tmp_path / "h.npz")
    assert "\n" not in str(err.value)


# ------------------------------------------------------------------------------------------------------------
# Spectra (SPD files, laser lines)


@pytest.mark.parametrize("text", [
    "wavelength;lamp\n400;1\n500;2\n600;3\n", "wavelength\tlamp\n400\t1\n500\t2\n600\t3\n",
    "400 1\n500   2\n600 3\n", "# lamp, measured 2026\nwavelength,lamp\n400,1\n500,2 # peak\n600,3\n",
    "wavelength,lamp,\n400,1,\n500,2,\n600,3,\n", "wavelength;lamp\n400;1,0\n500;2,0\n600;3,0\n",
    '"wavelength (nm)","lamp"\n"4e2","+1"\n"500","2"\n"600","3"\n'])
def test_spd_files_with_other_separators_comments_and_trailing_separators(tmp_path, text):
    from waveoptics.colour.illuminants import spd_from_csv

    for newline in ("\n", "\r\n"):
        spd = spd_from_csv(_write(tmp_path / "lamp.csv", "\ufeff" + text + "\n\n", newline))
        np.testing.assert_allclose(spd.wavelengths_nm, [400, 500, 600])
        np.testing.assert_allclose(spd.values, [1, 2, 3])


@pytest.mark.parametrize("text, needle", [("400,1\n500,x\n", "line 2"), ("400;1;2\n500;2\n", "same columns")])
def test_spd_files_with_bad_rows_stay_refused(tmp_path, text, needle):
    from waveoptics.colour.illuminants import spd_from_csv

    with pytest.raises(WaveopticsError, match=needle):
        spd_from_csv(_write(tmp_path / "lamp.csv", text))


@pytest.mark.parametrize("spec, lines", [("laser:532NM", [532]), ("laser: 465, 532 nm, 0.638um", [465, 532, 638]),
                                         ("laser:5320A", [532])])
def test_laser_lines_take_any_length_unit(spec, lines):
    from waveoptics.colour.illuminants import illuminant

    np.testing.assert_allclose(illuminant(spec).wavelengths_nm, lines, rtol=1e-14)
    for bad in ("laser:532:600:1", "laser:abc", "laser:"):
        with pytest.raises(WaveopticsError, match="write laser:NM"):
            illuminant(bad)


# ------------------------------------------------------------------------------------------------------------
# Materials


@pytest.mark.parametrize("text, eta", [
    ("1.5+0.01i", 1.5 + 0.01j), ("(1.5+0.01j)", 1.5 + 0.01j), ("1.5 + 0.01 j", 1.5 + 0.01j),
    ("1.5+0.01I", 1.5 + 0.01j), ("1.5+0.01J", 1.5 + 0.01j), ("1.5+j0.01", 1.5 + 0.01j), ("+1.5e0", 1.5 + 0j),
    (" ( 0.2 + 3.1i ) ", 0.2 + 3.1j)])
def test_complex_indices_in_the_common_notations(text, eta):
    from waveoptics.materials import get_material

    assert complex(get_material(text).eta(np.array([550.0]))[0]) == pytest.approx(eta, rel=1e-14)


@pytest.mark.parametrize("text", ["1.5-0.01j", "nan", "(1.5+0.01j", "1.5+0.01k"])
def test_ambiguous_or_meaningless_indices_stay_refused(text):
    from waveoptics.materials import get_material

    # n − ik is absorbing only in the engineering exp(+jωt) convention: ambiguous, refused
    with pytest.raises(WaveopticsError) as err:
        get_material(text)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("name, preset", [("GOLD", "Au"), ("Gold", "Au"), (" au ", "Au"), ("Fused Silica", "fused-silica"),
                                          ("fused_silica", "fused-silica"), ("MAGNESIUM FLUORIDE", "MgF2")])
def test_preset_names_in_any_case_with_blanks_or_underscores(name, preset):
    from waveoptics.materials import get_material

    assert get_material(name).name == preset


def test_a_stack_with_blanks_and_unit_spellings():
    from waveoptics.materials import get_material

    assert get_material("al | al2o3 : 0.12 micron").name == "Al|Al2O3:120nm"
    for bad in ("Al|Al2O3:120", "Al|Al2O3:-5nm"):   # deliberate: a thickness needs its unit and is >= 0
        with pytest.raises(FieldError, match="thickness"):
            get_material(bad)


# ------------------------------------------------------------------------------------------------------------
# Scene files


SCENE = '''name = "t"
[[materials]]
name = "m"
{material}
roughness = {roughness}
[[lights]]
name = "l"
spd = "{spd}"
directions_deg = {dirs}
[output]
rgb_images = true
'''


@pytest.mark.parametrize("fields, dirs, material", [
    (dict(material='material = "GOLD"', roughness="0", spd="D65", dirs="[[30, 0]]"), ((30.0, 0.0),), "GOLD"),
    (dict(material='material = "Au"', roughness="1e-1", spd="D65", dirs='[["30deg", "45°"]]'), ((30.0, 45.0),),
     "Au"),
    (dict(material='ior = "(1.5 + 0.01i)"', roughness="0.1", spd="laser:532 nm", dirs='"30°"'), ((30.0, 0.0),),
     "(1.5 + 0.01i)")])
def test_scene_with_bom_crlf_integers_and_angles_with_units(tmp_path, fields, dirs, material):
    from waveoptics.planning import scene

    for prefix, newline in (("", "\n"), ("\ufeff", "\r\n")):
        sc = scene.load(_write(tmp_path / "s.toml", prefix + SCENE.format(**fields), newline))
        assert sc.lights[0].directions_deg == dirs and sc.materials[0].material == material


@pytest.mark.parametrize("fields, needle", [
    (dict(material='material = "Au"', roughness="-0.1", spd="D65", dirs="[[30, 0]]"), "roughness = -0.1"),
    (dict(material='material = "Au"', roughness="nan", spd="D65", dirs="[[30, 0]]"), "roughness = nan"),
    (dict(material='material = "Au"', roughness="0.1", spd="D65", dirs='[["30 furlong", 0]]'), "theta")])
def test_scene_meaningless_values_stay_refused_naming_the_key(tmp_path, fields, needle):
    from waveoptics.planning import scene

    with pytest.raises(WaveopticsError, match=needle) as err:
        scene.load(_write(tmp_path / "s.toml", SCENE.format(**fields)))
    assert "\n" not in str(err.value)


# ------------------------------------------------------------------------------------------------------------
# Scattered fraction: the incoherent lobe's own integral (issue 34, item 3)


@pytest.mark.filterwarnings("ignore:aliasing")   # 250 nm samples alias near the horizon only; this lobe is narrow
@pytest.mark.parametrize("sigma, theta", [(0.05e-9, 40.0), (2e-9, 0.0), (2e-9, 40.0)])
def test_scattered_fraction_is_the_parseval_sum_of_the_patch(sigma, theta):
    """For a patch with correlation length ≫ λ the scattered light stays near the mirror direction, where Parseval's
    theorem makes the incoherent lobe's integral F Σ w² |exp(i v_z h) − χ|² / Σ w² (w the Hann window, χ the
    w²-mean of exp(i v_z h), v_z = 4π cos θ_i / λ). At σ = 0.05 nm and 40° the former difference
    albedo − |χ|² · flat came out −8.4e-7 (the quadrature of the mirror spike) and was clipped to 0."""
    from waveoptics import scatter, surfaces

    lam, F, n = 550.0, 0.9, 128
    hf = surfaces.gaussian(sigma, 2e-6, 32e-6, n, seed=3)
    res = scatter.scatter(hf, (theta, 0.0), [lam], F, resolution=128, window_name="hann")
    w2 = np.outer(np.hanning(n), np.hanning(n)) ** 2
    e = np.exp(1j * 4 * np.pi * math.cos(math.radians(theta)) / (lam * 1e-9) * hf.heights)
    chi = np.sum(w2 * e) / np.sum(w2)
    ref = F * np.sum(w2 * np.abs(e - chi) ** 2) / np.sum(w2)
    assert res.scattered_fraction[0] == pytest.approx(ref, rel=2e-3), (res.scattered_fraction[0], ref)


def test_scattered_fraction_of_an_ensemble_adds_the_spread_of_the_coherent_amplitudes():
    """Two patches: the ensemble's incoherent light is the mean of each patch's Parseval sum plus
    F · mean |χ_r − χ̄|² (light specular in each patch that does not add coherently over the ensemble)."""
    from waveoptics import scatter, surfaces

    lam, F, n = 550.0, 0.9, 128
    hfs = [surfaces.gaussian(3e-9, 2e-6, 32e-6, n, seed=s) for s in (11, 12)]
    res = scatter.scatter(hfs, (0.0, 0.0), [lam], F, resolution=128, window_name="hann")
    w2 = np.outer(np.hanning(n), np.hanning(n)) ** 2
    es = [np.exp(1j * 4 * np.pi / (lam * 1e-9) * hf.heights) for hf in hfs]
    chis = np.array([np.sum(w2 * e) / np.sum(w2) for e in es])
    per_patch = np.mean([np.sum(w2 * np.abs(e - c) ** 2) / np.sum(w2) for e, c in zip(es, chis)])
    ref = F * (per_patch + np.mean(np.abs(chis - chis.mean()) ** 2))
    assert res.scattered_fraction[0] == pytest.approx(ref, rel=2e-3), (res.scattered_fraction[0], ref)


# ------------------------------------------------------------------------------------------------------------
# Command line: an angle option with a unit, a wrong one refused with exit 2


def test_compare_tail_and_incident_angles_take_degree_suffixes():
    from waveoptics.cli import shared_parser

    args = shared_parser().parse_args(["compare", "--tail", "12.5°", "--incident-angles", "0deg:60deg:30deg"])
    assert args.tail == 12.5
    from waveoptics.units import ANGLE_UNITS

    np.testing.assert_allclose(parse_number_list(args.incident_angles, units=ANGLE_UNITS), [0, 30, 60])
    with pytest.raises(SystemExit) as ex:
        shared_parser().parse_args(["compare", "--tail", "ten"])
    assert ex.value.code == 2
