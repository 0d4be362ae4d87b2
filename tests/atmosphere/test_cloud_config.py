"""Cloud files and presets (`atmosphere.cloud_config`): every preset loads and cites sources,
and bad files are refused with the key, the value and what is allowed."""

import tomllib

import pytest

from skyscatter.atmosphere.cloud_config import (
    CLOUD_PRESETS_DIR,
    list_cloud_presets,
    load_clouds,
)
from skyscatter.errors import ConfigError, InputError

LAYER = """
[[layer]]
name = "{name}"
base_altitude_m = {base}
top_altitude_m = {top}
coverage = 0.4
water_content_g_m3 = 0.3
"""


def _write(tmp_path, text):
    path = tmp_path / "clouds.toml"
    path.write_text(text)
    return path


def test_the_issue_s_five_presets_load_and_cite_their_sources():
    names = set(list_cloud_presets())
    assert {"cumulus", "stratocumulus", "altocumulus", "cirrus", "stratus"} <= names
    for name in names:
        clouds = load_clouds(name)
        assert clouds.layers and clouds.description
        raw = tomllib.loads((CLOUD_PRESETS_DIR / f"{name}.toml").read_text())
        assert any("doi:" in source for source in raw["sources"]), name


def test_the_stratus_preset_is_the_overcast_deck_of_optical_depth_20():
    # earth-overcast's cloud: optical depth 20 at 550 nm over 500 m (its sources); the preset's
    # water content times the droplets' mass extinction (Mie) gives it back within 2 %.
    from skyscatter.optics.cloud_optics import liquid_cloud_optics
    layer = load_clouds("stratus").layers[0]
    k_ext = liquid_cloud_optics(10.0, 0.1, [550.0]).mass_extinction_m2_g[0]
    depth = k_ext * layer.water_content_g_m3 * (layer.top_altitude_m - layer.base_altitude_m)
    assert depth == pytest.approx(20.0, rel=0.02)


def test_a_file_with_two_layers_is_read_lowest_first(tmp_path):
    text = LAYER.format(name="high", base=4000, top=4500) + LAYER.format(name="low", base=800,
                                                                         top=1500)
    clouds = load_clouds(_write(tmp_path, text))
    assert [layer.name for layer in clouds.layers] == ["low", "high"]


@pytest.mark.parametrize("text, key", [
    (LAYER.format(name="a", base=1000, top=2000) + LAYER.format(name="b", base=1500, top=2500),
     "layer"),
    (LAYER.format(name="a", base=2000, top=1000), "top_altitude_m"),
    (LAYER.format(name="a", base=1000, top=2000).replace("0.4", "1.4"), "coverage"),
    (LAYER.format(name="a", base=1000, top=2000) + "profile = [[0.0, 1.0], [0.5, 2.0]]\n",
     "profile"),
    (LAYER.format(name="a", base=1000, top=2000) + "colour = 3\n", "colour"),
    (LAYER.format(name="a", base=1000, top=2000) + "[layer.particles]\nphase = 'ice'\n"
     "effective_radius_um = 1.0\n", "effective_radius_um"),
    ("name = 'empty'\n", "layer"),
])
def test_bad_cloud_files_name_the_key(tmp_path, text, key):
    with pytest.raises(ConfigError) as error:
        load_clouds(_write(tmp_path, text))
    assert key in str(error.value)


def test_an_unknown_preset_suggests_the_closest_name():
    with pytest.raises(InputError, match="did you mean 'cumulus'"):
        load_clouds("cumulu")
