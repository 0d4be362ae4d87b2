"""Benchmark: the tables' scattering orders in a cloud slab against a plane-parallel solution.

The slab of `skyscatter.validate.slab` (Henyey-Greenstein g = 0.75, single-scattering albedo 1,
black ground, sun at the zenith; van de Hulst 1980, Table 37) is solved order by order with a
plane-parallel successive-orders method written here for the purpose: azimuthally averaged
radiance (the sun at the zenith makes the field azimuth-free), Gauss-Legendre angles in each
hemisphere, the phase function as its Legendre series g^l (2l + 1), the slab cut into thin
layers with the source constant in each (exact exponential transmission). Its summed orders
reproduce van de Hulst's fluxes to 1e-4 (printed). The tables' orders n = 1, 2 are the
differences of tables computed with 1 and 2 orders; printed per view zenith: the radiance
leaving the bottom downwards and the top upwards, tables against the plane-parallel solution.
The upward ray at mu = 0.001 from just above the slab is not comparable: on the tables' shell
of Earth's radius it grazes the slab's top along a chord of ~13 km instead of an infinite
plane-parallel path.

Run: PYTHONPATH=src python benchmarks/compare_slab_orders.py [--tau 1] [--scattering-mu 128]
"""

from __future__ import annotations

import argparse
from dataclasses import replace

import numpy as np
from numpy.polynomial.legendre import leggauss, legvander

from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.tables import TableResolution, precompute_tables
from skyscatter.validate.slab import PUBLISHED, SLAB_G, slab_profile

LEGENDRE_TERMS = 400  # g^400 < 1e-49 for g = 0.75: the series is complete


def successive_orders(tau: float, orders: int, n_mu: int = 48, layers_per_tau: int = 400
                      ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per order n = 1 .. orders: (mu (n_mu,), downward radiance at the bottom, upward radiance
    at the top), for a beam of irradiance 1 at normal incidence."""
    x, w = leggauss(n_mu)
    mu, weight = 0.5 * (x + 1.0), 0.5 * w
    mus = np.concatenate([mu, -mu])  # > 0: travelling down
    weights = np.concatenate([weight, weight])
    coefficients = (2 * np.arange(LEGENDRE_TERMS) + 1) * SLAB_G ** np.arange(LEGENDRE_TERMS)
    legendre = legvander(mus, LEGENDRE_TERMS - 1)
    phase = (legendre * coefficients) @ legendre.T  # azimuth mean, (1/2) int p dmu' = 1
    beam = (legendre * coefficients) @ legvander(np.array([1.0]), LEGENDRE_TERMS - 1)[0]
    n_layers = max(int(layers_per_tau * tau), 100)
    step = tau / n_layers
    depth = (np.arange(n_layers) + 0.5) * step
    source = beam[None, :] / (4.0 * np.pi) * np.exp(-depth)[:, None]
    keep = np.exp(-step / np.abs(mus))
    down, up = slice(0, n_mu), slice(n_mu, 2 * n_mu)
    result = []
    for _ in range(orders):
        radiance = np.zeros((n_layers + 1, 2 * n_mu))
        for k in range(n_layers):
            radiance[k + 1, down] = (radiance[k, down] * keep[down]
                                     + source[k, down] * (1.0 - keep[down]))
        for k in range(n_layers - 1, -1, -1):
            radiance[k, up] = radiance[k + 1, up] * keep[up] + source[k, up] * (1.0 - keep[up])
        result.append((mu, radiance[-1, down].copy(), radiance[0, up].copy()))
        middle = 0.5 * (radiance[:-1] + radiance[1:])
        source = 0.5 * (middle * weights) @ phase.T
    return result


def fluxes(orders: list[tuple[np.ndarray, np.ndarray, np.ndarray]], n_mu: int = 48
           ) -> tuple[float, float]:
    """(R, T_d) of the summed orders, divided by the incident irradiance."""
    _, weight = leggauss(n_mu)
    mu = orders[0][0]
    down = sum(o[1] for o in orders)
    up = sum(o[2] for o in orders)
    return (float(2.0 * np.pi * np.sum(up * mu * 0.5 * weight)),
            float(2.0 * np.pi * np.sum(down * mu * 0.5 * weight)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tau", type=float, default=1.0, choices=sorted(PUBLISHED))
    parser.add_argument("--scattering-mu", type=int, default=TableResolution.scattering_mu)
    args = parser.parse_args()
    reference = successive_orders(args.tau, 300)
    reflectance, transmittance = fluxes(reference)
    published = PUBLISHED[args.tau]
    print(f"plane-parallel, 300 orders: R {reflectance:.5f} (published "
          f"{published.reflectance:.5f}), T_d {transmittance:.5f} (published "
          f"{published.diffuse_transmittance:.5f})")
    profile = slab_profile(args.tau)
    resolution = replace(TableResolution(), truncation_angle_deg=0.0,
                         scattering_mu=args.scattering_mu)
    mu = reference[0][0]
    sun = np.array([0.0, 0.0, 1.0])
    below = np.array([0.0, 0.0, profile.bottom_radius_m + 0.01])
    above = np.array([0.0, 0.0, profile.top_radius_m + 1.0])
    looking_up = local_frame_directions(np.arccos(mu), np.zeros_like(mu))
    looking_down = local_frame_directions(np.pi - np.arccos(mu), np.zeros_like(mu))
    summed = [np.zeros((2, mu.size))]
    for orders in (1, 2):
        solver = LutSolver(profile, tables=precompute_tables(profile, resolution, orders),
                           orders=orders)
        summed.append(np.stack([solver.sky_radiance(below, looking_up, sun)[..., 0],
                                solver.sky_radiance(above, looking_down, sun)[..., 0]]))
    print("| order | mu | down: tables | plane-parallel | error | up: tables | plane-parallel "
          "| error |")
    print("|---|---|---|---|---|---|---|---|")
    for order in (1, 2):
        tables = summed[order] - summed[order - 1]
        _, down, up = reference[order - 1]
        for i in range(0, mu.size, 4):
            print(f"| {order} | {mu[i]:.3f} | {tables[0, i]:.4e} | {down[i]:.4e} "
                  f"| {100 * (tables[0, i] / down[i] - 1):+.1f} % | {tables[1, i]:.4e} "
                  f"| {up[i]:.4e} | {100 * (tables[1, i] / up[i] - 1):+.1f} % |")


if __name__ == "__main__":
    main()
