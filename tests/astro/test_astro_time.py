"""Time: ISO parsing, Julian dates (Meeus ch. 7 examples) and ΔT = TT − UT."""

import datetime

import pytest

from skyscatter.astro.time import julian_date, parse_time, terrestrial_minus_universal_s
from skyscatter.errors import InputError

UTC = datetime.UTC
SECOND_IN_DAYS = 1.0 / 86400.0


def _utc(year, month, day_with_fraction):
    day = int(day_with_fraction)
    return (datetime.datetime(year, month, day, tzinfo=UTC)
            + datetime.timedelta(days=day_with_fraction - day))


@pytest.mark.parametrize(("when", "expected"), [
    (_utc(1957, 10, 4.81), 2436116.31),   # Meeus ex. 7.a (Sputnik 1)
    (_utc(2000, 1, 1.5), 2451545.0),      # Meeus p. 62
    (_utc(1987, 1, 27.0), 2446822.5),     # Meeus p. 62
    (_utc(1987, 6, 19.5), 2446966.0),
    (_utc(1988, 1, 27.0), 2447187.5),
    (_utc(1988, 6, 19.5), 2447332.0),
    (_utc(1900, 1, 1.0), 2415020.5),
    (_utc(1600, 1, 1.0), 2305447.5),
    (_utc(1600, 12, 31.0), 2305812.5),
    (datetime.datetime(1990, 1, 1, 18, tzinfo=UTC), 2447893.25),  # seed digest S.16
    (datetime.datetime(2006, 1, 14, 16, 30, tzinfo=UTC), 2453750.1875),
    (datetime.datetime(1582, 10, 15, tzinfo=UTC), 2299160.5),  # first Gregorian day
])
def test_julian_date_matches_meeus_examples(when, expected):
    # Meeus prints 2 decimals for 1957-10-04.81 (exact: .31); tolerance: 1 ms.
    assert julian_date(when) == pytest.approx(expected, abs=1e-3 * SECOND_IN_DAYS)


def test_julian_date_counts_days_from_the_unix_epoch():
    # Identity: JD(1970-01-01 00:00 UTC) = 2440587.5 and one day per 86400 s, to 50 µs
    # (float64 resolution of a JD near 2.4e6).
    start = datetime.datetime(1970, 1, 1, tzinfo=UTC)
    for seconds in (0.0, 1.25e9, -2.0e9, 3.3e9):
        jd = julian_date(start + datetime.timedelta(seconds=seconds))
        assert jd == pytest.approx(2440587.5 + seconds / 86400.0, abs=5e-5 * SECOND_IN_DAYS)


def test_julian_date_accepts_any_time_zone():
    berlin = datetime.timezone(datetime.timedelta(hours=2))
    local = datetime.datetime(2024, 6, 21, 21, 30, tzinfo=berlin)
    assert julian_date(local) == julian_date(datetime.datetime(2024, 6, 21, 19, 30, tzinfo=UTC))


def test_parse_time_returns_utc():
    assert parse_time("2024-06-21T21:30+02:00") == datetime.datetime(2024, 6, 21, 19, 30,
                                                                     tzinfo=UTC)
    parsed = parse_time("2024-06-21T19:30:15.5Z")
    assert parsed.tzinfo == UTC and parsed.microsecond == 500000


def test_parse_time_refuses_a_time_without_zone():
    with pytest.raises(InputError, match=r"--time '2024-06-21 21:30' has no time zone; add one"):
        parse_time("2024-06-21 21:30")


def test_parse_time_refuses_garbage():
    with pytest.raises(InputError, match="not an ISO 8601 date-time"):
        parse_time("midsummer")


def test_naive_datetime_is_refused_everywhere():
    with pytest.raises(InputError, match="has no time zone"):
        julian_date(datetime.datetime(2024, 6, 21, 19, 30))


@pytest.mark.parametrize(("when", "expected_s"), [
    # TAI − UTC (IERS Bulletin C) + 32.184 s.
    (datetime.datetime(1972, 1, 1, tzinfo=UTC), 42.184),
    (datetime.datetime(1999, 12, 31, 23, 59, 59, tzinfo=UTC), 64.184),
    (datetime.datetime(2000, 1, 6, tzinfo=UTC), 64.184),        # Mars24 example A, step A-4
    (datetime.datetime(2004, 1, 3, 13, 46, 31, tzinfo=UTC), 64.184),  # Mars24 example B
    (datetime.datetime(2016, 12, 31, 23, 59, 59, tzinfo=UTC), 68.184),
    (datetime.datetime(2017, 1, 1, tzinfo=UTC), 69.184),
    (datetime.datetime(2040, 1, 1, tzinfo=UTC), 69.184),        # held after the last one
])
def test_delta_t_from_leap_seconds(when, expected_s):
    assert terrestrial_minus_universal_s(when) == pytest.approx(expected_s, abs=1e-9)


@pytest.mark.parametrize(("year", "published_s", "tolerance_s"), [
    # Observed ΔT, Espenak & Meeus (2006) Table 1 / Meeus (1998) Table 10.A; the polynomials
    # reproduce them to about 1 s (their stated fit quality in the modern era).
    (1900, -2.8, 1.0),
    (1950, 29.1, 1.0),
    (1960, 33.2, 1.0),
    (1800, 13.7, 1.0),
    (1700, 8.8, 1.0),
])
def test_delta_t_before_1972_matches_observed_values(year, published_s, tolerance_s):
    when = datetime.datetime(year, 1, 1, tzinfo=UTC)
    assert terrestrial_minus_universal_s(when) == pytest.approx(published_s, abs=tolerance_s)


def test_delta_t_is_continuous_at_1972():
    # The polynomial meets the leap-second value within 0.1 s (42.25 s vs 42.184 s).
    before = terrestrial_minus_universal_s(datetime.datetime(1971, 12, 31, 23, 59, tzinfo=UTC))
    after = terrestrial_minus_universal_s(datetime.datetime(1972, 1, 1, tzinfo=UTC))
    assert abs(after - before) < 0.1


# References: Directive 2000/84/EC (EU summer time from the last Sunday of March, 01:00 UTC, to
# the last Sunday of October, 01:00 UTC; Berlin is UTC+1 in winter, UTC+2 in summer) and the US
# Energy Policy Act of 2005, sec. 110 (New York: UTC-4 from the second Sunday of March to the
# first Sunday of November, else UTC-5).
@pytest.mark.parametrize("text, utc", [
    ("2024-06-21T21:30[Europe/Berlin]", "2024-06-21T19:30+00:00"),
    ("2024-01-21T21:30 Europe/Berlin", "2024-01-21T20:30+00:00"),
    ("2024-03-31T01:59[Europe/Berlin]", "2024-03-31T00:59+00:00"),  # the last minute of winter
    ("2024-03-31T03:00[Europe/Berlin]", "2024-03-31T01:00+00:00"),  # the first of summer
    ("2024-07-04T12:00[America/New_York]", "2024-07-04T16:00+00:00"),
    ("2024-12-25T12:00 America/New_York", "2024-12-25T17:00+00:00"),
    ("2024-06-21T21:30+02:00[Europe/Berlin]", "2024-06-21T19:30+00:00"),  # RFC 9557, agreeing
])
def test_a_time_in_an_iana_zone_takes_the_zones_offset_at_that_date(text, utc):
    assert parse_time(text) == datetime.datetime.fromisoformat(utc)


def test_a_skipped_local_time_takes_the_offset_before_the_change():
    # 02:30 does not exist in Berlin on 2024-03-31 (01:00 UTC the clocks go from 02:00 to
    # 03:00); PEP 495's fold = 0 reads it with the winter offset, +01:00.
    assert parse_time("2024-03-31T02:30[Europe/Berlin]") == datetime.datetime(
        2024, 3, 31, 1, 30, tzinfo=datetime.UTC)


@pytest.mark.parametrize("text, message", [
    ("2024-06-21T21:30[Europe/Berln]", "not a zone of the IANA time zone database"),
    ("2024-06-21T21:30[../../etc/passwd]", "not a zone of the IANA time zone database"),
    ("2024-06-21T21:30+01:00[Europe/Berlin]", "the offset is not Europe/Berlin's"),
    ("[Europe/Berlin]", "not an ISO 8601 date-time"),
])
def test_a_bad_zone_is_refused_with_a_fix(text, message):
    with pytest.raises(InputError, match=message):
        parse_time(text)
