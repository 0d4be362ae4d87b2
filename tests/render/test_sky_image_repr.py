"""A SkyImage in a notebook: a one-line repr and the PNG that `save_image` writes."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

from skyscatter import api


def test_a_notebook_shows_the_saved_png(tmp_path):
    # Reference: the PNG `save_image` writes with its defaults, decoded by Pillow; the notebook's
    # PNG must be the same picture.
    image = api.render(api.load_atmosphere("earth"), api.FisheyeCamera(16), 40.0,
                       wavelengths_nm=(450.0, 550.0, 650.0), solver="single")
    path = tmp_path / "sky.png"
    api.save_image(image, path)
    shown = np.asarray(Image.open(io.BytesIO(image._repr_png_())))
    np.testing.assert_array_equal(shown, np.asarray(Image.open(path)))
    assert repr(image) == "SkyImage(16 x 16 pixels, 3 wavelengths 450-650 nm)"
