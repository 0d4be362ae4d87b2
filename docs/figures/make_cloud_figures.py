"""Make the cloud pictures of docs/clouds.md (docs/images/clouds_*.png) and docs/engines.md's
cube map with the command line;
run from the repo root: python docs/figures/make_cloud_figures.py [NAME ...]"""

from __future__ import annotations

import sys
from pathlib import Path

from skyscatter.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "images"
WIDE = ["--camera", "perspective", "--fov", "75", "--aspect", "1.7778", "--size", "360"]
FIGURES = {
    "clouds_cumulus_noon.png": ["earth", "--clouds", "cumulus", *WIDE, "--heading", "150",
                                "--pitch", "12", "--altitude", "2", "--sun-elevation", "55",
                                "--sun-azimuth", "160"],
    "clouds_cumulus_sunset.png": ["earth", "--clouds", "cumulus", *WIDE, "--heading", "250",
                                  "--pitch", "10", "--altitude", "2", "--sun-elevation", "3",
                                  "--sun-azimuth", "255"],
    "clouds_cumulus_above.png": ["earth", "--clouds", "cumulus", *WIDE, "--heading", "150",
                                 "--pitch", "-25", "--altitude", "6000", "--sun-elevation",
                                 "40", "--sun-azimuth", "135"],
    "clouds_mountains.png": ["earth", "--clouds", "altocumulus", "--terrain", "demo", *WIDE,
                             "--heading", "180", "--pitch", "4", "--altitude", "300",
                             "--sun-elevation", "35", "--sun-azimuth", "200"],
    "clouds_altocumulus_sunset.png": ["earth", "--clouds", "altocumulus", *WIDE, "--heading",
                                      "270", "--pitch", "20", "--altitude", "2",
                                      "--sun-elevation", "1", "--sun-azimuth", "265"],
    "clouds_stratus.png": ["earth", "--clouds", "stratus", "--size", "320", "--altitude", "2",
                           "--sun-elevation", "50"],
    "clouds_cirrus.png": ["earth", "--clouds", "cirrus", "--size", "320", "--altitude", "2",
                          "--sun-elevation", "35"],
    "clouds_orbit.png": ["earth", "--clouds", "earth-weather", "--camera", "orbit",
                         "--distance-km", "20000", "--lat", "20", "--lon", "-30",
                         "--sun-elevation", "40", "--sun-azimuth", "100", "--size", "400",
                         "--albedo-map", str(IMAGES / "demo_albedo.png")],
    "cubemap_cross.png": ["earth", "--camera", "cubemap", "--size", "160", "--sun-elevation", "8",
                          "--sun-azimuth", "240", "--clouds", "cumulus"],
    "clouds_stratocumulus_moonlit.png": ["earth", "--clouds", "stratocumulus", "--time",
                                         "2024-01-25T23:00+01:00", "--lat", "52.52", "--lon",
                                         "13.40", "--size", "320", "--altitude", "2"],
}


def make(names: list[str]) -> None:
    IMAGES.mkdir(parents=True, exist_ok=True)
    for name in names or FIGURES:
        print(name, flush=True)
        code = main(["render", *FIGURES[name], "-o", str(IMAGES / name)])
        if code:
            raise SystemExit(code)


if __name__ == "__main__":
    make(sys.argv[1:])
