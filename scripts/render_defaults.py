"""Render the shipped default scenes into a folder (what `make run` does).

Earth at noon, Earth at sunset (fisheye + equirectangular panorama), mountains fading into
the haze, Earth from space, Mars (gas and hematite-bearing Mie dust from physical parameters)
in the afternoon and at sunset with its blue glow, altocumulus at sunset with their shadows in
the air, the sky over Berlin at a date (21 June 2024,
21:30: sunset glow in the north-west; and a full-moon night with every star), all with multiple
scattering from the precomputed tables (computed once per atmosphere, then reused from the
cache): tone-mapped PNGs and linear EXRs (linear sRGB, 1.0 = 1 cd m^-2); and a short time-lapse
of that summer evening (GIF plus frames). Each line printed names the command-line equivalent,
so every picture can be made again by hand.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from skyscatter.cli import main

SCENES = [
    ("earth_noon", ["earth", "--sun-elevation", "60", "--sun-azimuth", "180"]),
    ("earth_sunset", ["earth", "--sun-elevation", "2", "--sun-azimuth", "270"]),
    ("earth_sunset_panorama", ["earth", "--sun-elevation", "2", "--sun-azimuth", "270",
                               "--camera", "panorama", "--heading", "270", "--size", "512"]),
    ("earth_mountains", ["earth", "--sun-elevation", "12", "--sun-azimuth", "235",
                         "--camera", "perspective", "--heading", "180", "--pitch", "3",
                         "--fov", "50", "--size", "540", "--altitude", "300",
                         "--terrain", "demo"]),
    ("earth_from_space", ["earth", "--camera", "orbit", "--distance-km", "20000", "--lat",
                          "30", "--sun-elevation", "15", "--sun-azimuth", "90"]),
    ("earth_altocumulus_sunset", ["earth", "--clouds", "altocumulus", "--camera", "perspective",
                                  "--fov", "75", "--aspect", "1.7778", "--size", "360",
                                  "--heading", "270", "--pitch", "20", "--altitude", "2",
                                  "--sun-elevation", "1", "--sun-azimuth", "265"]),
    ("mars_afternoon", ["mars-physical", "--sun-elevation", "35", "--sun-azimuth", "240"]),
    ("mars_sunset_glow", ["mars-physical", "--sun-elevation", "2", "--sun-azimuth", "270",
                          "--camera", "perspective", "--heading", "270", "--pitch", "20",
                          "--fov", "70", "--exposure", "16", "--tonemap", "reinhard"]),
    ("berlin_2024-06-21_2130", ["earth", "--time", "2024-06-21T21:30+02:00", "--lat", "52.52",
                                "--lon", "13.40", "--camera", "panorama", "--heading", "315",
                                "--size", "384"]),
    ("berlin_full_moon_night", ["earth", "--time", "2024-01-25T23:00+01:00", "--lat", "52.52",
                                "--lon", "13.40", "--size", "768"]),
]
TIMELAPSE = ["earth", "--start", "2024-06-21T20:30+02:00", "--end", "2024-06-22T00:30+02:00",
             "--step", "10min", "--lat", "52.52", "--lon", "13.40", "--size", "192", "--fps",
             "8", "--twinkle", "1"]


def render_all(folder: Path) -> int:
    folder.mkdir(parents=True, exist_ok=True)
    for name, arguments in SCENES:
        argv = ["render", *arguments, "-o", str(folder / f"{name}.png"),
                "--exr", str(folder / f"{name}.exr")]
        print("skyscatter " + " ".join(argv), flush=True)
        start = time.perf_counter()
        code = main(argv)
        if code != 0:
            return code
        print(f"  {time.perf_counter() - start:.1f} s", flush=True)
    argv = ["timelapse", *TIMELAPSE, "-o", str(folder / "berlin_evening.gif")]
    print("skyscatter " + " ".join(argv), flush=True)
    start = time.perf_counter()
    code = main(argv)
    print(f"  {time.perf_counter() - start:.1f} s", flush=True)
    return code


if __name__ == "__main__":
    sys.exit(render_all(Path(sys.argv[1] if len(sys.argv) > 1 else "out")))
