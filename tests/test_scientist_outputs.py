"""Scientist outputs: the rows' metadata (envelope, CSV comments, sidecar), numbers without
float noise, irradiance on tilted planes, and xarray Datasets / NetCDF files.

References: the documented row formats (docs/cli.md, read back with the csv and json modules
and pandas); closed-form integrals of test sky radiances over a tilted plane's view of the
sky; pvlib's isotropic and Perez transposition models (pvlib 0.16.1); scipy's NetCDF reader.
The single-scattering solver keeps the tests fast (no tables to precompute).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import re
import sys
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy.io import netcdf_file

from cli_runner import run_cli
from skyscatter import api
from skyscatter.atmosphere.config import PRESETS_DIR
from skyscatter.errors import InputError
from skyscatter.render.scene import sun_direction
from skyscatter.transport.plane_irradiance import plane_irradiance, plane_normal
from skyscatter.validate.disort import disort_fluxes, plane_parallel_layers

xarray = pytest.importorskip("xarray")

EARTH = api.load_atmosphere("earth")
RADIANCE_KEYS = ["sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg", "wavelength_nm",
                 "radiance", "toa_irradiance"]
RADIANCE = ["radiance", "earth", "--sun-zenith", "30", "--view-zenith", "0,60",
            "--view-azimuth", "0,180", "--wavelengths", "440,550", "--solver", "single",
            "--samples", "64"]
IRRADIANCE = ["irradiance", "earth", "--sun-zenith", "30", "--wavelengths", "450,550",
              "--solver", "single", "--samples", "64"]


def _radiance_rows() -> list[dict[str, float]]:
    options = api.solver_options(EARTH, n_samples=64)
    return api.sky_radiance_rows(EARTH, [30.0], [0.0, 60.0], [0.0, 180.0], [440.0, 550.0],
                                 solver="single", options=options)


def _documented_csv(rows: list[dict[str, float]]) -> str:
    """docs/cli.md's CSV as the command wrote it before metadata existed: a header of the keys,
    each number with 10 significant digits."""
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows({key: f"{value:.10g}" for key, value in row.items()} for row in rows)
    return text.getvalue()


# --- the default output is the documented one -------------------------------------------------

def test_default_csv_is_byte_for_byte_the_documented_format(capsys):
    code, out, err = run_cli(capsys, RADIANCE)
    assert code == 0 and err == ""
    assert out == _documented_csv(_radiance_rows())


def test_default_json_keeps_its_keys_and_types_and_prints_no_float_noise(capsys):
    code, out, _ = run_cli(capsys, [*RADIANCE, "--format", "json"])
    assert code == 0
    rows, exact = json.loads(out), _radiance_rows()
    assert isinstance(rows, list) and len(rows) == len(exact) == 8
    for row, reference in zip(rows, exact, strict=True):
        assert list(row) == RADIANCE_KEYS
        assert all(isinstance(value, float) for value in row.values())
        for key in RADIANCE_KEYS:  # the same number, rounded to 10 significant digits
            assert row[key] == float(f"{reference[key]:.10g}")
            # half a unit of the 10th digit (5e-10 relative), plus the float's own rounding
            assert row[key] == pytest.approx(reference[key], rel=6e-10)
    # float64 arithmetic leaves noise in the 16th digit (the 1 nm cell's mean of the ASTM
    # spectrum came out 1.7974999999999852 at 440 nm); no number has more than 10 digits
    numbers = re.findall(r"-?\d+\.\d+(?:e[-+]?\d+)?", out)
    assert numbers and all(len(re.sub(r"e.*|[-.]", "", n).strip("0")) <= 10 for n in numbers)
    assert {row["toa_irradiance"] for row in rows if row["wavelength_nm"] == 440.0} == {1.7975}
    assert "1.797499999" not in out


# --- metadata on request ----------------------------------------------------------------------

def _check_metadata(metadata: dict, columns: list[str], solver: dict) -> None:
    preset = PRESETS_DIR / "earth.toml"
    from importlib.metadata import version
    assert metadata["software"] == "skyscatter" and metadata["version"] == version("skyscatter")
    assert metadata["atmosphere"]["preset"] == "earth"
    assert metadata["atmosphere"]["config_sha256"] == hashlib.sha256(
        preset.read_bytes()).hexdigest()
    assert re.fullmatch(r"[0-9a-f]{64}", metadata["atmosphere"]["optical_profile_sha256"])
    assert metadata["solver"] == solver
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", metadata["computed_utc"])
    assert metadata["solar_spectrum"]["type"] == "astm-g173"
    assert "G173" in metadata["solar_spectrum"]["source"]
    assert list(metadata["columns"]) == columns
    units = {name: column["units"] for name, column in metadata["columns"].items()}
    assert units["radiance" if "radiance" in units else "direct_normal"] in (
        "W m-2 sr-1 nm-1", "W m-2 nm-1")
    assert units["wavelength_nm"] == "nm" and units["sun_zenith_deg"] == "degree"


def test_envelope_wraps_the_same_rows_with_their_metadata(capsys, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    code, out, _ = run_cli(capsys, [*RADIANCE, "--format", "json"])
    plain = json.loads(out)
    code, out, err = run_cli(capsys, [*RADIANCE, "--metadata", "envelope"])  # JSON implied
    assert code == 0 and err == ""
    document = json.loads(out)
    assert list(document) == ["metadata", "rows"] and document["rows"] == plain
    metadata = document["metadata"]
    _check_metadata(metadata, RADIANCE_KEYS, {"name": "single", "samples": 64})
    assert metadata["computed_utc"] == "2023-11-14T22:13:20Z"  # SOURCE_DATE_EPOCH
    assert metadata["wavelengths_nm"] == [440.0, 550.0]
    assert metadata["columns"]["radiance"]["units"] == "W m-2 sr-1 nm-1"
    assert metadata["geometry"] == {"altitude_m": 0.0, "sun_zeniths_deg": [30.0],
                                    "view_zeniths_deg": [0.0, 60.0],
                                    "relative_azimuths_deg": [0.0, 180.0]}


def test_csv_comments_come_before_the_header_and_pandas_skips_them(capsys):
    code, out, err = run_cli(capsys, [*IRRADIANCE, "--metadata", "comments", "--orders", "3"])
    assert code == 0 and err == ""
    comments = [line for line in out.splitlines() if line.startswith("#")]
    body = out[sum(len(line) + 1 for line in comments):]
    assert out.startswith("# ") and not body.startswith("#")
    assert body == run_cli(capsys, IRRADIANCE)[1]  # the plain CSV follows the comments
    table = pd.read_csv(io.StringIO(out), comment="#")
    assert list(table.columns) == ["sun_zenith_deg", "wavelength_nm", "direct_normal",
                                   "diffuse_horizontal", "global_horizontal", "toa_irradiance"]
    assert len(table) == 2
    entries = dict(line[2:].split(": ", 1) for line in comments)
    assert entries["solver.name"] == "single" and entries["solver.samples"] == "64"
    assert entries["columns.diffuse_horizontal.units"] == "W m-2 nm-1"
    assert json.loads(entries["wavelengths_nm"]) == [450.0, 550.0]


def test_sidecar_writes_the_rows_and_their_metadata_beside_them(capsys, tmp_path):
    out_csv = tmp_path / "sky.csv"
    code, out, err = run_cli(capsys, [*RADIANCE, "-o", str(out_csv), "--metadata", "sidecar"])
    assert code == 0 and out == "" and err == ""
    assert out_csv.read_text(encoding="utf-8") == _documented_csv(_radiance_rows())
    metadata = json.loads((tmp_path / "sky.csv.meta.json").read_text(encoding="utf-8"))
    _check_metadata(metadata, RADIANCE_KEYS, {"name": "single", "samples": 64})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sky.csv", "sky.csv.meta.json"]
    out_json = tmp_path / "sky.json"  # the suffix picks the format
    assert run_cli(capsys, [*RADIANCE, "-o", str(out_json)])[0] == 0
    assert json.loads(out_json.read_text(encoding="utf-8")) == json.loads(
        run_cli(capsys, [*RADIANCE, "--format", "json"])[1])


@pytest.mark.parametrize(("extra", "message"), [
    (["--metadata", "sidecar"], "give -o"),
    (["--metadata", "comments", "--format", "json"], "--metadata comments is for CSV"),
    (["--metadata", "envelope", "--format", "csv"], "--metadata envelope is for JSON"),
    (["-o", "x.json", "--format", "csv"], "name the file .csv or leave --format out"),
    (["-o", "x.nc", "--metadata", "sidecar"], "carries the metadata as its attributes"),
    (["--time", "2024-06-21T12:00Z", "--lat", "0", "--lon", "0", "--sun-azimuth", "10",
      "--tilt", "10"],
     "--sun-azimuth and --time both place the sun"),
    (["--tilt", "200"], "200"),
    (["--plane-azimuth", "90"], "--plane-azimuth is for the plane of --tilt"),
])
def test_contradicting_output_options_get_one_line_before_any_work(capsys, extra, message):
    argv = [*IRRADIANCE, *extra]
    if "--time" in extra:
        argv = [a for a in argv if a not in ("--sun-zenith", "30")]
    code, out, err = run_cli(capsys, argv)
    assert code == 2 and out == "" and "Traceback" not in err
    assert message in err.strip().splitlines()[-1]


# --- irradiance on tilted planes --------------------------------------------------------------

class _TestSky:
    """A solver stand-in with the sky radiance a + b cos(zenith) and given horizontal
    irradiances: the closed forms below hold for it."""

    def __init__(self, a: float, b: float, albedo: float = 0.3):
        self.a, self.b = a, b
        self.profile = SimpleNamespace(bottom_radius_m=6.371e6, ground_albedo=np.array([albedo]))
        # the sky's own diffuse horizontal: int (a + b mu) mu dw = pi a + 2 pi b / 3
        self.diffuse = np.array([math.pi * a + 2.0 * math.pi * b / 3.0])
        self.direct = np.array([0.9])

    def ground_irradiance(self, position, sun):
        return self.direct * max(float(sun[2]), 0.0), self.diffuse

    def sky_radiance(self, position, directions, sun):
        return (self.a + self.b * directions[..., 2])[..., None]


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 90.0, 135.0, 180.0])
def test_an_isotropic_sky_gives_the_view_factor_of_the_plane(tilt):
    # Closed form (Liu & Jordan 1963): E_sky = E_dh (1 + cos beta) / 2; ground (Duffie &
    # Beckman eq. 2.15.1): rho E_gh (1 - cos beta) / 2. Tolerance 6e-4: the 32 x 64 quadrature
    # of the kink where the plane's horizon cuts the sky (measured: 0 at 0 and 180 deg, at
    # most 2e-5 to 45 deg, 1.3e-4 at 135 deg, 4.1e-4 at 90 deg, over plane azimuths 0-180).
    sky = _TestSky(a=0.05, b=0.0)
    sun = sun_direction(40.0, 180.0)
    result = plane_irradiance(sky, sun, plane_normal(tilt, 100.0))
    beta = math.radians(tilt)
    assert result.sky_diffuse[0] == pytest.approx(sky.diffuse[0] * (1 + math.cos(beta)) / 2,
                                                  rel=6e-4, abs=1e-12)
    global_horizontal = sky.direct[0] * math.cos(math.radians(40.0)) + sky.diffuse[0]
    assert result.ground_reflected[0] == pytest.approx(
        0.3 * global_horizontal * (1 - math.cos(beta)) / 2, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize(("tilt", "azimuth"), [(35.0, 200.0), (90.0, 90.0), (60.0, 0.0)])
def test_an_isotropic_sky_gives_pvlibs_isotropic_plane_of_array(tilt, azimuth):
    # pvlib 0.16.1 get_total_irradiance(model="isotropic") fed the test sky's own DNI, DHI
    # and GHI and its ground albedo: beam, sky and ground on the plane by pvlib's code.
    # Tolerance 2e-4 of the total: the sky part's quadrature (at most 4.1e-4 of it, above).
    pvlib = pytest.importorskip("pvlib")
    sky = _TestSky(a=0.05, b=0.0)
    result = plane_irradiance(sky, sun_direction(40.0, 180.0), plane_normal(tilt, azimuth))
    mu = math.cos(math.radians(40.0))
    reference = pvlib.irradiance.get_total_irradiance(
        tilt, azimuth, 40.0, 180.0, sky.direct[0], sky.direct[0] * mu + sky.diffuse[0],
        sky.diffuse[0], albedo=0.3, model="isotropic")
    assert result.beam[0] == pytest.approx(float(reference["poa_direct"]), rel=1e-12)
    assert result.ground_reflected[0] == pytest.approx(
        float(reference["poa_ground_diffuse"]), rel=1e-12)
    assert result.total[0] == pytest.approx(float(reference["poa_global"]), rel=2e-4)


def test_a_zenith_bright_sky_on_a_vertical_plane_matches_its_closed_form():
    # L = a + b mu on a vertical plane: int_0^1 int_{-pi/2}^{pi/2} (a + b mu) sqrt(1 - mu^2)
    # cos(phi) dphi dmu = a pi / 2 + 2 b / 3, over the horizontal's pi a + 2 pi b / 3.
    # Tolerance 6e-4: the quadrature's kink error (measured 4.1e-4 facing north, 1.7e-4
    # facing 100 deg, at 32 x 64).
    sky = _TestSky(a=0.02, b=0.06)
    result = plane_irradiance(sky, sun_direction(30.0, 0.0), plane_normal(90.0, 0.0))
    expected = sky.diffuse[0] * (0.02 * math.pi / 2 + 2 * 0.06 / 3) / (
        math.pi * 0.02 + 2 * math.pi * 0.06 / 3)
    assert result.sky_diffuse[0] == pytest.approx(expected, rel=6e-4)


@pytest.fixture(scope="module")
def plane_rows():
    """Rows of sun-facing, away-facing and horizontal planes, sun at 30 deg from the south."""
    options = api.solver_options(EARTH, n_samples=64)
    return {(tilt, azimuth): api.irradiance_rows(
        EARTH, [30.0], [550.0], solver="single", options=options, tilt_deg=tilt,
        plane_azimuth_deg=azimuth, sun_azimuth_deg=180.0)[0]
        for tilt, azimuth in ((0.0, 180.0), (30.0, 180.0), (60.0, 180.0), (90.0, 180.0),
                              (60.0, 0.0), (90.0, 0.0), (180.0, 0.0))}


def test_a_horizontal_plane_gets_global_horizontal_and_a_sun_facing_one_the_beam(plane_rows):
    flat = plane_rows[(0.0, 180.0)]
    assert flat["plane_global"] == pytest.approx(flat["global_horizontal"], rel=1e-12)
    assert flat["plane_ground_reflected"] == 0.0
    # closed forms of the beam: DNI cos(incidence); a vertical plane facing the sun at zenith
    # 30 deg is lit at incidence 60 deg, one tilted 30 deg faces it squarely
    assert plane_rows[(90.0, 180.0)]["plane_direct"] == pytest.approx(
        flat["direct_normal"] * math.sin(math.radians(30.0)), rel=1e-12)
    assert plane_rows[(30.0, 180.0)]["plane_direct"] == pytest.approx(flat["direct_normal"],
                                                                      rel=1e-12)
    down = plane_rows[(180.0, 0.0)]  # facing the ground: its light only
    assert down["plane_direct"] == 0.0 and down["plane_sky_diffuse"] == pytest.approx(0.0,
                                                                                     abs=1e-15)
    assert down["plane_ground_reflected"] == pytest.approx(
        float(EARTH.planet.ground_albedo.at(np.array([550.0]))[0]) * flat["global_horizontal"],
        rel=1e-12)


def test_the_direct_transmittance_is_beer_lambert_through_disorts_layers(plane_rows):
    # exp(-tau / mu0) of the same profile's plane-parallel layers (DISORT's direct beam);
    # tolerance 0.05 %: the sphere's slant path at 30 deg (tests/test_irradiance_command.py).
    profile = api.load_solver(EARTH, [550.0], solver="single", monochromatic=True).profile
    _, _, direct = disort_fluxes(plane_parallel_layers(profile), profile.toa_irradiance,
                                 math.radians(30.0), profile.ground_albedo)
    expected = direct[0] / math.cos(math.radians(30.0)) / profile.toa_irradiance[0]
    assert plane_rows[(0.0, 180.0)]["direct_transmittance"] == pytest.approx(expected, rel=5e-4)


def test_the_computed_sky_on_planes_is_not_isotropic_and_leans_towards_perez(plane_rows):
    # pvlib 0.16.1 get_total_irradiance fed our own DNI, DHI, GHI at 550 nm (and the 1 nm
    # cell's top-of-atmosphere irradiance as dni_extra, Kasten-Young air mass for Perez).
    # The sky's aureole makes planes facing the sun brighter than the isotropic model says
    # and planes facing away darker, as Perez's circumsolar term does; measured (single
    # scattering, 64 samples): facing the sun at 30/60/90 deg tilt ours 0.188/0.177/0.128,
    # isotropic 0.150/0.121/0.081, Perez 0.181/0.163/0.111 W m^-2 nm^-1.
    pvlib = pytest.importorskip("pvlib")
    flat = plane_rows[(0.0, 180.0)]
    airmass = pvlib.atmosphere.get_relative_airmass(30.0)
    for (tilt, azimuth), row in plane_rows.items():
        if tilt in (0.0, 180.0):
            continue
        models = {model: float(pvlib.irradiance.get_total_irradiance(
            tilt, azimuth, 30.0, 180.0, flat["direct_normal"], flat["global_horizontal"],
            flat["diffuse_horizontal"], dni_extra=flat["toa_irradiance"], airmass=airmass,
            albedo=0.0, model=model)["poa_sky_diffuse"]) for model in ("isotropic", "perez")}
        ours = row["plane_sky_diffuse"]
        if azimuth == 180.0:  # facing the sun
            assert ours > 1.15 * models["isotropic"]
            assert abs(ours - models["perez"]) < abs(ours - models["isotropic"])
        else:
            assert ours < 0.9 * models["isotropic"]


def test_with_time_the_plane_sees_the_sun_where_pvlib_puts_it(capsys):
    # The sun at --time comes from the ephemeris; pvlib's NREL SPA (Reda & Andreas 2004)
    # places it independently: geometric zenith and azimuth within 0.02 deg (measured 4e-5
    # and 7e-5 deg). The beam on the plane is then DNI cos(incidence), pvlib's angle of
    # incidence (measured 1.6e-6 apart); 1e-3: 0.02 deg of the sun's position moves
    # cos(incidence) by at most 3.5e-4 / 0.72.
    pvlib = pytest.importorskip("pvlib")
    argv = ["irradiance", "earth", "--time", "2024-06-21T10:00+02:00", "--lat", "52.5",
            "--lon", "13.4", "--wavelengths", "550", "--solver", "single", "--samples", "64",
            "--tilt", "35", "--plane-azimuth", "200", "--format", "json"]
    code, out, _ = run_cli(capsys, argv)
    assert code == 0
    row = json.loads(out)[0]
    spa = pvlib.solarposition.get_solarposition(pd.Timestamp("2024-06-21T08:00Z"), 52.5, 13.4)
    zenith, azimuth = float(spa["zenith"].iloc[0]), float(spa["azimuth"].iloc[0])
    assert row["sun_zenith_deg"] == pytest.approx(zenith, abs=0.02)
    assert row["sun_azimuth_deg"] == pytest.approx(azimuth, abs=0.02)
    incidence = float(pvlib.irradiance.aoi(35.0, 200.0, zenith, azimuth))
    assert row["plane_direct"] == pytest.approx(
        row["direct_normal"] * math.cos(math.radians(incidence)), rel=1e-3)


# --- xarray datasets and NetCDF ---------------------------------------------------------------

def test_radiance_dataset_has_the_rows_on_labelled_axes_and_survives_netcdf(tmp_path):
    options = api.solver_options(EARTH, n_samples=64)
    dataset = api.radiance_dataset(EARTH, [30.0], [0.0, 60.0], [0.0, 180.0], [440.0, 550.0],
                                   solver="single", options=options)
    assert dataset["radiance"].dims == ("sun_zenith", "view_zenith", "azimuth", "wavelength")
    assert dataset["toa_irradiance"].dims == ("wavelength",)
    assert dataset["radiance"].attrs["units"] == "W m-2 sr-1 nm-1"
    for row in _radiance_rows():
        value = dataset["radiance"].sel(sun_zenith=row["sun_zenith_deg"],
                                        view_zenith=row["view_zenith_deg"],
                                        azimuth=row["relative_azimuth_deg"],
                                        wavelength=row["wavelength_nm"])
        assert float(value) == row["radiance"]
    path = api.write_netcdf(dataset, tmp_path / "sky.nc")
    with xarray.open_dataset(path) as back:
        np.testing.assert_array_equal(back["radiance"].values, dataset["radiance"].values)
        assert back.attrs["solver_name"] == "single" and back.attrs["Conventions"] == "CF-1.8"
    with netcdf_file(path, "r", mmap=False) as raw:  # scipy's reader, not xarray's
        radiance = raw.variables["radiance"]
        assert radiance.dimensions == ("sun_zenith", "view_zenith", "azimuth", "wavelength")
        assert radiance.units == b"W m-2 sr-1 nm-1"
        np.testing.assert_array_equal(raw.variables["wavelength"][:], [440.0, 550.0])
        np.testing.assert_array_equal(radiance[:], dataset["radiance"].values)
        assert raw.atmosphere_preset == b"earth"
        assert raw.version.decode() == dataset.attrs["version"]


def test_irradiance_dataset_and_the_commands_nc_output(capsys, tmp_path):
    dataset = api.irradiance_dataset(EARTH, [30.0, 60.0], [450.0, 550.0], solver="single",
                                     options=api.solver_options(EARTH, n_samples=64),
                                     tilt_deg=30.0)
    assert dataset["plane_global"].dims == ("sun_zenith", "wavelength")
    assert float(dataset["tilt"]) == 30.0 and dataset["tilt"].attrs["units"] == "degree"
    assert dataset["direct_transmittance"].attrs["units"] == "1"
    path = tmp_path / "irradiance.nc"
    argv = [a if a != "30" else "30,60" for a in IRRADIANCE]
    code, out, err = run_cli(capsys, [*argv, "-o", str(path), "--tilt", "30"])
    assert code == 0 and out == "" and err == ""
    with netcdf_file(path, "r", mmap=False) as raw:
        np.testing.assert_allclose(raw.variables["plane_global"][:],
                                   dataset["plane_global"].values, rtol=1e-12)
        assert raw.variables["direct_normal"].units == b"W m-2 nm-1"


def test_without_xarray_the_message_names_the_extra(capsys, monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "xarray", None)  # import xarray now raises ImportError
    with pytest.raises(InputError, match=r"skyscatter\[science\]"):
        api.radiance_dataset(EARTH, [30.0], [0.0], [0.0], [550.0], solver="single")
    code, _, err = run_cli(capsys, [*RADIANCE, "-o", str(tmp_path / "x.nc")])
    assert code == 2 and "skyscatter[science]" in err and "Traceback" not in err
    assert not (tmp_path / "x.nc").exists()
