"""The aureole of multiple forward-peak scattering (`transport.aureole`) against closed forms:
for a Gaussian peak of small width sigma the n-fold convolution on the sphere is, in the
small-angle limit, a Gaussian of variance n sigma^2, so the aureole's shape is a Poisson mixture
of Gaussians; and the shape integrates to 1 over the sphere."""

import math

import numpy as np
import pytest

from skyscatter.transport.aureole import peak_aureole

N_ANGLE = 4097  # the tables' sampling (TableResolution.phase_angles)
THETA = np.linspace(0.0, np.pi, N_ANGLE)
SIGMA = np.radians(1.0)
TRUNCATION_DEG = 10.0


def gaussian(psi: np.ndarray, variance: float) -> np.ndarray:
    """The small-angle 2-D Gaussian exp(-psi^2 / (2 v)) / (2 pi v) [sr^-1]."""
    return np.exp(-psi * psi / (2.0 * variance)) / (2.0 * np.pi * variance)


def mixture(psi: np.ndarray, x: float) -> np.ndarray:
    """sum_{n >= 2} x^n / n! N(n sigma^2)(psi) / (exp(x) - 1 - x)."""
    terms = [x ** n / math.factorial(n) * gaussian(psi, n * SIGMA ** 2) for n in range(2, 60)]
    return np.sum(terms, axis=0) / (math.expm1(x) - x)


@pytest.fixture(scope="module")
def aureole():
    peak = np.where(np.radians(TRUNCATION_DEG) > THETA, gaussian(THETA, SIGMA ** 2), 0.0)
    weight = 2.0 * np.pi * np.sin(THETA)
    peak /= np.trapezoid(peak * weight, THETA)
    return peak_aureole(peak[:, None], TRUNCATION_DEG, 20.0)


def x_nodes(aureole) -> np.ndarray:
    n_x = aureole.shape.shape[0]
    return np.expm1(np.log1p(aureole.x_max) * np.arange(n_x) / (n_x - 1))


def psi_nodes(aureole) -> np.ndarray:
    return np.linspace(0.0, aureole.psi_max_rad, aureole.shape.shape[1])


@pytest.mark.parametrize("node", [0, 20, 40])
def test_shape_is_the_poisson_mixture_of_widened_gaussians(aureole, node):
    x = max(x_nodes(aureole)[node], 1e-6)
    psi = psi_nodes(aureole)
    expected = mixture(psi, x)
    near = psi < np.radians(4.0)
    # small-angle limit: sin(psi) ~ psi to 0.1 % within 4 deg; the spherical convolution
    # differs from the planar one by O(sigma^2) = 3e-4
    np.testing.assert_allclose(aureole.shape[node, near, 0], expected[near],
                               rtol=5e-3, atol=1e-3 * expected[0])


def test_shape_integrates_to_one_while_the_angles_hold_it(aureole):
    psi = psi_nodes(aureole)
    x = x_nodes(aureole)
    energy = np.trapezoid(aureole.shape[:, :, 0] * 2.0 * np.pi * np.sin(psi), psi, axis=1)
    # up to x = 20 the widest term (n ~ 30: 5.5 deg rms) stays well inside psi_max = 30 deg
    np.testing.assert_allclose(energy[x <= 20.0], 1.0, atol=2e-3)


def test_no_peak_gives_no_aureole():
    empty = peak_aureole(np.zeros((N_ANGLE, 2)), TRUNCATION_DEG, 1.0)
    assert np.all(empty.shape == 0.0)
