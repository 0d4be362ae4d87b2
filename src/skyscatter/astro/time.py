"""Time: parsing user times, Julian dates, and the difference TT − UT.

- `parse_time`: ISO 8601 text with a time zone -> an aware `datetime` in UTC. A time without a
  zone is refused: a sky at "21:30" is a different sky in Berlin and in Sydney. The zone is an
  offset ("+02:00", "Z") or a zone of the IANA time zone database, in brackets as RFC 9557
  writes it ("2024-06-21T21:30[Europe/Berlin]") or after a space ("2024-06-21T21:30
  Europe/Berlin"), its offset at that date from the database (`zoneinfo`, with the `tzdata`
  package where the system has none).
- `julian_date`: the Julian date (UT) of a UTC instant, Meeus (1998), *Astronomical Algorithms*,
  2nd ed., ch. 7, eq. 7.1.
- `terrestrial_minus_universal_s`: ΔT = TT − UT [s]. From 1972 on: TAI − UTC from the leap-second
  table of IERS Bulletin C (the last leap second, 2016-12-31, makes TAI − UTC = 37 s; held
  constant afterwards) plus TT − TAI = 32.184 s (exact, IAU 1991). Before 1972: the polynomials
  of Espenak & Meeus (2006), "Polynomial expressions for Delta T", NASA Five Millennium Canon of
  Solar Eclipses (NASA/TP-2006-214141), section 2.6. UT1 − UTC (|x| < 0.9 s) is neglected, so
  UT ≈ UTC.

`check_utc` and `check_latitude`/`check_longitude`/`check_elevation` are the input checks that
every function of `skyscatter.astro` uses.

Public names: `parse_time`, `julian_date`, `terrestrial_minus_universal_s`, `julian_date_tt`,
`check_utc`, `check_latitude`, `check_longitude`, `check_elevation`, `J2000_JD`, `SECONDS_PER_DAY`.
"""

from __future__ import annotations

import datetime
import math
import numbers

from skyscatter.errors import InputError

__all__ = [
    "J2000_JD",
    "SECONDS_PER_DAY",
    "check_elevation",
    "check_latitude",
    "check_longitude",
    "check_utc",
    "julian_date",
    "julian_date_tt",
    "parse_time",
    "terrestrial_minus_universal_s",
]

J2000_JD = 2451545.0  # JD of the epoch J2000.0, 2000-01-01 12:00 TT (IAU 1976)
SECONDS_PER_DAY = 86400.0  # s per day (SI)
TT_MINUS_TAI_S = 32.184  # s, exact (IAU 1991 Resolution A4)
_UTC = datetime.UTC

# IERS Bulletin C: TAI − UTC [s] from each date (00:00 UTC) on; 10 s from 1972-01-01.
# Bulletin C 72 (2026) announces no new leap second; the last was inserted 2016-12-31.
_LEAP_SECONDS = (
    (datetime.datetime(1972, 1, 1, tzinfo=_UTC), 10.0),
    (datetime.datetime(1972, 7, 1, tzinfo=_UTC), 11.0),
    (datetime.datetime(1973, 1, 1, tzinfo=_UTC), 12.0),
    (datetime.datetime(1974, 1, 1, tzinfo=_UTC), 13.0),
    (datetime.datetime(1975, 1, 1, tzinfo=_UTC), 14.0),
    (datetime.datetime(1976, 1, 1, tzinfo=_UTC), 15.0),
    (datetime.datetime(1977, 1, 1, tzinfo=_UTC), 16.0),
    (datetime.datetime(1978, 1, 1, tzinfo=_UTC), 17.0),
    (datetime.datetime(1979, 1, 1, tzinfo=_UTC), 18.0),
    (datetime.datetime(1980, 1, 1, tzinfo=_UTC), 19.0),
    (datetime.datetime(1981, 7, 1, tzinfo=_UTC), 20.0),
    (datetime.datetime(1982, 7, 1, tzinfo=_UTC), 21.0),
    (datetime.datetime(1983, 7, 1, tzinfo=_UTC), 22.0),
    (datetime.datetime(1985, 7, 1, tzinfo=_UTC), 23.0),
    (datetime.datetime(1988, 1, 1, tzinfo=_UTC), 24.0),
    (datetime.datetime(1990, 1, 1, tzinfo=_UTC), 25.0),
    (datetime.datetime(1991, 1, 1, tzinfo=_UTC), 26.0),
    (datetime.datetime(1992, 7, 1, tzinfo=_UTC), 27.0),
    (datetime.datetime(1993, 7, 1, tzinfo=_UTC), 28.0),
    (datetime.datetime(1994, 7, 1, tzinfo=_UTC), 29.0),
    (datetime.datetime(1996, 1, 1, tzinfo=_UTC), 30.0),
    (datetime.datetime(1997, 7, 1, tzinfo=_UTC), 31.0),
    (datetime.datetime(1999, 1, 1, tzinfo=_UTC), 32.0),
    (datetime.datetime(2006, 1, 1, tzinfo=_UTC), 33.0),
    (datetime.datetime(2009, 1, 1, tzinfo=_UTC), 34.0),
    (datetime.datetime(2012, 7, 1, tzinfo=_UTC), 35.0),
    (datetime.datetime(2015, 7, 1, tzinfo=_UTC), 36.0),
    (datetime.datetime(2017, 1, 1, tzinfo=_UTC), 37.0),
)

_EXAMPLE = "e.g. 2024-06-21T21:30+02:00, 2024-06-21T19:30Z or 2024-06-21T21:30[Europe/Berlin]"


def parse_time(text: str) -> datetime.datetime:
    """Parse an ISO 8601 date-time with a time zone; return it as an aware datetime in UTC.

    Accepts what `datetime.fromisoformat` (Python 3.11) accepts, including a trailing "Z":
    "2024-06-21T21:30+02:00", "2024-06-21 19:30:00Z", "2024-06-21T19:30:00.5+00:00"; or a
    local date-time followed by an IANA zone, "2024-06-21T21:30[Europe/Berlin]" (RFC 9557) or
    "2024-06-21T21:30 Europe/Berlin" (with an offset too, "...+02:00[Europe/Berlin]", the
    two must agree). A local time that a zone's clocks skip or repeat (when
    daylight saving time starts or ends) is taken with the offset before the change (PEP 495,
    fold = 0).

    Raises
    ------
    InputError
        The text has no time zone, names an unknown zone, is not an ISO 8601 date-time, or lies
        outside the years 1-9999 in UTC; the message shows a fix.
    """
    if not isinstance(text, str):
        raise InputError(f"--time {text!r} must be text such as 2024-06-21T21:30+02:00",
                         key="time", value=text, allowed="ISO 8601 date-time with a time zone")
    local, zone = _split_zone(text.strip())
    try:
        parsed = datetime.datetime.fromisoformat(local)
    except ValueError:
        raise InputError(f"--time {text!r} is not an ISO 8601 date-time; write it as "
                         f"YYYY-MM-DDTHH:MM with a time zone, {_EXAMPLE}", key="time", value=text,
                         allowed="ISO 8601 date-time with a time zone") from None
    if zone is not None:
        zoned = parsed.replace(tzinfo=_zone(zone, text))
        if parsed.tzinfo is not None and parsed.utcoffset() != zoned.utcoffset():
            raise InputError(f"--time {text!r}: the offset is not {zone}'s at that time "
                             f"({zoned.isoformat()}); give the zone alone", key="time",
                             value=text, allowed="an offset that agrees with the zone")
        parsed = zoned
    if parsed.tzinfo is None or parsed.utcoffset() is None:
        raise InputError(f"--time {text!r} has no time zone; add one, {_EXAMPLE}", key="time",
                         value=text, allowed="ISO 8601 date-time with a time zone")
    return _in_utc(parsed, f"--time {text!r}", "time")


def _split_zone(text: str) -> tuple[str, str | None]:
    """(the date-time, the IANA zone name or None) of "...[Zone]" or "... Zone"."""
    if text.endswith("]") and "[" in text:
        local, _, zone = text[:-1].rpartition("[")
        return local.strip(), zone.strip()
    head, _, tail = text.rpartition(" ")
    if head and ("/" in tail or tail in ("UTC", "GMT")):
        return head.strip(), tail
    return text, None


def _zone(name: str, text: str) -> datetime.tzinfo:
    """The IANA zone `name`; InputError naming the text when the database has no such zone."""
    import zoneinfo

    try:
        return zoneinfo.ZoneInfo(name)
    except (zoneinfo.ZoneInfoNotFoundError, ValueError, OSError):  # unknown, or not a name
        raise InputError(f"--time {text!r}: {name!r} is not a zone of the IANA time zone "
                         "database; write it as Continent/City (Europe/Berlin, America/New_York) "
                         "or give an offset such as +02:00", key="time", value=text,
                         allowed="IANA zone names, e.g. Europe/Berlin") from None


def _in_utc(time: datetime.datetime, what: str, name: str) -> datetime.datetime:
    """An aware `time` in UTC; InputError when that falls outside the years 1-9999 that
    Python's datetime holds (0001-01-01T00:00+05:00 is in the year 0 in UTC)."""
    try:
        return time.astimezone(_UTC)
    except OverflowError:
        raise InputError(f"{what} is outside the years 1-9999 once converted to UTC; give a "
                         "time from 0001-01-01T00:00Z to 9999-12-31T23:59Z", key=name,
                         value=time, allowed="0001-01-01T00:00Z to 9999-12-31T23:59:59Z") from None


def check_utc(utc: datetime.datetime, name: str = "utc") -> datetime.datetime:
    """Return `utc` as an aware datetime in UTC; InputError if it is not an aware datetime."""
    if not isinstance(utc, datetime.datetime):
        raise InputError(f"{name} = {utc!r} must be a datetime with a time zone, "
                         f"e.g. parse_time('2024-06-21T19:30Z')", key=name, value=utc,
                         allowed="aware datetime.datetime")
    if utc.tzinfo is None or utc.utcoffset() is None:
        raise InputError(f"{name} = {utc.isoformat()} has no time zone; add one, e.g. "
                         f"{name}.replace(tzinfo=datetime.timezone.utc) or parse_time('...Z')",
                         key=name, value=utc, allowed="aware datetime.datetime")
    return _in_utc(utc, f"{name} = {utc.isoformat()}", name)


def _finite_float(value: float, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise InputError(f"{name} = {value!r} must be a finite number [{unit}]", key=name,
                         value=value, allowed=f"finite number [{unit}]")
    return float(value)


def check_latitude(latitude_deg: float, name: str = "latitude_deg") -> float:
    """Latitude as a float in [-90, 90] [deg]; InputError otherwise."""
    lat = _finite_float(latitude_deg, name, "deg")
    if not -90.0 <= lat <= 90.0:
        raise InputError(f"{name} = {latitude_deg!r} must be in [-90, 90] degrees (north "
                         f"positive)", key=name, value=latitude_deg, allowed="[-90, 90] deg")
    return lat


def check_longitude(longitude_deg: float, name: str = "longitude_deg") -> float:
    """Longitude (east positive) wrapped to [-180, 180) [deg]; InputError if not finite."""
    lon = _finite_float(longitude_deg, name, "deg")
    return (lon + 180.0) % 360.0 - 180.0


def check_elevation(elevation_m: float, name: str = "elevation_m") -> float:
    """Elevation above the reference ellipsoid, >= -500 m (the Dead Sea shore is -430 m) [m]."""
    h = _finite_float(elevation_m, name, "m")
    if h < -500.0:
        raise InputError(f"{name} = {elevation_m!r} must be >= -500 m above sea level",
                         key=name, value=elevation_m, allowed=">= -500 m")
    return h


def julian_date(utc: datetime.datetime) -> float:
    """Julian date (UT) of an instant.

        JD = INT(365.25 (Y + 4716)) + INT(30.6001 (M + 1)) + D + B - 1524.5,
        B = 2 - A + INT(A/4),   A = INT(Y/100)

    with Y, M the year and month (January and February counted as months 13 and 14 of the
    previous year) and D the day with its fraction; Meeus (1998), ch. 7, eq. 7.1. Python's
    `datetime` is proleptic Gregorian, so the Gregorian B is used for every date (Meeus uses
    the Julian calendar, B = 0, before 1582-10-15: pass such dates converted to Gregorian).

    Parameters
    ----------
    utc : datetime.datetime
        An aware datetime (any zone; converted to UTC).

    Returns
    -------
    float
        Julian date, counting UT (≈ UTC, |UT1 − UTC| < 0.9 s) days. [d]
    """
    t = check_utc(utc)
    year, month = t.year, t.month
    if month <= 2:
        year, month = year - 1, month + 12
    a = year // 100
    b = 2 - a + a // 4
    seconds = t.hour * 3600.0 + t.minute * 60.0 + t.second + t.microsecond * 1e-6
    day = t.day + seconds / SECONDS_PER_DAY
    return (math.floor(365.25 * (year + 4716)) + math.floor(30.6001 * (month + 1))
            + day + b - 1524.5)


def _decimal_year(t: datetime.datetime) -> float:
    start = datetime.datetime(t.year, 1, 1, tzinfo=_UTC)
    length = (datetime.datetime(t.year + 1, 1, 1, tzinfo=_UTC) - start
              if t.year < 9999 else datetime.timedelta(days=365))
    return t.year + (t - start) / length


def _delta_t_espenak_meeus_2006(y: float) -> float:
    """ΔT [s] at decimal year y, Espenak & Meeus (2006), NASA/TP-2006-214141, section 2.6."""
    if y < -500.0:
        u = (y - 1820.0) / 100.0
        return -20.0 + 32.0 * u * u
    if y < 500.0:
        u = y / 100.0
        return (10583.6 - 1014.41 * u + 33.78311 * u**2 - 5.952053 * u**3 - 0.1798452 * u**4
                + 0.022174192 * u**5 + 0.0090316521 * u**6)
    if y < 1600.0:
        u = (y - 1000.0) / 100.0
        return (1574.2 - 556.01 * u + 71.23472 * u**2 + 0.319781 * u**3 - 0.8503463 * u**4
                - 0.005050998 * u**5 + 0.0083572073 * u**6)
    if y < 1700.0:
        t = y - 1600.0
        return 120.0 - 0.9808 * t - 0.01532 * t**2 + t**3 / 7129.0
    if y < 1800.0:
        t = y - 1700.0
        return 8.83 + 0.1603 * t - 0.0059285 * t**2 + 0.00013336 * t**3 - t**4 / 1174000.0
    if y < 1860.0:
        t = y - 1800.0
        return (13.72 - 0.332447 * t + 0.0068612 * t**2 + 0.0041116 * t**3 - 0.00037436 * t**4
                + 0.0000121272 * t**5 - 0.0000001699 * t**6 + 0.000000000875 * t**7)
    if y < 1900.0:
        t = y - 1860.0
        return (7.62 + 0.5737 * t - 0.251754 * t**2 + 0.01680668 * t**3
                - 0.0004473624 * t**4 + t**5 / 233174.0)
    if y < 1920.0:
        t = y - 1900.0
        return -2.79 + 1.494119 * t - 0.0598939 * t**2 + 0.0061966 * t**3 - 0.000197 * t**4
    if y < 1941.0:
        t = y - 1920.0
        return 21.20 + 0.84493 * t - 0.076100 * t**2 + 0.0020936 * t**3
    if y < 1961.0:
        t = y - 1950.0
        return 29.07 + 0.407 * t - t**2 / 233.0 + t**3 / 2547.0
    t = y - 1975.0  # 1961-1986 (used here up to 1972)
    return 45.45 + 1.067 * t - t**2 / 260.0 - t**3 / 718.0


def terrestrial_minus_universal_s(utc: datetime.datetime) -> float:
    """ΔT = TT − UT at an instant. [s]

        ΔT = (TAI − UTC) + 32.184 s                      from 1972-01-01 (UT ≈ UTC)
        ΔT = Espenak & Meeus (2006) polynomial in the decimal year      before 1972

    TAI − UTC: the leap-second table of IERS Bulletin C, 10 s in 1972 to 37 s since
    2017-01-01, held at 37 s for later dates (no leap second is announced; the true ΔT will
    drift by about a second per year or two once they resume or UT1 − UTC grows). Before 1972:
    Espenak & Meeus (2006), NASA/TP-2006-214141, section 2.6; their 1961-1986 expression gives
    42.25 s at 1972.0, 0.07 s from the tabulated 42.184 s, so ΔT is continuous to 0.1 s.
    """
    t = check_utc(utc)
    if t < _LEAP_SECONDS[0][0]:
        return _delta_t_espenak_meeus_2006(_decimal_year(t))
    tai_minus_utc = _LEAP_SECONDS[0][1]
    for start, value in _LEAP_SECONDS:
        if t >= start:
            tai_minus_utc = value
        else:
            break
    return tai_minus_utc + TT_MINUS_TAI_S


def julian_date_tt(utc: datetime.datetime) -> float:
    """Julian date in Terrestrial Time, JD(UT) + ΔT/86400. [d]"""
    return julian_date(utc) + terrestrial_minus_universal_s(utc) / SECONDS_PER_DAY
