"""Benchmark: table lookups near the sun, where the aureole of multiple forward-peak scattering
follows the sun's path (`_table_lookup_kernels.aureole_path`).

`mars-physical` (16 bands, its own orders) is precomputed once; 200 000 rays from the ground,
view zenith 0-85 deg, within 40 deg of azimuth of the sun, are looked up (best of one after a
compile run). Prints the wall time; with `--save FILE` the radiances are written (.npy) so that
two source trees can be compared value by value (`--compare FILE`).

Run: PYTHONPATH=TREE/src python benchmarks/bench_aureole_lookups.py [--sun-zenith 60]
     [--save a.npy | --compare a.npy]
Results: docs/validation.md ("The aureole along the sun's path", its cost).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.tables import precompute_tables

RAYS = 200_000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sun-zenith", type=float, default=60.0)
    parser.add_argument("--save", type=Path)
    parser.add_argument("--compare", type=Path)
    args = parser.parse_args()
    atmosphere = load_atmosphere("mars-physical")
    profile = atmosphere.optical_profile(wavelength_grid(DEFAULT_WAVELENGTH_BINS))
    tables = precompute_tables(profile, orders=atmosphere.scattering_orders)
    solver = LutSolver(profile, tables=tables, orders=atmosphere.scattering_orders)
    rng = np.random.default_rng(1)
    views = local_frame_directions(np.radians(rng.uniform(0.0, 85.0, RAYS)),
                                   np.radians(rng.uniform(-40.0, 40.0, RAYS)))
    sun = local_frame_directions(np.radians(args.sun_zenith), 0.0)
    observer = observer_position(0.0, profile.bottom_radius_m)
    solver.sky_radiance(observer, views[:100], sun)  # compile
    start = time.perf_counter()
    radiance = solver.sky_radiance(observer, views, sun)
    print(f"{RAYS} rays near a sun {args.sun_zenith:g} deg from the zenith: "
          f"{time.perf_counter() - start:.2f} s")
    if args.save:
        np.save(args.save, radiance)
    if args.compare:
        difference = 100.0 * np.abs(radiance / np.load(args.compare) - 1.0)
        print(f"against {args.compare}: |difference| median {np.median(difference):.4f} %, "
              f"99th percentile {np.percentile(difference, 99):.4f} %, "
              f"max {difference.max():.4f} %")


if __name__ == "__main__":
    main()
