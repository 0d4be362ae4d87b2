"""Every registered solver (`transport.solvers.SOLVERS`) through the same checks: the `Solver`
contract (shapes, wavelength last, broadcasting, units, closed-form transmittance, finite at
the horizon, with the sun below it and from space) and the members of every capability protocol
it satisfies. A solver registered later is tested here without a new line.

The atmosphere is `exponential_earth` cut to 2 wavelengths, so that the spectral axis cannot be
mistaken for the 3 components of a direction; the solvers get small settings (`SMALL` tables
of 2 orders, 16 samples or paths). A solver with a narrower `domain` (`solver_domain`: the
analytic skies of Earth's ground) is held to it: outside, its sky radiance must be refused with
an InputError, inside the same checks apply.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from transport_cases import EARTH_RADIUS_M, SMALL, exponential_earth

from skyscatter.errors import InputError
from skyscatter.transport import solvers
from skyscatter.transport.geometry import ground_distances, local_frame_directions
from skyscatter.transport.solvers import (
    SOLVERS,
    NoisySolver,
    Solver,
    SolverOptions,
    SurfaceRadianceSolver,
    SurfaceSolver,
    TableSolver,
    make_solver,
    register_solver,
    solver_domain,
)

DEG = math.pi / 180.0
OPTIONS = SolverOptions(n_samples=16, orders=2, resolution=SMALL, seed=3)
SCALE_HEIGHTS_M = np.array([8000.0, 1200.0])  # of exponential_earth's two constituents
GROUND = np.array([0.0, 0.0, EARTH_RADIUS_M])
AIRCRAFT = GROUND + [0.0, 0.0, 10_000.0]
ORBIT = GROUND + [0.0, 0.0, 400_000.0]
NEAR_GROUND = GROUND + [0.0, 0.0, 500.0]  # a second observer inside a ground-only domain
HIGH_SUN = local_frame_directions(60.0 * DEG, 0.0)
CAPABILITIES = (SurfaceSolver, SurfaceRadianceSolver, NoisySolver, TableSolver)


def two_wavelength_earth():
    """`exponential_earth` at 440 and 680 nm only."""
    earth = exponential_earth()
    keep = [0, 2]
    return dataclasses.replace(
        earth, wavelengths_nm=earth.wavelengths_nm[keep],
        extinction_per_density=earth.extinction_per_density[:, keep],
        scattering_per_density=earth.scattering_per_density[:, keep],
        ground_albedo=earth.ground_albedo[keep], toa_irradiance=earth.toa_irradiance[keep])


@pytest.fixture(scope="module")
def profile():
    return two_wavelength_earth()


@pytest.fixture(scope="module", params=list(SOLVERS))
def solver(request, profile):
    return make_solver(request.param, profile, OPTIONS)


def directions(zenith_deg, azimuth_deg) -> np.ndarray:
    zenith, azimuth = np.broadcast_arrays(np.asarray(zenith_deg, dtype=np.float64),
                                          np.asarray(azimuth_deg, dtype=np.float64))
    return local_frame_directions(zenith * DEG, azimuth * DEG)


def vertical_optical_depth(profile, distance_m: float) -> np.ndarray:
    """Closed form of the optical depth (n_wl,) from the ground straight up over `distance_m`:
    sum_c beta_c H_c (1 - exp(-d / H_c)) for the exponential densities exp(-h / H_c)."""
    column = SCALE_HEIGHTS_M * -np.expm1(-distance_m / SCALE_HEIGHTS_M)
    return column @ profile.extinction_per_density


def assert_radiance(radiance: np.ndarray, shape: tuple[int, ...]) -> None:
    assert radiance.shape == shape
    assert np.all(np.isfinite(radiance)) and np.all(radiance >= 0.0)


def assert_refused(call) -> None:
    """The call raises the one-line InputError of a request outside the solver's domain."""
    with pytest.raises(InputError, match="solver '.*' describes"):
        call()


def assert_transmittance(transmittance: np.ndarray, shape: tuple[int, ...]) -> None:
    assert transmittance.shape == shape
    assert np.all((transmittance >= 0.0) & (transmittance <= 1.0))


# The contract of every solver -------------------------------------------------------------

def test_a_registered_solver_is_a_solver_of_the_profile_under_its_name(solver, profile):
    assert isinstance(solver, Solver)
    assert solver.name in SOLVERS and make_solver(solver.name, profile, OPTIONS).name == \
        solver.name
    assert solver.profile is profile


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_results_have_the_directions_shape_and_the_wavelengths_last(solver, profile, shape):
    # S + (n_wl,) with n_wl = 2 for scalar, (5,) and (2, 3) batches of directions (3,)
    rng = np.random.default_rng(1)
    views = directions(rng.uniform(0.0, 85.0, shape), rng.uniform(0.0, 360.0, shape))
    expected = shape + (profile.wavelengths_nm.size,)
    assert_radiance(solver.sky_radiance(GROUND, views, HIGH_SUN), expected)
    assert_transmittance(solver.transmittance(GROUND, views), expected)


def test_positions_and_distances_broadcast_against_the_directions(solver):
    # Two observers (2, 1, 3) x three directions (3, 3) -> (2, 3, n_wl), row i equal to the
    # call for observer i alone. Deterministic answers agree to rounding (1e-12); noisy ones
    # draw other random numbers for other rays, so they agree within 5 standard errors.
    second = NEAR_GROUND if solver_domain(solver).ground_only else AIRCRAFT
    positions = np.stack([GROUND, second])[:, None, :]
    views = directions([0.0, 45.0, 80.0], [0.0, 90.0, 200.0])
    radiance = solver.sky_radiance(positions, views, HIGH_SUN)
    transmittance = solver.transmittance(positions, views)
    assert radiance.shape == transmittance.shape == (2, 3, solver.profile.n_wavelengths)
    for i, position in enumerate(positions[:, 0]):
        np.testing.assert_allclose(transmittance[i], solver.transmittance(position, views),
                                   rtol=1e-12, atol=0.0)
        if isinstance(solver, NoisySolver):
            both, both_error = solver.sky_radiance_with_error(positions, views, HIGH_SUN)
            alone, alone_error = solver.sky_radiance_with_error(position, views, HIGH_SUN)
            assert np.all(np.abs(both[i] - alone) <= 5.0 * np.hypot(both_error[i], alone_error))
        else:
            np.testing.assert_allclose(radiance[i], solver.sky_radiance(position, views,
                                                                        HIGH_SUN), rtol=1e-12)
    # distances (3,) broadcast against the directions (3, 3)
    distances = np.array([1e3, 5e3, 20e3])
    np.testing.assert_allclose(
        solver.transmittance(GROUND, views, distances),
        np.stack([solver.transmittance(GROUND, v, d) for v, d in zip(views, distances,
                                                                     strict=True)]),
        rtol=1e-12)


@pytest.mark.parametrize("distance_m", [np.inf, 5000.0])
def test_zenith_transmittance_is_exp_minus_the_closed_form_optical_depth(solver, profile,
                                                                          distance_m):
    # Reference: T = exp(-sum_c beta_c H_c (1 - exp(-d / H_c))), d = min(distance, 60 km top).
    # The profile's densities are linear between 30 m levels (a relative error in tau of
    # (30 m)^2 / (12 H^2) <= 5e-5, below 1e-6 in T); the solvers' own quadrature measured
    # 1.2e-5 (256-interval ray march) and 3.6e-6 (the SMALL transmittance table). Tolerance
    # 3e-5 relative.
    expected = np.exp(-vertical_optical_depth(profile, min(distance_m, 60_000.0)))
    measured = solver.transmittance(GROUND, [0.0, 0.0, 1.0], distance_m)
    np.testing.assert_allclose(measured, expected, rtol=3e-5)


@pytest.mark.parametrize("position", [GROUND, AIRCRAFT], ids=["ground", "aircraft"])
def test_answers_are_finite_at_the_horizon(solver, position):
    # View zenith 89.9-90.1 deg, where the ray grazes the ground or the planet's limb.
    views = directions(np.array([89.9, 90.0, 90.1])[:, None], np.array([0.0, 90.0, 180.0]))
    shape = (3, 3, solver.profile.n_wavelengths)
    if solver_domain(solver).ground_only and position is AIRCRAFT:
        assert_refused(lambda: solver.sky_radiance(position, views, HIGH_SUN))
    else:
        assert_radiance(solver.sky_radiance(position, views, HIGH_SUN), shape)
    assert_transmittance(solver.transmittance(position, views), shape)


@pytest.mark.parametrize("sun_zenith_deg", [90.5, 96.0])
def test_answers_are_finite_with_the_sun_below_the_horizon(solver, sun_zenith_deg):
    # Twilight: the sky is still lit from above; the sun's own transmittance is 0, its ray
    # meets the planet.
    sun = directions(sun_zenith_deg, 0.0)
    views = directions(np.array([0.0, 45.0, 85.0, 89.9, 90.1, 120.0])[:, None],
                       np.array([0.0, 90.0, 180.0]))
    if solver_domain(solver).sun_above_horizon:
        assert_refused(lambda: solver.sky_radiance(GROUND, views, sun))
    else:
        assert_radiance(solver.sky_radiance(GROUND, views, sun),
                        (6, 3, solver.profile.n_wavelengths))
    assert np.all(solver.transmittance(GROUND, sun) == 0.0)


def test_an_observer_in_space_sees_no_sky_where_its_rays_miss_the_atmosphere(solver):
    # From 400 km: straight up and horizontally the rays miss the 60 km atmosphere (no
    # radiance, nothing lost); straight down they meet the planet (lit ground and air seen,
    # no light of a source passes).
    views = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    transmittance = solver.transmittance(ORBIT, views)
    np.testing.assert_array_equal(transmittance, [[1.0, 1.0], [1.0, 1.0], [0.0, 0.0]])
    if solver_domain(solver).ground_only:
        assert_refused(lambda: solver.sky_radiance(ORBIT, views, HIGH_SUN))
        return
    radiance = solver.sky_radiance(ORBIT, views, HIGH_SUN)
    assert_radiance(radiance, (3, solver.profile.n_wavelengths))
    assert np.all(radiance[:2] == 0.0) and np.all(radiance[2] > 0.0)


# The capabilities it claims --------------------------------------------------------------

def claimed(solver, protocol) -> None:
    if not isinstance(solver, protocol):
        pytest.skip(f"{solver.name} is not a {protocol.__name__}")


def test_ground_irradiance_is_the_attenuated_sun_plus_sky_light(solver, profile):
    # Direct = E_sun T_sun cos(sun zenith) for the point sun of this profile (the identity of
    # `SurfaceSolver.ground_irradiance`), T_sun from the same solver: agreement to rounding.
    claimed(solver, SurfaceSolver)
    sun = directions(40.0, 20.0)
    direct, diffuse = solver.ground_irradiance(GROUND, sun)
    assert direct.shape == diffuse.shape == (profile.n_wavelengths,)
    expected = profile.toa_irradiance * solver.transmittance(GROUND, sun) * math.cos(40 * DEG)
    np.testing.assert_allclose(direct, expected, rtol=1e-12)
    assert np.all(np.isfinite(diffuse)) and np.all(diffuse > 0.0)


@pytest.mark.parametrize("shape", [(5,), (2, 3)])
def test_aerial_perspective_transmittance_is_the_transmittance_to_the_point(solver, profile,
                                                                            shape):
    # Points 1-40 km away along a ray 80 deg from the zenith; T of the segment against
    # `transmittance` over the same distance. Tolerance 1e-3 relative: solvers may integrate
    # the segment with their own coarser quadrature (measured 6e-4 for "single" with 16
    # samples, 4e-14 for "lut").
    claimed(solver, SurfaceSolver)
    distance = np.geomspace(1e3, 40e3, math.prod(shape)).reshape(shape)
    view = np.broadcast_to(directions(80.0, 30.0), shape + (3,))
    points = GROUND + distance[..., None] * view
    inscattered, transmittance = solver.aerial_perspective(GROUND, points, HIGH_SUN)
    assert_radiance(inscattered, shape + (profile.n_wavelengths,))
    np.testing.assert_allclose(transmittance, solver.transmittance(GROUND, view, distance),
                               rtol=1e-3)


def test_surface_radiance_adds_the_reflected_light_to_the_aerial_perspective(solver, profile):
    # From 2 km, rays 95 deg from the zenith meet the ground. A black surface shows only the
    # air in between (`aerial_perspective`); a brighter one more, lit only where `lit`.
    claimed(solver, SurfaceRadianceSolver)
    position = GROUND + [0.0, 0.0, 2000.0]
    views = directions(95.0, np.linspace(0.0, 300.0, 4))
    distance = ground_distances(position, np.ascontiguousarray(views), EARTH_RADIUS_M)
    points = position + distance[:, None] * views
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    black = solver.surface_radiance(position, points, normals, np.zeros(2), HIGH_SUN)
    grey = solver.surface_radiance(position, points, normals, np.full(2, 0.3), HIGH_SUN)
    shaded = solver.surface_radiance(position, points, normals, np.full(2, 0.3), HIGH_SUN,
                                     lit=np.array([True, False, True, False]))
    for radiance in (black, grey, shaded):
        assert_radiance(radiance, (4, profile.n_wavelengths))
    assert np.all(grey > black) and np.all(shaded <= grey)
    np.testing.assert_array_equal(shaded[[0, 2]], grey[[0, 2]])
    assert np.all(shaded[[1, 3]] < grey[[1, 3]])
    if isinstance(solver, SurfaceSolver):
        # One pass over the points against the aerial perspective's own (measured equal for
        # "lut"); relative 1e-9 leaves room for another order of the same sums.
        np.testing.assert_allclose(black, solver.aerial_perspective(position, points,
                                                                    HIGH_SUN)[0], rtol=1e-9)


def test_noisy_radiance_is_the_mean_and_its_error_covers_another_seed(solver, profile):
    # The mean is `sky_radiance` itself; a second solver with another seed differs from it by
    # less than 5 combined standard errors (deterministic for the fixed seeds).
    claimed(solver, NoisySolver)
    views = directions([0.0, 30.0, 60.0, 75.0, 85.0], [0.0, 60.0, 120.0, 180.0, 240.0])
    mean, error = solver.sky_radiance_with_error(GROUND, views, HIGH_SUN)
    assert mean.shape == error.shape == (5, profile.n_wavelengths)
    np.testing.assert_array_equal(mean, solver.sky_radiance(GROUND, views, HIGH_SUN))
    assert np.all(error > 0.0) and np.all(np.isfinite(error))
    other = make_solver(solver.name, profile, dataclasses.replace(OPTIONS, seed=4))
    other_mean, other_error = other.sky_radiance_with_error(GROUND, views, HIGH_SUN)
    assert not np.array_equal(mean, other_mean)
    assert np.all(np.abs(mean - other_mean) <= 5.0 * np.hypot(error, other_error))


def test_tables_are_those_of_the_profile_and_options(solver, profile):
    claimed(solver, TableSolver)
    tables = solver.tables
    np.testing.assert_array_equal(tables.wavelengths_nm, profile.wavelengths_nm)
    assert tables.transmittance.shape[-1] == profile.n_wavelengths
    assert tables.orders == OPTIONS.orders


def test_the_module_docstring_lists_each_solvers_capabilities_truly(solver):
    # The table in `transport/solvers.py`'s docstring: a row per registered solver, a column
    # per protocol, "yes" exactly where the solver is an instance of the column's protocol.
    lines = solvers.__doc__.splitlines()
    header = next(line.split() for line in lines if line.split()[:1] == ["solver"])
    columns = header[1:]
    assert set(columns) == {p.__name__ for p in CAPABILITIES}
    rows = {line.split()[0]: line.split()[1:] for line in lines
            if line.split() and line.split()[0] in SOLVERS}
    assert sorted(rows) == sorted(SOLVERS)
    for protocol in CAPABILITIES:
        said = rows[solver.name][columns.index(protocol.__name__)]
        assert said == ("yes" if isinstance(solver, protocol) else "-"), protocol.__name__


# The registry ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["lutt", "", None, ["lut"]])
def test_an_unknown_solver_name_is_refused_with_the_registered_names(profile, name):
    with pytest.raises(InputError) as raised:
        make_solver(name, profile)
    assert raised.value.key == "solver"
    assert f"unknown solver {name!r}; available: {', '.join(SOLVERS)}" == str(raised.value)


def test_a_registered_factory_is_made_by_name_and_a_name_is_taken_once(monkeypatch, profile):
    monkeypatch.setattr(solvers, "SOLVERS", dict(SOLVERS))
    monkeypatch.setattr(solvers, "_FACTORIES", dict(solvers._FACTORIES))
    made = []

    @register_solver("toy", "a solver for this test")
    def _toy(toy_profile, options):
        made.append((toy_profile, options))
        return "toy solver"

    assert make_solver("toy", profile) == "toy solver"
    assert made == [(profile, SolverOptions())]
    assert solvers.SOLVERS["toy"] == "a solver for this test"
    with pytest.raises(ValueError, match="'toy' is registered already"):
        register_solver("toy", "again")(_toy)
