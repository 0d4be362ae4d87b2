"""Clouds in front of the sky: their light, their transmittance and the air between.

`clouds_in_front` marches the camera rays through a `CloudField` (`transport._cloud_kernels`
says how each sample is lit) and puts the result over what lies behind the clouds, L_behind
(the clear sky, or the ground, from the table solver):

    L = T_c (L_behind - S(x, p_c)) + V S(x, p_c) + T_air(x, p_c) L_c

with L_c and T_c the clouds' own radiance and transmittance along the ray, p_c the point at
the transmittance-weighted distance of their scattering, and S and T_air the air's
aerial perspective between the observer x and p_c (`LutSolver.aerial_perspective`). The first
term is what lies beyond the clouds, seen through them; the second the air in front of them,
V = 1 - f (1 - T_mid) of it lit, T_mid the clouds' transmittance towards the sun from the
middle of the stretch and f = min(1, `AIR_SHADE_M` / its length) the part of the stretch
taken as shaded (the air under a deck, in front of a near cloud, is in its shadow; a far
cloud's light comes through tens of kilometres of mostly sunlit air, and one shadow sample
there would dapple it). A stopgap until the march shades the air sample by sample
(crepuscular rays); the third term is the clouds' own light seen through that air.

The light reaching each sample comes from tables over (radius, sun zenith cosine) that
`cloud_lighting` fills from the solver: the air's transmittance towards the sun, the clear
sky's diffuse irradiance, and the irradiance the ground reflects up (dimmed in the kernel by
the cloud column above the ground). The air beyond the clouds, and the air of rays that meet
no cloud, are lit as in a clear sky (no crepuscular rays).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.atmosphere.cloud_field import CloudField
from skyscatter.transport import _cloud_kernels

__all__ = ["CloudField", "CloudLighting", "cloud_lighting", "cloud_transmittance",
           "clouds_in_front", "kernel_arrays"]

AIR_SHADE_M = 2000.0  # the stretch of air in front of a cloud that its layer may shade [m]
CHUNK_RAYS = 1 << 17  # rays per march: bounds the temporaries (n, n_wl) x 4
LIGHTING_RADII = 8  # nodes across the cloud layers
LIGHTING_MU = 241  # sun zenith cosines from MU_LOWEST to 1 (0.005 apart: the reddening sun)
MU_LOWEST = -0.2  # below this the sun is set for every cloud below 40 km


@dataclass(frozen=True, eq=False)
class CloudLighting:
    """Tables (n_r, n_mu, n_wl) over uniform radii [m] and sun zenith cosines (module
    docstring): sun_air [-], sky_down and ground_up [W m^-2 nm^-1]; sun_toa (n_wl,)."""

    r_nodes: np.ndarray
    mu_nodes: np.ndarray
    sun_air: np.ndarray
    sky_down: np.ndarray
    ground_up: np.ndarray
    sun_toa: np.ndarray


def cloud_lighting(solver, field: CloudField) -> CloudLighting:
    """The lighting tables of `field`'s layers from the table solver (`transmittance`,
    `ground_irradiance`); the sun is the profile's top-of-atmosphere irradiance."""
    profile = solver.profile
    bottom = float(profile.bottom_radius_m)
    r_nodes = np.linspace(field.lowest_radius_m, field.highest_radius_m, LIGHTING_RADII)
    mu_nodes = np.linspace(MU_LOWEST, 1.0, LIGHTING_MU)
    # the sun along z, the points at its zenith cosine mu: one sun for every lookup
    sun = np.array([0.0, 0.0, 1.0])
    ups = np.stack([np.sqrt(1.0 - mu_nodes**2), np.zeros_like(mu_nodes), mu_nodes], axis=-1)
    positions = r_nodes[:, None, None] * ups  # (n_r, n_mu, 3)
    sun_air = solver.transmittance(positions, sun)
    sky_down = solver.ground_irradiance(positions, sun)[1]
    direct, diffuse = solver.ground_irradiance(bottom * ups, sun)
    reflected = profile.ground_albedo * (direct + diffuse)  # (n_mu, n_wl)
    rise = solver.transmittance(np.broadcast_to(bottom * ups[-1], (r_nodes.size, 3)), ups[-1],
                                r_nodes - bottom)  # (n_r, n_wl)
    ground_up = reflected[None] * rise[:, None]
    return CloudLighting(r_nodes, mu_nodes, np.ascontiguousarray(sun_air),
                         np.ascontiguousarray(sky_down), np.ascontiguousarray(ground_up),
                         np.asarray(profile.toa_irradiance, dtype=np.float64))


def clouds_in_front(solver, field: CloudField, origin: np.ndarray, rays: np.ndarray,
                    sun: np.ndarray, *, behind: np.ndarray,
                    max_distance: np.ndarray | None = None,
                    lighting: CloudLighting | None = None) -> np.ndarray:
    """Radiance (n, n_wl) [W m^-2 sr^-1 nm^-1] along unit world `rays` (n, 3) from `origin`
    (3,) with the clouds of `field` in front of `behind` (n, n_wl), the radiance without them
    (module docstring), the sun along unit `sun` (3,). Rays stop at the planet's ground or
    at `max_distance` (n,) [m] (terrain)."""
    origin = np.ascontiguousarray(origin, dtype=np.float64)
    sun = np.ascontiguousarray(sun, dtype=np.float64)
    light = cloud_lighting(solver, field) if lighting is None else lighting
    result = np.array(behind, dtype=np.float64)
    limits = (np.full(rays.shape[0], np.inf) if max_distance is None
              else np.asarray(max_distance, dtype=np.float64))
    for start in range(0, rays.shape[0], CHUNK_RAYS):
        chunk = slice(start, start + CHUNK_RAYS)
        _clouds_over(solver, field, origin, np.ascontiguousarray(rays[chunk], dtype=np.float64),
                     np.ascontiguousarray(limits[chunk]), sun, light, result[chunk])
    return result


def _clouds_over(solver, field: CloudField, origin: np.ndarray, rays: np.ndarray,
                 limits: np.ndarray, sun: np.ndarray, light: CloudLighting,
                 result: np.ndarray) -> None:
    """`clouds_in_front` of one chunk of rays, over `result` in place."""
    n, n_wl = rays.shape[0], field.wavelengths_nm.size
    radiance, transmittance = np.empty((n, n_wl)), np.empty((n, n_wl))
    depth, hit = np.empty(n), np.empty(n, dtype=np.bool_)
    _cloud_kernels.march_clouds(
        origin, rays, limits, field.bottom_radius_m, sun, kernel_arrays(field),
        (light.r_nodes, light.mu_nodes, light.sun_air, light.sky_down, light.ground_up,
         light.sun_toa), radiance, transmittance, depth, hit)
    seen = np.flatnonzero(hit)
    if seen.size:
        points = origin + depth[seen, None] * rays[seen]
        air_light, air_transmittance = solver.aerial_perspective(origin, points, sun)
        middle = field.wavelengths_nm.size // 2
        stretch = depth[seen]
        lit = cloud_transmittance(field, origin + 0.5 * stretch[:, None] * rays[seen], sun)
        shaded_part = np.minimum(AIR_SHADE_M / np.maximum(stretch, 1.0), 1.0)
        shade = (1.0 - shaded_part * (1.0 - lit[:, middle]))[:, None]
        clouds_t = transmittance[seen]
        result[seen] = (clouds_t * (result[seen] - air_light) + shade * air_light
                        + air_transmittance * radiance[seen])


def kernel_arrays(field: CloudField) -> tuple:
    """The arrays of `field` in the order the kernels take them (`_cloud_kernels`)."""
    return (field.params, field.profiles, field.textures, field.mass_extinction_m2_g,
            field.single_scattering_albedo, field.asymmetry, field.phase)


def cloud_transmittance(field: CloudField, origins: np.ndarray, directions: np.ndarray,
                        max_distance: np.ndarray | float = np.inf) -> np.ndarray:
    """Transmittance [-] (n, n_wl) of the clouds from `origins` along unit `directions` (each
    (n, 3) or (3,)) up to `max_distance` [m] (the sun disk behind clouds, cloud shadows)."""
    starts, directions = np.broadcast_arrays(np.atleast_2d(origins), np.atleast_2d(directions))
    n = starts.shape[0]
    starts = np.array(starts, dtype=np.float64)  # copies: broadcast views are read-only
    directions = np.array(directions, dtype=np.float64)
    limits = np.array(np.broadcast_to(max_distance, (n,)), dtype=np.float64)
    water = np.empty((n, field.n_layers))
    _cloud_kernels.cloud_water_paths(starts, directions, limits, field.bottom_radius_m,
                                     field.params, field.profiles, field.textures, water)
    return np.exp(-water @ field.mass_extinction_m2_g)
