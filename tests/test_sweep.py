"""`skyscatter sweep` / `api.sweep` on Dask: the same numbers on a local cluster and on a
scheduler with two worker processes, both equal to `api.sky_radiance_rows` and
`api.irradiance_rows` called atmosphere by atmosphere (the reference: the atmospheres made
without `config_overrides`, by editing the preset's text and by `api.with_ground_albedo`); an
interrupted sweep resumes without recomputing its finished chunks; a worker killed mid-sweep
loses nothing; a sweep over times has astropy's sun and the radiance of the rows at its sun's
zenith angles; bad input gets one line.

The clusters are real: `distributed.LocalCluster` processes, and a scheduler and two workers
started here as subprocesses (`python -m distributed.cli.dask_scheduler` / `dask_worker`) on
127.0.0.1 at ports the system picks. Each cluster test has a watchdog that kills the cluster's
processes after `WATCHDOG_S`, so a hang fails the test instead of the CI job, and every process
is ended in `finally`. The solver is "single" with 16 samples (no tables: milliseconds per
chunk), so the time goes to starting the clusters (about 10 s each on 2 cores).
"""

from __future__ import annotations

import itertools
import os
import signal
import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

import skyscatter
from skyscatter import api, dask_cluster
from skyscatter.api_constants import AU_M
from skyscatter.atmosphere.config import PRESETS_DIR, parse_atmosphere
from skyscatter.cli import main
from skyscatter.errors import InputError
from skyscatter.output_files import TEMPORARY_NAME

xarray = pytest.importorskip("xarray")
pytest.importorskip("distributed")

WATCHDOG_S = 240.0  # s: far above the ~30 s a cluster test takes on 2 cores
ALBEDOS = (0.0, 0.3)
DEPTHS = (0.05, 0.4)  # aerosol optical depth at 500 nm, constituent[2] of the earth preset
VALUES = {"planet.ground_albedo": "0,0.3", "constituent[2].optics.optical_depth": "0.05,0.4"}
GEOMETRY = ([20.0, 70.0], [0.0, 45.0, 80.0], [0.0, 120.0])
WAVELENGTHS = [450.0, 650.0]
OPTIONS = {"wavelengths_nm": WAVELENGTHS, "solver": "single", "n_samples": 16}


def _reference_atmosphere(albedo: float, depth: float):
    """The earth preset with its aerosol depth edited in the TOML text (not by dotted key)
    and the ground albedo set by `api.with_ground_albedo`."""
    path = PRESETS_DIR / "earth.toml"
    text = path.read_text(encoding="utf-8")
    assert text.count("optical_depth = 0.1,") == 1
    document = tomllib.loads(text.replace("optical_depth = 0.1,", f"optical_depth = {depth},"))
    return api.with_ground_albedo(parse_atmosphere(document, path), albedo)


@pytest.fixture(scope="module")
def reference():
    """radiance (albedo, depth, sun, view, azimuth, wl) and the irradiance columns (albedo,
    depth, sun, wl) from the row functions, atmosphere by atmosphere."""
    shape = (len(ALBEDOS), len(DEPTHS))
    radiance = np.empty(shape + tuple(len(g) for g in GEOMETRY) + (len(WAVELENGTHS),))
    surface = {name: np.empty(shape + (len(GEOMETRY[0]), len(WAVELENGTHS))) for name in
               ("direct_normal", "diffuse_horizontal", "direct_transmittance")}
    for (i, albedo), (j, depth) in itertools.product(enumerate(ALBEDOS), enumerate(DEPTHS)):
        atmosphere = _reference_atmosphere(albedo, depth)
        rows = api.sky_radiance_rows(atmosphere, *GEOMETRY, WAVELENGTHS, solver="single",
                                     options=api.SolverOptions(n_samples=16))
        radiance[i, j] = np.reshape([row["radiance"] for row in rows], radiance.shape[2:])
        rows = api.irradiance_rows(atmosphere, GEOMETRY[0], WAVELENGTHS, solver="single",
                                   options=api.SolverOptions(n_samples=16), transmittance=True)
        for name, cube in surface.items():
            cube[i, j] = np.reshape([row[name] for row in rows], cube.shape[2:])
    return radiance, surface


def _check_against_reference(dataset, reference) -> None:
    # Same solver, same optical profile, same kernels: only the way the atmosphere was made
    # differs, so the numbers agree to rounding (1e-12 leaves room for none in practice).
    radiance, surface = reference
    assert list(dataset["radiance"].dims) == ["planet_ground_albedo",
                                              "constituent_2_optics_optical_depth",
                                              "sun_zenith", "view_zenith", "azimuth",
                                              "wavelength"]
    np.testing.assert_allclose(dataset["radiance"].values, radiance, rtol=1e-12, atol=0)
    for name, cube in surface.items():
        assert list(dataset[name].dims) == ["planet_ground_albedo",
                                            "constituent_2_optics_optical_depth", "sun_zenith",
                                            "wavelength"]
        np.testing.assert_allclose(dataset[name].values, cube, rtol=1e-12, atol=0)


class Cluster:
    """A `dask-scheduler` and `workers` `dask-worker` processes (no nanny: the worker is the
    process) on 127.0.0.1, ended by `close` or by the watchdog."""

    def __init__(self, folder: Path, workers: int = 2) -> None:
        env = dict(os.environ)
        source = str(Path(skyscatter.__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [source, env.get("PYTHONPATH")]))
        scheduler_file = folder / "scheduler.json"
        self.processes: list[subprocess.Popen] = []
        self._watchdog = threading.Timer(WATCHDOG_S, self.close)
        self._watchdog.start()
        self._start(env, "dask_scheduler", "--host", "127.0.0.1", "--port", "0",
                    "--no-dashboard", "--scheduler-file", str(scheduler_file))
        deadline = time.monotonic() + 60.0
        while not scheduler_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        import json
        self.address = json.loads(scheduler_file.read_text())["address"]
        self.workers = [self._start(env, "dask_worker", self.address, "--nthreads", "1",
                                    "--no-nanny", "--no-dashboard", "--host", "127.0.0.1")
                        for _ in range(workers)]
        from distributed import Client
        with Client(self.address, timeout=30) as client:
            client.wait_for_workers(workers, timeout=90)

    def _start(self, env: dict, module: str, *arguments: str) -> subprocess.Popen:
        process = subprocess.Popen([sys.executable, "-m", f"distributed.cli.{module}",
                                    *arguments], env=env, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL, start_new_session=True)
        self.processes.append(process)
        return process

    def close(self) -> None:
        self._watchdog.cancel()
        for process in reversed(self.processes):
            if process.poll() is None:
                process.kill()
            process.wait(timeout=30)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    started = Cluster(tmp_path_factory.mktemp("dask"))
    try:
        yield started
    finally:
        started.close()


def test_local_cluster_and_two_remote_workers_give_identical_datasets_equal_to_the_rows(
        cluster, reference, tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")  # the same attributes in both
    local = api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, workers=2,
                      output_path=tmp_path / "local.nc")
    remote = api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, scheduler=cluster.address,
                       output_path=tmp_path / "remote.zarr")
    assert (local.computed, remote.computed) == (8, 8)  # 4 atmospheres x 2 sun zeniths
    # read back by xarray's own readers: the files, not the objects, are the result
    local_file = xarray.open_dataset(tmp_path / "local.nc", engine="scipy")
    remote_file = xarray.open_zarr(tmp_path / "remote.zarr").load()
    xarray.testing.assert_identical(local_file, remote_file)
    _check_against_reference(local_file, reference)
    for name, key in (("planet_ground_albedo", "planet.ground_albedo"),
                      ("constituent_2_optics_optical_depth",
                       "constituent[2].optics.optical_depth")):
        assert local_file[name].attrs["config_key"] == key
    assert local_file["radiance"].attrs["units"] == "W m-2 sr-1 nm-1"
    assert local_file["toa_irradiance"].dims == ("wavelength",)
    assert local_file.attrs["solver_name"] == "single"
    assert not (tmp_path / "local.nc.parts").exists()  # removed once the output is written
    assert not (tmp_path / "remote.zarr.parts").exists()


def test_an_interrupted_sweep_resumes_without_recomputing_its_finished_chunks(
        cluster, reference, tmp_path):
    output = tmp_path / "lut.nc"
    stored = []

    def interrupt_after_three(done: int, total: int) -> None:
        stored.append(done)
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, scheduler=cluster.address,
                  output_path=output, atmospheres_in_flight=1, on_chunk=interrupt_after_three)
    parts = tmp_path / "lut.nc.parts"
    finished = sorted(parts.glob("chunk_*.npz"))
    assert len(finished) == 3 and not output.exists()
    assert not [p for p in tmp_path.rglob("*") if TEMPORARY_NAME.fullmatch(p.name)]
    before = {path.name: path.stat().st_mtime_ns for path in finished}
    result = api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, scheduler=cluster.address,
                       output_path=output, keep_parts=True)
    assert (result.reused, result.computed) == (3, 5)
    assert {path.name: path.stat().st_mtime_ns for path in finished} == before
    _check_against_reference(xarray.open_dataset(output, engine="scipy"), reference)
    # a third run finds every chunk and starts no cluster at all
    again = api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, scheduler="tcp://127.0.0.1:9",
                      output_path=output)
    assert (again.reused, again.computed) == (8, 0) and not parts.exists()


def test_a_store_of_another_sweep_is_refused_unless_restarted(cluster, tmp_path):
    output = tmp_path / "a.nc"
    api.sweep("earth", {"planet.ground_albedo": "0.1"}, [30.0], **OPTIONS,
              scheduler=cluster.address, output_path=output, keep_parts=True)
    with pytest.raises(InputError, match=r"a\.nc\.parts holds the chunks of another sweep.*"
                       r"--restart"):
        api.sweep("earth", {"planet.ground_albedo": "0.2"}, [30.0], **OPTIONS,
                  scheduler=cluster.address, output_path=output)
    result = api.sweep("earth", {"planet.ground_albedo": "0.2"}, [30.0], **OPTIONS,
                       scheduler=cluster.address, output_path=output, restart=True)
    assert result.computed == 1


def test_a_worker_killed_mid_sweep_loses_no_result(reference, tmp_path):
    cluster = Cluster(tmp_path)
    try:
        victim = cluster.workers[0]
        remaining = []

        def kill_a_worker(done: int, total: int) -> None:
            if done == 1:
                remaining.append(total - done)
                os.killpg(victim.pid, signal.SIGKILL)
                victim.wait(timeout=30)

        result = api.sweep("earth", VALUES, *GEOMETRY, **OPTIONS, scheduler=cluster.address,
                           output_path=tmp_path / "killed.nc", atmospheres_in_flight=1,
                           on_chunk=kill_a_worker)
        # one atmosphere in flight: when the worker died, 7 of 8 chunks were still to come
        assert victim.returncode == -signal.SIGKILL and remaining == [7]
        assert result.computed == 8
        _check_against_reference(xarray.open_dataset(tmp_path / "killed.nc", engine="scipy"),
                                 reference)
    finally:
        cluster.close()


def test_the_command_line_writes_the_dataset_of_the_api(cluster, tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    output = tmp_path / "cli.nc"
    code = main(["sweep", "earth", "--set", "planet.ground_albedo=0:0.3:2", "--sun-zenith",
                 "20,70", "--view-zenith", "0,45", "--azimuth", "0", "--wavelengths", "550",
                 "--solver", "single", "--samples", "16", "--scheduler", cluster.address,
                 "-o", str(output), "-q"])
    assert code == 0
    written = xarray.open_dataset(output, engine="scipy")
    expected = api.sweep("earth", {"planet.ground_albedo": [0.0, 0.3]}, [20.0, 70.0],
                         [0.0, 45.0], [0.0], wavelengths_nm=[550.0], solver="single",
                         n_samples=16, scheduler=cluster.address).dataset
    xarray.testing.assert_equal(written, expected)  # the attributes differ: the command
    assert written.attrs["sweep_command"].startswith("skyscatter sweep earth --set")


def _astropy_sun(utc: str, latitude: float, longitude: float) -> tuple[float, float, float]:
    """Zenith angle and azimuth [deg] of the sun's centre, topocentric and airless (pressure 0),
    and its distance [m], from astropy with its built-in ephemeris (no download)."""
    import warnings

    from astropy import units
    from astropy.coordinates import AltAz, EarthLocation, get_body, solar_system_ephemeris
    from astropy.time import Time
    from astropy.utils import iers

    iers.conf.auto_download = False
    place = EarthLocation.from_geodetic(longitude * units.deg, latitude * units.deg,
                                        0 * units.m)
    moment = Time(utc)
    with solar_system_ephemeris.set("builtin"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # IERS table age: UT1 - UTC to well under a second
        sun = get_body("sun", moment, place).transform_to(
            AltAz(obstime=moment, location=place, pressure=0 * units.hPa))
    return 90.0 - float(sun.alt.deg), float(sun.az.deg), float(sun.distance.to(units.m).value)


def test_a_sweep_over_times_has_the_suns_of_astropy_and_the_radiance_of_their_zeniths(
        cluster, tmp_path):
    pytest.importorskip("astropy")
    output = tmp_path / "berlin.nc"
    # midsummer in Berlin from deep twilight (00:00 local, sun 12.6 deg down) through noon to
    # dusk (21:00, 3 deg up), every 3 h: night, twilight and day rows, none dropped
    code = main(["sweep", "earth", "--start", "2024-06-21T00:00+02:00", "--end",
                 "2024-06-21T21:00+02:00", "--step", "3h", "--lat", "52.52", "--lon", "13.40",
                 "--view-zenith", "0,80", "--azimuth", "0,90", "--wavelengths", "450,650",
                 "--solver", "single", "--samples", "16", "--scheduler", cluster.address,
                 "--keep-parts", "-o", str(output), "-q"])
    assert code == 0
    written = xarray.open_dataset(output, engine="scipy").load()
    expected_utc = [f"2024-06-{day}T{hour:02d}:00:00" for day, hour in
                    [("20", 22)] + [("21", h) for h in range(1, 20, 3)]]
    assert [str(t)[:19] for t in written["time"].values] == expected_utc
    assert list(written["radiance"].dims) == ["time", "view_zenith", "azimuth", "wavelength"]
    assert list(written["direct_normal"].dims) == ["time", "wavelength"]
    assert written["sun_zenith"].dims == ("time",) and written["sun_azimuth"].dims == ("time",)
    assert written["sun_azimuth"].attrs["units"] == "degree"
    # Reference: astropy's airless topocentric sun; skyscatter's ephemeris agreed to 4e-5 deg
    # in zenith angle and 2.2e-4 deg in azimuth here (tests/astro: <= 4" over other cases),
    # so 1e-3 deg; its topocentric distance to 1e-7 (1.0163 AU at midsummer), so 1e-6.
    assert written["sun_distance"].attrs["units"] == "m"
    for utc, zenith, azimuth, distance in zip(
            expected_utc, written["sun_zenith"].values, written["sun_azimuth"].values,
            written["sun_distance"].values, strict=True):
        reference_zenith, reference_azimuth, reference_distance = _astropy_sun(utc, 52.52, 13.40)
        assert abs(zenith - reference_zenith) < 1e-3 and abs(azimuth - reference_azimuth) < 1e-3
        assert distance == pytest.approx(reference_distance, rel=1e-6)
    assert written["sun_zenith"].values.max() > 100.0  # a night row is there, radiance ~0
    # the radiance at those times is the rows' at those sun zenith angles, lit by the sun at
    # that distance: same solver, same kernels, only the way the sun was placed differs
    # (1e-12: rounding); toa_irradiance stays the config's (1 AU)
    earth = api.load_atmosphere("earth")
    for t, (zenith, distance) in enumerate(zip(written["sun_zenith"].values,
                                               written["sun_distance"].values, strict=True)):
        rows = api.sky_radiance_rows(earth, [zenith], [0.0, 80.0], [0.0, 90.0], [450.0, 650.0],
                                     solver="single", options=api.SolverOptions(n_samples=16),
                                     sun_distance_m=distance)
        np.testing.assert_allclose(written["radiance"].values[t],
                                   np.reshape([row["radiance"] for row in rows], (2, 2, 2)),
                                   rtol=1e-12, atol=0)
        scale = (AU_M / distance) ** 2  # ~0.968: 3 % less light than at 1 AU
        np.testing.assert_allclose([row["toa_irradiance"] for row in rows[:2]],
                                   scale * written["toa_irradiance"].values, rtol=1e-12)
    # the time on disk is CF: float64 seconds since the Unix epoch, read back the same by Zarr
    import scipy.io
    with scipy.io.netcdf_file(output, mmap=False) as raw:
        variable = raw.variables["time"]
        assert variable.units == b"seconds since 1970-01-01" and variable.data.dtype == ">f8"
        assert variable.data[0] == 1718920800.0  # 2024-06-20T22:00Z, `date -d ... +%s`
    api.write_zarr(written, tmp_path / "berlin.zarr")
    xarray.testing.assert_identical(xarray.open_zarr(tmp_path / "berlin.zarr").load(), written)
    # the times are in the fingerprint: other times do not resume from these chunks
    with pytest.raises(InputError, match="holds the chunks of another sweep"):
        api.sweep("earth", None, None, [0.0, 80.0], [0.0, 90.0],
                  times=["2024-06-22T00:00+02:00"], latitude_deg=52.52, longitude_deg=13.40,
                  wavelengths_nm=[450.0, 650.0], solver="single", n_samples=16,
                  output_path=output)


@pytest.mark.parametrize(("arguments", "message"), [
    (["--set", "planet.ground_albdo=0,1"],
     "unknown key 'planet.ground_albdo'; did you mean 'planet.ground_albedo'?"),
    (["--set", "planet.ground_albedo=0:1:1"], "COUNT from 2 to"),
    (["--set", "planet.ground_albedo=0,1", "--set", "planet.ground_albedo=2"], "given twice"),
    (["--set", "planet.ground_albedo=0,7"], "ground_albedo"),
    (["--sun-zenith", "0:200:3"], "--sun-zenith"),
    (["--solver", "magic"], "unknown solver 'magic'"),
    (["--wavelengths", "100"], "wavelength"),
    (["-o", "out.csv"], "name it .nc (NetCDF) or .zarr"),
    (["--set", "planet.ground_albedo=0:1:10000", "--view-zenith", "0:90:1000",
      "--azimuth", "0:180:1000", "--solver", "single"], "would"),
    (["--scheduler", "tcp://127.0.0.1:9"], "cannot reach the Dask scheduler"),
    (["--start", "2024-06-21T00:00", "--end", "2024-06-22T00:00Z", "--lat", "52", "--lon",
      "13"], "has no time zone"),
    (["--start", "2024-06-21T00:00Z", "--end", "2024-06-20T00:00Z", "--lat", "52", "--lon",
      "13"], "must come after --start"),
    (["--start", "2024-06-21T00:00Z", "--lat", "52", "--lon", "13"], "both --start and --end"),
    (["--start", "2024-06-21T00:00Z", "--end", "2024-06-22T00:00Z"], "give latitude_deg"),
    (["--start", "2024-06-21T00:00Z", "--end", "2024-06-22T00:00Z", "--lat", "52", "--lon",
      "13", "--sun-zenith", "30"], "both place the sun"),
    (["--start", "2024-01-01T00:00Z", "--end", "2024-12-31T00:00Z", "--lat", "52", "--lon",
      "13", "--step", "1min"], "give a longer --step"),
    (["--lat", "52", "--lon", "13"], "give --start and --end too"),
    (["--step", "10min"], "space the times of --start/--end"),
])
def test_bad_input_gets_one_line_and_exit_code_2(arguments, message, tmp_path, capsys,
                                                  monkeypatch):
    monkeypatch.setattr(dask_cluster, "CONNECT_TIMEOUT_S", 2.0)
    monkeypatch.chdir(tmp_path)
    full = ["sweep", "earth", "-o", "out.nc", "--solver", "single", *arguments]
    try:
        code = main(full)
    except SystemExit as exit_:  # argparse: usage, then one line naming the argument
        code = exit_.code
    error = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and error.startswith("skyscatter") and message in error, error
    assert not list(tmp_path.iterdir())  # nothing written, no cluster started for nothing


def test_an_unwritable_output_is_refused_before_any_work(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["sweep", "earth", "--solver", "single", "-o", str(blocker / "x.nc")]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_a_planet_without_an_ephemeris_cannot_sweep_times(tmp_path):
    with pytest.raises(InputError, match="no ephemeris"):
        api.sweep("exo-hazy", times=["2024-06-21T12:00Z"], latitude_deg=0.0,
                  longitude_deg=0.0, solver="single", output_path=tmp_path / "x.nc")


def test_two_keys_that_make_the_same_dimension_are_refused():
    with pytest.raises(InputError, match="both make the dimension 'planet_ground_albedo'"):
        api.sweep("earth", {"planet.ground_albedo": "0,1", "planet_ground.albedo": "0"},
                  solver="single")


def test_missing_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    with pytest.raises(InputError, match=r'pip install "skyscatter\[dask\]"'):
        api.sweep("earth", {"planet.ground_albedo": "0"}, solver="single")
