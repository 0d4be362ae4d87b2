"""Accuracy: a cloud slab's reflectance and transmittance from the tables, from PythonicDISORT
and as published (van de Hulst 1980, vol. 2, Table 37, DISORT's test problem 3:
skyscatter.validate.slab), for each forward-peak truncation angle of the tables.

Henyey-Greenstein g = 0.75, single-scattering albedo 1, optical thickness 1 and 8, black
ground, sun at the zenith. Prints R, T_d (diffuse) and R + T_d + T_0 (1 for this conservative
slab) and the tables' relative error in R and T_d, with the precompute time and the orders the
tables iterated before their geometric tail.

Run: python benchmarks/compare_slab_fluxes.py [--resolution small|default]
     [--truncation 0 5 10 15 20] [--orders 200] [--taus 1 8]
small: a few seconds per table; default (Bruneton's sizes): 1-4 min per table on 2 cores.
"""

from __future__ import annotations

import argparse
import time

from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.tables import TableResolution, precompute_tables
from skyscatter.validate.slab import (
    PUBLISHED,
    SlabFluxes,
    disort_slab_fluxes,
    slab_profile,
    table_slab_fluxes,
)

SMALL = dict(scattering_r=8, scattering_mu=32, scattering_mu_s=16, scattering_nu=4,
             transmittance_r=16, transmittance_mu=64, irradiance_r=4, irradiance_mu_s=16)


def row(tau: float, label: str, fluxes: SlabFluxes, published: SlabFluxes, note: str = "") -> str:
    """One Markdown row: the fluxes and their relative error against the published ones."""
    error_r = fluxes.reflectance / published.reflectance - 1.0
    error_t = fluxes.diffuse_transmittance / published.diffuse_transmittance - 1.0
    return (f"| {tau:g} | {label} | {fluxes.reflectance:.5f} | "
            f"{fluxes.diffuse_transmittance:.5f} | {fluxes.total:.5f} | {100 * error_r:+.2f} % | "
            f"{100 * error_t:+.2f} % | {note} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", choices=("small", "default"), default="small")
    parser.add_argument("--truncation", type=float, nargs="+", default=[0.0, 5.0, 10.0, 15.0,
                                                                           20.0])
    parser.add_argument("--orders", type=int, default=200)
    parser.add_argument("--taus", type=float, nargs="+", default=sorted(PUBLISHED),
                        choices=sorted(PUBLISHED), help="optical thicknesses")
    args = parser.parse_args()
    sizes = SMALL if args.resolution == "small" else {}
    print("| tau | source | R | T_d | R + T_d + T_0 | R error | T_d error | tables |")
    print("|---|---|---|---|---|---|---|---|")
    for tau in args.taus:
        published = PUBLISHED[tau]
        profile = slab_profile(tau)
        disort = disort_slab_fluxes(profile)
        print(row(tau, "published", published, published))
        print(row(tau, "DISORT 32 streams", disort, published))
        for angle in args.truncation:
            start = time.perf_counter()
            tables = precompute_tables(profile, TableResolution(truncation_angle_deg=angle,
                                                                **sizes), args.orders)
            seconds = time.perf_counter() - start
            ours = table_slab_fluxes(LutSolver(profile, tables=tables, orders=args.orders),
                                     profile)
            print(row(tau, f"tables {args.resolution}, truncation {angle:g} deg", ours,
                      published, f"{seconds:.0f} s, {tables.orders_computed} orders"),
                  flush=True)

if __name__ == "__main__":
    main()
