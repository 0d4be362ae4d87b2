"""Clouds in front of the sky: their light, their transmittance and the air between.

`clouds_in_front` marches the camera rays through a `CloudField` (`transport._cloud_kernels`
says how each sample is lit) and puts the result over what lies behind the clouds, L_behind
(the clear sky, or the ground, from the table solver):

    L = T_c (L_behind - S(x, p_c)) + S(x, p_c) - dL(x, p_c) + T_air(x, p_c) L_c

with L_c and T_c the clouds' own radiance and transmittance along the ray, p_c the point at
the transmittance-weighted distance of their scattering, S and T_air the air's aerial
perspective between the observer x and p_c (`LutSolver.aerial_perspective`), and dL the light
the clouds' shadows take from that air (`transport.air_shadows`: crepuscular rays). The first
term is what lies beyond the clouds, seen through them; the second the air in front of them;
the third the clouds' own light seen through that air. A ray that meets no cloud is
L_behind - dL(x, end of the ray).

The light reaching each sample comes from tables over (radius, sun zenith cosine) that
`cloud_lighting` fills from the solver: the air's transmittance towards the sun, the clear
sky's diffuse irradiance, and the irradiance the ground reflects up (dimmed by the clouds
around, `ground_shade`).

The march sees the droplets' optics delta-scaled (`delta_scaled`): the light they diffract
within `PEAK_ANGLE_RAD` of its direction goes on as if unscattered, along the view ray and
towards the sun alike (transmittance of the sky behind a thin cloud, depth of the sunlit
skin), and the single scattering keeps the exact phase function (the TMS correction). Against
the Monte Carlo reference this brightens the thin, sunlit edges of cumulus seen near the sun
(docs/clouds.md). The sun's disk behind clouds and the shadows on the ground use the clouds'
unscaled transmittance (`cloud_transmittance`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from skyscatter.atmosphere._cloud_sampling import (
    COLUMN_BINS,
    COLUMN_SHARES,
    column_cover,
    coverage_map_factor,
)
from skyscatter.atmosphere.cloud_field import CloudField
from skyscatter.transport import _cloud_kernels
from skyscatter.transport._settle_kernels import settle_mean
from skyscatter.transport.adaptive_pixels import coarse_spacing, refine
from skyscatter.transport.air_shadows import SUN_MU, AirShadows, air_shadows
from skyscatter.transport.cloud_far_field import diffuse_passed

__all__ = ["CloudField", "CloudLighting", "cloud_lighting", "cloud_transmittance",
           "clouds_in_front", "ground_shade", "kernel_arrays"]

# The droplets' diffraction peak: about half of what they scatter (Q_ext ~ 2, half of it
# diffraction: van de Hulst 1957, Light Scattering by Small Particles, sec. 8.22) lies within 5 deg
# of the forward direction for r_eff >= 5 um in the visible (the lobe is ~0.6 lambda / r wide)
PEAK_ANGLE_RAD = np.radians(5.0)
CHUNK_RAYS = 1 << 17  # rays per march: bounds the temporaries (n, n_wl) x 4
LIGHTING_RADII = 8  # nodes across the cloud layers
REFINE_TOLERANCE = 0.05  # neighbours whose radiance differs by less are interpolated between
# (a 960 x 540 cumulus frame: 33 % of the rays marched; the image differs from marching every
# pixel by no more than two passes of the march with different jitter differ from each other)


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


def cloud_lighting(solver, field: CloudField,
                   origin: np.ndarray | None = None) -> CloudLighting:
    """The lighting tables of `field`'s layers from the table solver (`transmittance`,
    `ground_irradiance`); the sun is the profile's top-of-atmosphere irradiance; the ground's
    light is dimmed by the clouds around the point below `origin` (`ground_shade`)."""
    profile = solver.profile
    bottom = float(profile.bottom_radius_m)
    r_nodes = np.linspace(field.lowest_radius_m, field.highest_radius_m, LIGHTING_RADII)
    mu_nodes = SUN_MU
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
    ground_up = reflected[None] * rise[:, None] * ground_shade(field, origin)
    return CloudLighting(r_nodes, mu_nodes, np.ascontiguousarray(sun_air),
                         np.ascontiguousarray(sky_down), np.ascontiguousarray(ground_up),
                         np.asarray(profile.toa_irradiance, dtype=np.float64))


def ground_shade(field: CloudField, origin: np.ndarray | None = None) -> np.ndarray:
    """(n_wl,) the share of the clear sky's light the ground keeps under `field`'s layers,
    averaged over the area that lights a cloud's base from below: per layer
    1 - f + f sum_k s_k / (1 + gamma k_ext W_k) over its cloudy columns (a fraction f of the area,
    shares s_k of water paths W_k: the far field's column statistics, at the coverage map's
    value below `origin`; a grid layer's own columns), the two-stream's transmittance of a
    conservative column (`transport._two_stream`, gamma = 3 (1 - g) / 4), layers overlapping at
    random. (A cloud's own shadow falls a base height times tan(sun zenith) away, so under a
    broken field the ground below a cloud is lit about as the area is.)"""
    shade = np.ones(field.wavelengths_nm.size)
    for layer, config in enumerate(field.clouds.layers):
        if config.grid is not None:
            grid = config.grid
            paths = grid.water_g_m3.sum(axis=2) * grid.spacing_m[2]  # (nx, ny) [g m^-2]
            shade *= np.mean(diffuse_passed(field, layer, paths), axis=(0, 1))
            continue
        paths = np.empty(COLUMN_BINS)
        factor = 1.0
        if origin is not None:
            factor = coverage_map_factor(field.params, field.profiles, layer, *map(float, origin))
        cover = column_cover(field.profiles, layer, factor, paths)
        cloudy = np.asarray(COLUMN_SHARES) @ diffuse_passed(field, layer, paths)
        shade *= 1.0 - cover + cover * cloudy
    return shade


def clouds_in_front(solver, field: CloudField, origin: np.ndarray, rays: np.ndarray,
                    sun: np.ndarray, *, behind: np.ndarray,
                    max_distance: np.ndarray | None = None,
                    lighting: CloudLighting | None = None,
                    image_mask: np.ndarray | None = None,
                    progress: Callable[[int], None] | None = None) -> np.ndarray:
    """Radiance (n, n_wl) [W m^-2 sr^-1 nm^-1] along unit world `rays` (n, 3) from `origin`
    (3,) with the clouds of `field` in front of `behind` (n, n_wl), the radiance without them
    (module docstring), the sun along unit `sun` (3,). Rays stop at the planet's ground or
    at `max_distance` (n,) [m] (terrain). With `image_mask` (h, w), whose True pixels the rays
    are in row-major order, the clouds are marched on a coarse lattice first and between its points
    only where neighbours differ by more than `REFINE_TOLERANCE` (`adaptive_pixels`).
    `progress(n)` is told of the rays as they are marched or interpolated."""
    report = progress or (lambda n: None)
    origin = np.ascontiguousarray(origin, dtype=np.float64)
    sun = np.ascontiguousarray(sun, dtype=np.float64)
    rays = np.ascontiguousarray(rays, dtype=np.float64)
    limits = (np.full(rays.shape[0], np.inf) if max_distance is None
              else np.asarray(max_distance, dtype=np.float64))
    light = cloud_lighting(solver, field, origin) if lighting is None else lighting
    shadows = air_shadows(solver, field, origin, rays, sun, stop=limits)
    every_ray = np.arange(rays.shape[0])
    # each ray's jitter from its pixel's index (row-major), as the viewer's shader has it
    over = _CloudsOver(every_ray if image_mask is None else np.flatnonzero(image_mask.ravel()),
                       field.wavelengths_nm.size)

    def evaluate(indices: np.ndarray) -> None:
        for start in range(0, indices.size, CHUNK_RAYS):
            chunk = indices[start:start + CHUNK_RAYS]
            over.march(solver, field, (origin, rays, limits, sun), (light, shadows), chunk)
            report(chunk.size)

    def settle(targets: np.ndarray, neighbours: np.ndarray) -> np.ndarray:
        agree = over.settle(targets, neighbours, behind)
        report(int(agree.sum()))
        return agree

    if image_mask is None:
        evaluate(every_ray)
    else:
        pixels = np.full(image_mask.shape, -1)  # each pixel's ray, -1 where none
        pixels[image_mask] = every_ray
        refine(pixels, coarse_spacing(rays, pixels), evaluate, settle)
    result = np.multiply(behind, over.transmittance)
    result += over.added
    return np.maximum(result, 0.0, out=result)


class _CloudsOver:
    """Per ray (n, n_wl), float32: the clouds' transmittance T and what they add A to the
    radiance behind them, L = T L_behind + A (module docstring: T = T_c and
    A = -T_c S + max(S - dL, 0) + T_air L_c; a clear ray T = 1, A = -dL), and whether the ray
    met a cloud; `ids` (n,) seed each ray's jitter."""

    def __init__(self, ids: np.ndarray, n_wl: int) -> None:
        n = ids.size
        self.ids = ids
        self.transmittance = np.ones((n, n_wl), dtype=np.float32)
        self.added = np.zeros((n, n_wl), dtype=np.float32)
        self.hit = np.zeros(n, dtype=np.bool_)

    def march(self, solver, field: CloudField, scene: tuple,
              lights: tuple[CloudLighting, AirShadows | None], indices: np.ndarray) -> None:
        """March the rays `indices` of `scene` (origin, rays, limits, sun) through `field`."""
        origin, all_rays, all_limits, sun = scene
        light, shadows = lights
        order = _interleaved(indices)
        rays, limits = all_rays[order], all_limits[order]
        n, n_wl = order.size, field.wavelengths_nm.size
        radiance, transmittance = np.empty((n, n_wl)), np.empty((n, n_wl))
        depth, hit = np.empty(n), np.empty(n, dtype=np.bool_)
        _cloud_kernels.march_clouds(
            origin, rays, self.ids[order], limits, field.bottom_radius_m, sun,
            kernel_arrays(field),
            (light.r_nodes, light.mu_nodes, light.sun_air, light.sky_down, light.ground_up,
             light.sun_toa), radiance, transmittance, depth, hit)
        added = (np.zeros((n, n_wl)) if shadows is None
                 else -shadows.loss(solver, rays, np.where(hit, depth, limits),
                                    self.ids[order]))
        seen = np.flatnonzero(hit)
        if seen.size:
            points = origin + depth[seen, None] * rays[seen]
            air_light, air_transmittance = solver.aerial_perspective(origin, points, sun)
            added[seen] = (np.maximum(air_light + added[seen], 0.0)
                           - transmittance[seen] * air_light + air_transmittance * radiance[seen])
            self.transmittance[order[seen]] = transmittance[seen]
        self.added[order] = added
        self.hit[order] = hit

    def settle(self, targets: np.ndarray, neighbours: np.ndarray,
               behind: np.ndarray) -> np.ndarray:
        """`adaptive_pixels.refine`'s settle: the targets whose neighbours all met a cloud or
        all missed, and whose radiance over the targets' own background differs by at most
        `REFINE_TOLERANCE` of its mean in every band, take their mean (`settle_mean`)."""
        agree = np.empty(targets.size, dtype=np.bool_)
        settle_mean(targets, np.ascontiguousarray(neighbours), behind, REFINE_TOLERANCE,
                    self.transmittance, self.added, self.hit, agree)
        return agree


def _interleaved(indices: np.ndarray) -> np.ndarray:
    """`indices` dealt round-robin to the kernels' threads: the parallel loops split the rays
    into one contiguous block per thread, and neighbouring rays cost alike (a block of sky
    against a block of cloud would leave one thread idle)."""
    threads = numba.get_num_threads()
    return np.concatenate([indices[k::threads] for k in range(threads)])


def kernel_arrays(field: CloudField) -> tuple:
    """The arrays of `field` in the order the kernels take them (`_cloud_kernels`), its
    optics delta-scaled (`delta_scaled`)."""
    return (field.params, field.profiles, field.textures) + delta_scaled(field)


def delta_scaled(field: CloudField) -> tuple:
    """(mass extinction [m^2 g^-1], single-scattering albedo, asymmetry, phase [sr^-1]) of the
    layers with the fraction f of the light their droplets scatter within `PEAK_ANGLE_RAD` of
    the forward direction counted as unscattered (Joseph et al. 1976, J. Atmos. Sci. 33, 2452):
    k' = (1 - f w) k, w' = w (1 - f) / (1 - f w), g' = (g - f) / (1 - f), p' = p / (1 - f),
    so that p' is the phase function outside the peak per unit of the scaled scattering
    (Nakajima & Tanaka 1988, JQSRT 40, 51: the exact phase function for single scattering
    with the scaled extinction)."""
    f = forward_peak_fraction(field.phase, PEAK_ANGLE_RAD)  # (n_layers, n_wl)
    albedo = field.single_scattering_albedo
    scaled = 1.0 - f * albedo
    return (field.mass_extinction_m2_g * scaled, albedo * (1.0 - f) / scaled,
            (field.asymmetry - f) / (1.0 - f), field.phase / (1.0 - f)[:, None, :])


def forward_peak_fraction(phase: np.ndarray, angle_rad: float) -> np.ndarray:
    """The fraction (n_layers, n_wl) of `phase` (n_layers, PHASE_ANGLES, n_wl) [sr^-1] (nodes
    theta = pi (i / (n - 1))^2) scattered within `angle_rad` of the forward direction
    (trapezoids in theta of 2 pi p sin(theta))."""
    n = phase.shape[1]
    theta = np.pi * np.linspace(0.0, 1.0, n) ** 2
    inside = theta <= angle_rad
    weight = 2.0 * np.pi * np.sin(theta[inside])
    return np.trapezoid(phase[:, inside] * weight[None, :, None], theta[inside], axis=1)


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
