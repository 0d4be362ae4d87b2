"""Benchmark: tables vs Monte Carlo for forward-peaked particles (issue 17), before and after.

Sky radiance from the ground on a sky grid (view zenith 0-85 deg x relative azimuth 0-180 deg)
plus the sun's aureole (2, 5, 10, 20 deg from the sun, towards the zenith and sideways), for
`earth` (HG aerosol g 0.65, tau 0.1), a dusty Mars with Henyey-Greenstein dust (`mars-physical`
with its Mie phase replaced by HG g 0.65, optical depth 0.5) and `mars-physical` (Mie hematite
dust), the sun at zenith 0, 30, 60 and 85 deg, 8 bands over 360-830 nm. The tables are computed
twice in one run: without forward-peak truncation (before, `truncation_angle_deg = 0`) and with
the default (after); precompute time and peak memory of each are printed. The Monte Carlo
reference is computed once per case and kept in `--cache` (it does not depend on the tables), with
its standard error; the table reports median and 95th percentile of |tables / Monte Carlo - 1|
per sun zenith (worst band), the aureole's worst |error|, and the Monte Carlo's median relative
standard error beside them.

With `--altitude A` the observer stands A metres up and looks up and down (view zenith 10, 40,
70, 110, 140, 170 deg x the same azimuths): the sky above a cloud deck and the deck seen from
above, e.g. `--atmospheres earth-overcast --altitude 3000 --suns 30 --bands 1
--variants default`.

Run: PYTHONPATH=src python benchmarks/bench_forward_peak.py [--paths 20000]
     [--atmospheres earth mars-hg-dust mars-physical] [--suns 0 30 60 85] [--altitude 0]
     [--orders N]
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.atmosphere.variants import mars_hg_dust
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.monte_carlo import MonteCarloSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.tables import TableResolution, precompute_tables

VIEW_ZENITHS_DEG = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 85.0)
ABOVE_VIEW_ZENITHS_DEG = (10.0, 40.0, 70.0, 110.0, 140.0, 170.0)  # observers above the ground
AZIMUTHS_DEG = (0.0, 45.0, 90.0, 135.0, 180.0)
AUREOLE_DEG = (2.0, 5.0, 10.0, 20.0)


def atmosphere(name: str) -> Atmosphere:
    return mars_hg_dust() if name == "mars-hg-dust" else load_atmosphere(name)


def directions(sun_zenith_deg: float, altitude_m: float) -> tuple[np.ndarray, np.ndarray]:
    """(view directions (n, 3), aureole mask (n,)) in the frame with the sun at azimuth 0."""
    zeniths = ABOVE_VIEW_ZENITHS_DEG if altitude_m > 0.0 else VIEW_ZENITHS_DEG
    z, a = np.meshgrid(zeniths, AZIMUTHS_DEG, indexing="ij")
    keep = (z > 0.0) | (a == 0.0)
    sky = local_frame_directions(np.radians(z[keep]), np.radians(a[keep]))
    sun = local_frame_directions(np.radians(sun_zenith_deg), 0.0)
    # towards the zenith in the sun's vertical plane (away from it for a sun at the zenith),
    # and sideways, perpendicular to it
    up = np.array([0.0, 0.0, 1.0]) - sun[..., :] * sun[2]
    up = up / np.linalg.norm(up) if np.linalg.norm(up) > 1e-9 else np.array([1.0, 0.0, 0.0])
    side = np.cross(sun, up)
    aureole = [np.cos(np.radians(d)) * sun + np.sin(np.radians(d)) * axis
               for d in AUREOLE_DEG for axis in (up, side)]
    views = np.concatenate([sky, np.array(aureole)])
    mask = np.zeros(len(views), dtype=bool)
    mask[len(sky):] = True
    return views, mask


def monte_carlo(profile, name: str, sun_zenith_deg: float, paths: int, cache: Path,
                altitude_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Monte Carlo mean and standard error (n, n_wl), computed once per case into `cache`."""
    height = f"_z{altitude_m:g}" if altitude_m > 0.0 else ""
    path = cache / (f"mc_{name}_sz{sun_zenith_deg:g}_p{paths}{height}"
                    f"_w{profile.n_wavelengths}.npz")
    if path.exists():
        data = np.load(path)
        return data["mean"], data["error"]
    views, _ = directions(sun_zenith_deg, altitude_m)
    sun = local_frame_directions(np.radians(sun_zenith_deg), 0.0)
    start = time.perf_counter()
    solver = MonteCarloSolver(profile, n_samples=paths, seed=17)
    mean, error = solver.sky_radiance_with_error(
        observer_position(altitude_m, profile.bottom_radius_m), views, sun)
    print(f"  Monte Carlo {name} sun {sun_zenith_deg:g}: {time.perf_counter() - start:.0f} s")
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, mean=mean, error=error)
    return mean, error


def tables(profile, orders: int, truncation_deg: float | None) -> tuple[LutSolver, float]:
    resolution = TableResolution() if truncation_deg is None else TableResolution(
        truncation_angle_deg=truncation_deg)
    start = time.perf_counter()
    computed = precompute_tables(profile, resolution=resolution, orders=orders)
    return LutSolver(profile, tables=computed, orders=orders), time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paths", type=int, default=20000)
    parser.add_argument("--atmospheres", nargs="+",
                        default=["earth", "mars-hg-dust", "mars-physical"])
    parser.add_argument("--suns", nargs="+", type=float, default=[0.0, 30.0, 60.0, 85.0])
    parser.add_argument("--bands", type=int, default=8)
    parser.add_argument("--cache", type=Path, default=Path("/tmp/skyscatter-bench-forward-peak"))
    parser.add_argument("--variants", nargs="+", default=["0", "default"],
                        help="truncation angles [deg] to compare; 0: none (before), "
                             "default: TableResolution's")
    parser.add_argument("--altitude", type=float, default=0.0,
                        help="the observer's altitude [m]; above 0 it looks down too")
    parser.add_argument("--orders", type=int, default=None,
                        help="the tables' scattering orders (default: each config's)")
    args = parser.parse_args()
    wavelengths = wavelength_grid(args.bands)
    rows = []
    for name in args.atmospheres:
        atm = atmosphere(name)
        profile = atm.optical_profile(wavelengths)
        solvers = {}
        for variant in args.variants:
            truncation = None if variant == "default" else float(variant)
            orders = atm.scattering_orders if args.orders is None else args.orders
            solver, seconds = tables(profile, orders, truncation)
            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            print(f"{name}: tables ({variant}, {orders} orders) {seconds:.1f} s, "
                  f"process peak so far {peak:.0f} MB")
            solvers[variant] = solver
        for sun_zenith in args.suns:
            mean, error = monte_carlo(profile, name, sun_zenith, args.paths, args.cache,
                                      args.altitude)
            views, aureole = directions(sun_zenith, args.altitude)
            sun = local_frame_directions(np.radians(sun_zenith), 0.0)
            origin = observer_position(args.altitude, profile.bottom_radius_m)
            downward = views[:, 2] < 0.0
            looks = [("up", ~downward), ("down", downward)] if args.altitude > 0.0 else [
                ("", np.ones(len(views), dtype=bool))]
            for variant, solver in solvers.items():
                ratio = solver.sky_radiance(origin, views, sun) / mean - 1.0
                for look, chosen in looks:
                    sky = np.abs(ratio[chosen & ~aureole])
                    rows.append((name + (f", looking {look}" if look else ""), sun_zenith,
                                 variant, np.median(sky, axis=0).max(),
                                 np.percentile(sky, 95, axis=0).max(),
                                 np.mean(ratio[chosen & ~aureole]),
                                 np.abs(ratio[aureole]).max(),
                                 np.nanmedian(error[chosen] / mean[chosen], axis=0).max(),
                                 np.mean(np.abs(ratio[chosen]) <= 2.0 * (error / mean)[chosen])))
    print("\n| atmosphere | sun zenith | truncation | median | 95th pct | mean bias "
          "| aureole max | MC noise | within 2 SE |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, sz, variant, med, p95, bias, aur, noise, within in rows:
        print(f"| {name} | {sz:g} | {variant} | {100 * med:.2f} % | {100 * p95:.1f} % "
              f"| {100 * bias:+.2f} % | {100 * aur:.1f} % | {100 * noise:.2f} % "
              f"| {100 * within:.0f} % |")


if __name__ == "__main__":
    main()
