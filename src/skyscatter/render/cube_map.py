"""A cube map camera: the whole sphere on six square faces, laid out as engines import them.

The faces follow OpenGL's cube map convention (The OpenGL Graphics System 4.6, section 8.13,
"Cube Map Texture Selection", Table 8.19; Direct3D, Vulkan, Metal, three.js and Unreal sample
cube maps the same way): a direction r in the map's axes picks the face of its largest
component, the major axis ma, and the texel

    face  sc   tc            s = (sc / |ma| + 1) / 2     (across the face, left to right)
    +X   -rz  -ry            t = (tc / |ma| + 1) / 2     (down the face, top row first)
    -X   +rz  -ry
    +Y   +rx  +rz
    -Y   +rx  -rz
    +Z   +rx  -ry
    -Z   -rx  -ry

with t = 0 the first row a loader uploads (the top row of the image file). The map's axes are
a right-handed, y-up world: +X east, +Y up (the zenith), +Z south, so north is -Z, as a
y-up engine whose scene has north along -Z expects; another orientation is a rotation of the
engine's lookup vector. Layouts: `cross`, the horizontal cross (4 x 3 faces: +Y above +Z,
then -X, +Z, +X, -Z in the middle row, -Y below +Z; every shared edge continuous), and
`strip`, the six faces side by side in the order +X, -X, +Y, -Y, +Z, -Z. Pixels of the cross
outside the faces are not valid (0 in the image).

A texel's solid angle is exact: for the face at unit distance, the area element
dx dy / (1 + x^2 + y^2)^(3/2) integrates to F(x, y) = atan2(x y, sqrt(1 + x^2 + y^2)) between
the texel's corners (e.g. Driscoll 2012, "Cubemap texel solid angle").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.render.camera import _check_size, _unit

__all__ = ["CUBE_LAYOUTS", "FACES", "CubeMapCamera"]

FACES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")
# layout -> (faces across, faces down, {face: (row, column) of its square})
CUBE_LAYOUTS = {
    "cross": (4, 3, {"+Y": (0, 1), "-X": (1, 0), "+Z": (1, 1), "+X": (1, 2), "-Z": (1, 3),
                     "-Y": (2, 1)}),
    "strip": (6, 1, {face: (0, k) for k, face in enumerate(FACES)}),
}
# map axes (x east, y up, z south) -> ENU (east, north, up)
_MAP_TO_ENU = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _face_directions(face: str, sc: np.ndarray, tc: np.ndarray) -> np.ndarray:
    """Map-axis directions (..., 3), not normalised, of face coordinates sc, tc in [-1, 1]
    (the inverse of the module docstring's table, |ma| = 1)."""
    one = np.ones_like(sc)
    columns = {"+X": (one, -tc, -sc), "-X": (-one, -tc, sc), "+Y": (sc, one, tc),
               "-Y": (sc, -one, -tc), "+Z": (sc, -tc, one), "-Z": (-sc, -tc, -one)}[face]
    return np.stack(columns, axis=-1)


def _texel_solid_angle(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """F(x, y) = atan2(x y, sqrt(1 + x^2 + y^2)) (module docstring)."""
    return np.arctan2(x * y, np.sqrt(1.0 + x * x + y * y))


@dataclass(frozen=True)
class CubeMapCamera:
    """The whole sphere on six `face`-pixel square faces in `layout` (module docstring).

    Parameters
    ----------
    face : int
        Pixels along a face's side. [pixels]
    layout : {"cross", "strip"}
        How the faces lie in the image: 4 x 3 faces or 6 x 1.
    """

    face: int
    layout: str = "cross"

    def __post_init__(self) -> None:
        if self.layout not in CUBE_LAYOUTS:
            raise InputError(f"unknown cube map layout {self.layout!r}; use one of "
                             f"{', '.join(CUBE_LAYOUTS)}", key="layout", value=self.layout,
                             allowed=", ".join(CUBE_LAYOUTS))
        _check_size("face", self.face)
        _check_size("width", self.face * CUBE_LAYOUTS[self.layout][0])

    @property
    def width(self) -> int:
        return self.face * CUBE_LAYOUTS[self.layout][0]

    @property
    def height(self) -> int:
        return self.face * CUBE_LAYOUTS[self.layout][1]

    def _squares(self):
        """(face name, row slice, column slice) of each face in the image."""
        for name, (row, column) in CUBE_LAYOUTS[self.layout][2].items():
            yield (name, slice(row * self.face, (row + 1) * self.face),
                   slice(column * self.face, (column + 1) * self.face))

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and the mask (h, w) of the faces' pixels;
        pixels outside the faces look at the zenith."""
        dirs = np.zeros((self.height, self.width, 3))
        dirs[..., 2] = 1.0
        centres = (np.arange(self.face) + 0.5) / self.face * 2.0 - 1.0
        sc, tc = np.meshgrid(centres, centres)  # sc across (columns), tc down (rows)
        for name, rows, columns in self._squares():
            local = _face_directions(name, sc, tc) @ _MAP_TO_ENU.T
            dirs[rows, columns] = local / np.linalg.norm(local, axis=-1, keepdims=True)
        return dirs, self.valid_mask()

    def valid_mask(self) -> np.ndarray:
        """The pixels (h, w) that lie on a face."""
        mask = np.zeros((self.height, self.width), dtype=bool)
        for _, rows, columns in self._squares():
            mask[rows, columns] = True
        return mask

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of ENU directions (..., 3) by the selection table of the
        module docstring; zero vectors give NaN."""
        r = _unit(dirs) @ _MAP_TO_ENU  # ENU -> map axes (the matrix is orthogonal)
        x, y, z = r[..., 0], r[..., 1], r[..., 2]
        ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
        index = np.where((ax >= ay) & (ax >= az), np.where(x >= 0, 0, 1),
                         np.where(ay >= az, np.where(y >= 0, 2, 3), np.where(z >= 0, 4, 5)))
        table = {0: (-z, -y, ax), 1: (z, -y, ax), 2: (x, z, ay), 3: (x, -z, ay),
                 4: (x, -y, az), 5: (-x, -y, az)}
        row = np.full(x.shape, np.nan)
        column = np.full(x.shape, np.nan)
        squares = CUBE_LAYOUTS[self.layout][2]
        for k, name in enumerate(FACES):
            sc, tc, ma = table[k]
            on = index == k
            with np.errstate(invalid="ignore", divide="ignore"):
                s = (sc / ma + 1.0) / 2.0
                t = (tc / ma + 1.0) / 2.0
            face_row, face_column = squares[name]
            row = np.where(on, (face_row + np.clip(t, 0.0, 1.0)) * self.face, row)
            column = np.where(on, (face_column + np.clip(s, 0.0, 1.0)) * self.face, column)
        return row, column

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle of each pixel (h, w), exact (module docstring), 0 off the faces. [sr]"""
        edges = np.arange(self.face + 1) / self.face * 2.0 - 1.0
        x0, x1 = edges[None, :-1], edges[None, 1:]
        y0, y1 = edges[:-1, None], edges[1:, None]
        texel = (_texel_solid_angle(x1, y1) - _texel_solid_angle(x0, y1)
                 - _texel_solid_angle(x1, y0) + _texel_solid_angle(x0, y0))
        out = np.zeros((self.height, self.width))
        for _, rows, columns in self._squares():
            out[rows, columns] = texel
        return out
