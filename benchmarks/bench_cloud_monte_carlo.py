"""Benchmark: the cloud Monte Carlo reference (`transport/cloud_monte_carlo.py`) on a fisheye.

A `--size` x `--size` fisheye (default 48: the 1 804 pixels inside its circle) from the ground
at the north pole under the `cumulus` preset in the `earth` atmosphere, sun at 40 deg zenith,
3 wavelengths (450, 550, 650 nm), `--paths` paths per ray and wavelength. Prints the wall time
(after a JIT warm-up), paths per second, peak memory (resource.ru_maxrss, the whole process),
and the median and 90th percentile of the relative standard error over rays x wavelengths,
for all rays and separately for the rays that meet a cloud (cloud transmittance below 0.99 at
550 nm, `transport.clouds.cloud_transmittance`) and those that do not.

Run: python benchmarks/bench_cloud_monte_carlo.py [--size 48] [--paths 2000] [--threads N]
     [--eps 0.5] [--seed 0]
"""

from __future__ import annotations

import argparse
import resource
import time

import numba
import numpy as np

from skyscatter.atmosphere.cloud_config import load_clouds
from skyscatter.atmosphere.cloud_field import cloud_field
from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.render.camera import FisheyeCamera
from skyscatter.render.scene import ground_viewpoint, sun_direction
from skyscatter.transport.cloud_monte_carlo import SUN_SAMPLING_PROBABILITY, CloudMonteCarlo
from skyscatter.transport.clouds import cloud_transmittance

WAVELENGTHS_NM = np.array([450.0, 550.0, 650.0])
SUN_ZENITH_DEG, SUN_AZIMUTH_DEG = 40.0, 180.0


def relative_errors(mean: np.ndarray, error: np.ndarray) -> np.ndarray:
    """error / mean (n, n_wl) where the mean is positive, NaN elsewhere."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mean > 0.0, error / mean, np.nan)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=48)
    parser.add_argument("--paths", type=int, default=2000)
    parser.add_argument("--threads", type=int, default=numba.config.NUMBA_NUM_THREADS)
    parser.add_argument("--eps", type=float, default=SUN_SAMPLING_PROBABILITY)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    atmosphere = load_atmosphere("earth")
    profile = atmosphere.optical_profile(WAVELENGTHS_NM)
    field = cloud_field(load_clouds("cumulus"), atmosphere.bottom_radius_m, WAVELENGTHS_NM)
    origin = ground_viewpoint(0.0, atmosphere.bottom_radius_m).position_m
    directions, inside = FisheyeCamera(args.size).directions()
    rays = np.ascontiguousarray(directions[inside])
    sun = sun_direction(SUN_ZENITH_DEG, SUN_AZIMUTH_DEG)
    cloudy = cloud_transmittance(field, origin, rays)[:, 1] < 0.99
    solver = CloudMonteCarlo(profile, field, n_samples=args.paths, seed=args.seed,
                             sun_sampling_probability=args.eps)
    CloudMonteCarlo(profile, field, n_samples=2, seed=args.seed,
                    sun_sampling_probability=args.eps).radiance_with_error(origin, rays[:4], sun)
    start = time.perf_counter()
    mean, error = solver.radiance_with_error(origin, rays, sun)
    seconds = time.perf_counter() - start
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    relative = relative_errors(mean, error)
    paths = args.paths * rays.shape[0] * WAVELENGTHS_NM.size
    print(f"cumulus over earth, sun zenith {SUN_ZENITH_DEG:g} deg, {args.size} x {args.size} "
          f"fisheye: {rays.shape[0]} rays x {WAVELENGTHS_NM.size} wavelengths x {args.paths} "
          f"paths, eps {args.eps:g}, {numba.get_num_threads()} threads")
    print(f"wall time {seconds:.1f} s, {paths / seconds:.0f} paths/s, peak memory "
          f"{peak_mib:.0f} MiB (ru_maxrss)")
    for name, chosen in (("all rays", np.ones_like(cloudy)), ("cloudy rays", cloudy),
                         ("clear rays", ~cloudy)):
        values = relative[chosen]
        values = values[np.isfinite(values)]
        if values.size:
            print(f"{name:12s} ({chosen.sum():4d}): relative standard error median "
                  f"{100 * np.median(values):.2f} %, 90th percentile "
                  f"{100 * np.quantile(values, 0.9):.2f} %, largest {100 * values.max():.1f} %")


if __name__ == "__main__":
    main()
