"""Clouds through the public API: the same clouds at the same time give the same image, the
wind moves them, and they need the table solver."""

import numpy as np
import pytest

from skyscatter import api
from skyscatter.errors import InputError

WAVELENGTHS_NM = [450.0, 550.0, 650.0]


@pytest.fixture(scope="module")
def atmosphere():
    return api.load_atmosphere("earth")


def _render(atmosphere, **clouds):
    return api.render(atmosphere, api.FisheyeCamera(24), 40.0, 135.0, 2.0,
                      wavelengths_nm=WAVELENGTHS_NM, clouds=api.load_clouds("cumulus"),
                      **clouds).spectral


def test_the_same_clouds_at_the_same_time_give_the_same_image_and_the_wind_moves_them(
        atmosphere):
    first, again = _render(atmosphere), _render(atmosphere)
    np.testing.assert_array_equal(first, again)
    later = _render(atmosphere, cloud_time_s=900.0)  # 6.3 m/s for 15 min: 5.7 km, a cloud
    assert np.mean(np.abs(later - first) > 0.05 * np.abs(first)) > 0.1
    clear = api.render(atmosphere, api.FisheyeCamera(24), 40.0, 135.0, 2.0,
                       wavelengths_nm=WAVELENGTHS_NM).spectral
    assert not np.allclose(first, clear)


def test_clouds_need_the_table_solver(atmosphere):
    with pytest.raises(InputError, match="table solver"):
        api.render(atmosphere, api.FisheyeCamera(8), 40.0, wavelengths_nm=WAVELENGTHS_NM,
                   solver="single", clouds=api.load_clouds("cumulus"))


def test_earth_from_orbit_with_the_earth_weather_clouds(atmosphere):
    # From 20 000 km a 32-pixel image's pixel spans ~400 km, thousands of the earth-weather
    # layers' tiles: the far field draws them (docs/clouds.md). The clouds (the demo map's
    # cover, ~0.6 of the disk) brighten the planet's disk against the clear view, whose
    # ocean-and-land albedo is 0.1 (tests/transport/test_clouds.py checks the far field
    # against closed forms and the columns one by one).
    def orbit(**clouds):
        camera = api.PerspectiveCamera(32, 32, 40.0, 0.0, -90.0)  # at the planet's centre
        return api.render(atmosphere, camera, 40.0, 100.0, 2.0e7,
                          wavelengths_nm=WAVELENGTHS_NM, orbit_latitude_deg=20.0,
                          orbit_longitude_deg=-30.0, **clouds).spectral

    cloudy = orbit(clouds=api.load_clouds("earth-weather"))
    clear = orbit()
    disk = clear[..., 1] > 0.0
    assert disk.sum() > 100 and np.all(np.isfinite(cloudy))
    assert cloudy[disk].mean() > 1.3 * clear[disk].mean()


@pytest.mark.parametrize("camera", [api.FisheyeCamera(40), api.PerspectiveCamera(96, 64, 20.0)])
def test_a_render_with_clouds_reports_every_ray_once(atmosphere, camera):
    # The clouds' pass reports the rays it marches and those it interpolates (adaptive
    # refinement, on the perspective's 0.2 deg pixels): together every ray of the camera,
    # once, as the CLI's bar expects.
    done = []
    api.render(atmosphere, camera, 40.0, 135.0, 2.0, wavelengths_nm=WAVELENGTHS_NM,
               clouds=api.load_clouds("cumulus"), progress=done.append)
    assert sum(done) == int(camera.valid_mask().sum())
    if isinstance(camera, api.PerspectiveCamera):
        assert len(done) > 3  # the lattice, then each level: in steps, not at the end
