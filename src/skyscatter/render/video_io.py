"""Write image sequences as animations: MP4 (H.264) and GIF, atomically.

- MP4: frames are piped to the ffmpeg executable that the `imageio-ffmpeg` wheel ships (no
  system ffmpeg needed), H.264 in yuv420p so that every player opens it. yuv420p needs even
  sizes, so an odd last row or column is dropped. imageio-ffmpeg is the optional `[video]`
  extra: without it an .mp4 target is refused before any frame is rendered.
- GIF: Pillow, one 256-colour palette per frame, looping forever.

Both write to a temporary file beside the target and rename it when complete, so an
interrupted time-lapse never leaves a half-written video under the final name
(`skyscatter.output_files`); given a `StagedOutputs`, the writer leaves the rename to its
owner, which replaces the video together with other outputs (the frames). Frames arrive one
at a time (`VideoWriter.add`), so a long sequence is never held in memory as a whole (GIF
keeps Pillow's palettised frames, 1 byte per pixel).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image

from skyscatter.errors import InputError
from skyscatter.output_files import StagedOutputs

__all__ = ["VIDEO_FORMATS", "VideoWriter", "video_format"]

VIDEO_FORMATS = ("mp4", "gif")


def video_format(path: str | os.PathLike[str]) -> str:
    """"mp4" or "gif" from the file name's suffix; InputError for anything else."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in VIDEO_FORMATS:
        raise InputError(f"cannot tell the video format of {str(path)!r}; name it .mp4 or .gif",
                         key="video", value=str(path), allowed=", ".join(VIDEO_FORMATS))
    return suffix


class VideoWriter:
    """Collects 8-bit sRGB frames (h, w, 3) and writes `path` (.mp4 or .gif) on `close`.

    Use as a context manager; if the block raises, nothing is written under `path`. With
    `stage`, the video is written to that stage's temporary and moved onto `path` when the
    stage commits; without, `close` moves it there.
    """

    def __init__(self, path: str | os.PathLike[str], fps: float,
                 stage: StagedOutputs | None = None) -> None:
        self.path = Path(path)
        self.format = video_format(self.path)
        if not (np.isfinite(fps) and 0.1 <= fps <= 120.0):
            raise InputError(f"fps = {fps!r} must lie in [0.1, 120]", key="fps", value=fps,
                             allowed="[0.1, 120]")
        self.fps = float(fps)
        if self.format == "mp4":
            try:
                import imageio_ffmpeg  # noqa: F401 - the optional [video] extra
            except ImportError:
                raise InputError(f"cannot write {self.path}: MP4 needs `pip install "
                                 "skyscatter[video]` (imageio-ffmpeg); or name it .gif",
                                 key="video", value=str(self.path)) from None
        self._own_stage = stage is None
        self._stage = StagedOutputs() if stage is None else stage
        self._gif_frames: list[Image.Image] = []
        self._ffmpeg = None
        self._size: tuple[int, int] | None = None

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, kind, value, traceback) -> None:
        if kind is None:
            self.close()
        else:
            self._abort()

    def add(self, rgb8: np.ndarray) -> None:
        """Append one frame (h, w, 3) uint8; every frame must have the first one's size."""
        frame = np.asarray(rgb8)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
            raise InputError(f"a video frame must be (h, w, 3) uint8; got {frame.shape} "
                             f"{frame.dtype}", key="frame", value=frame.shape)
        if self._size is None:
            self._size = frame.shape[:2]
        elif frame.shape[:2] != self._size:
            raise InputError(f"video frames must all be {self._size}; got {frame.shape[:2]}",
                             key="frame", value=frame.shape[:2])
        if self.format == "gif":
            self._gif_frames.append(Image.fromarray(frame).quantize(colors=256))
        else:
            self._send_mp4(frame)

    def close(self) -> Path:
        """Finish the file and move it to `path` (with a `stage`: when that commits); returns
        `path`."""
        if self._size is None:
            raise InputError("no frames to write", key="video", value=str(self.path))
        try:
            if self.format == "gif":
                first, rest = self._gif_frames[0], self._gif_frames[1:]
                duration_ms = max(20, round(1000.0 / self.fps))
                self._stage.write(self.path, lambda tmp: first.save(
                    tmp, format="GIF", save_all=True, append_images=rest,
                    duration=duration_ms, loop=0, optimize=False))
                self._gif_frames = []
            else:
                ffmpeg, self._ffmpeg = self._ffmpeg, None
                ffmpeg.close()  # flushes and waits for ffmpeg
            if self._own_stage:
                self._stage.commit()
        except (OSError, RuntimeError) as error:
            self._abort()
            raise InputError(f"cannot write {self.path}: {error}", key="video",
                             value=str(self.path)) from error
        except BaseException:
            self._abort()
            raise
        return self.path

    def _send_mp4(self, frame: np.ndarray) -> None:
        height, width = (n - n % 2 for n in frame.shape[:2])  # yuv420p: even sizes
        if self._ffmpeg is None:
            import imageio_ffmpeg

            temporary = self._stage.reserve(self.path)  # no .mp4 suffix: say the format
            self._ffmpeg = imageio_ffmpeg.write_frames(
                str(temporary), (width, height), fps=self.fps, codec="libx264",
                pix_fmt_in="rgb24", pix_fmt_out="yuv420p", quality=8, macro_block_size=1,
                ffmpeg_log_level="error", output_params=["-f", "mp4"])
            self._ffmpeg.send(None)  # start the generator
        self._ffmpeg.send(np.ascontiguousarray(frame[:height, :width]))

    def _abort(self) -> None:
        self._gif_frames = []
        try:
            if self._ffmpeg is not None:
                self._ffmpeg.close()
        finally:
            if self._own_stage:
                self._stage.discard()
