"""The simplified (single-scattering) Bruneton solver (`transport/bruneton_simplified.py`)
against the ray-marched single scattering of the "single" solver, and its tables against the
full ones."""

from __future__ import annotations

import numpy as np
import pytest
from transport_cases import EARTH_RADIUS_M, exponential_earth

from skyscatter.transport.bruneton_simplified import BrunetonSimplifiedSolver, SimplifiedTables
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import SingleScatteringSolver, observer_position
from skyscatter.transport.tables import precompute_tables

PERCENT = 0.01


@pytest.fixture(scope="module")
def profile():
    return exponential_earth()


@pytest.fixture(scope="module")
def one_order_tables(profile):
    return precompute_tables(profile, orders=1)  # Bruneton 2017's sizes


@pytest.fixture(scope="module")
def simplified(profile, one_order_tables):
    return BrunetonSimplifiedSolver(profile, SimplifiedTables.from_tables(one_order_tables, 0.0))


def sky_grid(max_view_zenith_deg=88.0):
    zenith, azimuth = np.meshgrid(np.radians(np.linspace(0.0, max_view_zenith_deg, 12)),
                                  np.radians(np.arange(0.0, 360.0, 30.0)), indexing="ij")
    return local_frame_directions(zenith, azimuth)


@pytest.mark.parametrize("altitude_m", [0.0, 5000.0])
def test_daylight_sky_is_the_ray_marched_single_scattering(simplified, profile, altitude_m):
    # View zenith 0-88 deg x 12 azimuths x sun zenith 0-80 deg, 3 wavelengths; reference: the
    # "single" solver, 256 samples per ray. The same lookups as the full tables' single
    # scattering, whose error docs/validation.md and test_transport_tables.py state (median
    # 0.05 %, 95th percentile 0.16 %); measured here from the ground: median 0.013 %, 95th
    # percentile 0.066 %, max 0.17 %; from 5 km 0.022 %, 0.15 %, max 0.4 %. Bounds 0.1 % and
    # 0.5 %.
    reference = SingleScatteringSolver(profile, n_samples=256)
    origin = observer_position(altitude_m, EARTH_RADIUS_M)
    directions = sky_grid()
    errors = []
    for sun_zenith_deg in (0.0, 20.0, 40.0, 60.0, 70.0, 80.0):
        sun = local_frame_directions(np.radians(sun_zenith_deg), 0.0)
        ours = simplified.sky_radiance(origin, directions, sun)
        errors.append(np.abs(ours / reference.sky_radiance(origin, directions, sun) - 1.0))
    errors = np.array(errors)
    assert np.median(errors) < 0.1 * PERCENT
    assert np.percentile(errors, 95) < 0.5 * PERCENT


def test_the_lit_ground_seen_from_above_is_the_ray_marched_one(simplified, profile):
    # From 10 km, views 100-180 deg from the zenith meet the ground: the air in front and the
    # ground lit by the direct sun only (no sky light, as the "single" solver). Measured
    # -0.075 % at most (440 nm, 100 deg); 0.3 %.
    reference = SingleScatteringSolver(profile, n_samples=256)
    origin = observer_position(10_000.0, EARTH_RADIUS_M)
    views = local_frame_directions(np.radians([100.0, 130.0, 180.0]), np.zeros(3))
    sun = local_frame_directions(np.radians(40.0), 0.5)
    np.testing.assert_allclose(simplified.sky_radiance(origin, views, sun),
                               reference.sky_radiance(origin, views, sun), rtol=3e-3)


def test_the_tables_kept_are_the_single_scattering_slices_and_the_transmittance(
        one_order_tables):
    # What is dropped: the orders >= 2 slice of the interleaved table (zero at one order), the
    # sky irradiance table (zero at one order), the peak-transmittance and aureole tables; what
    # is kept is bit for bit the builder's.
    kept = SimplifiedTables.from_tables(one_order_tables, 0.0)
    full = one_order_tables
    np.testing.assert_array_equal(np.moveaxis(kept.single, -2, 0), full.single_scattering)
    np.testing.assert_array_equal(kept.transmittance, full.transmittance)
    assert np.all(full.multiple_scattering == 0.0) and np.all(full.irradiance == 0.0)
    n_s = kept.single.shape[-2]
    assert kept.nbytes == (full.transmittance.nbytes + full.phase.nbytes
                           + full.scattering.nbytes * n_s // (n_s + 1))
    assert kept.nbytes < full.nbytes
