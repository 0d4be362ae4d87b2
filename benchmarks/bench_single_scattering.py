"""Benchmark: 512x512 fisheye single-scattering render at 16 wavelengths, and 10^4
transmittance rays. Prints wall time (best of 3 after a JIT warm-up) and peak memory.

Run: python benchmarks/bench_single_scattering.py   (or `make bench`)
"""

from __future__ import annotations

import resource
import time
import tracemalloc

import numba
import numpy as np

from skyscatter import api
from skyscatter.render.camera import FisheyeCamera
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import SingleScatteringSolver, observer_position


def best_of(function, repeats: int = 3) -> tuple[float, float]:
    """(best wall time [s], peak traced numpy/python memory of one call [MiB])."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    tracemalloc.start()
    function()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return min(times), peak


def main() -> None:
    atmosphere = api.load_atmosphere("earth")
    camera = FisheyeCamera(512)
    wavelengths = wavelength_grid(DEFAULT_WAVELENGTH_BINS)
    print(f"numba threads: {numba.get_num_threads()}")

    def render() -> None:
        api.render(atmosphere, camera, sun_zenith_deg=45.0, wavelengths_nm=wavelengths)

    render()  # JIT warm-up (cached on disk after the first run)
    seconds, peak = best_of(render)
    print(f"render 512x512 fisheye, 16 wavelengths, 64 samples/ray, earth preset "
          f"(atmosphere sampling + sun table + rays + sun disk): {seconds:.2f} s, "
          f"peak traced memory {peak:.0f} MiB")

    profile = atmosphere.optical_profile(wavelengths)
    solver = SingleScatteringSolver(profile)
    directions, valid = camera.directions()
    origin = observer_position(0.0, profile.bottom_radius_m)
    sun = local_frame_directions(np.radians(45.0), np.pi)
    seconds, peak = best_of(lambda: solver.sky_radiance(origin, directions[valid], sun))
    print(f"  of which sky_radiance for {valid.sum()} rays: {seconds:.2f} s, "
          f"peak {peak:.0f} MiB")

    rng = np.random.default_rng(0)
    rays = rng.normal(size=(10_000, 3))
    origins = origin + rng.uniform(0.0, 20_000.0, size=(10_000, 1)) * np.array([0, 0, 1.0])
    solver.transmittance(origins[:10], rays[:10])
    seconds, peak = best_of(lambda: solver.transmittance(origins, rays))
    print(f"10^4 transmittance rays (256 samples each, 16 wavelengths): {seconds * 1e3:.1f} ms, "
          f"peak {peak:.1f} MiB")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"process peak RSS: {rss:.0f} MiB")


if __name__ == "__main__":
    main()
