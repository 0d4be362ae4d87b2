"""Make docs/techniques.md's picture (docs/images/techniques_fisheye.png): the earth preset seen
by each fast solver beside the "lut" tables, one fisheye each, side by side, with the command
line; run from the repo root: python docs/figures/make_technique_figures.py"""

from __future__ import annotations

import tempfile
from pathlib import Path

from PIL import Image

from skyscatter.cli import main

IMAGES = Path(__file__).resolve().parents[1] / "images"
SOLVERS = ("lut", "hillaire", "schuler", "bruneton-simplified", "cie", "preetham")
SIZE = 240


def make() -> None:
    IMAGES.mkdir(parents=True, exist_ok=True)
    strip = Image.new("RGB", (SIZE * len(SOLVERS), SIZE))
    with tempfile.TemporaryDirectory() as folder:
        for k, solver in enumerate(SOLVERS):
            path = Path(folder) / f"{solver}.png"
            code = main(["render", "earth", "--solver", solver, "--size", str(SIZE),
                         "--sun-elevation", "30", "-o", str(path)])
            if code:
                raise SystemExit(code)
            with Image.open(path) as image:
                strip.paste(image.convert("RGB"), (SIZE * k, 0))
    target = IMAGES / "techniques_fisheye.png"
    strip.save(target.with_suffix(".tmp.png"), optimize=True)
    target.with_suffix(".tmp.png").replace(target)
    print(f"wrote {target}")


if __name__ == "__main__":
    make()
