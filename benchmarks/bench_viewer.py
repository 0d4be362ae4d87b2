"""Benchmark: the real-time viewer in headless Chromium (issue 7's measurements).

1. Frame time at 1920 x 1080 (and a 1080 x 1080 fisheye): the page draws N frames back to
   back, each waited for with a 1-pixel readPixels (`window.skyscatter.benchmark`), with the
   preview tables and with the full `earth` tables (16 wavelengths, default sizes, 8 orders;
   from the table cache, computed first when missing: about a minute on 2 cores). In headless
   Chromium WebGL2 runs on SwiftShader, the CPU: these numbers are for the record, not a GPU's.
2. Time from a parameter change to the new image: the page changes the aerosol amount (or the
   ground albedo) and waits until the server has computed the preview tables, the page has
   fetched, decoded and uploaded them and drawn a frame (`viewer.lastChange`, measured in the
   page from the change to gl.finish after the draw, split into the table request and the
   upload + draw). Goal: under 3 s for Earth. On 2 cores the server's table computation and
   SwiftShader's drawing share the CPU.
3. Table message sizes and the server's peak resident memory.
4. Frame time with clouds at 1280 x 720 (issue 19): the cumulus and stratocumulus presets in
   CLOUD_VIEW (the view of tests/viewer/test_viewer_clouds.py), preview tables, the clouds'
   own ray march in the fragment shader (shaders/clouds.glsl); the cloud message's size.
   `--clouds-only` skips 1-3.
5. The fast model (Hillaire 2020 on the GPU, docs/viewer.md "Instant changes"): the time of
   each of its LUT passes (all wavelength groups, each waited for with a readPixels; median
   of --frames), its frame at 1920 x 1080, and the time from a parameter change to its image
   (`viewer.lastFastChange`: the LUTs made again and a frame drawn). `--fast-only` runs only
   this section.

Run: PYTHONPATH=src python benchmarks/bench_viewer.py [--frames 5] [--chromium PATH]
(needs Debian's chromium and `pip install playwright`; `make test` installs both.)
"""

from __future__ import annotations

import argparse
import resource
import shutil
import threading
import time

from skyscatter import api

FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
         "--disable-gpu-vsync", "--force-color-profile=srgb"]
VIEW = "sun_zenith=60&sun_azimuth=200&heading=180&pitch=10&fov=60&altitude_m=2&ev100=13"
CLOUD_VIEW = ("sun_zenith=35&sun_azimuth=160&heading=150&pitch=12&fov=75&altitude_m=2&lat=45"
              "&lon=0&ev100=13.5&cloud_time=600")
CLOUD_PRESETS = ("cumulus", "stratocumulus")


def main() -> None:
    from playwright.sync_api import sync_playwright

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--chromium", default=shutil.which("chromium"))
    parser.add_argument("--skip-full", action="store_true",
                        help="only the preview tables (no full Earth tables)")
    parser.add_argument("--clouds-only", action="store_true",
                        help="only the frame time with clouds (section 4)")
    parser.add_argument("--fast-only", action="store_true",
                        help="only the fast model (section 5)")
    parser.add_argument("--screenshot", default=None,
                        help="save the cumulus frame as this PNG (docs/images/viewer_clouds.png)")
    args = parser.parse_args()
    server = api.viewer_server("earth")
    threading.Thread(target=server.serve_forever, daemon=True).start()
    print(f"server {server.url}; chromium {args.chromium}")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=args.chromium, args=FLAGS)
        page = browser.new_page(viewport={"width": 1920, "height": 1080})
        page.set_default_timeout(900_000)
        renderer = None
        fast_model(page, server, args.frames)
        if args.fast_only:
            browser.close()
            server.shutdown()
            return
        for clouds in CLOUD_PRESETS:
            start = time.perf_counter()
            page.goto(f"{server.url}&controls=0&quality=preview&width=1280&height=720"
                      f"&clouds={clouds}&{CLOUD_VIEW}")
            page.wait_for_function(f"document.body.dataset.clouds === '{clouds}' && "
                                   "document.body.dataset.ready === '1'")
            loaded = time.perf_counter() - start
            ms = page.evaluate(f"window.skyscatter.benchmark({args.frames})")
            print(f"clouds {clouds:14s} perspective 1280x720: {ms:8.1f} ms per frame "
                  f"(preview tables), page ready in {loaded:.1f} s")
            if clouds == "cumulus" and args.screenshot:  # metered as `render` meters
                page.evaluate("(() => { const s = window.skyscatter; "
                              "s.state.ev100 = s.viewer.meter(); s.viewer.frame(); })()")
                page.locator("#sky").screenshot(path=args.screenshot)
            message = server.clouds.message(clouds, "earth")
            print(f"cloud message, {clouds}: {len(message) / 2**20:.1f} MiB")
        if args.clouds_only:
            browser.close()
            server.shutdown()
            return
        qualities = ["preview"] if args.skip_full else ["preview", "full"]
        for quality in qualities:
            for label, size in (("perspective 1920x1080", "width=1920&height=1080"),
                                ("fisheye 1080x1080",
                                 "width=1080&height=1080&projection=fisheye")):
                start = time.perf_counter()
                page.goto(f"{server.url}&controls=0&quality={quality}&{size}&{VIEW}")
                page.wait_for_function(f"document.body.dataset.tables === '{quality}'")
                loaded = time.perf_counter() - start
                if renderer is None:
                    renderer = page.evaluate(
                        "(() => { const gl = window.skyscatter.viewer.gl; "
                        "const e = gl.getExtension('WEBGL_debug_renderer_info'); "
                        "return e ? gl.getParameter(e.UNMASKED_RENDERER_WEBGL) : "
                        "gl.getParameter(gl.RENDERER); })()")
                    print(f"WebGL renderer: {renderer}")
                ms = page.evaluate(f"window.skyscatter.benchmark({args.frames})")
                header = page.evaluate("window.skyscatter.viewer.tables.header")
                print(f"{quality:8s} {label:22s}: {ms:8.1f} ms per frame "
                      f"({header['n_wavelengths']} wavelengths, scattering "
                      f"{header['scattering_shape']}), page ready in {loaded:.1f} s")
        page.goto(f"{server.url}&controls=0&quality=preview&width=1920&height=1080&{VIEW}")
        page.wait_for_function("document.body.dataset.ready === '1'")
        changes = [("aerosol", "state.amounts.aerosol = 2.0"),
                   ("aerosol", "state.amounts.aerosol = 0.5"),
                   ("ozone", "state.amounts.ozone = 1.5"),
                   ("albedo", "state.albedo = 0.3")]
        for name, statement in changes:
            change = page.evaluate("async () => { const state = window.skyscatter.state; "
                                   f"{statement}; await window.skyscatter.reload(); "
                                   "return window.skyscatter.viewer.lastChange; }")
            print(f"parameter change ({name:7s} {statement.split('= ')[1]}) -> new image "
                  f"(1920x1080, preview tables): {change['total_ms'] / 1000:.2f} s (tables "
                  f"{change['tables_ms'] / 1000:.2f} s, upload + draw "
                  f"{change['draw_ms'] / 1000:.2f} s)")
        browser.close()
    for quality in ("preview",) if args.skip_full else ("preview", "full"):
        service = server.service
        message = service.tables(service.parse({"atmosphere": "earth", "quality": quality}))
        print(f"table message, earth {quality}: {len(message) / 2**20:.1f} MiB")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak resident memory of the server process: {peak:.0f} MiB")
    server.shutdown()


FAST_PASSES = (("transmittance", "fast_transmittance"), ("multiple", "fast_multiple"),
               ("irradiance", "fast_irradiance"), ("sky_view", "fast_sky_view"))


def fast_model(page, server, frames: int) -> None:
    """Section 5: the fast model's passes, frame and change-to-image time."""
    page.goto(f"{server.url}&controls=0&quality=preview&width=1920&height=1080&{VIEW}")
    page.wait_for_function("document.body.dataset.ready === '1'")
    for lut, program in FAST_PASSES:
        ms = page.evaluate(f"""() => {{ const v = window.skyscatter.viewer; const times = [];
            const view = v.viewUniforms(1920, 1080);
            const [p, sun] = [view.u_camera_position, view.u_sun_direction];
            const r = Math.hypot(...p);
            const muS = p.reduce((s, x, i) => s + x * sun[i], 0) / r;
            for (let i = 0; i < {frames}; ++i) {{
                const t0 = performance.now();
                v.fast.pass('{lut}', '{program}', {{u_fast_view_radius: r, u_fast_view_mu_s: muS}});
                v.fast.read('{lut}', 0);
                times.push(performance.now() - t0); }}
            v.gl.bindFramebuffer(v.gl.FRAMEBUFFER, null);
            return times.sort((a, b) => a - b)[times.length >> 1]; }}""")
        print(f"fast model, {lut:13s} LUT pass (all groups): {ms:8.1f} ms")
    page.evaluate("(() => { const v = window.skyscatter.viewer; v.tablesKey = null; "
                  "v.applyFast(); })()")
    ms = page.evaluate(f"window.skyscatter.benchmark({frames})")
    print(f"fast model, frame 1920x1080 perspective: {ms:8.1f} ms")
    page.evaluate("(() => { const v = window.skyscatter.viewer; v.tablesKey = v.physicalKey(); "
                  "v.setModel('tables'); })()")
    ms = page.evaluate(f"window.skyscatter.benchmark({frames})")
    print(f"tables (preview), frame 1920x1080 perspective, same page: {ms:8.1f} ms")
    for name, statement in (("aerosol", "state.amounts.aerosol = 2.0"),
                            ("aerosol", "state.amounts.aerosol = 0.5"),
                            ("ozone", "state.amounts.ozone = 1.5"),
                            ("albedo", "state.albedo = 0.3")):
        change = page.evaluate("() => { const state = window.skyscatter.state; "
                               f"{statement}; window.skyscatter.viewer.applyFast(); "
                               "return window.skyscatter.viewer.lastFastChange; }")
        print(f"parameter change ({name:7s} {statement.split('= ')[1]}) -> fast model's image "
              f"(1920x1080): {change['total_ms']:.0f} ms (LUTs {change['luts_ms']:.0f} ms, "
              f"frame {change['draw_ms']:.0f} ms)")


if __name__ == "__main__":
    main()
