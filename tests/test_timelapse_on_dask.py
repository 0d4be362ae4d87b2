"""`skyscatter timelapse --workers N`: the frames rendered on a local Dask cluster
(`dask_cluster.map_in_order`) are the serial run's, byte for byte, with the same exposures; the
twinkling stars, which draw their random numbers frame after frame, are refused there."""

from __future__ import annotations

import pytest
from PIL import Image

from skyscatter.cli import main

pytest.importorskip("distributed")

DUSK = ["timelapse", "earth", "--start", "2024-06-21T19:00Z", "--end", "2024-06-21T20:30Z",
        "--frames", "4", "--lat", "52.52", "--lon", "13.40", "--size", "16",
        "--wavelengths", "4", "--orders", "2", "-q"]


def test_frames_rendered_on_two_workers_are_the_serial_frames(tmp_path):
    assert main([*DUSK, "-o", str(tmp_path / "serial.gif")]) == 0
    assert main([*DUSK, "-o", str(tmp_path / "dask.gif"), "--workers", "2"]) == 0
    serial = sorted((tmp_path / "serial_frames").glob("frame_*.png"))
    parallel = sorted((tmp_path / "dask_frames").glob("frame_*.png"))
    assert [p.name for p in serial] == [p.name for p in parallel] and len(serial) == 4
    for one, other in zip(serial, parallel, strict=True):
        assert one.read_bytes() == other.read_bytes()  # pixels, EV100 and time in the text
    with Image.open(serial[0]) as first, Image.open(serial[-1]) as last:
        assert float(first.text["EV100"]) > float(last.text["EV100"])  # a dusk, not a copy
    assert (tmp_path / "serial.gif").read_bytes() == (tmp_path / "dask.gif").read_bytes()


def test_twinkling_stars_are_refused_on_a_cluster(tmp_path, capsys):
    assert main([*DUSK, "--twinkle", "3", "--workers", "2", "-o", str(tmp_path / "t.gif")]) == 2
    assert "leave --twinkle out on a cluster" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())
