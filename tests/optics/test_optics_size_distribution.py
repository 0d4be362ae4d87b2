"""Size-distribution quadratures against closed-form moments and scipy.stats."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from skyscatter.errors import InputError
from skyscatter.optics.size_distribution import (
    Gamma,
    JungePowerLaw,
    LogNormal,
    ModifiedGamma,
    Monodisperse,
    effective_radius,
    effective_variance,
)

UM = 1.0e-6
# The trapezoid rule in ln r converges exponentially for the gamma and log-normal densities,
# so the quadrature error is the tail cut: at most 1e-6 of each moment at each end
# (TAIL_FRACTION), hence <= 4e-6 for a ratio of two moments; 1e-5 leaves room for rounding.
TAIL_TOLERANCE = 1.0e-5
# v_eff = <r^4><r^2>/<r^3>^2 - 1: the ratio carries that relative error, the difference keeps it
# as an absolute one (relative to a small v_eff it grows as 1/v_eff).
VEFF_TOLERANCE = dict(abs=1.0e-5)


def moment(radii, weights, n):
    return float(np.sum(weights * radii**n))


@pytest.mark.parametrize("distribution", [
    LogNormal(0.5 * UM, 1.8), Gamma(3.0, 0.32 * UM), ModifiedGamma(1.6 * UM, 0.2),
    JungePowerLaw(3.0, 0.01 * UM, 10.0 * UM)])
def test_quadrature_is_increasing_radii_with_number_fractions_summing_to_one(distribution):
    radii, weights = distribution.quadrature(300)
    assert radii.shape == weights.shape == (300,)
    assert np.all(np.diff(radii) > 0.0) and np.all(weights >= 0.0)
    assert weights.sum() == pytest.approx(1.0, rel=1e-14)


@pytest.mark.parametrize("shape", [0.5, 3.0, 20.0])
def test_gamma_moments_match_closed_form(shape):
    # <r> = k theta, r_eff = (k + 2) theta, v_eff = 1 / (k + 2); scipy.stats for <r^2>, <r^3>.
    theta = 0.32 * UM
    radii, weights = Gamma(shape, theta).quadrature(400)
    assert moment(radii, weights, 1) == pytest.approx(shape * theta, rel=TAIL_TOLERANCE)
    reference = stats.gamma(a=shape, scale=theta)
    for n in (2, 3):
        assert moment(radii, weights, n) == pytest.approx(reference.moment(n),
                                                          rel=TAIL_TOLERANCE)
    assert effective_radius(radii, weights) == pytest.approx((shape + 2.0) * theta,
                                                             rel=TAIL_TOLERANCE)
    assert effective_variance(radii, weights) == pytest.approx(1.0 / (shape + 2.0),
                                                               **VEFF_TOLERANCE)


@pytest.mark.parametrize("sigma_g", [1.2, 1.8, 3.0])
def test_log_normal_moments_match_closed_form_and_scipy(sigma_g):
    r_g = 0.5 * UM
    s = math.log(sigma_g)
    radii, weights = LogNormal(r_g, sigma_g).quadrature(400)
    reference = stats.lognorm(s=s, scale=r_g)
    for n in range(4):
        closed_form = r_g**n * math.exp(n * n * s * s / 2.0)
        assert moment(radii, weights, n) == pytest.approx(closed_form, rel=TAIL_TOLERANCE)
        assert reference.moment(n) == pytest.approx(closed_form, rel=1e-12)


def test_log_normal_from_effective_returns_the_effective_radius_and_variance():
    distribution = LogNormal.from_effective(1.6 * UM, 0.2)
    radii, weights = distribution.quadrature(400)
    assert effective_radius(radii, weights) == pytest.approx(1.6 * UM, rel=TAIL_TOLERANCE)
    assert effective_variance(radii, weights) == pytest.approx(0.2, **VEFF_TOLERANCE)


@pytest.mark.parametrize(("a_um", "b"), [(1.6, 0.2), (0.5, 0.05), (10.0, 0.4)])
def test_modified_gamma_gives_back_its_effective_radius_and_variance(a_um, b):
    radii, weights = ModifiedGamma(a_um * UM, b).quadrature(400)
    assert effective_radius(radii, weights) == pytest.approx(a_um * UM, rel=TAIL_TOLERANCE)
    assert effective_variance(radii, weights) == pytest.approx(b, **VEFF_TOLERANCE)


def test_modified_gamma_of_mars_dust_is_the_gamma_of_meyran_2022():
    # Meyran 2022 App. A.2.2: a = 1.6 µm, b = 0.2 -> k = (1 - 2b)/b = 3, theta = 0.32 µm,
    # number-mean radius 0.96 µm.
    gamma = ModifiedGamma(1.6 * UM, 0.2).as_gamma()
    assert gamma.shape == pytest.approx(3.0, rel=1e-15)
    assert gamma.scale_m == pytest.approx(0.32 * UM, rel=1e-15)
    radii, weights = gamma.quadrature(400)
    assert moment(radii, weights, 1) == pytest.approx(0.96 * UM, rel=TAIL_TOLERANCE)


@pytest.mark.parametrize("nu", [0.0, 2.5, 3.0, 4.0])
def test_junge_moments_match_closed_form_to_second_order(nu):
    r1, r2 = 0.01 * UM, 1.0 * UM
    n_radii = 2000
    radii, weights = JungePowerLaw(nu, r1, r2).quadrature(n_radii)

    def integral(a):  # int_{ln r1}^{ln r2} r^a d ln r
        return math.log(r2 / r1) if a == 0.0 else (r2**a - r1**a) / a

    # Trapezoid rule on exp(a u): relative error (a h)^2 / 12 (Euler-Maclaurin); a ratio of two
    # such integrals, with |a| <= max(nu, |nu - 3|), is off by at most twice that.
    h = math.log(r2 / r1) / (n_radii - 1)
    tolerance = 2.0 * (max(nu, abs(nu - 3.0)) * h) ** 2 / 12.0 + 1e-13
    for n in range(1, 4):
        expected = integral(n - nu) / integral(-nu)
        assert moment(radii, weights, n) == pytest.approx(expected, rel=tolerance)


def test_monodisperse_is_one_radius():
    radii, weights = Monodisperse(2.0 * UM).quadrature(5000)
    np.testing.assert_array_equal(radii, [2.0 * UM])
    np.testing.assert_array_equal(weights, [1.0])
    assert effective_radius(radii, weights) == 2.0 * UM
    assert effective_variance(radii, weights) == 0.0


@pytest.mark.parametrize(("make", "message"), [
    (lambda: LogNormal(-1.0e-6, 1.5), "median_radius_m = -1e-06 must be finite and > 0"),
    (lambda: LogNormal(1.0e-6, 1.0), "geometric_std = 1.0 must be finite and > 1"),
    (lambda: LogNormal.from_effective(1.0e-6, 0.0), "effective_variance = 0.0 must be"),
    (lambda: Gamma(0.0, 1.0e-6), "shape = 0.0 must be finite and > 0"),
    (lambda: Gamma(2.0, math.nan), "scale_m = nan must be finite and > 0"),
    (lambda: ModifiedGamma(1.6e-6, 0.5), r"effective_variance = 0.5 must lie in \(0, 0.5\)"),
    (lambda: ModifiedGamma(0.0, 0.2), "effective_radius_m = 0.0 must be finite and > 0"),
    (lambda: JungePowerLaw(3.0, 1.0e-6, 1.0e-7), "max_radius_m = 1e-07 must be > min_radius_m"),
    (lambda: JungePowerLaw(math.inf, 1.0e-7, 1.0e-6), "exponent = inf must be finite"),
    (lambda: Monodisperse(-2.0), "radius_m = -2.0 must be finite and > 0"),
    (lambda: Gamma(3.0, 1.0e-7).quadrature(1), "n_radii = 1 must be an integer >= 2"),
    (lambda: effective_radius([1.0, 2.0], [1.0]), "must be 1-D of one length"),
])
def test_bad_parameters_raise_input_error_naming_them(make, message):
    with pytest.raises(InputError, match=message):
        make()
