"""Grazing rays (lunar-eclipse light): the bending against astronomical refraction and a closed
form, and the transmittance against a direct integral of the extinction along the chord."""

import math

import numpy as np
import pytest

from skyscatter import api
from skyscatter.transport.limb import grazing_deflection_rad, grazing_transmittance


@pytest.fixture(scope="module")
def earth_solver():
    atmosphere = api.load_atmosphere("earth")
    return api.load_solver(atmosphere, [450.0, 550.0, 650.0],
                           options=api.solver_options(atmosphere, orders=1))


def test_grazing_bending_is_twice_the_horizontal_refraction(earth_solver):
    # A ray grazing the ground is bent by the refraction of its incoming and its outgoing half:
    # 2 x the astronomical refraction at the horizon, 34.5' at 1010 hPa and 10 C (Meeus,
    # Astronomical Algorithms, ch. 16), 33.8' at the US standard atmosphere's 15 C (refraction
    # scales with P/T). 5 % allows for the USSA temperature profile above the ground.
    deflection_arcmin = math.degrees(grazing_deflection_rad(earth_solver.profile, [0.0])[0]) * 60
    assert deflection_arcmin == pytest.approx(2.0 * 33.8, rel=0.05)


def test_grazing_bending_decays_with_the_stratospheric_scale_height(earth_solver):
    # Above the tropopause the USSA is isothermal at 216.65 K: scale height R T / (M g) =
    # 8.314 * 216.65 / (0.028964 * 9.77) = 6.37 km at 15 km, so the bending, proportional to
    # the density at the tangent point times sqrt(2 pi r / H), falls by exp(-5/6.37) per 5 km
    # (3 % for the change of g and the sqrt factor).
    bending = grazing_deflection_rad(earth_solver.profile, [12e3, 17e3])
    scale_height = 8.314462618 * 216.65 / (0.0289644 * 9.77)
    assert bending[1] / bending[0] == pytest.approx(math.exp(-5e3 / scale_height), rel=0.03)


def test_grazing_transmittance_matches_the_chord_integral(earth_solver):
    # exp(-integral of the extinction along the straight chord tangent at h), integrated here
    # with 20 000 points, against the table lookups (two halves). 1 % in transmittance at an
    # optical depth up to ~3: the table's own interpolation error near the horizon.
    profile = earth_solver.profile
    heights = np.array([5e3, 12e3, 20e3])
    radius, top = profile.bottom_radius_m, profile.top_radius_m
    got = grazing_transmittance(earth_solver, heights)
    for h, row in zip(heights, got, strict=True):
        half_chord = math.sqrt(top**2 - (radius + h) ** 2)
        x = np.linspace(-half_chord, half_chord, 20_001)
        altitude = np.hypot(radius + h, x) - radius
        optical_depth = np.trapezoid(profile.extinction_at(altitude), x, axis=0)
        np.testing.assert_allclose(row, np.exp(-optical_depth), rtol=0.01, atol=1e-6)
