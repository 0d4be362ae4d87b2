"""An RGB EXR names its colour space the way compositors and engines read it: the standard
`chromaticities` and `whiteLuminance` attributes, read back by a parser of the OpenEXR file
layout written here (not the library that wrote them)."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from exr_header import exr_header
from skyscatter import api

# Reference: the primaries and whites as their standards publish them (CIE xy): IEC 61966-2-1
# (sRGB) and ITU-R BT.709-6; SMPTE EG 432-1 (Display P3: DCI-P3 primaries, D65); ITU-R
# BT.2020-2; Academy S-2014-004 (ACEScg, AP1) and SMPTE ST 2065-1 (AP0), ACES white.
PUBLISHED = {
    "srgb": (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),
    "rec709": (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290),
    "display-p3": (0.680, 0.320, 0.265, 0.690, 0.150, 0.060, 0.3127, 0.3290),
    "rec2020": (0.708, 0.292, 0.170, 0.797, 0.131, 0.046, 0.3127, 0.3290),
    "acescg": (0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767),
    "aces2065-1": (0.7347, 0.2653, 0.0, 1.0, 0.0001, -0.0770, 0.32168, 0.33767),
}


@pytest.fixture(scope="module")
def image():
    return api.render(api.load_atmosphere("earth"), api.FisheyeCamera(8), 40.0,
                      wavelengths_nm=(450.0, 550.0, 650.0), solver="single")


@pytest.mark.parametrize("space", list(PUBLISHED))
def test_an_rgb_exr_names_its_primaries_and_white(image, tmp_path, space):
    path = tmp_path / f"{space}.exr"
    api.save_image(image, exr_path=path, colour_space=space)
    attributes, _ = exr_header(path.read_bytes())
    kind, value = attributes["chromaticities"]
    assert kind == "chromaticities"
    np.testing.assert_allclose(struct.unpack("<8f", value), PUBLISHED[space], atol=1e-4)
    kind, value = attributes["whiteLuminance"]
    assert kind == "float" and struct.unpack("<f", value)[0] == 1.0


def test_a_spectral_exr_claims_no_primaries(image, tmp_path):
    path = tmp_path / "spectral.exr"
    api.save_image(image, exr_path=path, exr_content="spectral")
    attributes, _ = exr_header(path.read_bytes())
    assert "chromaticities" not in attributes and "whiteLuminance" not in attributes
