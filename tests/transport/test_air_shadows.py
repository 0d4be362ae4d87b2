"""The clouds' shadows in the air (`transport.air_shadows`): under a uniform deck against the
single-scattering solver's in-scattered light and the two-stream's diffuse flux evaluated
here, and the shadow map against the direct march of the water towards the sun."""


import numpy as np
import pytest
from test_clouds import RADIUS_M, WAVELENGTHS_NM, _direction, uniform_slab
from transport_cases import SMALL, exponential_earth

from skyscatter import api
from skyscatter.atmosphere.cloud_field import TOP_R, WATER, cloud_field
from skyscatter.transport._air_shadow_kernels import _sun_water
from skyscatter.transport.air_shadows import air_shadows
from skyscatter.transport.clouds import cloud_transmittance, clouds_in_front
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver

BASE_M = 1000.0  # uniform_slab's base


@pytest.fixture(scope="module")
def solver():
    return LutSolver(exponential_earth(), resolution=SMALL, orders=2)


def _expected_loss(solver, field, origin, ray, sun, stop):
    """The module docstring's dL below a uniform deck by 4000 steps: the in-scattered light of
    each step from `SingleScatteringSolver` (exact single scattering, its own march) times
    1 - T_c, minus the diffuse flux the deck passes, scattered with a phase of 1 / (4 pi)."""
    profile = solver.profile
    t = np.linspace(0.0, stop, 4001)
    points = origin + t[:, None] * ray
    inscattered, view_t = SingleScatteringSolver(profile, n_samples=512).aerial_perspective(
        origin, points, sun)
    steps = np.diff(inscattered, axis=0)
    middle = 0.5 * (points[1:] + points[:-1])
    r = np.linalg.norm(middle, axis=1)
    mu_s = middle @ sun / r
    water = field.params[0, WATER] * np.array([
        _chord(p, sun, RADIUS_M + BASE_M, field.params[0, TOP_R]) for p in middle])
    tau = water[:, None] * field.mass_extinction_m2_g[0]
    direct = np.exp(-tau)
    gamma = 0.75 * (1.0 - field.asymmetry[0])  # Eddington (transport._two_stream)
    mu = mu_s[:, None]
    slab = (1.0 + direct + 1.5 * mu * (1.0 - direct)) / (2.0 * (1.0 + gamma * tau * mu))
    scattering = sum(np.interp(r - profile.bottom_radius_m, profile.altitudes_m, d)[:, None] * s
                     for d, s, phase in zip(profile.density, profile.scattering_per_density,
                                            profile.phases, strict=True) if phase is not None)
    sun_air = solver.transmittance(middle, sun)
    view_mid = 0.5 * (view_t[1:] + view_t[:-1])
    glow = (profile.toa_irradiance * sun_air * view_mid * scattering * mu_s[:, None]
            * (slab - direct) / (2.0 * np.pi) * np.diff(t)[:, None])
    return (steps * (1.0 - direct) - glow).sum(axis=0)


def _chord(point, direction, base_r, top_r):
    """Length [m] of the ray from `point` (below base_r) along `direction` between the two
    spheres."""
    b, c = point @ direction, point @ point
    return (-b + np.sqrt(b * b - c + top_r**2)) - (-b + np.sqrt(b * b - c + base_r**2))


@pytest.mark.parametrize(("view_zenith", "sun_zenith"), [(0.0, 30.0), (50.0, 60.0),
                                                         (70.0, 20.0)])
def test_the_air_under_a_uniform_deck(solver, view_zenith, sun_zenith):
    """The loss up to the deck's base against `_expected_loss`: within 2 % (24 jittered
    samples against 4000 steps; the map's interpolation is exact for a uniform deck)."""
    field = uniform_slab(0.3)
    origin = np.array([0.0, 0.0, RADIUS_M + 1.0])
    ray = _direction(view_zenith, 0.0)
    sun = _direction(sun_zenith, 180.0)
    stop = _chord(origin, ray, RADIUS_M + 1.0, RADIUS_M + BASE_M)
    rays = np.tile(ray, (64, 1))  # 64 jitters: their mean is the integral
    shadows = air_shadows(solver, field, origin, rays, sun, stop=np.full(64, stop))
    loss = shadows.loss(solver, rays, np.full(64, stop)).mean(axis=0)
    expected = _expected_loss(solver, field, origin, ray, sun, stop)
    assert loss == pytest.approx(expected, rel=0.02)


def test_no_water_casts_no_shadow(solver):
    field = uniform_slab(1e-12)
    origin = np.array([0.0, 0.0, RADIUS_M + 1.0])
    rays = np.array([_direction(z, 40.0) for z in (0.0, 45.0, 85.0)])
    sun = _direction(40.0, 200.0)
    shadows = air_shadows(solver, field, origin, rays, sun, stop=np.full(3, np.inf))
    loss = shadows.loss(solver, rays, np.full(3, np.inf))
    clear = solver.sky_radiance(origin, rays, sun)
    assert np.all(np.abs(loss) < 1e-9 * clear)


def test_the_shadow_map_against_the_direct_march(solver):
    """Below a cumulus layer the map's transmittance towards the sun is the direct march's
    (`cloud_transmittance`): the map's lines are 30 m apart and bilinear, the cumulus edge
    ramps ~100 m, so the median difference is below 0.01 and the 95th percentile below 0.1."""
    clouds = api.load_clouds("cumulus")
    field = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM)
    origin = np.array([0.0, 0.0, RADIUS_M + 2.0])
    rng = np.random.default_rng(3)
    rays = rng.normal(size=(4000, 3))
    rays[:, 2] = np.abs(rays[:, 2]) + 0.3
    rays /= np.linalg.norm(rays, axis=1)[:, None]
    sun = _direction(35.0, 120.0)
    stop = np.full(rays.shape[0], 3000.0)
    shadows = air_shadows(solver, field, origin, rays, sun, stop=stop)
    distance = rng.uniform(0.0, 1.0, rays.shape[0]) * 3000.0
    points = origin + distance[:, None] * rays
    below = np.linalg.norm(points, axis=1) < field.lowest_radius_m
    points = points[below]
    paths = np.empty(field.n_layers)
    mapped = np.empty(points.shape[0])
    for i, p in enumerate(points):
        _sun_water(shadows.shadow_map, origin, p[0], p[1], p[2], np.linalg.norm(p), paths)
        mapped[i] = np.exp(-paths @ field.mass_extinction_m2_g[:, 1])
    marched = cloud_transmittance(field, points, sun)[:, 1]
    difference = np.abs(mapped - marched)
    assert np.mean(marched < 0.5) > 0.1  # the test sees shadows
    assert np.median(difference) < 0.01
    assert np.percentile(difference, 95) < 0.1


def test_a_thick_deck_dims_the_air_below_it(solver):
    """The whole composite (`clouds_in_front`) for a ray that stops before a thick deck's base
    (at a terrain distance): darker than the clear sky by the loss, never negative. (Under a
    thin deck, air seen at side angles can gain: the deck's diffuse light, scattered with
    1 / (4 pi), outweighs the sun's Rayleigh phase near 90 deg.)"""
    field = uniform_slab(3.0)  # optical depth ~80
    origin = np.array([0.0, 0.0, RADIUS_M + 1.0])
    rays = np.array([_direction(80.0, 0.0)])
    sun = _direction(30.0, 180.0)
    behind = solver.sky_radiance(origin, rays, sun)
    limit = np.array([5000.0])
    shaded = clouds_in_front(solver, field, origin, rays, sun, behind=behind,
                             max_distance=limit)
    loss = air_shadows(solver, field, origin, rays, sun, stop=limit).loss(solver, rays, limit)
    assert np.all(loss > 0.0)
    # rel 1e-6: the composite keeps the clouds' transmittance and added light in float32
    assert shaded == pytest.approx(np.maximum(behind - loss, 0.0), rel=1e-6)
