"""Compose a sky image: camera rays -> solver radiance -> plus the sun disk -> spectral image.

Cameras and the sun direction live in the local east-north-up frame of a `Viewpoint`: an
observer above the north pole (`ground_viewpoint`, where that frame is the world frame) or a
point in orbit above any latitude and longitude (`orbit_viewpoint`). The sun disk
is added with its limb-darkened radiance times the transmittance along the line of sight;
when the disk is smaller than about four pixels, its whole transmitted irradiance goes into the
pixel that contains its centre, so the image always carries the right solar flux.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from skyscatter.checks import ANGLE_DEG, ELEVATION_M, LATITUDE_DEG, ZENITH_DEG, checked_number
from skyscatter.errors import InputError
from skyscatter.render.camera import Camera
from skyscatter.render.lunar_eclipse import circle_overlap_area
from skyscatter.render.surfaces import Ground, surface_radiance
from skyscatter.spectrum.colour import spectral_to_xyz, white_balance, xyz_to_rgb
from skyscatter.spectrum.star import Star
from skyscatter.transport.clouds import CloudField, cloud_transmittance, clouds_in_front
from skyscatter.transport.geometry import (
    disk_fraction_above,
    horizon_cos_zenith,
    towards_visible_sun,
)
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import SurfaceSolver

__all__ = [
    "SkyImage",
    "SunLight",
    "Viewpoint",
    "add_sun_disk",
    "deposit_small_disk",
    "disk_visible_fraction",
    "cached_pixel_solid_angles",
    "camera_image",
    "diffuse_radiance",
    "ground_viewpoint",
    "orbit_viewpoint",
    "render_sky",
    "sky_image",
    "without_ground",
    "sun_direction",
]

SPLAT_PIXELS = 4.0  # a disk covering fewer pixels than this is deposited into one pixel


def sun_direction(zenith_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector towards the sun in the local east-north-up frame; azimuth from north
    towards east [deg]. InputError for a zenith angle outside [0, 180] or a non-finite
    azimuth (`checks.ZENITH_DEG`, `checks.ANGLE_DEG`)."""
    zenith = np.radians(ZENITH_DEG.check("zenith_deg", zenith_deg))
    azimuth = np.radians(ANGLE_DEG.check("azimuth_deg", azimuth_deg))
    return np.array([np.sin(zenith) * np.sin(azimuth), np.sin(zenith) * np.cos(azimuth),
                     np.cos(zenith)])


@dataclass(frozen=True)
class SunLight:
    """The sun seen from the camera as a directional light."""

    irradiance: np.ndarray  # (n_wl,) direct, normal to the sun, hidden part left out
    # [W m^-2 nm^-1]
    direction: np.ndarray  # (3,) unit, ENU, as seen (refracted where the render refracts)
    angular_radius_rad: float
    in_image: bool = True  # its disk is drawn in the image


@dataclass(frozen=True)
class SkyImage:
    """A rendered spectral image and what is needed to turn it into colour."""

    spectral: np.ndarray  # (h, w, n_wl) [W m^-2 sr^-1 nm^-1]; 0 outside the lens
    valid: np.ndarray  # (h, w) bool
    sky: np.ndarray  # (h, w) bool: the pixels to meter: valid ones looking above the
    # horizontal, else (views from space) the lit ones
    wavelengths_nm: np.ndarray  # (n_wl,)
    light_spectrum: np.ndarray  # (n_wl,) the star's irradiance at the top [W m^-2 nm^-1]
    from_space: bool = False  # camera above the atmosphere: meter the starlight, not the frame
    sun: SunLight | None = None  # the sun as a light at the camera

    def xyz(self, balance_to_light: bool = False) -> np.ndarray:
        """CIE 1931 XYZ (h, w, 3), Y = luminance [cd m^-2]; optionally adapted from the
        light source's white to D65 (Bradford)."""
        xyz = spectral_to_xyz(self.spectral, self.wavelengths_nm)
        if balance_to_light:
            xyz = white_balance(xyz, self.light_spectrum, self.wavelengths_nm)
        return xyz

    def rgb(self, space: str = "srgb", balance_to_light: bool = False) -> np.ndarray:
        """Linear RGB (h, w, 3) in `space`, scaled so that Y = 1 is 1 cd m^-2."""
        return xyz_to_rgb(self.xyz(balance_to_light), space)

    def __repr__(self) -> str:
        height, width = self.valid.shape
        wavelengths = self.wavelengths_nm
        where = ", from space" if self.from_space else ""
        return (f"SkyImage({width} x {height} pixels, {wavelengths.size} wavelengths "
                f"{wavelengths.min():.0f}-{wavelengths.max():.0f} nm{where})")

    def _repr_png_(self) -> bytes:
        """The image as `api.save_image` writes its PNG by default (metered exposure, the ACES
        curve, sRGB): what a Jupyter notebook shows."""
        from io import BytesIO

        from skyscatter.render.exposure import display_rgb8, metered_ev100
        from skyscatter.render.image_io import display_image_writer
        from skyscatter.render.image_options import ImageOptions

        options, xyz, buffer = ImageOptions(), self.xyz(), BytesIO()
        rgb8 = display_rgb8(xyz_to_rgb(xyz, options.colour_space), self.valid,
                            metered_ev100(self, xyz), options.compensation_ev, options.operator)
        display_image_writer(rgb8)(buffer)
        return buffer.getvalue()


@dataclass(frozen=True)
class Viewpoint:
    """Where the camera is (planet-centred [m]) and its local east-north-up axes (columns of
    `to_world`, world coordinates)."""

    position_m: np.ndarray  # (3,)
    to_world: np.ndarray  # (3, 3)

    def direction_to_world(self, local: np.ndarray) -> np.ndarray:
        return np.asarray(local) @ self.to_world.T


def ground_viewpoint(altitude_m: float, bottom_radius_m: float) -> Viewpoint:
    """An observer `altitude_m` above the north pole; local frame = world frame. InputError
    for an altitude outside `checks.ELEVATION_M` or a radius that is not finite and > 0."""
    _check_place(altitude_m, bottom_radius_m)
    return Viewpoint(observer_position(altitude_m, bottom_radius_m), np.eye(3))


def _check_place(altitude_m: float, bottom_radius_m: float) -> None:
    ELEVATION_M.check("altitude_m", altitude_m)
    checked_number("planet_radius_m", bottom_radius_m, 0.0, None, low_open=True)


def orbit_viewpoint(altitude_m: float, latitude_deg: float, longitude_deg: float,
                    bottom_radius_m: float) -> Viewpoint:
    """A camera `altitude_m` above the ground point at (latitude, longitude) [deg]; its local
    frame is east-north-up at that point, so pitch -90 looks at the planet's centre.
    InputError for a value outside `checks` bounds (as `ground_viewpoint`)."""
    _check_place(altitude_m, bottom_radius_m)
    lat = np.radians(LATITUDE_DEG.check("latitude_deg", latitude_deg))
    lon = np.radians(ANGLE_DEG.check("longitude_deg", longitude_deg))
    up = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(up, east)
    return Viewpoint((bottom_radius_m + altitude_m) * up, np.column_stack([east, north, up]))


def render_sky(solver, camera: Camera, viewpoint: Viewpoint, sun_dir: np.ndarray, star: Star, *,
               progress: Callable[[int], None] | None = None,
               ground: Ground | None = None, clouds: CloudField | None = None,
               sun_disk: bool = True) -> SkyImage:
    """Spectral image seen by `camera` from `viewpoint` with the sun along `sun_dir` (both in
    the viewpoint's local frame). `solver` answers `sky_radiance` and `transmittance`; with
    `ground` (an albedo map and/or terrain) the rays that meet it are shaded by
    `surfaces.surface_radiance`, with `clouds` the clouds are put in front
    (`transport.clouds.clouds_in_front`; both table solver only); without `sun_disk` the sun's
    disk is left out of the image (the image's `sun` still holds its light)."""
    profile = solver.profile
    directions, valid = camera.directions()
    world_sun = viewpoint.direction_to_world(sun_dir)
    spectral = camera_image(directions, valid, profile.n_wavelengths, lambda rays, mask: (
        diffuse_radiance(solver, viewpoint.position_m, rays, world_sun, ground=ground,
                         clouds=clouds, progress=progress, image_mask=mask)),
        viewpoint)
    # The visible part of a setting disk shines along the grazing ray; the planet hides the rest
    position = viewpoint.position_m
    sun_transmittance = solver.transmittance(
        position, towards_visible_sun(position, world_sun, profile.bottom_radius_m))
    if ground is not None and ground.terrain is not None and ground.terrain.shadowed(
            position, world_sun)[0]:
        sun_transmittance = np.zeros_like(sun_transmittance)  # the sun is behind a mountain
    if clouds is not None:
        sun_transmittance = sun_transmittance * cloud_transmittance(clouds, position,
                                                                    world_sun)[0]
    sun = add_sun_disk(spectral, camera, directions, valid, sun_dir, star=star,
                       wavelengths_nm=profile.wavelengths_nm, transmittance=sun_transmittance,
                       horizon_cos_zenith=horizon_cos_zenith(float(np.linalg.norm(position)),
                                                             profile.bottom_radius_m),
                       draw=sun_disk)
    return sky_image(spectral, directions, valid, viewpoint, profile,
                     sun=SunLight(sun, sun_dir, star.angular_radius_rad, sun_disk))


def without_ground(image: SkyImage, camera: Camera, radius_m: float,
                   bottom_radius_m: float) -> SkyImage:
    """`image` (of `camera`, seen from `radius_m` [m] from the planet's centre) with black
    wherever the view meets the planet (below the geometric horizon): the ground and the air in
    front of it, for an environment map whose lower half the engine draws itself."""
    directions, valid = camera.directions()
    below = valid & (directions[..., 2] < horizon_cos_zenith(radius_m, bottom_radius_m))
    return replace(image, spectral=np.where(below[..., None], 0.0, image.spectral))


def camera_image(directions: np.ndarray, valid: np.ndarray, n_wavelengths: int,
                 radiance_of: Callable[[np.ndarray, np.ndarray], np.ndarray],
                 viewpoint: Viewpoint) -> np.ndarray:
    """(h, w, n_wl) image of `radiance_of(world rays (n, 3), valid) -> (n, n_wl)` over a
    camera's `valid` pixels (h, w) (`directions` (h, w, 3) in the viewpoint's local frame; the
    rays are the valid pixels' in row-major order); 0 elsewhere."""
    world_directions = viewpoint.direction_to_world(directions)
    if bool(valid.all()):  # perspective and panorama: no masking, no copies
        radiance = radiance_of(world_directions.reshape(-1, 3), valid)
        return radiance.reshape(directions.shape[:2] + (n_wavelengths,))
    spectral = np.zeros(directions.shape[:2] + (n_wavelengths,))
    spectral[valid] = radiance_of(np.ascontiguousarray(world_directions[valid]), valid)
    return spectral


def diffuse_radiance(solver, position: np.ndarray, rays: np.ndarray, world_light: np.ndarray,
                     *, ground: Ground | None = None, clouds: CloudField | None = None,
                     progress: Callable[[int], None] | None = None,
                     image_mask: np.ndarray | None = None) -> np.ndarray:
    """Sky (and, with `ground`, surface) radiance (n, n_wl) [W m^-2 sr^-1 nm^-1] along world
    `rays` (n, 3) from `position`, lit from `world_light` with the profile's top-of-atmosphere
    irradiance; with `clouds` in front (`transport.clouds.clouds_in_front`, refined over the
    image whose `image_mask` (h, w) pixels the rays are, where given). `progress(n)` counts
    the rays done (with clouds, as their pass finishes them: the sky behind is quick)."""
    if clouds is not None:
        _check_cloud_solver(solver)
        behind, distance = _sky_and_surfaces(solver, position, rays, world_light,
                                             ground or Ground(), clouds, None)
        return clouds_in_front(solver, clouds, position, rays, world_light, behind=behind,
                               max_distance=distance, image_mask=image_mask,
                               progress=progress)
    if ground is None:
        return solver.sky_radiance(position, rays, world_light, progress)
    return _sky_and_surfaces(solver, position, rays, world_light, ground, None, progress)[0]


def _sky_and_surfaces(solver, position: np.ndarray, rays: np.ndarray, world_light: np.ndarray,
                      ground: Ground, clouds: CloudField | None,
                      progress: Callable[[int], None] | None) -> tuple[np.ndarray, np.ndarray]:
    """(radiance (n, n_wl), distance (n,) [m]): the sky along the rays that miss `ground`
    (distance inf), the surfaces (in the shadows of `clouds`) along those that meet it."""
    radiance = np.empty((rays.shape[0], solver.profile.n_wavelengths))
    surface, hit, distance = surface_radiance(solver, position, rays, world_light, ground,
                                              clouds=clouds, with_distance=True)
    hits, misses = np.flatnonzero(hit), np.flatnonzero(~hit)
    radiance[hits] = surface
    if progress is not None:
        progress(hits.size)
    radiance[misses] = solver.sky_radiance(position, rays[misses], world_light, progress)
    return radiance, distance


def _check_cloud_solver(solver) -> None:
    if not isinstance(solver, SurfaceSolver):
        raise InputError("clouds need the table solver (--solver lut)", key="solver",
                         value=getattr(solver, "name", solver), allowed="lut")


def sky_image(spectral: np.ndarray, directions: np.ndarray, valid: np.ndarray,
              viewpoint: Viewpoint, profile, *, sun: SunLight | None = None) -> SkyImage:
    """The SkyImage of a finished spectral image, with the pixels to meter: those looking
    above the horizontal, or, looking down from space, the lit ones."""
    sky = valid & (directions[..., 2] > 0.0)
    if not np.any(sky):  # looking down from space: meter on what is lit, not on black space
        lit = valid & np.any(spectral > 0.0, axis=-1)
        sky = lit if np.any(lit) else valid
    from_space = bool(np.linalg.norm(viewpoint.position_m) > profile.top_radius_m)
    return SkyImage(spectral, valid, sky, profile.wavelengths_nm, profile.toa_irradiance,
                    from_space, sun)


@lru_cache(maxsize=4)
def cached_pixel_solid_angles(camera: Camera) -> np.ndarray:
    """`camera.pixel_solid_angles()` (h, w) [sr], read-only, kept for the last few (frozen,
    hashable) cameras: the sun, the moon and the stars of every frame share one."""
    omega = camera.pixel_solid_angles()
    omega.flags.writeable = False
    return omega


def deposit_small_disk(spectral: np.ndarray, camera: Camera, valid: np.ndarray,
                       direction: np.ndarray, disk_solid_angle_sr: float, *,
                       irradiance: Callable[[], np.ndarray]) -> bool:
    """For a disk (sun, moon) smaller than `SPLAT_PIXELS` times the pixel that holds its centre:
    add its whole `irradiance()` (n_wl) [W m^-2 nm^-1] to that pixel as radiance (divided by
    the pixel's solid angle), so the image carries the disk's flux at any resolution. Returns
    True when the disk is done with (deposited, or behind a perspective camera), False when the
    caller must draw it pixel by pixel."""
    row, column = (float(v) for v in camera.direction_to_pixel(direction))
    if not (np.isfinite(row) and np.isfinite(column)):
        return True  # behind a perspective camera
    i, j = int(np.floor(row)), int(np.floor(column))
    if not (0 <= i < spectral.shape[0] and 0 <= j < spectral.shape[1]):
        return False  # centre outside the image: the visible part is drawn per pixel
    pixel = cached_pixel_solid_angles(camera)[i, j]
    if pixel * SPLAT_PIXELS <= disk_solid_angle_sr:
        return False
    if valid[i, j]:
        spectral[i, j] += irradiance() / pixel
    return True


def disk_visible_fraction(direction: np.ndarray, radius_rad: float,
                          occluder_direction: np.ndarray, occluder_radius_rad: float) -> float:
    """Fraction of a uniform disk (angular radius `radius_rad`, centre `direction`) not hidden
    by a nearer disk: 1 - overlap / (π r²), with the exact circle-overlap area
    (`lunar_eclipse.circle_overlap_area`) in the small-angle plane of the sky. [-]"""
    separation = float(np.arccos(np.clip(np.dot(direction, occluder_direction), -1.0, 1.0)))
    overlap = float(circle_overlap_area(radius_rad, occluder_radius_rad, separation))
    return max(0.0, 1.0 - overlap / (np.pi * radius_rad**2))


def add_sun_disk(spectral: np.ndarray, camera: Camera, directions: np.ndarray,
                 valid: np.ndarray, sun_dir: np.ndarray, *, star: Star,
                 wavelengths_nm: np.ndarray, transmittance: np.ndarray,
                 occluder: tuple[np.ndarray, float] | None = None,
                 horizon_cos_zenith: float = -1.0, draw: bool = True) -> np.ndarray:
    """Add the transmitted sun disk to `spectral` (h, w, n_wl) in place. `occluder`
    (direction, angular radius [rad]), e.g. the moon in a solar eclipse, hides the part of
    the disk behind it (a sub-pixel disk is dimmed by `disk_visible_fraction`, limb darkening
    left out there). The planet hides the part below the geometric horizon at local zenith
    cosine `horizon_cos_zenith` (a sub-pixel disk is dimmed by
    `geometry.disk_fraction_above`). Returns the sun's direct spectral irradiance at the camera
    normal to it (n_wl,) [W m^-2 nm^-1], its hidden part left out, whether or not the camera
    sees the disk; without `draw` only that, the image untouched."""
    visible = 1.0 if occluder is None else disk_visible_fraction(
        sun_dir, star.angular_radius_rad, *occluder)
    visible *= disk_fraction_above(float(sun_dir[2]), horizon_cos_zenith,
                                   star.angular_radius_rad)
    irradiance = star.irradiance_toa(wavelengths_nm) * transmittance * visible
    if not np.any(transmittance > 0.0) or visible <= 0.0:
        return np.zeros_like(irradiance)
    if not draw:
        return irradiance
    if deposit_small_disk(spectral, camera, valid, sun_dir, star.solid_angle_sr,
                          irradiance=lambda: irradiance):
        return irradiance
    sin_alpha = np.sin(star.angular_radius_rad)
    cos_angle = np.clip(directions @ sun_dir, -1.0, 1.0)
    inside = valid & (cos_angle > np.cos(star.angular_radius_rad))
    inside &= directions[..., 2] >= horizon_cos_zenith
    if occluder is not None:
        inside &= directions @ occluder[0] <= np.cos(occluder[1])
    if not np.any(inside):
        return irradiance
    sin_ratio = np.sqrt(1.0 - cos_angle[inside] ** 2) / sin_alpha
    cos_limb = np.sqrt(np.clip(1.0 - sin_ratio**2, 0.0, 1.0))
    spectral[inside] += star.disk_radiance(wavelengths_nm, cos_limb) * transmittance
