"""A dual paraboloid map camera: the upper hemisphere on the left `size` square, the lower on
the right, each on the disk of Heidrich & Seidel's paraboloid (render.disk_maps: the
formula, the orientation, the solid angles)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.render.camera import _SquareMap, _unit
from skyscatter.render.disk_maps import disk_pixel_solid_angles, disk_points, disk_valid_mask

__all__ = ["ParaboloidCamera"]


def _paraboloid_edge(c: np.ndarray, u: np.ndarray) -> np.ndarray:
    """c int_0^u g dy for g = 2 / (1 + x^2 + y^2) (dOmega = 4 dA_p / (1 + |p|^2)^2)."""
    root = np.sqrt(1.0 + c * c)
    return 2.0 * c / root * np.arctan(u / root)


@dataclass(frozen=True)
class ParaboloidCamera(_SquareMap):
    """The whole sphere on two `size` x `size` paraboloid maps side by side, upper hemisphere
    left, lower right (render.disk_maps)."""

    @property
    def width(self) -> int:
        return 2 * self.size

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and the pixels that reach into a disk."""
        px, py, rho = disk_points(self.size)
        rho2 = rho ** 2
        upper = np.stack([2.0 * px, 2.0 * py, 1.0 - rho2], axis=-1) / (1.0 + rho2)[..., None]
        lower = upper * np.array([1.0, 1.0, -1.0])
        return np.concatenate([upper, lower], axis=1), self.valid_mask()

    def valid_mask(self) -> np.ndarray:
        return np.tile(disk_valid_mask(self.size), (1, 2))

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of ENU directions (..., 3): p = (d_x, d_y) / (1 + |d_z|)
        in the left square for d_z >= 0, the right one below; zero vectors give NaN."""
        d = _unit(dirs)
        lower = d[..., 2] < 0.0
        denominator = 1.0 + np.abs(d[..., 2])
        px, py = d[..., 0] / denominator, d[..., 1] / denominator
        return (1.0 - py) / 2.0 * self.size, (px + 1.0) / 2.0 * self.size + lower * self.size

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle (h, w) [sr] of each pixel's part of its disk, exact; each disk's sum
        is 2 pi."""
        return np.tile(disk_pixel_solid_angles(self.size, _paraboloid_edge, 1.0), (1, 2))
