"""The sphere map and dual paraboloid map cameras against their published mappings, written
out here: OpenGL's SPHERE_MAP texture coordinates (OpenGL 1.1 specification, section 2.10.4)
and Heidrich & Seidel's (1998) paraboloid; their solid angles against the area element of the
mappings' inverses, found here by finite differences."""

from __future__ import annotations

import json

import numpy as np
import OpenEXR
import pytest

from skyscatter.render.environment_light import _ENU_TO_MAP, sh_basis, sh_irradiance
from skyscatter.render.paraboloid import ParaboloidCamera
from skyscatter.render.sphere_map import SphereMapCamera


def _sphere_map_st(r: np.ndarray) -> tuple[float, float]:
    """OpenGL 1.1, section 2.10.4: m = 2 sqrt(r_x^2 + r_y^2 + (r_z + 1)^2), s = r_x / m + 1/2,
    t = r_y / m + 1/2 (r in east, north, up)."""
    m = 2.0 * np.sqrt(r[0] ** 2 + r[1] ** 2 + (r[2] + 1.0) ** 2)
    return r[0] / m + 0.5, r[1] / m + 0.5


def _sphere_map_direction(px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """The inverse of _sphere_map_st in p = 2 (s, t) - 1: solve |r| = 1 for r_z, then r_x, r_y."""
    rho2 = px * px + py * py
    rz = 1.0 - 2.0 * rho2
    scale = np.sqrt(2.0 * (1.0 + rz))  # = m / 2
    return np.stack([px * scale, py * scale, rz], axis=-1)


def _paraboloid_direction(px: np.ndarray, py: np.ndarray, sign: float) -> np.ndarray:
    """Heidrich & Seidel (1998): the ray from the focus of z = 1/2 - (x^2 + y^2) / 2 through
    the paraboloid's point above p, d = (2 p, 1 - |p|^2) / (1 + |p|^2) (z negated below)."""
    rho2 = px * px + py * py
    return np.stack([2.0 * px, 2.0 * py, sign * (1.0 - rho2)], axis=-1) / (1.0 + rho2)[..., None]


def _solid_angle_by_jacobian(direction_of, x0: float, x1: float, y0: float, y1: float,
                             n: int) -> float:
    """The integral over the pixel's part of the unit disk of |dd/dp_x x dd/dp_y| (the area
    element of the unit sphere), by central differences and the midpoint rule on n x n points."""
    xs = x0 + (np.arange(n) + 0.5) / n * (x1 - x0)
    ys = y0 + (np.arange(n) + 0.5) / n * (y1 - y0)
    px, py = np.meshgrid(xs, ys)
    h = 1e-6
    with np.errstate(invalid="ignore"):  # beyond the rim, not used
        dx = (direction_of(px + h, py) - direction_of(px - h, py)) / (2 * h)
        dy = (direction_of(px, py + h) - direction_of(px, py - h)) / (2 * h)
    density = np.linalg.norm(np.cross(dx, dy), axis=-1)
    inside = px * px + py * py < (1.0 - 2 * h) ** 2  # differences reach h beyond the point
    return float(np.sum(np.where(inside, density, 0.0)) * (x1 - x0) * (y1 - y0) / n**2)


def _random_directions(count: int, seed: int) -> np.ndarray:
    d = np.random.default_rng(seed).normal(size=(count, 3))
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def test_the_sphere_map_puts_directions_where_opengl_does():
    camera = SphereMapCamera(64)
    for d in _random_directions(300, 1):
        s, t = _sphere_map_st(d)
        row, column = camera.direction_to_pixel(d)
        assert column == pytest.approx(s * 64, abs=1e-9)
        assert row == pytest.approx((1.0 - t) * 64, abs=1e-9)
    # the zenith at the centre, east to the right, north above, the horizon at 1 / sqrt(2)
    assert camera.direction_to_pixel([0.0, 0.0, 1.0]) == (32.0, 32.0)
    row, column = camera.direction_to_pixel([1.0, 0.0, 0.0])
    assert (row, column) == pytest.approx((32.0, 32.0 + 32.0 / np.sqrt(2.0)))
    row, column = camera.direction_to_pixel([0.0, 1.0, 0.0])
    assert (row, column) == pytest.approx((32.0 - 32.0 / np.sqrt(2.0), 32.0))


def test_the_paraboloid_map_puts_directions_where_heidrich_and_seidel_do():
    camera = ParaboloidCamera(64)
    for d in _random_directions(300, 2):
        p = d[:2] / (1.0 + abs(d[2]))  # eq. for the front (d_z >= 0) and back paraboloid
        row, column = camera.direction_to_pixel(d)
        assert row == pytest.approx((1.0 - p[1]) / 2.0 * 64, abs=1e-9)
        assert column == pytest.approx((p[0] + 1.0) / 2.0 * 64 + (64 if d[2] < 0 else 0),
                                       abs=1e-9)
    assert camera.direction_to_pixel([0.0, 0.0, 1.0]) == (32.0, 32.0)
    assert camera.direction_to_pixel([0.0, 0.0, -1.0]) == (32.0, 96.0)
    assert camera.direction_to_pixel([1.0, 0.0, 0.0]) == (32.0, 64.0)  # the rim, east


@pytest.mark.parametrize("camera", [SphereMapCamera(24), ParaboloidCamera(24)],
                         ids=["sphere", "paraboloid"])
def test_each_pixel_looks_where_its_centre_maps(camera):
    dirs, valid = camera.directions()
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-12)
    rows, columns = np.indices(valid.shape) + 0.5
    size = camera.height
    inside = np.hypot((columns % size) / size * 2 - 1, 1 - rows / size * 2) < 0.999
    row, column = camera.direction_to_pixel(dirs[inside])
    np.testing.assert_allclose(row, rows[inside], atol=1e-9)
    np.testing.assert_allclose(column, columns[inside], atol=1e-9)
    assert valid[inside].all() and not valid[0, 0]


def test_the_sphere_map_pixels_cover_the_sphere():
    # Closed form: 4 pi in all. Reference for single pixels: the area element of the inverse
    # of OpenGL's mapping, by central differences (1e-9) and the midpoint rule: 200 x 200
    # points inside a pixel (1e-9: the density is uniform), 1000 x 1000 on a pixel the rim cuts
    # (the rim through the midpoint grid: measured 4e-5; tolerance 5e-4).
    camera = SphereMapCamera(32)
    omega = camera.pixel_solid_angles()
    assert omega.sum() == pytest.approx(4.0 * np.pi, rel=1e-12)
    assert (omega[~camera.valid_mask()] == 0.0).all() and (omega[camera.valid_mask()] > 0).all()
    for (i, j), n, tolerance in [((10, 20), 200, 1e-7), ((0, 14), 1000, 5e-4),
                                 ((4, 4), 1000, 5e-4)]:
        x0, y1 = j / 16 - 1, 1 - i / 16
        expected = _solid_angle_by_jacobian(_sphere_map_direction, x0, x0 + 1 / 16, y1 - 1 / 16,
                                            y1, n)
        assert omega[i, j] == pytest.approx(expected, rel=tolerance)


def test_the_paraboloid_pixels_cover_each_hemisphere():
    # Closed form: 2 pi for each disk. Reference for single pixels as for the sphere map,
    # from the inverse of Heidrich & Seidel's mapping (inside: 1e-8 measured, 1e-5 allowed).
    camera = ParaboloidCamera(32)
    omega = camera.pixel_solid_angles()
    assert omega[:, :32].sum() == pytest.approx(2.0 * np.pi, rel=1e-12)
    assert omega[:, 32:].sum() == pytest.approx(2.0 * np.pi, rel=1e-12)
    for (i, j), n, tolerance in [((10, 20), 200, 1e-5), ((0, 14), 1000, 5e-4),
                                 ((4, 4), 1000, 5e-4)]:
        x0, y1 = j / 16 - 1, 1 - i / 16
        for sign, column in [(1.0, j), (-1.0, j + 32)]:
            expected = _solid_angle_by_jacobian(
                lambda px, py, s=sign: _paraboloid_direction(px, py, s), x0, x0 + 1 / 16,
                y1 - 1 / 16, y1, n)
            assert omega[i, column] == pytest.approx(expected, rel=tolerance)


@pytest.mark.parametrize("camera", [SphereMapCamera(64), ParaboloidCamera(64)],
                         ids=["sphere", "paraboloid"])
def test_a_linear_sky_on_the_map_has_the_closed_form_irradiance(camera):
    # Reference: radiance a + b w_up gives the irradiance pi a + (2 pi / 3) b n_up on a
    # surface facing n (Ramamoorthi & Hanrahan 2001, eq. 8; as for the cube map in
    # test_environment_light.py), here through the maps' directions and exact solid angles;
    # the pixels' centre directions stand for their pixels (midpoint rule, 64 pixels across,
    # where the maps are far from uniform: measured 1.3e-4 on the paraboloid, 4.1e-4 on the
    # sphere map, whose rim pixels all look at the nadir; tolerance 1e-3).
    dirs, valid = camera.directions()
    a, b = 2.0, 1.5
    radiance = np.where(valid, a + b * dirs[..., 2], 0.0)[..., None]
    coefficients = sh_irradiance(radiance, dirs, camera.pixel_solid_angles())
    for normal in _random_directions(12, 3):
        irradiance = sh_basis(_ENU_TO_MAP @ normal) @ coefficients
        expected = np.pi * a + 2.0 * np.pi / 3.0 * b * normal[2]
        assert irradiance[0] == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("name", ["sphere", "paraboloid"])
def test_the_command_line_renders_the_maps_with_their_light(tmp_path, name):
    # The map read back with OpenEXR has the camera's shape, black outside the disks and
    # finite inside; the light file's sun is the one the cube map's gives (the same solver
    # output, independent of the camera: 6 significant digits).
    from skyscatter.cli import main
    common = ["render", "earth", "--size", "16", "--solver", "single", "--wavelengths", "3",
              "--sun-elevation", "30"]
    assert main([*common, "--camera", name, "-o", str(tmp_path / "sky.png"), "--exr",
                 str(tmp_path / "sky.exr"), "--light", str(tmp_path / "light.json")]) == 0
    assert main([*common, "--camera", "cubemap", "-o", str(tmp_path / "cube.png"), "--light",
                 str(tmp_path / "cube.json")]) == 0
    channels = OpenEXR.File(str(tmp_path / "sky.exr"), separate_channels=True).channels()
    green = channels["G"].pixels
    camera = SphereMapCamera(16) if name == "sphere" else ParaboloidCamera(16)
    assert green.shape == (camera.height, camera.width)
    assert np.isfinite(green).all() and (green[~camera.valid_mask()] == 0.0).all()
    assert (green[camera.valid_mask()] > 0.0).all()
    light, cube = (json.loads((tmp_path / f).read_text()) for f in ("light.json", "cube.json"))
    assert light["sun"] == cube["sun"]
