"""Coverage maps of cloud layers (`atmosphere.cloud_maps`, the `coverage_map` key of a clouds
file): read as documented, refused with the file and what is wrong, oriented by the observer's
latitude and longitude, and the demo map of the `earth-weather` preset."""

import dataclasses

import numpy as np
import pytest
from PIL import Image

from skyscatter.atmosphere._cloud_sampling import coverage_map_factor
from skyscatter.atmosphere.cloud_config import Clouds, load_clouds
from skyscatter.atmosphere.cloud_field import _observer_axes, cloud_field, layer_water
from skyscatter.atmosphere.cloud_maps import (
    ZONAL_CLOUD_FRACTION,
    demo_coverage_map,
    read_coverage_map,
    zonal_cloud_fraction,
)
from skyscatter.errors import ConfigError

RADIUS_M = 6_371_000.0
LAYER = """
[[layer]]
name = "mapped"
base_altitude_m = 1000.0
top_altitude_m = 2000.0
coverage = 0.6
water_content_g_m3 = 0.3
coverage_map = "{map}"
[layer.shape]
coverage_variation = 0.0
"""


def _clouds_file(tmp_path, name="map.npy"):
    path = tmp_path / "clouds.toml"
    path.write_text(LAYER.format(map=name))
    return path


def _point(latitude_deg, longitude_deg, altitude_m=1500.0):
    """A planet-fixed point (z to the north pole, x to longitude 0)."""
    return (RADIUS_M + altitude_m) * _observer_axes(latitude_deg, longitude_deg)[:, 2]


def test_grey_pngs_and_npy_maps_read_as_fractions(tmp_path):
    levels = np.array([[0, 51, 255], [255, 102, 0]], dtype=np.uint8)
    Image.fromarray(levels).save(tmp_path / "a.png")
    np.testing.assert_allclose(read_coverage_map(tmp_path / "a.png"), levels / 255.0)
    wide = np.array([[0, 65535], [13107, 32768]], dtype=np.uint16)
    Image.fromarray(wide).save(tmp_path / "b.png")
    np.testing.assert_allclose(read_coverage_map(tmp_path / "b.png"), wide / 65535.0)
    np.save(tmp_path / "c.npy", np.array([[0.25, 1.0], [0.0, 0.5]]))
    np.testing.assert_array_equal(read_coverage_map(tmp_path / "c.npy"),
                                  [[0.25, 1.0], [0.0, 0.5]])


@pytest.mark.parametrize("content, message", [
    (None, "no such file"),
    (np.array([[0.5, 1.5], [0.0, 0.2]]), "lie in \\[0, 1\\]"),
    (np.array([[0.5, np.nan], [0.0, 0.2]]), "finite"),
    (np.array([0.5, 0.2, 0.1]), "shape"),
    (np.array([[1, 0], [0, 1]]), "floats"),
    ("rgb", "grey"),
    ("text", "cannot read"),
])
def test_bad_coverage_maps_are_refused_with_the_key_and_the_file(tmp_path, content, message):
    name = "map.npy"
    if isinstance(content, np.ndarray):
        np.save(tmp_path / name, content)
    elif content == "rgb":
        name = "map.png"
        Image.fromarray(np.zeros((4, 8, 3), dtype=np.uint8)).save(tmp_path / name)
    elif content == "text":
        name = "map.png"
        (tmp_path / name).write_text("not an image")
    with pytest.raises(ConfigError, match=message) as error:
        load_clouds(_clouds_file(tmp_path, name))
    text = str(error.value)
    assert "coverage_map" in text and name in text and "clouds.toml" in text


def test_the_map_path_is_relative_to_the_clouds_file(tmp_path):
    np.save(tmp_path / "map.npy", np.full((2, 4), 0.5))
    elsewhere = tmp_path / "sub"
    elsewhere.mkdir()
    (elsewhere / "clouds.toml").write_text(LAYER.format(map="../map.npy"))
    layer = load_clouds(elsewhere / "clouds.toml").layers[0]
    np.testing.assert_array_equal(layer.coverage_map.values, 0.5)


def test_the_map_is_read_at_the_point_s_latitude_and_longitude(tmp_path):
    # A 4 x 8 map whose pixel (row, column) holds 8 row + column, over 45 deg x 45 deg
    # pixels: the centre of pixel (1, 2) is at latitude 22.5, longitude -180 + 112.5 = -67.5
    # and holds 10; halfway between pixel centres the value is their mean (bilinear: 10.5 at
    # longitude -45, 6 at latitude 45 between rows 0 and 1); the
    # longitude wraps (column 7 next to column 0). Expected numbers from the layout in the
    # docs (row 0 at +90 deg, column 0 from -180 deg), with the field built for an orbit
    # camera (world = planet-fixed) and for an observer at (30, 40) on the north-pole frame.
    values = (8.0 * np.arange(4)[:, None] + np.arange(8)[None, :]) / 31.0
    np.save(tmp_path / "map.npy", values)
    clouds = load_clouds(_clouds_file(tmp_path))
    cases = [((22.5, -67.5), 10.0), ((22.5, -45.0), 10.5), ((45.0, -67.5), 6.0),
             ((-67.5, 157.5), 31.0), ((-67.5, 180.0), 27.5), ((89.0, -157.5), 0.0)]
    planet = cloud_field(clouds, RADIUS_M, np.array([550.0]), texture_size=8,
                         latitude_deg=30.0, longitude_deg=40.0,
                         to_world=_observer_axes(30.0, 40.0))
    pole = cloud_field(clouds, RADIUS_M, np.array([550.0]), texture_size=8,
                       latitude_deg=30.0, longitude_deg=40.0)  # world = the observer's frame
    to_pole_frame = _observer_axes(30.0, 40.0).T  # planet-fixed -> the observer's ENU
    for (lat, lon), expected in cases:
        p = _point(lat, lon)
        got = coverage_map_factor(planet.params, planet.profiles, 0, *p)
        assert got == pytest.approx(expected / 31.0, abs=1e-12), (lat, lon)
        q = to_pole_frame @ p
        got = coverage_map_factor(pole.params, pole.profiles, 0, *q)
        assert got == pytest.approx(expected / 31.0, abs=1e-12), (lat, lon)


def test_where_the_map_is_0_there_is_no_water_and_where_it_is_1_the_layer_is_unchanged(
        tmp_path):
    # West of longitude 0 the map is 0, east of it 1 (columns 0-3 and 4-7 of 8): points in
    # the middle of each half (lon -90, +90) see 0 and exactly the unmapped layer's water.
    values = np.zeros((4, 8))
    values[:, 4:] = 1.0
    np.save(tmp_path / "map.npy", values)
    mapped = cloud_field(load_clouds(_clouds_file(tmp_path)), RADIUS_M, np.array([550.0]),
                         texture_size=16, to_world=_observer_axes(0.0, 0.0))
    layer = load_clouds(_clouds_file(tmp_path)).layers[0]
    plain = cloud_field(Clouds((dataclasses.replace(layer, coverage_map=None),)), RADIUS_M,
                        np.array([550.0]), texture_size=16, to_world=_observer_axes(0.0, 0.0))
    rng = np.random.default_rng(3)
    wet = 0
    for _ in range(200):
        east = _point(rng.uniform(-30, 30), rng.uniform(70, 110), rng.uniform(1000, 2000))
        west = _point(rng.uniform(-30, 30), rng.uniform(-110, -70), rng.uniform(1000, 2000))
        for field, p, same in ((mapped, west, False), (mapped, east, True)):
            w = layer_water(field.params, field.profiles, field.textures, 0, *p,
                            np.linalg.norm(p))
            reference = layer_water(plain.params, plain.profiles, plain.textures, 0, *p,
                                    np.linalg.norm(p))
            assert w == (reference if same else 0.0)
            wet += w > 0.0
    assert wet > 50  # coverage 0.6: about 120 of the 200 eastern points


def test_the_demo_map_follows_the_zonal_climatology():
    # The zonal means of the demo map against the nodes it was made from (GEWEX Cloud
    # Assessment / MODIS zonal cloud fraction, `ZONAL_CLOUD_FRACTION`): the large-scale
    # noise spreads each band; its global mean (area-weighted) within 0.1 of the zonal
    # curve's (0.67), and every 30-degree band's within 0.2 of the curve's there (the noise
    # has systems ~20 degrees across, so a band holds only a few).
    coverage = demo_coverage_map(256, 128)
    latitude = 90.0 - (np.arange(128) + 0.5) * 180.0 / 128
    weight = np.cos(np.radians(latitude))
    zonal = coverage.mean(axis=1)
    curve = zonal_cloud_fraction(latitude)
    assert np.average(zonal, weights=weight) == pytest.approx(
        np.average(curve, weights=weight), abs=0.1)
    for low in range(-90, 90, 30):
        band = (latitude >= low) & (latitude < low + 30)
        assert np.average(zonal[band], weights=weight[band]) == pytest.approx(
            np.average(curve[band], weights=weight[band]), abs=0.2), low
    assert coverage.min() >= 0.0 and coverage.max() <= 1.0
    assert ZONAL_CLOUD_FRACTION[0, 0] == -90.0 and ZONAL_CLOUD_FRACTION[-1, 0] == 90.0


def test_the_earth_weather_preset_ships_its_map():
    clouds = load_clouds("earth-weather")
    maps = [layer.coverage_map for layer in clouds.layers]
    assert all(m is not None for m in maps)
    assert maps[0].values.shape == (512, 1024)
    np.testing.assert_array_equal(maps[0].values,
                                  np.round(demo_coverage_map(1024, 512) * 255.0) / 255.0)
