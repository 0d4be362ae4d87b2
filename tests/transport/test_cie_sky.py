"""The CIE standard general sky (`transport/cie_sky.py`): its table of the 15 types against the
standard's groups transcribed from Darula & Kittler (2002), and its distribution against closed
forms (the overcast sky of Moon & Spencer, the uniform sky, the zenith)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from transport_cases import exponential_earth

from skyscatter.errors import InputError
from skyscatter.transport.cie_sky import SKY_TYPES, CieSkySolver, cie_relative_luminance

# Darula & Kittler (2002), "CIE general sky standard defining luminance distributions", Proc.
# eSim 2002, Table 1 (= CIE S 011/E:2003 Table 1), typed by group: gradation groups I-VI (a, b),
# indicatrix groups 1-6 (c, d, e), and the group pair of each type
GRADATION = {"I": (4.0, -0.70), "II": (1.1, -0.80), "III": (0.0, -1.00), "IV": (-1.0, -0.55),
             "V": (-1.0, -0.32), "VI": (-1.0, -0.15)}
INDICATRIX = {1: (0.0, -1.0, 0.00), 2: (2.0, -1.5, 0.15), 3: (5.0, -2.5, 0.30),
              4: (10.0, -3.0, 0.45), 5: (16.0, -3.0, 0.30), 6: (24.0, -2.8, 0.15)}
TYPE_GROUPS = {1: ("I", 1), 2: ("I", 2), 3: ("II", 1), 4: ("II", 2), 5: ("III", 1),
               6: ("III", 2), 7: ("III", 3), 8: ("III", 4), 9: ("IV", 2), 10: ("IV", 3),
               11: ("IV", 4), 12: ("V", 4), 13: ("V", 5), 14: ("VI", 5), 15: ("VI", 6)}
DEG = math.pi / 180.0


def test_the_fifteen_types_are_the_standards_groups():
    assert sorted(SKY_TYPES) == list(range(1, 16))
    for sky_type, (gradation, indicatrix) in TYPE_GROUPS.items():
        assert SKY_TYPES[sky_type] == GRADATION[gradation] + INDICATRIX[indicatrix], sky_type


@pytest.mark.parametrize("sky_type", range(1, 16))
def test_the_zenith_is_one_and_the_luminance_positive_over_the_dome(sky_type):
    # L / L_z = 1 at the zenith for any sun (the normalisation), and > 0 over the dome.
    sun_zenith = np.radians([0.0, 30.0, 60.0, 89.0])
    assert np.allclose(cie_relative_luminance(sky_type, 1.0, sun_zenith, sun_zenith), 1.0,
                       rtol=1e-14)
    zenith, sun_angle = np.meshgrid(np.radians(np.linspace(0, 90, 19)),
                                    np.radians(np.linspace(0, 180, 37)))
    assert np.all(cie_relative_luminance(sky_type, np.cos(zenith), sun_angle, 0.5) > 0.0)


def test_type_1_has_the_moon_spencer_overcast_skys_horizon_ratio():
    # The CIE standard overcast sky (type 1) replaces Moon & Spencer (1942), L(Z) / L_z =
    # (1 + 2 cos Z) / 3, independent of the sun, with the gradation 1 + 4 exp(-0.7 / cos Z):
    # the same horizon (1/3; measured 0.3349) and 60 deg (2/3; measured 0.6652) values within
    # 1 %, darker towards the horizon in between (measured -20 % at 80 deg).
    zenith = np.radians([0.0, 60.0, 90.0])
    for sun_zenith_deg, sun_angle_deg in ((20.0, 50.0), (70.0, 150.0)):
        ours = cie_relative_luminance(1, np.cos(zenith), sun_angle_deg * DEG,
                                      sun_zenith_deg * DEG)
        np.testing.assert_allclose(ours, (1.0 + 2.0 * np.cos(zenith)) / 3.0, rtol=1e-2)


def test_type_5_is_uniform():
    # a = 0 (no gradation), c = e = 0 (no indicatrix): L = L_z everywhere, exactly.
    rng = np.random.default_rng(2)
    values = cie_relative_luminance(5, rng.uniform(0, 1, 50), rng.uniform(0, math.pi, 50),
                                    rng.uniform(0, math.pi / 2, 50))
    np.testing.assert_array_equal(values, 1.0)


def test_clear_skies_are_brightest_next_to_the_sun_and_darkest_opposite_it():
    # Types 11-15 (clear and turbid skies): the indicatrix peaks at the sun and falls to its
    # minimum near 90 deg from it, the clear sky's dark band (Kittler et al. 1998).
    for sky_type in (11, 12, 13, 14, 15):
        sun_zenith = 45.0 * DEG
        # along the sun's vertical, view zenith from -90 (opposite) to 90 deg (sun side)
        view = np.radians(np.linspace(-89.0, 89.0, 179))
        values = cie_relative_luminance(sky_type, np.cos(view), np.abs(view - sun_zenith),
                                        sun_zenith)
        assert np.argmax(values) == np.argmin(np.abs(view - sun_zenith))
        assert values[np.argmin(np.abs(view + sun_zenith))] < 1.0  # anti-solar side darker


def test_bad_sky_types_and_other_planets_are_refused():
    earth = exponential_earth()
    for bad in (0, 16, 12.5, True):
        with pytest.raises(InputError, match="CIE sky type .* must be an integer from 1 to 15"):
            CieSkySolver(earth, lambda: None, sky_type=bad)
    mars = dataclasses.replace(earth, bottom_radius_m=3_389_500.0,
                               top_radius_m=3_389_500.0 + 60e3)
    with pytest.raises(InputError, match="solver 'cie' describes Earth's sky only"):
        CieSkySolver(mars, lambda: None)
