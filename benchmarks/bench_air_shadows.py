"""Benchmark: the share of the clouds' shadows in the air (`transport.air_shadows`) in a frame
with clouds: CPU and wall time of the shadow map, of the shadow loss of every ray, and of the
whole frame (`render.scene.diffuse_radiance`, which includes both), best of 3 after a warm-up.

Earth's default tables, the cumulus preset, observer 2 m up, sun 40 deg from the zenith, a
perspective camera 75 deg wide looking 12 deg up (as benchmarks/bench_clouds.py).

Run: python benchmarks/bench_air_shadows.py [--width 960 --height 540] [--presets cumulus ...]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from skyscatter import api
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.render.scene import diffuse_radiance, ground_viewpoint, sun_direction
from skyscatter.transport.air_shadows import air_shadows


def timed(work) -> tuple[float, float]:
    """(wall, CPU) seconds of the best of 3 runs of `work()`."""
    best = (np.inf, np.inf)
    for _ in range(3):
        wall, cpu = time.perf_counter(), time.process_time()
        work()
        best = min(best, (time.perf_counter() - wall, time.process_time() - cpu))
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=int, default=960)
    parser.add_argument("--height", type=int, default=540)
    parser.add_argument("--presets", nargs="+", default=["cumulus", "stratocumulus"])
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    solver = api.load_solver(api.load_atmosphere("earth"))
    profile = solver.profile
    viewpoint = ground_viewpoint(2.0, profile.bottom_radius_m)
    camera = api.PerspectiveCamera(args.width, args.height, 75.0, heading_deg=150.0,
                                   pitch_deg=12.0)
    directions, _ = camera.directions()
    rays = np.ascontiguousarray(viewpoint.direction_to_world(directions.reshape(-1, 3)))
    sun = viewpoint.direction_to_world(sun_direction(40.0, 135.0))
    origin = viewpoint.position_m
    stop = np.full(rays.shape[0], np.inf)
    for preset in args.presets:
        field = cloud_field(api.load_clouds(preset), profile.bottom_radius_m,
                            profile.wavelengths_nm)
        diffuse_radiance(solver, origin, rays[:2000], sun, clouds=field)  # compile, caches
        shadows = air_shadows(solver, field, origin, rays, sun, stop=stop)
        rows = [("shadow map", lambda f=field: air_shadows(solver, f, origin, rays, sun,
                                                           stop=stop)),
                ("shadow loss of every ray", lambda s=shadows: s.loss(solver, rays, stop)),
                ("whole frame", lambda f=field: diffuse_radiance(solver, origin, rays, sun,
                                                                 clouds=f))]
        for name, work in rows:
            wall, cpu = timed(work)
            print(f"{preset} {args.width}x{args.height}: {name}: {wall:.2f} s wall, "
                  f"{cpu:.2f} s CPU", flush=True)


if __name__ == "__main__":
    main()
