"""Ray geometry in a spherical shell atmosphere, robust at the horizon and from space.

A ray starts at distance r from the planet centre with mu = cos(angle between the ray and the
local zenith). The distance along the ray to a sphere of radius R solves
t^2 + 2 r mu t + r^2 - R^2 = 0, so t = -r mu +- sqrt(r^2 (mu^2 - 1) + R^2)
(Bruneton 2017, functions.glsl `DistanceToTopAtmosphereBoundary`;
docs/physics/single_scattering.md).
All functions are numba kernels that work on floats; numpy wrappers broadcast.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

__all__ = [
    "atmosphere_segment",
    "broadcast_rays",
    "disk_fraction_above",
    "distance_to_sphere",
    "ground_distances",
    "horizon_cos_zenith",
    "horizontal_towards",
    "local_frame_directions",
    "segment_rays",
    "sun_visible_fraction",
    "towards_visible_sun",
]


@njit(cache=True)
def distance_to_sphere(r, mu, radius, far):
    """Distance [m] along the ray (r, mu) to the sphere `radius`: the far root if `far`, else
    the near one. NaN when the ray's line misses the sphere."""
    discriminant = r * r * (mu * mu - 1.0) + radius * radius
    if discriminant < 0.0:
        return math.nan
    root = math.sqrt(discriminant)
    return -r * mu + root if far else -r * mu - root


@njit(parallel=True, cache=True)
def ground_distances(origin, directions, radius):
    """Distance [m] (n,) from `origin` (3,) along unit `directions` (n, 3) to the sphere
    `radius` where the ray meets it from outside (`distance_to_sphere`'s near root), inf where
    it does not."""
    r = math.sqrt(origin[0] ** 2 + origin[1] ** 2 + origin[2] ** 2)
    out = np.full(directions.shape[0], np.inf)
    for i in prange(directions.shape[0]):
        mu = (origin[0] * directions[i, 0] + origin[1] * directions[i, 1]
              + origin[2] * directions[i, 2]) / r
        if r > radius and mu < 0.0:
            d = distance_to_sphere(r, mu, radius, False)
            if d >= 0.0:  # NaN (a miss) fails this too
                out[i] = d
    return out


@njit(cache=True)
def atmosphere_segment(r, mu, bottom_radius, top_radius):
    """Part of the ray (r, mu) inside the atmosphere: (t_start, t_end, hits_ground) [m].

    t_start > 0 for observers in space. t_end is the ground hit when the ray meets the
    ground before leaving the atmosphere. t_end <= t_start means the ray misses the shell.
    A ray that starts on or above the top and does not point down has no length inside, exactly:
    the far root -r mu + sqrt(r^2 mu^2 - r^2 + R_top^2) would otherwise leave a rounding-error
    segment (~1e-9 m) at r = R_top."""
    if r >= top_radius and mu >= 0.0:
        return 0.0, 0.0, False
    t_top_far = distance_to_sphere(r, mu, top_radius, True)
    if math.isnan(t_top_far) or t_top_far <= 0.0:
        return 0.0, 0.0, False
    t_start = max(0.0, distance_to_sphere(r, mu, top_radius, False))
    t_end = t_top_far
    hits_ground = False
    if mu < 0.0:
        t_ground = distance_to_sphere(r, mu, bottom_radius, False)
        if not math.isnan(t_ground) and t_ground < t_end:
            # Mathematically t_ground >= 0 for r >= bottom_radius; clamp the rounding error of
            # an observer standing on the ground (t_ground = -r mu - r |mu| = 0).
            t_end = max(t_ground, t_start)
            hits_ground = True
    return t_start, t_end, hits_ground


@njit(cache=True)
def horizon_cos_zenith(r, bottom_radius):
    """cos of the zenith angle of the geometric horizon seen from radius r [-] (<= 0)."""
    if r <= bottom_radius:
        return 0.0
    return -math.sqrt(r * r - bottom_radius * bottom_radius) / r


@njit(cache=True)
def sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius):
    """Fraction of a uniform sun disk above the geometric horizon seen from radius r [-]
    (`disk_fraction_above` with the horizon of `horizon_cos_zenith`)."""
    return disk_fraction_above(mu_s, horizon_cos_zenith(r, bottom_radius), sun_angular_radius)


@njit(cache=True)
def disk_fraction_above(mu, mu_h, angular_radius):
    """Fraction of a uniform disk whose centre has zenith cosine `mu` above a horizon at
    zenith cosine `mu_h` [-].

    With x = (elevation of the disk centre above the horizon) / (angular radius), the visible
    part of a disk cut by a straight edge is 1/2 + (x sqrt(1 - x^2) + asin x) / pi (circular
    segment area). A point disk (radius 0) is visible when above the horizon."""
    sin_h = math.sqrt(max(0.0, 1.0 - mu_h * mu_h))
    # Fast exit well above the horizon: mu >= cos(theta_h - radius) (no inverse cosines).
    if mu >= mu_h * math.cos(angular_radius) + sin_h * math.sin(angular_radius):
        return 1.0
    elevation = math.acos(min(1.0, max(-1.0, mu_h))) - math.acos(min(1.0, max(-1.0, mu)))
    if angular_radius <= 0.0:
        return 1.0 if elevation >= 0.0 else 0.0
    x = elevation / angular_radius
    if x >= 1.0:
        return 1.0
    if x <= -1.0:
        return 0.0
    return 0.5 + (x * math.sqrt(1.0 - x * x) + math.asin(x)) / math.pi


def towards_visible_sun(position: np.ndarray, sun_direction: np.ndarray,
                        bottom_radius: float) -> np.ndarray:
    """Unit direction (3,) along which the visible part of the sun disk is attenuated, seen
    from `position` (planet-centred [m], (3,)): the sun's own direction (3,) while its centre is
    above the geometric horizon; below it, the horizon direction at the sun's azimuth (the
    part of a setting disk still visible shines along the grazing ray), raised by 1e-9 rad so
    that rounding does not make the tangent ray meet the ground. Solvers' `transmittance`
    along it gives the light of the sun's visible part; `sun_visible_fraction` its size."""
    position = np.asarray(position, dtype=np.float64)
    sun = np.asarray(sun_direction, dtype=np.float64)
    sun = sun / np.linalg.norm(sun)
    r = float(np.linalg.norm(position))
    up = position / r
    mu_s = float(up @ sun)
    mu_h = horizon_cos_zenith(r, bottom_radius)
    if mu_s >= mu_h:
        return sun
    elevation = math.asin(max(-1.0, min(1.0, mu_h))) + 1e-9  # above the horizontal [rad]
    return math.sin(elevation) * up + math.cos(elevation) * horizontal_towards(up, sun)


def horizontal_towards(up: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The unit vector (3,) perpendicular to the unit vertical `up` at the azimuth of
    `direction` (3,); any such vector where `direction` is vertical (a sun at the zenith or
    the nadir has every azimuth)."""
    horizontal = direction - float(up @ direction) * up
    if float(np.linalg.norm(horizontal)) == 0.0:
        horizontal = np.cross(up, [1.0, 0.0, 0.0] if abs(up[0]) < 0.9 else [0.0, 1.0, 0.0])
    return horizontal / np.linalg.norm(horizontal)


def local_frame_directions(zenith_rad: np.ndarray, azimuth_rad: np.ndarray) -> np.ndarray:
    """Unit vectors (..., 3) in the local east-north-up frame from zenith angle and azimuth
    (azimuth from north towards east) [rad]."""
    zenith = np.asarray(zenith_rad, dtype=np.float64)
    azimuth = np.asarray(azimuth_rad, dtype=np.float64)
    s = np.sin(zenith)
    return np.stack([s * np.sin(azimuth), s * np.cos(azimuth), np.cos(zenith)], axis=-1)


def broadcast_rays(position: ArrayLike, directions: ArrayLike, normalise: bool = True
                   ) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """(origins, directions, S): `position` [m] ((3,) or (..., 3)) and `directions` (..., 3)
    broadcast to the shape S + (3,) and flattened to (n, 3) C-contiguous float64 arrays, the
    directions made unit vectors when `normalise`: the rays a solver's kernels march."""
    dirs = np.asarray(directions, dtype=np.float64)
    origins = np.asarray(position, dtype=np.float64)
    shape = np.broadcast_shapes(dirs.shape, origins.shape)[:-1]
    dirs = np.broadcast_to(dirs, shape + (3,))
    if normalise:
        dirs = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
    origins = np.broadcast_to(origins, shape + (3,))
    return (np.ascontiguousarray(origins.reshape(-1, 3)),
            np.ascontiguousarray(dirs.reshape(-1, 3)), shape)


def segment_rays(position: ArrayLike, points: ArrayLike
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[int, ...]]:
    """(origins, directions, lengths, S) of the segments from `position` [m] to `points`
    (..., 3) [m], broadcast and flattened as `broadcast_rays`: unit directions (n, 3) (any
    for a segment of no length) and lengths (n,) [m]."""
    origins, targets, shape = broadcast_rays(position, points, normalise=False)
    offsets = targets - origins
    lengths = np.linalg.norm(offsets, axis=1)
    directions = np.ascontiguousarray(offsets / np.where(lengths > 0, lengths, 1.0)[:, None])
    return origins, directions, lengths, shape
