"""Output files: checked before work, replaced together, no temporaries left behind.

Observables only: the bytes of the files in a folder, its listing, exit codes of processes
killed mid-write, and error messages naming the path.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from failing_exr import FailingExrFile
from PIL import Image

from skyscatter import api, output_files
from skyscatter.errors import InputError
from skyscatter.output_files import (
    TEMPORARY_NAME,
    check_writable_file,
    check_writable_folder,
    staged_outputs,
    sweep_stale_temporaries,
    temporary_path,
)
from skyscatter.render import image_io
from skyscatter.render.image_io import read_exr, write_png
from skyscatter.render.scene import SkyImage

DAY_S = 86400.0


def _dead_pid() -> int:
    """The pid of a process that has finished (and been reaped)."""
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def _sky_image(radiance: float) -> SkyImage:
    """A 4 x 6 sky of uniform spectral radiance [W m^-2 sr^-1 nm^-1] on 3 wavelengths."""
    wavelengths = np.array([450.0, 550.0, 650.0])
    return SkyImage(spectral=np.full((4, 6, 3), radiance), valid=np.ones((4, 6), bool),
                    sky=np.ones((4, 6), bool), wavelengths_nm=wavelengths,
                    light_spectrum=np.full(3, 1.8))


def _hidden(folder) -> list[str]:
    return sorted(name for name in os.listdir(folder) if name.startswith("."))


# --- names and the sweep ----------------------------------------------------------------------

def test_temporaries_are_hidden_beside_the_target_and_carry_our_pid(tmp_path):
    temporary = temporary_path(tmp_path / "sky.png")
    match = TEMPORARY_NAME.fullmatch(temporary.name)
    assert temporary.parent == tmp_path and temporary.name.startswith(".sky.png.")
    assert match is not None and int(match["pid"]) == os.getpid()
    assert temporary != temporary_path(tmp_path / "sky.png")  # a fresh name each time


def test_sweep_removes_only_our_temporaries_of_dead_or_day_old_writers(tmp_path):
    dead, alive = _dead_pid(), os.getppid()
    stale_file = tmp_path / f".sky.png.{dead}.0123abcd.tmp"
    stale_folder = tmp_path / f".sky_frames.{dead}.89abcdef.tmp"
    old_but_alive = tmp_path / f".sky.exr.{alive}.00000000.tmp"
    young_and_alive = tmp_path / f".sky.exr.{alive}.11111111.tmp"
    ours = temporary_path(tmp_path / "sky.png")
    users = [tmp_path / ".sky.png.bak", tmp_path / f"sky.png.{dead}.0123abcd.tmp",
             tmp_path / f".sky.png.{dead}.tmp", tmp_path / "notes.tmp"]
    for path in [stale_file, old_but_alive, young_and_alive, ours, *users]:
        path.write_bytes(b"x")
    stale_folder.mkdir()
    (stale_folder / "frame_00001.png").write_bytes(b"x")
    os.utime(old_but_alive, (time.time() - 2 * DAY_S,) * 2)
    removed = sweep_stale_temporaries(tmp_path)
    assert sorted(removed) == sorted([stale_file, stale_folder, old_but_alive])
    assert sorted(os.listdir(tmp_path)) == sorted(p.name for p in [young_and_alive, ours, *users])


# --- checks before work -----------------------------------------------------------------------

def test_check_refuses_a_directory_and_a_file_in_the_way_naming_the_path(tmp_path):
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("x")
    with pytest.raises(InputError, match=r"cannot write .*adir: it is a directory"):
        check_writable_file(tmp_path / "adir")
    with pytest.raises(InputError, match=r"cannot write .*afile/sky\.png: Not a directory"):
        check_writable_file(tmp_path / "afile" / "sky.png")
    with pytest.raises(InputError, match=r"cannot write .*afile: it is a file; give a folder"):
        check_writable_folder(tmp_path / "afile", api.FRAME_NAME)


def test_check_accepts_missing_folders_and_creates_nothing(tmp_path):
    check_writable_file(tmp_path / "new" / "deeper" / "sky.png")
    check_writable_folder(tmp_path / "new" / "frames", api.FRAME_NAME)
    assert os.listdir(tmp_path) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write read-only files and folders")
def test_check_refuses_a_read_only_folder_and_file(tmp_path):
    (tmp_path / "ro").mkdir()
    (tmp_path / "sky.png").write_bytes(b"old")
    os.chmod(tmp_path / "sky.png", 0o444)
    os.chmod(tmp_path / "ro", 0o555)
    try:
        with pytest.raises(InputError, match=r"cannot write .*ro/sky\.png: Permission denied"):
            check_writable_file(tmp_path / "ro" / "sky.png")
        with pytest.raises(InputError, match=r"cannot write .*sky\.png: the file is read-only"):
            check_writable_file(tmp_path / "sky.png")
    finally:
        os.chmod(tmp_path / "ro", 0o755)


def test_a_frames_folder_with_other_files_is_refused_not_replaced(tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    (frames / "frame_00001.png").write_bytes(b"x")
    check_writable_folder(frames, api.FRAME_NAME)  # only frames: may be replaced
    (frames / "holiday.jpg").write_bytes(b"mine")
    with pytest.raises(InputError, match=r"frames: it holds other files \(holiday\.jpg\)"):
        check_writable_folder(frames, api.FRAME_NAME)


# --- a PNG and its EXR are replaced together ----------------------------------------------------

@pytest.fixture
def old_pair(tmp_path):
    """sky.png + sky.exr of a first save, and their bytes."""
    png, exr = tmp_path / "sky.png", tmp_path / "sky.exr"
    api.save_image(_sky_image(0.01), png, exr)
    return png, exr, png.read_bytes(), exr.read_bytes()


def test_a_failing_exr_write_leaves_the_old_png_and_exr(old_pair, monkeypatch):
    # Before: the PNG was replaced first, so a failed EXR left a new PNG beside the old EXR.
    png, exr, png_bytes, exr_bytes = old_pair
    monkeypatch.setattr(image_io.OpenEXR, "File", FailingExrFile)
    with pytest.raises(InputError, match=r"cannot write .*sky\.exr: No space left on device"):
        api.save_image(_sky_image(0.05), png, exr, ev100=10.0)
    assert png.read_bytes() == png_bytes and exr.read_bytes() == exr_bytes
    assert sorted(os.listdir(png.parent)) == ["sky.exr", "sky.png"]


def test_a_failing_png_write_leaves_the_old_png_and_exr(old_pair, monkeypatch):
    png, exr, png_bytes, exr_bytes = old_pair

    def failing_save(self, fp, *args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Image.Image, "save", failing_save)
    with pytest.raises(InputError, match=r"cannot write .*sky\.png: No space left on device"):
        api.save_image(_sky_image(0.05), png, exr, ev100=10.0)
    assert png.read_bytes() == png_bytes and exr.read_bytes() == exr_bytes
    assert sorted(os.listdir(png.parent)) == ["sky.exr", "sky.png"]


def test_a_successful_save_replaces_both(old_pair):
    png, exr, png_bytes, _ = old_pair
    old_rgb, _ = read_exr(exr)
    api.save_image(_sky_image(0.05), png, exr, ev100=10.0)
    assert png.read_bytes() != png_bytes
    # 5 times the radiance: the linear EXR holds 5 times the values (float32 rounding)
    np.testing.assert_allclose(read_exr(exr)[0], 5.0 * old_rgb, rtol=1e-6)


# --- folders are swapped whole ------------------------------------------------------------------

def test_a_staged_folder_replaces_the_old_one_whole_and_a_failure_keeps_it(tmp_path):
    frames = tmp_path / "frames"
    with staged_outputs() as stage:
        new = stage.folder(frames)
        for k in (1, 2, 3):
            write_png(new / f"frame_0000{k}.png", np.full((2, 2, 3), k, np.uint8))
    with pytest.raises(KeyboardInterrupt), staged_outputs() as stage:
        write_png(stage.folder(frames) / "frame_00001.png", np.zeros((2, 2, 3), np.uint8))
        raise KeyboardInterrupt
    assert sorted(os.listdir(frames)) == ["frame_00001.png", "frame_00002.png", "frame_00003.png"]
    with staged_outputs() as stage:
        write_png(stage.folder(frames) / "frame_00001.png", np.zeros((2, 2, 3), np.uint8))
    assert os.listdir(frames) == ["frame_00001.png"]  # exactly the last run's frames
    assert os.listdir(tmp_path) == ["frames"]


# --- killed writers -----------------------------------------------------------------------------

# A writer that stages a PNG, then an EXR that it writes half of and sleeps on (the window a
# real EXR write of a large image takes), as `skyscatter render` does under `main`.
_WRITER = """
import sys, time
import numpy as np
from skyscatter.output_files import sigterm_as_interrupt, staged_outputs
from skyscatter.render.image_io import display_image_writer

png, exr, flag = sys.argv[1:4]

def slow_exr(path):
    with open(path, "wb") as stream:
        stream.write(b"v/1\\x01half an EXR")
    open(flag, "w").close()
    time.sleep(60)

try:
    with sigterm_as_interrupt(), staged_outputs() as stage:
        stage.write(png, display_image_writer(np.full((4, 4, 3), 7, np.uint8)))
        stage.write(exr, slow_exr)
except KeyboardInterrupt:
    sys.exit(143)
"""


def _kill_mid_write(folder, sig: int) -> int:
    """Run `_WRITER` on folder/sky.png + sky.exr, send `sig` while it writes the EXR; its
    exit code."""
    flag = folder.parent / f"writing-{sig}"
    process = subprocess.Popen([sys.executable, "-c", _WRITER, str(folder / "sky.png"),
                                str(folder / "sky.exr"), str(flag)])
    deadline = time.monotonic() + 30.0
    while not flag.exists() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert flag.exists(), "the writer never reached its EXR"
    process.send_signal(sig)
    return process.wait(timeout=30)


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGKILL, -signal.SIGKILL),
                                           (signal.SIGTERM, 143)])
def test_a_writer_killed_mid_write_leaves_the_old_pair_and_the_next_run_sweeps(tmp_path, sig,
                                                                            code):
    folder = tmp_path / "out"
    folder.mkdir()
    (folder / "sky.png").write_bytes(b"old png")
    (folder / "sky.exr").write_bytes(b"old exr")
    assert _kill_mid_write(folder, sig) == code
    assert (folder / "sky.png").read_bytes() == b"old png"
    assert (folder / "sky.exr").read_bytes() == b"old exr"
    left = _hidden(folder)
    # SIGKILL: nothing runs, the two temporaries stay (named with the dead pid); SIGTERM: the
    # handler's exception removes them
    assert len(left) == (2 if sig == signal.SIGKILL else 0)
    write_png(folder / "sky.png", np.zeros((2, 2, 3), np.uint8))  # the next run
    assert _hidden(folder) == [] and sorted(os.listdir(folder)) == ["sky.exr", "sky.png"]


def test_signals_wait_until_the_renames_are_done(tmp_path, monkeypatch):
    # A SIGINT arriving between the renames is delivered after all of them (and the old folder
    # set aside is still removed).
    (tmp_path / "a.png").write_bytes(b"old a")
    (tmp_path / "b.png").write_bytes(b"old b")
    (tmp_path / "frames").mkdir()
    (tmp_path / "frames" / "frame_00001.png").write_bytes(b"old frame")
    real_replace = os.replace
    calls = []

    def replace_then_interrupt(source, target):
        real_replace(source, target)
        calls.append(target)
        if len(calls) == 1:
            signal.raise_signal(signal.SIGINT)

    monkeypatch.setattr(output_files.os, "replace", replace_then_interrupt)
    with pytest.raises(KeyboardInterrupt), staged_outputs() as stage:
        (stage.folder(tmp_path / "frames") / "frame_00002.png").write_bytes(b"new frame")
        stage.write(tmp_path / "a.png", lambda path: Path(path).write_bytes(b"new a"))
        stage.write(tmp_path / "b.png", lambda path: Path(path).write_bytes(b"new b"))
    assert (tmp_path / "a.png").read_bytes() == b"new a"
    assert (tmp_path / "b.png").read_bytes() == b"new b"
    assert os.listdir(tmp_path / "frames") == ["frame_00002.png"]
    assert _hidden(tmp_path) == []
