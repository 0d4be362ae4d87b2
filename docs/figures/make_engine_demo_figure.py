"""The engine demo page (docs/engine_demo) in headless Chromium for docs/engines.md: a cube map
from `skyscatter render` as the background of a plain WebGL2 page and the light file lighting a
diffuse sphere.

Run: PYTHONPATH=src python docs/figures/make_engine_demo_figure.py
(needs Debian's chromium and playwright; renders a 64-pixel cube map with Earth's tables, from
the table cache or computed first, about a minute.)
"""

from __future__ import annotations

import functools
import http.server
import shutil
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--force-color-profile=srgb"]
RENDER = ["render", "earth", "--camera", "cubemap", "--size", "64", "--sun-elevation", "30",
          "--sun-azimuth", "135", "--no-sun-disk", "--exr", "sky.hdr", "--light", "light.json",
          "-o", "sky.png"]


def main() -> None:
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        for name in ("index.html", "engine_demo.js"):
            shutil.copy(DOCS / "engine_demo" / name, root / name)
        subprocess.run([sys.executable, "-m", "skyscatter.cli", *RENDER], cwd=root, check=True)
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
    main()
