"""The "optical-depth" validation case: vertical optical depths of the earth preset against
Bodhaine et al. 1999 and the ozone references, and the column integral against a closed form."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from skyscatter import api
from skyscatter.atmosphere.model import Constituent
from skyscatter.atmosphere.profiles import ExponentialProfile
from skyscatter.optics.absorption import AbsorberOptics
from skyscatter.optics.rayleigh import RayleighOptics, rayleigh_optical_depth_bodhaine1999
from skyscatter.spectrum.tabulated import SpectralParameter
from skyscatter.validate.optical_depth import (
    air_column_bodhaine1999,
    compare_optical_depths,
    run,
    vertical_optical_depth,
)
from skyscatter.validate.report import ValidationSettings

PERCENT = 1e-2


@pytest.fixture(scope="module")
def earth():
    return api.load_atmosphere("earth")


def test_run_writes_both_figures_and_passes_its_checks(tmp_path):
    result = run(ValidationSettings(output_dir=tmp_path, quick=True, log=lambda line: None))
    assert result.key == "optical-depth"
    assert [f.path for f in result.figures] == ["optical_depth_rayleigh.png",
                                                "optical_depth_ozone.png"]
    for figure in result.figures:
        assert (tmp_path / figure.path).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    failed = [(c.name, c.value, c.limit) for c in result.checks if not c.passed]
    assert result.checks and not failed, failed


def test_vertical_optical_depth_of_an_exponential_profile_is_the_closed_form(earth):
    # tau = sigma n0 int_0^top exp(-z/H) dz = sigma n0 H (1 - exp(-top/H)). The trapezoid rule on
    # the profile's 2001 levels (dz = 50 m) overestimates an exponential by dz^2 / (12 H^2) =
    # 3.3e-6 for H = 8 km; tolerance 1e-5.
    n0, scale_height, sigma = 2.5e25, 8000.0, 4.5e-31
    gas = Constituent("test", ExponentialProfile(scale_height, n0),
                      AbsorberOptics(SpectralParameter.constant(sigma)))
    atmosphere = dataclasses.replace(earth, constituents=(gas,))
    profile = atmosphere.optical_profile([450.0, 550.0], monochromatic=True)
    top = atmosphere.top_altitude_m
    expected = sigma * n0 * scale_height * (1.0 - np.exp(-top / scale_height))
    np.testing.assert_allclose(vertical_optical_depth(profile), [[expected, expected]], rtol=1e-5)


def test_ozone_optical_depth_at_600nm_matches_serdyuchenko_bins(earth):
    # 0.0405 for 300 DU (Serdyuchenko et al. 2014, 233 K, 10-nm bin of Bruneton's demo.cc). Ours is
    # another dataset (Malicet/Brion 295 K) at 600 nm itself: 0.0415. Tolerance 15 %: the spread
    # between ozone datasets (0.036 from SPECTRL2's coefficients, Bird & Riordan 1986).
    comparison = compare_optical_depths(earth, [600.0])
    assert comparison.ozone_column_du == pytest.approx(300.0, rel=1e-9)
    assert comparison.ozone[0] == pytest.approx(0.0405, rel=15 * PERCENT)


def test_bodhaine_column_with_our_cross_section_reproduces_eq30():
    # Bodhaine 1999's column (1013.25 hPa, 45 deg, g at the mass-weighted altitude z_c) x our
    # cross-section (same refractivity and King factor) against his fit eq. 30. Measured gap:
    # at most 0.01 % at 360-830 nm. Tolerance 0.05 %: the fit's rounding; g at the site instead
    # of z_c (colour-science's choice) would miss by 0.18 %.
    wl = np.arange(360.0, 831.0, 10.0)
    tau = RayleighOptics().scattering_per_density(wl) * air_column_bodhaine1999()
    np.testing.assert_allclose(tau, rayleigh_optical_depth_bodhaine1999(wl),
                               rtol=0.05 * PERCENT)
