"""docs/engine_demo, the plain WebGL2 page of docs/engines.md, in headless Chromium: a cube map
written by skyscatter as its background and a diffuse sphere lit by the light file, against
the map itself read back with OpenEXR and integrated here in numpy."""

from __future__ import annotations

import functools
import http.server
import json
import shutil
import threading
from pathlib import Path

import numpy as np
import OpenEXR
import pytest

from skyscatter import api

DEMO = Path(__file__).resolve().parents[2] / "docs" / "engine_demo"
FACE = 32
WIDTH, HEIGHT = 480, 320  # the canvas of index.html
EYE, ORIGIN, FOV_DEG, ALBEDO = np.array([0.0, 1.5, 4.0]), np.zeros(3), 50.0, 0.8
# views far from the sphere along each of the map's axes (tilted off the page's y up)
AXES = {"+X": (1.0, 0.1, 0.2), "-X": (-1.0, 0.1, 0.2), "+Y": (0.1, 1.0, 0.2),
        "-Y": (0.1, -1.0, 0.2), "+Z": (0.2, 0.1, 1.0), "-Z": (0.2, 0.1, -1.0)}


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """A served copy of the page with sky.hdr, sky.exr (the same map) and light.json."""
    root = tmp_path_factory.mktemp("engine-demo")
    for name in ("index.html", "engine_demo.js"):
        shutil.copy(DEMO / name, root / name)
    camera = api.CubeMapCamera(FACE)
    image = api.render(api.load_atmosphere("earth"), camera, 60.0, 135.0,
                       wavelengths_nm=(450.0, 550.0, 650.0), solver="single", sun_disk=False)
    api.save_image(image, exr_path=root / "sky.hdr")
    api.save_image(image, exr_path=root / "sky.exr")
    (root / "light.json").write_text(json.dumps(api.environment_light(image, camera)))
    handler = functools.partial(_QuietHandler, directory=str(root))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}/", root
    server.shutdown()
    server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:
        pass


def _open(page, url: str, eye: np.ndarray = EYE, target: np.ndarray = ORIGIN) -> None:
    page.goto(f"{url}index.html?eye={_triple(eye)}&target={_triple(target)}&fov={FOV_DEG:g}"
              f"&albedo={ALBEDO:g}")
    page.wait_for_function("document.body.dataset.ready")
    assert page.evaluate("document.body.dataset.ready") == "1", \
        page.evaluate("document.getElementById('error').textContent")
    assert page.errors == []


def _triple(v: np.ndarray) -> str:
    return ",".join(f"{x:g}" for x in v)


def _basis(eye: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """forward, right, up of the camera at `eye` looking at `target`, y up (the page's)."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    return forward, right, np.cross(right, forward)


def _ray(column: int, row: int, eye: np.ndarray = EYE,
         target: np.ndarray = ORIGIN) -> np.ndarray:
    """The direction through the centre of pixel (column, row from the top) of a pinhole at
    `eye` looking at `target` with a vertical field of view FOV_DEG."""
    forward, right, up = _basis(eye, target)
    tan_half = np.tan(np.radians(FOV_DEG) / 2.0)
    x = (2.0 * (column + 0.5) / WIDTH - 1.0) * tan_half * WIDTH / HEIGHT
    y = (1.0 - 2.0 * (row + 0.5) / HEIGHT) * tan_half
    d = forward + x * right + y * up
    return d / np.linalg.norm(d)


def _sphere_hit(d: np.ndarray, eye: np.ndarray) -> np.ndarray | None:
    """The unit sphere's normal where the ray eye + t d first meets it, or None."""
    b = eye @ d
    disc = b * b - eye @ eye + 1.0
    return None if disc < 0.0 else eye + (-b - np.sqrt(disc)) * d


def _pixel_of(point: np.ndarray) -> tuple[int, int]:
    """The pixel (column, row from the top) that sees `point`."""
    forward, right, up = _basis(EYE, ORIGIN)
    v = point - EYE
    tan_half = np.tan(np.radians(FOV_DEG) / 2.0)
    x = (v @ right) / (v @ forward) / tan_half / (WIDTH / HEIGHT)
    y = (v @ up) / (v @ forward) / tan_half
    return int((x + 1.0) / 2.0 * WIDTH), int((1.0 - y) / 2.0 * HEIGHT)


def _map(root: Path) -> np.ndarray:
    """The cross (h, w, 3) as OpenEXR reads it."""
    channels = OpenEXR.File(str(root / "sky.exr"), separate_channels=True).channels()
    return np.stack([channels[c].pixels for c in "RGB"], axis=-1).astype(np.float64)


def _face_texel(rgb: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The map's radiance in direction d (map axes: x east, y up, z south), bilinear within the
    face that OpenGL's Table 8.19 selects, written out here: major axis, then sc, tc."""
    x, y, z = d
    ax, ay, az = abs(x), abs(y), abs(z)
    if ax >= ay and ax >= az:
        face, sc, tc, ma = ("+X", -z, -y, ax) if x > 0 else ("-X", z, -y, ax)
    elif ay >= az:
        face, sc, tc, ma = ("+Y", x, z, ay) if y > 0 else ("-Y", x, -z, ay)
    else:
        face, sc, tc, ma = ("+Z", x, -y, az) if z > 0 else ("-Z", -x, -y, az)
    row, column = {"+Y": (0, 1), "-X": (1, 0), "+Z": (1, 1), "+X": (1, 2), "-Z": (1, 3),
                   "-Y": (2, 1)}[face]
    s, t = (sc / ma + 1.0) / 2.0 * FACE - 0.5, (tc / ma + 1.0) / 2.0 * FACE - 0.5
    i, j = int(np.floor(t)), int(np.floor(s))
    assert 0 <= i < FACE - 1 and 0 <= j < FACE - 1, "pick directions away from face edges"
    fi, fj = t - i, s - j
    block = rgb[row * FACE + i: row * FACE + i + 2, column * FACE + j: column * FACE + j + 2]
    weights = np.array([[(1 - fi) * (1 - fj), (1 - fi) * fj], [fi * (1 - fj), fi * fj]])
    return np.einsum("ab,abc->c", weights, block)


def _map_directions_and_solid_angles() -> tuple[np.ndarray, np.ndarray]:
    """Each texel's unit direction (map axes) and solid angle, from the face geometry: the
    texel (i, j) of a face at unit distance spans [x0, x1] x [y0, y1], dOmega = dA / r^3,
    integrated here by a 4 x 4 midpoint rule on each texel (1e-5 of the exact value)."""
    rgb_shape = (3 * FACE, 4 * FACE)
    directions = np.zeros(rgb_shape + (3,))
    omega = np.zeros(rgb_shape)
    fine = (np.arange(FACE * 4) + 0.5) / (FACE * 4) * 2.0 - 1.0
    sc, tc = np.meshgrid(fine, fine)  # sc across, tc down
    one = np.ones_like(sc)
    faces = {"+X": (one, -tc, -sc), "-X": (-one, -tc, sc), "+Y": (sc, one, tc),
             "-Y": (sc, -one, -tc), "+Z": (sc, -tc, one), "-Z": (-sc, -tc, -one)}
    places = {"+Y": (0, 1), "-X": (1, 0), "+Z": (1, 1), "+X": (1, 2), "-Z": (1, 3),
              "-Y": (2, 1)}
    for face, columns in faces.items():
        q = np.stack(columns, axis=-1)
        r = np.linalg.norm(q, axis=-1)
        dw = (2.0 / (FACE * 4)) ** 2 / r**3
        row, column = places[face]
        block = (slice(row * FACE, (row + 1) * FACE), slice(column * FACE, (column + 1) * FACE))
        omega[block] = dw.reshape(FACE, 4, FACE, 4).sum(axis=(1, 3))
        directions[block] = (q / r[..., None]).reshape(FACE, 4, FACE, 4, 3).mean(axis=(1, 3))
    norm = np.linalg.norm(directions, axis=-1, keepdims=True)
    return directions / np.where(norm > 0.0, norm, 1.0), omega  # 0 outside the faces


def _sh_irradiance_here(rgb: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """E(n) of orders l <= 2 (Ramamoorthi & Hanrahan 2001, eqs. 3, 7, 8 and their Y_lm
    constants), projected here from the map read back."""
    directions, omega = _map_directions_and_solid_angles()

    def basis(v: np.ndarray) -> np.ndarray:
        x, y, z = v[..., 0], v[..., 1], v[..., 2]
        return np.stack([0.282095 + 0 * x, 0.488603 * y, 0.488603 * z, 0.488603 * x,
                         1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3 * z * z - 1),
                         1.092548 * x * z, 0.546274 * (x * x - y * y)], axis=-1)

    moments = np.einsum("hwk,hw,hwc->kc", basis(directions), omega, rgb)
    a = np.array([np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)
    return basis(normal) @ (a[:, None] * moments)


def _cosine_integral_here(rgb: np.ndarray, normal: np.ndarray) -> np.ndarray:
    directions, omega = _map_directions_and_solid_angles()
    return np.einsum("hw,hwc->c", np.maximum(directions @ normal, 0.0) * omega, rgb)


@pytest.mark.parametrize("face", AXES)
def test_the_background_is_the_cube_map_texel_in_that_direction(page, demo, face):
    # Reference: the EXR of the same map, read with OpenEXR, bilinear in the face that OpenGL's
    # selection table picks for the pixel's ray (written out above), for views along each
    # axis of the map from 50 units off the sphere (its disk is 1.2 deg across, at the centre).
    # The page reads the .hdr: RGBE keeps a pixel's largest channel to 2^-8 (0.4 %), and the
    # GPU's texture filter weights and float32 add ~1e-3; measured 0.25 % at most, tolerance
    # 0.6 % of the pixel's largest channel.
    url, root = demo
    eye = np.array([0.0, 0.0, 50.0])
    target = eye + np.array(AXES[face])
    _open(page, url, eye, target)
    rgb = _map(root)
    for column, row in [(120, 80), (360, 80), (120, 240), (360, 240), (240, 130)]:
        d = _ray(column, row, eye, target)
        shown = np.array(page.evaluate(f"engineDemo.linearAt({column}, {row})"))
        expected = _face_texel(rgb, d)
        np.testing.assert_allclose(shown, expected, rtol=0, atol=0.006 * expected.max())


@pytest.mark.parametrize("facing", ["up", "sun", "west"])
def test_the_sphere_is_lit_by_the_sh_irradiance_and_the_sun(page, demo, facing):
    # Reference: L = albedo / pi (E(n) + E_sun max(n . s, 0)) with E(n) the SH irradiance
    # projected here from the map OpenEXR reads (float32 map, the light file's 6 digits, GPU
    # float32: measured 6e-6; tolerance 1e-4). And E(n) is the map's exact cosine-weighted
    # integral to what orders l <= 2 keep of a sky with a horizon (Ramamoorthi & Hanrahan
    # 2001: 1 % mean, 3 % at most): measured +2.0 % (red, facing up), 1.6 % (the sun), 1.4 %
    # (west); tolerance 2.5 %.
    url, root = demo
    _open(page, url)
    light = json.loads((root / "light.json").read_text())
    sun = np.array(light["sun"]["direction"])
    target = {"up": np.array([0.0, 1.0, 0.0]), "sun": sun,
              "west": np.array([-1.0, 0.3, 0.5]) / np.linalg.norm([-1.0, 0.3, 0.5])}[facing]
    column, row = _pixel_of(target)
    normal = _sphere_hit(_ray(column, row), EYE)
    assert normal is not None and normal @ target > 0.99
    rgb = _map(root)
    sun_term = np.array(light["sun"]["rgb"]) * max(normal @ sun, 0.0)
    sh = _sh_irradiance_here(rgb, normal)
    shown = np.array(page.evaluate(f"engineDemo.linearAt({column}, {row})"))
    np.testing.assert_allclose(shown, ALBEDO / np.pi * (sh + sun_term), rtol=1e-4)
    exact = _cosine_integral_here(rgb, normal)
    np.testing.assert_allclose(sh, exact, rtol=0.025)


def test_a_map_that_is_not_a_cube_map_is_refused_with_a_message(page, demo):
    url, root = demo
    api.save_image(api.render(api.load_atmosphere("earth"), api.EquirectangularCamera(16, 8),
                              30.0, wavelengths_nm=(550.0,), solver="single"),
                   exr_path=root / "panorama.hdr")
    page.goto(f"{url}index.html?map=panorama.hdr")
    page.wait_for_function("document.body.dataset.ready")
    assert page.evaluate("document.body.dataset.ready") == "error"
    message = page.evaluate("document.getElementById('error').textContent")
    assert "a cube map cross is 4:3" in message
