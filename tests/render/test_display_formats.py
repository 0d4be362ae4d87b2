"""Display images as TIFF (-o x.tif), read back with tifffile: the PNG's codes, its metadata and
the ICC profile of a wide gamut. (WebP and JPEG are decoded by Chromium in
tests/viewer/test_display_formats_in_chromium.py.)"""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from skyscatter import api
from skyscatter.errors import InputError

tifffile = pytest.importorskip("tifffile")


@pytest.fixture(scope="module")
def sky():
    return api.render(api.load_atmosphere("earth"), api.FisheyeCamera(24), 60.0,
                      wavelengths_nm=(450.0, 550.0, 650.0), solver="single")


@pytest.mark.parametrize("suffix", [".tif", ".tiff"])
def test_a_tiff_holds_the_pngs_codes_and_its_metadata(tmp_path, sky, suffix):
    api.save_image(sky, tmp_path / "sky.png", ev100=12.0)
    api.save_image(sky, tmp_path / f"sky{suffix}", ev100=12.0)
    with tifffile.TiffFile(tmp_path / f"sky{suffix}") as tiff:
        page = tiff.pages[0]
        codes = page.asarray()
        assert page.compression == tifffile.COMPRESSION.ADOBE_DEFLATE
        assert "EV100: 12.000" in page.description
        assert page.tags["Software"].value == "skyscatter"
        assert "InterColorProfile" not in page.tags  # sRGB: untagged, read as sRGB
    np.testing.assert_array_equal(codes, np.asarray(Image.open(tmp_path / "sky.png")))


def test_a_wide_gamut_tiff_carries_its_icc_profile(tmp_path, sky):
    # The profile's bytes are those `render.icc_profile` makes (read back with littleCMS in
    # test_icc_profile.py); here only that the TIFF carries them: tag 34675.
    from skyscatter.render.icc_profile import icc_profile

    api.save_image(sky, tmp_path / "p3.tif", ev100=12.0, colour_space="display-p3")
    with tifffile.TiffFile(tmp_path / "p3.tif") as tiff:
        assert bytes(tiff.pages[0].tags["InterColorProfile"].value) == icc_profile("display-p3")


def test_other_suffixes_are_refused_with_the_list(tmp_path, sky):
    with pytest.raises(InputError, match=r"name it \.png, \.jpg, \.jpeg, \.tif, \.tiff, "
                                             r"\.webp"):
        api.save_image(sky, tmp_path / "sky.bmp")
    assert not (tmp_path / "sky.bmp").exists()
