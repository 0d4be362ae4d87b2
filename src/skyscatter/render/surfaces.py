"""Lit surfaces seen through the atmosphere: the planet's ground (with an albedo map) and
heightfield terrain, with aerial perspective.

A ray that meets a surface at p, with normal n and spectral albedo a, carries

    L = L_in(x, p) + T(x, p) a / pi (E_sun(p, n) [not in the terrain's shadow] + E_sky(p, n))

with L_in and T the solver's aerial perspective (the light the air between the observer and
p scatters towards the observer, and the transmittance), E_sun the direct sunlight on a surface
facing n and E_sky the sky light it sees (Bruneton 2017 `GetSunAndSkyIrradiance` and the demo's
ground shading), all in `LutSolver.surface_radiance`. Light reflected by the ground enters
the tables' higher orders with the atmosphere's single albedo, not the map's (an
approximation of the same kind as Bruneton's; the direct reflection uses the map exactly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.errors import InputError
from skyscatter.render.albedo_map import AlbedoMap
from skyscatter.render.terrain import Heightfield
from skyscatter.transport.cloud_far_field import surface_cloud_transmittance
from skyscatter.transport.clouds import CloudField
from skyscatter.transport.geometry import ground_distances
from skyscatter.transport.solvers import Solver, SurfaceRadianceSolver

__all__ = ["Ground", "surface_radiance"]


@dataclass(frozen=True)
class Ground:
    """What replaces the plain sphere of constant albedo: an albedo map, terrain, or both."""

    albedo_map: AlbedoMap | None = None
    terrain: Heightfield | None = None


def surface_radiance(solver: Solver, position: np.ndarray, directions: np.ndarray,
                     sun_direction: np.ndarray, ground: Ground, *,
                     clouds: CloudField | None = None,
                     with_distance: bool = False) -> tuple[np.ndarray, ...]:
    """(radiance (n_hit, n_wl) [W m^-2 sr^-1 nm^-1], hit (n,) bool) of the rays from
    `position` along unit `directions` (n, 3) that meet the ground or the terrain, in the
    shadows of the terrain and of `clouds` (the share of the sunlight they let through
    towards the point, directly or scattered, at the middle wavelength: the droplets'
    extinction varies by ~2 % over the visible; `surface_cloud_transmittance` with
    `diffuse`); with
    `with_distance` also the distance (n,) [m] to the surface (inf for a miss). InputError
    unless the solver is a `SurfaceRadianceSolver`."""
    if not isinstance(solver, SurfaceRadianceSolver):
        raise InputError("an albedo map or terrain needs the table solver (--solver lut)",
                         key="solver", value=getattr(solver, "name", solver), allowed="lut")
    profile = solver.profile
    origin = np.asarray(position, dtype=np.float64)
    if ground.terrain is not None:
        _, points, normals, hit = ground.terrain.intersect(origin, directions)
        points, normals = points[hit], normals[hit]
        lit = ~ground.terrain.shadowed(points, sun_direction)
    else:
        distance = ground_distances(origin, np.ascontiguousarray(directions, dtype=np.float64),
                                    float(profile.bottom_radius_m))
        hit = np.isfinite(distance)
        points = origin + distance[hit, None] * directions[hit]
        normals = points / np.linalg.norm(points, axis=1, keepdims=True)
        lit = np.ones(points.shape[0], dtype=bool)
    if clouds is not None:
        middle = clouds.wavelengths_nm.size // 2
        lit = lit * surface_cloud_transmittance(clouds, origin, points, sun_direction,
                                                diffuse=True)[:, middle]
    if ground.albedo_map is not None:
        albedo = ground.albedo_map.spectral(points, profile.wavelengths_nm)
    else:
        albedo = profile.ground_albedo
    radiance = solver.surface_radiance(origin, points, normals, albedo, sun_direction, lit=lit)
    if not with_distance:
        return radiance, hit
    distance = np.full(hit.shape, np.inf)
    distance[hit] = np.linalg.norm(points - origin, axis=1)
    return radiance, hit, distance
