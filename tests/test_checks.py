"""The validation layer's primitives (checks.py): what they refuse and how the refusal reads."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.checks import (
    checked_array,
    checked_choice,
    checked_finite_array,
    checked_instance,
    checked_integer,
    checked_number,
)
from skyscatter.errors import InputError


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 10**400, -(10**400), True,
                                   "0.5", b"0.5", None, [0.5]])
def test_checked_number_refuses_what_is_not_a_finite_number_in_range(value):
    with pytest.raises(InputError) as error:
        checked_number("sun_zenith_deg", value, 0.0, 180.0)
    message = str(error.value)
    # One short line naming the input and the range, whatever the value (a 400-digit integer
    # is shortened, not printed whole).
    assert message.startswith("sun_zenith_deg = ")
    assert "\n" not in message and len(message) < 200
    assert error.value.key == "sun_zenith_deg"


def test_checked_number_keeps_the_bounds_open_or_closed_as_asked():
    assert checked_number("x", 0.0, 0.0, 1.0) == 0.0
    with pytest.raises(InputError, match="> 0"):
        checked_number("x", 0.0, 0.0, 1.0, low_open=True)
    assert checked_number("x", np.float32(0.25), 0.0, 1.0) == 0.25


def test_checked_integer_refuses_floats_bools_and_out_of_range():
    assert checked_integer("orders", np.int64(4), 1, 1000) == 4
    for value in (4.0, True, 0, 1001, "4"):
        with pytest.raises(InputError, match="a whole number from 1 to 1000"):
            checked_integer("orders", value, 1, 1000)


def test_checked_array_names_the_first_bad_element_and_refuses_text_and_bools():
    assert checked_array("wavelengths_nm", [440, 550.0], 280.0, 1690.0).dtype == np.float64
    with pytest.raises(InputError, match="wavelengths_nm = nan"):
        checked_array("wavelengths_nm", [440.0, math.nan], 280.0, 1690.0)
    for values in (["440"], [440.0, True], [[440.0], "x"]):
        with pytest.raises(InputError, match="is not allowed: numbers"):
            checked_array("wavelengths_nm", values, 280.0, 1690.0)


@pytest.mark.parametrize("value", ["sepia", "ACES", None, 3, ["aces"], {"aces": 1}])
def test_checked_choice_refuses_names_not_listed_and_non_text(value):
    # a list or dict as the value (unhashable) must be refused like any other, not TypeError
    with pytest.raises(InputError) as raised:
        checked_choice("tone curve", "operator", value, ("aces", "clamp"))
    assert raised.value.key == "operator"
    assert str(raised.value).startswith("unknown tone curve ")
    assert str(raised.value).endswith("choose one of: aces, clamp")


def test_checked_choice_returns_the_name_as_given_and_folds_case_only_when_asked():
    assert checked_choice("colour space", "colour_space", "sRGB", ("srgb",),
                          fold_case=True) == "sRGB"
    with pytest.raises(InputError):
        checked_choice("colour space", "colour_space", "sRGB", ("srgb",))


def test_checked_finite_array_names_the_first_bad_element_its_index_and_the_unit():
    values = np.array([[5000.0, 6000.0], [-1.0, math.nan]])
    with pytest.raises(InputError) as error:
        checked_finite_array("temperature_k", values, "K", positive=True)
    assert str(error.value) == ("temperature_k must be positive and finite; got -1.0 at index "
                                "(1, 0) [K]")
    assert error.value.value == -1.0 and error.value.allowed == "0 < temperature_k < inf [K]"
    with pytest.raises(InputError, match=r"^v_magnitude must be finite; got inf \[mag\]$"):
        checked_finite_array("v_magnitude", math.inf, "mag")
    with pytest.raises(InputError, match="v_magnitude must be numbers in mag"):
        checked_finite_array("v_magnitude", "bright", "mag")
    # zero and negatives are finite: refused only with positive=True
    np.testing.assert_array_equal(checked_finite_array("b_minus_v", [0.0, -0.3], "mag"),
                                  [0.0, -0.3])
    assert checked_finite_array("x", [1, 2], "m", positive=True).dtype == np.float64


def test_checked_instance_returns_the_value_or_names_what_is_allowed_and_where_to_get_it():
    assert checked_instance("n", 3, int, "an int") == 3
    with pytest.raises(InputError) as error:
        checked_instance("observer", "Berlin", tuple, "an Observer", " from make_observer(...)")
    assert str(error.value) == ("observer = 'Berlin' is not allowed: an Observer from "
                                "make_observer(...)")
    assert error.value.key == "observer" and error.value.allowed == "an Observer"
