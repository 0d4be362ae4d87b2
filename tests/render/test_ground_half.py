"""`render --ground tables|black|ALBEDO`: the lower half of an environment map as the tables see
it, black, or over a grey ground of another albedo (`api.without_ground`,
`api.with_ground_albedo`).

Black starts at the geometric horizon, whose depression below the horizontal seen from height h
is arccos(R / (R + h)) (a closed form, not the renderer's own test); the albedo variant equals the
same atmosphere whose config file names that albedo (the config loader, an independent path).
"""

from __future__ import annotations

import math
import shutil

import numpy as np
import OpenEXR
import pytest

from cli_runner import run_cli
from skyscatter import api
from skyscatter.atmosphere.config import PRESETS_DIR
from skyscatter.render.camera import EquirectangularCamera

SINGLE = api.solver_options(api.load_atmosphere("earth"), n_samples=8)
WAVELENGTHS = [450.0, 550.0, 650.0]


def _panorama(atmosphere, altitude_m: float):
    camera = EquirectangularCamera(48, 240)  # 0.75 deg rows: the horizon's dip is resolved
    image = api.render(atmosphere, camera, 60.0, altitude_m=altitude_m,
                       wavelengths_nm=WAVELENGTHS, solver="single", options=SINGLE)
    return camera, image


def test_black_starts_at_the_geometric_horizon():
    earth = api.load_atmosphere("earth")
    altitude_m = 10_000.0
    camera, image = _panorama(earth, altitude_m)
    black = api.without_ground(image, camera, earth, altitude_m)
    radius = earth.planet.radius_m
    dip_deg = math.degrees(math.acos(radius / (radius + altitude_m)))  # 3.2 deg at 10 km
    elevation_deg = 90.0 - 180.0 * (np.arange(camera.height) + 0.5) / camera.height
    below = elevation_deg < -dip_deg
    assert np.all(black.spectral[below] == 0.0)
    assert np.array_equal(black.spectral[~below], image.spectral[~below])
    # the rows between the horizontal and the horizon see the sky (and were not cut)
    dipped = (elevation_deg < 0.0) & ~below
    assert dipped.sum() >= 3 and np.all(black.spectral[dipped] > 0.0)
    assert np.all(image.spectral[below] > 0.0)  # there was a ground to remove


def test_a_ground_albedo_equals_the_config_that_names_it(tmp_path):
    text = (PRESETS_DIR / "earth.toml").read_text(encoding="utf-8")
    assert "ground_albedo = 0.1 " in text
    for table in PRESETS_DIR.glob("*.csv"):  # the profiles it names, beside it
        shutil.copy(table, tmp_path)
    config = tmp_path / "earth_bright.toml"
    config.write_text(text.replace("ground_albedo = 0.1 ", "ground_albedo = 0.6 "),
                      encoding="utf-8")
    variant = api.with_ground_albedo(api.load_atmosphere("earth"), 0.6)
    _, ours = _panorama(variant, 0.0)
    _, theirs = _panorama(api.load_atmosphere(config), 0.0)
    np.testing.assert_allclose(ours.spectral, theirs.spectral, rtol=1e-12)
    _, darker = _panorama(api.load_atmosphere("earth"), 0.0)
    assert np.all(ours.spectral[-1] > darker.spectral[-1])  # the nadir row: a brighter ground


def test_the_cli_writes_a_cube_map_whose_lower_face_is_black(capsys, tmp_path):
    exr = tmp_path / "sky.exr"
    code, _, err = run_cli(capsys, [
        "render", "earth", "--camera", "cubemap", "--cube-layout", "strip", "--size", "8",
        "--solver", "single", "--samples", "8", "--wavelengths", "450,550,650",
        "--ground", "black", "--exr", str(exr), "-o", str(tmp_path / "sky.png")])
    assert code == 0, err
    green = OpenEXR.File(str(exr), separate_channels=True).channels()["G"].pixels
    faces = green.reshape(8, 6, 8)  # strip: +X, -X, +Y, -Y, +Z, -Z
    assert np.all(faces[:, 3] == 0.0) and np.all(faces[:, 2] > 0.0)


@pytest.mark.parametrize("value", ["1.5", "-0.1", "grey", "nan"])
def test_a_bad_ground_is_refused_in_one_line(capsys, value):
    code, _, err = run_cli(capsys, ["render", "earth", "--ground", value])
    assert code == 2
    assert "--ground" in err and "tables, black or an albedo from 0 to 1" in err
    assert "Traceback" not in err
