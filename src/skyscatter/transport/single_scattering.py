"""Single-scattering solver: sky radiance, transmittance and ground irradiance by ray marching.

L(x, v) = E_sun * [ sum_c p_c(nu) beta_s,c  int T(x, p) n_c(p) T_sun(p) ds
                    + albedo / pi * T(x, g) T_sun(g) max(mu_s(g), 0) ]
for an observer at x looking along v, with the sun as a distant source of irradiance E_sun
normal to its beam at the top of the atmosphere (Nishita et al. 1993; Bruneton & Neyret 2008,
eq. 4 with one scattering order). The sun disk's own radiance is not included. Ground light is
reflected once (Lambertian) from direct sunlight only. Kernels: `transport/_kernels.py`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _kernels
from skyscatter.transport.geometry import (
    broadcast_rays,
    segment_rays,
    sun_visible_fraction,
    towards_visible_sun,
)
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["SingleScatteringSolver", "hemisphere_irradiance", "observer_position",
           "ray_marched_transmittance"]

CHUNK_RAYS = 16384  # rays per kernel call: bounds memory (n_c x n_wl doubles per ray)


def observer_position(altitude_m: float, bottom_radius_m: float) -> np.ndarray:
    """Planet-centred position [m] of an observer at `altitude_m` above the north pole, whose
    local east-north-up frame then coincides with the world axes."""
    return np.array([0.0, 0.0, bottom_radius_m + altitude_m])


class SingleScatteringSolver:
    """Answers the solver questions with one scattering order; an independent check for the
    precomputed tables."""

    name = "single"

    def __init__(self, profile: OpticalProfile, n_samples: int = 64,
                 table_size: tuple[int, int] = (128, 256), table_samples: int = 512) -> None:
        self.profile = profile
        self.n_samples = int(n_samples)
        self._h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
        self._sun_table = _kernels.column_table(
            table_size[0], table_size[1], table_samples, profile.bottom_radius_m,
            profile.top_radius_m, self._h_step, profile.density)

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1] seen from `position` (planet-centred,
        (3,) or broadcastable to the directions) along unit `view_directions` (..., 3), with the
        sun along unit `sun_direction` (3,). Returns (..., n_wl). `progress(n)` is called with
        the number of rays done after each chunk."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        distances = np.full(directions.shape[0], np.inf)
        radiance, _ = self._march(origins, directions, distances, sun_direction, True, progress)
        return radiance.reshape(shape + (self.profile.n_wavelengths,))

    def aerial_perspective(self, position: ArrayLike, points: ArrayLike,
                           sun_direction: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(inscattered [W m^-2 sr^-1 nm^-1], transmittance [-]) between `position` and
        `points` (..., 3) [m], each (..., n_wl): single scattering of the air in between,
        ray marched (`LutSolver.aerial_perspective` has the meaning)."""
        origins, directions, distances, shape = segment_rays(position, points)
        inscattered, transmittance = self._march(origins, directions, distances,
                                                 sun_direction, False, None)
        n_wl = self.profile.n_wavelengths
        return inscattered.reshape(shape + (n_wl,)), transmittance.reshape(shape + (n_wl,))

    def _march(self, origins: np.ndarray, directions: np.ndarray, distances: np.ndarray,
               sun_direction: ArrayLike, with_ground: bool,
               progress: Callable[[int], None] | None) -> tuple[np.ndarray, np.ndarray]:
        """(radiance, transmittance) (n, n_wl) along rays that end after `distances` at the
        latest; the lit Lambertian ground is added `with_ground`."""
        sun = _unit(np.asarray(sun_direction, dtype=np.float64))
        p = self.profile
        radiance = np.empty((directions.shape[0], p.n_wavelengths))
        transmittance = np.empty_like(radiance)
        for start in range(0, directions.shape[0], CHUNK_RAYS):
            stop = min(start + CHUNK_RAYS, directions.shape[0])
            inscatter, transmittance[start:stop], ground = _kernels.single_scattering(
                origins[start:stop], directions[start:stop], distances[start:stop], sun,
                self.n_samples, p.bottom_radius_m, p.top_radius_m, self._h_step, p.density,
                p.extinction_per_density, self._sun_table, p.sun_angular_radius_rad)
            nu = directions[start:stop] @ sun
            chunk = ground * (p.ground_albedo / np.pi) if with_ground else np.zeros_like(ground)
            for c, phase in enumerate(p.phases):
                if phase is None:
                    continue
                chunk += (phase.evaluate(nu, p.wavelengths_nm)
                          * p.scattering_per_density[c] * inscatter[:, c, :])
            radiance[start:stop] = chunk * p.toa_irradiance
            if progress is not None:
                progress(stop - start)
        return radiance, transmittance

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf, n_samples: int = 256) -> np.ndarray:
        """Transmittance [-] from `position` along `directions` over `distance_m` (inf: out
        of the atmosphere, towards a light source; 0 when the ground blocks the path, so for a
        light below the horizon). (..., n_wl)."""
        return ray_marched_transmittance(self.profile, position, directions, distance_m,
                                         n_samples)

    def ground_irradiance(self, position: ArrayLike, sun_direction: ArrayLike,
                          n_zenith: int = 24, n_azimuth: int = 48) -> tuple[np.ndarray, np.ndarray]:
        """(direct, diffuse) spectral irradiance on a horizontal surface at `position`
        [W m^-2 nm^-1], each (n_wl,): `hemisphere_irradiance` of this solver."""
        return hemisphere_irradiance(self, position, sun_direction, n_zenith, n_azimuth)


def hemisphere_irradiance(solver, position: ArrayLike, sun_direction: ArrayLike,
                          n_zenith: int = 24, n_azimuth: int = 48
                          ) -> tuple[np.ndarray, np.ndarray]:
    """(direct, diffuse) spectral irradiance [W m^-2 nm^-1], each (n_wl,), on a horizontal
    surface at `position` (planet-centred [m], (3,)) from a solver's `transmittance` and
    `sky_radiance`. Direct: E_sun T_sun mu_s times the visible part of the disk; diffuse: the
    sky radiance integrated over the upper hemisphere (Gauss-Legendre in cos(zenith),
    midpoint rule in azimuth)."""
    origin = np.asarray(position, dtype=np.float64)
    up = _unit(origin)
    sun = _unit(np.asarray(sun_direction, dtype=np.float64))
    p = solver.profile
    mu_s = float(up @ sun)
    r = float(np.linalg.norm(origin))
    visible = sun_visible_fraction(r, mu_s, p.bottom_radius_m, p.sun_angular_radius_rad)
    sun_transmittance = solver.transmittance(
        origin, towards_visible_sun(origin, sun, p.bottom_radius_m))
    direct = p.toa_irradiance * sun_transmittance * max(mu_s, 0.0) * visible
    nodes, weights = np.polynomial.legendre.leggauss(n_zenith)
    cos_zenith = 0.5 * (nodes + 1.0)
    azimuth = (np.arange(n_azimuth) + 0.5) * 2.0 * np.pi / n_azimuth
    east, north = _tangent_frame(up)
    sin_zenith = np.sqrt(1.0 - cos_zenith**2)
    dirs = (sin_zenith[:, None, None] * (np.cos(azimuth)[None, :, None] * east
                                         + np.sin(azimuth)[None, :, None] * north)
            + cos_zenith[:, None, None] * up)
    radiance = solver.sky_radiance(origin, dirs, sun)
    weight = (0.5 * weights * cos_zenith)[:, None, None] * (2.0 * np.pi / n_azimuth)
    diffuse = np.sum(radiance * weight, axis=(0, 1))
    return direct, diffuse


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector, axis=-1, keepdims=True)


def _tangent_frame(up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthogonal to `up` (east, north for the north-pole observer)."""
    helper = np.array([0.0, 1.0, 0.0]) if abs(up[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    east = np.cross(helper, up)
    east /= np.linalg.norm(east)
    return east, np.cross(up, east)
