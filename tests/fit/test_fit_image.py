"""Fitting an image: the luminance of sky pixels of a linear EXR written by `skyscatter render`
(`fit.image_samples`), with the render's camera options; rendered and fitted by the same
solver, the fit must give back the config (an end-to-end check of the pixel directions, the
relative azimuth, the EXR's RGB -> Y and the luminance forward model)."""

import json

import pytest

from cli_runner import run_cli

KEY = "constituent[2].optics.optical_depth"


@pytest.mark.parametrize("camera", [
    ["--size", "48", "--sun-zenith", "50"],
    ["--camera", "perspective", "--size", "40", "--fov", "70", "--heading", "60",
     "--pitch", "25", "--sun-zenith", "65", "--sun-azimuth", "100"],
])
def test_a_rendered_sky_fitted_gives_back_its_optical_depth(capsys, tmp_path, camera):
    # hillaire renders (16 bands, 64 samples) and fits (the same): the optical depth of the
    # preset, 0.1, within 1e-5 - the EXR's float32 (1e-7 relative) and the fit's
    # convergence, far inside the stated sigma; a wrong direction or azimuth (the sun at
    # 100 deg, the camera at 60 deg) would leave a chi-square far from 0
    exr = tmp_path / "sky.exr"
    code, _, err = run_cli(capsys, ["render", "earth", "--solver", "hillaire", *camera,
                                    "--exr", str(exr), "-o", str(tmp_path / "sky.png")])
    assert code == 0, err
    report = tmp_path / "report.json"
    code, out, err = run_cli(capsys, ["fit", "earth", "--image", str(exr), *camera,
                                      "--pixels", "60", "--relative-uncertainty", "0.02",
                                      "--samples", "64", "--free", f"{KEY}=0.01:1:0.3",
                                      "-o", str(report)])
    assert code == 0, err
    result = json.loads(report.read_text())
    assert result["parameters"][0]["estimate"] == pytest.approx(0.1, abs=1e-5)
    assert result["chi_square"] < 1e-6
    assert {row["quantity"] for row in result["rows"]} == {"luminance"}


def test_an_image_needs_its_sun_and_a_camera_of_its_size(capsys, tmp_path):
    exr = tmp_path / "sky.exr"
    code, _, _ = run_cli(capsys, ["render", "earth", "--solver", "schuler", "--size", "32",
                                  "--sun-zenith", "40", "--exr", str(exr), "-o",
                                  str(tmp_path / "sky.png")])
    assert code == 0
    base = ["fit", "earth", "--image", str(exr), "--free", f"{KEY}=0:1",
            "--relative-uncertainty", "0.02"]
    code, _, err = run_cli(capsys, [*base, "--size", "32"])
    assert code == 2 and "--sun-zenith" in err and err.count("\n") == 1
    code, _, err = run_cli(capsys, [*base, "--size", "40", "--sun-zenith", "40"])
    assert code == 2 and "give the camera options it was rendered with" in err
    code, _, err = run_cli(capsys, [*base, "--size", "32", "--sun-zenith", "40",
                                    "--pixels", "100000"])
    assert code == 2 and "fewer than 100000" in err
    code, _, err = run_cli(capsys, ["fit", "earth", "--free", f"{KEY}=0:1"])
    assert code == 2 and "nothing to fit" in err
