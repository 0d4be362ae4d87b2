"""Measurement for issue 18: how well does a per-frame sky-view grid stand in for per-pixel
table lookups? (The measurement that chose the sizes of `LutSolver`'s grid, SKY_GRID_*; it
interpolates across the horizon, which the package's grid does not, and has no rays looked up
one by one next to the sun. tests/transport/test_sky_view_grid.py checks the package's grid.)

For one observer the sky's radiance depends on the view's zenith cosine mu and its azimuth
from the sun only. This script looks the tables up on a grid of N_MU x N_PHI views (mu on the
scattering table's mapping, which crowds cells at the horizon; azimuth uniform over
[0, pi]) and interpolates it bilinearly in the logarithm for 200 000 random views (view
zenith 0 to 107 deg), against the lookups of those views themselves. It prints the grid's
cost and the relative errors: all views, views more than 5 deg from the sun, and views more
than 1 deg from the horizon (the grid interpolates across the horizon, where the sky meets
the ground: a real implementation would keep each side to its own half of the mu axis, as
the tables do).

Run: python benchmarks/bench_sky_view_grid.py [--atmosphere earth] [--mu 256] [--phi 128]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.table_parameterisation import scattering_mu_from_u, scattering_u_mu

VIEWS = 200_000
SUN_ZENITHS_DEG = (30.0, 60.0, 80.0, 88.0, 94.0)


def grid_estimate(log_grid: np.ndarray, u_mu: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of log_grid (n_mu, n_phi, n_wl) at texture coordinates u_mu
    (cell centres at (i + 0.5) / n_mu) and azimuths phi in [0, pi], exponentiated."""
    n_mu, n_phi = log_grid.shape[:2]
    x = np.clip(u_mu * n_mu - 0.5, 0.0, n_mu - 1 - 1e-9)
    i = x.astype(int)
    a = (x - i)[:, None]
    y = np.clip(phi / np.pi * (n_phi - 1), 0.0, n_phi - 1 - 1e-9)
    k = y.astype(int)
    b = (y - k)[:, None]
    return np.exp((1 - a) * ((1 - b) * log_grid[i, k] + b * log_grid[i, k + 1])
                  + a * ((1 - b) * log_grid[i + 1, k] + b * log_grid[i + 1, k + 1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmosphere", default="earth")
    parser.add_argument("--mu", type=int, default=256)
    parser.add_argument("--phi", type=int, default=128)
    parser.add_argument("--wavelengths", type=int, default=8)
    args = parser.parse_args()
    atmosphere = load_atmosphere(args.atmosphere)
    profile = atmosphere.optical_profile(wavelength_grid(args.wavelengths))
    solver = LutSolver(profile, orders=atmosphere.scattering_orders)
    origin = observer_position(1000.0, profile.bottom_radius_m)
    r = float(np.linalg.norm(origin))
    bottom, top = profile.bottom_radius_m, profile.top_radius_m
    horizon_mu = -np.sqrt(1.0 - (bottom / r) ** 2)
    grid_mu = np.array([scattering_mu_from_u((i + 0.5) / args.mu, r, bottom, top, args.mu)[0]
                        for i in range(args.mu)])
    grid_zenith, grid_phi = np.meshgrid(np.arccos(np.clip(grid_mu, -1.0, 1.0)),
                                        np.linspace(0.0, np.pi, args.phi), indexing="ij")
    rng = np.random.default_rng(1)
    zenith = np.arccos(rng.uniform(-0.3, 1.0, VIEWS))
    azimuth = rng.uniform(0.0, 2.0 * np.pi, VIEWS)
    views = local_frame_directions(zenith, azimuth)
    mu = np.cos(zenith)
    u_mu = np.array([scattering_u_mu(r, m, bool(m < horizon_mu), bottom, top, args.mu)
                     for m in mu])
    phi = np.abs((azimuth + np.pi) % (2.0 * np.pi) - np.pi)  # from the sun's azimuth, 0
    off_horizon = np.abs(mu - horizon_mu) > np.sin(np.radians(1.0))
    print(f"{args.atmosphere}, {args.wavelengths} bands, observer at 1 km, grid {args.mu} x "
          f"{args.phi}; |grid / lookup - 1| [%]")
    for sun_zenith_deg in SUN_ZENITHS_DEG:
        sun = local_frame_directions(np.radians(sun_zenith_deg), 0.0)
        start = time.perf_counter()
        grid = solver.sky_radiance(origin, local_frame_directions(grid_zenith, grid_phi), sun)
        seconds = time.perf_counter() - start
        exact = solver.sky_radiance(origin, views, sun)
        estimate = grid_estimate(np.log(np.maximum(grid, 1e-300)), u_mu, phi)
        lit = exact > 1e-30
        error = np.where(lit, np.abs(estimate / np.where(lit, exact, 1.0) - 1.0), np.nan)
        away = np.degrees(np.arccos(np.clip(views @ sun, -1.0, 1.0))) > 5.0
        parts = {"all": error, "> 5 deg from the sun": error[away],
                 "> 1 deg from the horizon": error[off_horizon]}
        summary = "; ".join(
            f"{label}: median {100 * np.nanmedian(e):.3f}, p99.9 "
            f"{100 * np.nanpercentile(e, 99.9):.2f}, max {100 * np.nanmax(e):.1f}"
            for label, e in parts.items())
        print(f"  sun zenith {sun_zenith_deg:4.0f} deg: grid {seconds:.3f} s; {summary}")


if __name__ == "__main__":
    main()
