r"""The Moon's phase, bright limb, apparent size and the Earth's shadow: geometry from vectors.

Every function takes positions as Cartesian vectors [m] in any one frame (J2000, ecliptic,
east-north-up, ...); only their differences and angles are used, so the frame only has to be
the same for all arguments. Topocentric vectors give the topocentric phase; geocentric ones the
geocentric phase and the shadow geometry of lunar eclipses.

- `phase_angle_rad`: the angle i at the Moon between the Sun and the observer,
  cos i = û_sun · û_obs (Meeus 1998, *Astronomical Algorithms*, 2nd ed., ch. 48, eq. 48.2 in
  vector form; exact for the given vectors).
- `illuminated_fraction`: k = (1 + cos i) / 2 (Meeus eq. 48.1), the illuminated fraction of the
  disk's area for a sphere lit by a point sun.
- `bright_limb_direction` / `bright_limb_position_angle_rad`: the direction on the sky from the
  Moon's centre towards the Sun's side, and its position angle χ from the celestial north pole
  through east (Meeus eq. 48.5 gives χ from right ascensions and declinations, with the Earth-Sun
  instead of the Moon-Sun direction; here it is the exact projection of the Moon-Sun vector).
- `moon_angular_radius_rad`: asin(R_moon / d), R_moon = 1737.4 km (IAU WGCCRE mean radius,
  Archinal et al. 2018, Celest. Mech. Dyn. Astron. 130, 22, doi:10.1007/s10569-017-9805-5).
- `shadow_radii_rad`, `shadow_axis_distance_rad`, `eclipse_magnitudes`: the angular radii of
  the Earth's umbra and penumbra at the Moon's distance, seen from the Earth's centre,

      ρ_u = π_1 + π_s - s,   ρ_p = π_1 + π_s + s,
      π_1 = asin(R_⊕/D_m),   π_s = asin(R_⊕/D_s),   s = asin(R_⊙/D_s)

  (the seed's eqs. 4.12-4.13 multiplied by r_m/D_m; Explanatory Supplement to the Astronomical
  Almanac (Seidelmann 1992) §8.4; Meeus 1998 ch. 54), the Earth's radius taken at 45° latitude
  (0.998340 × equatorial, Meeus ch. 54) and enlarged for the opaque lower atmosphere either by
  Danjon's rule (R_⊕ × (1 + 1/85); Danjon 1951, Bull. Astron. 15, 259; used by Espenak & Meeus
  2009, *Five Millennium Canon of Lunar Eclipses*, NASA/TP-2009-214172, §1.4) or by
  Chauvenet's rule (both radii × 1.02; Chauvenet 1891, *Manual of Spherical and Practical
  Astronomy*, vol. 1, p. 549). Magnitudes (Espenak & Meeus 2009 §1.4):
  umbral = (ρ_u + s_m - θ) / (2 s_m), penumbral = (ρ_p + s_m - θ) / (2 s_m), where θ is the
  angle between the Moon and the anti-Sun direction seen from the Earth's centre and s_m the
  Moon's geocentric semi-diameter.

Public names: `MOON_RADIUS_M`, `EARTH_EQUATORIAL_RADIUS_M`, `EARTH_SHADOW_RADIUS_M`,
`SUN_RADIUS_M`, `SHADOW_ENLARGEMENTS`, `phase_angle_rad`, `illuminated_fraction`,
`bright_limb_direction`, `bright_limb_position_angle_rad`, `moon_angular_radius_rad`,
`shadow_radii_rad`, `shadow_axis_distance_rad`, `eclipse_magnitudes`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError

__all__ = [
    "EARTH_EQUATORIAL_RADIUS_M",
    "EARTH_SHADOW_RADIUS_M",
    "MOON_RADIUS_M",
    "SHADOW_ENLARGEMENTS",
    "SUN_RADIUS_M",
    "bright_limb_direction",
    "bright_limb_position_angle_rad",
    "eclipse_magnitudes",
    "illuminated_fraction",
    "moon_angular_radius_rad",
    "phase_angle_rad",
    "shadow_axis_distance_rad",
    "shadow_radii_rad",
]

MOON_RADIUS_M = 1_737_400.0  # m, mean radius (IAU WGCCRE 2015; Archinal et al. 2018)
EARTH_EQUATORIAL_RADIUS_M = 6_378_137.0  # m, GRS80 / IERS Conventions 2010 (Petit & Luzum)
# m; the Earth's radius at 45° latitude used for shadow cones: 0.998340 x equatorial (Meeus 1998,
# ch. 54: π_1 = 0.998340 π); the Earth is treated as a sphere of this radius.
EARTH_SHADOW_RADIUS_M = 0.998340 * EARTH_EQUATORIAL_RADIUS_M
SUN_RADIUS_M = 6.957e8  # m, nominal (IAU 2015 B3); same as spectrum.star.SOLAR_RADIUS_M
# Ways to enlarge the geometric shadow for the Earth's opaque lower atmosphere:
# "danjon": Earth's radius x (1 + 1/85) (Danjon 1951); "chauvenet": both shadow radii x 1.02
# (Chauvenet 1891); "none": geometric shadow of the solid Earth.
SHADOW_ENLARGEMENTS = ("danjon", "chauvenet", "none")
_DANJON_FACTOR = 1.0 + 1.0 / 85.0  # Danjon (1951): atmosphere opaque to ~75 km
_CHAUVENET_FACTOR = 1.02  # Chauvenet (1891): the "2 % rule"


def _vectors(value: ArrayLike, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.ndim == 0 or v.shape[-1] != 3:
        raise InputError(f"{name} must have shape (..., 3) (x, y, z in metres); got {v.shape}",
                         key=name, value=v.shape, allowed="(..., 3)")
    if not np.all(np.isfinite(v)):
        raise InputError(f"{name} must be finite", key=name, value=value, allowed="finite")
    return v


def _unit(v: np.ndarray, name: str) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm <= 0.0):
        raise InputError(f"{name} must not be a zero vector", key=name, value=v,
                         allowed="non-zero (..., 3)")
    return v / norm


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between vectors (..., 3), accurate at 0 and π (atan2 of |a × b| and a · b). [rad]"""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def _positive(value: ArrayLike, name: str) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if not np.all(np.isfinite(v) & (v > 0.0)):
        raise InputError(f"{name} must be finite and > 0 [m]; got {value!r}", key=name,
                         value=value, allowed="> 0 [m]")
    return v


def phase_angle_rad(moon_position_m: ArrayLike, sun_position_m: ArrayLike) -> np.ndarray:
    """Phase angle i: the angle at the Moon's centre between the Sun and the observer.

        i = ∠(r_sun - r_moon, -r_moon)

    0 at full moon, π at new moon. Meeus (1998) ch. 48 (eq. 48.2 is its form from elongation
    and distances); exact for the given vectors.

    Parameters
    ----------
    moon_position_m, sun_position_m : array_like, shape (..., 3)
        Moon's and Sun's centres relative to the observer, in one frame; broadcast. [m]

    Returns
    -------
    ndarray, shape (...)
        Phase angle in [0, π]. [rad]
    """
    moon = _vectors(moon_position_m, "moon_position_m")
    sun = _vectors(sun_position_m, "sun_position_m")
    return _angle(sun - moon, -moon)


def illuminated_fraction(moon_position_m: ArrayLike, sun_position_m: ArrayLike) -> np.ndarray:
    """Illuminated fraction of the Moon's disk, k = (1 + cos i) / 2 (Meeus 1998, eq. 48.1).

    The lit area of the disk over its whole area, for a sphere lit by a point sun (the
    terminator projects to a half-ellipse of semi-minor axis |cos i|).

    Parameters
    ----------
    moon_position_m, sun_position_m : array_like, shape (..., 3)
        Moon's and Sun's centres relative to the observer, in one frame. [m]

    Returns
    -------
    ndarray, shape (...)
        k in [0, 1]. [-]
    """
    return 0.5 * (1.0 + np.cos(phase_angle_rad(moon_position_m, sun_position_m)))


def bright_limb_direction(moon_position_m: ArrayLike, sun_position_m: ArrayLike) -> np.ndarray:
    """Unit vector on the sky from the Moon's centre towards its sunlit limb.

        b = normalise(u - (u · m̂) m̂),   u = r_sun - r_moon,   m̂ = r_moon / |r_moon|

    The Moon-Sun direction projected onto the plane perpendicular to the line of sight: the
    axis of symmetry of the phase, pointing to the midpoint of the bright limb. Undefined at
    exactly full or new moon (u ∥ m̂); there the result is NaN.

    Parameters
    ----------
    moon_position_m, sun_position_m : array_like, shape (..., 3)
        Moon's and Sun's centres relative to the observer, in one frame. [m]

    Returns
    -------
    ndarray, shape (..., 3)
        Unit vector perpendicular to the line of sight, in the input frame. [-]
    """
    moon = _vectors(moon_position_m, "moon_position_m")
    sun = _vectors(sun_position_m, "sun_position_m")
    m = _unit(moon, "moon_position_m")
    u = sun - moon
    b = u - np.sum(u * m, axis=-1, keepdims=True) * m
    norm = np.linalg.norm(b, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        return b / np.where(norm > 0.0, norm, np.nan)


def bright_limb_position_angle_rad(moon_position_m: ArrayLike, sun_position_m: ArrayLike,
                                   north_pole: ArrayLike = (0.0, 0.0, 1.0)) -> np.ndarray:
    """Position angle χ of the bright limb, from the north pole through east.

        n = normalise(p - (p · m̂) m̂),  e = normalise(p × m̂),  χ = atan2(b · e, b · n)

    b = `bright_limb_direction`, p = `north_pole` (the celestial pole of the frame: (0, 0, 1)
    in an equatorial frame such as GCRS/J2000). Agrees with Meeus (1998) eq. 48.5,
    tan χ = cos δ_0 sin(α_0 - α) / (sin δ_0 cos δ - cos δ_0 sin δ cos(α_0 - α)), to the
    Sun's parallax seen from the Moon (< 0.2° away from full and new moon).

    Parameters
    ----------
    moon_position_m, sun_position_m : array_like, shape (..., 3)
        Moon's and Sun's centres relative to the observer, in one frame. [m]
    north_pole : array_like, shape (3,)
        Direction of the pole the angle is counted from, in the same frame. [-]

    Returns
    -------
    ndarray, shape (...)
        χ in [0, 2π); NaN at exactly full or new moon. [rad]
    """
    b = bright_limb_direction(moon_position_m, sun_position_m)
    m = _unit(_vectors(moon_position_m, "moon_position_m"), "moon_position_m")
    p = _unit(_vectors(north_pole, "north_pole"), "north_pole")
    north = p - np.sum(p * m, axis=-1, keepdims=True) * m
    north = north / np.linalg.norm(north, axis=-1, keepdims=True)
    east = np.cross(p, m)
    east = east / np.linalg.norm(east, axis=-1, keepdims=True)
    chi = np.arctan2(np.sum(b * east, axis=-1), np.sum(b * north, axis=-1))
    return np.mod(chi, 2.0 * np.pi)


def moon_angular_radius_rad(moon_distance_m: ArrayLike,
                            moon_radius_m: float = MOON_RADIUS_M) -> np.ndarray:
    """Angular radius (semi-diameter) of the Moon, s_m = asin(R_moon / d) (exact for a sphere).

    Parameters
    ----------
    moon_distance_m : array_like, shape S
        Distance from the observer to the Moon's centre, > moon_radius_m. [m]
    moon_radius_m : float
        Radius; 1737.4 km (IAU mean radius) by default. [m]

    Returns
    -------
    ndarray, shape S
        Angular radius; 0.2725° at 365 000 km. [rad]
    """
    d = _positive(moon_distance_m, "moon_distance_m")
    if np.any(d <= moon_radius_m):
        raise InputError("moon_distance_m must exceed the Moon's radius", key="moon_distance_m",
                         value=moon_distance_m, allowed=f"> {moon_radius_m} m")
    return np.arcsin(moon_radius_m / d)


def shadow_radii_rad(moon_distance_m: ArrayLike, sun_distance_m: ArrayLike,
                     enlargement: str = "danjon",
                     earth_radius_m: float = EARTH_SHADOW_RADIUS_M,
                     sun_radius_m: float = SUN_RADIUS_M) -> tuple[np.ndarray, np.ndarray]:
    """Angular radii of the Earth's umbra and penumbra at the Moon's distance.

        ρ_u = π_1 + π_s - s,   ρ_p = π_1 + π_s + s
        π_1 = asin(R/D_m),   π_s = asin(R/D_s),   s = asin(R_⊙/D_s)

    seen from the Earth's centre, for the cones tangent to the Sun and to a spherical Earth of
    radius R (the seed's eqs. 4.12-4.13 in angles: multiply ε by r_m/D_m; Explanatory
    Supplement 1992 §8.4; Meeus 1998 ch. 54). `enlargement` adds the opaque lower atmosphere:
    "danjon": R -> R (1 + 1/85) (Danjon 1951); "chauvenet": ρ_u, ρ_p -> 1.02 ρ_u, 1.02 ρ_p
    (Chauvenet 1891); "none": the bare geometric shadow. The two rules differ by ~0.2′ in ρ_u
    and ~0.9′ in ρ_p (0.007 and 0.03 in eclipse magnitude).

    Parameters
    ----------
    moon_distance_m, sun_distance_m : array_like, broadcast to S
        Geocentric distances of the Moon's and the Sun's centres. [m]
    enlargement : str
        One of `SHADOW_ENLARGEMENTS`.
    earth_radius_m : float
        Radius of the spherical Earth; default 0.998340 × 6378.137 km (45° latitude). [m]
    sun_radius_m : float
        Solar radius; default 6.957e8 m (IAU 2015 B3). [m]

    Returns
    -------
    (ndarray, ndarray), each shape S
        ρ_u (negative beyond the umbra's apex) and ρ_p. [rad]
    """
    if enlargement not in SHADOW_ENLARGEMENTS:
        raise InputError(f"enlargement = {enlargement!r} is not one of "
                         f"{', '.join(SHADOW_ENLARGEMENTS)}", key="enlargement",
                         value=enlargement, allowed=", ".join(SHADOW_ENLARGEMENTS))
    d_m = _positive(moon_distance_m, "moon_distance_m")
    d_s = _positive(sun_distance_m, "sun_distance_m")
    radius = earth_radius_m * (_DANJON_FACTOR if enlargement == "danjon" else 1.0)
    pi_1 = np.arcsin(radius / d_m)
    pi_s = np.arcsin(radius / d_s)
    s = np.arcsin(sun_radius_m / d_s)
    scale = _CHAUVENET_FACTOR if enlargement == "chauvenet" else 1.0
    return scale * (pi_1 + pi_s - s), scale * (pi_1 + pi_s + s)


def shadow_axis_distance_rad(moon_geocentric_m: ArrayLike,
                             sun_geocentric_m: ArrayLike) -> np.ndarray:
    """Angle θ between the Moon's centre and the shadow axis, seen from the Earth's centre.

        θ = ∠(r_moon, -r_sun)

    The shadow axis is the line from the Sun's centre through the Earth's centre; use the Sun's
    apparent (light-time corrected) position.

    Parameters
    ----------
    moon_geocentric_m, sun_geocentric_m : array_like, shape (..., 3)
        Geocentric positions of the Moon and the Sun, one frame. [m]

    Returns
    -------
    ndarray, shape (...)
        θ in [0, π]. [rad]
    """
    moon = _vectors(moon_geocentric_m, "moon_geocentric_m")
    sun = _vectors(sun_geocentric_m, "sun_geocentric_m")
    return _angle(moon, -sun)


def eclipse_magnitudes(moon_geocentric_m: ArrayLike, sun_geocentric_m: ArrayLike, *,
                       enlargement: str = "danjon",
                       earth_radius_m: float = EARTH_SHADOW_RADIUS_M,
                       moon_radius_m: float = MOON_RADIUS_M,
                       sun_radius_m: float = SUN_RADIUS_M) -> tuple[np.ndarray, np.ndarray]:
    """Umbral and penumbral magnitudes of a lunar eclipse.

        M_u = (ρ_u + s_m - θ) / (2 s_m),   M_p = (ρ_p + s_m - θ) / (2 s_m)

    the fraction of the Moon's diameter inside the shadow along the line through the shadow
    axis (Espenak & Meeus 2009, NASA/TP-2009-214172, §1.4): ρ_u, ρ_p from `shadow_radii_rad`,
    θ from `shadow_axis_distance_rad`, s_m = asin(R_moon / D_m) geocentric. M > 0: the Moon
    touches that shadow; M >= 1: it is wholly inside it (total eclipse for the umbra).

    Parameters
    ----------
    moon_geocentric_m, sun_geocentric_m : array_like, shape (..., 3)
        Geocentric positions of the Moon and the Sun, one frame. [m]
    enlargement : str
        Shadow enlargement rule, one of `SHADOW_ENLARGEMENTS` (default Danjon's).
    earth_radius_m, moon_radius_m, sun_radius_m : float
        Radii of the spheres. [m]

    Returns
    -------
    (ndarray, ndarray), each shape (...)
        Umbral and penumbral magnitudes (negative when the Moon misses that shadow). [-]
    """
    moon = _vectors(moon_geocentric_m, "moon_geocentric_m")
    sun = _vectors(sun_geocentric_m, "sun_geocentric_m")
    d_m = np.linalg.norm(moon, axis=-1)
    d_s = np.linalg.norm(sun, axis=-1)
    rho_u, rho_p = shadow_radii_rad(d_m, d_s, enlargement, earth_radius_m, sun_radius_m)
    s_m = moon_angular_radius_rad(d_m, moon_radius_m)
    theta = shadow_axis_distance_rad(moon, sun)
    return (rho_u + s_m - theta) / (2.0 * s_m), (rho_p + s_m - theta) / (2.0 * s_m)
