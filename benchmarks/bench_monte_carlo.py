"""Benchmark: Monte Carlo sky radiance (all orders) for the earth preset at 8 wavelengths,
16 view rays x 4000 paths per ray and wavelength, sun at 45° and 95° zenith, on 2 threads.
Prints paths per second (one path = one wavelength), wall time (best of 3 after a JIT warm-up),
the typical relative standard error and peak memory.

Run: python benchmarks/bench_monte_carlo.py
"""

from __future__ import annotations

import resource
import time
import tracemalloc

import numba
import numpy as np

from skyscatter import api
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.monte_carlo import MonteCarloSolver
from skyscatter.transport.single_scattering import observer_position

N_PATHS = 4000


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


def main() -> None:
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    print(f"numba threads: {numba.get_num_threads()}")
    profile = api.load_atmosphere("earth").optical_profile(wavelength_grid(8))
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
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
