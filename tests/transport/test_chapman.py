"""Schüler's Chapman approximation and the closed-form columns (`transport/chapman.py`) against
the Chapman function integrated numerically, and the constituent fit against profiles of known
form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from transport_cases import EARTH_RADIUS_M, exponential_earth

from skyscatter.transport.chapman import (
    EXPONENTIAL,
    LAYER,
    chapman_horizontal,
    chapman_schuler_2012,
    exponential_column,
    fit_constituents,
    layer_column,
)


def chapman_numerical(x: float, chi_deg: float) -> float:
    """Ch(x, chi) by its definition (Chapman 1931): the column of exp(-(r' - r)) along the ray
    from the normalised radius x at zenith angle chi to infinity, over the vertical column (1),
    integrated with scipy's adaptive quadrature along the ray (distance s in scale heights)."""
    mu = math.cos(math.radians(chi_deg))

    def density(s: float) -> float:
        return math.exp(x - math.sqrt(x * x + s * s + 2.0 * x * s * mu))

    perigee = max(-x * mu, 0.0)  # the density peaks there: integrate up to it, then beyond
    before, _ = quad(density, 0.0, perigee, limit=500, epsabs=0.0, epsrel=1e-10)
    after, _ = quad(density, perigee, np.inf, limit=500, epsabs=0.0, epsrel=1e-10)
    return before + after


# Ch(795, chi), the approximation's error against the integral: the test's reference values
# come from the integral; the expected relative errors are the approximation's own, measured
# (a rational function of cos chi through the exact values at 0 and 90 deg undershoots the
# exponential growth in between), each with 0.2 % of room.
@pytest.mark.parametrize(("chi_deg", "error"), [(0.0, 0.0), (30.0, -0.004), (60.0, -0.024),
                                                 (80.0, -0.086), (88.0, -0.138),
                                                 (90.0, 0.0)])
def test_schuler_approximation_against_the_numerical_chapman_function(chi_deg, error):
    x = EARTH_RADIUS_M / 8000.0  # 795: Earth's air
    exact = chapman_numerical(x, chi_deg)
    approx = chapman_schuler_2012(x, math.cos(math.radians(chi_deg)))
    assert approx / exact - 1.0 == pytest.approx(error, abs=2e-3)


def test_the_horizontal_value_is_the_integral_to_order_one_over_x():
    # Ch(x, 90 deg) ~ (1 / (2x) + 1) sqrt(pi x / 2) (Schüler 2012, eq. 11), an expansion in
    # 1 / x: measured 1.6e-4 high at x = 795 (Earth's air) and 2.4e-5 at 5300 (aerosol,
    # H = 1.2 km), about 1 / (8 x); tolerance 0.15 / x.
    for x in (795.0, 5300.0):
        assert chapman_horizontal(x) == pytest.approx(chapman_numerical(x, 90.0),
                                                      rel=0.15 / x)


@pytest.mark.parametrize("chi_deg", [92.0, 95.0, 120.0])
def test_below_the_horizon_the_error_is_that_of_the_part_behind_the_observer(chi_deg):
    # Ch(x, chi) = 2 exp(x - x0) Ch(x0, 90 deg) - Ch(x, 180 deg - chi) (Schüler 2012, the
    # column of the whole line less the part behind): the whole line is nearly exact, so the
    # error is minus the approximation's error at 180 deg - chi (2.7 % at 92 deg, where the
    # part behind is a fifth of the whole). Tolerance 0.05 % of Ch for the whole line's own
    # error (eq. 11's, 1.6e-4 at x = 795) and the quadrature.
    x = 795.0
    mu = math.cos(math.radians(chi_deg))
    exact = chapman_numerical(x, chi_deg)
    behind_error = chapman_schuler_2012(x, -mu) - chapman_numerical(x, 180.0 - chi_deg)
    error = chapman_schuler_2012(x, mu) - exact
    assert error == pytest.approx(-behind_error, abs=5e-4 * exact)


def test_the_scaled_column_is_the_chapman_function_times_the_density_and_height():
    # exponential_column = H exp(-(r - R) / H) Ch(r / H, chi) (Schüler's first modification,
    # which only avoids overflow): equal to rounding where the unscaled form is finite.
    height, altitude = 8000.0, 3000.0
    r = EARTH_RADIUS_M + altitude
    for mu in (1.0, 0.3, 0.0, -0.05):
        expected = (height * math.exp(-altitude / height)
                    * chapman_schuler_2012(r / height, mu))
        assert exponential_column(r, mu, EARTH_RADIUS_M, height) == pytest.approx(expected,
                                                                                  rel=1e-9)


def test_a_layer_is_crossed_once_from_below_twice_or_never_from_above_and_smoothly():
    # A layer at 25 km, 5 km wide. Far from it (5 widths) its Gaussian share is whole or
    # nothing (to 3e-7): from the ground straight up the column is 1 / sqrt(1 + w / R_c) (the
    # width's term), from 25 km above looking down twice that, looking up from there or along
    # a line passing 25 km above it 0. Across the layer's centre and across grazing the column
    # changes by less than 3e-4 of itself per metre (at the centre the Gaussian's 1 /
    # (sqrt(2 pi) w) = 8e-5 of the column per metre, 1.6e-4 of the half above; 6e-5 at
    # grazing; a hard shell would jump by its whole column).
    shell, width = EARTH_RADIUS_M + 25e3, 5e3
    slant = 1.0 / math.sqrt(1.0 + width / shell)
    assert layer_column(EARTH_RADIUS_M, 1.0, shell, width) == pytest.approx(slant, rel=1e-6)
    assert layer_column(shell + 25e3, -1.0, shell, width) == pytest.approx(2.0 * slant,
                                                                           rel=1e-6)
    assert layer_column(shell + 25e3, 1.0, shell, width) < 1e-6
    # perigee 25 km above: twice the share 2.9e-7 times the grazing slant sqrt(R_c / w) = 36
    r = shell + 30e3
    assert layer_column(r, -math.sqrt(1.0 - ((shell + 25e3) / r) ** 2), shell, width) < 3e-5
    for mu in (1.0, 0.2, -0.2):
        upper = layer_column(shell + 0.5, mu, shell, width)
        assert abs(upper - layer_column(shell - 0.5, mu, shell, width)) < 3e-4 * upper
    # perigee 0.5 m below and above the layer's centre radius, seen from 40 km above it
    r = shell + 40e3
    mu_low = -math.sqrt(1.0 - ((shell - 0.5) / r) ** 2)
    mu_high = -math.sqrt(1.0 - ((shell + 0.5) / r) ** 2)
    low = layer_column(r, mu_low, shell, width)
    assert abs(low - layer_column(r, mu_high, shell, width)) < 3e-4 * low


def test_the_fit_recovers_exponential_scale_heights_and_a_layers_centroid():
    # exponential_earth's 8 km and 1.2 km (its densities are linear between 30 m levels: the
    # trapezoid column is high by (30 m)^2 / (12 H^2) <= 5.2e-5, so is H); a Gaussian layer at
    # 25 km, sigma 5 km: centroid and width to 0.1 % (the grid's rounding).
    profile = exponential_earth()
    model = fit_constituents(profile)
    assert list(model.kind) == [EXPONENTIAL, EXPONENTIAL]
    np.testing.assert_allclose(model.scale_height, [8000.0, 1200.0], rtol=6e-5)
    z = profile.altitudes_m
    layered = np.stack([profile.density[0], np.exp(-0.5 * ((z - 25e3) / 5e3) ** 2)])
    from dataclasses import replace
    model = fit_constituents(replace(profile, density=layered))
    assert model.kind[1] == LAYER
    assert model.layer_radius[1] - EARTH_RADIUS_M == pytest.approx(25e3, rel=1e-3)
    assert model.layer_width[1] == pytest.approx(5e3, rel=1e-3)
    assert model.layer_column[1] == pytest.approx(5e3 * math.sqrt(2.0 * math.pi), rel=1e-3)

