"""One observer's frames from a sky-view grid (`LutSolver`'s SKY_GRID_* constants) against the
lookups of every ray, which the rest of the suite checks against exact references."""

import numpy as np
import pytest
from transport_cases import SMALL, exponential_earth

from skyscatter.transport import lut_solver
from skyscatter.transport._table_lookup_kernels import EXP_DARKEST, exp_by_squaring
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position

RAYS = 200_000


@pytest.fixture(scope="module")
def hazy_earth():
    """Rayleigh + HG 0.8 haze, small tables: a forward peak and a bright horizon."""
    return LutSolver(exponential_earth(), SMALL, orders=3)


def relative_errors(from_grid: np.ndarray, per_ray: np.ndarray) -> np.ndarray:
    """|from_grid / per_ray - 1| where the per-ray lookups are lit (> 1e-30)."""
    lit = per_ray > 1e-30
    return np.abs(from_grid[lit] / per_ray[lit] - 1.0)


@pytest.mark.parametrize("altitude_m", [2.0, 1000.0])
@pytest.mark.parametrize("sun_zenith_deg", [0.0, 60.0, 88.0, 94.0])
def test_the_grid_matches_the_lookups_of_every_ray(hazy_earth, monkeypatch, altitude_m,
                                                   sun_zenith_deg):
    rng = np.random.default_rng(11)
    zenith = np.arccos(rng.uniform(-0.3, 1.0, RAYS))
    views = local_frame_directions(zenith, rng.uniform(0.0, 2.0 * np.pi, RAYS))
    origin = observer_position(altitude_m, hazy_earth.tables.bottom_radius_m)
    sun = local_frame_directions(np.radians(sun_zenith_deg), 0.7)
    assert RAYS >= lut_solver.SKY_GRID_MIN_RAYS
    from_grid = hazy_earth.sky_radiance(origin, views, sun)
    monkeypatch.setattr(lut_solver, "SKY_GRID_MIN_RAYS", RAYS + 1)
    per_ray = hazy_earth.sky_radiance(origin, views, sun)
    # next to the sun both are the same lookups
    near_sun = views @ sun > np.cos(np.radians(lut_solver.SKY_GRID_EXACT_DEG))
    np.testing.assert_array_equal(from_grid[near_sun], per_ray[near_sun])
    # elsewhere log-bilinear interpolation between cells 0.1-1.4 deg apart: far below the
    # tables' own accuracy (0.2-1 % median against the Monte Carlo). Measured here: median
    # < 0.01 %, 99.9th percentile < 0.6 % (twilight, sun 94 deg, the largest); single
    # values up to ~2 % in the row of pixels just below the horizon, where the ground's
    # light changes fastest.
    lit = per_ray > 1e-30
    error = relative_errors(from_grid, per_ray)
    assert np.median(error) < 1e-4
    assert np.percentile(error, 99.9) < 1e-2
    assert error.max() < 0.03
    assert np.all(from_grid[~lit] < 1e-25)


@pytest.mark.parametrize("altitude_m", [2.0, 1000.0])
@pytest.mark.parametrize("sun_zenith_deg", [0.0, 60.0, 88.0, 94.0])
def test_the_sun_grid_matches_the_lookups_of_every_ray(hazy_earth, monkeypatch, altitude_m,
                                                       sun_zenith_deg):
    # A frame with many rays next to the sun: those within SKY_GRID_EXACT_DEG of it come from
    # the sun grid, except where its cell may reach across the horizon (looked up alone).
    rng = np.random.default_rng(12)
    n_near = 2 * lut_solver.SUN_GRID_MIN_RAYS
    psi = np.radians(lut_solver.SKY_GRID_EXACT_DEG) * np.sqrt(rng.uniform(0.0, 0.9999, n_near))
    chi = rng.uniform(0.0, 2.0 * np.pi, n_near)
    sun = local_frame_directions(np.radians(sun_zenith_deg), 0.7)
    across = np.cross(sun, [0.3, 0.2, 0.9])
    across /= np.linalg.norm(across)
    near = (np.cos(psi)[:, None] * sun + np.sin(psi)[:, None]
            * (np.cos(chi)[:, None] * across + np.sin(chi)[:, None] * np.cross(sun, across)))
    views = np.concatenate([near, rng.normal(size=(RAYS, 3))])
    origin = observer_position(altitude_m, hazy_earth.tables.bottom_radius_m)
    from_grid = hazy_earth.sky_radiance(origin, views, sun)[:n_near]
    monkeypatch.setattr(lut_solver, "SKY_GRID_MIN_RAYS", 10 * RAYS)
    per_ray = hazy_earth.sky_radiance(origin, near, sun)
    # rays whose cell may reach across the horizon: the same lookups
    r = np.linalg.norm(origin)
    up = origin / r
    horizon = np.pi / 2 + np.arccos(hazy_earth.tables.bottom_radius_m / r)  # the dip below 90
    at_horizon = np.abs(np.arccos(near @ up) - horizon) < np.radians(
        lut_solver.SUN_GRID_HORIZON_DEG)
    np.testing.assert_array_equal(from_grid[at_horizon], per_ray[at_horizon])
    # elsewhere log-bilinear interpolation in cells at most 0.31 deg x 0.49 deg (at 20 deg
    # from the sun; 0.002 deg next to it), held to the sky-view grid's bounds above.
    # Measured here: median < 0.005 %, 99.9th percentile < 0.31 %, every value < 0.49 %
    # (twilight, sun 94 deg); `earth` and `mars-physical` at 16 bands: 99.9th percentile
    # 0.56 %, every value < 0.82 % (docs/performance.md).
    error = relative_errors(from_grid, per_ray)
    assert np.median(error) < 1e-4
    assert np.percentile(error, 99.9) < 1e-2
    assert error.max() < 0.02


def test_small_frames_and_many_origins_are_looked_up_ray_by_ray(hazy_earth, monkeypatch):
    origin = observer_position(10.0, hazy_earth.tables.bottom_radius_m)
    views = local_frame_directions(np.radians([10.0, 50.0, 89.0]), np.radians([0.0, 90.0, 180.0]))
    sun = local_frame_directions(np.radians(40.0), 0.0)
    calls = []
    monkeypatch.setattr(LutSolver, "_sky_from_view_grid",
                        lambda *args: calls.append(args))
    hazy_earth.sky_radiance(origin, views, sun)
    hazy_earth.sky_radiance(np.repeat(origin[None], RAYS, 0),
                            np.repeat(views[:1], RAYS, 0), sun)
    assert calls == []


def test_the_grids_exponential_is_the_librarys_to_its_stated_accuracy():
    # Reference: numpy's exp. exp_by_squaring's docstring: 1e-12 relative from -40 (the
    # logarithms of skies down to 4e-18 of 1), 1e-8 down to the darkest argument it takes
    # (half the logarithm of the view tables' floor), 0 below.
    bright = np.linspace(-40.0, 50.0, 20_001)
    dark = np.linspace(EXP_DARKEST + 1e-9, -40.0, 20_001)
    for x, tolerance in ((bright, 1e-12), (dark, 1e-8)):
        values = np.array([exp_by_squaring(v) for v in x])
        np.testing.assert_allclose(values, np.exp(x), rtol=tolerance, atol=0.0)
    assert exp_by_squaring(EXP_DARKEST - 1e-9) == 0.0
    assert exp_by_squaring(-np.inf) == 0.0
