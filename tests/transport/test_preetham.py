"""Preetham's analytic sky (`transport/preetham.py`) against closed forms: the Perez function's
limits, the CIE colorimetry of its spectra, the daylight locus and its domain."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from transport_cases import EARTH_RADIUS_M, exponential_earth

from skyscatter.errors import InputError
from skyscatter.spectrum.colour import spectral_to_xyz
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.preetham import PEREZ_Y, PreethamSolver, perez, preetham_xyy

DEG = math.pi / 180.0
GROUND = np.array([0.0, 0.0, EARTH_RADIUS_M])


def ground_profile(wavelengths_nm):
    earth = exponential_earth()
    n = len(wavelengths_nm)
    return dataclasses.replace(
        earth, wavelengths_nm=np.asarray(wavelengths_nm, dtype=float),
        extinction_per_density=np.repeat(earth.extinction_per_density[:, :1], n, axis=1),
        scattering_per_density=np.repeat(earth.scattering_per_density[:, :1], n, axis=1),
        ground_albedo=np.full(n, 0.1), toa_irradiance=np.full(n, 1.8))


def test_perez_function_limits():
    # Perez et al. (1993): at the horizon the gradation term is 1 (B < 0); at the sun
    # (gamma = 0) the indicatrix is 1 + C + E; with A = C = E = 0 it is 1 everywhere.
    a, b, c, d, e = PEREZ_Y[:, 0] * 3.0 + PEREZ_Y[:, 1]
    assert perez(0.0, 1.0, (a, b, c, d, e)) == pytest.approx(1.0 + c * math.exp(d) +
                                                             e * math.cos(1.0) ** 2, rel=1e-14)
    assert perez(1.0, 0.0, (a, b, c, d, e)) == pytest.approx((1 + a * math.exp(b)) * (1 + c + e),
                                                             rel=1e-14)
    assert np.all(perez(np.linspace(0, 1, 5), 0.3, (0.0, -1.0, 0.0, -1.0, 0.0)) == 1.0)


@pytest.mark.parametrize(("turbidity", "sun_zenith_deg"), [(2.0, 20.0), (3.0, 50.0),
                                                           (6.0, 70.0)])
def test_spectra_have_the_models_luminance_and_chromaticity(turbidity, sun_zenith_deg):
    # The spectral radiance (CIE daylight basis scaled to Y) integrated with the CIE 1931
    # colour-matching functions (spectrum.colour) gives back the model's (x, y, Y): Y to
    # rounding (on this 5 nm grid the scaling's own integral), x and y within 3e-4 (the CIE
    # daylight basis reproduces a chromaticity only approximately: measured <= 1.3e-4).
    wavelengths = np.arange(360.0, 831.0, 5.0)
    solver = PreethamSolver(ground_profile(wavelengths), turbidity=turbidity)
    sun = local_frame_directions(sun_zenith_deg * DEG, 0.0)
    views = local_frame_directions(np.radians([0.0, 30.0, 60.0, 85.0]),
                                   np.radians([0.0, 90.0, 180.0, 30.0]))
    xyz = spectral_to_xyz(solver.sky_radiance(GROUND, views, sun), wavelengths)
    cos_view = views[:, 2]
    gamma = np.arccos(views @ sun)
    x, y, big_y = preetham_xyy(turbidity, cos_view, gamma, sun_zenith_deg * DEG)
    np.testing.assert_allclose(xyz[:, 1], big_y, rtol=1e-9)
    np.testing.assert_allclose(xyz[:, 0] / xyz.sum(axis=1), x, atol=3e-4)
    np.testing.assert_allclose(xyz[:, 1] / xyz.sum(axis=1), y, atol=3e-4)


def test_zenith_is_a_bluish_daylight_of_kilocandelas():
    # A clear sky's zenith (T = 2-4, sun 20-60 deg from the zenith) is bluer than D65
    # (x < 0.3127) and lies within 0.02 of the CIE daylight locus y = -3 x^2 + 2.87 x - 0.275
    # (CIE 015:2018 eq. 4.3; measured 0.0053 at most); its luminance is kilocandelas per square
    # metre (measured 3.5-19 kcd m^-2, the range of measured clear zeniths).
    for turbidity in (2.0, 3.0, 4.0):
        for sun_zenith_deg in (20.0, 40.0, 60.0):
            x, y, big_y = preetham_xyy(turbidity, 1.0, sun_zenith_deg * DEG,
                                       sun_zenith_deg * DEG)
            assert 0.2 < x < 0.3127
            assert abs(y - (-3.0 * x * x + 2.87 * x - 0.275)) < 0.02
            assert 1e3 < big_y < 3e4


def test_ground_views_are_dark_and_bad_turbidities_refused():
    solver = PreethamSolver(exponential_earth())
    sun = local_frame_directions(30.0 * DEG, 0.0)
    below = local_frame_directions(np.radians([91.0, 150.0]), np.zeros(2))
    assert np.all(solver.sky_radiance(GROUND, below, sun) == 0.0)
    for bad in (0.5, 25.0, True):
        with pytest.raises(InputError, match="turbidity = .* must lie in"):
            PreethamSolver(exponential_earth(), turbidity=bad)
