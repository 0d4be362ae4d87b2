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
