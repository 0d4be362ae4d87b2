"""Cloud layers from a 3-D water grid (`atmosphere.cloud_grids`, `type = "grid"` in a clouds
file): read as documented, placed on the observer, interpolated within the trilinear error
bound of a smooth field, periodic or not, moved by the wind, and bad files refused with the
file, the array and how to fix it."""

import numpy as np
import pytest

from skyscatter.atmosphere.cloud_config import load_clouds
from skyscatter.atmosphere.cloud_field import _observer_axes, cloud_field, layer_water
from skyscatter.atmosphere.cloud_grids import MAX_GRID_CELLS
from skyscatter.errors import ConfigError

RADIUS_M = 6_371_000.0
BASE_M = 1000.0
WAVELENGTHS_NM = np.array([550.0])
LAYER = """
[[layer]]
name = "les"
type = "grid"
grid = "{grid}"
base_altitude_m = {base}
{extra}
[layer.particles]
phase = "liquid"
effective_radius_um = 10.0
"""


def _clouds_file(tmp_path, water, spacing=(100.0, 200.0, 50.0), periodic=None, extra="",
                 name="grid.npz"):
    arrays = {"water_g_m3": water, "spacing_m": np.asarray(spacing)}
    if periodic is not None:
        arrays["periodic"] = np.bool_(periodic)
    np.savez(tmp_path / name, **arrays)
    path = tmp_path / "clouds.toml"
    path.write_text(LAYER.format(grid=name, base=BASE_M, extra=extra))
    return path


def _world(frame, east, north, height):
    """World points at (east, north) [m] on the observer's tangent plane, `height` [m] above
    the ground (the box follows the curvature: the height is |p| - R), for the east-north-up
    axes `frame` (columns)."""
    east, north, height = np.broadcast_arrays(east, north, height)
    r = RADIUS_M + height
    up = np.sqrt(r * r - east * east - north * north)
    return (frame[:, 0] * east[..., None] + frame[:, 1] * north[..., None]
            + frame[:, 2] * up[..., None]), r


def _water(field, points, r):
    return np.array([layer_water(field.params, field.profiles, field.textures, 0, *p, q)
                     for p, q in zip(points.reshape(-1, 3), r.ravel(), strict=True)])


def test_a_grid_file_gives_its_values_at_the_cell_centres(tmp_path):
    water = np.random.default_rng(3).random((8, 6, 5))
    clouds = load_clouds(_clouds_file(tmp_path, water, periodic=False))
    layer = clouds.layers[0]
    assert layer.kind == "grid" and layer.top_altitude_m == BASE_M + 5 * 50.0
    assert layer.water_content_g_m3 == water.max()  # the Monte Carlo's majorant
    # an observer at 40 N 20 E whose world frame is rotated: the grid follows east and north
    frame = _observer_axes(40.0, 20.0)
    field = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM, to_world=frame, latitude_deg=40.0,
                        longitude_deg=20.0)
    i, j, k = np.meshgrid(np.arange(8), np.arange(6), np.arange(5), indexing="ij")
    points, r = _world(frame, (i + 0.5 - 4) * 100.0, (j + 0.5 - 3) * 200.0,
                       BASE_M + (k + 0.5) * 50.0)
    np.testing.assert_allclose(_water(field, points, r), water.ravel(), atol=1e-9)  # p to ~1e-9 m
    # no water below the base, above the top, on the far side of the planet
    below, rb = _world(frame, 0.0, 0.0, BASE_M - 1.0)
    above, ra = _world(frame, 0.0, 0.0, BASE_M + 251.0)
    centre, rc = _world(frame, 0.0, 0.0, BASE_M + 100.0)
    assert _water(field, below, rb)[0] == 0.0 and _water(field, above, ra)[0] == 0.0
    assert _water(field, centre, rc)[0] > 0.0 and _water(field, -centre, rc)[0] == 0.0


def test_a_sampled_smooth_field_is_reproduced_within_the_trilinear_bound(tmp_path):
    # Reference: an analytic field f, periodic over the box, sampled at the cell centres.
    # Trilinear interpolation errs by at most (dx^2 max|f_xx| + dy^2 max|f_yy|
    # + dz^2 max|f_zz|) / 8 (the tensor product of linear interpolation's h^2 |f''| / 8);
    # here 0.0146 g m^-3 of a field that varies by 0.8 (measured: at most 0.0135, mean 0.0026).
    n, spacing = (24, 16, 12), (125.0, 250.0, 40.0)
    lx, ly, h = n[0] * spacing[0], n[1] * spacing[1], n[2] * spacing[2]

    def f(x, y, z):
        return 0.5 + 0.4 * np.sin(2 * np.pi * x / lx) * np.cos(2 * np.pi * y / ly) * np.sin(
            np.pi * z / h)

    centres = [(np.arange(m) + 0.5) * d for m, d in zip(n, spacing, strict=True)]
    x, y, z = np.meshgrid(*centres, indexing="ij")
    clouds = load_clouds(_clouds_file(tmp_path, f(x, y, z), spacing))
    field = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM)
    rng = np.random.default_rng(7)
    # inside the box, away from the half cells at the top and bottom (held constant there)
    px = rng.uniform(0.0, lx, 2000)
    py = rng.uniform(0.0, ly, 2000)
    pz = rng.uniform(0.5 * spacing[2], h - 0.5 * spacing[2], 2000)
    points, r = _world(np.eye(3), px - lx / 2, py - ly / 2, BASE_M + pz)
    bound = 0.4 / 8 * ((2 * np.pi / lx * spacing[0]) ** 2 + (2 * np.pi / ly * spacing[1]) ** 2
                       + (np.pi / h * spacing[2]) ** 2)
    error = np.abs(_water(field, points, r) - f(px, py, pz))
    assert error.max() <= bound
    assert error.max() > 0.3 * bound  # the bound is not vacuous: the grid is coarse enough


@pytest.mark.parametrize("periodic", [None, True, False])
def test_a_point_one_period_away_has_the_same_water_or_none(tmp_path, periodic):
    water = np.random.default_rng(5).random((6, 4, 3)) + 0.1
    clouds = load_clouds(_clouds_file(tmp_path, water, periodic=periodic))
    field = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM)
    rng = np.random.default_rng(11)
    east, north = rng.uniform(-300.0, 300.0, 50), rng.uniform(-400.0, 400.0, 50)
    height = BASE_M + rng.uniform(0.0, 150.0, 50)
    inside = _water(field, *_world(np.eye(3), east, north, height))
    assert np.all(inside > 0.0)
    for shift in ((600.0, 0.0), (0.0, -800.0), (-1200.0, 1600.0)):
        away = _water(field, *_world(np.eye(3), east + shift[0], north + shift[1], height))
        if periodic is False:
            assert np.all(away == 0.0)
        else:  # default: periodic (tangent-plane metres equal to 1e-9 this close)
            np.testing.assert_allclose(away, inside, rtol=1e-9)


def test_the_wind_moves_the_grid(tmp_path):
    water = np.random.default_rng(2).random((10, 10, 4))
    path = _clouds_file(tmp_path, water, periodic=False)
    path.write_text(path.read_text() + "[layer.wind]\neast_m_s = 10.0\nnorth_m_s = -5.0\n")
    clouds = load_clouds(path)
    still = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM)
    later = cloud_field(clouds, RADIUS_M, WAVELENGTHS_NM, time_s=30.0)
    rng = np.random.default_rng(4)
    east, north = rng.uniform(-400.0, 400.0, 30), rng.uniform(-900.0, 900.0, 30)
    height = BASE_M + rng.uniform(0.0, 200.0, 30)
    before = _water(still, *_world(np.eye(3), east, north, height))
    after = _water(later, *_world(np.eye(3), east + 300.0, north - 150.0, height))
    np.testing.assert_allclose(after, before, rtol=1e-6, atol=1e-12)


def test_the_top_may_be_left_out_or_must_match_the_grid(tmp_path):
    water = np.ones((2, 2, 4))
    good = load_clouds(_clouds_file(tmp_path, water, extra="top_altitude_m = 1200.0"))
    assert good.layers[0].top_altitude_m == 1200.0
    with pytest.raises(ConfigError, match="base_altitude_m \\+ nz dz = 1200") as error:
        load_clouds(_clouds_file(tmp_path, water, extra="top_altitude_m = 1500.0"))
    assert "top_altitude_m" in str(error.value)


@pytest.mark.parametrize("extra", ["coverage = 0.5", "water_content_g_m3 = 0.3",
                                   "profile = [[0.0, 1.0], [1.0, 1.0]]",
                                   'coverage_map = "map.png"', "[layer.shape]\nseed = 2"])
def test_the_noise_keys_are_refused_in_a_grid_layer(tmp_path, extra):
    path = _clouds_file(tmp_path, np.ones((2, 2, 2)))
    text = path.read_text().replace("[layer.particles]", extra + "\n[layer.particles]")
    path.write_text(text)
    key = extra.split()[0].strip("[]").removeprefix("layer.")
    with pytest.raises(ConfigError, match='type = "grid"') as error:
        load_clouds(path)
    assert key in str(error.value) and str(path) in str(error.value)


def _save(path, **arrays):
    np.savez_compressed(path, **arrays)


@pytest.mark.parametrize("arrays, message", [
    (None, "no such file"),
    ("npy", "not an .npz archive"),
    ("text", "cannot read it"),
    ({"spacing_m": np.ones(3)}, "no array 'water_g_m3' \\(it has: spacing_m\\)"),
    ({"water_g_m3": np.ones((2, 2, 2))}, "no array 'spacing_m'"),
    ({"water_g_m3": np.ones((4, 4)), "spacing_m": np.ones(3)},
     "shape \\(4, 4\\).*\\(nx, ny, nz\\)"),
    ({"water_g_m3": np.ones((2, 2, 2)), "spacing_m": np.ones(2)}, "spacing_m = \\[1.0, 1.0\\]"),
    ({"water_g_m3": np.ones((2, 2, 2)), "spacing_m": [10.0, 0.0, 10.0]}, "\\(0, 10000\\] m"),
    ({"water_g_m3": np.ones((2, 2, 2)), "spacing_m": [10.0, -5.0, 10.0]}, "spacing_m"),
    ({"water_g_m3": np.full((2, 2, 2), np.nan), "spacing_m": np.ones(3)}, "not finite"),
    ({"water_g_m3": np.full((2, 2, 2), np.inf), "spacing_m": np.ones(3)}, "not finite"),
    ({"water_g_m3": -np.ones((2, 2, 2)), "spacing_m": np.ones(3)}, "np.clip"),
    ({"water_g_m3": np.full((2, 2, 2), 300.0), "spacing_m": np.ones(3)}, "kg m\\^-3 times 1000"),
    ({"water_g_m3": np.array([[["a"]]]), "spacing_m": np.ones(3)}, "not real numbers"),
    ({"water_g_m3": np.ones((2, 2, 2)), "spacing_m": np.ones(3), "periodic": np.array([1, 0])},
     "periodic = \\[1, 0\\]"),
    ("huge", f"more than {MAX_GRID_CELLS}.*coarsen"),
])
def test_bad_grid_files_are_refused_with_the_file_the_array_and_a_fix(tmp_path, arrays, message):
    grid = tmp_path / "grid.npz"
    if arrays == "npy":
        grid = tmp_path / "grid.npy"
        np.save(grid, np.ones((2, 2, 2)))
    elif arrays == "text":
        grid.write_text("not an archive")
    elif arrays == "huge":  # one cell more than the limit, as zeros: cheap to write
        _save(grid, water_g_m3=np.zeros((MAX_GRID_CELLS // 64 + 1, 8, 8), dtype=np.float32),
              spacing_m=np.ones(3))
    elif arrays is not None:
        _save(grid, **arrays)
    path = tmp_path / "clouds.toml"
    path.write_text(LAYER.format(grid=grid.name, base=BASE_M, extra=""))
    with pytest.raises(ConfigError, match=message) as error:
        load_clouds(path)
    text = str(error.value)
    assert str(path) in text and str(grid) in text and "grid" in text
    assert "relative to the clouds file" in text


def test_a_grid_layer_needs_its_file(tmp_path):
    path = tmp_path / "clouds.toml"
    path.write_text('[[layer]]\ntype = "grid"\nbase_altitude_m = 1000.0\n')
    with pytest.raises(ConfigError, match="grid is missing"):
        load_clouds(path)
