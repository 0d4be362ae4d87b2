"""Accuracy: the tables for observers below, inside and above a cloud deck, against DISORT.

`earth-overcast` (a stratus of optical depth 20 between 600 and 1100 m) seen from several
altitudes: the table solver's diffuse radiance against PythonicDISORT's at the same optical
depth of the plane-parallel twin (`validate.disort.disort_sky_radiance` with `altitude_m`),
on DISORT's quadrature directions looking up and looking down (within 70 deg of the zenith
and of the nadir, where the plane-parallel twin's missing curvature stays small) x
relative azimuths 0-180 deg, without the views within 10 deg of the sun (the aureole, which
DISORT's truncated peak does not resolve). `--check-streams` solves DISORT again with another
stream count and prints how far the reference itself moves. Prints, per altitude and sun
zenith, the signed median and the median / 95th percentile / largest |tables / DISORT - 1|
over views and bands, as a Markdown table.

Run: python benchmarks/compare_disort_inside.py [--altitudes 0 700 850 1000 1500]
     [--suns 0 30 60] [--streams 64] [--check-streams 96]
Needs PythonicDISORT (installed by `make`). About 2-3 min on 2 cores (the tables of the
deck at 4 bands; DISORT per altitude, sun and band).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from compare_disort import AWAY_DEG, MAX_VIEW_ZENITH_DEG, WAVELENGTHS_NM, agreement

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.tables import precompute_tables
from skyscatter.validate.disort import disort_sky_radiance, plane_parallel_layers

AZIMUTH_DEG = np.array([0.0, 45.0, 90.0, 135.0, 180.0])
# views within this angle of the zenith or the nadir: the plane-parallel twin's curvature error
# stays small there (as compare_disort.MAX_VIEW_ZENITH_DEG)
MAX_OFF_VERTICAL_DEG = MAX_VIEW_ZENITH_DEG


def reference(profile, layers, altitude_m: float, sun_zenith_deg: float, streams: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """DISORT's (view zenith (n_view,) [rad], radiance (n_view, n_az, n_wl)) at `altitude_m`."""
    return disort_sky_radiance(profile, np.radians(sun_zenith_deg), np.radians(AZIMUTH_DEG),
                               np.pi, n_streams=streams, layers=layers, altitude_m=altitude_m)


def markdown_stats(values: np.ndarray) -> str:
    """`compare_disort.agreement` as Markdown table cells."""
    return " | ".join(f"{value:+.2f}" if i == 0 else f"{value:.2f}"
                      for i, value in enumerate(agreement(values)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmosphere", default="earth-overcast")
    parser.add_argument("--altitudes", type=float, nargs="+",
                        default=[0.0, 700.0, 850.0, 1000.0, 1500.0])
    parser.add_argument("--suns", type=float, nargs="+", default=[0.0, 30.0, 60.0])
    parser.add_argument("--streams", type=int, default=64, help="DISORT NQuad")
    parser.add_argument("--check-streams", type=int, default=0,
                        help="solve DISORT again with this NQuad and report the change")
    parser.add_argument("--moments", type=int, default=256)
    args = parser.parse_args()

    atmosphere = load_atmosphere(args.atmosphere)
    profile = atmosphere.optical_profile(WAVELENGTHS_NM)
    start = time.perf_counter()
    tables = precompute_tables(profile, orders=atmosphere.scattering_orders)
    print(f"{args.atmosphere}: tables at {len(WAVELENGTHS_NM)} bands in "
          f"{time.perf_counter() - start:.1f} s, {tables.orders_computed} orders iterated")
    solver = LutSolver(profile, tables=tables)
    layers = plane_parallel_layers(profile, n_moments=args.moments,
                                   boundaries_m=args.altitudes)
    print(f"\n|tables / DISORT - 1| (DISORT {args.streams} streams, {args.moments} moments; "
          f"views > {AWAY_DEG:g} deg from the sun, {len(WAVELENGTHS_NM)} bands "
          f"{', '.join(f'{w:g}' for w in WAVELENGTHS_NM)} nm), in %:\n")
    check = (f" | DISORT {args.streams} vs {args.check_streams} streams, median / largest"
             if args.check_streams else "")
    print(f"| altitude [m] | sun zenith | looking | signed median | median | 95th pct | "
          f"largest{check} |")
    print("|---|---|---|---|---|---|---|" + ("---|" if check else ""))
    for altitude in args.altitudes:
        position = observer_position(altitude, profile.bottom_radius_m)
        for sun_zenith in args.suns:
            view_zenith, theirs = reference(profile, layers, altitude, sun_zenith, args.streams)
            views = local_frame_directions(*np.meshgrid(view_zenith, np.radians(AZIMUTH_DEG),
                                                        indexing="ij"))
            sun = local_frame_directions(np.radians(sun_zenith), 0.0)
            error = solver.sky_radiance(position, views, sun) / theirs - 1.0
            away = views @ sun < np.cos(np.radians(AWAY_DEG))  # the aureole left out
            moved = None
            if args.check_streams:
                other_zenith, other = reference(profile, layers, altitude, sun_zenith,
                                                args.check_streams)
                # the nodes differ: compare on the zenith of this reference, linearly
                other_on = np.stack([[np.interp(view_zenith, other_zenith, other[:, a, w])
                                      for w in range(other.shape[2])]
                                     for a in range(other.shape[1])]).transpose(2, 0, 1)
                moved = np.abs(other_on / theirs - 1.0)
            steep = np.abs(np.cos(view_zenith)) >= np.cos(np.radians(MAX_OFF_VERTICAL_DEG))
            for looking, half in (("up", view_zenith < 0.5 * np.pi),
                                  ("down", view_zenith > 0.5 * np.pi)):
                if looking == "down" and altitude <= 0.0:
                    continue  # the ground itself: no air between
                mask = away & (half & steep)[:, None]
                row = markdown_stats(error[mask])
                extra = ""
                if moved is not None:
                    part = moved[mask]
                    extra = (f" | {100 * np.median(part):.2f} / {100 * part.max():.2f}")
                print(f"| {altitude:g} | {sun_zenith:g} | {looking} | {row}{extra} |",
                      flush=True)


if __name__ == "__main__":
    main()
