"""skyscatter envmap: a series of environment maps with their light files and an index, read
back with OpenEXR and json; the sun's place in the index against astropy's ephemeris."""

from __future__ import annotations

import datetime
import json

import numpy as np
import OpenEXR
import pytest

from skyscatter.cli import main

LAT, LON = 52.52, 13.40
COMMON = ["envmap", "earth", "--lat", str(LAT), "--lon", str(LON), "--size", "8", "--solver",
          "single", "--wavelengths", "3", "--no-stars", "--no-moon", "--no-airglow"]


def _astropy_sun(time: str) -> tuple[float, float]:
    """Elevation and azimuth [deg] of the sun's centre without refraction (astropy, built-in
    ephemeris, no IERS download)."""
    from astropy import units
    from astropy.coordinates import AltAz, EarthLocation, get_body
    from astropy.time import Time
    from astropy.utils import iers

    iers.conf.auto_download = False
    place = EarthLocation(lat=LAT * units.deg, lon=LON * units.deg, height=0 * units.m)
    moment = Time(datetime.datetime.fromisoformat(time))
    sun = get_body("sun", moment, place).transform_to(AltAz(obstime=moment, location=place))
    return float(sun.alt.deg), float(sun.az.deg)


def test_the_series_writes_a_map_a_light_and_mips_per_time_and_an_index(tmp_path):
    # Reference for the sun: astropy's geometric position plus Bennett's (1982) refraction,
    # R = cot(h + 7.31 / (h + 4.4)) arcmin (0.017 deg at 44 deg); skyscatter's comes from
    # ephem's ephemeris with refraction. Measured 2e-4 deg apart in azimuth and, after the
    # refraction, 3e-4 in elevation; tolerance 5e-3 deg.
    out = tmp_path / "maps"
    assert main([*COMMON, "--start", "2024-06-21T10:00+02:00", "--end",
                 "2024-06-21T12:00+02:00", "--step", "1h", "--mips", "2", "-o", str(out)]) == 0
    index = json.loads((out / "index.json").read_text())
    assert [entry["time"] for entry in index["maps"]] == [
        "2024-06-21T08:00:00+00:00", "2024-06-21T09:00:00+00:00", "2024-06-21T10:00:00+00:00"]
    assert index["camera"] == "CubeMapCamera" and index["cube_layout"] == "cross"
    assert index["place"]["latitude_deg"] == LAT
    for entry in index["maps"]:
        channels = OpenEXR.File(str(out / entry["map"]), separate_channels=True).channels()
        assert channels["R"].pixels.shape == (24, 32)
        assert np.isfinite(channels["B"].pixels).all()
        mip = OpenEXR.File(str(out / entry["mips"][0]), separate_channels=True).channels()
        assert mip["G"].pixels.shape == (12, 16)
        light = json.loads((out / entry["light"]).read_text())
        assert light["sun"]["direction"] == entry["sun"]["direction"]
        elevation, azimuth = _astropy_sun(entry["time"])
        refraction = 1.0 / np.tan(np.radians(elevation + 7.31 / (elevation + 4.4))) / 60.0
        assert entry["sun"]["elevation_deg"] == pytest.approx(elevation + refraction, abs=5e-3)
        assert entry["sun"]["azimuth_deg"] == pytest.approx(azimuth, abs=5e-3)
        assert entry["sun"]["illuminance"] == light["sun"]["illuminance"] > 0.0
    assert sorted(p.name for p in out.iterdir()) == sorted(
        ["index.json"] + [name for entry in index["maps"]
                          for name in (entry["map"], entry["light"], *entry["mips"])])


def test_hdr_maps_and_a_folder_of_other_files_refused(tmp_path, capsys):
    out = tmp_path / "hdr"
    assert main([*COMMON, "--start", "2024-06-21T12:00+02:00", "--end",
                 "2024-06-21T13:00+02:00", "--frames", "2", "--format", "hdr",
                 "--camera", "octahedral", "-o", str(out)]) == 0
    index = json.loads((out / "index.json").read_text())
    assert [entry["map"] for entry in index["maps"]] == ["sky_00001.hdr", "sky_00002.hdr"]
    assert (out / "sky_00002.hdr").read_bytes().startswith(b"#?RADIANCE")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep")
    capsys.readouterr()
    assert main([*COMMON, "--start", "2024-06-21T12:00+02:00", "--end",
                 "2024-06-21T13:00+02:00", "-o", str(tmp_path / "mine")]) == 2
    assert "it holds other files (notes.txt)" in capsys.readouterr().err
    assert main([*COMMON, "--start", "2024-06-21T12:00+02:00", "--end",
                 "2024-06-21T13:00+02:00", "--mips", "5", "-o", str(tmp_path / "m")]) == 2
    assert "--size must be a multiple of 16" in capsys.readouterr().err
