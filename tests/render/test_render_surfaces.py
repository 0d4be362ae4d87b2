"""Surfaces seen through the atmosphere (albedo maps, terrain, views from space) against the
table solver's own built-in ground, closed forms and an independent colour library."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "transport"))
from transport_cases import EARTH_RADIUS_M, SMALL, exponential_earth  # noqa: E402

from skyscatter.api import look_at_direction, viewpoint_at  # noqa: E402
from skyscatter.errors import InputError  # noqa: E402
from skyscatter.render.albedo_map import AlbedoMap  # noqa: E402
from skyscatter.render.camera import PerspectiveCamera  # noqa: E402
from skyscatter.render.scene import orbit_viewpoint, render_sky, sun_direction  # noqa: E402
from skyscatter.render.surfaces import Ground, surface_radiance  # noqa: E402
from skyscatter.render.terrain import Heightfield  # noqa: E402
from skyscatter.render.tonemap import incident_ev100  # noqa: E402
from skyscatter.spectrum.reflectance import reflectance_from_rgb  # noqa: E402
from skyscatter.spectrum.star import Star  # noqa: E402
from skyscatter.transport.lut_solver import LutSolver  # noqa: E402
from skyscatter.transport.single_scattering import SingleScatteringSolver  # noqa: E402

PERCENT = 0.01


@pytest.fixture(scope="module")
def solver():
    return LutSolver(exponential_earth(), resolution=SMALL, orders=2)


def _grey_map(value: float) -> AlbedoMap:
    return AlbedoMap(np.full((8, 16, 3), value))


def _downward_rays(n: int = 40) -> np.ndarray:
    zenith = np.radians(np.linspace(91.0, 180.0, n))
    azimuth = np.radians(np.linspace(0.0, 330.0, n))
    return np.stack([np.sin(zenith) * np.sin(azimuth), np.sin(zenith) * np.cos(azimuth),
                     np.cos(zenith)], axis=-1)


@pytest.mark.parametrize("altitude_m", [5_000.0, 1_000_000.0])
def test_a_uniform_map_reproduces_the_tables_own_ground(solver, altitude_m):
    # The table kernel shades the ground with the profile's albedo inside `sky_radiance`; the
    # surface path uses aerial perspective + surface irradiance instead. A grey map of the same
    # albedo (0.1; the RGB-to-spectrum step is flat to 0.03 %) must give the same radiance.
    position = np.array([0.0, 0.0, EARTH_RADIUS_M + altitude_m])
    directions = _downward_rays()
    sun = sun_direction(50.0, 30.0)
    radiance, hit = surface_radiance(solver, position, directions, sun,
                                     Ground(albedo_map=_grey_map(0.1)))
    assert hit.sum() >= 25  # from 1000 km the horizon is 31 deg below the horizontal
    reference = solver.sky_radiance(position, directions[hit], sun)
    np.testing.assert_allclose(radiance, reference, rtol=0.1 * PERCENT)


def test_flat_terrain_renders_like_the_bare_planet(solver):
    # A heightfield of zeros is the sphere itself: the terrain path (ray marcher, surface
    # normals, terrain shadows) must give the image of the bare planet (0.2 %: the bisection
    # of the hit distance and the albedo's RGB round trip).
    camera = PerspectiveCamera(24, 16, 60.0, heading_deg=150.0, pitch_deg=-10.0)
    viewpoint = viewpoint_at(300.0, EARTH_RADIUS_M)
    sun = sun_direction(60.0, 200.0)
    star = Star.sun()
    flat = Heightfield(np.zeros((64, 64)), 500.0, EARTH_RADIUS_M)
    bare = render_sky(solver, camera, viewpoint, sun, star)
    with_terrain = render_sky(solver, camera, viewpoint, sun, star,
                              ground=Ground(terrain=flat))
    np.testing.assert_allclose(with_terrain.spectral, bare.spectral, rtol=0.2 * PERCENT,
                               atol=1e-9)


def test_a_black_wall_fades_into_the_sky_with_distance(solver):
    # Aerial perspective: a black surface shows only the air in front of it, which tends to the
    # sky behind it as the surface moves away (transmittance -> 0 along the horizontal).
    position = np.array([0.0, 0.0, EARTH_RADIUS_M + 10.0])
    sun = sun_direction(60.0, 90.0)
    horizontal = np.array([0.0, 1.0, 0.0])
    sky = solver.sky_radiance(position, horizontal, sun)
    distances = np.array([1e3, 1e4, 5e4, 2e5])
    inscattered, transmittance = solver.aerial_perspective(
        position, position + distances[:, None] * horizontal, sun)
    assert np.all(np.diff(transmittance, axis=0) < 0.0)
    assert np.all(np.diff(inscattered, axis=0) > 0.0)
    assert np.all(inscattered < 1.01 * sky)  # sky = inscattered + T x (light from behind)
    assert np.all(inscattered[-1] > 0.8 * sky)  # at 200 km: 85-100 % of the sky


def test_surfaces_need_the_table_solver():
    single = SingleScatteringSolver(exponential_earth(), n_samples=8)
    with pytest.raises(InputError, match="--solver lut"):
        surface_radiance(single, np.array([0.0, 0.0, EARTH_RADIUS_M + 10.0]),
                         _downward_rays(4), sun_direction(40.0, 0.0),
                         Ground(albedo_map=_grey_map(0.2)))


# --- views from space ------------------------------------------------------------------------

def test_day_twilight_and_night_across_the_terminator(solver):
    # Camera 20,000 km above (0, 0), sun on its local horizon in the east: the terminator runs
    # through the image centre. Beyond it the ground is in the planet's shadow; the air above
    # it still catches sunlight for a while (twilight), then nothing does.
    altitude = 20_000e3
    viewpoint = orbit_viewpoint(altitude, 0.0, 0.0, EARTH_RADIUS_M)
    camera = PerspectiveCamera(81, 81, 40.0, heading_deg=0.0, pitch_deg=-90.0)
    sun = sun_direction(90.0, 90.0)
    image = render_sky(solver, camera, viewpoint, sun, Star.sun())
    row = image.spectral[40, :, 1] / image.spectral[40, 60, 1]  # green, west to east
    # the planet spans columns 13-67; the terminator is at column 40
    day, twilight, night = row[41:67], row[35:40], row[14:34]
    assert np.all(np.diff(day) > 0.0)  # brighter towards the sun
    # the faintest twilight column: 8.3e-5 of the day with single scattering ray marched through
    # the lit part of each ray (issue 6; 1.3e-4 when the tables interpolated it across the
    # terminator); well above the night's 1e-5
    assert np.all(np.diff(twilight) > 0.0) and twilight[0] > 4e-5 and twilight[-1] < 0.1
    assert np.all(night < 1e-5)  # the planet's shadow (measured: 1e-6, the tables' floor)
    assert image.from_space


def test_look_at_the_point_below_is_straight_down():
    viewpoint = viewpoint_at(1e6, EARTH_RADIUS_M, 35.0, -20.0)
    down = look_at_direction(viewpoint, 35.0, -20.0, 0.0, EARTH_RADIUS_M)
    np.testing.assert_allclose(down, [0.0, 0.0, -1.0], atol=1e-12)
    northwards = look_at_direction(viewpoint, 45.0, -20.0, 0.0, EARTH_RADIUS_M)
    assert northwards[1] > 0.3 and abs(northwards[0]) < 1e-9 and northwards[2] < 0.0
    with pytest.raises(InputError, match="look-at point is where the camera is"):
        look_at_direction(viewpoint, 35.0, -20.0, 1e6, EARTH_RADIUS_M)


def test_incident_metering_is_iso_2720():
    # EV100 = log2(E S / C), C = 250 lx s (ISO 2720 flat receptor), S = 100: 133.1 klx (the
    # sun at the top of Earth's atmosphere) -> 15.70 EV.
    assert incident_ev100(133_100.0) == pytest.approx(math.log2(133_100.0 * 100 / 250), 1e-12)
    assert incident_ev100(133_100.0) == pytest.approx(15.70, abs=0.01)
    with pytest.raises(InputError, match="not positive"):
        incident_ev100(0.0)


# --- albedo maps -------------------------------------------------------------------------------

def test_albedo_map_orientation_north_up_longitude_from_minus_180():
    rgb = np.zeros((18, 36, 3))
    rgb[:2, :, 0] = 1.0        # north polar cap: red
    rgb[8:10, 18:20, 1] = 1.0  # at (0 N, 5 E): green (columns 18-19 = 0..10 deg east)
    albedo = AlbedoMap(rgb)
    r = EARTH_RADIUS_M
    north_pole = np.array([0.0, 0.0, r])
    lon5 = np.array([r * math.cos(math.radians(5.0)), r * math.sin(math.radians(5.0)), 0.0])
    lon_west = np.array([r * math.cos(math.radians(-5.0)), r * math.sin(math.radians(-5.0)),
                         0.0])
    np.testing.assert_allclose(albedo.rgb_at(north_pole), [1.0, 0.0, 0.0])
    np.testing.assert_allclose(albedo.rgb_at(lon5), [0.0, 1.0, 0.0])
    np.testing.assert_allclose(albedo.rgb_at(lon_west), [0.0, 0.0, 0.0])


@pytest.mark.filterwarnings("ignore:Aligning")  # colour-science resamples to its CMF range
def test_reflectance_from_rgb_has_the_pixel_colour_under_d65():
    # Independent check with colour-science's own spectral integration (sd_to_XYZ, D65,
    # CIE 1931) and sRGB conversion: the colour is reproduced within 0.01 for in-gamut
    # earth tones; greys are flat.
    import colour

    wavelengths = np.arange(360.0, 831.0, 1.0)
    np.testing.assert_allclose(reflectance_from_rgb([0.3, 0.3, 0.3], wavelengths), 0.3,
                               rtol=0.05 * PERCENT)
    for rgb in ([0.40, 0.30, 0.20], [0.05, 0.10, 0.25], [0.2, 0.35, 0.1]):
        spectrum = reflectance_from_rgb(rgb, wavelengths)
        sd = colour.SpectralDistribution(dict(zip(wavelengths, spectrum, strict=True)))
        xyz = colour.sd_to_XYZ(sd, illuminant=colour.SDS_ILLUMINANTS["D65"]) / 100.0
        back = colour.XYZ_to_RGB(xyz, "sRGB", apply_cctf_encoding=False)
        np.testing.assert_allclose(back, rgb, atol=0.01)


def test_albedo_map_files_png_round_trip_and_bad_files(tmp_path):
    from PIL import Image

    pixels = np.zeros((4, 8, 3), dtype=np.uint8)
    pixels[..., 1] = 188  # sRGB-encoded 188 -> linear 0.5029
    Image.fromarray(pixels).save(tmp_path / "map.png")
    albedo = AlbedoMap.from_image(tmp_path / "map.png")
    np.testing.assert_allclose(albedo.rgb[..., 1], 0.5029, atol=1e-3)
    assert np.all(albedo.rgb[..., 0] == 0.0)
    with pytest.raises(InputError, match="no such file"):
        AlbedoMap.from_image(tmp_path / "missing.png")
    (tmp_path / "junk.png").write_bytes(b"not an image")
    with pytest.raises(InputError, match="cannot read it"):
        AlbedoMap.from_image(tmp_path / "junk.png")
    np.save(tmp_path / "bright.npy", np.full((4, 8, 3), 1.5))
    with pytest.raises(InputError, match=r"bright.npy.*\[0, 1\]"):
        AlbedoMap.from_image(tmp_path / "bright.npy")
