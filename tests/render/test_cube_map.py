"""The cube map camera against OpenGL's cube map selection rule and closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.errors import InputError
from skyscatter.render.cube_map import CUBE_LAYOUTS, CubeMapCamera

# Reference: The OpenGL Graphics System 4.6 (Core Profile), section 8.13, Table 8.19 -
# the major axis and the face coordinates (sc, tc) of a direction (rx, ry, rz), written out
# here from the specification, not from the module. s = (sc / |ma| + 1) / 2 across a face,
# t = (tc / |ma| + 1) / 2 down it.
GL_TABLE = {
    "+X": lambda x, y, z: (-z, -y, x),
    "-X": lambda x, y, z: (z, -y, -x),
    "+Y": lambda x, y, z: (x, z, y),
    "-Y": lambda x, y, z: (x, -z, -y),
    "+Z": lambda x, y, z: (x, -y, z),
    "-Z": lambda x, y, z: (-x, -y, -z),
}


def _gl_face(x: float, y: float, z: float) -> str:
    """The face OpenGL picks: the largest magnitude component and its sign."""
    axis = int(np.argmax(np.abs([x, y, z])))
    return ("+" if (x, y, z)[axis] >= 0 else "-") + "XYZ"[axis]


def _enu(x: float, y: float, z: float) -> np.ndarray:
    """The map's axes (x east, y up, z south) in east-north-up."""
    return np.array([x, -z, y])


@pytest.mark.parametrize("layout", tuple(CUBE_LAYOUTS))
def test_every_direction_lands_where_opengl_samples_it(layout):
    camera = CubeMapCamera(16, layout)
    squares = CUBE_LAYOUTS[layout][2]
    rng = np.random.default_rng(7)
    for x, y, z in rng.normal(size=(200, 3)):
        face = _gl_face(x, y, z)
        sc, tc, ma = GL_TABLE[face](x, y, z)
        s, t = (sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0
        row, column = camera.direction_to_pixel(_enu(x, y, z))
        face_row, face_column = squares[face]
        assert row == pytest.approx((face_row + t) * 16, abs=1e-9)
        assert column == pytest.approx((face_column + s) * 16, abs=1e-9)


@pytest.mark.parametrize("layout", tuple(CUBE_LAYOUTS))
def test_each_pixel_looks_where_its_centre_maps(layout):
    # directions() and direction_to_pixel are inverses: every face pixel's direction maps back
    # to its centre (i + 0.5, j + 0.5).
    camera = CubeMapCamera(8, layout)
    dirs, valid = camera.directions()
    row, column = camera.direction_to_pixel(dirs[valid])
    rows, columns = np.nonzero(valid)
    np.testing.assert_allclose(row, rows + 0.5, atol=1e-9)
    np.testing.assert_allclose(column, columns + 0.5, atol=1e-9)
    assert valid.sum() == 6 * 8 * 8
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=-1), 1.0, atol=1e-12)


@pytest.mark.parametrize("layout", tuple(CUBE_LAYOUTS))
def test_the_pixels_cover_the_sphere_once(layout):
    # Closed form: the faces' solid angles sum to 4 pi; a texel's equals the integral of the
    # pinhole's dA / (1 + x^2 + y^2)^(3/2) over it, here by the midpoint rule on 200 x 200
    # points (error ~1e-6 relative), for a texel at the centre and one in a corner.
    n = 32
    camera = CubeMapCamera(n, layout)
    omega = camera.pixel_solid_angles()
    assert omega.sum() == pytest.approx(4.0 * np.pi, rel=1e-12)
    assert np.all(omega[~camera.valid_mask()] == 0.0)
    face_row, face_column = CUBE_LAYOUTS[layout][2]["+Z"]
    for i, j in ((16, 16), (0, n - 1)):
        x0, y0 = 2.0 * j / n - 1.0, 2.0 * i / n - 1.0
        sub = (np.arange(200) + 0.5) / 200 * (2.0 / n)
        x, y = np.meshgrid(x0 + sub, y0 + sub)
        integral = np.sum((2.0 / n / 200) ** 2 / (1.0 + x * x + y * y) ** 1.5)
        assert omega[face_row * n + i, face_column * n + j] == pytest.approx(integral, rel=1e-5)


def test_the_cross_is_continuous_across_its_folds():
    # Where two faces meet in the cross (+Y over +Z, -X beside +Z, ...) the pixels on either
    # side of the shared edge look at directions one pixel apart (< 2 pixel angles).
    n = 32
    camera = CubeMapCamera(n, "cross")
    dirs, _ = camera.directions()
    pixel = 2.0 / n  # a texel's angle at the face centre [rad]
    pairs = [((n - 1, slice(n, 2 * n)), (n, slice(n, 2 * n))),       # +Y | +Z
             ((2 * n - 1, slice(n, 2 * n)), (2 * n, slice(n, 2 * n))),  # +Z | -Y
             ((slice(n, 2 * n), n - 1), (slice(n, 2 * n), n)),       # -X | +Z
             ((slice(n, 2 * n), 2 * n - 1), (slice(n, 2 * n), 2 * n)),  # +Z | +X
             ((slice(n, 2 * n), 3 * n - 1), (slice(n, 2 * n), 3 * n))]  # +X | -Z
    for a, b in pairs:
        angle = np.arccos(np.clip(np.sum(dirs[a] * dirs[b], axis=-1), -1.0, 1.0))
        assert np.all(angle < 2.0 * pixel)


def test_a_bad_layout_is_refused_with_the_choices():
    with pytest.raises(InputError, match="cross, strip"):
        CubeMapCamera(8, "sphere")
