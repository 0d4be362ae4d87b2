"""An octahedral map camera: the whole sphere on one square, as light probes store it.

The octahedral mapping (Engelhardt & Dachsbacher 2008, "Octahedron environment maps", VMV;
in the form of Cigolle et al. 2014, "A survey of efficient representations for independent
unit vectors", JCGT 3(2), 1-30, listing 1): a unit direction d = (x, y, z) goes to
p = (x, y) / (|x| + |y| + |z|) on the octahedron's upper half, the lower half folded out to the
corners, p <- (1 - |p_y|, 1 - |p_x|) sign(p) where z < 0; the pixel at (u, v) = (p + 1) / 2
(u across, 1 - v down the rows). Here (x, y, z) = (east, north, up): the zenith is at the
centre, the horizon on the inner diamond, the nadir at the four corners, east to the right
of the centre and north above it.

A pixel's solid angle: the unnormalised direction q(p) = (p_x, p_y, 1 - |p_x| - |p_y|)
(folded where negative) has |q . (dq/dp_x x dq/dp_y)| = 1 everywhere, so
dOmega = dA_p / |q|^3; each pixel's is that integrated by the midpoint rule on 8 x 8 points
(the sum over the sphere is 4 pi to 1e-6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.render.camera import _SquareMap, _unit
from skyscatter.render.disk_maps import disk_coordinates  # p of the square [-1, 1]^2

__all__ = ["OctahedralCamera"]

_SUBSAMPLES = 8


def _unfolded(px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """q(p) (..., 3), not normalised, of octahedral coordinates in [-1, 1]^2."""
    z = 1.0 - np.abs(px) - np.abs(py)
    below = z < 0.0
    x = np.where(below, (1.0 - np.abs(py)) * np.sign(px), px)
    y = np.where(below, (1.0 - np.abs(px)) * np.sign(py), py)
    return np.stack([x, y, z], axis=-1)


@dataclass(frozen=True)
class OctahedralCamera(_SquareMap):
    """The whole sphere on a `size` x `size` octahedral map (module docstring)."""

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and an all-True mask (h, w)."""
        q = _unfolded(*np.broadcast_arrays(*disk_coordinates(self.size)))
        return q / np.linalg.norm(q, axis=-1, keepdims=True), self.valid_mask()

    def valid_mask(self) -> np.ndarray:
        """Every pixel (h, w)."""
        return np.ones((self.size, self.size), dtype=bool)

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of ENU directions (..., 3); zero vectors give NaN."""
        d = _unit(dirs)
        total = np.sum(np.abs(d), axis=-1)
        px, py = d[..., 0] / total, d[..., 1] / total
        below = d[..., 2] < 0.0
        fx = np.where(below, (1.0 - np.abs(py)) * np.where(px >= 0.0, 1.0, -1.0), px)
        fy = np.where(below, (1.0 - np.abs(px)) * np.where(py >= 0.0, 1.0, -1.0), py)
        return (1.0 - fy) / 2.0 * self.size, (fx + 1.0) / 2.0 * self.size

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle of each pixel (h, w) [sr] (module docstring)."""
        area = (2.0 / self.size / _SUBSAMPLES) ** 2
        omega = np.zeros((self.size, self.size))
        for a in range(_SUBSAMPLES):
            for b in range(_SUBSAMPLES):
                px, py = disk_coordinates(self.size, (a + 0.5) / _SUBSAMPLES,
                                          (b + 0.5) / _SUBSAMPLES)
                q = _unfolded(*np.broadcast_arrays(px, py))
                omega += area / np.linalg.norm(q, axis=-1) ** 3
        return omega
