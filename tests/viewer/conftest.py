"""Fixtures of the browser tests: the viewer's server in a thread and a headless Debian
Chromium (SwiftShader WebGL2) driven by Playwright.

`make test` installs chromium (apt) and sets SKYSCATTER_REQUIRE_BROWSER=1, so there a missing
browser fails the tests; elsewhere (a developer without root) they are skipped with the reason.
"""

from __future__ import annotations

import os
import shutil
import threading

import pytest

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader", "--disable-gpu-vsync",
                  "--force-color-profile=srgb", "--disable-background-networking",
                  "--disable-component-update", "--no-first-run"]
PAGE_TIMEOUT_MS = 120_000  # a preview table set takes 2-5 s on 2 cores, SwiftShader frames ~1 s


def chromium_path() -> str | None:
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _browser_or_skip():
    missing = []
    path = chromium_path()
    if path is None:
        missing.append("chromium (apt-get install chromium)")
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        sync_playwright = None
        missing.append("playwright (pip install playwright)")
    if missing:
        message = "browser tests need " + " and ".join(missing)
        if os.environ.get("SKYSCATTER_REQUIRE_BROWSER") == "1":
            pytest.fail(message)
        pytest.skip(message)
    return path, sync_playwright


@pytest.fixture(scope="session")
def viewer_url(tmp_path_factory):
    """URL of a viewer server (earth first) with its own table cache, and the server."""
    from skyscatter import api
    server = api.viewer_server("earth", cache_dir=tmp_path_factory.mktemp("viewer-cache"))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server
    server.shutdown()
    server.server_close()


@pytest.fixture(scope="session")
def browser():
    path, sync_playwright = _browser_or_skip()
    with sync_playwright() as playwright:
        instance = playwright.chromium.launch(executable_path=path, args=CHROMIUM_FLAGS)
        yield instance
        instance.close()


@pytest.fixture()
def page(browser):
    """A fresh page; its console errors and uncaught exceptions are in `page.errors`."""
    context = browser.new_context(viewport={"width": 1000, "height": 800},
                                  device_scale_factor=1)
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    page.on("console", lambda message: message.type == "error"
            and page.errors.append(message.text))
    page.set_default_timeout(PAGE_TIMEOUT_MS)
    yield page
    context.close()
