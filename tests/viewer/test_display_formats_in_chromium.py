"""Display images as WebP and JPEG, decoded by Chromium (its own libwebp and libjpeg-turbo, not
the Pillow that wrote them): a lossless WebP holds the PNG's codes exactly, a JPEG nearly."""

from __future__ import annotations

import base64

import numpy as np
import pytest
from PIL import Image

from skyscatter import api

DECODE = """async (url) => {
  const image = new Image();
  image.src = url;
  await image.decode();
  const canvas = document.createElement("canvas");
  canvas.width = image.width;
  canvas.height = image.height;
  const context = canvas.getContext("2d");
  context.drawImage(image, 0, 0);
  return Array.from(context.getImageData(0, 0, image.width, image.height).data);
}"""


@pytest.fixture(scope="module")
def sky():
    return api.render(api.load_atmosphere("earth"), api.FisheyeCamera(24), 60.0,
                      wavelengths_nm=(450.0, 550.0, 650.0), solver="single")


def _decoded(page, path, mime: str) -> np.ndarray:
    url = f"data:{mime};base64,{base64.b64encode(path.read_bytes()).decode()}"
    page.set_content("<html><body></body></html>")
    data = np.array(page.evaluate(DECODE, url), dtype=np.uint8)
    return data.reshape(24, 24, 4)[..., :3]


def test_a_webp_is_the_pngs_codes_exactly_and_a_jpeg_nearly(page, tmp_path, sky):
    # sRGB images (untagged, --force-color-profile=srgb: no colour conversion in the canvas).
    # JPEG at quality 95 without chroma subsampling: measured at most 5 codes apart on this
    # sky's gradients and its black corners; tolerance 8.
    api.save_image(sky, tmp_path / "sky.png", ev100=12.0)
    api.save_image(sky, tmp_path / "sky.webp", ev100=12.0)
    api.save_image(sky, tmp_path / "sky.jpg", ev100=12.0)
    png = np.asarray(Image.open(tmp_path / "sky.png").convert("RGB"))
    np.testing.assert_array_equal(_decoded(page, tmp_path / "sky.webp", "image/webp"), png)
    jpeg = _decoded(page, tmp_path / "sky.jpg", "image/jpeg").astype(int)
    assert np.abs(jpeg - png).max() <= 8
    assert page.errors == []
