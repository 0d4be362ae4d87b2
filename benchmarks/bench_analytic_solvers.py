"""Benchmark of the fast sky models against the "lut" tables on the earth preset: per solver the
precompute time, the CPU time, wall time and peak memory of a 1080 x 1080 fisheye render at 16
wavelengths, the memory of its tables, and its relative radiance error against "lut" over the
sky from the ground at several sun zeniths (median and 95th percentile over directions and
wavelengths; and of the luminance). Writes the rendered PNGs beside the numbers.

Run: python benchmarks/bench_analytic_solvers.py [--size 1080] [--out DIR]
(numbers in docs/techniques.md; a first run also compiles the kernels and the tables)
"""

from __future__ import annotations

import argparse
import resource
import time
import tracemalloc
from pathlib import Path

import numba
import numpy as np

from skyscatter import api
from skyscatter.render.camera import FisheyeCamera
from skyscatter.render.scene import render_sky
from skyscatter.spectrum.colour import luminance
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import make_solver
from skyscatter.transport.tables import precompute_tables

SOLVERS = ("lut", "schuler", "bruneton-simplified", "cie", "preetham")
SUN_ZENITHS_DEG = (0.0, 30.0, 60.0, 80.0)
RENDER_SUN_ZENITH_DEG = 60.0


def sky_directions() -> np.ndarray:
    """View zeniths 0-88 deg (23) x azimuths every 10 deg (36): the upper hemisphere."""
    zenith, azimuth = np.meshgrid(np.radians(np.linspace(0.0, 88.0, 23)),
                                  np.radians(np.arange(0.0, 360.0, 10.0)), indexing="ij")
    return local_frame_directions(zenith, azimuth)


def timed(function):
    """(result, wall [s], CPU [s]) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def tables_report(atmosphere, profile, wavelengths, options) -> None:
    """The tables' memory at Bruneton 2017's sizes, full and simplified, and their precompute
    times (computed afresh, not from the cache)."""
    full = api.load_solver(atmosphere, wavelengths, "lut", options).tables
    _, one_wall, one_cpu = timed(lambda: precompute_tables(profile, orders=1))
    simplified = make_solver("bruneton-simplified", profile, options).simplified_tables
    print(f"tables: full ({full.orders} orders) {full.nbytes / 2**10:,.0f} KiB; simplified "
          f"{simplified.nbytes / 2**10:,.0f} KiB ({1 - simplified.nbytes / full.nbytes:.1%} "
          f"less); one-order precompute {one_wall:.1f} s wall, {one_cpu:.1f} s CPU")
    _, full_wall, full_cpu = timed(lambda: precompute_tables(profile, orders=full.orders))
    print(f"full precompute ({full.orders} orders): {full_wall:.1f} s wall, {full_cpu:.1f} s "
          "CPU")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=1080)
    parser.add_argument("--out", type=Path, default=Path("benchmark-analytic"))
    parser.add_argument("--solvers", default=",".join(SOLVERS),
                        help="comma-separated; lut is always run first (the reference)")
    parser.add_argument("--samples", type=int, default=64,
                        help="samples per view ray of the marching solvers (schuler)")
    parser.add_argument("--skip-tables", action="store_true",
                        help="skip the tables' memory and precompute timings")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    atmosphere = api.load_atmosphere("earth")
    wavelengths = wavelength_grid(DEFAULT_WAVELENGTH_BINS)
    profile = atmosphere.optical_profile(wavelengths)
    options = api.solver_options(atmosphere, n_samples=args.samples)  # tables cached
    print(f"numba threads: {numba.get_num_threads()}; {wavelengths.size} wavelengths; "
          f"fisheye {args.size} x {args.size}; render sun zenith {RENDER_SUN_ZENITH_DEG:g} deg; "
          f"{args.samples} samples per ray")
    if not args.skip_tables:
        tables_report(atmosphere, profile, wavelengths, options)
    names = ["lut"] + [n for n in args.solvers.split(",") if n != "lut"]

    origin = observer_position(0.0, profile.bottom_radius_m)
    directions = sky_directions()
    camera = FisheyeCamera(args.size)
    viewpoint = api.viewpoint_at(0.0, profile.bottom_radius_m)
    render_sun = local_frame_directions(np.radians(RENDER_SUN_ZENITH_DEG), np.radians(180.0))
    reference = {}
    print("solver               make [s]  render wall [s]  CPU [s]  peak [MiB]  "
          "error vs lut per sun zenith: median / 95 % (luminance median / 95 %)")
    for name in names:
        engine, make_wall, _ = timed(lambda name=name: make_solver(name, profile, options))
        # warm-up: compiles the kernels, the sky-view grid's too (>= 2^17 rays)
        render_sky(engine, FisheyeCamera(512), viewpoint, render_sun, atmosphere.planet.star)
        tracemalloc.start()
        image, wall, cpu = timed(lambda engine=engine: render_sky(
            engine, camera, viewpoint, render_sun, atmosphere.planet.star))
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        api.save_image(image, args.out / f"{name}.png")
        errors = []
        for sun_zenith in SUN_ZENITHS_DEG:
            sun = local_frame_directions(np.radians(sun_zenith), 0.0)
            radiance = engine.sky_radiance(origin, directions, sun)
            if name == "lut":
                reference[sun_zenith] = radiance
            ref = reference[sun_zenith]
            spectral = np.abs(radiance / ref - 1.0)
            lum = np.abs(luminance(radiance, wavelengths) / luminance(ref, wavelengths) - 1.0)
            errors.append(f"{sun_zenith:g}: {np.median(spectral):.1%}/"
                          f"{np.percentile(spectral, 95):.1%} ({np.median(lum):.1%}/"
                          f"{np.percentile(lum, 95):.1%})")
        print(f"{name:20s} {make_wall:8.2f}  {wall:15.2f}  {cpu:7.2f}  {peak:10.0f}  "
              + "; ".join(errors))
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**10
    print(f"process peak resident memory {rss:.0f} MiB; PNGs in {args.out}/")


if __name__ == "__main__":
    main()
