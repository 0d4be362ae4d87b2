"""Wavelength grids, cells and exact cell averages (skyscatter.spectrum.grid)."""

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.spectrum.grid import (
    cell_average,
    cell_edges,
    cell_widths,
    checked_grid,
    wavelength_grid,
)


def test_default_grid_is_bruneton_16_bin_centres():
    # Bruneton & Neyret 2008 / Elek 2010: 16 bins of (830 - 360)/16 = 29.375 nm, centres.
    grid = wavelength_grid()
    assert grid.shape == (16,)
    assert grid[0] == pytest.approx(360.0 + 29.375 / 2, abs=1e-12)
    assert grid[-1] == pytest.approx(830.0 - 29.375 / 2, abs=1e-12)
    np.testing.assert_allclose(np.diff(grid), 29.375, atol=1e-12)


def test_edges_of_an_equal_bin_grid_are_the_bin_edges():
    # Closed form: edges of wavelength_grid(n, a, b) are a + k (b - a)/n.
    edges = cell_edges(wavelength_grid(47, 360.0, 830.0))
    np.testing.assert_allclose(edges, np.linspace(360.0, 830.0, 48), atol=1e-9)


def test_edges_of_an_uneven_grid_are_midpoints_with_symmetric_end_cells():
    edges = cell_edges([400.0, 410.0, 440.0])
    np.testing.assert_allclose(edges, [395.0, 405.0, 425.0, 455.0])
    np.testing.assert_allclose(cell_widths([400.0, 410.0, 440.0]), [10.0, 20.0, 30.0])


def test_single_wavelength_gets_a_one_nm_cell():
    np.testing.assert_allclose(cell_edges(550.0), [549.5, 550.5])
    np.testing.assert_allclose(cell_edges([550.0]), [549.5, 550.5])


def test_cell_average_of_a_linear_function_is_its_value_at_the_cell_centre():
    # Identity: the mean of a linear f over [a, b] is f((a + b)/2); the table is exactly linear.
    table_wl = np.array([300.0, 900.0])
    table = np.array([[1.0, 7.0], [2.0, 2.0]])  # two spectra: slope 0.01 nm⁻¹, and constant
    grid = wavelength_grid(16)
    centres = 0.5 * (cell_edges(grid)[1:] + cell_edges(grid)[:-1])
    expected = np.stack([1.0 + 0.01 * (centres - 300.0), np.full(16, 2.0)])
    np.testing.assert_allclose(cell_average(table_wl, table, grid), expected, rtol=1e-12)


def test_cell_average_conserves_the_table_integral_and_counts_zero_outside():
    # Σ f̄ w over cells covering the table = trapezoid integral of the table (exact);
    # a cell half outside the table averages with zeros.
    rng = np.random.default_rng(1)
    table_wl = np.sort(rng.uniform(400.0, 700.0, 200))
    values = rng.uniform(0.0, 2.0, 200)
    grid = wavelength_grid(7, 380.0, 720.0)
    total = np.sum(cell_average(table_wl, values, grid) * cell_widths(grid))
    assert total == pytest.approx(np.trapezoid(values, table_wl), rel=1e-12)
    half_out = cell_average([500.0, 600.0], [1.0, 1.0], [450.0, 550.0, 650.0])
    np.testing.assert_allclose(half_out, [0.0, 1.0, 0.0])
    np.testing.assert_allclose(cell_average([500.0, 600.0], [1.0, 1.0], [600.0]), [0.5])


@pytest.mark.parametrize("bad", [[-5.0, 400.0], [400.0, np.nan], [400.0, 0.0]])
def test_non_positive_or_nan_wavelength_is_refused_with_its_value(bad):
    with pytest.raises(InputError, match=r"wavelengths_nm must be positive and finite.*got"):
        cell_edges(bad)


def test_descending_grid_is_refused_naming_the_values():
    with pytest.raises(InputError, match=r"strictly ascending; got 500.0 then 450.0 at index 1"):
        checked_grid([500.0, 450.0])


def test_two_dimensional_grid_is_refused():
    with pytest.raises(InputError, match=r"1-D grid.*shape \(2, 2\)"):
        checked_grid([[400.0, 500.0], [600.0, 700.0]])


@pytest.mark.parametrize("count", [0, -3, 2.5, True])
def test_bad_count_is_refused(count):
    with pytest.raises(InputError, match=r"count must be an integer >= 1"):
        wavelength_grid(count)


def test_bad_range_is_refused():
    with pytest.raises(InputError, match=r"start_nm < stop_nm.*start_nm=830.*stop_nm=360"):
        wavelength_grid(16, 830.0, 360.0)
