"""Display images name their colour space: an sRGB chunk, or an ICC profile of the wide gamut
read back by Pillow's littleCMS (not by the code that wrote it)."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image, ImageCms

from skyscatter import api
from skyscatter.render.icc_profile import icc_profile

# Reference: the published primaries (CIE xy) as in test_exr_colour_tags.py: SMPTE EG 432-1
# (Display P3), ITU-R BT.2020-2, Academy S-2014-004 (ACEScg, AP1, ACES white).
PUBLISHED = {
    "display-p3": ((0.680, 0.320), (0.265, 0.690), (0.150, 0.060)),
    "rec2020": ((0.708, 0.292), (0.170, 0.797), (0.131, 0.046)),
    "acescg": ((0.713, 0.293), (0.165, 0.830), (0.128, 0.044)),
}


@pytest.mark.parametrize("space", list(PUBLISHED))
def test_the_profile_holds_the_spaces_primaries(space):
    # The colorants littleCMS reads (adapted to D50) taken back through the inverse of the
    # chromatic adaptation it reads (chad) give the primaries' own chromaticities; they equal
    # the published ones to the s15Fixed16 encoding (~1e-4).
    profile = ImageCms.ImageCmsProfile(io.BytesIO(icc_profile(space))).profile
    undo = np.linalg.inv(np.array(profile.chromatic_adaptation[0]))
    for colorant, expected in zip((profile.red_colorant, profile.green_colorant,
                                   profile.blue_colorant), PUBLISHED[space], strict=True):
        xyz = undo @ np.array(colorant[0])
        np.testing.assert_allclose(xyz[:2] / xyz.sum(), expected, atol=5e-4)
    np.testing.assert_allclose(profile.media_white_point[0], (0.9642, 1.0, 0.8249), atol=1e-4)
    assert profile.version == pytest.approx(4.4)


def test_a_p3_pixel_converts_to_srgb_as_the_matrices_say():
    # littleCMS's transform from the profile to its own sRGB: P3's pure green, linear
    # (0, 1, 0) -> XYZ by P3's primaries -> linear sRGB (-0.225, 1.042, -0.079), clipped by
    # the 8-bit transform to (0, 255, 0) in the red and blue; a mid grey stays grey.
    p3 = ImageCms.ImageCmsProfile(io.BytesIO(icc_profile("display-p3")))
    srgb = ImageCms.createProfile("sRGB")
    transform = ImageCms.buildTransform(p3, srgb, "RGB", "RGB")
    pixels = Image.fromarray(np.array([[[0, 255, 0], [128, 128, 128]]], dtype=np.uint8))
    out = np.asarray(ImageCms.applyTransform(pixels, transform))
    np.testing.assert_array_equal(out[0, 0, [0, 2]], 0)
    assert out[0, 0, 1] == 255
    assert np.all(np.abs(out[0, 1].astype(int) - 128) <= 1)


@pytest.mark.parametrize("space", ["srgb", "display-p3"])
def test_a_rendered_png_is_tagged(space, tmp_path):
    image = api.render(api.load_atmosphere("earth"), api.FisheyeCamera(8), 40.0,
                       wavelengths_nm=(450.0, 550.0, 650.0), solver="single")
    path = tmp_path / f"{space}.png"
    api.save_image(image, path, colour_space=space)
    with Image.open(path) as png:
        if space == "srgb":
            assert png.info.get("srgb") == 0 and "icc_profile" not in png.info
        else:
            assert png.info["icc_profile"] == icc_profile("display-p3")
