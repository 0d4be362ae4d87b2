"""Rotations from the J2000 equatorial frame to an observer's horizon (east, north, up).

For stars: a catalogue direction u (ICRS ≈ J2000 mean equator and equinox, a column vector)
seen by an observer on Earth or on Mars is `M @ u` in the local frame (x east, y north, z up).

Earth (`j2000_to_horizon_matrix`), M = H(φ, λ) R3(θ_app) N P:

- P: precession J2000 -> mean equator of date, IAU 1976 (Lieske et al. 1977, A&A 58, 1),
  P = R3(−z) R2(θ) R3(−ζ) with ζ, z, θ of Meeus (1998), *Astronomical Algorithms*, eqs.
  21.2-21.4 (T in Julian centuries of TT from J2000).
- N: nutation, N = R1(−ε) R3(−Δψ) R1(ε0), Δψ and Δε from the four main terms of Meeus ch. 22
  (accuracy 0.5" in Δψ, 0.1" in Δε), mean obliquity ε0 from Meeus eq. 22.2, ε = ε0 + Δε.
- θ_app: Greenwich apparent sidereal time, mean sidereal time of Meeus eq. 12.4 (UT ≈ UTC)
  plus the equation of the equinoxes Δψ cos ε.
- H: terrestrial -> local east-north-up at geodetic latitude φ and east longitude λ.

Left out, each stated: annual aberration (≤ 20.5"), the light deflection by the Sun, polar
motion (≤ 0.5"), UT1 − UTC (≤ 0.9 s of time, ≤ 13.5" in hour angle), diurnal aberration
(≤ 0.3"), the frame bias ICRS−J2000 (0.02"). Together ≤ 35" = 0.0097°; measured against
astropy in tests/astro/test_astro_frames.py. Refraction is applied separately
(`earth_sky.refract`).

Mars (`mars_j2000_to_horizon_matrix`), M = H(φ, λ) R3(W) R1(90° − δ0) R3(90° + α0): the IAU
WGCCRE 2015 rotation model of Mars (Archinal et al. 2018, Celest. Mech. Dyn. Astron. 130:22,
doi:10.1007/s10569-017-9805-5, Table 2: pole α0, δ0 and prime meridian W with their periodic
terms), with d, T counted from J2000 in TT (TDB − TT < 2 ms). Planetocentric latitude, east
longitude; "up" is the radial direction (a sphere; the areoid's normal differs from it by up to
0.34° at 45° latitude).

R1, R2, R3 are frame rotations about x, y, z (Meeus ch. 21 conventions):
R3(a) = [[cos a, sin a, 0], [−sin a, cos a, 0], [0, 0, 1]].

Public names: `j2000_to_horizon_matrix`, `mars_j2000_to_horizon_matrix`,
`precession_matrix_iau1976`, `nutation_meeus`, `nutation_matrix`,
`mean_obliquity_deg`, `greenwich_mean_sidereal_time_deg`, `mars_pole_and_meridian_deg`,
`enu_from_body_fixed_matrix`.
"""

from __future__ import annotations

import datetime
import math

import numpy as np

from skyscatter.astro.time import (
    J2000_JD,
    check_latitude,
    check_longitude,
    check_utc,
    julian_date,
    julian_date_tt,
)

__all__ = [
    "enu_from_body_fixed_matrix",
    "greenwich_mean_sidereal_time_deg",
    "j2000_to_horizon_matrix",
    "mars_j2000_to_horizon_matrix",
    "mars_pole_and_meridian_deg",
    "mean_obliquity_deg",
    "nutation_matrix",
    "nutation_meeus",
    "precession_matrix_iau1976",
]

_ARCSEC = math.pi / (180.0 * 3600.0)  # rad per arcsecond
_DAYS_PER_CENTURY = 36525.0  # d per Julian century


def _r1(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def _r2(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def _r3(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def precession_matrix_iau1976(jd_tt: float) -> np.ndarray:
    """Precession matrix J2000 mean equator/equinox -> mean equator/equinox of date.

        ζ = 2306.2181" T + 0.30188" T² + 0.017998" T³
        z = 2306.2181" T + 1.09468" T² + 0.018203" T³
        θ = 2004.3109" T − 0.42665" T² − 0.041833" T³,   P = R3(−z) R2(θ) R3(−ζ)

    T = (JD_TT − 2451545.0)/36525; Meeus (1998) eqs. 21.2-21.4, IAU 1976 (Lieske et al. 1977).

    Parameters
    ----------
    jd_tt : float
        Julian date in TT. [d]

    Returns
    -------
    ndarray, shape (3, 3)
        Rotation matrix acting on column vectors. [-]
    """
    t = (jd_tt - J2000_JD) / _DAYS_PER_CENTURY
    zeta = (2306.2181 * t + 0.30188 * t**2 + 0.017998 * t**3) * _ARCSEC
    z = (2306.2181 * t + 1.09468 * t**2 + 0.018203 * t**3) * _ARCSEC
    theta = (2004.3109 * t - 0.42665 * t**2 - 0.041833 * t**3) * _ARCSEC
    return _r3(-z) @ _r2(theta) @ _r3(-zeta)


def mean_obliquity_deg(jd_tt: float) -> float:
    """Mean obliquity of the ecliptic ε0 [deg], Meeus (1998) eq. 22.2 (IAU 1980).

        ε0 = 23°26'21.448" − 46.8150" T − 0.00059" T² + 0.001813" T³
    """
    t = (jd_tt - J2000_JD) / _DAYS_PER_CENTURY
    return 23.0 + 26.0 / 60.0 + (21.448 - 46.8150 * t - 0.00059 * t**2 + 0.001813 * t**3) / 3600.0


def nutation_meeus(jd_tt: float) -> tuple[float, float]:
    """Nutation in longitude and obliquity (Δψ, Δε) [deg], the main terms of Meeus ch. 22.

        Δψ = −17.20" sin Ω − 1.32" sin 2L − 0.23" sin 2L' + 0.21" sin 2Ω
        Δε =  +9.20" cos Ω + 0.57" cos 2L + 0.10" cos 2L' − 0.09" cos 2Ω

    L = 280.4665° + 36000.7698° T and L' = 218.3165° + 481267.8813° T (mean longitudes of Sun
    and Moon), Ω = 125.04452° − 1934.136261° T + 0.0020708° T² + T³/450000 (Moon's ascending
    node, Meeus p. 144). Accuracy 0.5" in Δψ and 0.1" in Δε (Meeus p. 144).
    """
    t = (jd_tt - J2000_JD) / _DAYS_PER_CENTURY
    omega = math.radians(125.04452 - 1934.136261 * t + 0.0020708 * t**2 + t**3 / 450000.0)
    l_sun = math.radians(280.4665 + 36000.7698 * t)
    l_moon = math.radians(218.3165 + 481267.8813 * t)
    dpsi = (-17.20 * math.sin(omega) - 1.32 * math.sin(2 * l_sun) - 0.23 * math.sin(2 * l_moon)
            + 0.21 * math.sin(2 * omega))
    deps = (9.20 * math.cos(omega) + 0.57 * math.cos(2 * l_sun) + 0.10 * math.cos(2 * l_moon)
            - 0.09 * math.cos(2 * omega))
    return dpsi / 3600.0, deps / 3600.0


def nutation_matrix(jd_tt: float) -> np.ndarray:
    """Nutation matrix, mean -> true equator and equinox of date: R1(−ε) R3(−Δψ) R1(ε0).

    Δψ, Δε from `nutation_meeus`, ε0 from `mean_obliquity_deg`, ε = ε0 + Δε. [-], (3, 3)
    """
    eps0 = math.radians(mean_obliquity_deg(jd_tt))
    dpsi, deps = nutation_meeus(jd_tt)
    return _r1(-(eps0 + math.radians(deps))) @ _r3(-math.radians(dpsi)) @ _r1(eps0)


def greenwich_mean_sidereal_time_deg(jd_ut: float) -> float:
    """Greenwich mean sidereal time [deg], in [0, 360); Meeus (1998) eq. 12.4.

        θ0 = 280.46061837° + 360.98564736629° (JD − 2451545.0) + 0.000387933° T²
             − T³/38710000,   T = (JD − 2451545.0)/36525,  JD in UT
    """
    d = jd_ut - J2000_JD
    t = d / _DAYS_PER_CENTURY
    theta = (280.46061837 + 360.98564736629 * d + 0.000387933 * t**2 - t**3 / 38710000.0)
    return theta % 360.0


def enu_from_body_fixed_matrix(latitude_deg: float, longitude_deg: float) -> np.ndarray:
    """Rows: the east, north and up unit vectors at (latitude, east longitude), body-fixed axes.

        e = (−sin λ, cos λ, 0),  n = (−sin φ cos λ, −sin φ sin λ, cos φ),
        u = (cos φ cos λ, cos φ sin λ, sin φ)

    φ is the latitude whose normal is "up" (geodetic on Earth, planetocentric on a sphere). [-]
    """
    phi, lam = math.radians(latitude_deg), math.radians(longitude_deg)
    sp, cp, sl, cl = math.sin(phi), math.cos(phi), math.sin(lam), math.cos(lam)
    return np.array([[-sl, cl, 0.0], [-sp * cl, -sp * sl, cp], [cp * cl, cp * sl, sp]])


def j2000_to_horizon_matrix(utc: datetime.datetime, latitude_deg: float,
                            longitude_deg: float) -> np.ndarray:
    """Rotation from J2000/ICRS equatorial unit vectors to the local (east, north, up) frame.

        M = H(φ, λ) R3(θ_app) N P

    (see the module docstring for each factor and what is left out: aberration ≤ 20.5",
    polar motion, UT1 − UTC). Apply as `M @ u` to column vectors, or `u @ M.T` to an (n, 3)
    array of star directions.

    Parameters
    ----------
    utc : datetime.datetime
        Aware datetime.
    latitude_deg : float
        Geodetic latitude, north positive, in [-90, 90]. [deg]
    longitude_deg : float
        Longitude, east positive (wrapped). [deg]

    Returns
    -------
    ndarray, shape (3, 3)
        Orthonormal rotation matrix. [-]
    """
    t = check_utc(utc)
    lat = check_latitude(latitude_deg)
    lon = check_longitude(longitude_deg)
    jd_tt = julian_date_tt(t)
    dpsi, deps = nutation_meeus(jd_tt)
    eps = math.radians(mean_obliquity_deg(jd_tt) + deps)
    gast = greenwich_mean_sidereal_time_deg(julian_date(t)) + dpsi * math.cos(eps)
    return (enu_from_body_fixed_matrix(lat, lon) @ _r3(math.radians(gast))
            @ nutation_matrix(jd_tt) @ precession_matrix_iau1976(jd_tt))


def _sin_terms(t: float, terms: tuple[tuple[float, float, float], ...], fn) -> float:
    return sum(a * fn(math.radians(phase + rate * t)) for a, phase, rate in terms)


# IAU WGCCRE 2015, Mars (Archinal et al. 2018, Table 2): (amplitude [deg], phase [deg],
# rate [deg per century]). The last term of each is the slow 0.5042615°/cy one that carries the
# 2015 pole back to the IAU 2009 pole (317.68143°, 52.88650°).
_MARS_RA_TERMS = (
    (0.000068, 198.991226, 19139.4819985),
    (0.000238, 226.292679, 38280.8511281),
    (0.000052, 249.663391, 57420.7251593),
    (0.000009, 266.183510, 76560.6367950),
    (0.419057, 79.398797, 0.5042615),
)
_MARS_DEC_TERMS = (
    (0.000051, 122.433576, 19139.9407476),
    (0.000141, 43.058401, 38280.8753272),
    (0.000031, 57.663379, 57420.7517205),
    (0.000005, 79.476401, 76560.6495004),
    (1.591274, 166.325722, 0.5042615),
)
_MARS_W_TERMS = (
    (0.000145, 129.071773, 19140.0328244),
    (0.000157, 36.352167, 38281.0473591),
    (0.000040, 56.668646, 57420.9295360),
    (0.000001, 67.364003, 76560.2552215),
    (0.000001, 104.792680, 95700.4387578),
    (0.584542, 95.391654, 0.5042615),
)


def mars_pole_and_meridian_deg(jd_tt: float) -> tuple[float, float, float]:
    """Mars's north pole (α0, δ0) in ICRS and its prime meridian angle W [deg].

        α0 = 317.269202° − 0.10927547° T + Σ a_i sin(φ_i + ω_i T)
        δ0 =  54.432516° − 0.05827105° T + Σ b_i cos(φ_i + ω_i T)
        W  = 176.049863° + 350.891982443297° d + Σ c_i sin(φ_i + ω_i T)

    d in days and T in Julian centuries from J2000 (TT for TDB); IAU WGCCRE 2015, Archinal et
    al. (2018), Celest. Mech. Dyn. Astron. 130:22, Table 2. W is returned modulo 360.
    """
    d = jd_tt - J2000_JD
    t = d / _DAYS_PER_CENTURY
    alpha0 = 317.269202 - 0.10927547 * t + _sin_terms(t, _MARS_RA_TERMS, math.sin)
    delta0 = 54.432516 - 0.05827105 * t + _sin_terms(t, _MARS_DEC_TERMS, math.cos)
    w = 176.049863 + 350.891982443297 * d + _sin_terms(t, _MARS_W_TERMS, math.sin)
    return alpha0, delta0, w % 360.0


def mars_j2000_to_horizon_matrix(utc: datetime.datetime, latitude_deg: float,
                                 longitude_deg: float) -> np.ndarray:
    """Rotation from J2000/ICRS unit vectors to the (east, north, up) frame of a site on Mars.

        M = H(φ, λ) R3(W) R1(90° − δ0) R3(90° + α0)

    α0, δ0, W from `mars_pole_and_meridian_deg` (IAU WGCCRE 2015). Directions only: the
    parallax of stars across Mars's orbit and aberration (≤ 17") are left out; light time is
    irrelevant for directions from the site. "Up" is radial (planetocentric).

    Parameters
    ----------
    utc : datetime.datetime
        Aware datetime.
    latitude_deg : float
        Planetocentric latitude, north positive, in [-90, 90]. [deg]
    longitude_deg : float
        Planetocentric longitude, EAST positive (wrapped). [deg]

    Returns
    -------
    ndarray, shape (3, 3)
        Orthonormal rotation matrix acting on column vectors. [-]
    """
    t = check_utc(utc)
    lat = check_latitude(latitude_deg)
    lon = check_longitude(longitude_deg)
    alpha0, delta0, w = mars_pole_and_meridian_deg(julian_date_tt(t))
    body = _r3(math.radians(w)) @ _r1(math.radians(90.0 - delta0)) @ _r3(
        math.radians(90.0 + alpha0))
    return enu_from_body_fixed_matrix(lat, lon) @ body
