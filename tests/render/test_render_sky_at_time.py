"""The whole sky at a date: where the sun, the stars and the moon land in the image (checked
against PyEphem's own positions and refraction, an implementation independent of astro/frames
and of our refraction), and what a lunar eclipse does to the moonlight."""

import datetime
import math

import ephem
import numpy as np
import pytest

from skyscatter import api
from skyscatter.astro.moon_phase import MOON_RADIUS_M
from skyscatter.errors import InputError
from skyscatter.render.moon import moon_irradiance
from skyscatter.render.sky_at_time import eclipse_optics, moon_light
from skyscatter.spectrum.colour import spectral_to_xyz
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.spectrum.magnitudes import v_magnitude_of_spectrum
from skyscatter.spectrum.star import SOLAR_RADIUS_M

BERLIN = (52.52, 13.40)
HONOLULU = (21.31, -157.86)


@pytest.fixture(scope="module")
def earth():
    atmosphere = api.load_atmosphere("earth")
    solver = api.load_solver(atmosphere, wavelength_grid(4),
                             options=api.solver_options(atmosphere, orders=2))
    return atmosphere, solver


def _ephem_observer(when: datetime.datetime, latitude: float, longitude: float,
                    pressure_hpa: float = 0.0) -> ephem.Observer:
    observer = ephem.Observer()
    observer.lat, observer.lon = str(latitude), str(longitude)
    observer.elevation = 0.0
    observer.date = ephem.Date(when.astimezone(datetime.UTC).replace(tzinfo=None))
    observer.pressure, observer.temp = pressure_hpa, 10.0
    return observer


def _pixel_of(camera, altitude_deg: float, azimuth_deg: float) -> tuple[float, float]:
    direction = api.sun_direction(90.0 - altitude_deg, azimuth_deg)
    row, column = camera.direction_to_pixel(direction)
    return float(row), float(column)


def _peak_near(image: np.ndarray, row: float, column: float, radius: int = 4):
    """(row, column) of the brightest pixel within `radius` of (row, column)."""
    r0, c0 = int(row), int(column)
    window = image[r0 - radius:r0 + radius + 1, c0 - radius:c0 + radius + 1]
    i, j = np.unravel_index(np.argmax(window), window.shape)
    return r0 - radius + i, c0 - radius + j


def test_bright_stars_land_where_pyephem_puts_them(earth):
    # Berlin, a moonless January night; only stars brighter than V = 1.0. PyEphem (its own
    # precession, nutation and aberration; refraction at 1010 hPa and 10 C like ours) gives
    # each star's apparent alt/az; the star's image peak must be within one pixel of it
    # (0.35 deg at 512 px): catalogue -> precession -> horizon frame -> refraction -> lens.
    atmosphere, solver = earth
    when = datetime.datetime(2024, 1, 10, 22, 0, tzinfo=datetime.UTC)
    camera = api.FisheyeCamera(512)
    observer = api.make_observer(when, *BERLIN)
    image = api.render_at(atmosphere, camera, observer, api.SkyObjects(magnitude_limit=1.0),
                          wavelengths_nm=wavelength_grid(4),
                          options=api.solver_options(atmosphere, orders=2))
    luminance = image.xyz()[..., 1]
    site = _ephem_observer(when, *BERLIN, pressure_hpa=1010.0)
    checked = 0
    for name in ("Capella", "Sirius", "Betelgeuse", "Rigel", "Aldebaran", "Procyon"):
        star = ephem.star(name)
        star.compute(site)
        altitude, azimuth = math.degrees(star.alt), math.degrees(star.az)
        if altitude < 10.0:
            continue
        row, column = _pixel_of(camera, altitude, azimuth)
        peak = _peak_near(luminance, row, column)
        assert abs(peak[0] + 0.5 - row) <= 1.0 and abs(peak[1] + 0.5 - column) <= 1.0, name
        checked += 1
    assert checked >= 4


def test_the_sun_disk_is_at_pyephems_refracted_position(earth):
    # Berlin, a winter noon: the sun (a sub-4-pixel disk deposited in one pixel) is the
    # image's brightest pixel, within one pixel of PyEphem's refracted alt/az.
    atmosphere, _ = earth
    when = datetime.datetime(2024, 12, 21, 11, 0, tzinfo=datetime.UTC)
    camera = api.FisheyeCamera(256)
    image = api.render_at(atmosphere, camera, api.make_observer(when, *BERLIN),
                          api.SkyObjects(stars=False), wavelengths_nm=wavelength_grid(4),
                          options=api.solver_options(atmosphere, orders=2))
    sun = ephem.Sun()
    sun.compute(_ephem_observer(when, *BERLIN, pressure_hpa=1010.0))
    row, column = _pixel_of(camera, math.degrees(sun.alt), math.degrees(sun.az))
    luminance = image.xyz()[..., 1]
    peak = np.unravel_index(np.argmax(luminance), luminance.shape)
    assert abs(peak[0] + 0.5 - row) <= 1.0 and abs(peak[1] + 0.5 - column) <= 1.0


def test_total_lunar_eclipse_dims_and_reddens_the_moon(earth):
    # 2022-11-08, greatest eclipse 10:59 UTC (umbral magnitude 1.359, NASA), seen from
    # Honolulu. The moonlight through our own atmosphere's grazing transmittance and
    # refraction (transport/limb.py) against the same moon unshaded: total eclipses fade the
    # moon by about 10-14 magnitudes and turn it copper-red (Keen 1983, Science 222, 1011;
    # Danjon scale). The bounds are wide because the real fading depends on clouds and
    # volcanic aerosol along the terminator, which our clear atmosphere leaves out.
    atmosphere, solver = earth
    wavelengths = solver.profile.wavelengths_nm
    sky = api.sky_ephemeris(atmosphere, api.make_observer(
        datetime.datetime(2022, 11, 8, 10, 59, tzinfo=datetime.UTC), *HONOLULU))
    sun = atmosphere.planet.star
    optics = eclipse_optics(solver)
    eclipsed = moon_light(sky, sun, wavelengths, optics)
    uneclipsed = moon_irradiance(eclipsed.geometry, wavelengths, eclipsed.solar_irradiance)
    fading = (v_magnitude_of_spectrum(wavelengths, eclipsed.irradiance)
              - v_magnitude_of_spectrum(wavelengths, uneclipsed))
    assert 8.0 < float(fading) < 16.0
    ratio = eclipsed.irradiance / uneclipsed
    assert ratio[-1] > 5.0 * ratio[0]  # red (~770 nm) passes, blue (~420 nm) does not
    # before the umbra arrives (penumbral phase, 08:45 UTC) the moon is only slightly dimmed
    penumbral = api.sky_ephemeris(atmosphere, api.make_observer(
        datetime.datetime(2022, 11, 8, 8, 45, tzinfo=datetime.UTC), *HONOLULU))
    light = moon_light(penumbral, sun, wavelengths, optics)
    plain = moon_irradiance(light.geometry, wavelengths, light.solar_irradiance)
    assert 0.2 < float(np.mean(light.irradiance / plain)) < 1.0


def test_the_lit_side_of_a_waxing_moon_faces_the_sun(earth):
    # First quarter, 2024-01-18 around 17:00 UTC in Berlin: in a narrow view centred on the
    # moon the brightness centroid lies off the disk centre towards the projected sun.
    atmosphere, _ = earth
    when = datetime.datetime(2024, 1, 18, 17, 0, tzinfo=datetime.UTC)
    sky = api.sky_ephemeris(atmosphere, api.make_observer(when, *BERLIN))
    moon, sun = sky.moon.direction(), sky.sun.direction()
    camera = api.PerspectiveCamera.from_forward_up(64, 64, 1.0, moon, (0.0, 0.0, 1.0))
    image = api.render_at(atmosphere, camera, api.make_observer(when, *BERLIN),
                          api.SkyObjects(stars=False), wavelengths_nm=wavelength_grid(4),
                          options=api.solver_options(atmosphere, orders=2))
    luminance = image.xyz()[..., 1]
    moon_pixels = luminance > 50.0 * np.median(luminance)
    rows, columns = np.nonzero(moon_pixels)
    weights = luminance[moon_pixels]
    centroid = np.array([rows @ weights, columns @ weights]) / weights.sum()
    centre = np.array(camera.direction_to_pixel(moon)) - 0.5
    towards_sun = np.array(camera.direction_to_pixel(moon + 0.01 * (sun - moon))) - 0.5
    offset, expected = centroid - centre, towards_sun - centre
    assert offset @ expected / (np.linalg.norm(offset) * np.linalg.norm(expected)) > 0.9


def test_moonlit_sky_agrees_with_krisciunas_and_schaefer(earth):
    # Krisciunas & Schaefer (1991), PASP 103, 1033, eqs. 15-21: the V-band brightness of the
    # moonlit sky, B = f(rho) I* 10^(-0.4 k X(Z_moon)) (1 - 10^(-0.4 k X(Z))) [nL], with
    # f(rho) = 10^5.36 (1.06 + cos^2 rho) + 10^(6.15 - rho/40), I* = 10^(-0.4 (3.84 + 0.026
    # |alpha| + 4e-9 alpha^4)), X(Z) = (1 - 0.96 sin^2 Z)^-1/2, 1 nL = 3.183e-6 cd m^-2; k from
    # our own zenith transmittance at 550 nm. Full moon over Berlin, 55 deg high. Their model
    # fits measurements to 8-23 % rms; we allow 25 % away from the moon, and 60 % 10 deg from
    # it, where the aerosol's forward peak (theirs: Mauna Kea's, ours: a continental haze)
    # decides the aureole.
    atmosphere, solver = earth
    profile = solver.profile
    wavelengths = profile.wavelengths_nm
    sky = api.sky_ephemeris(atmosphere, api.make_observer("2024-01-25T23:00+01:00", *BERLIN))
    moon = moon_light(sky, atmosphere.planet.star, wavelengths, None)
    position = np.array([0.0, 0.0, profile.bottom_radius_m + 1.0])
    zenith_transmittance = solver.transmittance(position, np.array([[0.0, 0.0, 1.0]]))[0]
    k = -2.5 * math.log10(np.interp(550.0, wavelengths, zenith_transmittance))
    alpha = math.degrees(math.acos(np.clip(
        -moon.geometry.moon_direction @ moon.geometry.sun_from_moon, -1.0, 1.0)))

    def airmass(zenith_deg):
        return (1.0 - 0.96 * math.sin(math.radians(zenith_deg)) ** 2) ** -0.5

    brightness = 10.0 ** (-0.4 * (3.84 + 0.026 * alpha + 4e-9 * alpha**4))
    moon_zenith = 90.0 - sky.moon.altitude_deg
    for view_zenith, azimuth_offset, tolerance in ((0.0, 0.0, 0.25), (60.0, 90.0, 0.25),
                                                   (75.0, 180.0, 0.25), (45.0, 0.0, 0.6)):
        view = api.sun_direction(view_zenith, sky.moon.azimuth_deg + azimuth_offset)
        rho = math.degrees(math.acos(view @ sky.moon.direction()))
        f = 10**5.36 * (1.06 + math.cos(math.radians(rho)) ** 2) + 10 ** (6.15 - rho / 40.0)
        expected = (f * brightness * 10 ** (-0.4 * k * airmass(moon_zenith))
                    * (1.0 - 10 ** (-0.4 * k * airmass(view_zenith))) * 3.183e-6)
        radiance = solver.sky_radiance(position, view[None], sky.moon.direction())[0]
        luminance = spectral_to_xyz(radiance * moon.irradiance / profile.toa_irradiance,
                                    wavelengths)[1]
        assert luminance == pytest.approx(expected, rel=tolerance), (view_zenith, rho)


def test_a_mars_sol_date_places_the_sun_as_the_same_utc():
    # Mars24's worked example A: 2000-01-06 00:00:00 UTC is MSD 44795.9998 (Allison & McEwen
    # 2000; printed to 1e-4 sol = 8.9 s, in which the sun moves 0.04 deg at most). Viking
    # Lander 1's site, 22.697 N, 48.222 W.
    mars = api.load_atmosphere("mars-costa")
    by_msd = api.sky_ephemeris(mars, api.make_observer("MSD 44795.9998", 22.697, -48.222))
    by_utc = api.sky_ephemeris(mars, api.make_observer("2000-01-06T00:00Z", 22.697, -48.222))
    assert abs((by_msd.observer.time_utc - by_utc.observer.time_utc).total_seconds()) < 9.0
    assert by_msd.sun.altitude_deg == pytest.approx(by_utc.sun.altitude_deg, abs=0.04)
    with pytest.raises(InputError, match="MSD 44795.9998"):
        api.make_observer("MSD soon", 0.0, 0.0)


def test_the_moon_hides_the_sun_in_the_2024_solar_eclipse():
    # 2024-04-08. Dallas (32.78 N, 96.80 W): totality 18:40:43-18:44:35 UTC (NASA, Espenak's
    # eclipse pages); New York City: greatest obscuration 89.6 % near 19:25 UTC (NASA /
    # timeanddate.com). Our sun and moon disks (ephemeris, true angular sizes) overlap as a
    # uniform disk: 1 % allows for the limb darkening left out and the 1-minute sampling.
    from skyscatter.render.scene import disk_visible_fraction

    earth = api.load_atmosphere("earth")

    def visible(time: str, latitude: float, longitude: float) -> float:
        sky = api.sky_ephemeris(earth, api.make_observer(time, latitude, longitude))
        sun = math.asin(SOLAR_RADIUS_M / sky.sun.distance_m)
        moon = math.asin(MOON_RADIUS_M / sky.moon.distance_m)
        return disk_visible_fraction(sky.sun.direction(), sun, sky.moon.direction(), moon)

    assert visible("2024-04-08T18:42:40Z", 32.7767, -96.7970) == 0.0
    assert 0.0 < visible("2024-04-08T18:39:30Z", 32.7767, -96.7970) < 0.02
    assert 0.0 < visible("2024-04-08T18:46:00Z", 32.7767, -96.7970) < 0.05
    deepest = min(visible(f"2024-04-08T19:{minute:02d}:00Z", 40.7128, -74.0060)
                  for minute in range(15, 36))
    assert 1.0 - deepest == pytest.approx(0.896, abs=0.01)
