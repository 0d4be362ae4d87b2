"""Time on Mars and where the Sun stands in a Martian sky: the Mars24 algorithm.

Allison & McEwen (2000), Planet. Space Sci. 48, 215, doi:10.1016/S0032-0633(99)00092-6
(AM2000), as revised on NASA GISS's "Mars24 Algorithm and Worked Examples" page
(https://www.giss.nasa.gov/tools/mars24/help/algorithm.html; steps A-1 to D-6 below carry that
page's numbers). With Δt = days since J2000 in TT (A-6):

    B-1  M    = 19.3871° + 0.52402073° Δt                        (mean anomaly)
    B-2  α    = 270.3871° + 0.524038496° Δt                      (fictitious mean sun)
    B-3  PBS  = Σ_i A_i cos(0.985626° Δt / τ_i + φ_i)            (7 planetary perturbations)
    B-4  ν−M  = (10.691° + 3.0e-7° Δt) sin M + 0.623° sin 2M + 0.050° sin 3M
                + 0.005° sin 4M + 0.0005° sin 5M + PBS           (equation of centre)
    B-5  Ls   = α + (ν − M)                                      (areocentric solar longitude)
    C-1  EOT  = 2.861° sin 2Ls − 0.071° sin 4Ls + 0.002° sin 6Ls − (ν − M)
    C-2  MSD  = (Δt − 4.5)/1.0274912517 + 44796.0 − 0.0009626,  MTC = 24 h × MSD mod 24 h
    C-3  LMST = MTC − Λ/15 (Λ west longitude [deg]),  C-4  LTST = LMST + EOT/15
    C-5  Λs   = 15 MTC + EOT + 180°                               (subsolar west longitude)
    D-1  δs   = asin(0.42565 sin Ls) + 0.25° sin Ls               (planetographic declination)
    D-2  r    = 1.52367934 AU (1.00436 − 0.09309 cos M − 0.004336 cos 2M − 0.00031 cos 3M
                − 0.00003 cos 4M)                                 (heliocentric distance)
    D-5  cos Z = sin δ sin φ + cos δ cos φ cos H,  H = Λ − Λs
    D-6  A    = atan2(sin H, cos φ tan δ − sin φ cos H)           (from north towards east)

This module takes EAST-positive planetocentric longitudes λ and converts, Λ = −λ mod 360°.
Deliberate departure from D-5/D-6: the zenith angle and azimuth use the planetocentric solar
declination δc = asin(0.42565 sin Ls) (the angle of the Sun's direction above Mars's equator)
with the planetocentric latitude φ, i.e. the angle from the radial "up" — the same geometry as
`frames.mars_j2000_to_horizon_matrix`. Mars24's δs adds 0.25° sin Ls, the planetographic
latitude of the subsolar point; it is kept in `MarsSunGeometry.declination_deg` as published.
Mars24's own accuracy: Ls to ~0.01° over 1990-2030, times to ~1 s (AM2000, sect. 5).

TT: `time.terrestrial_minus_universal_s` (leap seconds + 32.184 s; A-4).

Public names: `MarsSunGeometry`, `mars_sol_date`, `utc_from_mars_sol_date`, `mars24_steps`,
`mars_sun_geometry`, `mars_sun_position`, `MARS_SOL_IN_DAYS`.
"""

from __future__ import annotations

import datetime
import math
from dataclasses import dataclass

from skyscatter.astro.earth_sky import AU_M, SkyPosition
from skyscatter.astro.time import (
    SECONDS_PER_DAY,
    check_latitude,
    check_longitude,
    check_utc,
    terrestrial_minus_universal_s,
)
from skyscatter.errors import InputError

__all__ = [
    "MARS_SOL_IN_DAYS",
    "MarsSunGeometry",
    "mars24_steps",
    "mars_sol_date",
    "mars_sun_geometry",
    "mars_sun_position",
    "utc_from_mars_sol_date",
]

MARS_SOL_IN_DAYS = 1.0274912517  # d per mean solar day on Mars (Mars24 step C-2; AM2000 eq. 32)
_J2000_UTC = datetime.datetime(2000, 1, 1, 12, tzinfo=datetime.UTC)  # JD 2451545.0 as a clock
_MSD_AT_4_5 = 44796.0 - 0.0009626  # MSD at Δt = 4.5 d (Mars24 C-2)
_ONE_DAY = datetime.timedelta(days=1)

# Mars24 step B-3 (AM2000 Table 5): amplitude A [deg], period τ [Julian years], phase φ [deg].
_PERTURBERS = (
    (0.0071, 2.2353, 49.409),
    (0.0057, 2.7543, 168.173),
    (0.0039, 1.1177, 191.837),
    (0.0037, 15.7866, 21.736),
    (0.0021, 2.1354, 15.704),
    (0.0020, 2.4694, 95.528),
    (0.0018, 32.8493, 49.095),
)


@dataclass(frozen=True)
class MarsSunGeometry:
    """The Mars24 quantities for one instant and one site on Mars.

    msd: Mars Sol Date [sol]; areocentric_longitude_ls_deg: Ls [deg];
    heliocentric_distance_au: Sun-Mars distance [AU]; declination_deg: Mars24's planetographic
    solar declination δs (step D-1) [deg]; equation_of_time_deg: EOT (C-1), true minus mean
    solar time as an angle [deg]; local_mean_solar_time_h, local_true_solar_time_h: LMST, LTST
    in [0, 24) [Mars hours]; zenith_deg: Sun's zenith angle from the radial vertical [deg];
    azimuth_deg: from north towards east, [0, 360) [deg].
    """

    msd: float
    areocentric_longitude_ls_deg: float
    heliocentric_distance_au: float
    declination_deg: float
    equation_of_time_deg: float
    local_mean_solar_time_h: float
    local_true_solar_time_h: float
    zenith_deg: float
    azimuth_deg: float


def _days_since_j2000_tt(utc: datetime.datetime) -> float:
    """Mars24 A-1..A-6: Δt_J2000 = JD_TT − 2451545.0 [d], from the datetime without rounding."""
    t = check_utc(utc)
    return (t - _J2000_UTC) / _ONE_DAY + terrestrial_minus_universal_s(t) / SECONDS_PER_DAY


def _sind(x: float) -> float:
    return math.sin(math.radians(x))


def _cosd(x: float) -> float:
    return math.cos(math.radians(x))


def _steps_from_dt(dt: float) -> dict[str, float]:
    m = 19.3871 + 0.52402073 * dt
    alpha = 270.3871 + 0.524038496 * dt
    pbs = sum(a * _cosd(0.985626 * dt / tau + phi) for a, tau, phi in _PERTURBERS)
    nu_m = ((10.691 + 3.0e-7 * dt) * _sind(m) + 0.623 * _sind(2 * m) + 0.050 * _sind(3 * m)
            + 0.005 * _sind(4 * m) + 0.0005 * _sind(5 * m) + pbs)
    ls = (alpha + nu_m) % 360.0
    eot = 2.861 * _sind(2 * ls) - 0.071 * _sind(4 * ls) + 0.002 * _sind(6 * ls) - nu_m
    msd = (dt - 4.5) / MARS_SOL_IN_DAYS + _MSD_AT_4_5
    mtc = (24.0 * msd) % 24.0
    r = 1.52367934 * (1.00436 - 0.09309 * _cosd(m) - 0.004336 * _cosd(2 * m)
                      - 0.00031 * _cosd(3 * m) - 0.00003 * _cosd(4 * m))
    return {
        "delta_t_j2000_d": dt,
        "mean_anomaly_deg": m % 360.0,
        "fms_angle_deg": alpha % 360.0,
        "perturbers_deg": pbs,
        "equation_of_center_deg": nu_m,
        "ls_deg": ls,
        "eot_deg": eot,
        "msd": msd,
        "mtc_h": mtc,
        "subsolar_longitude_west_deg": (15.0 * mtc + eot + 180.0) % 360.0,
        "declination_planetographic_deg": math.degrees(math.asin(0.42565 * _sind(ls)))
        + 0.25 * _sind(ls),
        "declination_planetocentric_deg": math.degrees(math.asin(0.42565 * _sind(ls))),
        "heliocentric_distance_au": r,
    }


def mars24_steps(utc: datetime.datetime) -> dict[str, float]:
    """The intermediate quantities of the Mars24 algorithm (steps A-6 to D-2), by name.

    Keys: delta_t_j2000_d (A-6) [d], mean_anomaly_deg (B-1), fms_angle_deg (B-2),
    perturbers_deg (B-3), equation_of_center_deg (B-4), ls_deg (B-5), eot_deg (C-1) [deg],
    msd (C-2) [sol], mtc_h (C-2) [h], subsolar_longitude_west_deg (C-5),
    declination_planetographic_deg (D-1), declination_planetocentric_deg (D-1 without the
    0.25° sin Ls term) [deg], heliocentric_distance_au (D-2) [AU]. Angles of B-1, B-2, B-5 and
    C-5 are reduced to [0, 360).
    """
    return _steps_from_dt(_days_since_j2000_tt(utc))


def mars_sol_date(utc: datetime.datetime) -> float:
    """Mars Sol Date (Mars24 C-2; AM2000 eq. 32), the count of mean Martian solar days.

        MSD = (Δt_J2000,TT − 4.5 d)/1.0274912517 + 44796.0 − 0.0009626

    MSD 0 began near 1873-12-29 (AM2000); 44795.9998 at 2000-01-06 00:00 UTC. [sol]
    """
    return _steps_from_dt(_days_since_j2000_tt(utc))["msd"]


def utc_from_mars_sol_date(msd: float) -> datetime.datetime:
    """The UTC instant of a Mars Sol Date: the inverse of `mars_sol_date` (to ~1 µs).

    Δt_TT = (MSD − 44796.0 + 0.0009626) × 1.0274912517 + 4.5; UTC = J2000 + Δt_TT − ΔT, with
    ΔT = TT − UT at that instant (two fixed-point steps; exact except within a leap second's
    jump). Returns an aware datetime in UTC; InputError if the date is outside years 1-9999.
    """
    if isinstance(msd, bool) or not isinstance(msd, (int, float)) or not math.isfinite(msd):
        raise InputError(f"msd = {msd!r} must be a finite number [sol]", key="msd", value=msd,
                         allowed="finite number")
    dt_tt = (float(msd) - _MSD_AT_4_5) * MARS_SOL_IN_DAYS + 4.5
    try:
        utc = _J2000_UTC + datetime.timedelta(days=dt_tt)
        for _ in range(3):
            utc = _J2000_UTC + datetime.timedelta(
                days=dt_tt - terrestrial_minus_universal_s(utc) / SECONDS_PER_DAY)
    except OverflowError:
        raise InputError(f"msd = {msd!r} is outside the years 1-9999 that datetime can hold",
                         key="msd", value=msd, allowed="years 1-9999") from None
    return utc


def mars_sun_geometry(utc: datetime.datetime, latitude_deg: float,
                      longitude_deg: float) -> MarsSunGeometry:
    """Mars24 local solar times and the Sun's zenith angle and azimuth at a site on Mars.

    Parameters
    ----------
    utc : datetime.datetime
        Aware datetime.
    latitude_deg : float
        Planetocentric latitude, north positive, in [-90, 90]. [deg]
    longitude_deg : float
        Planetocentric longitude, EAST positive (wrapped); Mars24's west longitude is
        Λ = −λ mod 360°. [deg]

    Returns
    -------
    MarsSunGeometry
        Zenith and azimuth from D-5/D-6 with the planetocentric declination (see the module
        docstring); the other fields as Mars24 prints them.
    """
    lat = check_latitude(latitude_deg)
    lon_east = check_longitude(longitude_deg)
    s = mars24_steps(utc)
    lon_west = (-lon_east) % 360.0
    lmst = (s["mtc_h"] - lon_west / 15.0) % 24.0
    ltst = (lmst + s["eot_deg"] / 15.0) % 24.0
    hour = math.radians(lon_west - s["subsolar_longitude_west_deg"])
    dec = math.radians(s["declination_planetocentric_deg"])
    phi = math.radians(lat)
    cos_z = math.sin(dec) * math.sin(phi) + math.cos(dec) * math.cos(phi) * math.cos(hour)
    zenith = math.degrees(math.acos(max(-1.0, min(1.0, cos_z))))
    azimuth = math.degrees(math.atan2(
        math.sin(hour), math.cos(phi) * math.tan(dec) - math.sin(phi) * math.cos(hour))) % 360.0
    return MarsSunGeometry(
        msd=s["msd"],
        areocentric_longitude_ls_deg=s["ls_deg"],
        heliocentric_distance_au=s["heliocentric_distance_au"],
        declination_deg=s["declination_planetographic_deg"],
        equation_of_time_deg=s["eot_deg"],
        local_mean_solar_time_h=lmst,
        local_true_solar_time_h=ltst,
        zenith_deg=zenith,
        azimuth_deg=azimuth,
    )


def mars_sun_position(utc: datetime.datetime, latitude_deg: float,
                      longitude_deg: float) -> SkyPosition:
    """The Sun in a Martian sky: azimuth, altitude = 90° − zenith, and distance from Mars.

    From `mars_sun_geometry` (same arguments: planetocentric latitude, east longitude);
    distance_m is the heliocentric distance of Mars's centre (Mars24 D-2) [m]. No refraction
    (Mars's is ≲ 0.01° above 10° altitude). Accuracy ~0.05° against an ephemeris (tests).
    """
    g = mars_sun_geometry(utc, latitude_deg, longitude_deg)
    return SkyPosition(azimuth_deg=g.azimuth_deg, altitude_deg=90.0 - g.zenith_deg,
                       distance_m=g.heliocentric_distance_au * AU_M)
