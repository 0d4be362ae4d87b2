"""Benchmark: the Monte Carlo reference's speed and noise.

1. Speed: sky radiance (all orders) for the earth preset at 8 wavelengths, 16 view rays x 4000
   paths per ray and wavelength, sun at 45° and 95° zenith. Prints paths per second (one path =
   one wavelength), wall time (best of 3 after a JIT warm-up), the median relative standard
   error and peak memory.
2. Noise with forward-peaked phase functions (issue 17): `mars-physical` (Mie dust), the same
   Mars with Henyey-Greenstein dust (g 0.65, optical depth 0.5 at 880 nm) and `earth` with its
   aerosol as Henyey-Greenstein g 0.7; sun zenith 0, 30, 60 and 85°, 16 rays x 3 bands. For
   plain phase sampling (sun_sampling_probability=0) and the default sun-centred mixture:
   `--seeds` runs of `--paths` paths against one run of `--long-paths` (default mixture), the
   median relative standard error, the share of values within 2 combined standard errors of the
   long run (about 95 % when the standard errors are honest), the spread of the seeds over the
   median standard error (about 1) and paths per second; then the default with
   target_relative_error = 1 %: its median and largest relative error and seconds.

Run: python benchmarks/bench_monte_carlo.py [--threads 2] [--seeds 4] [--paths 2000]
     [--long-paths 16000] [--skip-speed]
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import time
import tracemalloc

import numba
import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.optics.phase import HenyeyGreensteinPhase
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.monte_carlo import SUN_SAMPLING_PROBABILITY, MonteCarloSolver
from skyscatter.transport.single_scattering import observer_position

N_PATHS = 4000
SUN_ZENITHS_DEG = (0.0, 30.0, 60.0, 85.0)


def best_of(function, repeats: int = 3) -> tuple[float, float, object]:
    """(best wall time [s], peak traced memory of one call [MiB], last result)."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    tracemalloc.start()
    function()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return min(times), peak, result


def speed() -> None:
    profile = load_atmosphere("earth").optical_profile(wavelength_grid(8))
    solver = MonteCarloSolver(profile, n_samples=N_PATHS, seed=0)
    origin = observer_position(0.0, profile.bottom_radius_m)
    zenith = np.radians(np.linspace(0.0, 88.0, 16))
    views = local_frame_directions(zenith, np.linspace(0.0, 2.0 * np.pi, 16, endpoint=False))
    paths = views.shape[0] * profile.n_wavelengths * N_PATHS
    for sun_zenith in (45.0, 95.0):
        sun = local_frame_directions(np.radians(sun_zenith), np.pi)
        solver.sky_radiance_with_error(origin, views[:1], sun)  # JIT warm-up (cached on disk)
        seconds, peak, (mean, error) = best_of(
            lambda sun=sun: solver.sky_radiance_with_error(origin, views, sun))
        relative = np.median(error[mean > 0] / mean[mean > 0])
        print(f"sun zenith {sun_zenith:.0f}°: {paths} paths in {seconds:.2f} s = "
              f"{paths / seconds / 1e6:.2f} M paths/s; median relative standard error "
              f"{relative * 100:.2f} %; peak traced memory {peak:.1f} MiB")


def with_henyey_greenstein(profile: OpticalProfile, name: str, g: float) -> OpticalProfile:
    """`profile` with constituent `name`'s phase function replaced by HG(g)."""
    phases = list(profile.phases)
    phases[profile.names.index(name)] = HenyeyGreensteinPhase(g)
    return dataclasses.replace(profile, phases=tuple(phases))


def peaked_atmospheres() -> dict[str, OpticalProfile]:
    wavelengths = wavelength_grid(3)
    mars = load_atmosphere("mars-physical").optical_profile(wavelengths)
    earth = load_atmosphere("earth").optical_profile(wavelengths)
    return {"mars-physical (Mie dust)": mars,
            "mars, HG dust g 0.65": with_henyey_greenstein(mars, "dust", 0.65),
            "earth, HG aerosol g 0.7": with_henyey_greenstein(earth, "aerosol", 0.7)}


def noise(seeds: int, paths: int, long_paths: int) -> None:
    zenith, azimuth = np.meshgrid([0.0, 10.0, 20.0, 40.0, 60.0, 80.0], [0.0, 90.0, 180.0],
                                  indexing="ij")
    keep = (zenith > 0.0) | (azimuth == 0.0)
    views = local_frame_directions(np.radians(zenith[keep]), np.radians(azimuth[keep]))
    print(f"\nnoise: {views.shape[0]} rays x 3 bands, {seeds} seeds x {paths} paths against "
          f"{long_paths} paths")
    for name, profile in peaked_atmospheres().items():
        origin = observer_position(0.0, profile.bottom_radius_m)
        MonteCarloSolver(profile, n_samples=16).sky_radiance(origin, views[:1], views[0])
        for sun_zenith in SUN_ZENITHS_DEG:
            sun = local_frame_directions(np.radians(sun_zenith), 0.0)
            long, long_error = MonteCarloSolver(
                profile, n_samples=long_paths, seed=10_000).sky_radiance_with_error(
                origin, views, sun)
            lit = long > 0.0
            parts = []
            for eps in (0.0, SUN_SAMPLING_PROBABILITY):
                start = time.perf_counter()
                runs = [MonteCarloSolver(profile, n_samples=paths, seed=seed + 1,
                                         sun_sampling_probability=eps
                                         ).sky_radiance_with_error(origin, views, sun)
                        for seed in range(seeds)]
                rate = seeds * paths * long.size / (time.perf_counter() - start)
                means, errors = (np.array(values) for values in zip(*runs, strict=True))
                within = np.abs(means - long) <= 2.0 * np.hypot(errors, long_error)
                spread = means.std(axis=0, ddof=1)[lit] / np.median(errors, axis=0)[lit]
                parts.append(f"eps {eps:.1f}: {np.median(errors[:, lit] / means[:, lit]):6.2%}"
                             f" {np.mean(within[:, lit]):4.0%} in 2 SE, spread/SE "
                             f"{np.median(spread):.2f}, {rate / 1e6:.2f} M paths/s")
            start = time.perf_counter()
            mean, error = MonteCarloSolver(profile, n_samples=paths, seed=777,
                                           target_relative_error=0.01
                                           ).sky_radiance_with_error(origin, views, sun)
            seconds = time.perf_counter() - start
            relative = error[mean > 0.0] / mean[mean > 0.0]
            print(f"{name:26s} sun {sun_zenith:2.0f}°: " + " | ".join(parts)
                  + f" | target 1 %: median {np.median(relative):.2%}, largest "
                  f"{relative.max():.2%}, {seconds:.1f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--paths", type=int, default=2000)
    parser.add_argument("--long-paths", type=int, default=16000)
    parser.add_argument("--skip-speed", action="store_true")
    args = parser.parse_args()
    numba.set_num_threads(min(args.threads, numba.config.NUMBA_NUM_THREADS))
    print(f"numba threads: {numba.get_num_threads()}")
    if not args.skip_speed:
        speed()
    noise(args.seeds, args.paths, args.long_paths)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
