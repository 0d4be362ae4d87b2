"""The whole sky for a date, time and place: atmosphere, sun, moon and stars together.

`ephemeris(body, observer)` gathers the astronomy of one instant (astro/): the sun's and the
moon's topocentric positions and the rotation from J2000 to the observer's east-north-up frame.
`render_sky_at(...)` then composes, in physical units (W m⁻² sr⁻¹ nm⁻¹):

1. the sky lit by the sun, from its geometric (airless) direction, through civil, nautical and
   astronomical twilight down to sun zenith 110° (`NIGHT_SUN_ZENITH_DEG`; below it the sunlit
   sky is left out), scaled by (d_preset / d_date)² for the sun's distance on that date;
2. the sky lit by the moon (Earth): the same solver with the moon's direction, times the moon's
   spectral irradiance over the sun's (`render.moon.moon_irradiance`); scattering is linear
   in the source, so one set of tables serves both lights;
3. the sun's disk at its refracted (apparent) position, its angular size from the distance of
   the date, limb-darkened and transmitted (red at sunset);
4. the moon's disk (phase, earthshine, eclipses: `render.moon`, `render.lunar_eclipse`, the
   air's grazing transmittance and bending from `eclipse_optics`), and
   on Earth the airglow of the upper atmosphere seen through the air (`render.airglow`);
5. the stars of the Hipparcos 2 catalogue moved by proper motion and precessed to the date,
   refracted, dimmed by the transmittance along each line of sight, optionally twinkling, and
   the integrated light of the unresolved stars (Milky Way) as an option (`render.stars`).

Refraction moves what is seen through the air (disks and stars; Saemundsson 1986 via
`astro.earth_sky.refract`), not the light that scatters in it (the tables assume straight
rays), so the sky is lit by the sun's geometric direction as osgHimmel does (Müller 2012, M.Sc.
thesis, Hasso-Plattner-Institut; github.com/cgcostume/osghimmel, src/atmospheregeode.cpp).
"""

from __future__ import annotations

import dataclasses
import datetime
import functools
import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from skyscatter.astro.earth_sky import (
    SkyPosition,
    geocentric_sun_moon_m,
    moon_position,
    refract,
    sun_position,
)
from skyscatter.astro.frames import j2000_to_horizon_matrix, mars_j2000_to_horizon_matrix
from skyscatter.astro.mars_time import mars_sun_position
from skyscatter.astro.moon_phase import EARTH_SHADOW_RADIUS_M, eclipse_magnitudes
from skyscatter.astro.star_catalogue import load_star_catalogue
from skyscatter.errors import InputError
from skyscatter.render.airglow import airglow_radiance
from skyscatter.render.camera import Camera
from skyscatter.render.lunar_eclipse import eclipse_factor
from skyscatter.render.moon import MoonGeometry, add_moon_disk, moon_irradiance
from skyscatter.render.scene import (
    SkyImage,
    SunLight,
    Viewpoint,
    add_sun_disk,
    camera_image,
    diffuse_radiance,
    disk_visible_fraction,
    sky_image,
)
from skyscatter.render.stars import (
    add_star_background,
    add_stars,
    airmass_kasten_young_1989,
    scintillation_factors,
)
from skyscatter.render.surfaces import Ground
from skyscatter.spectrum.magnitudes import colour_temperature_from_b_minus_v, stellar_irradiance
from skyscatter.spectrum.star import Star
from skyscatter.transport.clouds import CloudField, cloud_transmittance
from skyscatter.transport.limb import grazing_deflection_rad, grazing_transmittance
from skyscatter.transport.solvers import Solver, TableSolver

__all__ = ["BODIES", "EclipseOptics", "Ephemeris", "MoonLight", "Observer", "SkyObjects",
           "apparent_directions", "eclipse_optics", "ephemeris", "moon_light", "render_sky_at",
           "star_field"]

BODIES = ("earth", "mars")
# Mean obliquity of the ecliptic at J2000, 84381.406" (IAU 2006, Hilton et al. 2006, Celest.
# Mech. Dyn. Astr. 94, 351): the ecliptic north pole in J2000 equatorial coordinates is
# (0, -sin ε, cos ε). The moon's spin axis is within 1.54° of it (Cassini's laws).
_OBLIQUITY_J2000_RAD = math.radians(84381.406 / 3600.0)
ECLIPTIC_NORTH_POLE_J2000 = np.array([0.0, -math.sin(_OBLIQUITY_J2000_RAD),
                                      math.cos(_OBLIQUITY_J2000_RAD)])
# Refraction: standard air at the ground for Earth (Meeus ch. 16: 1010 hPa, 10 °C); Mars' mean
# surface pressure 6.1 hPa (NASA Mars fact sheet) at 210 K scales it to under 0.01°.
_REFRACTION_AIR = {"earth": (1010.0, 10.0), "mars": (6.1, -63.0)}
# Below this sun the sunlit sky is left out: at sun zenith 110° Earth's zenith sky is 3.3e-7 cd
# m⁻² (the tables, `earth` preset), 0.2 % of the airglow's 1.6e-4; each 2° lower divides it by 7
NIGHT_SUN_ZENITH_DEG = 110.0
LOWEST_AIRGLOW_M = 85e3  # m; observers above the OH layer see no airglow overhead (left out)
_CHUNK_RAYS = 1 << 16  # rays per pass of the airglow


@dataclass(frozen=True)
class Observer:
    """Where and when: an aware UTC time, planetographic latitude [deg] (north positive),
    longitude [deg] (east positive) and elevation above the ground [m]."""

    time_utc: datetime.datetime
    latitude_deg: float
    longitude_deg: float
    elevation_m: float = 0.0


@dataclass(frozen=True)
class SkyObjects:
    """What is drawn besides the atmosphere and the sun.

    stars            the catalogue's stars down to `magnitude_limit` (None: all 117 955)
    moon             the moon's disk and moonlight in the sky (Earth)
    airglow          the night glow of the upper atmosphere (Earth; `render.airglow`)
    milky_way        the integrated light of the stars fainter than the catalogue
    scintillation    a random generator: each star's brightness twinkles (one draw per frame)
    sun_disk         the sun's disk (without it the image's `sun` still holds its light)
    """

    stars: bool = True
    moon: bool = True
    milky_way: bool = False
    airglow: bool = True
    magnitude_limit: float | None = None
    scintillation: np.random.Generator | None = None
    sun_disk: bool = True

    def __post_init__(self) -> None:
        limit = self.magnitude_limit
        if limit is not None and not (isinstance(limit, numbers.Real)
                                      and not isinstance(limit, bool) and math.isfinite(limit)):
            raise InputError(f"magnitude limit {limit!r} must be a finite V magnitude",
                             key="magnitude_limit", value=limit, allowed="finite numbers")


@dataclass(frozen=True)
class EclipseOptics:
    """The planet's air for the light in the umbra (`lunar_eclipse.eclipse_factor`):
    `grazing_transmittance(tangent altitudes (k,) [m]) -> (k, n_wl)`, `grazing_deflection(
    tangent altitudes) -> (k,)` [rad] (`transport.limb`), the planet's radius and the top of
    its refracting air [m]."""

    grazing_transmittance: Callable[[np.ndarray], np.ndarray]
    grazing_deflection: Callable[[np.ndarray], np.ndarray]
    planet_radius_m: float
    top_altitude_m: float


def eclipse_optics(solver: Solver) -> EclipseOptics | None:
    """The grazing transmittance and bending of the planet's air (`transport.limb`), for the
    light in the umbra; None when the solver has no transmittance table or the air no
    Rayleigh gas."""
    if not isinstance(solver, TableSolver):
        return None
    try:
        grazing_deflection_rad(solver.profile, [0.0])
    except InputError:
        return None
    profile = solver.profile
    return EclipseOptics(
        grazing_transmittance=lambda heights: grazing_transmittance(solver, heights),
        grazing_deflection=lambda heights: grazing_deflection_rad(profile, heights),
        planet_radius_m=profile.bottom_radius_m,
        top_altitude_m=profile.top_radius_m - profile.bottom_radius_m)


@dataclass(frozen=True)
class Ephemeris:
    """The astronomy of one instant for one observer (positions are topocentric, airless)."""

    body: str
    observer: Observer
    sun: SkyPosition
    moon: SkyPosition | None  # None on Mars
    to_horizon: np.ndarray  # (3, 3): J2000 equatorial unit vectors -> local east-north-up
    sun_geocentric_m: np.ndarray | None  # (3,) J2000, Earth only (eclipses)
    moon_geocentric_m: np.ndarray | None

    @property
    def sun_zenith_deg(self) -> float:
        return 90.0 - self.sun.altitude_deg


def ephemeris(body: str, observer: Observer) -> Ephemeris:
    """Sun, moon and sky orientation for `observer` on `body` ("earth" or "mars")."""
    if body not in BODIES:
        raise InputError(
            "this planet has no ephemeris (its config has no [planet] body), so --time cannot "
            "place the sun; give --sun-zenith/--sun-azimuth instead, or use an Earth or Mars "
            "preset", key="body", value=body, allowed=", ".join(BODIES))
    o = observer
    if body == "mars":
        return Ephemeris(body, o, mars_sun_position(o.time_utc, o.latitude_deg, o.longitude_deg),
                         None, mars_j2000_to_horizon_matrix(o.time_utc, o.latitude_deg,
                                                            o.longitude_deg), None, None)
    sun_geo, moon_geo = geocentric_sun_moon_m(o.time_utc)
    return Ephemeris(
        body, o, sun_position(o.time_utc, o.latitude_deg, o.longitude_deg, o.elevation_m),
        moon_position(o.time_utc, o.latitude_deg, o.longitude_deg, o.elevation_m),
        j2000_to_horizon_matrix(o.time_utc, o.latitude_deg, o.longitude_deg), sun_geo, moon_geo)


def render_sky_at(solver, camera: Camera, viewpoint: Viewpoint, star: Star, sky: Ephemeris, *,
                  objects: SkyObjects | None = None,
                  progress: Callable[[int], None] | None = None,
                  ground: Ground | None = None,
                  eclipse_optics: EclipseOptics | None = None,
                  clouds: CloudField | None = None) -> SkyImage:
    """Spectral image of the sky of `sky` (an `ephemeris`) seen by `camera` from `viewpoint`
    (its local frame is the observer's east-north-up frame). `star` is the planet's star as
    configured; its distance is replaced by the date's. `eclipse_optics` gives the grazing
    transmittance and refraction of the planet's air for the light in the umbra (lunar
    eclipses; None: the umbra is dark). `clouds` are lit by the sun and the moon and hide
    what lies behind them (`transport.clouds`)."""
    objects = objects or SkyObjects()
    profile = solver.profile
    wavelengths = profile.wavelengths_nm
    position = viewpoint.position_m
    directions, valid = camera.directions()
    sun_today = dataclasses.replace(star, distance_m=sky.sun.distance_m)
    distance_scale = star.irradiance_scale_at(sky.sun.distance_m)
    sun_true = sky.sun.direction()
    lights = []
    moon = None
    if objects.moon and sky.moon is not None and sky.moon.altitude_deg > -5.0:
        moon = moon_light(sky, sun_today, wavelengths, eclipse_optics)
    sun_visible = 1.0 if moon is None else disk_visible_fraction(  # solar eclipses
        sun_true, sun_today.angular_radius_rad, sky.moon.direction(),
        moon.geometry.angular_radius_rad)
    if _sun_lights_the_sky(solver, sun_true) and sun_visible > 0.0:
        lights.append((viewpoint.direction_to_world(sun_true), distance_scale * sun_visible))
    if moon is not None and np.any(moon.irradiance > 0.0):
        lights.append((viewpoint.direction_to_world(sky.moon.direction()),
                       moon.irradiance / profile.toa_irradiance))

    observer_radius = float(np.linalg.norm(position))
    glow = (objects.airglow and sky.body == "earth"
            and observer_radius < profile.bottom_radius_m + LOWEST_AIRGLOW_M)

    def radiance_of(rays: np.ndarray, mask: np.ndarray) -> np.ndarray:
        total = np.zeros((rays.shape[0], profile.n_wavelengths)) if not lights else None
        for index, (world_light, scale) in enumerate(lights):  # the solver chunks the rays
            lit = diffuse_radiance(solver, position, rays, world_light, ground=ground,
                                   clouds=clouds, image_mask=mask,
                                   progress=progress if index == 0 else None)  # count once
            lit *= scale
            if index == 0:
                total = lit
            else:
                total += lit
        for start in range(0, rays.shape[0] if glow else 0, _CHUNK_RAYS):  # small temporaries
            chunk = rays[start:start + _CHUNK_RAYS]
            airglow = airglow_radiance(chunk @ position / observer_radius, wavelengths,
                                       observer_radius, profile.bottom_radius_m)
            airglow *= _world_transmittance(solver, position, chunk, ground, clouds)
            total[start:start + _CHUNK_RAYS] += airglow
        return total

    spectral = camera_image(directions, valid, profile.n_wavelengths, radiance_of, viewpoint)
    pressure, temperature = _REFRACTION_AIR[sky.body]
    sun_seen = refract(sun_true, pressure, temperature)
    moon_seen = None if moon is None else refract(sky.moon.direction(), pressure, temperature)
    sun = add_sun_disk(spectral, camera, directions, valid, sun_seen, star=sun_today,
                       wavelengths_nm=wavelengths,
                       transmittance=_transmittance(solver, viewpoint, sun_seen[None], ground,
                                                    clouds)[0],
                       occluder=None if moon is None else (moon_seen,
                                                           moon.geometry.angular_radius_rad),
                       draw=objects.sun_disk)
    if moon is not None:
        seen = dataclasses.replace(moon.geometry, moon_direction=moon_seen)
        add_moon_disk(spectral, camera, directions, valid, seen, wavelengths_nm=wavelengths,
                      solar_irradiance_at_moon=moon.solar_irradiance,
                      transmittance=_transmittance(solver, viewpoint, moon_seen[None], ground,
                                                    clouds)[0],
                      eclipse=moon.eclipse, irradiance=moon.irradiance)
    if objects.stars:
        _add_catalogue_stars(spectral, camera, valid, solver, viewpoint, sky, objects,
                             wavelengths, ground, clouds)
    if objects.milky_way:
        add_star_background(spectral, valid, directions, sky.to_horizon, wavelengths,
                            transmittance_of=lambda rays: _transmittance(
                                solver, viewpoint, rays, ground, clouds),
                            magnitude_limit=objects.magnitude_limit)
    return sky_image(spectral, directions, valid, viewpoint, profile,
                     sun=SunLight(sun, sun_seen, sun_today.angular_radius_rad, objects.sun_disk))


def _sun_lights_the_sky(solver: Solver, sun_true: np.ndarray) -> bool:
    """True while the sun is higher than `NIGHT_SUN_ZENITH_DEG` and than the lowest sun the
    solver's tables hold; below that the sunlit sky is left out."""
    lowest = solver.tables.min_cos_sun_zenith if isinstance(solver, TableSolver) else -1.0
    return bool(sun_true[2] >= max(lowest, math.cos(math.radians(NIGHT_SUN_ZENITH_DEG))))


def _transmittance(solver, viewpoint: Viewpoint, local_directions: np.ndarray,
                   ground: Ground | None, clouds: CloudField | None = None) -> np.ndarray:
    """Transmittance (n, n_wl) from the observer out of the atmosphere along local directions;
    0 where the planet (or terrain) is in the way."""
    world = viewpoint.direction_to_world(np.asarray(local_directions, dtype=np.float64))
    return _world_transmittance(solver, viewpoint.position_m, world, ground, clouds)


def _world_transmittance(solver, position: np.ndarray, world: np.ndarray,
                         ground: Ground | None, clouds: CloudField | None = None) -> np.ndarray:
    """`_transmittance` for world directions (n, 3) from `position`, through `clouds` too."""
    if clouds is not None:
        return (_world_transmittance(solver, position, world, ground)
                * cloud_transmittance(clouds, position, world))
    along = world @ position
    radius = solver.profile.bottom_radius_m
    blocked = (along < 0.0) & (position @ position - along**2 < radius**2)
    if ground is not None and ground.terrain is not None:
        blocked |= ground.terrain.shadowed(position, world)
    if not np.any(blocked):  # a sky view: no masked copies
        return solver.transmittance(position, world)
    result = np.zeros((world.shape[0], solver.profile.n_wavelengths))
    if not np.all(blocked):
        result[~blocked] = solver.transmittance(position, world[~blocked])
    return result


@dataclass(frozen=True)
class MoonLight:
    """The moon of an `Ephemeris` as a light source and a disk to draw."""

    geometry: MoonGeometry  # true (airless) directions, the observer's east-north-up frame
    solar_irradiance: np.ndarray  # (n_wl,) sunlight at the moon [W m⁻² nm⁻¹]
    eclipse: Callable[[np.ndarray], np.ndarray] | None
    irradiance: np.ndarray  # (n_wl,) the moon's light at the top of the air [W m⁻² nm⁻¹]


def moon_light(sky: Ephemeris, sun: Star, wavelengths: np.ndarray,
                optics: EclipseOptics | None) -> MoonLight:
    """The moon's geometry, its sunlight, the eclipse shading near full moon, and the
    disk-integrated moonlight (`moon.moon_irradiance`)."""
    geometry = MoonGeometry(sky.moon.direction(), sky.moon.distance_m, sky.sun.direction(),
                            sky.to_horizon @ ECLIPTIC_NORTH_POLE_J2000, sky.sun.distance_m)
    solar = sun.irradiance_toa(wavelengths)
    eclipse = _eclipse(sky, optics, wavelengths)
    return MoonLight(geometry, solar, eclipse,
                 moon_irradiance(geometry, wavelengths, solar, eclipse=eclipse))


def _eclipse(sky: Ephemeris, optics: EclipseOptics | None, wavelengths: np.ndarray
             ) -> Callable[[np.ndarray], np.ndarray] | None:
    """`eclipse(points (n, 3) relative to the observer, east-north-up [m]) -> (n, n_wl)`, the
    sunlight reaching those points of the moon in the Earth's shadow; None when the moon is
    outside the penumbra (`astro.moon_phase.eclipse_magnitudes`)."""
    if sky.moon_geocentric_m is None:
        return None
    _, penumbral_magnitude = eclipse_magnitudes(sky.moon_geocentric_m, sky.sun_geocentric_m)
    if penumbral_magnitude < -0.05:  # the moon clear of the penumbra (with a margin)
        return None
    to_j2000 = sky.to_horizon.T
    # the observer relative to the Earth's centre: the geocentric moon minus the topocentric
    observer_j2000 = sky.moon_geocentric_m - to_j2000 @ (sky.moon.distance_m
                                                         * sky.moon.direction())

    if optics is None:  # no air: the bare geometric shadow
        def no_light(heights: np.ndarray) -> np.ndarray:
            return np.zeros((np.size(heights), wavelengths.size))

        optics = EclipseOptics(no_light, lambda heights: np.zeros(np.size(heights)),
                               EARTH_SHADOW_RADIUS_M, 0.0)

    def eclipse(points_enu: np.ndarray) -> np.ndarray:
        points = observer_j2000 + points_enu @ sky.to_horizon
        return eclipse_factor(points, sky.sun_geocentric_m, optics.grazing_transmittance,
                              optics.grazing_deflection, earth_radius_m=optics.planet_radius_m,
                              top_altitude_m=optics.top_altitude_m)

    return eclipse


def apparent_directions(sky: Ephemeris, local_directions: np.ndarray) -> np.ndarray:
    """True east-north-up directions (..., 3) as seen through the planet's air: refracted with
    its standard surface air (`astro.earth_sky.refract`), as the sun, moon and stars are drawn."""
    return refract(local_directions, *_REFRACTION_AIR[sky.body])


def star_field(sky: Ephemeris, magnitude_limit: float | None,
               wavelengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The catalogue's stars above the horizon: refracted unit directions (n, 3) in the
    observer's east-north-up frame and spectral irradiance above the air (n, n_wl)
    [W m^-2 nm^-1], for `sky`'s time and place."""
    catalogue = load_star_catalogue(magnitude_limit)
    seen = apparent_directions(sky, catalogue.directions_at(sky.observer.time_utc)
                               @ sky.to_horizon.T)
    up = np.flatnonzero(seen[:, 2] > 0.0)
    return seen[up], _star_irradiance(magnitude_limit, tuple(wavelengths))[up]


def _add_catalogue_stars(spectral, camera, valid, solver, viewpoint, sky: Ephemeris,
                         objects: SkyObjects, wavelengths, ground, clouds):
    seen, irradiance = star_field(sky, objects.magnitude_limit, wavelengths)
    transmittance = _transmittance(solver, viewpoint, seen, ground, clouds)
    twinkle = None
    if objects.scintillation is not None:
        airmass = airmass_kasten_young_1989(np.degrees(np.arccos(seen[:, 2])))
        twinkle = scintillation_factors(airmass, objects.scintillation,
                                        altitude_m=sky.observer.elevation_m)
    add_stars(spectral, camera, valid, seen, irradiance, transmittance=transmittance,
              scintillation=twinkle)


@functools.lru_cache(maxsize=4)
def _star_irradiance(magnitude_limit: float | None, wavelengths: tuple[float, ...]) -> np.ndarray:
    """Top-of-atmosphere spectral irradiance (n_stars, n_wl) of the catalogue's stars."""
    catalogue = load_star_catalogue(magnitude_limit)
    temperature = colour_temperature_from_b_minus_v(catalogue.b_minus_v)
    return stellar_irradiance(catalogue.v_magnitude, temperature, np.asarray(wavelengths))
