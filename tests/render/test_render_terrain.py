"""Heightfield terrain: hits and normals against closed forms, shadows, loaders, demo terrain."""

import math

import numpy as np
import pytest
from PIL import Image

from skyscatter.errors import InputError
from skyscatter.render.camera import EquirectangularCamera
from skyscatter.render.image_io import write_exr
from skyscatter.render.terrain import (
    HORIZON_MIN_RAYS,
    REFINE_HEIGHT_TOLERANCE_M,
    Heightfield,
    demo_mountains,
)

R = 6_371_000.0
DEG = math.pi / 180.0


def frame_at(latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """East, north, up (columns) at a point of the sphere, independent of the module."""
    lat, lon = np.radians(latitude_deg), np.radians(longitude_deg)
    up = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    return np.column_stack([east, np.cross(up, east), up])


FRAMES = {"north_pole": np.eye(3), "lat40_lon30": frame_at(40.0, 30.0)}


def grid_coordinates(n: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Map coordinates (x east, y north) [m] of the samples; row 0 is the north edge."""
    offsets = (np.arange(n) - (n - 1) / 2.0) * spacing
    return offsets[None, :], -offsets[:, None]


def local_directions(elevation_deg, azimuth_deg) -> np.ndarray:
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    return np.stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)], axis=-1)


def sphere_distance(origin: np.ndarray, directions: np.ndarray, radius: float) -> np.ndarray:
    """Closed form: nearer root of |o + t d|^2 = radius^2 for unit d."""
    od = directions @ origin
    return -od - np.sqrt(od**2 - (origin @ origin - radius**2))


def surface_normal(frame: np.ndarray, height, x: float, y: float, step: float = 1.0):
    """Normal of the parametric surface P(x, y) = (R + h(x, y)) u(x, y), u the inverse
    azimuthal-equidistant map around the anchor, by central differences of P."""
    east, north, up = frame.T

    def position(xx, yy):
        rho = math.hypot(xx, yy)
        u = math.cos(rho / R) * up + math.sin(rho / R) * (xx * east + yy * north) / rho
        return (R + height(xx, yy)) * u

    px = position(x + step, y) - position(x - step, y)
    py = position(x, y + step) - position(x, y - step)
    n = np.cross(px, py)
    return n / np.linalg.norm(n)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0))


# --- constant height: a sphere of radius R + h0 ---------------------------------------------


@pytest.mark.parametrize("frame_name", FRAMES)
def test_constant_height_hits_the_sphere_of_that_radius(frame_name):
    frame = FRAMES[frame_name]
    h0 = 500.0
    terrain = Heightfield(np.full((64, 64), h0), 1000.0, R, frame)
    origin, view = terrain.viewpoint_at(0.0, 0.0, 1500.0)  # 2000 m above the sphere
    el, az = np.meshgrid([-5.0, -12.0, -30.0, -60.0, -89.0], np.arange(0.0, 360.0, 30.0))
    directions = local_directions(el, az).reshape(-1, 3) @ view.T
    distance, points, normals, hit = terrain.intersect(origin, directions)
    assert hit.all()
    # Hits are refined until the clearance is below REFINE_HEIGHT_TOLERANCE_M (1 mm); along
    # a ray 5 deg from grazing that is 1.2 cm, and twice that bounds the error.
    along = 2.0 * REFINE_HEIGHT_TOLERANCE_M / math.sin(5.0 * DEG)
    np.testing.assert_allclose(distance, sphere_distance(origin, directions, R + h0), atol=along)
    np.testing.assert_allclose(np.linalg.norm(points, axis=1), R + h0,
                               atol=REFINE_HEIGHT_TOLERANCE_M)
    radial = points / np.linalg.norm(points, axis=1, keepdims=True)
    # Central differences of a constant are exactly zero: the normal is the radial direction.
    np.testing.assert_allclose(normals, radial, atol=1e-12)


# --- a ramp: slope against the parametric surface --------------------------------------------


@pytest.mark.parametrize("frame_name", FRAMES)
@pytest.mark.parametrize("slope", [(0.2, 0.0), (0.0, 0.2), (0.1, -0.15)])
def test_ramp_normals_match_the_parametric_surface(frame_name, slope):
    frame = FRAMES[frame_name]
    s_east, s_north = slope
    spacing = 100.0
    x, y = grid_coordinates(101, spacing)
    terrain = Heightfield(1000.0 + s_east * x + s_north * y, spacing, R, frame)
    origin, view = terrain.viewpoint_at(0.0, 0.0, 4000.0)
    el, az = np.meshgrid([-50.0, -70.0, -89.0], np.arange(0.0, 360.0, 45.0))
    directions = local_directions(el, az).reshape(-1, 3) @ view.T
    _, points, normals, hit = terrain.intersect(origin, directions)
    assert hit.all()
    east, north, up = frame.T
    for p, n in zip(points, normals, strict=True):
        u = p / np.linalg.norm(p)
        theta = math.acos(min(1.0, u @ up))
        bearing = u - (u @ up) * up
        bearing /= np.linalg.norm(bearing)
        px, py = R * theta * (bearing @ east), R * theta * (bearing @ north)
        expected = surface_normal(frame, lambda xx, yy: 1000.0 + s_east * xx + s_north * yy,
                                  px, py)
        # The module neglects the map's tangential stretch theta / sin(theta) - 1 < 1e-7 here
        # (hits within 4 km); the finite differences of P add < 1e-7 rad.
        assert angle_between(n, expected) < 1e-6
    # Against the plane's normal in the anchor frame: off by the curvature between anchor and
    # hit (theta < 7e-4 rad within 4.5 km) and the R / (R + h) scaling of slopes (< 1e-4 rad).
    plane = (up - s_east * east - s_north * north) / math.sqrt(1.0 + s_east**2 + s_north**2)
    assert angle_between(normals, plane).max() < 1e-3


def test_height_at_reads_row_zero_as_the_north_edge():
    spacing = 1000.0
    heights = np.arange(5 * 7, dtype=float).reshape(5, 7) * 10.0
    terrain = Heightfield(heights, spacing, R)
    for i, j in [(0, 0), (0, 6), (4, 0), (2, 3), (1, 5)]:
        east_m, north_m = (j - 3) * spacing, (2 - i) * spacing
        position, _ = terrain.viewpoint_at(east_m, north_m, 0.0)
        assert terrain.height_at(position)[0] == pytest.approx(heights[i, j], abs=1e-6)
        assert np.linalg.norm(position) - R == pytest.approx(heights[i, j], abs=1e-6)


# --- a block north of the observer ----------------------------------------------------------


@pytest.fixture(scope="module")
def block():
    """Flat ground with a 2000 m block: x in [-1000, 1000] m, y in [3000, 4000] m, on a
    201 x 201 grid 100 m apart; its south face spans the cell y in [2900, 3000] m."""
    x, y = grid_coordinates(201, 100.0)
    heights = np.where((np.abs(x) <= 1000.0) & (y >= 3000.0) & (y <= 4000.0), 2000.0, 0.0)
    return Heightfield(heights, 100.0, R)


def test_rays_at_the_block_hit_its_south_face(block):
    origin = np.array([0.0, 0.0, R + 2.0])
    directions = local_directions([0.0, 10.0, 20.0, 30.0], 0.0)
    distance, points, normals, hit = block.intersect(origin, directions)
    assert hit.all()
    north_m = points[:, 1]  # at the pole the anchor frame is the world frame
    assert np.all((north_m > 2900.0) & (north_m < 3000.1))
    # The face cell's slope is 2000 m per 100 m; central differences one cell apart read
    # 10 (half the cliff): the normal faces south, tilted up by atan(1/10).
    expected = np.array([0.0, -10.0, 1.0]) / math.sqrt(101.0)
    assert angle_between(normals, expected).max() < 0.02


def test_rays_above_the_block_or_upwards_miss(block):
    origin = np.array([0.0, 0.0, R + 2.0])
    # The block's nearest top edge is at atan(2000 / 3000) = 33.7 deg elevation.
    directions = np.concatenate([local_directions([40.0, 60.0, 90.0], 0.0),
                                 local_directions([0.0, 5.0, 45.0], 90.0)])
    distance, points, normals, hit = block.intersect(origin, directions)
    assert not hit.any()
    assert np.all(np.isinf(distance))
    assert np.all(np.isnan(points)) and np.all(np.isnan(normals))


def test_downward_rays_beside_the_block_hit_the_ground_sphere(block):
    origin = np.array([0.0, 0.0, R + 2.0])
    directions = local_directions(np.array([-0.5, -1.0, -10.0, -0.5]),
                                  np.array([90.0, 270.0, 180.0, 180.0]))
    distance, _, normals, hit = block.intersect(origin, directions)
    assert hit.all()
    # Flat ground at height 0 inside the grid and the bare sphere beyond it (-0.5 deg lands
    # 229 m away, inside; rays below the horizon but beyond 10 km would land outside).
    np.testing.assert_allclose(distance, sphere_distance(origin, directions, R), atol=0.05)
    np.testing.assert_allclose(normals[:, 2], 1.0, atol=1e-6)


def test_rays_far_beyond_the_grid_hit_the_bare_sphere(block):
    origin = np.array([0.0, 0.0, R + 3000.0])
    # The horizon dips 1.76 deg from 3000 m: these land 60-90 km away, far beyond the grid.
    directions = local_directions([-2.0, -2.6], [90.0, 200.0])
    distance, _, normals, hit = block.intersect(origin, directions)
    assert hit.all()
    np.testing.assert_allclose(distance, sphere_distance(origin, directions, R), atol=1e-3)


def test_max_distance_turns_far_hits_into_misses(block):
    origin = np.array([0.0, 0.0, R + 2.0])
    distance, _, _, hit = block.intersect(origin, local_directions([0.0, -1.0], [0.0, 90.0]),
                                          max_distance_m=1000.0)
    assert not hit[0] and hit[1]  # the block is 2.9 km away; the ground 115 m


def test_a_ray_starting_underground_hits_at_once(block):
    origin = np.array([0.0, 3500.0, R + 100.0])  # inside the block
    distance, _, _, hit = block.intersect(origin, local_directions([0.0], [180.0]))
    assert hit[0] and distance[0] == 0.0


# --- shadows ---------------------------------------------------------------------------------


@pytest.mark.parametrize(("elevation_deg", "azimuth_deg", "expected"), [
    (5.0, 0.0, True),     # low in the north, behind the 2000 m block 2.9 km away (33.7 deg)
    (30.0, 10.0, True),
    (60.0, 0.0, False),   # high above it
    (5.0, 180.0, False),  # low in the south, open
    (-2.0, 180.0, True),  # below the horizon: the planet itself
])
def test_shadowed_by_the_block_or_the_planet(block, elevation_deg, azimuth_deg, expected):
    origin = np.array([0.0, 0.0, R + 10.0])
    _, points, _, hit = block.intersect(origin, local_directions([-89.0, -45.0], 0.0))
    assert hit.all()
    sun = local_directions(elevation_deg, azimuth_deg)
    assert block.shadowed(points, sun).tolist() == [expected, expected]


def test_shadowed_marks_nan_points_unshadowed(block):
    points = np.array([[np.nan, np.nan, np.nan], [0.0, 0.0, R]])
    assert block.shadowed(points, local_directions(5.0, 0.0)).tolist() == [False, True]


# --- against a slow numpy march ---------------------------------------------------------------


def numpy_clearance(terrain: Heightfield, points: np.ndarray) -> np.ndarray:
    """Altitude above the terrain [m] of points (..., 3): the module docstring's map, written
    out with numpy (arctan2, bilinear weights, zero beyond the grid)."""
    east, north, up = terrain.frame.T
    r = np.linalg.norm(points, axis=-1)
    u = points / r[..., None]
    e, n, c = u @ east, u @ north, u @ up
    s = np.hypot(e, n)
    scale = terrain.planet_radius_m * np.arctan2(s, c) / np.where(s > 0.0, s, 1.0)
    ny, nx = terrain.heights_m.shape
    col = scale * e / terrain.spacing_m + (nx - 1) / 2.0
    row = (ny - 1) / 2.0 - scale * n / terrain.spacing_m
    framed = np.pad(terrain.heights_m, 1)  # zero samples around the grid
    col, row = np.clip(col + 1.0, 0.0, nx + 1.0), np.clip(row + 1.0, 0.0, ny + 1.0)
    j, i = np.minimum(col.astype(int), nx), np.minimum(row.astype(int), ny)
    fx, fy = col - j, row - i
    h = ((framed[i, j] * (1 - fx) + framed[i, j + 1] * fx) * (1 - fy)
         + (framed[i + 1, j] * (1 - fx) + framed[i + 1, j + 1] * fx) * fy)
    return r - terrain.planet_radius_m - h


def numpy_first_hit(terrain, origin, direction, step_m, far_m):
    """First sign change of the clearance sampled every step_m, bisected to 0.1 mm."""
    t = np.arange(0.0, far_m, step_m)
    f = numpy_clearance(terrain, origin + t[:, None] * direction)
    below = np.flatnonzero(f <= 0.0)
    if len(below) == 0:
        return math.inf
    lo, hi = t[below[0] - 1], t[below[0]]
    while hi - lo > 1e-4:
        mid = 0.5 * (lo + hi)
        if numpy_clearance(terrain, origin + mid * direction) > 0.0:
            lo = mid
        else:
            hi = mid
    return hi


def test_hits_agree_with_a_slow_numpy_march():
    terrain = demo_mountains(size=64, spacing_m=800.0, peak_m=3000.0, seed=5,
                             frame=frame_at(-20.0, 100.0))
    rng = np.random.default_rng(11)
    disagree = 0
    for _ in range(60):
        origin, view = terrain.viewpoint_at(*rng.uniform(-20e3, 20e3, 2),
                                            rng.choice([2.0, 300.0, 2500.0]))
        local = local_directions(rng.uniform(-30.0, 12.0), rng.uniform(0.0, 360.0))
        direction = view @ local
        # 1/40 of a cell per step, as far as the bare sphere beyond the grid (< 200 km).
        expected = numpy_first_hit(terrain, origin, direction, 20.0, 250e3)
        distance, points, _, hit = terrain.intersect(origin, direction[None])
        if math.isinf(expected):
            disagree += int(hit[0])
            continue
        assert hit[0]
        # Both refine to ~1 mm of clearance; the numpy march may step over a graze that the
        # kernel finds, and then the kernel's hit is nearer.
        assert distance[0] <= expected + 0.005
        disagree += int(distance[0] < expected - 0.005)
    assert disagree <= 1


def test_every_hit_lies_on_the_numpy_surface():
    terrain = demo_mountains(size=64, spacing_m=800.0, peak_m=3000.0, seed=5)
    origin, view = terrain.viewpoint_at(1000.0, -3000.0, 50.0)
    directions = EquirectangularCamera(64, 32).directions()[0].reshape(-1, 3) @ view.T
    distance, points, _, hit = terrain.intersect(origin, directions)
    assert 0.3 < hit.mean() < 0.7
    # Hits end within REFINE_HEIGHT_TOLERANCE_M of the surface, or within the 1 cm bracket
    # of the refinement times the ray's slope to it.
    assert np.abs(numpy_clearance(terrain, points[hit])).max() < 0.01


# --- culling with a horizon from one origin ---------------------------------------------------


def test_horizon_culling_changes_no_result():
    terrain = demo_mountains(size=96, spacing_m=1200.0, seed=3)
    camera = EquirectangularCamera(128, 64)
    assert camera.width * camera.height >= HORIZON_MIN_RAYS
    for east_m, north_m, above_m in [(0.0, 0.0, 2.0), (3000.0, -20000.0, 800.0)]:
        origin, view = terrain.viewpoint_at(east_m, north_m, above_m)
        directions = camera.directions()[0].reshape(-1, 3) @ view.T
        culled = terrain.intersect(origin, directions)  # one origin: culls
        plain = terrain.intersect(np.repeat(origin[None], len(directions), 0), directions)
        np.testing.assert_array_equal(culled[3], plain[3])
        np.testing.assert_array_equal(culled[0], plain[0])


# --- shapes and bad arguments ----------------------------------------------------------------


def test_intersect_shapes_and_origin_forms(block):
    origin = np.array([0.0, 0.0, R + 2.0])
    directions = local_directions([-10.0, 10.0, -20.0, 45.0, -5.0], 0.0)
    for origins in (origin, origin[None], np.repeat(origin[None], 5, 0)):
        distance, points, normals, hit = block.intersect(origins, directions)
        assert distance.shape == (5,) and hit.shape == (5,) and hit.dtype == bool
        assert points.shape == (5, 3) and normals.shape == (5, 3)
    distance, *_ = block.intersect(origin, 7.0 * directions[:1])  # any length
    assert distance[0] == pytest.approx(2.0 / math.sin(10 * DEG), rel=1e-3)
    assert block.intersect(origin, np.zeros((0, 3)))[0].shape == (0,)


@pytest.mark.parametrize(("origins", "directions", "message"), [
    (np.zeros((2, 3)), np.ones((3, 3)), "origins must be one point or one per direction"),
    (np.zeros(3), np.ones((3, 2)), "directions must have shape"),
    (np.zeros(3), np.array([[0.0, 0.0, np.nan]]), "directions must be finite"),
    (np.array([0.0, 0.0, R]), np.zeros((1, 3)), "must not contain zero vectors"),
])
def test_intersect_rejects_bad_rays(block, origins, directions, message):
    with pytest.raises(InputError, match=message):
        block.intersect(origins, directions)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"heights_m": np.zeros(5)}, "2-D grid of at least 2 x 2"),
    ({"heights_m": np.array([[0.0, np.inf], [0.0, 0.0]])}, "must be finite"),
    ({"spacing_m": 0.0}, "spacing_m = 0.0 must be a finite number > 0"),
    ({"planet_radius_m": -1.0}, "planet_radius_m"),
    ({"frame": np.diag([1.0, 1.0, -1.0])}, "frame must be a rotation"),
    ({"frame": np.ones((2, 2))}, "frame must be a finite 3x3 matrix"),
])
def test_heightfield_rejects_bad_arguments(kwargs, message):
    arguments = {"heights_m": np.zeros((3, 3)), "spacing_m": 10.0, "planet_radius_m": R}
    with pytest.raises(InputError, match=message):
        Heightfield(**{**arguments, **kwargs})


# --- loaders ---------------------------------------------------------------------------------


def test_sixteen_bit_png_round_trip(tmp_path):
    codes = np.random.default_rng(1).integers(0, 65536, size=(9, 13), dtype=np.uint16)
    Image.fromarray(codes).save(tmp_path / "dem.png")
    terrain = Heightfield.from_image(tmp_path / "dem.png", 30.0, 3000.0, R)
    np.testing.assert_allclose(terrain.heights_m, codes / 65535.0 * 3000.0, rtol=1e-15)
    assert terrain.spacing_m == 30.0 and terrain.heights_m.shape == (9, 13)


def test_eight_bit_png_full_white_is_the_vertical_scale(tmp_path):
    codes = np.array([[0, 128], [255, 17]], dtype=np.uint8)
    Image.fromarray(codes).save(tmp_path / "dem8.png")
    terrain = Heightfield.from_image(tmp_path / "dem8.png", 30.0, 1000.0, R)
    np.testing.assert_allclose(terrain.heights_m, codes / 255.0 * 1000.0, rtol=1e-15)


def test_exr_and_npy_round_trip(tmp_path):
    heights = np.random.default_rng(2).uniform(-50.0, 4000.0, size=(6, 8)).astype(np.float32)
    write_exr(tmp_path / "dem.exr", heights[..., None], channel_names=("Y",))
    np.save(tmp_path / "dem.npy", heights.astype(np.float64))
    for name in ("dem.exr", "dem.npy"):
        terrain = Heightfield.from_image(tmp_path / name, 25.0, 1.0, R)
        np.testing.assert_array_equal(terrain.heights_m, heights.astype(np.float64))


def write_bad(tmp_path, name):
    path = tmp_path / name
    if name == "rgb.png":
        Image.fromarray(np.zeros((4, 4, 3), dtype=np.uint8)).save(path)
    elif name == "text.png":
        path.write_text("not an image")
    elif name == "rgb.exr":
        write_exr(path, np.zeros((4, 4, 3)))
    elif name == "cube.npy":
        np.save(path, np.zeros((2, 3, 4)))
    elif name == "nan.npy":
        np.save(path, np.array([[0.0, np.nan], [1.0, 2.0]]))
    elif name == "line.npy":
        np.save(path, np.zeros((1, 5)))
    elif name == "broken.npy":
        path.write_bytes(b"\x93NUMPY garbage")
    return path


@pytest.mark.parametrize(("name", "message"), [
    ("missing.png", "no such file"),
    ("rgb.png", "must be 8- or 16-bit grayscale"),
    ("text.png", "not a PNG, EXR or .npy height map"),
    ("rgb.exr", "needs one channel"),
    ("cube.npy", "2-D grid"),
    ("nan.npy", "must be finite"),
    ("line.npy", "at least 2 x 2"),
    ("broken.npy", "not a readable .npy array"),
])
def test_bad_height_files_name_the_file(tmp_path, name, message):
    path = write_bad(tmp_path, name)
    with pytest.raises(InputError, match=message) as info:
        Heightfield.from_image(path, 30.0, 1000.0, R)
    assert str(path) in str(info.value)


# --- demo terrain ----------------------------------------------------------------------------


def test_demo_mountains_is_deterministic_with_a_flat_valley_at_the_anchor():
    a = demo_mountains(size=128, spacing_m=1000.0, peak_m=3000.0, seed=7)
    b = demo_mountains(size=128, spacing_m=1000.0, peak_m=3000.0, seed=7)
    c = demo_mountains(size=128, spacing_m=1000.0, peak_m=3000.0, seed=8)
    np.testing.assert_array_equal(a.heights_m, b.heights_m)
    assert not np.array_equal(a.heights_m, c.heights_m)
    assert a.heights_m.max() == pytest.approx(3000.0)
    x, y = grid_coordinates(128, 1000.0)
    assert np.all(a.heights_m[np.hypot(x, y) < 7000.0] == 0.0)  # the valley floor
    south, north = a.heights_m[y[:, 0] < -30e3], a.heights_m[y[:, 0] > 30e3]
    assert south.max() > 2.0 * north.max()  # the main range lies towards the south


def test_demo_mountains_rejects_bad_sizes():
    with pytest.raises(InputError, match="size = 4 must be an integer >= 16"):
        demo_mountains(size=4)
    with pytest.raises(InputError, match="peak_m"):
        demo_mountains(size=32, peak_m=-1.0)
