"""Make the pictures of docs/physics/tables.md (docs/images/tables_*.png) with the command line:
the same sunset panorama with single scattering (ray marched) and with the precomputed tables
(4 orders). Run from the repo root: python docs/figures/tables_figures.py"""

from __future__ import annotations

import sys
from pathlib import Path

from skyscatter.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "images"
SCENE = ["earth", "--sun-elevation", "4", "--sun-azimuth", "270", "--camera", "panorama",
         "--heading", "270", "--size", "160", "--exposure", "12"]
FIGURES = {
    "tables_sunset_single.png": [*SCENE, "--solver", "single"],
    "tables_sunset_lut.png": [*SCENE, "--solver", "lut"],
}

if __name__ == "__main__":
    for name, arguments in FIGURES.items():
        argv = ["render", *arguments, "-o", str(IMAGES / name)]
        print("skyscatter " + " ".join(argv))
        if main(argv) != 0:
            sys.exit(1)
