"""The clouds' shadows in the air: crepuscular rays, and the dim air under a deck.

The table solver's sky assumes sunlit air everywhere. Along each view ray, where the air lies
below cloud tops, the light it scatters once from the sun is taken out where clouds shade it,
and the light the clouds pass on diffusely is put back:

    dL = int E T_air(p) T(x, p) [ sum_c sigma_c p_c(nu) (1 - T_c)
                                  - sum_c sigma_c mu_s (N - T_c) / (2 pi) ] dt

with E the sun's top-of-atmosphere irradiance, T_air(p) the air's transmittance from p towards
the sun and T(x, p) from the observer to p, sigma_c and p_c each constituent's scattering
coefficient and phase function, T_c = exp(-tau) the clouds' direct transmittance towards the
sun and N the net flux of the conservative two-stream slab they form, lit by the sun
(`transport._two_stream.beam_passed`, gamma tau summed over the layers): below a cloud
the air is lit by the flux the cloud transmits diffusely, E mu_s (N - T_c), whose radiance
from above, taken isotropic, it scatters with a mean phase of 1 / (4 pi) over the upper
hemisphere. Light the clouds reflect sideways onto the air, and the shadows' effect on the
orders >= 2 of the air, are left out.

T_c comes from a map of lines parallel to the sun (a deep shadow map, Lokovic & Veach 2000,
SIGGRAPH, doi:10.1145/344779.344958, along radius levels): for each line of a grid across the
sun's beam over the region the view rays cross below the cloud tops, each layer's water
towards the sun from where the line leaves each of `MAP_LEVELS` spheres between the lowest
cloud base and the highest top (`_air_shadow_kernels.sun_line_water`). A point below the
lowest base sees no cloud between it and its line's exit from that sphere, so its shadow is
exact up to the map's interpolation; within the layers the levels are interpolated linearly.
The integral is sampled at `SHADOW_SAMPLES` jittered points per ray, denser near its start.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.transport import _air_shadow_kernels
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents

__all__ = ["MAP_LEVELS", "MAP_MIN_TEXEL_M", "MAP_MAX_TEXEL_M", "MAP_TEXELS",
           "SHADOW_MAX_M", "SUN_MU", "AirShadows", "MapFrame",
           "air_shadows", "map_frame", "shaded_stretch"]

SHADOW_MAX_M = 40000.0  # the shaded stretch of a view ray ends this far from where it starts [m]
MAP_TEXELS = 512  # the map's lines across its longer side, at most ...
MAP_MIN_TEXEL_M = 30.0  # ... and at least this far apart [m] (a cumulus's edge: 100-300 m);
MAP_MAX_TEXEL_M = 1000.0  # coarser (views from space) and the shadows are below a pixel: none
MAP_LEVELS = 12  # radius levels between the lowest cloud base and the highest top
AIR_RADII = 16  # nodes of the air's transmittance towards the sun, ground to cloud tops
PHASE_NODES = 1024  # the air's phase functions, uniform in scattering angle (0.18 deg)
# Sun zenith cosines of the tables of the light reaching the air and the clouds, 0.005 apart (the
# reddening sun); below -0.2 the sun is set for everything under 40 km
SUN_MU = np.linspace(-0.2, 1.0, 241)


@dataclass(frozen=True, eq=False)
class AirShadows:
    """The clouds' shadow map over the region a frame's rays cross, and the air's arrays, for
    an observer at `origin` (3,) [m] and a sun along unit `sun` (3,)."""

    origin: np.ndarray
    sun: np.ndarray
    shadow_map: tuple
    air: tuple
    clouds: tuple

    def loss(self, solver, rays: np.ndarray, stop: np.ndarray,
             ray_ids: np.ndarray | None = None) -> np.ndarray:
        """dL (n, n_wl) [W m^-2 sr^-1 nm^-1] (module docstring) along unit world `rays`
        (n, 3) up to `stop` (n,) [m] (a cloud, a surface; inf: the sky); rays outside the
        region the map was made for are shaded from its nearest lines. `ray_ids` (n,) (default
        0 .. n-1) seed each ray's jitter."""
        origin, sun = self.origin, self.sun
        stretch = shaded_stretch(origin, rays, stop, float(solver.profile.bottom_radius_m),
                                  float(self.shadow_map[5][-1]))
        loss = np.zeros((rays.shape[0], solver.profile.n_wavelengths))
        marched = np.flatnonzero(stretch[:, 1] > stretch[:, 0])
        if marched.size == 0:
            return loss
        ids = np.arange(rays.shape[0]) if ray_ids is None else np.asarray(ray_ids)
        ids = np.ascontiguousarray(ids[marched], dtype=np.int64)
        rays = np.ascontiguousarray(rays[marched])
        stretch = np.ascontiguousarray(stretch[marched])
        before = np.ones((marched.size, loss.shape[1]))
        away = np.flatnonzero(stretch[:, 0] > 0.0)
        if away.size:
            starts = origin + stretch[away, :1] * rays[away]
            before[away] = solver.aerial_perspective(origin, starts, sun)[1]
        part = np.empty_like(before)
        _air_shadow_kernels.shadow_loss(origin, rays, ids, stretch, before, sun,
                                        self.shadow_map, self.air, self.clouds, part)
        loss[marched] = part
        return loss


def air_shadows(solver, field, origin: np.ndarray, rays: np.ndarray, sun: np.ndarray, *,
                stop: np.ndarray) -> AirShadows | None:
    """The `AirShadows` of `field` (`atmosphere.cloud_field.CloudField`) for unit world `rays`
    (n, 3) from `origin` (3,) that end at `stop` (n,) [m] at the latest, the sun along unit
    `sun` (3,); None where its map would be coarser than `MAP_MAX_TEXEL_M` (views from
    space: the shadows in the air are far below a pixel)."""
    profile = solver.profile
    stretch = shaded_stretch(origin, rays, stop, float(profile.bottom_radius_m),
                              field.highest_radius_m)
    shadow_map = _shadow_map(field, origin, rays, stretch, sun)
    if shadow_map is None:
        return None
    return AirShadows(origin, sun, shadow_map, _air_arrays(solver, field),
                      (field.mass_extinction_m2_g, field.asymmetry))


def shaded_stretch(origin: np.ndarray, rays: np.ndarray, stop: np.ndarray, bottom_r: float,
                   top_r: float) -> np.ndarray:
    """(n, 2): where each of unit world `rays` (n, 3) from `origin` [m] is below the sphere
    `top_r` (the highest cloud top), before `stop` (n,) and the sphere `bottom_r` (the
    ground), at most `SHADOW_MAX_M` long (empty: start = end) [m]."""
    b = rays @ origin
    c = float(origin @ origin)
    disc = b * b - c + top_r * top_r
    root = np.sqrt(np.maximum(disc, 0.0))
    start = np.maximum(-b - root, 0.0)
    end = np.where(disc > 0.0, -b + root, 0.0)
    ground_disc = b * b - c + bottom_r * bottom_r
    ground = np.where((ground_disc > 0.0) & (b < 0.0), -b - np.sqrt(np.maximum(ground_disc, 0.0)),
                      np.inf)
    end = np.minimum.reduce([end, stop, np.maximum(ground, 0.0), start + SHADOW_MAX_M])
    return np.stack([start, np.maximum(end, start)], axis=-1)


@dataclass(frozen=True, eq=False)
class MapFrame:
    """Where the shadow map's lines lie: through origin + u e1 + w e2 (world, unit `e1`, `e2`
    across the sun's beam) at texel centres u, w = corner + (i + 0.5) texel [m], `shape`
    (n_u, n_w) of them, each with the water from where it leaves each sphere of `levels` [m]."""

    e1: np.ndarray
    e2: np.ndarray
    corner: np.ndarray
    texel: float
    shape: tuple[int, int]
    levels: np.ndarray


def map_frame(lowest_r: float, highest_r: float, rays: np.ndarray, stretch: np.ndarray,
              sun: np.ndarray) -> MapFrame | None:
    """The `MapFrame` over the projections of the rays' shaded `stretch` (n, 2) [m] across the
    sun's beam, levels between the radii of the lowest cloud base and the highest top; None
    where its texels would be coarser than `MAP_MAX_TEXEL_M`."""
    e1 = np.cross(sun, [0.0, 0.0, 1.0] if abs(sun[2]) < 0.9 else [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(sun, e1)
    ends = np.concatenate([stretch[:, :1] * rays, stretch[:, 1:] * rays])
    across = np.stack([ends @ e1, ends @ e2], axis=-1)
    low, high = across.min(axis=0), across.max(axis=0)
    texel = max(float((high - low).max()) / (MAP_TEXELS - 2), MAP_MIN_TEXEL_M)
    if texel > MAP_MAX_TEXEL_M:
        return None
    n_u, n_w = (np.ceil((high - low) / texel).astype(int) + 2).tolist()
    return MapFrame(e1, e2, low - texel, texel, (n_u, n_w),
                    np.linspace(lowest_r, highest_r, MAP_LEVELS))


def _shadow_map(field, origin: np.ndarray, rays: np.ndarray, stretch: np.ndarray,
                sun: np.ndarray) -> tuple | None:
    """(water, e1, e2, corner, texel, levels) of `_air_shadow_kernels.shadow_loss` over the
    stretches' projections across the sun's beam (None: coarser than `MAP_MAX_TEXEL_M`)."""
    frame = map_frame(field.lowest_radius_m, field.highest_radius_m, rays, stretch, sun)
    if frame is None:
        return None
    water = np.empty((*frame.shape, MAP_LEVELS, field.n_layers))
    _air_shadow_kernels.sun_line_water(origin, frame.e1, frame.e2, sun, frame.corner,
                                       frame.texel, frame.levels, field.params, field.profiles,
                                       field.textures, water)
    return water, frame.e1, frame.e2, frame.corner, frame.texel, frame.levels


def _air_arrays(solver, field) -> tuple:
    """The `air` tuple of `_air_shadow_kernels.shadow_loss`."""
    profile = solver.profile
    bottom = float(profile.bottom_radius_m)
    scattering = scattering_constituents(profile)
    r_nodes = np.linspace(bottom, field.highest_radius_m, AIR_RADII)
    mu_nodes = SUN_MU
    along = np.array([0.0, 0.0, 1.0])
    ups = np.stack([np.sqrt(1.0 - mu_nodes**2), np.zeros_like(mu_nodes), mu_nodes], axis=-1)
    sun_air = solver.transmittance(r_nodes[:, None, None] * ups, along)
    h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
    return (bottom, h_step, np.ascontiguousarray(profile.density[list(scattering)]),
            np.ascontiguousarray(profile.scattering_per_density[list(scattering)]),
            np.ascontiguousarray(profile.extinction_per_density),
            np.ascontiguousarray(profile.density),
            sample_phase_functions(profile, scattering, PHASE_NODES), r_nodes, mu_nodes,
            np.ascontiguousarray(sun_air), np.asarray(profile.toa_irradiance, dtype=np.float64))
