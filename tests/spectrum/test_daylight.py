"""CIE daylight spectra from a chromaticity (`spectrum.daylight`) against colour-science's own
D-series construction and the CIE's tabulated D65."""

from __future__ import annotations

import colour
import numpy as np
import pytest

from skyscatter.spectrum.daylight import daylight_spectrum

WAVELENGTHS_NM = np.arange(300.0, 831.0, 5.0)


@pytest.mark.parametrize("cct_k", [4000.0, 6504.0, 10000.0, 25000.0])
def test_daylight_spectra_match_colour_science(cct_k):
    # colour-science 0.4.7 `sd_CIE_illuminant_D_series` (the same CIE 015 equations, its own
    # code; it rounds M1 and M2 to 3 decimals as the standard's tables do, we do not): at the
    # 5 nm nodes within 0.1 of the 100-normalised spectrum (M rounding: < 0.5e-3 x |S1|, |S2|
    # <= 47). Chromaticities from colour-science's CIE daylight locus.
    xy = colour.temperature.CCT_to_xy_CIE_D(cct_k)
    expected = colour.sd_CIE_illuminant_D_series(xy)
    ours = daylight_spectrum(xy[0], xy[1], WAVELENGTHS_NM)
    np.testing.assert_allclose(ours, expected[WAVELENGTHS_NM], atol=0.1)


def test_d65_from_its_chromaticity_is_the_tabulated_d65():
    # CIE 015:2018 Table 5, D65 (colour-science's copy), from D65's (x, y) = (0.31272, 0.32903)
    # of the 2 deg observer: within 0.5 of the 100-normalised spectrum, measured 0.35 (the
    # table rounds M1, M2 to 3 decimals and S to 0.1; its chromaticity to 5 decimals). At the
    # 10 nm nodes, 300-780 nm: the 5 nm entries are linear between them (CIE 015:2018 §4.1).
    d65 = colour.SDS_ILLUMINANTS["D65"]
    nodes = np.arange(300.0, 781.0, 10.0)
    ours = daylight_spectrum(0.31272, 0.32903, nodes)
    np.testing.assert_allclose(ours, d65[nodes], atol=0.5)


def test_shapes_broadcast_with_wavelengths_last():
    x = np.array([[0.30, 0.31, 0.32]])
    assert daylight_spectrum(x, 0.33, [450.0, 550.0]).shape == (1, 3, 2)
    assert daylight_spectrum(0.31, 0.33, [450.0, 550.0, 900.0])[-1] == 0.0
