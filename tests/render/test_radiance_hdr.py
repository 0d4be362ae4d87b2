"""Radiance .hdr files decoded by a reader written here from the format's description (Ward,
"Real pixels", Graphics Gems II; Radiance File Formats), against the EXR of the same image."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter import api
from skyscatter.errors import InputError
from skyscatter.render.image_io import read_exr


def _read_hdr(path) -> tuple[dict[str, str], np.ndarray]:
    """(header variables, linear RGB (h, w, 3)) of a flat (not run-length encoded) RGBE file:
    v = (m + 0.5) / 256 * 2^(e - 128), 0 where e = 0."""
    data = path.read_bytes()
    assert data.startswith(b"#?RADIANCE\n")
    head, _, rest = data.partition(b"\n\n")
    variables = dict(line.split("=", 1) for line in head.decode().splitlines()[1:]
                     if "=" in line)
    size, _, pixels = rest.partition(b"\n")
    _, height, _, width = size.decode().split()
    rgbe = np.frombuffer(pixels, dtype=np.uint8).reshape(int(height), int(width), 4)
    exponent = rgbe[..., 3:].astype(np.float64)
    value = (rgbe[..., :3] + 0.5) / 256.0 * np.exp2(exponent - 128.0)
    return variables, np.where(exponent > 0, value, 0.0)


@pytest.fixture(scope="module")
def image():
    return api.render(api.load_atmosphere("earth"), api.EquirectangularCamera(64, 32), 60.0,
                      wavelengths_nm=(450.0, 550.0, 650.0), solver="single")


@pytest.mark.parametrize("space", ["srgb", "rec2020"])
def test_the_hdr_holds_the_exrs_pixels(image, tmp_path, space):
    # RGBE keeps each pixel's largest channel to 1/256 (relative, half a step on average) and
    # the others to 1/256 of that largest one: the tolerance.
    hdr, exr = tmp_path / "sky.hdr", tmp_path / "sky.exr"
    api.save_image(image, exr_path=hdr, colour_space=space)
    api.save_image(image, exr_path=exr, colour_space=space)
    variables, rgb = _read_hdr(hdr)
    expected = read_exr(exr)[0].astype(np.float64)
    largest = expected.max(axis=-1, keepdims=True)
    assert np.all(np.abs(rgb - expected) <= largest / 256.0)
    assert variables["FORMAT"] == "32-bit_rle_rgbe" and variables["EXPOSURE"] == "179"
    primaries = [float(v) for v in variables["PRIMARIES"].split()]
    published = {"srgb": (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),
                 "rec2020": (0.708, 0.292, 0.170, 0.797, 0.131, 0.046, 0.3127, 0.3290)}
    np.testing.assert_allclose(primaries, published[space], atol=1e-4)


def test_an_hdr_of_spectra_is_refused_before_writing(image, tmp_path):
    with pytest.raises(InputError, match="holds RGB"):
        api.save_image(image, exr_path=tmp_path / "sky.hdr", exr_content="spectral")
    assert not (tmp_path / "sky.hdr").exists()
