"""The Hipparcos star catalogue: parsing, Johnson V, positions, proper motion
(skyscatter.astro.star_catalogue)."""

import datetime as dt
import math

import numpy as np
import pytest

from skyscatter.astro import star_catalogue
from skyscatter.astro.star_catalogue import (
    hipparcos_v_minus_hp_bessell_2000,
    julian_year,
    load_star_catalogue,
)
from skyscatter.errors import InputError

ARCSEC = math.pi / (180.0 * 3600.0)
ARCMIN = 60.0 * ARCSEC


def unit(ra_rad, dec_rad):
    return np.array([math.cos(dec_rad) * math.cos(ra_rad), math.cos(dec_rad) * math.sin(ra_rad),
                     math.sin(dec_rad)])


def angle(a, b):
    return math.atan2(np.linalg.norm(np.cross(a, b)), float(np.dot(a, b)))


@pytest.fixture(scope="module")
def catalogue():
    return load_star_catalogue()


def test_catalogue_has_all_hip2_records(catalogue):
    # van Leeuwen (2007), CDS I/311: 117 955 entries; none lacks Hp or B-V.
    assert len(catalogue) == 117_955
    assert not catalogue.colour_missing.any()
    assert np.all(np.diff(catalogue.hip) > 0)
    np.testing.assert_allclose(np.linalg.norm(catalogue.unit_vectors, axis=1), 1.0, atol=1e-15)


def test_naked_eye_star_count_is_about_5000():
    # Reference: ~5000 stars of V < 6 (Yale Bright Star Catalogue counts 4800-5100 to V = 6.0,
    # Hoffleit & Warren 1991). Hipparcos splits some doubles the BSC lists as one entry, so the
    # upper bound gets 4 % more. Measured: 5098.
    count = len(load_star_catalogue(6.0))
    assert 4800 <= count <= 5300


def test_sirius_v_magnitude(catalogue):
    # Bright Star Catalogue V = -1.46 (Sirius' Hp is off the V scale, so this checks the BSC5
    # override path of the loader; the colour conversion is checked below).
    assert catalogue.v_magnitude[catalogue.index_of(32349)] == pytest.approx(-1.46, abs=0.03)
    # and independently of the override's own number: PyEphem's Hipparcos-based V, -1.44
    import ephem

    sirius = ephem.star("Sirius")
    sirius.compute("2000/1/1")
    assert catalogue.v_magnitude[catalogue.index_of(32349)] == pytest.approx(sirius.mag,
                                                                              abs=0.03)


def test_vega_v_magnitude_from_hp_and_bessell_2000(catalogue):
    # Ours: Hp 0.0868 + (V - Hp)(B-V = -0.001) from Bessell (2000) Table 2 = 0.075.
    # Reference: V = 0.03 (Johnson; Hipparcos H5). Tolerance 0.06 mag: Bessell's mean relation
    # has ~0.02 mag star-to-star scatter and Vega (pole-on fast rotator) sits 0.045 mag off it.
    assert catalogue.v_magnitude[catalogue.index_of(91262)] == pytest.approx(0.03, abs=0.06)


def test_v_magnitudes_match_hipparcos_main_catalogue_johnson_v(catalogue):
    # Reference: Johnson V (field H5 of ESA 1997, I/239 hip_main.dat) and J2000 positions of
    # the ~110 bright stars shipped with PyEphem 4.2.1 (ephem.stars; positions propagated by
    # Skyfield). Measured: median |ΔV| 0.013 mag, 90th percentile 0.047, largest 0.25 (M giants,
    # which are variable and beyond Bessell's table); positions agree to <= 0.17".
    ephem = pytest.importorskip("ephem")
    bright_star_table = pytest.importorskip("ephem.stars").db

    directions = catalogue.directions_at(2000.0)
    bright = catalogue.v_magnitude < 8.0
    dv, separations, seen = [], [], set()
    for line in bright_star_table.strip().splitlines():
        star = ephem.star(line.split(",")[0])
        star.compute("2000/1/1 12:00", epoch=ephem.J2000)
        key = (float(star.a_ra), float(star.a_dec))
        if key in seen:  # alternative names of one star
            continue
        seen.add(key)
        cosine = np.where(bright, directions @ unit(*key), -2.0)
        row = int(np.argmax(cosine))
        separations.append(math.acos(min(cosine[row], 1.0)))
        if catalogue.b_minus_v[row] < 1.4:  # M stars: see module docstring
            dv.append(catalogue.v_magnitude[row] - star.mag)
    dv = np.abs(dv)
    assert len(seen) > 100
    assert np.median(dv) < 0.03
    assert np.percentile(dv, 90) < 0.06
    assert max(separations) < 0.5 * ARCSEC


def test_polaris_j2000_position(catalogue):
    # Reference: Polaris (HIP 11767) α = 02h31m49.09s, δ = +89°15'50.8" (ICRS, J2000; SIMBAD).
    # Tolerance 1': the brief's requirement (measured agreement is far better, < 0.1").
    ra = (2.0 + 31.0 / 60.0 + 49.09 / 3600.0) * 15.0 * math.pi / 180.0
    dec = (89.0 + 15.0 / 60.0 + 50.8 / 3600.0) * math.pi / 180.0
    ours = catalogue.directions_at(2000.0)[catalogue.index_of(11767)]
    assert angle(ours, unit(ra, dec)) < 1.0 * ARCMIN
    assert angle(ours, unit(ra, dec)) < 0.5 * ARCSEC


def test_barnards_star_proper_motion(catalogue):
    # Reference: Barnard (1916), AJ 29, 181: 10.3"/yr. Tolerance 0.1"/yr.
    row = catalogue.index_of(87937)
    a = catalogue.directions_at(1991.25)[row]
    b = catalogue.directions_at(2001.25)[row]
    assert angle(a, b) / 10.0 == pytest.approx(10.3 * ARCSEC, abs=0.1 * ARCSEC)
    # Moves north (μδ > 0): declination grows.
    assert b[2] > a[2]


def test_directions_at_datetime_equals_julian_year(catalogue):
    moment = dt.datetime(2024, 7, 2, 12, tzinfo=dt.UTC)
    assert julian_year(moment) == pytest.approx(2024.5, abs=0.01)
    assert julian_year(dt.datetime(2000, 1, 1, 12)) == pytest.approx(2000.0, abs=1e-12)
    np.testing.assert_array_equal(catalogue.directions_at(moment),
                                  catalogue.directions_at(julian_year(moment)))
    with pytest.raises(InputError, match="epoch"):
        catalogue.directions_at("2024")


def test_v_minus_hp_table_is_held_at_its_ends():
    v_hp = hipparcos_v_minus_hp_bessell_2000([-1.0, -0.005, 1.034, 3.0])
    np.testing.assert_allclose(v_hp, [0.066, -0.011, -0.162, -0.162])


def test_magnitude_limit_selects(catalogue):
    bright = load_star_catalogue(2.0)
    assert np.all(bright.v_magnitude <= 2.0)
    assert len(bright) == int(np.sum(catalogue.v_magnitude <= 2.0))
    with pytest.raises(InputError, match="magnitude_limit"):
        load_star_catalogue(float("nan"))
    with pytest.raises(InputError, match="HIP 1000000"):
        catalogue.index_of(1_000_000)


def test_parse_and_disk_cache_round_trips(tmp_path):
    # Timings (0.15 s parse, 0.03 s from the .npz cache) are measured by
    # benchmarks/bench_stars.py, not asserted here (STYLE: no timings in tests).
    parsed = star_catalogue._parse_hip2(star_catalogue._catalogue_path())
    first = load_star_catalogue(cache_directory=tmp_path)
    assert (tmp_path / "hipparcos_hip2.npz").exists()
    star_catalogue._full_catalogue.cache_clear()
    second = load_star_catalogue(cache_directory=tmp_path)
    np.testing.assert_array_equal(first.v_magnitude, second.v_magnitude)
    np.testing.assert_array_equal(second.hip, parsed["hip"])
    np.testing.assert_array_equal(first.unit_vectors, second.unit_vectors)
