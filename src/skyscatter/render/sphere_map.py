"""A sphere map camera: the whole sky as OpenGL's SPHERE_MAP texture holds it, a mirror ball
seen from straight above (render.disk_maps: the formula, the orientation, the solid angles)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.render.camera import _SquareMap, _unit
from skyscatter.render.disk_maps import disk_pixel_solid_angles, disk_points, disk_valid_mask

__all__ = ["SphereMapCamera"]


def _uniform_edge(c: np.ndarray, u: np.ndarray) -> np.ndarray:
    """c int_0^u g dy for g = 2 (dOmega = 4 dA_p)."""
    return 2.0 * c * u


@dataclass(frozen=True)
class SphereMapCamera(_SquareMap):
    """The whole sphere on a `size` x `size` sphere map (render.disk_maps)."""

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and the pixels that reach into the disk."""
        px, py, rho = disk_points(self.size)
        across = 2.0 * np.sqrt(1.0 - rho * rho)
        return (np.stack([px * across, py * across, 1.0 - 2.0 * rho * rho], axis=-1),
                self.valid_mask())

    def valid_mask(self) -> np.ndarray:
        return disk_valid_mask(self.size)

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of ENU directions (..., 3): s and t of OpenGL's formula
        (render.disk_maps), t up the image; the nadir gives NaN, zero vectors NaN."""
        r = _unit(dirs)
        with np.errstate(invalid="ignore", divide="ignore"):
            m = 2.0 * np.sqrt(r[..., 0] ** 2 + r[..., 1] ** 2 + (r[..., 2] + 1.0) ** 2)
            m = np.where(m > 0.0, m, np.nan)
            s, t = r[..., 0] / m + 0.5, r[..., 1] / m + 0.5
        return (1.0 - t) * self.size, s * self.size

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle (h, w) [sr] of each pixel's part of the disk, exact; they sum to 4 pi."""
        return disk_pixel_solid_angles(self.size, _uniform_edge, 2.0)
