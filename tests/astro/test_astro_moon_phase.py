"""Moon phase, bright limb and eclipse shadow geometry (astro/moon_phase.py) against ephem,
Meeus' formulas and NASA's published lunar-eclipse magnitudes."""

import math

import ephem
import numpy as np
import pytest

from skyscatter.astro import moon_phase as mp
from skyscatter.errors import InputError

DEG = math.pi / 180.0
PERCENT = 0.01


@pytest.fixture(scope="module")
def geocentric():
    """Geocentric GCRS Sun and Moon vectors [m] from astropy's builtin ephemeris, offline."""
    from astropy.utils import iers
    from astropy.utils.data import conf

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    conf.allow_internet = False
    from astropy.coordinates import get_body, solar_system_ephemeris
    from astropy.time import Time

    def vectors(times, scale="utc"):
        t = Time(times, scale=scale)
        with solar_system_ephemeris.set("builtin"):
            moon = get_body("moon", t)
            sun = get_body("sun", t)
        return (moon.cartesian.xyz.to_value("m").T, sun.cartesian.xyz.to_value("m").T,
                moon, sun)

    return vectors


def test_illuminated_fraction_matches_ephem_over_a_month(geocentric):
    # Ours: k = (1 + cos i)/2 from astropy vectors; reference: PyEphem 4.2.1 Moon.moon_phase
    # (geocentric). Tolerance 0.5 % of the disk: the two ephemerides (ELP/VSOP vs ephem's
    # libastro) differ by arcseconds to arcminutes; measured worst 0.08 %.
    times = [f"2024-01-{d:02d} {h:02d}:00" for d in range(1, 31) for h in (0, 6, 12, 18)]
    moon, sun, *_ = geocentric(times)
    ours = mp.illuminated_fraction(moon, sun)
    theirs = np.array([ephem.Moon(ephem.Date(t.replace("-", "/"))).moon_phase for t in times])
    np.testing.assert_allclose(ours, theirs, atol=0.5 * PERCENT)
    assert ours.min() < 0.01 and ours.max() > 0.99  # a whole lunation was covered


@pytest.mark.parametrize("instant", ["2024-01-25 17:54", "2022-11-08 11:02"])
def test_phase_angle_equals_ecliptic_latitude_at_published_full_moons(geocentric, instant):
    # Full-moon instants (UTC) from the published moon-phase tables (USNO / Espenak): there the
    # geocentric ecliptic longitudes of Sun and Moon differ by exactly 180°, so the phase angle
    # is the Moon's ecliptic latitude |β| (the Sun's is < 1″). 2024-01-25: |β| ≈ 4.8° (far from
    # a node, so i is not small); 2022-11-08: total eclipse, |β| ≈ 0.2°. Tolerance 0.05°: the
    # minute-rounded instant (0.5°/h relative motion -> 0.004°) and the ephemeris (~10″).
    from astropy.coordinates import GeocentricTrueEcliptic

    moon, sun, moon_c, _ = geocentric([instant])
    i = mp.phase_angle_rad(moon, sun)[0]
    beta = abs(moon_c.transform_to(GeocentricTrueEcliptic(equinox=moon_c.obstime)).lat.rad[0])
    assert i == pytest.approx(beta, abs=0.05 * DEG)
    assert i < 5.3 * DEG  # the Moon's orbit is inclined 5.1°


def test_umbral_and_penumbral_magnitudes_match_nasa_2022_nov_08(geocentric):
    # NASA (Espenak) total lunar eclipse 2022 Nov 08, greatest eclipse 10:59:11 TD: umbral
    # magnitude 1.3590, penumbral 2.4165. NASA's predictions enlarge the shadow by Danjon's rule
    # (Espenak & Meeus 2009 §1.4). Tolerance 0.005: astropy's builtin Moon (ELP-2000/82 via
    # ERFA, ~10″) vs NASA's ELP/DE ephemeris and their apparent-place reduction; measured
    # 0.0002 (umbral) and 0.002 (penumbral). Chauvenet's 2 % rule gives 1.364 / 2.440, i.e.
    # off by 0.005 / 0.024 — the test would tell the rules apart in the penumbra.
    moon, sun, *_ = geocentric(["2022-11-08 10:59:11"], scale="tt")
    umbral, penumbral = mp.eclipse_magnitudes(moon, sun, enlargement="danjon")
    assert umbral[0] == pytest.approx(1.3590, abs=0.005)
    assert penumbral[0] == pytest.approx(2.4165, abs=0.005)
    _, penumbral_chauvenet = mp.eclipse_magnitudes(moon, sun, enlargement="chauvenet")
    assert abs(penumbral_chauvenet[0] - 2.4165) > 0.015


def test_umbral_magnitude_matches_nasa_2025_mar_14(geocentric):
    # NASA (Espenak) total lunar eclipse 2025 Mar 14, greatest 06:58:44 TD: umbral magnitude
    # 1.1784. Tolerance 0.005 as above; measured 0.00003.
    moon, sun, *_ = geocentric(["2025-03-14 06:58:44"], scale="tt")
    umbral, penumbral = mp.eclipse_magnitudes(moon, sun)
    assert umbral[0] == pytest.approx(1.1784, abs=0.005)
    assert penumbral[0] > umbral[0] + 1.0  # the penumbra is ~2 s_sun / (2 s_m) ≈ 1.1 wider


def test_penumbral_eclipse_2024_mar_25_misses_the_umbra(geocentric):
    # NASA: 2024 Mar 25 was a penumbral eclipse (greatest 07:12:51 TD), penumbral magnitude
    # ≈ 0.956, umbral ≈ -0.13 (the Moon never touched the umbra). Tolerance 0.01: as above.
    moon, sun, *_ = geocentric(["2024-03-25 07:12:51"], scale="tt")
    umbral, penumbral = mp.eclipse_magnitudes(moon, sun)
    assert -0.15 < umbral[0] < -0.11
    assert 0.945 < penumbral[0] < 0.97


def test_bright_limb_position_angle_matches_meeus_48_5(geocentric):
    # Reference: Meeus (1998) eq. 48.5 with the GCRS right ascensions and declinations of the
    # Sun (α0, δ0) and Moon (α, δ). Ours projects the Moon-Sun vector, Meeus uses the Earth-Sun
    # direction: they differ by the Sun's parallax seen from the Moon, ~(d_moon/d_sun) sin i ≤
    # 0.15°, magnified near full and new moon, which are excluded (15° < i < 165°). Tolerance 1°.
    times = [f"2024-02-{d:02d} 12:00" for d in range(1, 29)]
    moon, sun, moon_c, sun_c = geocentric(times)
    ours = mp.bright_limb_position_angle_rad(moon, sun)
    a, d = moon_c.ra.rad, moon_c.dec.rad
    a0, d0 = sun_c.ra.rad, sun_c.dec.rad
    chi = np.arctan2(np.cos(d0) * np.sin(a0 - a),
                     np.sin(d0) * np.cos(d) - np.cos(d0) * np.sin(d) * np.cos(a0 - a))
    i = mp.phase_angle_rad(moon, sun)
    keep = (i > 15 * DEG) & (i < 165 * DEG)
    assert keep.sum() > 15
    diff = np.angle(np.exp(1j * (ours - chi)))[keep]
    assert np.max(np.abs(diff)) < 1.0 * DEG


def test_bright_limb_direction_is_perpendicular_to_the_line_of_sight():
    moon = np.array([3.8e8, 0.0, 0.0])
    sun = np.array([0.0, 1.496e11, 0.0])  # first quarter: Sun 90° away, to +y
    b = mp.bright_limb_direction(moon, sun)
    np.testing.assert_allclose(b, [0.0, 1.0, 0.0], atol=1e-3)
    assert mp.illuminated_fraction(moon, sun) == pytest.approx(0.5, abs=2e-3)
    # east of north: +y is east of +x seen with the pole +z, so χ = 90°
    assert mp.bright_limb_position_angle_rad(moon, sun) == pytest.approx(np.pi / 2, abs=2e-3)


def test_angular_radius_and_shadow_radii_closed_forms():
    # Closed forms: s = asin(R/d); at mean distances (384 400 km, 1 AU) the seed's eqs. 4.14-4.15
    # give the umbra/penumbra radii 3.6676 -/+ (397.0 or 404.3) D_m/D_s moon radii with
    # R_e = 6371 km, r_m = 1737.1 km. Tolerance 1e-3 moon radii (small-angle vs asin).
    d_m, d_s = 384_400e3, 1.495978707e11
    assert mp.moon_angular_radius_rad(d_m) == pytest.approx(math.asin(1737.4 / 384400.0))
    u, p = mp.shadow_radii_rad(d_m, d_s, "none", earth_radius_m=6371e3, sun_radius_m=696000e3)
    moon_radius_angle = 1737.1e3 / d_m
    assert u / moon_radius_angle == pytest.approx(3.6676 - 397.0001 * d_m / d_s, abs=1e-3)
    assert p / moon_radius_angle == pytest.approx(3.6676 + 404.3354 * d_m / d_s, abs=1e-3)


@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_shapes_broadcast(shape):
    rng = np.random.default_rng(1)
    moon = rng.normal(size=shape + (3,)) * 3.8e8
    sun = rng.normal(size=shape + (3,)) * 1.5e11
    for f in (mp.phase_angle_rad, mp.illuminated_fraction, mp.bright_limb_position_angle_rad,
              mp.shadow_axis_distance_rad):
        out = f(moon, sun)
        assert out.shape == shape and np.all(np.isfinite(out))
    assert mp.bright_limb_direction(moon, sun).shape == shape + (3,)
    u, p = mp.eclipse_magnitudes(moon, sun)
    assert u.shape == shape and p.shape == shape


def test_edges_full_and_new_moon_are_finite():
    moon = np.array([3.8e8, 0.0, 0.0])
    assert mp.phase_angle_rad(moon, -1.5e11 * np.array([1.0, 0, 0])) == pytest.approx(0.0)
    assert mp.phase_angle_rad(moon, 1.5e11 * np.array([1.0, 0, 0])) == pytest.approx(np.pi)
    assert np.all(np.isnan(mp.bright_limb_direction(moon, -1.5e11 * np.array([1.0, 0, 0]))))


def test_bad_inputs_raise_input_error():
    with pytest.raises(InputError, match="enlargement"):
        mp.shadow_radii_rad(3.8e8, 1.5e11, enlargement="2percent")
    with pytest.raises(InputError, match=r"shape \(\.\.\., 3\)"):
        mp.phase_angle_rad([1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="moon_distance_m"):
        mp.moon_angular_radius_rad(1000.0)
