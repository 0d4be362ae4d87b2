"""`skyscatter fit`: the output of `skyscatter radiance` as a measurement file, the report,
mixed rows, and every bad input as one line and exit code 2."""

import json
import math

import numpy as np
import pytest

from cli_runner import run_cli
from skyscatter import api
from skyscatter.errors import InputError
from skyscatter.fit.measurements import read_measurements

KEY = "constituent[2].optics.optical_depth"
FREE = f"{KEY}=0.01:1:0.3"


@pytest.fixture(scope="module")
def radiance_csv(tmp_path_factory):
    """Hillaire's own radiances at tau(500) = 0.1 (the preset's), written by the command."""
    path = tmp_path_factory.mktemp("fit") / "sky.csv"
    code = api_cli(["radiance", "earth", "--sun-zenith", "60", "--view-zenith", "60",
                    "--view-azimuth", "10,30,90,180", "--wavelengths", "440,870",
                    "--solver", "hillaire", "-o", str(path)])
    assert code == 0
    return path


def api_cli(argv):
    from skyscatter.cli import main
    return main(argv)


def test_radiance_output_fitted_with_its_own_solver_gives_back_the_config(capsys, radiance_csv,
                                                                          tmp_path):
    # noise-free data from the same model: the estimate is the preset's 0.1 within the
    # fit's convergence (xtol 1e-8 of the bounds' width -> 1e-6 with room), chi-square ~ 0
    report_path = tmp_path / "report.json"
    code, out, err = run_cli(capsys, ["fit", "earth", str(radiance_csv), "--free", FREE,
                                      "--relative-uncertainty", "0.03", "-o",
                                      str(report_path)])
    assert code == 0, err
    assert out.startswith(f"{KEY} = 0.1 +- ")
    report = json.loads(report_path.read_text())
    (parameter,) = report["parameters"]
    assert parameter["estimate"] == pytest.approx(0.1, abs=1e-6)
    assert parameter["constrained"] and report["chi_square"] < 1e-8
    assert report["degrees_of_freedom"] == 7
    assert len(report["rows"]) == 8 and report["rows"][0]["quantity"] == "radiance"
    assert report["correlation"] == [[1.0]]
    assert "not scaled" in report["covariance_scaling"]


def test_mixed_rows_and_a_parameter_the_data_cannot_see(tmp_path):
    # radiance, transmittance and chromaticity rows in one CSV (empty cells: absent). The
    # forward model is "schuler" (single scattering, 0.01 s per atmosphere): a sky without
    # light from the ground, so the ground albedo changes nothing - a zero column of J, named
    # as not constrained - while the optical depth is constrained
    path = tmp_path / "mixed.csv"
    path.write_text(
        "sun_zenith_deg,view_zenith_deg,relative_azimuth_deg,wavelength_nm,radiance,"
        "direct_transmittance,chromaticity_x,chromaticity_y,uncertainty\n"
        "60,60,90,440,0.19,,,,0.006\n"
        "60,,,440,,0.49,,,0.005\n"
        "60,,,870,,0.82,,,0.005\n"
        "60,60,90,,,,0.24,0.25,0.01\n")
    measurements = read_measurements(path)
    assert list(measurements.kind) == ["radiance", "transmittance", "transmittance",
                                       "chromaticity_x", "chromaticity_y"]
    result = api.fit("earth", path, [FREE, "planet.ground_albedo=0:0.05:0.025"],
                     solver="schuler")
    named = {note["key"] for note in result.report["not_constrained"]}
    assert "planet.ground_albedo" in named and KEY not in named
    assert np.isfinite(result.uncertainties[KEY])


@pytest.mark.parametrize(("text", "args", "message"), [
    ("", [], "no measurement rows"),
    ("sun_zenith_deg,wavelength_nm,radiance\n", [], "no measurement rows"),
    ("a,b\n1,2\n", [], "row 1 gives none of radiance"),
    ("sun_zenith_deg,view_zenith_deg,wavelength_nm,radiance,uncertainty\n60,60,440,0.2,0.01\n",
     [], "row 1 has no relative_azimuth_deg"),
    ("sun_zenith_deg,view_zenith_deg,relative_azimuth_deg,wavelength_nm,radiance,uncertainty\n"
     "60,60,0,440,nan,0.01\n", [], "radiance = 'nan' is not finite"),
    ("sun_zenith_deg,view_zenith_deg,relative_azimuth_deg,wavelength_nm,radiance\n"
     "60,60,0,440,0.2\n", [], "row 1 has no uncertainty"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,1.5,0.01\n", [],
     "must be in (0, 1]"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", "constituent[9].optics.optical_depth=0:1"], "has 3 entries"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", f"{KEY}=1:0"], "LOW < HIGH"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", f"{KEY}=0:1:2"], "START 2 lies outside the bounds"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", "name=0:1"], "not a number; only numbers can be fitted"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", f"{KEY}=0:1", "--solver", "cie"], "not a fit's forward model"),
    ("sun_zenith_deg,wavelength_nm,direct_transmittance,uncertainty\n60,440,0.5,0.01\n",
     ["--free", f"{KEY}=0:1", "--model", "missing.nc"], "no such file"),
])
def test_bad_input_is_one_line_and_exit_code_2(capsys, tmp_path, text, args, message):
    path = tmp_path / "rows.csv"
    path.write_text(text)
    argv = ["fit", "earth", str(path), *(args or ["--free", f"{KEY}=0:1"])]
    code, out, err = run_cli(capsys, argv)
    assert code == 2
    assert err.count("\n") == 1 and message in err, err


def test_garbled_json_and_a_missing_file(capsys, tmp_path):
    path = tmp_path / "rows.json"
    path.write_text("{not json")
    code, _, err = run_cli(capsys, ["fit", "earth", str(path), "--free", f"{KEY}=0:1"])
    assert code == 2 and "cannot read it" in err and err.count("\n") == 1
    code, _, err = run_cli(capsys, ["fit", "earth", str(tmp_path / "none.csv"), "--free",
                                    f"{KEY}=0:1"])
    assert code == 2 and "no such file" in err


def test_the_measurements_may_come_after_the_options(capsys, tmp_path):
    # argparse fills the optional MEASUREMENTS, empty, with the preset before it; the file
    # after the options is taken as the measurements (it is read: the garbled JSON is refused
    # as such), and a second file is still an unrecognized argument
    path = tmp_path / "rows.json"
    path.write_text("{not json")
    code, _, err = run_cli(capsys, ["fit", "earth", "--free", f"{KEY}=0:1", str(path)])
    assert code == 2 and "cannot read it" in err and err.count("\n") == 1
    code, _, err = run_cli(capsys, ["fit", "earth", "--free", f"{KEY}=0:1", str(path), "b.csv"])
    assert code == 2 and "unrecognized arguments" in err


def test_a_sweep_that_does_not_hold_the_free_key_is_refused(tmp_path):
    xarray = pytest.importorskip("xarray")
    dims = ("sun_zenith", "view_zenith", "azimuth", "wavelength")
    sweep = xarray.Dataset({"radiance": (dims, np.ones((1, 1, 2, 1)))},
                           coords={"sun_zenith": [60.0], "view_zenith": [60.0],
                                   "azimuth": [0.0, 180.0], "wavelength": [440.0]})
    path = tmp_path / "sweep.nc"
    sweep.to_netcdf(path)
    rows = [{"sun_zenith_deg": 60, "view_zenith_deg": 60, "relative_azimuth_deg": 90,
             "wavelength_nm": 440, "radiance": 1.0, "uncertainty": 0.1}]
    with pytest.raises(InputError, match="does not sweep constituent"):
        api.fit("earth", rows, [f"{KEY}=0:1"], model=path)


def test_a_sweep_over_times_is_refused_with_what_to_sweep_instead(tmp_path):
    path = tmp_path / "times.nc"
    api.sweep("earth", {KEY: [0.05, 0.2]}, view_zeniths_deg=[60.0],
              relative_azimuths_deg=[0.0, 90.0], wavelengths_nm=[440.0], solver="single",
              times=["2026-06-21T10:00+02:00", "2026-06-21T12:00+02:00"], latitude_deg=52.5,
              longitude_deg=13.4, output_path=path, workers=1)
    rows = [{"sun_zenith_deg": 40, "view_zenith_deg": 60, "relative_azimuth_deg": 90,
             "wavelength_nm": 440, "radiance": 1.0, "uncertainty": 0.1}]
    with pytest.raises(InputError, match="sweep over times.*--sun-zenith"):
        api.fit("earth", rows, [f"{KEY}=0:1"], model=path)


ROWS = [{"sun_zenith_deg": 60, "wavelength_nm": 440, "direct_transmittance": 0.5,
         "uncertainty": 0.01}]


@pytest.mark.parametrize(("free", "options", "message"), [
    ([f"{KEY}=nan:1"], {}, "must be finite"),
    ([f"{KEY}=0:inf"], {}, "must be finite"),
    ([f"{KEY}=0:1:nan"], {}, "lies outside the bounds"),
    ([f"{KEY}"], {}, "give KEY=LOW:HIGH"),
    ([], {}, "no free parameter"),
    ([f"{KEY}=0:1", f"{KEY}=0:2"], {}, "given twice"),
    ([f"{KEY}=0:1"], {"model_error": math.nan}, "model_error"),
    ([f"{KEY}=0:1"], {"model_error_correlation": 1.5}, "model_error_correlation"),
    ([f"{KEY}=0:1"], {"relative_uncertainty": math.nan}, "relative_uncertainty"),
    ([f"{KEY}=0:1"], {"samples": 0}, "samples"),
    ([f"{KEY}=0:1"], {"refine": "hillaire"}, "refine"),
    ([f"{KEY}=0:1"], {"checks": ["schuler"]}, "check"),
    ([f"{KEY}=0:1"], {"altitude_m": math.inf}, "altitude_m"),
])
def test_the_api_refuses_hostile_arguments_before_any_work(free, options, message):
    # every refusal comes before a forward model runs (each would take a second or more)
    with pytest.raises(InputError, match=message):
        api.fit("earth", ROWS, free, **options)
