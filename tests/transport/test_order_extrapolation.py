"""Reduced-rank extrapolation of the scattering orders against the exact sum of a linear
iteration: a 1-D diffusion operator, whose many slow modes of nearly equal eigenvalue are
those of an optically thick cloud, solved by a direct linear solve."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.transport.order_extrapolation import (
    ERROR_MEDIAN,
    ERROR_P95,
    OrderExtrapolation,
)


def _diffusion(n_cells: int, albedo: float, width: float) -> tuple[np.ndarray, np.ndarray]:
    """(K, first order): K spreads each cell's light over a Gaussian of `width` cells, keeps
    `albedo` of it and leaks it at the two ends; the first order falls off from one end."""
    x = np.arange(n_cells)
    spread = np.exp(-0.5 * ((x[:, None] - x[None, :]) / width) ** 2)
    spread /= spread.sum(axis=0, keepdims=True)
    kept = 1.0 - np.exp(-20.0 * np.minimum(x, n_cells - 1 - x) / n_cells)
    return albedo * spread * kept[:, None], np.exp(-x / (0.1 * n_cells)) + 0.01


def _extrapolate(operator: np.ndarray, first: np.ndarray, max_orders: int
                 ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """(stop order, extrapolated sum, partial sum there, extrapolated 'irradiance' of the
    first three cells) of the orders first, K first, K^2 first, ..."""
    extrapolation = OrderExtrapolation(first_order=2)
    partial, delta = first.copy(), first.copy()
    for order in range(2, max_orders):
        delta = operator @ delta
        partial = partial + delta
        tails = extrapolation.add(order, partial[:, None], delta[:, None], delta[:3, None])
        if tails is not None:
            return (order, partial + tails[0][:, 0], partial,
                    partial[:3] + tails[1][:, 0])
    raise AssertionError(f"no estimate settled within {max_orders} orders")


@pytest.mark.parametrize("albedo, width", [(0.95, 5.0), (0.99, 30.0), (0.999, 10.0)])
def test_the_extrapolated_orders_reach_the_exact_sum_within_their_tolerance(albedo, width):
    operator, first = _diffusion(1400, albedo, width)
    exact = np.linalg.solve(np.eye(first.size) - operator, first)
    order, estimate, partial, irradiance = _extrapolate(operator, first, 2000)
    error = np.abs(estimate / exact - 1.0)
    # the error left is estimated from the estimates' own convergence, so it may miss by a
    # factor: 2x the tolerances (measured 0.5-1.1e-3 median, 0.3-1.6e-2 max)
    assert np.median(error) < 2.0 * ERROR_MEDIAN
    assert np.percentile(error, 95) < 2.0 * ERROR_P95
    # it stopped where the orders summed so far were still far from the sum (8-12 %) ...
    assert np.median(np.abs(partial / exact - 1.0)) > 0.05
    # ... and the other quantities of the same orders go the same way
    np.testing.assert_allclose(irradiance, exact[:3], rtol=2.0 * ERROR_P95)


def test_nothing_is_extrapolated_before_the_first_order_kept_or_from_orders_of_zeros():
    extrapolation = OrderExtrapolation(first_order=5)
    ones = np.ones((50, 2))
    assert all(extrapolation.add(order, ones, ones, ones) is None for order in range(2, 5))
    zeros = np.zeros((50, 2))
    assert all(extrapolation.add(order, ones, zeros, zeros) is None for order in range(5, 20))
