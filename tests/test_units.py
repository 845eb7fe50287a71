"""waveoptics.units: quantities with units as typed on the command line and in scene files.

References are the SI prefixes (BIPM SI Brochure, 9th ed., 2019, table 7) and plain arithmetic; every parser's
refusal is a FieldError naming the field it was given."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from waveoptics.errors import FieldError
from waveoptics.units import (LENGTH_UNITS, direction_from_angles, parse_direction, parse_length,
                              parse_number_list, parse_wavelengths, split_spec)

#: metres per unit, from the SI prefixes (written here, not read from the module)
SI = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "nm": 1e-9, "pm": 1e-12, "A": 1e-10}


@settings(max_examples=200, derandomize=True, deadline=None)
@given(value=st.floats(min_value=1e-6, max_value=1e6, allow_nan=False), unit=st.sampled_from(sorted(SI)),
       space=st.sampled_from(["", " "]))
def test_a_length_is_its_number_times_the_si_factor(value, unit, space):
    text = f"{value!r}{space}{unit}"
    assert parse_length(text) == pytest.approx(value * SI[unit], rel=1e-15)


def test_every_documented_unit_has_its_si_factor():
    for unit, factor in SI.items():
        assert LENGTH_UNITS[unit] == pytest.approx(factor, rel=1e-15)


@pytest.mark.parametrize("text, needle", [("5", "needs a unit"), ("5 furlong", "unknown unit"),
                                          ("five nm", "is not a length"), ("-5nm", "negative"),
                                          ("0nm", "zero"), ("1e400nm", "not finite")])
def test_a_bad_length_is_refused_naming_its_field(text, needle):
    with pytest.raises(FieldError, match=needle) as err:
        parse_length(text, name="sigma")
    assert err.value.field == "sigma"


def test_bare_numbers_take_the_default_unit_and_zero_or_negative_only_when_allowed():
    assert parse_length(5, default_unit="nm") == pytest.approx(5e-9)
    assert parse_length("0um", allow_zero=True) == 0.0
    assert parse_length("-2um", allow_negative=True) == pytest.approx(-2e-6)


@pytest.mark.parametrize("text, want", [("1:3:1", [1, 2, 3]), ("0:1:0.25", [0, 0.25, 0.5, 0.75, 1.0]),
                                        ("0:1:0.3", [0, 0.3, 0.6, 0.9]), ("4,2,7", [4, 2, 7]), ("5", [5])])
def test_number_lists_and_inclusive_ranges(text, want):
    np.testing.assert_allclose(parse_number_list(text), want, rtol=0, atol=1e-12)


@pytest.mark.parametrize("text", ["1:0:1", "0:1:0", "0:1", "1,,2", ",", "1,nan", "0:1e9:1e-9"])
def test_bad_number_lists_are_refused_in_one_line(text):
    with pytest.raises(FieldError) as err:
        parse_number_list(text, name="vary")
    assert "\n" not in str(err.value) and err.value.field == "vary"


def test_wavelengths_take_nm_or_um_and_stay_in_the_optical_range():
    np.testing.assert_allclose(parse_wavelengths("0.45um,550nm,650"), [450, 550, 650])
    for bad in ("50", "2e6", "0", "-400"):
        with pytest.raises(FieldError) as err:
            parse_wavelengths(bad)
        assert err.value.field == "wavelengths_nm"


def test_directions_are_unit_vectors_at_their_angles():
    theta, phi = parse_direction("30,400")
    assert (theta, phi) == (30.0, pytest.approx(40.0))
    d = direction_from_angles(theta, phi)
    assert np.linalg.norm(d) == pytest.approx(1.0)
    assert math.degrees(math.acos(d[2])) == pytest.approx(30.0)
    assert math.degrees(math.atan2(d[1], d[0])) == pytest.approx(40.0)
    for bad in ("95", "-1", "nan", "30,inf", "a,b", "1,2,3"):
        with pytest.raises(FieldError):
            parse_direction(bad)


def test_the_model_grammar_splits_keys_values_and_bare_items():
    model, items = split_spec(" ABC : sigma = 10nm, B=2um ,junk,")
    assert model == "abc"
    assert items == [("sigma", "10nm", "sigma = 10nm"), ("B", "2um", "B=2um"), ("", "", "junk")]
