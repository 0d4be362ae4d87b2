"""Hostile command lines: every numeric option refuses NaN, infinities, out-of-range numbers and
text that is no number before any work, with exit code 2 and one line naming the option.

The allowed ranges below are written from the physics, independently of the code (`checks`):
zenith angles 0-180 deg, elevations and latitudes -90-90, azimuths any finite number,
perspective field of view in (0, 180), and so on. Hypothesis generates values outside them;
each must be refused, nothing may be written and no table computed (a private cache folder
stays absent).
"""

import json
import math

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from skyscatter.cli import build_parser, main

FINITE = (-math.inf, math.inf)
RENDER = ["render", "earth"]
TIMELAPSE = ["timelapse", "earth", "--start", "2024-06-21T20:00Z", "--end",
             "2024-06-21T21:00Z", "--lat", "52", "--lon", "13"]
RADIANCE = ["radiance", "earth", "--sun-zenith", "30"]
SWEEP = ["sweep", "earth", "-o", "x.nc"]

# (command, option, lowest allowed, highest allowed, lowest is excluded, is a whole number)
NUMBERS = [
    (RENDER, "--sun-zenith", 0.0, 180.0, False, False),
    (RENDER, "--sun-elevation", -90.0, 90.0, False, False),
    (RENDER, "--sun-azimuth", *FINITE, False, False),
    (RENDER, "--aspect", 0.0, 100.0, True, False),
    (RENDER, "--fov", 0.0, math.nextafter(180.0, 0.0), True, False),
    (RENDER, "--distance-km", 0.0, 1e9, True, False),
    (RENDER, "--lat", -90.0, 90.0, False, False),
    (RENDER, "--lon", *FINITE, False, False),
    (RENDER, "--elevation-m", -500.0, 1e12, False, False),
    (RENDER, "--heading", *FINITE, False, False),
    (RENDER, "--pitch", -90.0, 90.0, False, False),
    (RENDER, "--terrain-spacing", 0.0, 1e5, True, False),
    (RENDER, "--terrain-height", 0.0, 1e5, True, False),
    (RENDER, "--magnitude-limit", -30.0, 30.0, False, False),
    (RENDER, "--exposure", -40.0, 40.0, False, False),
    (RENDER, "--exposure-compensation", -40.0, 40.0, False, False),
    (RENDER, "--size", 1, 2**20, False, True),
    (RENDER, "--orders", 1, 1000, False, True),
    (RENDER, "--samples", 1, 10**9, False, True),
    (RENDER, "--twinkle", 0, 2**64 - 1, False, True),
    (TIMELAPSE, "--fps", 0.0, math.inf, True, False),
    (TIMELAPSE, "--adaptation-minutes", 0.0, 1e7, False, False),
    (TIMELAPSE, "--frames", 1, 100_000, False, True),
    (RADIANCE, "--view-zenith", 0.0, 180.0, False, False),
    (RADIANCE, "--view-azimuth", *FINITE, False, False),
    (RADIANCE, "--wavelengths", 280.5, 1690.0, False, False),
    (SWEEP, "--view-zenith", 0.0, 180.0, False, False),
    (SWEEP, "--azimuth", *FINITE, False, False),
    (SWEEP, "--workers", 1, 1024, False, True),
    (SWEEP, "--lat", -90.0, 90.0, False, False),
    (SWEEP, "--lon", *FINITE, False, False),
    (SWEEP, "--frames", 1, 100_000, False, True),
    (["view"], "--port", 0, 65535, False, True),
    (["validate"], "--seed", 0, 2**32 - 1, False, True),
]
NON_FINITE = ["nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e309", "-1e999"]
LISTS = ("--view-zenith", "--view-azimuth", "--azimuth", "--wavelengths")  # comma-separated


def _allowed(text: str, low: float, high: float, low_open: bool, whole: bool) -> bool:
    """Whether `text` is a number the option must accept (the reference, not the code)."""
    try:
        value = int(text) if whole else float(text)
    except ValueError:
        return False
    if not whole and not math.isfinite(value):
        return False
    return (value > low if low_open else value >= low) and value <= high


def _error_line(stderr: str) -> str:
    """The one error line after argparse's usage block; no traceback."""
    assert "Traceback" not in stderr
    lines = [line for line in stderr.rstrip("\n").split("\n")
             if line and not line.startswith(("usage:", " "))]
    assert len(lines) == 1, stderr
    assert lines[0].startswith("skyscatter"), stderr
    return lines[0]


def _exit_code(call) -> int:
    try:
        return call()
    except SystemExit as exit_:
        return exit_.code


@pytest.fixture
def quiet_folder(tmp_path, monkeypatch):
    """Run in an empty folder with a cache there that must stay absent."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path


hostile_text = st.one_of(
    st.sampled_from(NON_FINITE),
    st.text(max_size=12),  # odd unicode, empty, letters, digits of other scripts
    st.floats(allow_nan=False, allow_infinity=False).map(repr),  # numbers, often far out
    st.integers(min_value=-(2**70), max_value=2**70).map(str),
    st.sampled_from(["", " ", "1,2", "0x10", "1_0e", "12abc", "\u0663\u0660\u0660", "\u221e",
                     "１８１", "9" * 400]),
)


@settings(max_examples=80, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=st.sampled_from(NUMBERS), text=hostile_text)
def test_a_numeric_option_refuses_every_value_outside_its_range(capsys, quiet_folder, case,
                                                                 text):
    command, option, low, high, low_open, whole = case
    if option in LISTS:
        parts = [part for part in text.split(",") if part.strip()]
        assume(not parts or not all(_allowed(part, low, high, low_open, whole)
                                    for part in parts))
    else:
        assume(not _allowed(text, low, high, low_open, whole))
    assume(not (option == "--exposure" and text == "auto"))
    code = _exit_code(lambda: build_parser().parse_args([*command, f"{option}={text}"]))
    assert code == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    line = _error_line(captured.err)
    assert f"argument {option}" in line
    assert list(quiet_folder.iterdir()) == []


@pytest.mark.parametrize(("argv", "expected"), [
    (["render", "earth", "--view-zenith", "nan"], "unrecognized arguments"),
    (["radiance", "earth", "--sun-zenith", "30", "--view-azimuth", "nan"],
     "--view-azimuth: 'nan' is not allowed: a finite number"),
    (["render", "earth", "--aspect", "0"], "--aspect: '0' is not allowed: a finite number > 0"),
    (["render", "earth", "--aspect", "nan"], "--aspect: 'nan' is not allowed"),
    (["render", "earth", "--twinkle", "-1"], "--twinkle: -1 is not allowed"),
    (TIMELAPSE + ["--step", "infh"], "--step: 'infh' is not allowed"),
    (["render", "earth", "--wavelengths", "1e-300"], "--wavelengths: '1e-300' is not a whole"),
    (["render", "earth", "--wavelengths", "1e-300,"], "--wavelengths: '1e-300' is not allowed"),
    (["render", "earth", "--sun-azimuth", "inf"], "--sun-azimuth: 'inf' is not allowed"),
    (["render", "earth", "--fov", "0"], "--fov: '0' is not allowed"),
    (["render", "earth", "--fov", "200"], "--fov: '200' is not allowed"),
    (["render", "earth", "--lat", "91"], "--lat: '91' is not allowed"),
    (["render", "earth", "--orders", "100000"],
     "--orders: 100000 is not allowed: a whole number from 1 to 1000"),
    (["render", "earth", "--camera", "orbit", "--look-at", "100,0"], "--look-at: '100'"),
    (["render", "earth", "--aspect", "1\n2"], r"--aspect: '1\n2' is not a number"),
])
def test_hostile_option_gets_one_line_naming_it(capsys, quiet_folder, argv, expected):
    code = _exit_code(lambda: main(argv))
    assert code == 2
    assert expected in _error_line(capsys.readouterr().err)
    assert list(quiet_folder.iterdir()) == []


def test_orders_cap_is_the_configs_cap():
    # One constant: the command line refuses exactly what a config file refuses.
    from skyscatter.atmosphere.model import MAX_SCATTERING_ORDERS
    parser = build_parser()
    ok = parser.parse_args(["precompute", "earth", "--orders", str(MAX_SCATTERING_ORDERS)])
    assert ok.orders == MAX_SCATTERING_ORDERS
    with pytest.raises(SystemExit):
        parser.parse_args(["precompute", "earth", "--orders", str(MAX_SCATTERING_ORDERS + 1)])


# --- refused before work by the library, still one line ---------------------------------------

@pytest.mark.parametrize(("argv", "expected"), [
    (["render", "earth", "--size", "100000"],
     "a 100000 x 100000-pixel image at 16 wavelengths would need about 9,537 GiB of memory"),
    (["render", "earth", "--camera", "perspective", "--size", "30000", "--aspect", "30"],
     "a 900000 x 30000-pixel image"),
    (["radiance", "earth", "--sun-zenith", "30", "--solver", "montecarlo", "--samples",
      "1000000000"], "would take about 10.4 hours"),
    (TIMELAPSE + ["--step", "1e-300s"], "more than 100000 frames; give a longer --step"),
    (TIMELAPSE + ["--solver", "single", "--samples", "100000"], "would take about"),
    (["render", "earth", "--time", "0001-01-01T00:00+05:00", "--lat", "0", "--lon", "0"],
     "is outside the years 1-9999 once converted to UTC"),
    (["render", "earth", "--time", "9999-12-31T23:00-05:00", "--lat", "0", "--lon", "0"],
     "is outside the years 1-9999 once converted to UTC"),
    (["radiance", "earth", "--time", "9999-12-31T23:00-05:00", "--lat", "0", "--lon", "0"],
     "is outside the years 1-9999 once converted to UTC"),
    (["render", "earth", "--time", "MSD 1e9", "--lat", "0", "--lon", "0"],
     "Mars Sol Date = 1000000000.0 is not allowed"),
    (["render", "earth", "--time", "MSD nan", "--lat", "0", "--lon", "0"],
     "Mars Sol Date = nan is not allowed"),
    (SWEEP + ["--start", "0001-01-01T00:00+05:00", "--end", "0001-01-02T00:00+05:00", "--lat",
              "0", "--lon", "0"], "is outside the years 1-9999 once converted to UTC"),
    (SWEEP + ["--start", "2024-01-01T00:00Z", "--end", "2024-01-02T00:00Z", "--step",
              "1e-300s", "--lat", "0", "--lon", "0"],
     "more than 100000 frames; give a longer --step"),
])
def test_costly_or_impossible_requests_are_refused_with_the_estimate(capsys, quiet_folder, argv,
                                                                     expected):
    code = _exit_code(lambda: main(argv))
    assert code == 2
    line = _error_line(capsys.readouterr().err)
    assert expected in line
    if "GiB" in line or "hours" in line:  # an estimate, and the way past it
        assert "--allow-large" in line
    assert list(quiet_folder.iterdir()) == []


@pytest.mark.parametrize(("argv", "low", "high"), [
    (["radiance", "earth", "--sun-zenith", "30", "--wavelengths", "200"], "280.5", "1690"),
    (["radiance", "earth", "--sun-zenith", "30", "--wavelengths", "1e9,"], "280.5", "1690"),
    (["render", "earth", "--wavelengths", "1e9,"], "360", "830"),
    (["render", "earth", "--wavelengths", "300,550"], "360", "830"),
    (["precompute", "earth", "--wavelengths", "900,"], "360", "830"),
    (["precompute", "earth", "--monochromatic", "--wavelengths", "250"], "280.5", "1690"),
])
def test_wavelengths_outside_the_data_are_refused_with_its_range(capsys, quiet_folder, argv, low,
                                                                 high):
    # radiance printed 0 at 200 nm with exit code 0; render computed tables for 1e9 nm
    code = _exit_code(lambda: main(argv))
    assert code == 2
    line = _error_line(capsys.readouterr().err)
    assert f">= {low} and <= {high} nm" in line
    assert list(quiet_folder.iterdir()) == []


def test_data_ranges_are_those_of_the_shipped_tables():
    # The bounds are read off the data: CIE tables 360-830 nm, solar spectrum from 280 nm
    # (half a 1 nm cell inside it).
    from skyscatter.spectrum.colour import _cie1931_table
    from skyscatter.spectrum.grid import COLOUR_RANGE_NM, MONOCHROMATIC_RANGE_NM
    from skyscatter.spectrum.solar import solar_spectrum_table
    cie = _cie1931_table()[0]
    assert (cie[0], cie[-1]) == COLOUR_RANGE_NM
    solar = solar_spectrum_table()[0]
    assert MONOCHROMATIC_RANGE_NM[0] == solar[0] + 0.5
    assert MONOCHROMATIC_RANGE_NM[1] < solar[-1]


# --- --format json is strict JSON -------------------------------------------------------------

def _no_constants(name: str):
    raise ValueError(f"not JSON: {name}")


@pytest.mark.parametrize("extra", [
    ["--solver", "single", "--samples", "8", "--sun-zenith", "0,90,180", "--view-zenith",
     "0,90,180", "--elevation-m", "1e9"],
    ["--solver", "single", "--samples", "8", "--sun-zenith", "180", "--wavelengths",
     "280.5,1690"],
    ["--solver", "montecarlo", "--samples", "2", "--sun-zenith", "90", "--view-zenith", "0,180",
     "--elevation-m", "100000"],
])
def test_radiance_json_parses_as_strict_json(capsys, extra):
    # jq and JSON.parse refuse bare NaN/Infinity; so does json.loads with parse_constant.
    code = _exit_code(lambda: main(["radiance", "earth", *extra, "--format", "json"]))
    captured = capsys.readouterr()
    assert code == 0, captured.err
    rows = json.loads(captured.out, parse_constant=_no_constants)
    assert rows and all(math.isfinite(value) for row in rows for value in row.values())
    if "montecarlo" in extra:
        assert all("standard_error" in row for row in rows)
