"""Benchmark: the `lut` solver's sky through twilight (issue 6). A 1024 x 1024 equidistant
fisheye (the disc inside the square: about 0.82 M rays) from the ground, 16 wavelengths, the
`earth` preset (its 8 orders), sun zenith 60, 96 and 106 deg: wall time and peak memory of
`LutSolver.sky_radiance`, best of `--repeat` runs after a warm-up (numba compiled). With
`--precompute` the tables are computed here (time and peak memory added to the process, as in
bench_tables.py); otherwise they come from the table cache (`--cache-dir`).

Run: python benchmarks/bench_twilight.py [--size 1024] [--precompute] [--cache-dir DIR]
Goal (issue 6): the sky part of a night frame under about 1 s on 2 cores; precomputation of
`earth` at most 1.5 x its time and memory before the twilight work.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numba
import numpy as np
from bench_tables import PeakMemory

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.cache import TableCache
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import precompute_tables


def fisheye_directions(size: int) -> np.ndarray:
    """Unit view directions (n, 3) of the pixels of a size x size equidistant fisheye whose
    inscribed circle is the horizon (zenith angle proportional to the distance from the
    centre); pixels outside the circle are left out."""
    centre = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(centre, centre, indexing="xy")
    radius = np.hypot(x, y)
    inside = radius <= 1.0
    zenith = 0.5 * np.pi * radius[inside]
    azimuth = np.arctan2(x[inside], y[inside])
    return np.ascontiguousarray(local_frame_directions(zenith, azimuth))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--wavelengths", type=int, default=DEFAULT_WAVELENGTH_BINS)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--sun-zenith", type=float, nargs="+", default=[60.0, 96.0, 106.0])
    parser.add_argument("--precompute", action="store_true")
    parser.add_argument("--cache-dir", type=Path, default=Path("/tmp/skyscatter-bench-cache"))
    args = parser.parse_args()

    atmosphere = load_atmosphere("earth")
    profile = atmosphere.optical_profile(wavelength_grid(args.wavelengths))
    orders = atmosphere.scattering_orders
    print(f"numba threads: {numba.get_num_threads()}; earth, {profile.n_wavelengths} "
          f"wavelengths, {orders} orders")
    if args.precompute:
        with PeakMemory() as memory:
            start = time.perf_counter()
            tables = precompute_tables(profile, orders=orders)
            seconds = time.perf_counter() - start
        print(f"precompute: {seconds:.1f} s, peak memory added {memory.added_mib:.0f} MiB, "
              f"tables {tables.nbytes / 2**20:.0f} MiB, mu_s from "
              f"{np.degrees(np.arccos(tables.min_cos_sun_zenith)):.1f} deg")
    else:
        tables = cached_tables(profile, orders=orders, cache=TableCache(args.cache_dir),
                               log=print)
    solver = LutSolver(profile, tables=tables)
    directions = fisheye_directions(args.size)
    origin = observer_position(0.0, profile.bottom_radius_m)
    print(f"{directions.shape[0]} rays ({args.size} x {args.size} fisheye)")
    solver.sky_radiance(origin, directions[:1000], local_frame_directions(np.radians(96.0), 0.0))
    for sun_zenith in args.sun_zenith:
        sun = local_frame_directions(np.radians(sun_zenith), 0.0)
        times = []
        with PeakMemory() as memory:
            for _ in range(args.repeat):
                start = time.perf_counter()
                radiance = solver.sky_radiance(origin, directions, sun)
                times.append(time.perf_counter() - start)
        zenith = float(radiance[np.argmax(directions[:, 2]), profile.n_wavelengths // 2])
        print(f"sun zenith {sun_zenith:5.1f} deg: sky_radiance best {min(times):.3f} s "
              f"(runs {', '.join(f'{t:.2f}' for t in times)}), peak memory added "
              f"{memory.added_mib:.0f} MiB (result {radiance.nbytes / 2**20:.0f} MiB), zenith "
              f"radiance at {profile.wavelengths_nm[profile.n_wavelengths // 2]:.0f} nm "
              f"{zenith:.3e} W m-2 sr-1 nm-1")


if __name__ == "__main__":
    main()
