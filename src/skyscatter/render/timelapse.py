"""A time-lapse: one sky image per observer time, each written as a PNG frame and a video frame,
the exposure adapting from frame to frame (`exposure.frame_ev100`).

The caller renders (`render_frame`, which reuses one solver's tables for every frame), stages
the outputs and opens the video (`render.video_io.VideoWriter`); this module runs the loop.
"""

from __future__ import annotations

import datetime
from collections.abc import Callable, Sequence
from pathlib import Path

from skyscatter.render.exposure import display_rgb8, frame_ev100
from skyscatter.render.image_io import write_png
from skyscatter.render.scene import SkyImage
from skyscatter.render.sky_at_time import Observer
from skyscatter.render.video_io import VideoWriter
from skyscatter.spectrum.colour import xyz_to_rgb

__all__ = ["write_frames"]


def write_frames(render_frame: Callable[[Observer], SkyImage], observers: Sequence[Observer],
                 video: VideoWriter, staged_dir: Path, frames_dir: Path, *,
                 compensation_ev: float, operator: str, colour_space: str,
                 adaptation_time_s: float,
                 on_frame: Callable[[int, datetime.datetime, float], None] | None = None,
                 ) -> tuple[list[Path], list[float]]:
    """Render each of `observers` with `render_frame`, write it as `staged_dir/frame_00001.png`
    ... (with its EV100 and time in the PNG text) and add it to `video`; returns the frames'
    paths under `frames_dir` (where `staged_dir` ends up) and their EV100s. The exposure
    follows the night-adapted meter with time constant `adaptation_time_s` [s] of simulated
    time; `compensation_ev`, `operator` and `colour_space` as `exposure.display_rgb8` and
    `spectrum.colour.xyz_to_rgb`. `on_frame(index, time, ev100)` is called after each frame."""
    frames, exposures = [], []
    ev100 = None
    for index, observer in enumerate(observers):
        image = render_frame(observer)
        xyz = image.xyz()
        elapsed = ((observer.time_utc - observers[index - 1].time_utc).total_seconds()
                   if index else 0.0)
        ev100 = frame_ev100(ev100, image, xyz, elapsed, adaptation_time_s)
        rgb8 = display_rgb8(xyz_to_rgb(xyz, colour_space), image.valid, ev100,
                            compensation_ev, operator)
        name = f"frame_{index + 1:05d}.png"
        write_png(staged_dir / name, rgb8,
                  text={"Software": "skyscatter", "EV100": f"{ev100:.3f}",
                        "Time": observer.time_utc.isoformat()}, colour_space=colour_space)
        video.add(rgb8)
        frames.append(frames_dir / name)
        exposures.append(ev100)
        if on_frame is not None:
            on_frame(index, observer.time_utc, ev100)
    return frames, exposures
