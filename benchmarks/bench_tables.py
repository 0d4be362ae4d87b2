"""Benchmark: precomputed tables (Bruneton's default resolution, 4 orders, 15 wavelengths, the
`earth` preset) and a 1920x1080 render from them. Prints wall time, the peak memory the
precomputation adds to the process (resident set, sampled every 5 ms: numba's arrays are not
seen by tracemalloc), the convergence of the orders, the time of `sky_radiance` for
1920 x 1080 rays, and of a whole 1920x1080 frame with terrain (`demo_mountains`: ray march,
terrain shadows, aerial perspective, sky, sun disk) and its conversion to sRGB.

Run: python benchmarks/bench_tables.py [--wavelengths 15] [--orders 4] [--accuracy]
Goals (issue 3): precompute < 30 s on 2 cores (stretch 10 s), peak < 2 GB; render < 1 s.
`--accuracy` also compares the default resolution with tables 2x finer on every axis (3
wavelengths, about 2 minutes): median and 95th percentile of the relative difference of the
sky radiance over ground, 1 km and 10 km observers, view zenith 0-180 deg, sun zenith 0-85 deg.
"""

from __future__ import annotations

import argparse
import threading
import time

import numba
import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS
from skyscatter.render.camera import PerspectiveCamera
from skyscatter.render.scene import ground_viewpoint, render_sky, sun_direction
from skyscatter.render.surfaces import Ground
from skyscatter.render.terrain import demo_mountains
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.spectrum.star import Star
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.tables import TableResolution, precompute_tables


def resident_mib() -> float:
    """Resident set size of this process [MiB] (Linux /proc)."""
    with open("/proc/self/statm") as statm:
        pages = int(statm.read().split()[1])
    return pages * 4096 / 2**20


class PeakMemory:
    """Peak resident memory above the level at entry, sampled in a background thread."""

    def __enter__(self) -> PeakMemory:
        self.base = resident_mib()
        self.peak = self.base
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._sample, daemon=True)
        self._thread.start()
        return self

    def _sample(self) -> None:
        while not self._stop.is_set():
            self.peak = max(self.peak, resident_mib())
            time.sleep(0.005)

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.peak = max(self.peak, resident_mib())

    @property
    def added_mib(self) -> float:
        return self.peak - self.base


def accuracy_against_finer_tables(orders: int) -> None:
    """Default resolution vs 2x finer tables (module docstring)."""
    profile = load_atmosphere("earth").optical_profile(np.array([440.0, 550.0, 680.0]),
                                                       monochromatic=True)
    default = TableResolution()
    start = time.perf_counter()
    coarse = LutSolver(profile, resolution=default, orders=orders)
    fine = LutSolver(profile, resolution=default.scaled(2.0), orders=orders)
    print(f"accuracy: 2x finer tables {default.scaled(2.0)} computed in "
          f"{time.perf_counter() - start:.0f} s")
    zenith, azimuth = np.meshgrid(np.radians(np.linspace(0.0, 180.0, 73)),
                                  np.radians(np.arange(0.0, 360.0, 15.0)), indexing="ij")
    views = local_frame_directions(zenith, azimuth)
    errors = {}
    for altitude_m in (0.0, 1000.0, 10_000.0):
        origin = observer_position(altitude_m, profile.bottom_radius_m)
        for sun_zenith_deg in (0.0, 30.0, 60.0, 75.0, 85.0):
            sun = local_frame_directions(np.radians(sun_zenith_deg), 0.0)
            reference = fine.sky_radiance(origin, views, sun)
            error = np.abs(coarse.sky_radiance(origin, views, sun) / reference - 1.0)
            errors.setdefault(sun_zenith_deg, []).append(error.ravel())
    everything = np.concatenate([e for v in errors.values() for e in v])
    print(f"  all: median {100 * np.median(everything):.3f} %, 95th percentile "
          f"{100 * np.percentile(everything, 95):.3f} %, max {100 * everything.max():.2f} %")
    for sun_zenith_deg, values in errors.items():
        e = np.concatenate(values)
        print(f"  sun zenith {sun_zenith_deg:4.0f} deg: median {100 * np.median(e):.3f} %, "
              f"95th percentile {100 * np.percentile(e, 95):.3f} %")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wavelengths", type=int, default=15)
    parser.add_argument("--orders", type=int, default=DEFAULT_SCATTERING_ORDERS)
    parser.add_argument("--accuracy", action="store_true",
                        help="also compare with 2x finer tables (3 wavelengths, minutes)")
    args = parser.parse_args()

    wavelengths = wavelength_grid(args.wavelengths)
    profile = load_atmosphere("earth").optical_profile(wavelengths)
    resolution = TableResolution()
    print(f"numba threads: {numba.get_num_threads()}; {args.wavelengths} wavelengths, "
          f"{args.orders} orders, constituents {', '.join(profile.names)}")
    print(f"resolution: {resolution}")

    small = TableResolution(scattering_r=4, scattering_mu=8, scattering_mu_s=4,
                            scattering_nu=2, transmittance_r=4, transmittance_mu=8)
    precompute_tables(profile, small, orders=2)  # JIT warm-up (cached on disk after a run)

    stages: list[tuple[float, str]] = []
    start = time.perf_counter()

    def progress(done: int, total: int, stage: str) -> None:
        stages.append((time.perf_counter() - start, stage))

    with PeakMemory() as memory:
        start = time.perf_counter()
        tables = precompute_tables(profile, resolution, orders=args.orders, progress=progress)
        seconds = time.perf_counter() - start
    previous = 0.0
    for at, stage in stages:
        print(f"  {at:7.2f} s  (+{at - previous:5.2f})  {stage}")
        previous = at
    print(f"precompute: {seconds:.2f} s, peak memory added {memory.added_mib:.0f} MiB "
          f"(tables themselves {tables.nbytes / 2**20:.0f} MiB)")

    # the orders iterated; the rest, if any, was added as their geometric tail
    zenith = tables.order_zenith_radiance[:tables.orders_computed]
    mean = tables.order_mean_radiance[:tables.orders_computed]
    pick = [int(np.argmin(np.abs(wavelengths - w))) for w in (440.0, 550.0, 680.0)]
    print("convergence with orders (radiance of each order alone; ratio to the previous one):")
    for w in pick:
        z = ", ".join(f"{v:.3g}" for v in zenith[:, w])
        m = ", ".join(f"{v:.3g}" for v in mean[:, w])
        ratio = ", ".join(f"{v:.3f}" for v in mean[1:, w] / mean[:-1, w])
        print(f"  {wavelengths[w]:6.1f} nm  zenith (sun at zenith) [{z}]  "
              f"table mean [{m}]  mean ratios [{ratio}]")

    solver = LutSolver(profile, tables=tables)
    camera = PerspectiveCamera(1920, 1080, 60.0, heading_deg=180.0, pitch_deg=5.0)
    directions, _ = camera.directions()
    origin = observer_position(1000.0, profile.bottom_radius_m)
    # the sun 20 deg high in the frame (its aureole's pixels), then behind the camera
    for where, azimuth in (("sun in the frame", np.pi), ("sun behind", 0.0)):
        sun = local_frame_directions(np.radians(70.0), azimuth)
        solver.sky_radiance(origin, directions[:8], sun)  # JIT warm-up
        times = []
        for _ in range(3):
            begin = time.perf_counter()
            image = solver.sky_radiance(origin, directions, sun)
            times.append(time.perf_counter() - begin)
        print(f"sky_radiance, 1920x1080 rays from 1 km (sky and ground), {where}, "
              f"{args.wavelengths} wavelengths: {min(times):.2f} s (best of 3); output "
              f"{image.nbytes / 2**20:.0f} MiB, all finite: {bool(np.all(np.isfinite(image)))}")
    render_with_terrain(solver, camera)
    if args.accuracy:
        accuracy_against_finer_tables(args.orders)


def render_with_terrain(solver: LutSolver, camera: PerspectiveCamera) -> None:
    """A whole frame: sky + terrain + aerial perspective + sun, then colour (best of 3)."""
    profile = solver.profile
    ground = Ground(terrain=demo_mountains(planet_radius_m=profile.bottom_radius_m))
    viewpoint = ground_viewpoint(300.0, profile.bottom_radius_m)
    sun = sun_direction(70.0, 220.0)
    star = Star.sun()
    small = PerspectiveCamera(16, 9, 60.0, heading_deg=180.0, pitch_deg=5.0)
    render_sky(solver, small, viewpoint, sun, star, ground=ground)  # JIT warm-up
    times, colour_times = [], []
    for _ in range(3):
        begin = time.perf_counter()
        image = render_sky(solver, camera, viewpoint, sun, star, ground=ground)
        times.append(time.perf_counter() - begin)
        begin = time.perf_counter()
        image.rgb()
        colour_times.append(time.perf_counter() - begin)
    print(f"render_sky 1920x1080 from 300 m with terrain (512x512 heights), aerial perspective "
          f"and sun, {profile.n_wavelengths} wavelengths: {min(times):.2f} s (best of 3); "
          f"spectral -> linear sRGB {min(colour_times):.2f} s")


if __name__ == "__main__":
    main()
