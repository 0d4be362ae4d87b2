"""The least-squares core (`fit.least_squares`) against closed forms: Beer-Lambert at several
airmasses, whose optical depth has an analytic standard error, and a model that only sees the
sum of two parameters."""

import numpy as np
import pytest

from skyscatter.fit.least_squares import weighted_fit
from skyscatter.fit.model_error import error_covariance, whitened
from skyscatter.fit.parameters import FreeParameter

AIRMASSES = np.array([1.0, 1.5, 2.0, 3.0, 5.0])
TAU = 0.3
RELATIVE = 0.01
SIGNS = np.array([1.0, -1.0, 1.0, -1.0, 1.0])  # 1 % relative uncertainty of each transmittance


def _beer_lambert(measured: np.ndarray, sigma: np.ndarray):
    return lambda p: (measured - np.exp(-p[0] * AIRMASSES)) / sigma


def test_optical_depth_standard_error_matches_the_closed_form():
    # T_i = exp(-tau m_i) measured with sigma_i = s T_i: d T_i / d tau = -m_i T_i, so the
    # linearised normal equation gives var(tau) = 1 / sum(m_i^2 T_i^2 / sigma_i^2)
    # = s^2 / sum(m_i^2) exactly at noise-free data. Tolerance 1e-4 relative: the central
    # difference's error (m h)^2 / 6 with step h = 2e-3 in tau is 2e-5 at airmass 5
    # (a forward difference's m h / 2 would be 5e-3: the test tells them apart).
    truth = np.exp(-TAU * AIRMASSES)
    fit = weighted_fit(_beer_lambert(truth, RELATIVE * truth), [FreeParameter("tau", 0, 2, 1)])
    assert fit.estimates[0] == pytest.approx(TAU, abs=1e-8)
    expected = RELATIVE / np.sqrt(np.sum(AIRMASSES ** 2))
    assert fit.uncertainties[0] == pytest.approx(expected, rel=1e-4)
    assert fit.chi_square == pytest.approx(0.0, abs=1e-12)
    assert not fit.unconstrained


def test_stated_uncertainty_matches_the_scatter_of_noisy_fits():
    # 400 noise realisations: the standard deviation of the estimates must equal the stated
    # sigma; the sample standard deviation of 400 normal draws is within 3.5/sqrt(2 x 400)
    # = 12 % of the true one at 3.5 sigma, so 12 % it is.
    rng = np.random.default_rng(7)
    truth = np.exp(-TAU * AIRMASSES)
    sigma = RELATIVE * truth
    estimates, stated = [], []
    for _ in range(400):
        measured = truth + sigma * rng.standard_normal(AIRMASSES.size)
        fit = weighted_fit(_beer_lambert(measured, sigma), [FreeParameter("tau", 0, 2, 0.5)])
        estimates.append(fit.estimates[0])
        stated.append(fit.uncertainties[0])
    assert np.std(estimates) == pytest.approx(np.median(stated), rel=0.12)


def test_relative_weights_scale_by_the_reduced_chi_square():
    # Same data, sigmas ten times too small: absolute covariance is 100 times smaller, the
    # scaled one (curve_fit's absolute_sigma=False) unchanged - a closed-form identity, so
    # 1e-6 (the solver's convergence).
    rng = np.random.default_rng(3)
    truth = np.exp(-TAU * AIRMASSES)
    measured = truth * (1 + RELATIVE * rng.standard_normal(AIRMASSES.size))
    parameter = [FreeParameter("tau", 0, 2, 0.5)]
    right = weighted_fit(_beer_lambert(measured, RELATIVE * truth), parameter,
                         relative_weights=True)
    small = weighted_fit(_beer_lambert(measured, 0.1 * RELATIVE * truth), parameter,
                         relative_weights=True)
    absolute = weighted_fit(_beer_lambert(measured, 0.1 * RELATIVE * truth), parameter)
    assert small.scaled and not absolute.scaled
    assert small.uncertainties[0] == pytest.approx(right.uncertainties[0], rel=1e-6)
    assert absolute.uncertainties[0] == pytest.approx(0.1 * np.sqrt(
        right.covariance[0, 0] / right.reduced_chi_square), rel=1e-6)


def test_a_combination_only_is_named_and_left_unbounded():
    # T = exp(-(a + b) m): only a + b is seen; J has a zero singular value, both are named
    truth = np.exp(-TAU * AIRMASSES)
    fit = weighted_fit(lambda p: (truth - np.exp(-(p[0] + p[1]) * AIRMASSES)) / 0.01,
                       [FreeParameter("a", 0, 1, 0.1), FreeParameter("b", 0, 1, 0.1)])
    assert fit.estimates.sum() == pytest.approx(TAU, abs=1e-6)
    assert {n["key"] for n in fit.unconstrained} == {"a", "b"}
    assert "combination" in fit.unconstrained[0]["reason"]
    assert np.all(np.isinf(fit.uncertainties))


def test_a_parameter_the_data_hardly_see_is_named_with_its_share_of_the_bounds():
    # exp(-tau m) + 1e-2 c (-1)^i: c moves the values by +-1e-2 per unit against sigma 1e-2
    # (a pattern nearly orthogonal to tau's), so its 1-sigma is ~1 / sqrt(5) = 0.45, above a
    # quarter of its bounds' width (1), while J's singular values differ by ~1/200 only (not
    # degenerate): named for its share of the bounds; tau stays constrained
    truth = np.exp(-TAU * AIRMASSES)
    fit = weighted_fit(lambda p: (truth - np.exp(-p[0] * AIRMASSES) - 1e-2 * p[1] * SIGNS) / 0.01,
                       [FreeParameter("tau", 0, 2, 0.5), FreeParameter("c", 0, 1, 0.5)])
    named = {n["key"]: n["reason"] for n in fit.unconstrained}
    assert "tau" not in named
    assert "c" in named and "bounds' width" in named["c"]


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.9])
def test_correlated_model_error_gives_the_variance_of_a_mean_of_correlated_values(rho):
    # n values of one level c, each with error sigma, errors correlated rho pairwise: the
    # generalised least-squares estimate of c is their mean, of variance
    # sigma^2 (1 + (n - 1) rho) / n (equicorrelated errors). Here the whole sigma is the model
    # error (the measurements' own 1e-9 is nil); 1e-3: the measurements' term, the Jacobian's
    # central difference and the model error's change with c over the step.
    n, sigma, level = 8, 0.05, 1.0
    measured = np.full(n, level)
    kind = np.array(["radiance"] * n)

    def residuals(p):
        predicted = np.full(n, p[0])
        covariance = error_covariance(np.full(n, 1e-9), np.full(n, sigma), kind, rho)
        return whitened(measured - predicted, covariance)

    fit = weighted_fit(residuals, [FreeParameter("c", 0.5, 1.5, 0.8)])
    assert fit.estimates[0] == pytest.approx(level, abs=1e-8)
    expected = sigma * np.sqrt((1 + (n - 1) * rho) / n)
    assert fit.uncertainties[0] == pytest.approx(expected, rel=1e-3)
