"""Cameras: which direction each pixel of an image looks in.

Every camera works in the observer's LOCAL frame, east-north-up (ENU): x = east, y = north,
z = up. The scene rotates these directions to the planet frame; cameras know nothing of
latitude, longitude or altitude.

Conventions shared by all cameras:

* An image is `(height, width, ...)`; pixel `(i, j)` is row `i` (from the top), column `j`
  (from the left), and its centre lies at the continuous coordinates `(i + 0.5, j + 0.5)`.
* Azimuth is measured from north through east (clockwise seen from above), elevation up from
  the horizon, zenith angle down from the zenith. [rad] inside, [deg] in parameter names.
* `directions()` returns unit vectors, shape `(height, width, 3)` float64, and a boolean mask
  `(height, width)` of the pixels that see the sky through the lens. Pixels outside the lens
  still hold finite unit vectors (kernels never see NaN); mask them with `valid`.
* `direction_to_pixel(dirs)` maps directions `(..., 3)` (any length > 0) to continuous
  `(row, column)` coordinates, each of shape `(...)`; `np.floor` gives the pixel index.
* `pixel_solid_angles()` returns the solid angle of each pixel [sr], 0 outside the lens.

Projections:

* `FisheyeCamera`: equidistant all-sky lens looking at the zenith (zenith angle proportional
  to the distance from the image centre). North is at the top and EAST ON THE LEFT, as an
  all-sky camera lying on the ground and looking up records it, and as sky charts and
  all-sky-camera archives show the sky seen from below.
* `EquirectangularCamera`: the full sphere, azimuth across (increasing to the right, i.e.
  clockwise: north, east, south, west), elevation down the rows (+90° top, −90° bottom);
  the layout of latitude-longitude environment maps viewed from inside.
* `PerspectiveCamera`: pinhole camera with square pixels, set by heading (azimuth of the view
  axis), pitch (its elevation) and roll (positive = camera turned clockwise about the view
  axis as seen from behind, i.e. right wing down), or by forward and up vectors.

Sources: equidistant projection r = f·θ (Kannala & Brandt 2006, IEEE TPAMI 28, 1335,
doi:10.1109/TPAMI.2006.153, projection (iii)); pinhole solid angle dΩ = dA cos³θ / f².
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.checks import (
    ANGLE_DEG,
    ELEVATION_ANGLE_DEG,
    PERSPECTIVE_FOV_DEG,
    Bounds,
    checked_integer,
)
from skyscatter.errors import InputError

__all__ = [
    "Camera",
    "EquirectangularCamera",
    "FisheyeCamera",
    "PerspectiveCamera",
]


class Camera(Protocol):
    """What the renderer needs from a camera."""

    @property
    def width(self) -> int: ...

    @property
    def height(self) -> int: ...

    def directions(self) -> tuple[np.ndarray, np.ndarray]: ...

    def valid_mask(self) -> np.ndarray: ...

    def pixel_solid_angles(self) -> np.ndarray: ...


# Pixels along one side of an image: 2^20 (a million) is far past any display; the memory an
# image needs is checked before rendering (`render.budget`).
MAX_SIDE_PIXELS = 1 << 20
FISHEYE_FOV_DEG = Bounds(0.0, 360.0, low_open=True)


def _check_size(name: str, value: int) -> None:
    checked_integer(name, value, 1, MAX_SIDE_PIXELS)


def _pixel_centres(height: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """Continuous coordinates of the pixel centres: rows (h, 1) and columns (1, w)."""
    rows = (np.arange(height, dtype=np.float64) + 0.5)[:, None]
    cols = (np.arange(width, dtype=np.float64) + 0.5)[None, :]
    return rows, cols


def _unit(dirs: ArrayLike) -> np.ndarray:
    """Normalise directions (..., 3); zero vectors become NaN."""
    d = np.asarray(dirs, dtype=np.float64)
    if d.shape[-1:] != (3,):
        raise InputError(f"directions must have shape (..., 3), got {d.shape}",
                         key="dirs", value=d.shape, allowed="(..., 3)")
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return d / np.where(norm > 0.0, norm, np.nan)


@dataclass(frozen=True)
class _SquareMap:
    """What the whole-sphere maps on `size` x `size` squares share (sphere, paraboloid and
    octahedral maps): the checked size, an image one square high and, unless a map sets it
    otherwise, one wide."""

    size: int

    def __post_init__(self) -> None:
        _check_size("size", self.size)

    @property
    def width(self) -> int:
        return self.size

    @property
    def height(self) -> int:
        return self.size


@dataclass(frozen=True)
class FisheyeCamera:
    """Equidistant all-sky camera looking at the zenith; image `size` x `size` pixels.

    Zenith angle θ = (ρ / R) · field_of_view / 2, where ρ is the distance from the image
    centre and R = size / 2 [pixels]: the zenith is the centre, θ = field_of_view / 2 lies on
    the inscribed circle (the horizon for the default 180°). North is at the top, east on the
    LEFT, south at the bottom, west on the right: the sky as seen from below.

    Parameters
    ----------
    size : int
        Width and height of the square image. [pixels]
    field_of_view_deg : float
        Full angle across the circle, in (0, 360]; 180 shows the whole upper hemisphere. [deg]
    """

    size: int
    field_of_view_deg: float = 180.0

    def __post_init__(self) -> None:
        _check_size("size", self.size)
        FISHEYE_FOV_DEG.check("field_of_view_deg", self.field_of_view_deg)

    @property
    def width(self) -> int:
        return int(self.size)

    @property
    def height(self) -> int:
        return int(self.size)

    @property
    def _theta_max(self) -> float:
        """Zenith angle on the circle edge. [rad]"""
        return math.radians(self.field_of_view_deg) / 2.0

    def _normalised_offsets(self) -> tuple[np.ndarray, np.ndarray]:
        """Offsets (u to the right, v downwards) of the pixel centres in units of R."""
        rows, cols = _pixel_centres(self.size, self.size)
        radius = self.size / 2.0
        return (cols - radius) / radius, (rows - radius) / radius

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and the mask (h, w) of pixels inside the circle.

        Outside the circle the equidistant map is continued (θ > field_of_view / 2), so those
        pixels hold finite unit vectors too.
        """
        u, v = self._normalised_offsets()
        rho = np.hypot(u, v)
        theta = self._theta_max * rho
        # sin(θ)/ρ without a 0/0 at the centre: θ_max · sinc(θ/π), np.sinc(x) = sin(πx)/(πx).
        sin_over_rho = self._theta_max * np.sinc(theta / np.pi)
        dirs = np.empty((self.size, self.size, 3), dtype=np.float64)
        dirs[..., 0] = -u * sin_over_rho  # image left = east
        dirs[..., 1] = -v * sin_over_rho  # image top = north
        dirs[..., 2] = np.cos(theta)
        return dirs, rho <= 1.0

    def valid_mask(self) -> np.ndarray:
        """Pixels inside the circle (h, w), as `directions` returns them, without the rays."""
        return np.hypot(*self._normalised_offsets()) <= 1.0

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of directions (..., 3); each result has shape (...).

        Directions with zenith angle > field_of_view / 2 land outside the circle (ρ > R); the
        nadir's azimuth is undefined and maps to the bottom of the circle's continuation.
        Zero vectors give NaN.
        """
        d = _unit(dirs)
        theta = np.arccos(np.clip(d[..., 2], -1.0, 1.0))
        azimuth = np.arctan2(d[..., 0], d[..., 1])  # from north through east
        radius = self.size / 2.0
        rho = theta / self._theta_max * radius
        column = radius - rho * np.sin(azimuth)
        row = radius - rho * np.cos(azimuth)
        return row, column

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle of each pixel (h, w), 0 outside the circle. [sr]

        dΩ = sin θ dθ dφ = θ_max sin θ / ρ · dA with dA = (1/R)² per pixel (midpoint rule).
        """
        u, v = self._normalised_offsets()
        rho = np.hypot(u, v)
        radius = self.size / 2.0
        jacobian = self._theta_max**2 * np.sinc(self._theta_max * rho / np.pi)
        omega = jacobian / radius**2
        return np.where(rho <= 1.0, omega, 0.0)


@dataclass(frozen=True)
class EquirectangularCamera:
    """Full panorama: azimuth across the columns, elevation down the rows.

    Column j looks at azimuth heading + 2π ((j + 0.5) / width − 1/2): the centre of the image
    looks at `heading_deg` and azimuth grows to the right (north → east → south → west for
    heading 0, which puts north in the middle, south at both edges). Row i looks at elevation
    π/2 − π (i + 0.5) / height (+90° at the top edge, −90° at the bottom edge). All pixels
    are valid.

    Parameters
    ----------
    width, height : int
        Image size; width = 2 · height gives square pixels in angle. [pixels]
    heading_deg : float
        Azimuth seen at the centre column, from north through east. [deg]
    """

    width: int
    height: int
    heading_deg: float = 0.0

    def __post_init__(self) -> None:
        _check_size("width", self.width)
        _check_size("height", self.height)
        ANGLE_DEG.check("heading_deg", self.heading_deg)

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and an all-True mask (h, w)."""
        rows, cols = _pixel_centres(self.height, self.width)
        azimuth = math.radians(self.heading_deg) + 2.0 * np.pi * (cols / self.width - 0.5)
        elevation = 0.5 * np.pi - np.pi * rows / self.height
        cos_e = np.cos(elevation)
        dirs = np.empty((self.height, self.width, 3), dtype=np.float64)
        dirs[..., 0] = cos_e * np.sin(azimuth)
        dirs[..., 1] = cos_e * np.cos(azimuth)
        dirs[..., 2] = np.sin(elevation)
        return dirs, self.valid_mask()

    def valid_mask(self) -> np.ndarray:
        """Every pixel (h, w)."""
        return np.ones((self.height, self.width), dtype=bool)

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of directions (..., 3); each result has shape (...).

        Columns wrap into [0, width); zero vectors give NaN.
        """
        d = _unit(dirs)
        elevation = np.arcsin(np.clip(d[..., 2], -1.0, 1.0))
        azimuth = np.arctan2(d[..., 0], d[..., 1])
        turns = (azimuth - math.radians(self.heading_deg)) / (2.0 * np.pi) + 0.5
        column = np.mod(turns, 1.0) * self.width
        row = (0.5 - elevation / np.pi) * self.height
        return row, column

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle of each pixel (h, w), exact for the band of rows. [sr]

        Ω = Δφ (sin e_top − sin e_bottom) with Δφ = 2π / width.
        """
        edges = 0.5 * np.pi - np.pi * np.arange(self.height + 1, dtype=np.float64) / self.height
        band = np.sin(edges[:-1]) - np.sin(edges[1:])
        return np.broadcast_to((2.0 * np.pi / self.width * band)[:, None],
                               (self.height, self.width)).copy()


@dataclass(frozen=True)
class PerspectiveCamera:
    """Pinhole camera with square pixels.

    The view axis (forward) has azimuth `heading_deg` (from north through east) and elevation
    `pitch_deg`; `roll_deg` turns the camera clockwise about the view axis as seen from behind
    it (positive = right side down). With roll 0 the image's up vector lies in the vertical
    plane through the view axis, so the horizon is level. The ray through continuous image
    coordinates (x, y) ∈ [−1, 1]² (x right, y up) is forward + x tan(hfov/2) right +
    y tan(vfov/2) up, with tan(hfov/2) = tan(vfov/2) · width / height.

    Parameters
    ----------
    width, height : int
        Image size. [pixels]
    vertical_fov_deg : float
        Angle between the top and bottom edges of the image, in (0, 180). [deg]
    heading_deg : float
        Azimuth of the view axis, from north through east. [deg]
    pitch_deg : float
        Elevation of the view axis, in [−90, 90]. [deg]
    roll_deg : float
        Rotation about the view axis, clockwise seen from behind. [deg]
    """

    width: int
    height: int
    vertical_fov_deg: float
    heading_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0

    def __post_init__(self) -> None:
        _check_size("width", self.width)
        _check_size("height", self.height)
        PERSPECTIVE_FOV_DEG.check("vertical_fov_deg", self.vertical_fov_deg)
        ELEVATION_ANGLE_DEG.check("pitch_deg", self.pitch_deg)
        ANGLE_DEG.check("heading_deg", self.heading_deg)
        ANGLE_DEG.check("roll_deg", self.roll_deg)

    @classmethod
    def from_forward_up(cls, width: int, height: int, vertical_fov_deg: float,
                        forward: ArrayLike, up: ArrayLike) -> PerspectiveCamera:
        """Camera looking along `forward` (3,) with `up` (3,) towards the image top (look-at).

        Both in ENU, any length; `up` need not be orthogonal to `forward` (its component
        along `forward` is dropped) but must not be parallel to it. Heading, pitch and roll
        are solved from the two vectors, so the camera equals the one built from them.
        """
        f = _unit(forward)
        u = np.asarray(up, dtype=np.float64)
        if f.shape != (3,) or u.shape != (3,) or not np.all(np.isfinite(f)):
            raise InputError("forward and up must be finite non-zero 3-vectors "
                             f"(east, north, up), got {forward!r} and {up!r}",
                             key="forward", value=forward)
        up_length = float(np.linalg.norm(u))
        u = u - np.dot(u, f) * f
        norm_u = float(np.linalg.norm(u))
        if not (np.isfinite(norm_u) and norm_u > 1e-9 * up_length):
            raise InputError(f"up {up!r} is zero or parallel to forward {forward!r}; give an up "
                             "vector that is not along the view axis", key="up", value=up)
        u = u / norm_u
        heading = math.atan2(f[0], f[1])
        pitch = math.asin(min(1.0, max(-1.0, f[2])))
        right0, up0, _ = _basis(heading, pitch, 0.0)
        roll = math.atan2(float(np.dot(u, right0)), float(np.dot(u, up0)))
        return cls(width, height, vertical_fov_deg, math.degrees(heading), math.degrees(pitch),
                   math.degrees(roll))

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors (3,) of the camera in ENU; right = forward × up."""
        return _basis(math.radians(self.heading_deg), math.radians(self.pitch_deg),
                      math.radians(self.roll_deg))

    @property
    def _half_extent(self) -> tuple[float, float]:
        """tan(hfov / 2), tan(vfov / 2) [-]."""
        tan_v = math.tan(math.radians(self.vertical_fov_deg) / 2.0)
        return tan_v * self.width / self.height, tan_v

    def _image_plane(self) -> tuple[np.ndarray, np.ndarray]:
        """Pixel centres on the plane at unit distance: x (1, w) to the right, y (h, 1) up."""
        rows, cols = _pixel_centres(self.height, self.width)
        half_w, half_h = self._half_extent
        return (2.0 * cols / self.width - 1.0) * half_w, (1.0 - 2.0 * rows / self.height) * half_h

    def directions(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit view directions (h, w, 3) in ENU and an all-True mask (h, w)."""
        right, up, forward = self.basis()
        x, y = self._image_plane()
        rays = forward + x[..., None] * right + y[..., None] * up
        rays /= np.linalg.norm(rays, axis=-1, keepdims=True)
        return rays, self.valid_mask()

    def valid_mask(self) -> np.ndarray:
        """Every pixel (h, w)."""
        return np.ones((self.height, self.width), dtype=bool)

    def direction_to_pixel(self, dirs: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, column) of directions (..., 3); NaN for directions behind the camera."""
        d = _unit(dirs)
        right, up, forward = self.basis()
        depth = d @ forward
        half_w, half_h = self._half_extent
        with np.errstate(invalid="ignore", divide="ignore"):
            depth = np.where(depth > 0.0, depth, np.nan)
            x = (d @ right) / depth / half_w
            y = (d @ up) / depth / half_h
        return (1.0 - y) * self.height / 2.0, (x + 1.0) * self.width / 2.0

    def pixel_solid_angles(self) -> np.ndarray:
        """Solid angle of each pixel (h, w) [sr]: dA / (1 + x² + y²)^{3/2} (midpoint rule)."""
        x, y = self._image_plane()
        half_w, half_h = self._half_extent
        area = (2.0 * half_w / self.width) * (2.0 * half_h / self.height)
        return area / (1.0 + x * x + y * y) ** 1.5


def _basis(heading: float, pitch: float, roll: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(right, up, forward) in ENU from heading, pitch, roll [rad] (see PerspectiveCamera)."""
    sh, ch = math.sin(heading), math.cos(heading)
    sp, cp = math.sin(pitch), math.cos(pitch)
    forward = np.array([sh * cp, ch * cp, sp])
    up0 = np.array([-sh * sp, -ch * sp, cp])
    right0 = np.array([ch, -sh, 0.0])
    sr, cr = math.sin(roll), math.cos(roll)
    up = cr * up0 + sr * right0
    right = cr * right0 - sr * up0
    return right, up, forward
