"""The octahedral map camera against the mapping's closed forms (Engelhardt & Dachsbacher
2008; Cigolle et al. 2014, listing 1, written out here)."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.render.octahedral import OctahedralCamera


def _encode(d: np.ndarray) -> np.ndarray:
    """Cigolle et al. (2014), listing 1: a unit vector -> [-1, 1]^2."""
    p = d[:2] / np.abs(d).sum()
    if d[2] < 0.0:
        p = (1.0 - np.abs(p[::-1])) * np.where(p >= 0.0, 1.0, -1.0)
    return p


def test_directions_land_where_the_published_mapping_puts_them():
    camera = OctahedralCamera(32)
    rng = np.random.default_rng(5)
    for d in rng.normal(size=(300, 3)):
        d /= np.linalg.norm(d)
        px, py = _encode(d)
        row, column = camera.direction_to_pixel(d)
        assert column == pytest.approx((px + 1.0) / 2.0 * 32, abs=1e-9)
        assert row == pytest.approx((1.0 - py) / 2.0 * 32, abs=1e-9)
    # zenith at the centre, east at the right edge, north at the top, nadir in the corners
    assert camera.direction_to_pixel(np.array([0.0, 0.0, 1.0])) == (16.0, 16.0)
    assert camera.direction_to_pixel(np.array([1.0, 0.0, 0.0])) == (16.0, 32.0)
    assert camera.direction_to_pixel(np.array([0.0, 1.0, 0.0])) == (0.0, 16.0)
    assert camera.direction_to_pixel(np.array([1e-9, 1e-9, -1.0])) == pytest.approx((0.0, 32.0),
                                                                                    abs=1e-6)


def test_each_pixel_looks_where_its_centre_maps():
    camera = OctahedralCamera(16)
    dirs, valid = camera.directions()
    row, column = camera.direction_to_pixel(dirs)
    rows, columns = np.indices((16, 16))
    np.testing.assert_allclose(row, rows + 0.5, atol=1e-9)
    np.testing.assert_allclose(column, columns + 0.5, atol=1e-9)
    assert valid.all()


def test_the_pixels_cover_the_sphere():
    # Closed form: the solid angles sum to 4 pi; a pixel next to the zenith covers the patch
    # q = (p_x, p_y, 1 - p_x - p_y) of the octahedron's face x + y + z = 1, whose solid angle
    # seen from the centre is the integral of dA (q . N) / |q|^3 with N = (1, 1, 1), q . N = 1:
    # by the midpoint rule on 200 x 200 points.
    camera = OctahedralCamera(64)
    omega = camera.pixel_solid_angles()
    assert omega.sum() == pytest.approx(4.0 * np.pi, rel=1e-6)
    sub = (np.arange(200) + 0.5) / 200 * (2.0 / 64)
    px, py = np.meshgrid(sub, sub)  # the pixel just north-east of the zenith
    q = np.stack([px, py, 1.0 - px - py], axis=-1)
    integral = np.sum((2.0 / 64 / 200) ** 2 / np.linalg.norm(q, axis=-1) ** 3)
    assert omega[31, 32] == pytest.approx(integral, rel=1e-4)
