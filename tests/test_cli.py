"""The command line as a contract: what each command prints, writes and exits with.

Calls `skyscatter.cli.main(argv)` in-process. argparse exits through SystemExit (for --help and
for arguments it rejects itself); `_run` turns that into the exit code as a shell sees it.
"""

import csv
import io
import json
import math
import re
import tomllib

import numpy as np
import pytest
from PIL import Image

from cli_runner import run_cli
from skyscatter.atmosphere.config import PRESETS_DIR
from skyscatter.cli import build_parser, main
from skyscatter.render.image_io import read_exr

PERCENT = 1e-2
RADIANCE_KEYS = ["sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg", "wavelength_nm",
                 "radiance", "toa_irradiance"]
RADIANCE_ARGS = ["radiance", "earth", "--sun-zenith", "30", "--view-zenith", "0,60",
                 "--view-azimuth", "0,180", "--wavelengths", "450,550", "--solver", "single"]


def _error_line(stderr: str) -> str:
    """The one line of an error; argparse also prints its usage block, which we skip."""
    assert "Traceback" not in stderr
    lines = stderr.rstrip("\n").split("\n")
    if lines[0].startswith("usage:"):
        lines = [line for line in lines[1:] if not line.startswith(" ")]
    assert len(lines) == 1, stderr
    assert lines[0].startswith("skyscatter"), stderr
    return lines[0]


# --- presets ----------------------------------------------------------------------------------

def test_presets_lists_each_shipped_preset_with_its_description(capsys):
    code, out, err = run_cli(capsys, ["presets"])
    assert code == 0 and err == ""
    lines = out.splitlines()
    shipped = sorted(PRESETS_DIR.glob("*.toml"))
    assert {"earth", "earth-bruneton", "mars-costa"} <= {p.stem for p in shipped}
    assert len(lines) == len(shipped)
    for path, line in zip(shipped, lines, strict=True):
        description = tomllib.loads(path.read_text(encoding="utf-8"))["description"]
        assert line.split()[0] == path.stem
        assert line.endswith(description) and description


def test_presets_verbose_prints_the_derived_numbers_of_each_gas_table(capsys):
    # earth-physical's [gas]: H = R T / (M g) = 8434 m, N0 = P / (k T) = 2.547e25 m^-3,
    # tau_R(550 nm) = 0.0969 (tests/atmosphere/test_atmosphere_gas.py checks the numbers).
    code, out, err = run_cli(capsys, ["presets", "--verbose"])
    assert code == 0 and err == ""
    lines = out.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("earth-physical "))
    block = "\n".join(lines[start + 1:start + 4])
    assert "[gas] 'gas': n2 0.7808, o2 0.2095" in block
    assert "N0 = 2.547e+25 m^-3" in block and "H = 8434 m" in block
    assert "0.0969 (550 nm)" in block
    names = [line.split()[0] for line in lines if not line.startswith(" ")]
    assert names == [p.stem for p in sorted(PRESETS_DIR.glob("*.toml"))]


# --- radiance ---------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def radiance_json():
    # module-scoped: capsys is function-scoped, so capture by hand
    import contextlib
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        assert main([*RADIANCE_ARGS, "--format", "json"]) == 0
    return json.loads(buffer.getvalue())


def test_radiance_json_has_one_row_per_combination_with_the_documented_keys(radiance_json):
    rows = radiance_json
    assert len(rows) == 1 * 2 * 2 * 2  # sun zeniths x view zeniths x azimuths x wavelengths
    for row in rows:
        assert list(row) == RADIANCE_KEYS
        assert all(isinstance(v, float) and math.isfinite(v) for v in row.values())
        assert row["radiance"] > 0.0 and row["toa_irradiance"] > 0.0
    combinations = {(r["view_zenith_deg"], r["relative_azimuth_deg"], r["wavelength_nm"])
                    for r in rows}
    assert combinations == {(vz, az, wl) for vz in (0.0, 60.0) for az in (0.0, 180.0)
                            for wl in (450.0, 550.0)}
    assert {r["sun_zenith_deg"] for r in rows} == {30.0}


def test_radiance_csv_has_the_same_columns_and_rows_as_json(capsys, radiance_json):
    code, out, err = run_cli(capsys, [*RADIANCE_ARGS, "--format", "csv"])
    assert code == 0
    reader = csv.DictReader(io.StringIO(out))
    assert reader.fieldnames == RADIANCE_KEYS
    rows = list(reader)
    assert len(rows) == len(radiance_json)
    for row, reference in zip(rows, radiance_json, strict=True):
        for key in RADIANCE_KEYS:  # CSV prints 10 significant digits
            assert float(row[key]) == pytest.approx(reference[key], rel=1e-9)


def test_radiance_toa_irradiance_at_550nm_is_astm_g173(radiance_json):
    # ASTM G173-03 ETR at 550 nm: 1.863 W m^-2 nm^-1 (point), 1.868 (10-nm mean),
    # (pvlib 0.16.1 data/ASTMG173.csv). 2 %: the CLI averages over a 1-nm cell.
    values = {r["toa_irradiance"] for r in radiance_json if r["wavelength_nm"] == 550.0}
    assert len(values) == 1
    assert values.pop() == pytest.approx(1.86, rel=2 * PERCENT)


def test_radiance_is_mirror_symmetric_about_the_sun_vertical(capsys):
    # A horizontally uniform atmosphere is symmetric under reflection in the vertical plane
    # through the sun: relative azimuth +90 and -90 (= 270) see the same sky. Tolerance: rounding.
    code, out, _ = run_cli(capsys, ["radiance", "earth", "--sun-zenith", "50", "--view-zenith",
                                 "40,80", "--view-azimuth", "0,90,-90,270", "--wavelengths",
                                 "450,650", "--orders", "2", "--format", "json"])
    assert code == 0
    radiance, towards_sun = {}, {}
    for row in json.loads(out):
        key = (row["view_zenith_deg"], row["wavelength_nm"])
        if row["relative_azimuth_deg"] == 0.0:
            towards_sun[key] = row["radiance"]
        else:
            radiance.setdefault(key, []).append(row["radiance"])
    assert len(radiance) == 4
    for key, values in radiance.items():
        np.testing.assert_allclose(values, values[0], rtol=1e-9)
        assert towards_sun[key] > 1.05 * values[0]  # azimuth matters: forward scattering


# --- help -------------------------------------------------------------------------------------

@pytest.mark.parametrize(("command", "options"), [
    ([], ["presets", "render", "timelapse", "radiance", "--version", "--debug"]),
    (["presets"], []),
    (["render"], ["--sun-zenith", "--sun-elevation", "--sun-azimuth", "--camera", "--size",
                  "--wavelengths", "--exposure", "--output", "--exr", "--exr-content"]),
    (["radiance"], ["--sun-zenith", "--view-zenith", "--view-azimuth", "--wavelengths",
                    "--altitude", "--format", "--time", "--lat", "--lon", "--elevation-m"]),
    (["timelapse"], ["--start", "--end", "--step", "--frames", "--lat", "--lon", "--fps",
                     "--twinkle", "--milky-way", "--frames-dir", "--adaptation-minutes"]),
])
def test_help_of_each_command_exits_0_and_lists_its_options(capsys, command, options):
    code, out, err = run_cli(capsys, [*command, "--help"])
    assert code == 0 and err == ""
    assert out.startswith("usage: skyscatter" + "".join(f" {c}" for c in command))
    for option in options:
        assert option in out


@pytest.mark.parametrize("command", ["render", "timelapse", "radiance"])
def test_solver_help_lists_every_registered_solver(capsys, command):
    # the help is read from the registry: a solver registered with a description shows up
    from skyscatter.transport.solvers import SOLVERS
    code, out, _ = run_cli(capsys, [command, "--help"])
    text = "".join(out.split())  # argparse wraps the help, at spaces and after hyphens
    assert code == 0 and set(SOLVERS) >= {"lut", "single", "montecarlo"}
    for name, description in SOLVERS.items():
        line = f"{name}{' (default)' if name == 'lut' else ''}: {description}"
        assert "".join(line.split()) in text


# --- bad arguments: exit 2, one line, no traceback -------------------------------------------

@pytest.mark.parametrize(("argv", "expected"), [
    (["radiance", "eart", "--sun-zenith", "30"], "did you mean 'earth'"),
    (["radiance", "earth", "--sun-zenith", "abc"], "'abc' is not a comma-separated list"),
    (["radiance", "earth", "--sun-zenith", "200"],
     "--sun-zenith: '200' is not allowed: a finite number >= 0 and <= 180"),
    (["radiance", "earth", "--sun-zenith", "30", "--view-zenith", "-1"],
     "--view-zenith: '-1' is not allowed"),
    (["radiance", "earth", "--sun-zenith", "30", "--wavelengths", "-5"], "wavelength"),
    (["radiance", "earth", "--sun-zenith", "30", "--format", "xml"], "invalid choice: 'xml'"),
    (["render", "earth", "--size", "0"], "--size: 0 is not allowed: a whole number from 1"),
    (["render", "earth", "--wavelengths", "472"], "more than the 471 1-nm bins of 360-830 nm"),
    (["radiance", "earth", "--sun-zenith", "30", "--solver", "lutt"],
     "unknown solver 'lutt'; available: lut, single, montecarlo"),
    (["render", "earth", "--camera", "orthographic"], "invalid choice: 'orthographic'"),
    (["rendr", "earth"], "did you mean 'render'?"),
    (["render", "earth", "--camera", "cubmap"], "did you mean 'cubemap'?"),
    (["render", "earth", "--sun-elevaton", "5"],
     "did you mean --sun-elevation for --sun-elevaton?"),
    (["radiance", "earth", "--sun-zenith", "30", "--paths", "100"],
     "--paths is an option of compare, not of radiance"),
    (["render", "earth", "--time", "2024-06-21T21:30[Europe/Berln]", "--lat", "52", "--lon",
      "13"], "not a zone of the IANA time zone database"),
    (["render", "earth", "--sun-zenith", "30", "--sun-elevation", "60"], "not allowed with"),
    (["render", "earth", "--time", "2024-06-21T21:30", "--lat", "52", "--lon", "13"],
     "has no time zone"),
    (["render", "earth", "--time", "2024-06-21T21:30+02:00"], "give --lat and --lon"),
    (["render", "earth", "--time", "2024-06-21T21:30Z", "--sun-zenith", "30"], "not allowed"),
    (["render", "earth", "--time", "2024-06-21T21:30Z", "--lat", "95", "--lon", "0"],
     "--lat: '95' is not allowed: a finite number >= -90 and <= 90"),
    (["render", "exo-hazy", "--time", "2024-06-21T21:30Z", "--lat", "0", "--lon", "0"],
     "has no ephemeris"),
    (["radiance", "earth", "--time", "yesterday", "--lat", "0", "--lon", "0"], "yesterday"),
    (["timelapse", "earth", "--start", "2024-06-21T22:00Z", "--end", "2024-06-21T21:00Z",
      "--lat", "0", "--lon", "0"], "must come after"),
    (["timelapse", "earth", "--start", "2024-06-21T20:00Z", "--end", "2024-06-21T21:00Z",
      "--lat", "0", "--lon", "0", "--step", "10 parsecs"], "is not a duration"),
    (["timelapse", "earth", "--start", "2024-06-21T20:00Z", "--end", "2024-06-21T21:00Z",
      "--lat", "0", "--lon", "0", "-o", "sky.avi"], ".mp4 or .gif"),
    (["render", "earth", "--clouds", "cumuls"], "did you mean 'cumulus'"),
    (["render", "earth", "--clouds", "cumulus", "--solver", "single"], "needs the table solver"),
    (["render", "earth", "--clouds", "/nonexistent/clouds.toml"], "does not exist"),
    (["render", "earth", "--clouds", "cumulus", "--cloud-time", "nan"], "--cloud-time"),
])
def test_bad_argument_exits_2_with_one_clear_line(capsys, argv, expected):
    code, out, err = run_cli(capsys, argv)
    assert code == 2
    assert out == ""
    assert expected in _error_line(err)


def test_negative_wavelength_message_names_the_value(capsys):
    code, _, err = run_cli(capsys, ["radiance", "earth", "--sun-zenith", "30", "--wavelengths",
                                 "-5"])
    assert code == 2
    line = _error_line(err)
    assert "'-5' is not allowed" in line and "280.5" in line and "nm" in line


def test_missing_config_file_exits_2_naming_the_file(capsys, tmp_path):
    missing = tmp_path / "missing.toml"
    code, _, err = run_cli(capsys, ["radiance", str(missing), "--sun-zenith", "30"])
    assert code == 2
    assert _error_line(err) == f"skyscatter: config file '{missing}' does not exist"


def test_config_file_with_a_bad_value_exits_2_naming_file_key_and_value(capsys, tmp_path):
    text = (PRESETS_DIR / "earth-bruneton.toml").read_text(encoding="utf-8")
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("ground_albedo = 0.1", "ground_albedo = 1.5", 1),
                   encoding="utf-8")
    for command in (["radiance", str(bad), "--sun-zenith", "30"],
                    ["render", str(bad), "--size", "8", "-o", str(tmp_path / "x.png")]):
        code, _, err = run_cli(capsys, command)
        assert code == 2
        line = _error_line(err)
        assert line.startswith(f"skyscatter: {bad}: planet.ground_albedo = 1.5")
        assert "<= 1" in line
    assert not (tmp_path / "x.png").exists()


# --- render -----------------------------------------------------------------------------------

def test_a_bad_clouds_file_names_the_key(capsys, tmp_path):
    clouds = tmp_path / "clouds.toml"
    clouds.write_text("[[layer]]\nbase_altitude_m = 1000\ntop_altitude_m = 2000\n"
                      "coverage = 0.5\nwater_content_g_m3 = -1\n")
    code, out, err = run_cli(capsys, ["render", "earth", "--clouds", str(clouds), "--size", "8",
                                      "-o", str(tmp_path / "x.png")])
    assert code == 2 and out == ""
    line = _error_line(err)
    assert "water_content_g_m3" in line and "-1" in line and str(clouds) in line
    assert not (tmp_path / "x.png").exists()


def test_a_bad_coverage_map_names_the_key_and_the_file(capsys, tmp_path):
    np.save(tmp_path / "weather.npy", np.full((4, 8), 1.5))
    clouds = tmp_path / "clouds.toml"
    clouds.write_text("[[layer]]\nbase_altitude_m = 1000\ntop_altitude_m = 2000\n"
                      "coverage = 0.5\nwater_content_g_m3 = 0.3\n"
                      "coverage_map = 'weather.npy'\n")
    code, out, err = run_cli(capsys, ["render", "earth", "--clouds", str(clouds), "--size", "8",
                                      "-o", str(tmp_path / "x.png")])
    assert code == 2 and out == ""
    line = _error_line(err)
    assert "coverage_map" in line and "weather.npy" in line and "[0, 1]" in line
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("arrays, message", [
    (None, "no such file"),
    ({"water_g_m3": np.ones((2, 2, 2))}, "no array 'spacing_m'"),
    ({"water_g_m3": np.full((2, 2, 2), np.nan), "spacing_m": np.ones(3)}, "not finite"),
    ({"water_g_m3": -np.ones((2, 2, 2)), "spacing_m": np.ones(3)}, "np.clip"),
])
def test_a_bad_cloud_grid_names_the_key_the_file_and_a_fix(capsys, tmp_path, arrays, message):
    if arrays is not None:
        np.savez(tmp_path / "les.npz", **arrays)
    clouds = tmp_path / "clouds.toml"
    clouds.write_text("[[layer]]\ntype = 'grid'\ngrid = 'les.npz'\nbase_altitude_m = 1000\n")
    code, out, err = run_cli(capsys, ["render", "earth", "--clouds", str(clouds), "--size", "8",
                                      "-o", str(tmp_path / "x.png")])
    assert code == 2 and out == ""
    line = _error_line(err)
    assert "grid" in line and "les.npz" in line and str(clouds) in line and message in line
    assert not (tmp_path / "x.png").exists()


def test_render_with_a_grid_cloud_writes_a_finite_image(capsys, tmp_path):
    x, y, z = np.meshgrid(*(np.linspace(-1.0, 1.0, 16),) * 3, indexing="ij")
    np.savez(tmp_path / "bubble.npz", water_g_m3=np.clip(0.5 * (1 - x**2 - y**2 - z**2), 0, None),
             spacing_m=(100.0, 100.0, 100.0), periodic=False)
    clouds = tmp_path / "clouds.toml"
    clouds.write_text("[[layer]]\ntype = 'grid'\ngrid = 'bubble.npz'\nbase_altitude_m = 1000\n")
    exr = tmp_path / "grid.exr"
    code, _, err = run_cli(capsys, ["render", "earth", "--clouds", str(clouds), "--size", "16",
                                    "-o", str(tmp_path / "grid.png"), "--exr", str(exr)])
    assert code == 0, err
    assert (tmp_path / "grid.png").exists() and exr.exists()


def test_earth_from_orbit_with_the_earth_weather_clouds(capsys, tmp_path):
    exr = tmp_path / "orbit.exr"
    code, _, err = run_cli(capsys, ["render", "earth", "--camera", "orbit", "--clouds",
                                    "earth-weather", "--distance-km", "20000", "--size", "16",
                                    "--wavelengths", "3", "-o", str(tmp_path / "orbit.png"),
                                    "--exr", str(exr)])
    assert code == 0, err
    pixels, _ = read_exr(exr)
    assert np.all(np.isfinite(pixels)) and pixels.max() > 0.0


def test_render_with_clouds_writes_a_finite_image(capsys, tmp_path):
    exr = tmp_path / "clouds.exr"
    code, _, err = run_cli(capsys, ["render", "earth", "--clouds", "stratus", "--size", "16",
                                    "--wavelengths", "3", "--altitude", "2", "-o",
                                    str(tmp_path / "clouds.png"), "--exr", str(exr)])
    assert code == 0, err
    pixels, _ = read_exr(exr)
    assert np.all(np.isfinite(pixels)) and pixels.max() > 0.0


def test_render_fisheye_writes_png_and_linear_exr(capsys, tmp_path):
    png, exr = tmp_path / "out" / "x.png", tmp_path / "out" / "x.exr"
    code, out, err = run_cli(capsys, ["render", "earth", "--size", "32", "--camera", "fisheye",
                                   "--solver", "single", "-o", str(png), "--exr", str(exr)])
    assert code == 0, err
    assert str(png) in err and str(exr) in err
    with Image.open(png) as image:
        assert image.size == (32, 32)
    rgb, names = read_exr(exr)
    assert names == ("R", "G", "B") and rgb.shape == (32, 32, 3)
    assert np.all(np.isfinite(rgb))
    # The zenith is the image centre (equidistant all-sky lens); linear sRGB/Rec.709 primaries:
    # Y = 0.2126 R + 0.7152 G + 0.0722 B (IEC 61966-2-1), in cd m^-2.
    centre = rgb[15:17, 15:17].reshape(-1, 3).astype(np.float64)
    luminance = centre @ np.array([0.2126, 0.7152, 0.0722])
    assert np.all(luminance > 0.0)


@pytest.mark.parametrize(("camera", "size", "expected_wh"), [
    ("panorama", 12, (24, 12)),          # equirectangular: width = 2 x size
    ("perspective", 9, (16, 9)),         # width = round(size x 16/9)
])
def test_render_other_cameras_at_small_sizes(capsys, tmp_path, camera, size, expected_wh):
    png = tmp_path / f"{camera}.png"
    code, _, err = run_cli(capsys, ["render", "earth", "--size", str(size), "--camera", camera,
                                 "--sun-elevation", "20", "--wavelengths", "8", "--samples", "16",
                                 "--solver", "single", "-o", str(png)])
    assert code == 0, err
    with Image.open(png) as image:
        assert image.size == expected_wh
        assert np.asarray(image.convert("RGB")).max() > 0


def test_orbit_camera_sees_the_lit_side_towards_the_sun(capsys, tmp_path):
    # Sun low in the east of the point below the camera: looking down with north up, east is
    # on the right of the image, so the right half must be brighter than the left.
    exr = tmp_path / "orbit.exr"
    code, _, err = run_cli(capsys, ["render", "earth", "--camera", "orbit", "--distance-km",
                                 "20000", "--lat", "0", "--sun-elevation", "10",
                                 "--sun-azimuth", "90", "--size", "24", "-o",
                                 str(tmp_path / "orbit.png"), "--exr", str(exr),
                                 "--wavelengths", "4", "--orders", "2"])
    assert code == 0, err
    image, _ = read_exr(exr)
    luminance = image.sum(axis=-1)
    assert luminance[:, 16:].mean() > 3.0 * luminance[:, :8].mean()


# --- precompute and the table cache -------------------------------------------------------------

PRECOMPUTE_ARGS = ["--wavelengths", "550", "--orders", "1"]


def test_precompute_says_how_many_orders_it_iterated(capsys, tmp_path):
    # Earth's orders fall off by ~0.4 per order and their ratio settles within a few orders:
    # with 12 allowed the iteration stops early and adds the rest as a geometric series
    # (tables.TAIL_TOLERANCE); the log names the orders iterated, not only the limit.
    code, _, err = run_cli(capsys, ["precompute", "earth", "--monochromatic", "--wavelengths",
                                    "550", "--orders", "12", "--cache-dir", str(tmp_path)])
    assert code == 0, err
    assert "precomputing 12 orders for 1 wavelengths" in err
    match = re.search(r"tables: (\d+) orders iterated, the orders beyond added as their "
                      r"geometric series or extrapolated limit \(up to (\d+) % of the orders "
                      r">= 2\)", err)
    assert match is not None, err
    assert 4 <= int(match.group(1)) < 12 and int(match.group(2)) < 10


def test_precompute_stores_tables_that_radiance_then_reuses(capsys, tmp_path):
    cache = tmp_path / "cache"
    code, _, err = run_cli(capsys, ["precompute", "earth", "--monochromatic", *PRECOMPUTE_ARGS,
                                 "--cache-dir", str(cache)])
    assert code == 0, err
    assert "precomputing 1 orders for 1 wavelengths (not cached yet" in err
    assert "earth: 1 orders, 1 wavelengths" in err
    (entry,) = cache.glob("*.npz")
    code, out, err = run_cli(capsys, ["radiance", "earth", "--sun-zenith", "30", *PRECOMPUTE_ARGS,
                                   "--cache-dir", str(cache)])
    assert code == 0, err
    assert f"using {entry}" in err
    lut_radiance = float(out.splitlines()[1].split(",")[4])
    # order 1 from the tables is the single-scattering solver's answer (0.5 %: table
    # interpolation, measured 0.05 % median in tests/transport)
    code, out, _ = run_cli(capsys, ["radiance", "earth", "--sun-zenith", "30", "--wavelengths",
                                 "550", "--solver", "single"])
    assert lut_radiance == pytest.approx(float(out.splitlines()[1].split(",")[4]),
                                         rel=0.5 * PERCENT)


def test_a_corrupt_cache_entry_is_rebuilt_not_used(capsys, tmp_path):
    cache = tmp_path / "cache"
    argv = ["precompute", "earth", "--monochromatic", *PRECOMPUTE_ARGS, "--cache-dir",
            str(cache)]
    assert run_cli(capsys, argv)[0] == 0
    (entry,) = cache.glob("*.npz")
    entry.write_bytes(entry.read_bytes()[:1000])  # truncated, as by a full disk
    code, _, err = run_cli(capsys, argv)
    assert code == 0, err
    assert "unreadable cache file" in err and "precomputing" in err
    code, _, err = run_cli(capsys, argv)
    assert "using" in err
    assert not list(cache.glob(".*tmp"))  # no temporary files left behind


def test_no_cache_writes_nothing(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path / "cache"))
    code, _, err = run_cli(capsys, ["radiance", "earth", "--sun-zenith", "30", *PRECOMPUTE_ARGS,
                                 "--no-cache"])
    assert code == 0, err
    assert not (tmp_path / "cache").exists()


@pytest.mark.parametrize(("argv", "message"), [
    (["render", "earth", "--look-at", "10,20"], "--look-at is for --camera orbit"),
    (["render", "earth", "--camera", "orbit", "--look-at", "10"], "LAT,LON or LAT,LON,ALT_KM"),
    (["render", "earth", "--terrain", "nowhere.png"], "nowhere.png"),
    (["render", "earth", "--albedo-map", "nowhere.png"], "nowhere.png: no such file"),
    (["render", "earth", "--terrain", "demo", "--solver", "single", "--size", "8"],
     "needs the table solver"),
    (["precompute", "earth", "--orders", "0"], "--orders: 0 is not allowed"),
])
def test_bad_scene_arguments_get_one_clear_line(capsys, tmp_path, argv, message):
    code, _, err = run_cli(capsys, [*argv, "-o", str(tmp_path / "x.png")] if argv[0] == "render"
                        else argv)
    assert code == 2
    assert message in _error_line(err)
    assert not (tmp_path / "x.png").exists()


def test_monte_carlo_radiance_comes_with_its_standard_error(capsys):
    # 1500 paths at 450 nm: the standard error is below 3 % of the value (measured 0.8 %)
    # and above 0 (it is a real noise estimate, not a placeholder).
    assert main(["radiance", "earth", "--solver", "montecarlo", "--samples", "1500",
                 "--sun-zenith", "30", "--view-zenith", "0,60", "--wavelengths", "450",
                 "--format", "json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert len(rows) == 2
    for row in rows:
        assert 0.0 < row["standard_error"] < 0.03 * row["radiance"]


@pytest.mark.parametrize(("option", "value", "message"), [
    ("--tonemap", "sepia", "unknown tone-mapping operator 'sepia'"),
    ("--colour-space", "cmyk", "unknown colour space 'cmyk'"),
])
def test_bad_image_option_is_rejected_before_any_table_is_computed(capsys, tmp_path, option,
                                                                    value, message):
    # The image options were checked only when saving, after tens of seconds of tables.
    cache = tmp_path / "cache"
    code, _, err = run_cli(capsys, ["render", "earth", option, value, "--cache-dir", str(cache),
                                 "-o", str(tmp_path / "x.png")])
    assert code == 2
    assert message in _error_line(err)
    assert not cache.exists() and not (tmp_path / "x.png").exists()


# --- skies at a date: render --time, radiance --time, timelapse -------------------------------

def test_render_at_a_time_and_place_reports_the_sun_and_moon(capsys, tmp_path):
    # Berlin, 2024-06-21 21:30 CEST: the sun has just set in the north-west (PyEphem, airless:
    # altitude -0.45 deg, azimuth 311.6 deg; the test of astro/earth_sky checks it against
    # astropy); the summary line reports it.
    png = tmp_path / "berlin.png"
    code, _, err = run_cli(capsys, ["render", "earth", "--time", "2024-06-21T21:30+02:00", "--lat",
                                 "52.52", "--lon", "13.40", "--size", "24", "--wavelengths",
                                 "4", "--orders", "2", "-o", str(png)])
    assert code == 0, err
    assert "sun: altitude -0.45 deg, azimuth 311.59 deg" in err and "moon:" in err
    with Image.open(png) as image:
        rgb = np.asarray(image.convert("RGB")).astype(float)
    # the fisheye's west (right) half glows brighter than the east half after sunset
    assert rgb[:, 14:].mean() > rgb[:, :10].mean()


@pytest.mark.parametrize("date", ["2024-01-03T12:00Z", "2024-07-05T12:00Z"])
def test_radiance_at_a_time_uses_the_suns_zenith_and_distance_then(capsys, date):
    # The numbers of that sun zenith asked for directly (the config's sun at 1 AU), times the
    # inverse-square law for the sun's distance that day: perihelion 0.9833 AU (+3.4 %),
    # aphelion 1.0167 AU (-3.3 %). Reference distance: NREL SPA (Reda & Andreas 2004) through
    # pvlib, geocentric; ours is topocentric (4.3e-5 closer at most), so 1e-4 on the square.
    pvlib = pytest.importorskip("pvlib")
    pd = pytest.importorskip("pandas")
    common = ["--wavelengths", "550", "--solver", "single", "--samples", "16",
              "--format", "json"]
    code, out, err = run_cli(capsys, ["radiance", "earth", "--time", date, "--lat", "0",
                                      "--lon", "0", *common])
    assert code == 0, err
    assert " AU" in err  # the sun's distance is said with its position
    rows = json.loads(out)
    zenith = rows[0]["sun_zenith_deg"]
    code, out, _ = run_cli(capsys, ["radiance", "earth", "--sun-zenith", str(zenith), *common])
    at_one_au = json.loads(out)[0]
    distance_au = float(pvlib.solarposition.nrel_earthsun_distance(
        pd.DatetimeIndex([date])).iloc[0])
    for key in ("radiance", "toa_irradiance"):
        assert rows[0][key] == pytest.approx(at_one_au[key] / distance_au**2, rel=1e-4)


def test_timelapse_writes_frames_and_a_video(capsys, tmp_path):
    video = tmp_path / "dusk.mp4"
    code, _, err = run_cli(capsys, ["timelapse", "earth", "--start", "2024-06-21T19:00Z", "--end",
                                 "2024-06-21T20:00Z", "--frames", "3", "--lat", "52.52",
                                 "--lon", "13.40", "--size", "16", "--wavelengths", "4",
                                 "--orders", "2", "--twinkle", "3", "-o", str(video)])
    assert code == 0, err
    frames = sorted((tmp_path / "dusk_frames").glob("frame_*.png"))
    assert [f.name for f in frames] == ["frame_00001.png", "frame_00002.png", "frame_00003.png"]
    with Image.open(frames[0]) as first, Image.open(frames[-1]) as last:
        assert first.text["Time"] == "2024-06-21T19:00:00+00:00"
        # the exposure follows the dusk: a higher EV100 before sunset than after
        assert float(first.text["EV100"]) > float(last.text["EV100"])
    assert video.stat().st_size > 0 and "wrote" in err


@pytest.mark.parametrize(("argv", "expected"), [
    (["render", "earth", "--time", "2024-01-25T23:00Z", "--lat", "52", "--lon", "13",
      "--magnitude-limit", "nan"], "--magnitude-limit: 'nan' is not allowed"),
    (["timelapse", "earth", "--start", "2024-01-25T20:00Z", "--end", "2024-01-25T21:00Z",
      "--lat", "52", "--lon", "13", "--fps", "0"], "--fps: '0' is not allowed"),
])
def test_bad_sky_options_are_refused_before_any_table_work(capsys, tmp_path, monkeypatch,
                                                            argv, expected):
    cache = tmp_path / "cache"
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(cache))
    code, _, err = run_cli(capsys, [*argv, "-o", str(tmp_path / "x.gif")])
    assert code == 2 and expected in _error_line(err)
    assert not cache.exists()  # nothing computed or stored


# --- options shared by render and timelapse ---------------------------------------------------

def _options(command: str) -> dict:
    """option string -> argparse action of one subcommand."""
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    return {name: action for action in commands[command]._actions
            for name in action.option_strings}


def test_render_and_timelapse_describe_their_shared_options_alike():
    # The two commands once said different things about the same option; one text each now.
    # --size differs in its default (512 / 384), --fov in the orbit camera render alone has,
    # --camera in the choices (timelapse has no orbit camera).
    render, timelapse = _options("render"), _options("timelapse")
    for option in ("--aspect", "--heading", "--pitch", "--wavelengths",
                   "--exposure-compensation", "--tonemap", "--colour-space"):
        assert render[option].help == timelapse[option].help, option
        assert render[option].default == timelapse[option].default, option
    assert (render["--size"].default, timelapse["--size"].default) == (512, 384)
    assert timelapse["--camera"].choices == ("fisheye", "panorama", "perspective")
    assert "orbit" not in timelapse["--camera"].help + timelapse["--fov"].help


def test_image_option_help_names_every_tone_curve_and_colour_space():
    from skyscatter.render.tonemap import OPERATORS
    from skyscatter.spectrum.colour import RGB_SPACES
    render = _options("render")
    for name in OPERATORS:
        assert name in render["--tonemap"].help
    for name in RGB_SPACES:
        assert name in render["--colour-space"].help



def test_skyscatter_alone_prints_its_help(capsys):
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: skyscatter") and "render" in out
