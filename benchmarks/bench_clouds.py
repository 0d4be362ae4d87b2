"""Benchmark: frames with clouds from the tables (issue 19's goals: a 1920 x 1080 perspective
frame of a cumulus field under 10 s, a 512 x 512 fisheye under 2 s, on 2 cores).

Earth's default tables (loaded from the cache or computed first), the observer 2 m above the
ground, the sun 40 deg from the zenith in the south-east. For each cloud preset and camera:
the best of 3 wall times of `render_sky` with the clouds and without them (after a warm-up:
numba's compile and the cloud field's Mie optics are cached on disk), the time to build the
cloud field (noise tile and optics, cached in memory after the first), and the peak traced
memory of one frame with clouds (numpy's and Python's allocations, tracemalloc).

Run: python benchmarks/bench_clouds.py [--presets cumulus stratus ...]
"""

from __future__ import annotations

import argparse
import os
import time

import numba
from timing import best_of

from skyscatter import api
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.atmosphere.cloud_noise import noise_texture
from skyscatter.render.scene import ground_viewpoint, render_sky, sun_direction

CAMERAS = {
    "fisheye 512x512": lambda: api.FisheyeCamera(512),
    "perspective 1920x1080": lambda: api.PerspectiveCamera(1920, 1080, 75.0, heading_deg=150.0,
                                                           pitch_deg=12.0),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--presets", nargs="+", default=["cumulus", "stratocumulus", "stratus",
                                                         "cirrus"])
    args = parser.parse_args()
    print(f"numba threads: {numba.get_num_threads()}, load average {os.getloadavg()[0]:.1f} "
          f"on {os.cpu_count()} CPUs")
    atmosphere = api.load_atmosphere("earth")
    solver = api.load_solver(atmosphere)
    profile = solver.profile
    viewpoint = ground_viewpoint(2.0, profile.bottom_radius_m)
    sun = sun_direction(40.0, 135.0)
    star = atmosphere.planet.star
    for preset in args.presets:
        clouds = api.load_clouds(preset)
        start = time.perf_counter()
        field = cloud_field(clouds, profile.bottom_radius_m, profile.wavelengths_nm)
        first = time.perf_counter() - start
        noise_texture.cache_clear()
        start = time.perf_counter()
        field = cloud_field(clouds, profile.bottom_radius_m, profile.wavelengths_nm)
        print(f"{preset}: cloud field {first:.2f} s the first time in this process, "
              f"{time.perf_counter() - start:.2f} s with the Mie optics cached on disk")
        for name, make in CAMERAS.items():
            camera = make()
            clear, _, _ = best_of(lambda c=camera: render_sky(solver, c, viewpoint, sun, star),
                                  warm_up=True)
            cloudy, cpu, peak = best_of(lambda c=camera, f=field: render_sky(
                solver, c, viewpoint, sun, star, clouds=f), warm_up=True)
            print(f"  {name}: {cloudy:.2f} s with clouds ({cpu:.2f} s CPU), {clear:.2f} s "
                  f"without; peak traced memory with clouds {peak:.0f} MiB")


if __name__ == "__main__":
    main()
