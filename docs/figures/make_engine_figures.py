"""Pictures for docs/engines.md: the engine demo page (docs/engine_demo) in headless Chromium,
a cube map from `skyscatter render` as the background of a plain WebGL2 page and the light
file lighting a diffuse sphere (engine_demo.png); a sphere map and a dual paraboloid map of the
same sky side by side (disk_maps.png).

Run: PYTHONPATH=src python docs/figures/make_engine_figures.py [engine_demo.png|disk_maps.png]
(the demo needs Debian's chromium and playwright; Earth's tables come from the table cache or
are computed first, about a minute.)
"""

from __future__ import annotations

import functools
import http.server
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--force-color-profile=srgb"]
RENDER = ["earth", "--camera", "cubemap", "--size", "64", "--sun-elevation", "30",
          "--sun-azimuth", "135", "--no-sun-disk", "--exr", "sky.hdr", "--light", "light.json",
          "-o", "sky.png"]


DISK_MAPS = ["earth", "--size", "160", "--sun-elevation", "20", "--sun-azimuth", "240",
             "--clouds", "cumulus"]


def _render(arguments: list[str], folder: Path) -> None:
    source = str(DOCS.parent / "src")  # this checkout's package, from any folder
    subprocess.run([sys.executable, "-m", "skyscatter.cli", "render", *arguments], cwd=folder,
                   check=True, env={**os.environ, "PYTHONPATH": source})


def disk_maps() -> None:
    """The sphere map (left) and the dual paraboloid map of one sky, 8 pixels apart."""
    from PIL import Image

    with tempfile.TemporaryDirectory() as folder:
        _render([*DISK_MAPS, "--camera", "sphere", "-o", "sphere.png"], Path(folder))
        _render([*DISK_MAPS, "--camera", "paraboloid", "-o", "paraboloid.png"], Path(folder))
        sphere, paraboloid = (Image.open(Path(folder) / name) for name in
                              ("sphere.png", "paraboloid.png"))
        sheet = Image.new("RGB", (sphere.width + 8 + paraboloid.width, sphere.height), "white")
        sheet.paste(sphere, (0, 0))
        sheet.paste(paraboloid, (sphere.width + 8, 0))
        sheet.save(DOCS / "images" / "disk_maps.png")
    print(DOCS / "images" / "disk_maps.png")


def engine_demo() -> None:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        for name in ("index.html", "engine_demo.js"):
            shutil.copy(DOCS / "engine_demo" / name, root / name)
        _render(RENDER, root)
        handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=folder)
        server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=shutil.which("chromium"),
                                                 args=FLAGS)
            page = browser.new_page(viewport={"width": 480, "height": 320})
            page.goto(f"http://127.0.0.1:{server.server_address[1]}/index.html")
            page.wait_for_function("document.body.dataset.ready === '1'")
            page.locator("#view").screenshot(path=str(DOCS / "images" / "engine_demo.png"))
            browser.close()
        server.shutdown()
    print(DOCS / "images" / "engine_demo.png")


if __name__ == "__main__":
    FIGURES = {"engine_demo.png": engine_demo, "disk_maps.png": disk_maps}
    for name in sys.argv[1:] or FIGURES:
        FIGURES[name]()
