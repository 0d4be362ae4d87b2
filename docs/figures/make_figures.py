"""Make every picture in the docs (docs/images/*.png) with the command line; run from the
repo root: python docs/figures/make_figures.py

README pictures, and for docs/physics/tables.md the same sunset panorama with single scattering
(ray marched) and with the precomputed tables (4 orders)."""

from __future__ import annotations

import sys
from pathlib import Path

from skyscatter.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "images"
TABLES_SCENE = ["earth", "--sun-elevation", "4", "--sun-azimuth", "270", "--camera",
                "panorama", "--heading", "270", "--size", "160", "--exposure", "12"]
FIGURES = {
    "earth_noon.png": ["earth", "--sun-elevation", "60", "--size", "256"],
    "earth_sunset.png": ["earth", "--sun-elevation", "2", "--sun-azimuth", "270", "--size",
                         "256"],
    "earth_sunset_panorama.png": ["earth", "--sun-elevation", "2", "--sun-azimuth", "270",
                                  "--camera", "panorama", "--heading", "270", "--size", "192"],
    "mars_afternoon.png": ["mars-costa", "--sun-elevation", "35", "--sun-azimuth", "240",
                           "--size", "256"],
    "earth_from_space.png": ["earth", "--camera", "orbit", "--distance-km", "20000", "--lat",
                             "30", "--sun-elevation", "15", "--sun-azimuth", "90", "--size",
                             "256"],
    "tables_sunset_single.png": [*TABLES_SCENE, "--solver", "single"],
    "tables_sunset_lut.png": [*TABLES_SCENE, "--solver", "lut"],
}

if __name__ == "__main__":
    for name, arguments in FIGURES.items():
        argv = ["render", *arguments, "-o", str(IMAGES / name)]
        print("skyscatter " + " ".join(argv))
        if main(argv) != 0:
            sys.exit(1)
