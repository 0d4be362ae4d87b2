"""Environment maps on a disk: the sphere map of OpenGL and the dual paraboloid map.

Both put directions on the unit disk, p = (p_x, p_y), |p| <= 1, of a `size` x `size` square
(p_x = 2 s - 1 across, p_y = 2 t - 1 up the image), with (x, y, z) = (east, north, up):

- Sphere map, OpenGL's SPHERE_MAP texture coordinates (The OpenGL Graphics System: A
  Specification, version 1.1, section 2.10.4, "Generating Texture Coordinates"): for the unit
  direction r, m = 2 sqrt(r_x^2 + r_y^2 + (r_z + 1)^2), s = r_x / m + 1/2, t = r_y / m + 1/2,
  so p = (r_x, r_y) / sqrt(2 (1 + r_z)): the sphere as a mirror ball shows it, photographed
  from straight above. The zenith is at the centre, the horizon on the circle |p| = 1/sqrt(2),
  the nadir all round the rim. The inverse: r_z = 1 - 2 |p|^2, (r_x, r_y) = 2 p sqrt(1 - |p|^2).
  Its area element is uniform: dOmega = 4 dA_p.
- Paraboloid map (Heidrich & Seidel 1998, "View-independent environment maps", Proc.
  Eurographics/SIGGRAPH Workshop on Graphics Hardware, 39-45, doi:10.1145/285305.285310):
  the paraboloid f(x, y) = 1/2 - (x^2 + y^2) / 2 around the focus at the origin reflects the
  direction d into the z axis at p = (d_x, d_y) / (1 + d_z) for the upper hemisphere (d_z >= 0)
  and p = (d_x, d_y) / (1 - d_z) for the lower one (d_z <= 0, the "back" paraboloid). The
  zenith (nadir) is at the centre, the horizon on the rim, p = tan(theta / 2) in the zenith
  (nadir) angle theta. The inverse: d = (2 p_x, 2 p_y, +-(1 - |p|^2)) / (1 + |p|^2). Its area
  element: dOmega = 4 dA_p / (1 + |p|^2)^2. Here both disks are seen from above, east to the
  right and north up: the lower one as through the ground, so the two rims meet point for point
  as mirror images.

A pixel's solid angle is exact: the density 4 / (1 + |p|^2)^2 (or 4) is the exterior
derivative of g(|p|) (x dy - y dx) with g = 2 / (1 + |p|^2) (or 2), so by Green's theorem the
solid angle of the part of a pixel inside the disk is that form's integral round its outline:
along a straight edge x = c from y = 0 to y = u it is c int_0^u g dy
(2 c / sqrt(1 + c^2) atan(u / sqrt(1 + c^2)), or 2 c u), along the rim g(1) times the angle.
Pixels that reach into the disk are valid; one whose centre lies outside looks along the rim
direction of its centre's azimuth and holds the solid angle of its part inside.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["disk_coordinates", "disk_pixel_solid_angles", "disk_points", "disk_valid_mask"]

EdgeIntegral = Callable[[np.ndarray, np.ndarray], np.ndarray]


def disk_coordinates(size: int, offset_x: float = 0.5,
                     offset_y: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """p_x (1, size) across and p_y (size, 1) up of the points a fraction (offset_x, offset_y)
    into the pixels of a `size` square spanning [-1, 1]^2."""
    cells = np.arange(size)
    px = ((cells + offset_x) / size * 2.0 - 1.0)[None, :]
    py = (1.0 - (cells + offset_y) / size * 2.0)[:, None]
    return px, py


def disk_points(size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """p_x, p_y and |p|, each (size, size), of the pixel centres, those outside the unit disk
    moved in to its rim along their azimuth (the rim direction they look along)."""
    px, py = np.broadcast_arrays(*disk_coordinates(size))
    rho = np.hypot(px, py)
    shrink = 1.0 / np.maximum(rho, 1.0)
    return px * shrink, py * shrink, rho * shrink


def disk_valid_mask(size: int) -> np.ndarray:
    """Pixels (size, size) of which some part lies inside the unit disk."""
    low, high = disk_coordinates(size, 0.0, 1.0), disk_coordinates(size, 1.0, 0.0)
    nearest_x = np.maximum(0.0, np.maximum(low[0], -high[0]))
    nearest_y = np.maximum(0.0, np.maximum(low[1], -high[1]))
    return np.hypot(nearest_x, nearest_y) < 1.0


def _quadrant(x: np.ndarray, y: np.ndarray, edge: EdgeIntegral, rim: float) -> np.ndarray:
    """Solid angle of the disk's part of the rectangle between the origin and (x, y), signed
    by the quadrant (module docstring: along x = |x| up to the rim or |y|, along y = |y| up to
    the rim or |x|, and round the rim between)."""
    ax, ay = np.minimum(np.abs(x), 1.0), np.minimum(np.abs(y), 1.0)
    rim_y, rim_x = np.sqrt(1.0 - ax * ax), np.sqrt(1.0 - ay * ay)
    arc = np.maximum(0.0, np.arctan2(ay, rim_x) - np.arctan2(rim_y, ax))
    inside = edge(ax, np.minimum(ay, rim_y)) + edge(ay, np.minimum(ax, rim_x)) + rim * arc
    return np.sign(x) * np.sign(y) * inside


def disk_pixel_solid_angles(size: int, edge: EdgeIntegral, rim: float) -> np.ndarray:
    """Solid angle (size, size) [sr] of each pixel's part inside the unit disk, for a density
    whose edge integral is `edge(c, u)` and whose g at the rim is `rim` (module docstring)."""
    x0, y1 = disk_coordinates(size, 0.0, 0.0)
    x1, y0 = disk_coordinates(size, 1.0, 1.0)
    omega = (_quadrant(x1, y1, edge, rim) - _quadrant(x0, y1, edge, rim)
             - _quadrant(x1, y0, edge, rim) + _quadrant(x0, y0, edge, rim))
    # outside the disk the four terms cancel to rounding (1e-16)
    return np.where(disk_valid_mask(size), np.maximum(omega, 0.0), 0.0)
