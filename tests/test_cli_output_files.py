"""The command line's output files: refused before any work, written in the format their name
says, replaced together, and never left half done by an interrupt, SIGTERM or SIGKILL.

"Before any work" is observed as a table cache folder that stays absent (the lut solver would
have filled it); kills run the CLI in a child process.
"""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image

from cli_runner import run_cli, unprivileged_prefix
from skyscatter import api
from skyscatter.cli import main
from skyscatter.render.image_io import read_exr

SMALL = ["--solver", "single", "--size", "8", "--wavelengths", "3", "--no-cache"]
TIMELAPSE = ["timelapse", "earth", "--start", "2024-06-21T19:00Z", "--end", "2024-06-21T20:00Z",
             "--lat", "52.52", "--lon", "13.40"]


def _one_line(stderr: str) -> str:
    assert "Traceback" not in stderr
    lines = stderr.rstrip("\n").split("\n")
    assert len(lines) == 1 and lines[0].startswith("skyscatter: "), stderr
    return lines[0]


def _hidden(folder) -> list[str]:
    return sorted(name for name in os.listdir(folder) if name.startswith("."))


# --- refused before any work ------------------------------------------------------------------

@pytest.mark.parametrize(("argv", "message"), [
    (["render", "earth", "-o", "{t}/adir.png"], "adir.png: it is a directory; give a file"),
    (["render", "earth", "-o", "{t}/afile/x.png"], "afile/x.png: Not a directory"),
    (["render", "earth", "-o", "{t}/x.bmp"], "'{t}/x.bmp': name it .png, .jpg, .jpeg, .tif"),
    (["render", "earth", "-o", "{t}/x.exr"], "a linear EXR is written with --exr"),
    (["render", "earth", "--exr", "{t}/x.png"],
     "a linear image as '{t}/x.png': name it .exr (OpenEXR) or .hdr"),
    (["render", "earth", "-o", "{t}/y.png", "--exr", "{t}/adir.exr"],
     "adir.exr: it is a directory"),
    ([*TIMELAPSE, "-o", "{t}/adir.png/t.gif", "--frames-dir", "{t}/afile"],
     "afile: it is a file; give a folder"),
    ([*TIMELAPSE, "-o", "{t}/t.gif", "--frames-dir", "{t}/mine"],
     "mine: it holds other files (holiday.jpg)"),
    ([*TIMELAPSE, "-o", "{t}/adir.gif"], "adir.gif: it is a directory"),
    ([*TIMELAPSE, "-o", "{t}/new/t.gif", "--frames-dir", "{t}/new"],
     "the video {t}/new/t.gif cannot go inside the frames folder {t}/new"),
])
def test_unwritable_outputs_are_refused_before_any_table_work(capsys, tmp_path, argv, message):
    # Before: the tables were computed (and cached) first, the error came at the end.
    for folder in ("adir.png", "adir.exr", "adir.gif"):
        (tmp_path / folder).mkdir()
    (tmp_path / "afile").write_text("x")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "holiday.jpg").write_bytes(b"mine")
    cache = tmp_path / "cache"
    before = sorted(os.listdir(tmp_path))
    argv = [arg.replace("{t}", str(tmp_path)) for arg in argv]
    code, _, err = run_cli(capsys, [*argv, "--cache-dir", str(cache), "--size", "8"])
    assert code == 2
    assert message.replace("{t}", str(tmp_path)) in _one_line(err)
    assert sorted(os.listdir(tmp_path)) == before  # no cache, no output, no temporary


@pytest.mark.parametrize(("argv", "refused"), [
    (["render", "earth", "-o", "{ro}/x.png"], "{ro}/x.png"),
    (["render", "earth", "-o", "{t}/x.png", "--exr", "{ro}/x.exr"], "{ro}/x.exr"),
    ([*TIMELAPSE, "-o", "{ro}/t.gif", "--frames-dir", "{t}/frames"], "{ro}/t.gif"),
    ([*TIMELAPSE, "-o", "{t}/t.gif", "--frames-dir", "{ro}/frames"], "{ro}/frames"),
    (["render", "earth", "-o", "{t}/locked.png"], "{t}/locked.png"),
])
def test_a_read_only_folder_is_refused_before_any_table_work(tmp_path, argv, refused):
    read_only = tmp_path / "ro"
    read_only.mkdir(mode=0o555)
    (tmp_path / "locked.png").write_bytes(b"kept")
    (tmp_path / "locked.png").chmod(0o444)
    cache = tmp_path / "cache"
    argv = [a.replace("{ro}", str(read_only)).replace("{t}", str(tmp_path)) for a in argv]
    result = subprocess.run([*unprivileged_prefix(), sys.executable, "-m", "skyscatter.cli", *argv,
                             "--cache-dir", str(cache), "--size", "8"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    refused = refused.replace("{ro}", str(read_only)).replace("{t}", str(tmp_path))
    reason = "the file is read-only" if "locked" in refused else "Permission denied"
    assert _one_line(result.stderr) == f"skyscatter: cannot write {refused}: {reason}"
    assert sorted(os.listdir(tmp_path)) == ["locked.png", "ro"] and os.listdir(read_only) == []
    assert (tmp_path / "locked.png").read_bytes() == b"kept"


# --- the format the name says; standard output ---------------------------------------------------

def test_jpg_name_writes_a_jpeg_with_the_pngs_pixels(capsys, tmp_path):
    # Before: PNG bytes under the .jpg name.
    for name in ("sky.png", "sky.jpg"):
        code, _, err = run_cli(capsys, ["render", "earth", *SMALL, "-o", str(tmp_path / name)])
        assert code == 0, err
    with Image.open(tmp_path / "sky.jpg") as jpeg, Image.open(tmp_path / "sky.png") as png:
        assert jpeg.format == "JPEG" and png.format == "PNG"
        difference = np.asarray(jpeg, float) - np.asarray(png.convert("RGB"), float)
    # JPEG quality 95 without chroma subsampling: a few codes at most on a smooth 8 x 8 sky
    assert np.abs(difference).mean() < 3.0


def test_dash_writes_the_png_to_standard_output(capsysbinary, tmp_path, monkeypatch):
    # Before: a file named "-" in the working folder, nothing on standard output.
    monkeypatch.chdir(tmp_path)
    code = main(["render", "earth", *SMALL, "-o", "-"])
    out, err = capsysbinary.readouterr()
    assert code == 0
    assert out.startswith(b"\x89PNG\r\n\x1a\n")
    assert err.decode().startswith("wrote the PNG to standard output")
    assert os.listdir(tmp_path) == []


# --- time-lapse frames ---------------------------------------------------------------------------

def _timelapse(capsys, tmp_path, frames: int) -> int:
    code, _, err = run_cli(capsys, [*TIMELAPSE, *SMALL, "--no-stars", "--no-moon", "--no-airglow",
                                 "--frames", str(frames), "-o", str(tmp_path / "t.gif")])
    assert code in (0, 130), err
    return code


def test_a_shorter_time_lapse_leaves_exactly_its_own_frames(capsys, tmp_path):
    # Before: 3 frames then 1 left frame_00002/3 of the first run beside the new one.
    _timelapse(capsys, tmp_path, 3)
    _timelapse(capsys, tmp_path, 1)
    assert os.listdir(tmp_path / "t_frames") == ["frame_00001.png"]
    with Image.open(tmp_path / "t.gif") as video:
        assert video.n_frames == 1
    assert _hidden(tmp_path) == []


def test_an_interrupted_time_lapse_leaves_the_previous_frames_and_video(capsys, tmp_path,
                                                                        monkeypatch):
    _timelapse(capsys, tmp_path, 2)
    frames = {p.name: p.read_bytes() for p in (tmp_path / "t_frames").iterdir()}
    video = (tmp_path / "t.gif").read_bytes()
    calls = []

    def interrupted_on_the_second_frame(index, *args):
        calls.append(index)
        if len(calls) == 2:
            raise KeyboardInterrupt

    real_timelapse = api.timelapse
    monkeypatch.setattr(api, "timelapse", lambda *a, **k: real_timelapse(
        *a, **{**k, "on_frame": interrupted_on_the_second_frame}))
    assert _timelapse(capsys, tmp_path, 3) == 130
    assert {p.name: p.read_bytes() for p in (tmp_path / "t_frames").iterdir()} == frames
    assert (tmp_path / "t.gif").read_bytes() == video
    assert _hidden(tmp_path) == []


# --- PNG + EXR under SIGTERM and SIGKILL -------------------------------------------------------

# `skyscatter render` whose EXR write stops half way (the time a large EXR takes to write)
_SLOW_EXR_RENDER = """
import sys, time
import OpenEXR
from skyscatter.cli import main

flag = sys.argv[1]

class SlowFile:
    def __init__(self, header, channels):
        pass

    def write(self, path):
        with open(path, "wb") as stream:
            stream.write(b"v/1\\x01half an EXR")
        open(flag, "w").close()
        time.sleep(60)

OpenEXR.File = SlowFile
sys.exit(main(sys.argv[2:]))
"""


@pytest.fixture
def old_pair(capsys, tmp_path):
    """out/sky.png + out/sky.exr from a first render (sun 30 deg up) and their bytes."""
    png, exr = tmp_path / "out" / "sky.png", tmp_path / "out" / "sky.exr"
    code, _, err = run_cli(capsys, ["render", "earth", *SMALL, "-o", str(png), "--exr", str(exr)])
    assert code == 0, err
    return png, exr, png.read_bytes(), exr.read_bytes()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_a_render_killed_while_writing_leaves_the_old_pair(capsys, tmp_path, old_pair, sig):
    # Before: SIGKILL left a new PNG beside the old EXR and hidden temporaries that nothing
    # removed; SIGTERM left the temporaries too.
    png, exr, png_bytes, exr_bytes = old_pair
    flag = tmp_path / "writing"
    child = subprocess.Popen([sys.executable, "-c", _SLOW_EXR_RENDER, str(flag), "render",
                              "earth", *SMALL, "--sun-elevation", "10", "-o", str(png),
                              "--exr", str(exr)], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120.0
    while not flag.exists() and child.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert flag.exists(), child.stderr.read()
    child.send_signal(sig)
    code, stderr = child.wait(timeout=60), child.stderr.read()
    assert png.read_bytes() == png_bytes and exr.read_bytes() == exr_bytes
    if sig == signal.SIGTERM:
        assert code == 143 and _one_line(stderr) == "skyscatter: terminated"
        assert _hidden(png.parent) == []
    else:
        assert code == -signal.SIGKILL and len(_hidden(png.parent)) == 2
    # the next run sweeps the dead writer's temporaries and replaces both files
    code, _, err = run_cli(capsys, ["render", "earth", *SMALL, "--sun-elevation", "10",
                                 "-o", str(png), "--exr", str(exr)])
    assert code == 0, err
    assert sorted(os.listdir(png.parent)) == ["sky.exr", "sky.png"]
    assert png.read_bytes() != png_bytes and exr.read_bytes() != exr_bytes
    assert read_exr(exr)[0].shape == (8, 8, 3)


def test_validate_refuses_a_read_only_report_folder_before_the_suite(tmp_path):
    read_only = tmp_path / "ro"
    read_only.mkdir(mode=0o555)
    result = subprocess.run([*unprivileged_prefix(), sys.executable, "-m", "skyscatter.cli",
                             "validate", "--quick", "--output", str(read_only / "report"),
                             "--cache-dir", str(tmp_path / "cache")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert _one_line(result.stderr) == (f"skyscatter: cannot write {read_only}/report/report.md: "
                                        f"Permission denied (in {read_only})")
    assert sorted(os.listdir(tmp_path)) == ["ro"]
