"""The video writer: files that other readers open with the frames we sent, written atomically."""

import sys

import numpy as np
import pytest
from PIL import Image

from cli_runner import run_cli
from skyscatter.errors import InputError
from skyscatter.render.video_io import VideoWriter, video_format


def _frames(count, height=33, width=48):
    rng = np.random.default_rng(1)
    base = rng.integers(0, 255, size=(height, width, 3), dtype=np.uint8)
    return [np.roll(base, 3 * i, axis=1) for i in range(count)]


def test_gif_holds_every_frame_and_loops(tmp_path):
    path = tmp_path / "sky.gif"
    frames = _frames(5)
    with VideoWriter(path, fps=10) as video:
        for frame in frames:
            video.add(frame)
    with Image.open(path) as gif:  # Pillow reads it back: frame count, size, timing
        assert gif.n_frames == 5
        assert gif.size == (48, 33)
        assert gif.info["duration"] == 100
        assert gif.info["loop"] == 0


def test_mp4_is_read_back_by_ffmpeg_with_even_size(tmp_path):
    import imageio_ffmpeg

    path = tmp_path / "sky.mp4"
    frames = [np.full((33, 48, 3), 40 * i, dtype=np.uint8) for i in range(6)]
    with VideoWriter(path, fps=12) as video:
        for frame in frames:
            video.add(frame)
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    assert tuple(meta["size"]) == (48, 32)  # yuv420p drops the odd last row
    decoded = [np.frombuffer(f, dtype=np.uint8).reshape(32, 48, 3) for f in reader]
    assert len(decoded) == 6
    # H.264 is lossy: flat grey frames come back within a few codes of what was sent
    for sent, got in zip(frames, decoded, strict=True):
        assert abs(float(got.mean()) - float(sent[:32].mean())) < 4.0
    assert not list(tmp_path.glob(".*partial*"))


def test_failure_leaves_no_file_and_bad_input_is_named(tmp_path):
    path = tmp_path / "broken.mp4"
    with pytest.raises(RuntimeError), VideoWriter(path, fps=12) as video:
        video.add(_frames(1)[0])
        raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(InputError, match=r"\.mp4 or \.gif"):
        video_format(tmp_path / "sky.avi")
    with pytest.raises(InputError, match="fps"):
        VideoWriter(tmp_path / "a.gif", fps=0)
    with VideoWriter(tmp_path / "a.gif", fps=5) as video, pytest.raises(InputError,
                                                                         match="frames must"):
        video.add(_frames(1)[0])
        video.add(_frames(1, height=10)[0])


def test_mp4_without_the_video_extra_is_refused_in_one_line(tmp_path, monkeypatch, capsys):
    """imageio-ffmpeg is the [video] extra: without it (None in sys.modules makes its import
    fail as a missing package does) an .mp4 is refused before any frame, a .gif still works."""
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    with pytest.raises(InputError, match=r"MP4 needs `pip install skyscatter\[video\]`"):
        VideoWriter(tmp_path / "sky.mp4", fps=10)
    code, _, err = run_cli(capsys, [
        "timelapse", "earth", "--start", "2024-06-21T20:30+02:00", "--end",
        "2024-06-21T21:30+02:00", "--frames", "2", "--lat", "52.5", "--lon", "13.4",
        "--size", "8", "-o", str(tmp_path / "sky.mp4")])
    assert code == 2
    assert err.count("\n") == 1 and "pip install skyscatter[video]" in err
    assert not any(tmp_path.iterdir())  # refused before any work
    with VideoWriter(tmp_path / "sky.gif", fps=10) as video:
        video.add(_frames(1)[0])
    assert (tmp_path / "sky.gif").is_file()
