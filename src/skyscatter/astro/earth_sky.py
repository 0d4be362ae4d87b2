"""Sun and Moon seen from a place on Earth, and atmospheric refraction.

- `sun_position`, `moon_position`: topocentric azimuth and geometric (airless) altitude, via
  PyEphem (Rhodes, https://rhodesmill.org/pyephem/; libastro: VSOP87 for the Sun and its
  own lunar theory for the Moon) with pressure = 0, so no refraction is applied. Altitudes are
  apparent positions of date (aberration, nutation, light time, parallax included). The Moon's
  topocentric parallax (up to 1.0°) matters; the observer sits on the WGS 84 ellipsoid (NIMA
  TR8350.2) at geodetic latitude φ, east longitude λ, height h.
- `geocentric_sun_moon_m`: geocentric astrometric position vectors of Sun and Moon in the J2000
  equatorial frame [m], for eclipse geometry and the Moon's phase.
- `refraction_deg` (true -> apparent, Saemundsson 1986, Sky & Telescope 72, 70; Meeus (1998)
  eq. 16.4) and `true_altitude_deg` (apparent -> true, Bennett 1982, J. Navigation 35, 255,
  doi:10.1017/S0373463300022037; Meeus eq. 16.3), each scaled by Meeus's (P/1010)(283/(273+T))
  for pressure P [hPa] and temperature T [°C]; `refract` raises direction vectors by it.

Accuracy against astropy 8 (ERFA) measured in tests/astro/test_astro_earth_sky.py and
docs/physics/astronomy.md.

Public names: `SkyPosition`, `sun_position`, `moon_position`, `geocentric_sun_moon_m`,
`refraction_deg`, `true_altitude_deg`, `refract`, `AU_M`.
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass

import ephem
import numpy as np
from numpy.typing import ArrayLike

from skyscatter.astro.time import (
    check_elevation,
    check_latitude,
    check_longitude,
    check_utc,
    julian_date,
)
from skyscatter.errors import InputError

__all__ = [
    "AU_M",
    "SkyPosition",
    "geocentric_sun_moon_m",
    "moon_position",
    "refract",
    "refraction_deg",
    "sun_position",
    "true_altitude_deg",
]

AU_M = 149_597_870_700.0  # m, astronomical unit, exact (IAU 2012 Resolution B2)
_DUBLIN_JD = 2415020.0  # JD of ephem's day 0, 1899-12-31 12:00

# Refraction: below these altitudes (true for Saemundsson, apparent for Bennett) the formulas
# stop being physical (they peak near −1.9° and −1.7°, then fall); we taper linearly to 0 at
# _TAPER_END_DEG, which keeps true <-> apparent monotonic and `refract` continuous at the nadir.
_SAEMUNDSSON_TAPER_START_DEG = -1.5
_BENNETT_TAPER_START_DEG = -1.0
_TAPER_END_DEG = -5.0


@dataclass(frozen=True)
class SkyPosition:
    """Where a body is in an observer's sky.

    azimuth_deg: from north towards east, in [0, 360) [deg]; altitude_deg: geometric (airless)
    topocentric altitude [deg]; distance_m: observer (or, for the Sun seen from Mars, the
    planet's centre) to the body's centre [m].
    """

    azimuth_deg: float
    altitude_deg: float
    distance_m: float

    def direction(self) -> np.ndarray:
        """Unit vector towards the body in the local (east, north, up) frame, shape (3,). [-]"""
        az, alt = math.radians(self.azimuth_deg), math.radians(self.altitude_deg)
        return np.array([math.cos(alt) * math.sin(az), math.cos(alt) * math.cos(az),
                         math.sin(alt)])


def _observer(utc: datetime.datetime, latitude_deg: float, longitude_deg: float,
              elevation_m: float) -> ephem.Observer:
    t = check_utc(utc)
    lat = check_latitude(latitude_deg)
    lon = check_longitude(longitude_deg)
    h = check_elevation(elevation_m)
    observer = ephem.Observer()
    observer.lat = math.radians(lat)
    observer.lon = math.radians(lon)
    observer.elevation = h
    observer.pressure = 0.0  # no refraction: geometric altitude
    observer.date = julian_date(t) - _DUBLIN_JD
    return observer


def _topocentric(body: ephem.Body) -> SkyPosition:
    # With an Observer, PyEphem's earth_distance is already the topocentric distance (checked
    # against astropy in tests/astro/test_astro_earth_sky.py).
    return SkyPosition(math.degrees(float(body.az)) % 360.0, math.degrees(float(body.alt)),
                       float(body.earth_distance) * AU_M)


def sun_position(utc: datetime.datetime, latitude_deg: float, longitude_deg: float,
                 elevation_m: float = 0.0) -> SkyPosition:
    """The Sun's topocentric azimuth, geometric altitude and distance (PyEphem, no refraction).

    Parameters
    ----------
    utc : datetime.datetime
        Aware datetime.
    latitude_deg : float
        Geodetic latitude, north positive, in [-90, 90]. [deg]
    longitude_deg : float
        East longitude (wrapped). [deg]
    elevation_m : float
        Height above the WGS 84 ellipsoid, >= -500. [m]

    Returns
    -------
    SkyPosition
        Azimuth from north towards east [deg], airless altitude [deg], distance observer-Sun
        centre [m]. Agrees with astropy's apparent AltAz (pressure 0) to ≲ 0.001°.
    """
    observer = _observer(utc, latitude_deg, longitude_deg, elevation_m)
    sun = ephem.Sun()
    sun.compute(observer)
    return _topocentric(sun)


def moon_position(utc: datetime.datetime, latitude_deg: float, longitude_deg: float,
                  elevation_m: float = 0.0) -> SkyPosition:
    """The Moon's topocentric azimuth, geometric altitude and distance (PyEphem, no refraction).

    Topocentric: the parallax (up to 1.0° near the horizon) is included, and the distance is
    from the observer (it differs from the geocentric one by up to an Earth radius, 1.7 %).
    Parameters and units as `sun_position`.
    """
    observer = _observer(utc, latitude_deg, longitude_deg, elevation_m)
    moon = ephem.Moon()
    moon.compute(observer)
    return _topocentric(moon)


def geocentric_sun_moon_m(utc: datetime.datetime) -> tuple[np.ndarray, np.ndarray]:
    """Geocentric astrometric positions of the Sun and the Moon, J2000 equatorial frame [m].

        r = D (cos δ cos α, cos δ sin α, sin δ)

    with (α, δ) PyEphem's astrometric J2000 right ascension and declination (light time
    included) and D its geocentric distance. Returns (sun, moon), each shape (3,).
    """
    date = julian_date(check_utc(utc)) - _DUBLIN_JD
    out = []
    for body in (ephem.Sun(), ephem.Moon()):
        body.compute(date, epoch=ephem.J2000)
        ra, dec = float(body.a_ra), float(body.a_dec)
        distance = float(body.earth_distance) * AU_M
        out.append(distance * np.array([math.cos(dec) * math.cos(ra),
                                        math.cos(dec) * math.sin(ra), math.sin(dec)]))
    return out[0], out[1]


def _weather_factor(pressure_hpa: ArrayLike, temperature_c: ArrayLike) -> np.ndarray:
    """Meeus (1998) p. 107: refraction scales with (P/1010 hPa)(283 K/(273 K + T))."""
    p = np.asarray(pressure_hpa, dtype=np.float64)
    t = np.asarray(temperature_c, dtype=np.float64)
    if np.any(~np.isfinite(p)) or np.any(p < 0.0):
        raise InputError(f"pressure_hpa = {pressure_hpa!r} must be finite and >= 0 [hPa]",
                         key="pressure_hpa", value=pressure_hpa, allowed=">= 0 hPa")
    if np.any(~np.isfinite(t)) or np.any(t <= -273.0):
        raise InputError(f"temperature_c = {temperature_c!r} must be finite and > -273 [°C]",
                         key="temperature_c", value=temperature_c, allowed="> -273 °C")
    return (p / 1010.0) * (283.0 / (273.0 + t))


def _tapered(formula, h: np.ndarray, start_deg: float) -> np.ndarray:
    """formula(h) [arcmin] for h >= start, linear to 0 at −5°, 0 below; >= 0; h in [-90, 90]."""
    r_start = formula(np.float64(start_deg))
    above = formula(np.maximum(h, start_deg))
    ramp = r_start * np.clip((h - _TAPER_END_DEG) / (start_deg - _TAPER_END_DEG), 0.0, 1.0)
    return np.maximum(np.where(h >= start_deg, above, ramp), 0.0)


def _saemundsson_arcmin(h: np.ndarray) -> np.ndarray:
    return 1.02 / np.tan(np.radians(h + 10.3 / (h + 5.11)))


def _bennett_arcmin(h0: np.ndarray) -> np.ndarray:
    return 1.0 / np.tan(np.radians(h0 + 7.31 / (h0 + 4.4)))


def refraction_deg(true_altitude_deg: ArrayLike, pressure_hpa: ArrayLike = 1010.0,
                   temperature_c: ArrayLike = 10.0) -> np.ndarray:
    """Atmospheric refraction R for a body at a true (airless) altitude h: apparent = h + R.

        R = 1.02' / tan(h + 10.3°/(h + 5.11°)) × (P/1010)(283/(273 + T))

    Saemundsson (1986), Sky & Telescope 72, 70; Meeus (1998) eq. 16.4 with the pressure and
    temperature factor of p. 107. 28.9' at h = 0, 34.4' at h = −0.575° (a body on the apparent
    horizon), 0 at the zenith (R is clipped at 0, which it reaches at h ≈ 89.9°). Below
    h = −1.5° (where R = 43.2') the formula stops being physical (it peaks at −1.9°); R is
    tapered linearly to 0 at h = −5° and is 0 below, so R is finite and continuous everywhere
    and h + R increases with h.
    Altitudes are clipped to [-90, 90].

    Parameters
    ----------
    true_altitude_deg : array_like, shape S
        True altitude h. [deg]
    pressure_hpa : array_like, broadcasts with S
        Air pressure at the observer, >= 0. [hPa]
    temperature_c : array_like, broadcasts with S
        Air temperature at the observer, > -273. [°C]

    Returns
    -------
    ndarray, broadcast shape
        Refraction R >= 0. [deg]
    """
    factor = _weather_factor(pressure_hpa, temperature_c)
    h = np.clip(np.asarray(true_altitude_deg, dtype=np.float64), -90.0, 90.0)
    return _tapered(_saemundsson_arcmin, h, _SAEMUNDSSON_TAPER_START_DEG) / 60.0 * factor


def true_altitude_deg(apparent_altitude_deg: ArrayLike, pressure_hpa: ArrayLike = 1010.0,
                      temperature_c: ArrayLike = 10.0) -> np.ndarray:
    """True (airless) altitude h = h0 − R of a body seen at apparent altitude h0.

        R = 1' / tan(h0 + 7.31°/(h0 + 4.4°)) × (P/1010)(283/(273 + T))

    Bennett (1982), J. Navigation 35, 255, doi:10.1017/S0373463300022037; Meeus (1998) eq.
    16.3 (accurate to 0.07' for 0° <= h0 <= 90°). 34.5' at the apparent horizon, clipped at 0
    near the zenith; tapered linearly to 0 from h0 = −1° (R = 49.8') to h0 = −5°, as in
    `refraction_deg`. The inverse of `refraction_deg` to ≲ 0.1' above −0.5°.

    Parameters
    ----------
    apparent_altitude_deg : array_like, shape S
        Apparent altitude h0. [deg]
    pressure_hpa, temperature_c : array_like
        As `refraction_deg`. [hPa], [°C]

    Returns
    -------
    ndarray, broadcast shape
        True altitude. [deg]
    """
    factor = _weather_factor(pressure_hpa, temperature_c)
    h0 = np.clip(np.asarray(apparent_altitude_deg, dtype=np.float64), -90.0, 90.0)
    return h0 - _tapered(_bennett_arcmin, h0, _BENNETT_TAPER_START_DEG) / 60.0 * factor


def refract(directions_enu: ArrayLike, pressure_hpa: ArrayLike = 1010.0,
            temperature_c: ArrayLike = 10.0) -> np.ndarray:
    """Apparent directions: true (east, north, up) directions raised by `refraction_deg`.

    Refraction acts in the vertical plane: the azimuth is kept and the altitude h becomes
    h + R(h). Directions need not be unit vectors; results are. A direction straight up or
    down is returned unchanged (R is 0 there).

    Parameters
    ----------
    directions_enu : array_like, shape (..., 3)
        True directions, nonzero. [-]
    pressure_hpa, temperature_c : array_like
        Broadcast with the shape (...). [hPa], [°C]

    Returns
    -------
    ndarray, shape (..., 3)
        Apparent unit directions. [-]
    """
    v = np.asarray(directions_enu, dtype=np.float64)
    if v.shape[-1:] != (3,):
        raise InputError(f"directions_enu has shape {v.shape}; it must be (..., 3)",
                         key="directions_enu", value=v.shape, allowed="shape (..., 3)")
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    u = v / np.where(norm > 0.0, norm, 1.0)
    horizontal = np.hypot(u[..., 0], u[..., 1])
    altitude = np.degrees(np.arctan2(u[..., 2], horizontal))
    apparent = np.radians(altitude + refraction_deg(altitude, pressure_hpa, temperature_c))
    scale = np.where(horizontal > 0.0, np.cos(apparent) / np.where(horizontal > 0.0,
                                                                    horizontal, 1.0), 0.0)
    out = np.empty(np.broadcast_shapes(u.shape, apparent.shape + (3,)))
    out[..., 0] = u[..., 0] * scale
    out[..., 1] = u[..., 1] * scale
    out[..., 2] = np.where(horizontal > 0.0, np.sin(apparent), u[..., 2])
    return out
