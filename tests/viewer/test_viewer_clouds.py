"""Clouds in the viewer (issue 19, section 4): the cloud message and its route, and the page's
screenshots in headless Chromium (SwiftShader WebGL2) against the CPU renderer's PNGs of the
same views with the same clouds (`render_sky` with `cloud_field`), from the same tables."""

from __future__ import annotations

import json
import urllib.error
import urllib.request

import numpy as np
import pytest
from PIL import Image

from skyscatter import api
from skyscatter.atmosphere.cloud_config import CLOUD_PRESETS_DIR
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.errors import InputError
from skyscatter.render.scene import render_sky, sun_direction
from skyscatter.render.sky_at_time import render_sky_at
from skyscatter.spectrum.colour import cmf_weights
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.clouds import kernel_arrays
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.viewer import codegen
from skyscatter.viewer.gpu_clouds import decode_clouds, encode_clouds, gpu_clouds

from .test_viewer_browser import NIGHT, camera_of, open_view, psnr_db

# The views: cumulus at noon, looking towards the sun's side, and stratocumulus with a low
# afternoon sun; both from the ground at 45 deg N with the clouds' time 600 s (the wind has
# moved them). The CPU renderer is the reference: its cloud field is made for the same
# observer frame (`viewpoint.to_world`) and time, on the preview tables' wavelengths.
CLOUD_VIEWS = {
    "cumulus": dict(clouds="cumulus", projection="perspective", sun_zenith=35, sun_azimuth=160,
                    heading=150, pitch=12, fov=75, altitude_m=2, lat=45, lon=0, cloud_time=600),
    "stratocumulus": dict(clouds="stratocumulus", projection="perspective", sun_zenith=60,
                          sun_azimuth=220, heading=200, pitch=20, fov=75, altitude_m=2, lat=45,
                          lon=0, cloud_time=600),
}
SIZE = (320, 240)
# PSNR limit of the cloud views [dB]: the clear sky's (issue 7). The page marches the same
# field with the same steps and the same per-ray jitter, but in float32 against float64 (a
# sample that lands just inside a cloud's edge in one and outside in the other starts another
# sequence of segments: single pixels differ by up to 111 of 255 at edges), from a float16
# noise tile filtered in hardware, with the optics in three XYZ channels against the
# renderer's 8 wavelengths (gpu_clouds); the clouds' shadows in the air are taken from table
# differences instead of the CPU's density integral, and from a float16 shadow map placed over
# a 17 x 17 grid of the rays instead of all of them (clouds.glsl air_shadow_loss); the
# adaptive refinement's choices between interpolating and marching follow from these small
# differences. Measured 42.7 dB (cumulus) and 38.2 dB (stratocumulus) at 320 x 240
# (docs/viewer.md, Clouds), 24.4 and 21.9 dB without the shadows in the air (each pixel
# marched); the clear page's image is at 13.9 and 14.0 dB.
MIN_CLOUD_PSNR_DB = 35.0
# ... and of a starry night under cumulus: the stars dominate its differences, so the limit
# sits between the 41.2 dB measured and the 35.5 dB of stars drawn through the clouds
MIN_NIGHT_CLOUD_PSNR_DB = 38.0


def cpu_cloud_png(server, view: dict, path, width: int, height: int) -> tuple[np.ndarray, float]:
    """The CPU renderer's PNG of `view` with its clouds (metered automatically) and its EV100."""
    service = server.service
    atmosphere, profile, tables = service.spectral_tables(
        service.parse({"atmosphere": "earth", "quality": "preview"}))
    solver = LutSolver(profile, tables=tables)
    viewpoint = api.viewpoint_at(view["altitude_m"], profile.bottom_radius_m, view["lat"],
                                 view["lon"])
    field = cloud_field(api.load_clouds(view["clouds"]), profile.bottom_radius_m,
                        profile.wavelengths_nm, to_world=viewpoint.to_world,
                        time_s=view["cloud_time"])
    image = render_sky(solver, camera_of(view, width, height), viewpoint,
                       sun_direction(view["sun_zenith"], view["sun_azimuth"]),
                       atmosphere.planet.star, clouds=field)
    ev100 = api.save_image(image, path)
    return np.asarray(Image.open(path).convert("RGB")), ev100


@pytest.mark.parametrize("name", list(CLOUD_VIEWS))
def test_cloud_screenshot_matches_cpu_renderer(name, page, viewer_url, tmp_path):
    # Both refine adaptively over the pixels (transport.adaptive_pixels and its twin,
    # cloud_level.frag; here from a lattice of every 2nd pixel): 42.7 and 38.2 dB (43.5 and
    # 39.3 dB with the clouds lit by Bohren's slab; 43.0 and 38.0 dB with the ground lit
    # through the clouds' direct beam only, where both marching every pixel gave 43.6 and
    # 38.1 dB).
    view = CLOUD_VIEWS[name]
    width, height = SIZE
    cpu, ev100 = cpu_cloud_png(viewer_url, view, tmp_path / f"{name}.png", width, height)
    gpu = open_view(page, viewer_url, view, width=width, height=height, ev100=f"{ev100:.6f}",
                    compensation=1)
    assert gpu.shape == cpu.shape
    psnr = psnr_db(gpu, cpu)
    assert psnr >= MIN_CLOUD_PSNR_DB, f"{psnr:.1f} dB"
    clear = open_view(page, viewer_url, dict(view, clouds="none"), width=width, height=height,
                      ev100=f"{ev100:.6f}", compensation=1)
    assert psnr_db(clear, cpu) < psnr_db(gpu, cpu) - 5.0  # the clouds are what matches
    assert not page.errors


def test_clouds_hide_the_stars_as_on_the_cpu(page, viewer_url, tmp_path):
    """A moonless night under cumulus (the stars brighter than V 6.5, as the clear night of
    test_viewer_browser): each star dimmed by the clouds' transmittance along its line of sight
    (stars.vert with CLOUDS), as `render_sky_at` with the same clouds at the same date; under an
    overcast stratus no star is left."""
    time, lat, lon, size, ev100 = NIGHT
    service = viewer_url.service
    atmosphere, profile, tables = service.spectral_tables(
        service.parse({"atmosphere": "earth", "quality": "preview"}))
    observer = api.make_observer(time, lat, lon)
    viewpoint = api.viewpoint_at(0.0, profile.bottom_radius_m, lat, lon)  # the page's camera
    view = {"projection": "fisheye", "altitude_m": 0, "lat": lat, "lon": lon, "time": time}
    shots = {}
    for name in ("cumulus", "stratus"):
        # with a date, the clouds' time is the seconds since J2000 (viewer.js cloudTime)
        field = cloud_field(api.load_clouds(name), profile.bottom_radius_m,
                            profile.wavelengths_nm, to_world=viewpoint.to_world,
                            time_s=(observer.time_utc - api.J2000_UTC).total_seconds())
        image = render_sky_at(LutSolver(profile, tables=tables), api.FisheyeCamera(size),
                              viewpoint, atmosphere.planet.star,
                              api.sky_ephemeris(atmosphere, observer),
                              objects=api.SkyObjects(moon=False, airglow=False,
                                                     magnitude_limit=6.5), clouds=field)
        api.save_image(image, tmp_path / f"{name}.png", ev100=ev100)
        cpu = np.asarray(Image.open(tmp_path / f"{name}.png").convert("RGB"))
        shots[name] = cpu, open_view(page, viewer_url, dict(view, clouds=name), width=size,
                                     height=size, ev100=ev100, compensation=1)
    clear = open_view(page, viewer_url, view, width=size, height=size, ev100=ev100,
                      compensation=1)

    def star_pixels(image: np.ndarray) -> int:
        return int(np.count_nonzero(image.max(axis=-1) > 40))  # the night sky itself is darker

    cpu, gpu = shots["cumulus"]
    # measured: 285 star pixels clear, 94 under the cumulus (the CPU 103: stars on cloud edges,
    # where float32 and float64 marches part), 0 under the stratus; 41.2 dB, and 35.5 dB when
    # the page drew every star through the clouds
    assert 0 < star_pixels(gpu) < star_pixels(clear)
    assert star_pixels(gpu) == pytest.approx(star_pixels(cpu), rel=0.2)
    assert psnr_db(gpu, cpu) >= MIN_NIGHT_CLOUD_PSNR_DB
    assert star_pixels(shots["stratus"][1]) == 0
    assert not page.errors


@pytest.mark.parametrize("projection", ["perspective", "fisheye"])
def test_page_places_the_shadow_map_as_the_renderer(projection, page, viewer_url):
    """geometry.js mapFrame over the page's 17 x 17 grid of rays against
    transport.air_shadows.map_frame over every ray of the CPU camera: the same axes and levels,
    the extent from the grid (and a fisheye's rim) close to the one from every pixel."""
    from skyscatter.transport.air_shadows import SHADOW_MAX_M, map_frame, shaded_stretch

    view = dict(CLOUD_VIEWS["cumulus"], projection=projection)
    width, height = 320, 180
    open_view(page, viewer_url, view, width=width, height=height)
    place = page.evaluate(f"""() => {{
        const v = window.skyscatter.viewer;
        return v.cloudMapFrame(v.viewUniforms({width}, {height}), {width}, {height}); }}""")
    service = viewer_url.service
    _, profile, _ = service.spectral_tables(service.parse({"atmosphere": "earth",
                                                           "quality": "preview"}))
    bottom = profile.bottom_radius_m
    viewpoint = api.viewpoint_at(view["altitude_m"], bottom, view["lat"], view["lon"])
    local, valid = camera_of(view, width, height).directions()
    rays = viewpoint.direction_to_world(local[valid])
    field = cloud_field(api.load_clouds("cumulus"), bottom, np.array([550.0]))
    sun = viewpoint.direction_to_world(sun_direction(view["sun_zenith"], view["sun_azimuth"]))
    origin = viewpoint.position_m
    stretch = shaded_stretch(origin, rays, np.full(len(rays), np.inf), bottom,
                             field.highest_radius_m)
    assert stretch[:, 1].max() <= SHADOW_MAX_M + 1.0
    frame = map_frame(field.lowest_radius_m, field.highest_radius_m, rays, stretch, sun)
    np.testing.assert_allclose(place["e1"], frame.e1, atol=1e-6)  # float32 sun direction
    np.testing.assert_allclose(place["e2"], frame.e2, atol=1e-6)
    np.testing.assert_allclose(place["levels"], [frame.levels[0],
                                                 frame.levels[1] - frame.levels[0]], rtol=1e-6)
    # the extent: within 2 % at each end (a fisheye's farthest rays lie between its samples)
    assert place["texel"] == pytest.approx(frame.texel, rel=0.02)
    np.testing.assert_allclose(place["shape"], frame.shape, rtol=0.02, atol=2)
    np.testing.assert_allclose(place["corner"], frame.corner, atol=0.02 * 512 * frame.texel)


def test_cloud_optics_are_the_spectral_ones_weighted_by_the_sun():
    """gpu_clouds' XYZ optics against the spectral optics the CPU's kernels take (`kernel_arrays`)
    for the same field: each channel a
    mean of the spectral values with the weights CIE x, y, z times the sun (module docstring),
    so it lies between their extremes; the round trip of the message keeps every array."""
    clouds = api.load_clouds("cumulus")
    grid = wavelength_grid(16)
    star = api.load_atmosphere("earth").planet.star
    sun = star.irradiance_toa(grid)
    gpu = gpu_clouds(clouds, 6_371_000.0, grid, sun)
    field = cloud_field(clouds, 6_371_000.0, grid)
    weights = cmf_weights(grid) * sun[:, None]
    spectral = kernel_arrays(field)[3]  # as the CPU's kernels take it
    expected = spectral @ weights / weights.sum(axis=0)
    np.testing.assert_allclose(gpu.header["mass_extinction_xyz_m2_g"], expected, rtol=1e-12)
    k = spectral[0]
    assert np.all((expected >= k.min()) & (expected <= k.max()))
    back = decode_clouds(encode_clouds(gpu))
    assert back.header["n_layers"] == 1
    n = field.textures.shape[1]
    noise = back.arrays["noise"].reshape(1, n + 1, n, n, 2)
    # float16: 11 significant bits, values in [0, 1]: within 2^-12
    np.testing.assert_allclose(noise[0, :n], field.textures[0], atol=2.0**-12)
    np.testing.assert_array_equal(noise[0, n], noise[0, 0])  # the wrap slice
    np.testing.assert_array_equal(back.arrays["params"], field.params.astype(np.float32))


def test_cloud_columns_are_generated_from_the_sampling_module():
    """The shader and the page read the parameter table's columns by name (codegen)."""
    from skyscatter.atmosphere import _cloud_sampling
    layout = json.loads(codegen.layout_json())["clouds"]
    assert layout["n_params"] == _cloud_sampling.N_PARAMS
    for name in ("BASE_R", "TOP_R", "COVERAGE", "OFFSET_X", "ALONG_X", "STRETCH_MINUS_ONE"):
        assert layout["columns"][name] == getattr(_cloud_sampling, name)
        assert f"#define CLOUD_{name} {getattr(_cloud_sampling, name)}\n" in \
            codegen.constants_glsl()


def _get(server, path: str) -> tuple[int, bytes]:
    host, port = server.server_address[:2]
    request = urllib.request.Request(f"http://{host}:{port}{path}",
                                     headers={"X-Skyscatter-Token": server.token})
    try:
        with urllib.request.urlopen(request, timeout=120) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


@pytest.mark.parametrize("query, words", [
    ("clouds=cumulonimbus", ["unknown clouds", "cumulus"]),
    ("clouds=../../etc/passwd", ["unknown clouds"]),
    ("clouds=cumulus&atmosphere=venus-ish", ["unknown atmosphere"]),
    ("clouds=cumulus&seed=3", ["unknown parameter", "seed"]),
    ("atmosphere=earth", ["missing parameter", "clouds"]),
])
def test_cloud_route_refuses_bad_parameters(viewer_url, query, words):
    status, body = _get(viewer_url, f"/api/clouds?{query}")
    assert status == 400
    message = json.loads(body)["error"]
    assert all(word in message for word in words), message


def test_cloud_route_needs_the_token_and_sends_the_message(viewer_url):
    host, port = viewer_url.server_address[:2]
    with pytest.raises(urllib.error.HTTPError) as refused:
        urllib.request.urlopen(f"http://{host}:{port}/api/clouds?clouds=cirrus", timeout=30)
    assert refused.value.code == 403
    status, body = _get(viewer_url, "/api/clouds?clouds=cirrus&atmosphere=earth")
    assert status == 200
    gpu = decode_clouds(body)
    assert gpu.header["label"] == "cirrus" and gpu.header["n_layers"] == 1
    status, body = _get(viewer_url, "/api/atmospheres")
    offered = {entry["name"] for entry in json.loads(body)["clouds"]["clouds"]}
    assert {"cumulus", "stratocumulus", "altocumulus", "cirrus", "stratus"} <= offered


def test_view_with_a_bad_clouds_file_names_it_before_serving(tmp_path, capsys):
    """`skyscatter view --clouds FILE` reads the file first: a bad value is one line naming the
    file, the key and the value, exit code 2, and no server is started."""
    from skyscatter import cli
    bad = tmp_path / "sky.toml"
    bad.write_text('[[layer]]\nbase_altitude_m = 1000.0\ntop_altitude_m = 2000.0\n'
                   'coverage = 1.7\nwater_content_g_m3 = 0.3\n')
    assert cli.main(["view", "--no-browser", "--clouds", str(bad)]) == 2
    error = capsys.readouterr().err
    assert "sky.toml" in error and "coverage" in error and "1.7" in error
    assert "Traceback" not in error
    assert cli.main(["view", "--no-browser", "--clouds", "cumulonimbus"]) == 2
    assert "cumulonimbus" in capsys.readouterr().err


def test_offered_clouds_file_is_the_pages_first_choice(tmp_path):
    """A clouds file given to the viewer is offered under its own name and chosen first; the
    page still offers the presets, and a request never names a path."""
    from skyscatter.viewer.cloud_service import CloudService
    from skyscatter.viewer.table_service import TableService
    sky = tmp_path / "my-sky.toml"
    sky.write_text((CLOUD_PRESETS_DIR / "altocumulus.toml").read_text())
    service = CloudService(TableService())
    assert service.offer(sky) == "my-sky"
    described = service.describe()
    assert described["default"] == "my-sky"
    assert {"my-sky", "cumulus"} <= {entry["name"] for entry in described["clouds"]}
    assert service.parse({"clouds": "my-sky"}) == ("my-sky", "earth")
    with pytest.raises(InputError, match="unknown clouds"):
        service.parse({"clouds": str(sky)})
