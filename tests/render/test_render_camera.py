"""Cameras against closed forms: projection laws, solid-angle identities, orientation."""

import math

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.render.camera import EquirectangularCamera, FisheyeCamera, PerspectiveCamera

DEG = math.pi / 180.0
EAST, NORTH, UP = np.eye(3)


def _all_cameras():
    return [FisheyeCamera(64), FisheyeCamera(63, field_of_view_deg=220.0),
            EquirectangularCamera(64, 32, heading_deg=30.0),
            PerspectiveCamera(48, 32, 60.0, heading_deg=30.0, pitch_deg=50.0, roll_deg=10.0)]


@pytest.mark.parametrize("camera", _all_cameras(), ids=type)
def test_directions_are_unit_vectors_of_image_shape(camera):
    dirs, valid = camera.directions()
    assert dirs.shape == (camera.height, camera.width, 3) and dirs.dtype == np.float64
    assert valid.shape == (camera.height, camera.width) and valid.dtype == bool
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-14)


@pytest.mark.parametrize("camera", _all_cameras(), ids=type)
def test_direction_to_pixel_inverts_directions_at_pixel_centres(camera):
    dirs, valid = camera.directions()
    row, col = camera.direction_to_pixel(dirs)
    i, j = np.indices(valid.shape)
    np.testing.assert_allclose(row[valid], i[valid] + 0.5, atol=1e-9)
    np.testing.assert_allclose(col[valid], j[valid] + 0.5, atol=1e-9)


@pytest.mark.parametrize("camera", _all_cameras(), ids=type)
@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_direction_to_pixel_broadcasts(camera, shape):
    dirs = np.broadcast_to(np.array([0.3, 0.5, 0.8]), shape + (3,))  # in view of all four
    row, col = camera.direction_to_pixel(dirs)
    assert row.shape == shape and col.shape == shape
    assert np.all(np.isfinite(row)) and np.all(np.isfinite(col))


# --- fisheye --------------------------------------------------------------------------------

def test_fisheye_centre_pixel_looks_at_the_zenith():
    dirs, valid = FisheyeCamera(101).directions()  # odd size: pixel (50, 50) is the centre
    np.testing.assert_allclose(dirs[50, 50], UP, atol=1e-15)
    assert valid[50, 50]


def test_fisheye_zenith_angle_grows_linearly_with_radius_equidistant():
    # Equidistant law θ = (ρ / R) · fov / 2, ρ measured from the pixel index alone.
    for size, fov in ((101, 180.0), (64, 150.0), (40, 360.0)):
        camera = FisheyeCamera(size, field_of_view_deg=fov)
        dirs, valid = camera.directions()
        i, j = np.indices((size, size))
        rho = np.hypot(j + 0.5 - size / 2, i + 0.5 - size / 2) / (size / 2)
        theta = np.arccos(np.clip(dirs[..., 2], -1, 1))
        inside = rho <= 1
        np.testing.assert_allclose(theta[inside], rho[inside] * fov / 2 * DEG, atol=1e-7)
        np.testing.assert_array_equal(valid, inside)


def test_fisheye_circle_edge_is_the_horizon():
    camera = FisheyeCamera(200)
    azimuth = np.linspace(0, 2 * np.pi, 37)
    horizon = np.stack([np.sin(azimuth), np.cos(azimuth), np.zeros_like(azimuth)], axis=-1)
    row, col = camera.direction_to_pixel(horizon)
    np.testing.assert_allclose(np.hypot(row - 100, col - 100), 100.0, atol=1e-9)


def test_fisheye_has_north_up_and_east_left_as_seen_from_below():
    camera = FisheyeCamera(100)
    row, col = camera.direction_to_pixel(np.array([NORTH, EAST, -NORTH, -EAST]))
    np.testing.assert_allclose(row, [0, 50, 100, 50], atol=1e-9)  # north top, south bottom
    np.testing.assert_allclose(col, [50, 0, 50, 100], atol=1e-9)  # east left, west right
    dirs, _ = camera.directions()
    assert dirs[50, 0, 0] > 0.99  # left edge, middle row: looks east
    assert dirs[0, 50, 1] > 0.99  # top edge, middle column: looks north


def test_fisheye_solid_angles_of_valid_pixels_sum_to_a_hemisphere():
    # Midpoint rule on pixels; the error comes from pixels that straddle the circle edge.
    # Tolerance: a tenth of the solid angle of a one-pixel-wide ring at the horizon,
    # 2π · (π/2)/R sr = 6e-4 of 2π at R = 256 (measured: 2e-5).
    camera = FisheyeCamera(512)
    omega = camera.pixel_solid_angles()
    ring = 2 * np.pi * (np.pi / 2) / 256
    assert omega.sum() == pytest.approx(2 * np.pi, abs=0.1 * ring)
    assert np.all(omega[~camera.directions()[1]] == 0)


def test_fisheye_360_degree_solid_angles_sum_to_the_sphere():
    # θ_max = π: sin θ vanishes on the circle, so edge pixels hardly matter (measured 3e-7).
    omega = FisheyeCamera(400, field_of_view_deg=360.0).pixel_solid_angles()
    assert omega.sum() == pytest.approx(4 * np.pi, rel=1e-5)


# --- equirectangular --------------------------------------------------------------------------

def test_equirectangular_rows_map_to_elevations_from_plus_to_minus_90():
    camera = EquirectangularCamera(36, 18)
    dirs, valid = camera.directions()
    elevation = np.arcsin(dirs[..., 2]) / DEG
    expected = 90.0 - 180.0 * (np.arange(18) + 0.5) / 18
    np.testing.assert_allclose(elevation, np.broadcast_to(expected[:, None], (18, 36)), atol=1e-12)
    assert valid.all()


def test_equirectangular_centre_column_looks_at_heading_and_azimuth_grows_eastwards():
    camera = EquirectangularCamera(8, 4, heading_deg=0.0)
    row, col = camera.direction_to_pixel(np.array([NORTH, EAST, -NORTH, -EAST]))
    np.testing.assert_allclose(col, [4, 6, 0, 2], atol=1e-9)  # N centre, E right, W left
    np.testing.assert_allclose(row, 2.0, atol=1e-12)  # horizon is the middle row
    south_heading = EquirectangularCamera(8, 4, heading_deg=180.0)
    np.testing.assert_allclose(south_heading.direction_to_pixel(-NORTH)[1], 4.0, atol=1e-9)


def test_equirectangular_solid_angles_sum_to_the_sphere():
    # Exact per band of rows, so only rounding remains.
    omega = EquirectangularCamera(90, 45).pixel_solid_angles()
    assert omega.shape == (45, 90)
    assert omega.sum() == pytest.approx(4 * np.pi, rel=1e-12)


# --- perspective ------------------------------------------------------------------------------

def test_perspective_centre_ray_is_the_forward_vector():
    forward = np.array([1.0, -2.0, 0.5])
    camera = PerspectiveCamera.from_forward_up(101, 61, 45.0, forward, UP)
    dirs, _ = camera.directions()
    np.testing.assert_allclose(dirs[30, 50], forward / np.linalg.norm(forward), atol=1e-14)


def test_perspective_heading_pitch_give_the_documented_forward():
    camera = PerspectiveCamera(11, 11, 30.0, heading_deg=90.0, pitch_deg=30.0)
    right, up, forward = camera.basis()
    np.testing.assert_allclose(forward, [math.cos(30 * DEG), 0, math.sin(30 * DEG)], atol=1e-15)
    np.testing.assert_allclose(right, -NORTH, atol=1e-15)  # facing east, south is on the right
    np.testing.assert_allclose(np.cross(forward, up), right, atol=1e-15)


def test_perspective_corner_rays_make_the_closed_form_angle():
    # Corner pixel centre sits at x = (1 - 1/w) tan(hfov/2), y = (1 - 1/h) tan(vfov/2) on the
    # plane at unit distance, so the angle to the axis is atan(hypot(x, y)).
    w, h, vfov = 64, 48, 70.0
    camera = PerspectiveCamera(w, h, vfov, heading_deg=33.0, pitch_deg=-12.0, roll_deg=5.0)
    dirs, _ = camera.directions()
    forward = camera.basis()[2]
    tan_v = math.tan(vfov / 2 * DEG)
    x, y = (1 - 1 / w) * tan_v * w / h, (1 - 1 / h) * tan_v
    expected = math.atan(math.hypot(x, y))
    for corner in (dirs[0, 0], dirs[0, -1], dirs[-1, 0], dirs[-1, -1]):
        assert math.acos(np.clip(corner @ forward, -1, 1)) == pytest.approx(expected, abs=1e-12)


def test_perspective_image_right_is_east_when_facing_north_and_roll_turns_clockwise():
    dirs, _ = PerspectiveCamera(21, 21, 90.0).directions()
    assert dirs[10, -1, 0] > 0.5 and dirs[0, 10, 2] > 0.5  # right edge east, top edge up
    rolled = PerspectiveCamera(21, 21, 90.0, roll_deg=90.0)
    right, up, _ = rolled.basis()
    np.testing.assert_allclose(up, EAST, atol=1e-15)  # image top now points east
    np.testing.assert_allclose(right, -UP, atol=1e-15)  # right side down


def test_perspective_from_forward_up_matches_heading_pitch_roll():
    reference = PerspectiveCamera(30, 20, 50.0, heading_deg=250.0, pitch_deg=40.0, roll_deg=-25.0)
    right, up, forward = reference.basis()
    rebuilt = PerspectiveCamera.from_forward_up(30, 20, 50.0, 3 * forward, up + 0.7 * forward)
    np.testing.assert_allclose(np.array(rebuilt.basis()), np.array([right, up, forward]),
                               atol=1e-14)


def test_perspective_looking_straight_up_keeps_the_given_up_vector():
    camera = PerspectiveCamera.from_forward_up(9, 9, 60.0, UP, NORTH)
    right, up, forward = camera.basis()
    np.testing.assert_allclose(forward, UP, atol=1e-15)
    np.testing.assert_allclose(up, NORTH, atol=1e-15)
    np.testing.assert_allclose(right, -EAST, atol=1e-15)  # seen from below: east on the left,
    # as in the fisheye image


def test_perspective_cube_face_solid_angle_is_4pi_over_6():
    # A 90° x 90° square frustum is one face of a cube around the eye: Ω = 4π/6.
    # Midpoint rule, O(1/n²): relative error 4e-6 measured at 256², tolerance 1e-4.
    omega = PerspectiveCamera(256, 256, 90.0, pitch_deg=-20.0).pixel_solid_angles()
    assert omega.sum() == pytest.approx(4 * np.pi / 6, rel=1e-4)


def test_perspective_direction_behind_camera_is_nan():
    row, col = PerspectiveCamera(10, 10, 60.0).direction_to_pixel(-NORTH)
    assert np.isnan(row) and np.isnan(col)


# --- bad input --------------------------------------------------------------------------------

@pytest.mark.parametrize("make, match", [
    (lambda: FisheyeCamera(0), "size = 0 is not allowed: a whole number from 1 to"),
    (lambda: FisheyeCamera(64, field_of_view_deg=400.0),
     "field_of_view_deg = 400.0 .*> 0 and <= 360"),
    (lambda: EquirectangularCamera(64, -2), "height = -2"),
    (lambda: PerspectiveCamera(10, 10, 180.0), "vertical_fov_deg = 180.0 .*> 0 and < 180"),
    (lambda: PerspectiveCamera(10, 10, 60.0, pitch_deg=95.0),
     "pitch_deg = 95.0 .*>= -90 and <= 90"),
    (lambda: PerspectiveCamera.from_forward_up(10, 10, 60.0, UP, 2 * UP), "parallel to forward"),
    (lambda: PerspectiveCamera.from_forward_up(10, 10, 60.0, [0, 0, 0], UP), "non-zero 3-vectors"),
])
def test_bad_camera_parameters_raise_input_error(make, match):
    with pytest.raises(InputError, match=match):
        make()


@pytest.mark.parametrize("camera", _all_cameras(), ids=type)
def test_valid_mask_is_the_mask_of_directions(camera):
    _, valid = camera.directions()
    np.testing.assert_array_equal(camera.valid_mask(), valid)
