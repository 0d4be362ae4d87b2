"""Screenshots of the real-time viewer for the README and docs/viewer.md: the page with its
controls in headless Chromium (SwiftShader), as a user sees it.

Run: PYTHONPATH=src python docs/figures/make_viewer_figures.py
(needs Debian's chromium and playwright; the full Earth tables come from the table cache or are
computed first, about a minute.)
"""

from __future__ import annotations

import shutil
import threading
from pathlib import Path

from skyscatter import api

IMAGES = Path(__file__).resolve().parents[1] / "images"
FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--force-color-profile=srgb"]
SHOTS = {
    "viewer_earth.png": "atmosphere=earth&quality=full&sun_zenith=86&sun_azimuth=255"
                        "&heading=250&pitch=8&fov=75&altitude_m=2",
    "viewer_mars_orbit.png": "atmosphere=mars-physical&quality=preview&sun_zenith=50"
                             "&sun_azimuth=90&heading=0&pitch=-22&fov=70&altitude_m=300000",
    "viewer_night.png": "atmosphere=earth&quality=full&projection=fisheye&altitude_m=0"
                        "&time=2024-07-05T06:00Z&lat=-29.26&lon=-70.73&ev100=-6",
}


def main() -> None:
    from playwright.sync_api import sync_playwright

    server = api.viewer_server("earth")
    threading.Thread(target=server.serve_forever, daemon=True).start()
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=shutil.which("chromium"),
                                             args=FLAGS)
        page = browser.new_page(viewport={"width": 1280, "height": 720})
        page.set_default_timeout(900_000)
        for name, query in SHOTS.items():
            quality = "full" if "quality=full" in query else "preview"
            page.goto(f"{server.url}&{query}")
            page.wait_for_function(f"document.body.dataset.tables === '{quality}'")
            page.wait_for_timeout(1500)  # the automatic exposure settles
            page.screenshot(path=str(IMAGES / name))
            print(IMAGES / name)
        browser.close()
    server.shutdown()


if __name__ == "__main__":
    main()
