"""The cloud water-content field (`atmosphere.cloud_field`) and its noise tile
(`atmosphere.cloud_noise`): periodic, reproducible, coverage as the fraction of the volume
that is cloud, and wind as a translation."""

import dataclasses

import numpy as np
import pytest

from skyscatter.atmosphere._cloud_sampling import sample_texture
from skyscatter.atmosphere.cloud_config import CloudLayer, CloudParticles, Clouds, CloudShape
from skyscatter.atmosphere.cloud_field import cloud_field, layer_water
from skyscatter.atmosphere.cloud_noise import noise_texture

RADIUS_M = 6_371_000.0
WAVELENGTHS_NM = np.array([450.0, 550.0, 650.0])


def _layer(coverage=0.4, base_m=1000.0, top_m=2000.0, **shape):
    return CloudLayer("test", "volume", base_m, top_m, coverage, 0.5, ((0.0, 1.0), (1.0, 1.0)),
                      CloudShape(**({"detail_strength": 0.0, "coverage_variation": 0.0,
                                     "edge": 0.01} | shape)), CloudParticles("ice", 30.0))


def _points_in_shell(rng, n, low_m, high_m, spread_m):
    """n random points between the radii R + low and R + high, within ~spread of the pole."""
    horizontal = rng.uniform(-spread_m, spread_m, (n, 2))
    up = np.column_stack([horizontal / RADIUS_M, np.ones(n)])
    up /= np.linalg.norm(up, axis=1, keepdims=True)
    return up * (RADIUS_M + rng.uniform(low_m, high_m, n))[:, None]


def _waters(field, points):
    params, profiles, textures = field.params, field.profiles, field.textures
    return np.array([layer_water(params, profiles, textures, 0, *p, np.linalg.norm(p))
                     for p in points])


def test_the_tile_is_periodic_and_reproducible():
    tile = noise_texture(5, 32)
    again = noise_texture.__wrapped__(5, 32)
    np.testing.assert_array_equal(tile, again)
    assert not np.array_equal(tile, noise_texture(6, 32))
    textures = tile[None]
    for x, y, z in [(3.2, 7.9, 1.1), (-0.4, 31.7, 12.5)]:
        a = sample_texture(textures, 0, 0, x, y, z)
        b = sample_texture(textures, 0, 0, x + 32.0, y - 64.0, z + 96.0)
        assert a == pytest.approx(b, abs=1e-6)
    # the equalised shape channel is uniform on [0, 1]: quantiles are their own levels
    shape = tile[..., 0].ravel()
    np.testing.assert_allclose(np.quantile(shape, [0.1, 0.5, 0.9]), [0.1, 0.5, 0.9], atol=1e-3)
    assert tile[..., 1].min() >= 0.0 and tile[..., 1].max() <= 1.0


@pytest.mark.parametrize("coverage", [0.2, 0.5, 0.8])
def test_coverage_is_the_fraction_of_the_volume_with_cloud(coverage):
    # With a flat profile, no coverage variation, no erosion and a 1 % edge ramp, w > 0 where
    # the equalised shape noise exceeds 1 - coverage: a fraction `coverage` of the texels, and
    # of random points up to the smoothing of trilinear interpolation. The layer spans 3 tiles
    # vertically and 30 across, so the points sample the whole tile. Tolerance 0.03: binomial
    # sigma 0.008 for 4000 points, plus the spatial correlation of the noise.
    layer = _layer(coverage, base_m=1000.0, top_m=10_000.0, scale_m=3000.0)
    field = cloud_field(Clouds((layer,)), RADIUS_M, WAVELENGTHS_NM, texture_size=64)
    points = _points_in_shell(np.random.default_rng(1), 4000, 1000.0, 10_000.0, 4.5e4)
    covered = np.mean(_waters(field, points) > 0.0)
    assert covered == pytest.approx(coverage, abs=0.03)


def test_the_wind_moves_the_field_without_changing_it():
    layer = dataclasses.replace(_layer(), wind_m_s=(12.0, -5.0))
    still = cloud_field(Clouds((layer,)), RADIUS_M, WAVELENGTHS_NM, texture_size=32)
    moved = cloud_field(Clouds((layer,)), RADIUS_M, WAVELENGTHS_NM, time_s=600.0,
                        texture_size=32)
    points = _points_in_shell(np.random.default_rng(2), 300, 1400.0, 1600.0, 2e4)
    shift = 600.0 * np.array([12.0, -5.0, 0.0])  # east = x, north = y at the north pole
    np.testing.assert_allclose(_waters(moved, points + shift), _waters(still, points),
                               atol=1e-9)


def test_no_water_outside_the_layer():
    field = cloud_field(Clouds((_layer(1.0),)), RADIUS_M, WAVELENGTHS_NM, texture_size=32)
    points = np.array([[0.0, 0.0, RADIUS_M + 999.0], [0.0, 0.0, RADIUS_M + 2001.0],
                       [0.0, 0.0, RADIUS_M + 1500.0]])
    water = _waters(field, points)
    assert water[0] == 0.0 and water[1] == 0.0 and water[2] > 0.0
