"""--exr-content spectral-fichet2021: the spectral EXR layout of Fichet, Pacanowski & Wilkie
(2021, JCGT 10(3)), read back with OpenEXR; the channel names parsed with the layout's regular
expression written out here (the authors' reference implementation's) and with
colour-science's reader of the layout (colour.io.fichet2021)."""

from __future__ import annotations

import re

import numpy as np
import OpenEXR
import pytest

from skyscatter import api
from skyscatter.cli import main

WAVELENGTHS_NM = (440.0, 550.0, 612.5)
# Fichet et al. (2021), the emissive channel: Stokes component, value with a decimal comma and
# an optional exponent, SI prefix, unit (m or Hz)
CHANNEL = re.compile(r"^(S[0-3])\.(\d*,?\d*([Ee][+-]?\d+)?)"
                     r"(Y|Z|E|P|T|G|M|k|h|da|d|c|m|u|n|p)?(m|Hz)$")
PREFIX = {"n": 1.0, "u": 1e3, "m": 1e6, "": 1e9, "p": 1e-3}  # -> nm, for the unit m


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("spectral")
    image = api.render(api.load_atmosphere("earth"), api.FisheyeCamera(12), 50.0,
                       wavelengths_nm=WAVELENGTHS_NM, solver="single")
    api.save_image(image, exr_path=folder / "fichet.exr", exr_content="spectral-fichet2021")
    api.save_image(image, exr_path=folder / "rgb.exr")
    return image, folder


def test_the_channels_are_named_and_tagged_as_the_layout_says(files):
    image, folder = files
    exr = OpenEXR.File(str(folder / "fichet.exr"), separate_channels=True)
    channels = exr.channels()
    header = exr.header()
    assert header["spectralLayoutVersion"] == "1.0"
    assert header["emissiveUnits"] == "W.m^-2.sr^-1"
    assert header["chromaticities"] is not None
    spectral = {}
    for name in channels:
        match = CHANNEL.match(name)
        if match is None:
            continue
        assert match.group(1) == "S0" and match.group(5) == "m"
        wavelength = float(match.group(2).replace(",", ".")) * PREFIX[match.group(4) or ""]
        spectral[wavelength] = channels[name].pixels
    assert sorted(spectral) == list(WAVELENGTHS_NM)
    assert "S0.612,500000nm" in channels
    for k, wavelength in enumerate(WAVELENGTHS_NM):
        np.testing.assert_array_equal(spectral[wavelength],
                                      image.spectral[..., k].astype(np.float32))
    rgb = OpenEXR.File(str(folder / "rgb.exr"), separate_channels=True).channels()
    for c in "RGB":
        np.testing.assert_array_equal(channels[c].pixels, rgb[c].pixels)


def test_colour_science_reads_the_wavelengths_of_the_names(files):
    fichet2021 = pytest.importorskip("colour.io.fichet2021")
    _, folder = files
    names = OpenEXR.File(str(folder / "fichet.exr"), separate_channels=True).channels()
    pattern = re.compile(rf"^(S[0-3])\.*{fichet2021.PATTERN_FICHET2021}$")
    found = []
    for name in names:
        match = pattern.match(name)
        if match is not None:
            multiplier, units = match.group(4, 5)
            found.append(fichet2021.match_groups_to_nm(match.group(2), multiplier, units))
    assert sorted(found) == pytest.approx(WAVELENGTHS_NM, abs=1e-9)


def test_the_command_line_writes_the_layout(tmp_path):
    assert main(["render", "earth", "--size", "8", "--solver", "single", "--wavelengths",
                 "450,550", "-o", str(tmp_path / "s.png"), "--exr", str(tmp_path / "s.exr"),
                 "--exr-content", "spectral-fichet2021"]) == 0
    names = set(OpenEXR.File(str(tmp_path / "s.exr"), separate_channels=True).channels())
    assert names == {"R", "G", "B", "S0.450,000000nm", "S0.550,000000nm"}
