"""Dotted-key changes of a config (atmosphere.config_overrides) against the same change made in
the TOML text, and the vertical optical depth the changed value sets."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from skyscatter.atmosphere.config import PRESETS_DIR, load_atmosphere
from skyscatter.atmosphere.config_overrides import (
    MAX_AXIS_VALUES,
    atmosphere_with,
    get_value,
    load_document,
    parse_value,
    parse_values,
    with_values,
)
from skyscatter.errors import ConfigError, InputError
from skyscatter.validate.mars_models import vertical_optical_depths


def test_a_changed_value_is_the_config_file_edited_by_hand(tmp_path):
    text = (PRESETS_DIR / "earth.toml").read_text()
    edited = tmp_path / "earth-edited.toml"
    for table in PRESETS_DIR.glob("*.csv"):  # the profiles earth.toml names
        (tmp_path / table.name).write_bytes(table.read_bytes())
    edited.write_text(text.replace("optical_depth = 0.1,", "optical_depth = 0.37,")
                      .replace("ground_albedo = 0.1", "ground_albedo = 0.25")
                      .replace('name = "earth"', 'name = "earth-edited"', 1))
    document, path = load_document("earth")
    changed = atmosphere_with(document, path, {"constituent[2].optics.optical_depth": 0.37,
                                               "planet.ground_albedo": np.float64(0.25)})
    by_hand = load_atmosphere(edited)
    wavelengths = [400.0, 550.0, 900.0]
    for name, depth in vertical_optical_depths(by_hand, wavelengths).items():
        np.testing.assert_allclose(vertical_optical_depths(changed, wavelengths)[name], depth,
                                   rtol=1e-12)
    assert changed.planet.ground_albedo == by_hand.planet.ground_albedo
    # the aerosol's optical depth at its 500 nm reference is the value set (exact: the
    # Angstrom optics is scaled to it)
    assert vertical_optical_depths(changed, [500.0])["aerosol"][0] == pytest.approx(0.37,
                                                                                     rel=1e-9)


def test_the_document_read_is_left_as_it_was():
    document, _ = load_document("earth")
    before = copy.deepcopy(document)
    with_values(document, {"planet.ground_albedo": 0.9, "tables.orders": 3})
    assert document == before


def test_a_missing_table_on_the_way_is_created_and_parsed():
    document, path = load_document("earth")
    del document["tables"]  # [tables] is optional
    assert atmosphere_with(document, path, {"tables.orders": 3}).scattering_orders == 3


@pytest.mark.parametrize(("key", "words"), [
    ("constituent[7].optics.optical_depth", "has 3 entries"),
    ("planet[0].radius_m", "not an array of tables"),
    ("planet.radius_m.x", "is a value, not a table"),
    ("planet..radius_m", "is not a config key"),
    ("", "is not a config key"),
])
def test_a_key_that_goes_nowhere_is_named(key, words):
    document, _ = load_document("earth")
    with pytest.raises(InputError, match=words):
        with_values(document, {key: 1.0})


def test_a_misspelt_leaf_gets_the_config_parsers_message():
    document, path = load_document("earth")
    with pytest.raises(ConfigError, match="did you mean 'planet.ground_albedo'"):
        atmosphere_with(document, path, {"planet.ground_albedoo": 0.3})
    with pytest.raises(InputError, match="has no 'ground_albedoo'"):
        get_value(document, "planet.ground_albedoo")


def test_values_are_read_as_toml_or_as_bare_words():
    assert parse_value("0.3") == 0.3
    assert parse_value("5") == 5
    assert parse_value("true") is True
    assert parse_value("{ real = 1.5, imaginary = 0.01 }") == {"real": 1.5, "imaginary": 0.01}
    assert parse_value("mie") == "mie"
    assert parse_values("0,0.1,0.3") == [0.0, 0.1, 0.3]
    assert parse_values("{ a = 1, b = 2 },[1, 2]") == [{"a": 1, "b": 2}, [1, 2]]


def test_ranges_are_numpys_linspace_and_geomspace():
    assert parse_values("0.02:0.8:20") == pytest.approx(np.linspace(0.02, 0.8, 20), abs=0)
    logarithmic = parse_values("0.01:1:5:log")
    assert logarithmic == pytest.approx([0.01, 10**-1.5, 0.1, 10**-0.5, 1.0], rel=1e-12)
    assert all(math.isfinite(v) for v in logarithmic)


@pytest.mark.parametrize(("text", "words"), [
    ("0:1:1", "COUNT from 2"),
    (f"0:1:{MAX_AXIS_VALUES + 1}", "COUNT from 2"),
    ("0:1:x", "is not a range"),
    ("0:nan:3", "finite ends"),
    ("0:1:3:lin", "may only be 'log'"),
    ("0:1:3:log", "positive ends"),
    ("0,,1", "no value"),
    (",".join(["1"] * (MAX_AXIS_VALUES + 1)), "more than"),
])
def test_bad_axes_are_refused_with_the_reason(text, words):
    with pytest.raises(InputError, match=words):
        parse_values(text)
