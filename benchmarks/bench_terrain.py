"""Benchmark: terrain ray casting of a 1920x1080 perspective view from a ground observer.

The observer stands 2 m above the valley floor at the anchor of `demo_mountains` (grids of
256^2, 512^2 and 1024^2 samples over the same 128 km square) and looks south at the range
(heading 180, pitch 0, 60 deg vertical field of view). Prints the wall and process CPU time
of `Heightfield.intersect` (best of 3 after a JIT warm-up), peak traced memory, the share of
rays that hit, and the same for `Heightfield.shadowed` of the hits with the sun 10 deg high in
the south-west. The CPU time is the sum over numba's threads, so on a machine shared with
other work it says more than the wall time.

Run: python benchmarks/bench_terrain.py
"""

from __future__ import annotations

import os

import numba
from timing import best_of

from skyscatter.render.camera import PerspectiveCamera
from skyscatter.render.scene import sun_direction
from skyscatter.render.terrain import demo_mountains

EXTENT_M = 128_000.0
EYE_HEIGHT_M = 2.0


def main() -> None:
    print(f"numba threads: {numba.get_num_threads()}, load average {os.getloadavg()[0]:.1f} "
          f"on {os.cpu_count()} CPUs")
    camera = PerspectiveCamera(1920, 1080, 60.0, heading_deg=180.0, pitch_deg=0.0)
    local = camera.directions()[0].reshape(-1, 3)
    for size in (256, 512, 1024):
        terrain = demo_mountains(size=size, spacing_m=EXTENT_M / size)
        origin, frame = terrain.viewpoint_at(0.0, 0.0, EYE_HEIGHT_M)
        directions = local @ frame.T
        sun = frame @ sun_direction(80.0, 225.0)
        terrain.intersect(origin, directions[:5000])  # JIT warm-up (cached on disk afterwards)
        wall, cpu, peak = best_of(lambda t=terrain, o=origin, d=directions: t.intersect(o, d))
        _, points, _, hit = terrain.intersect(origin, directions)
        print(f"intersect {size}x{size} grid, {len(directions)} rays: {wall:.3f} s wall, "
              f"{cpu:.3f} s CPU, peak traced memory {peak:.0f} MiB, {hit.mean():.0%} hit")
        wall, cpu, peak = best_of(lambda t=terrain, p=points[hit], s=sun: t.shadowed(p, s))
        print(f"  shadowed for the {hit.sum()} hits: {wall:.3f} s wall, {cpu:.3f} s CPU, "
              f"peak {peak:.0f} MiB")


if __name__ == "__main__":
    main()
