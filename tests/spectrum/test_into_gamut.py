"""Colours outside an RGB space's gamut brought inside at constant luminance
(`spectrum.colour.into_gamut`), judged by colour-science's own RGB -> XYZ."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter import api
from skyscatter.render.image_io import read_exr
from skyscatter.spectrum.colour import into_gamut, luminance, xyz_to_rgb

colour = pytest.importorskip("colour")
NAMES = {"srgb": "sRGB", "rec2020": "ITU-R BT.2020", "display-p3": "Display P3"}


def _y(rgb: np.ndarray, space: str) -> np.ndarray:
    """Luminance of linear RGB by colour-science's normalised primary matrix of the space's
    primaries and white (SMPTE RP 177; not its sRGB matrix, which is the standard's rounded
    one, 1e-4 off)."""
    space = colour.RGB_COLOURSPACES[NAMES[space]]
    matrix = colour.models.normalised_primary_matrix(space.primaries, space.whitepoint)
    return rgb @ matrix[1]


@pytest.mark.parametrize("space", list(NAMES))
def test_out_of_gamut_colours_keep_their_luminance_and_hue(space):
    rng = np.random.default_rng(11)
    rgb = rng.normal(1.0, 1.5, size=(2000, 3))
    mapped = into_gamut(rgb, space)
    y = _y(rgb, space)
    outside = rgb.min(axis=1) < 0.0
    np.testing.assert_array_equal(mapped[~outside], rgb[~outside])  # inside: untouched
    assert mapped.min() >= -1e-12
    lit = outside & (y > 0.0)
    np.testing.assert_allclose(_y(mapped[lit], space), y[lit], rtol=1e-9)
    # on the segment from the colour to the white of its luminance (the same hue)
    towards = mapped[lit] - y[lit, None]
    away = rgb[lit] - y[lit, None]
    cross = np.cross(towards, away)
    np.testing.assert_allclose(cross, 0.0, atol=1e-9 * np.abs(away).max())
    np.testing.assert_array_equal(mapped[outside & (y <= 0.0)], 0.0)


def test_a_setting_suns_exr_has_no_negative_pixel(tmp_path):
    # The sun 2 deg high seen in a panorama: its reddened light lies outside sRGB (blue
    # -8e4 before); every pixel's luminance stays the spectral image's (float32 rounding).
    image = api.render(api.load_atmosphere("earth"), api.EquirectangularCamera(128, 64, 270.0),
                       88.0, 270.0, wavelengths_nm=tuple(np.linspace(380.0, 780.0, 16)))
    path = tmp_path / "sunset.exr"
    api.save_image(image, exr_path=path)
    rgb, _ = read_exr(path)
    assert np.isfinite(rgb).all() and rgb.min() >= 0.0
    raw = xyz_to_rgb(image.xyz(), "srgb")
    assert raw.min() < 0.0  # the sun's pixel is out of gamut
    np.testing.assert_allclose(_y(rgb.astype(np.float64), "srgb"),
                               luminance(image.spectral, image.wavelengths_nm), rtol=1e-5,
                               atol=1e-6)
