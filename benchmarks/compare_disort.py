"""Accuracy: the table solver against PythonicDISORT (plane-parallel, all orders).

Default (the `earth` preset): prints the agreement per sun zenith and wavelength, splits the
plane-parallel radiance into single and multiple scattering to show where the differences come
from, and draws the principal plane (docs/images/disort_comparison.png).

With --truncation (forward-peaked media, issue 17): the tables of one atmosphere (a preset, or
`mars-hg-dust`: mars-physical with HG g 0.65 dust, benchmarks/bench_forward_peak.py) computed
for each forward-peak truncation angle given (`TableResolution.truncation_angle_deg`; 0: none),
each against the same DISORT reference (delta-M with `--streams` streams and the
Nakajima-Tanaka corrections from `--moments` Legendre moments); `--check-streams` solves DISORT
again with another stream count and prints how much the reference moved (its convergence);
the plane-parallel geometry's own share is the ray-marched spherical single scattering against
the plane-parallel closed form (printed per sun zenith). Prints |tables / DISORT - 1| (median,
95th percentile) per sun zenith and band for every angle as a Markdown table.

Run: python benchmarks/compare_disort.py [--orders 10] [--streams 32] [--plot PATH | --no-plot]
     python benchmarks/compare_disort.py --atmosphere mars-physical --truncation 0 5 10 15 20
         --suns 0 20 40 60 --streams 64 --check-streams 96 --moments 512
Needs PythonicDISORT (pip install PythonicDISORT; 1.8 used) and matplotlib for the plot.
Grid: diffuse sky radiance at the ground, view zenith 6-69 deg (DISORT's nodes up to 70 deg),
relative azimuth 0, 45, 90, 135, 180 deg, sun zenith 0, 20, 40, 60, 80 deg, 360/440/550/680 nm.
Earth: 40-50 s on 2 cores (the tables with 10 orders: 22-36 s; DISORT: 5 s).
docs/physics/disort_comparison.md discusses the numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np
from bench_forward_peak import atmosphere as benchmark_atmosphere

from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver, observer_position
from skyscatter.transport.table_parameterisation import scattering_mu_s_from_u
from skyscatter.transport.tables import TableResolution, precompute_tables
from skyscatter.validate.disort import (
    DisortComparison,
    compare_with_disort,
    disort_reference,
    disort_sky_radiance,
    plane_parallel_layers,
    plane_parallel_single_scattering,
    solver_on_nodes,
)

WAVELENGTHS_NM = np.array([360.0, 440.0, 550.0, 680.0])
SUN_ZENITH_DEG = np.array([0.0, 20.0, 40.0, 60.0, 80.0])
AZIMUTH_DEG = np.array([0.0, 45.0, 90.0, 135.0, 180.0])
MAX_VIEW_ZENITH_DEG = 70.0
PLOT_SUN_ZENITH_DEG = (0.0, 20.0, 60.0, 80.0)
# the aureole is judged apart: statistics "away from the sun" leave out lines of sight nearer
AWAY_DEG = 10.0
DEFAULT_PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "disort_comparison.png"


def agreement(values: np.ndarray) -> tuple[float, float, float, float]:
    """Median of the signed relative difference, then median / 95th percentile / max of its
    absolute value, in %."""
    a = np.abs(values)
    return (100 * float(np.median(values)), 100 * float(np.median(a)),
            100 * float(np.percentile(a, 95)), 100 * float(a.max()))


def stats(values: np.ndarray) -> str:
    """`agreement` in fixed-width columns."""
    signed, median, p95, largest = agreement(values)
    return f"{signed:+6.2f} {median:6.2f} {p95:6.2f} {largest:6.2f}"


def print_agreement(c: DisortComparison) -> None:
    r = c.relative_difference  # (n_sun, n_view, n_az, n_wl)
    header = "median   |med|   |p95|   |max|  [%]"
    print(f"\nours / DISORT - 1 over view zenith x azimuth ({r.shape[1]} x {r.shape[2]} points)")
    print(f"{'sun zenith':>10} {'wavelength':>10}   {header}")
    for i, theta_s in enumerate(np.degrees(c.sun_zenith_rad)):
        for w, wl in enumerate(c.wavelengths_nm):
            print(f"{theta_s:10.0f} {wl:10.0f}   {stats(r[i, ..., w])}")
        print(f"{theta_s:10.0f} {'all':>10}   {stats(r[i])}")
    low = r[np.degrees(c.sun_zenith_rad) <= 60.0]
    print(f"{'0-60':>10} {'all':>10}   {stats(low)}")
    print(f"{'0-80':>10} {'all':>10}   {stats(r)}")


def print_single_scattering_split(profile, c: DisortComparison, lut_single: LutSolver,
                                  layers) -> None:
    """Where the differences come from: single scattering (spherical ray marching and the
    single-scattering tables against the plane-parallel closed form) and the rest."""
    marcher = SingleScatteringSolver(profile, n_samples=512)
    position = observer_position(0.0, profile.bottom_radius_m)
    azimuth = c.relative_azimuth_rad
    zenith, phi = np.meshgrid(c.view_zenith_rad, azimuth, indexing="ij")
    views = local_frame_directions(zenith, phi)
    print("\nsingle scattering alone, |med| / |max| [%]: (a) ray-marched spherical vs "
          "plane-parallel closed form (curvature),\n(b) tables (1 order) vs ray-marched "
          "(table interpolation); (c) orders >= 2 + ground: ours vs DISORT minus (closed "
          "form),\nmedian and max |difference| relative to the multiple-scattering part")
    for i, theta_s in enumerate(c.sun_zenith_rad):
        sun = local_frame_directions(theta_s, 0.0)
        closed = plane_parallel_single_scattering(layers, profile.toa_irradiance, theta_s,
                                                  c.view_zenith_rad, azimuth)
        marched = marcher.sky_radiance(position, views, sun)
        table = lut_single.sky_radiance(position, views, sun)
        curvature = np.abs(marched / closed - 1)
        interpolation = np.abs(table / marched - 1)
        multiple = np.abs((c.ours[i] - table) / (c.reference[i] - closed) - 1)
        print(f"  sun zenith {np.degrees(theta_s):3.0f}:  (a) {100 * np.median(curvature):5.2f} "
              f"/ {100 * curvature.max():5.2f}   (b) {100 * np.median(interpolation):5.2f} / "
              f"{100 * interpolation.max():5.2f}   (c) {100 * np.median(multiple):5.2f} / "
              f"{100 * multiple.max():5.2f}")


def plot_principal_plane(profile, solver: LutSolver, layers, path: Path,
                         n_streams: int) -> None:
    """Radiance in the sun's vertical plane, ours (lines) and DISORT (points), and the
    relative difference below; negative view zenith = away from the sun."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    position = observer_position(0.0, profile.bottom_radius_m)
    signed = np.linspace(-MAX_VIEW_ZENITH_DEG, MAX_VIEW_ZENITH_DEG, 281)
    views = local_frame_directions(np.radians(np.abs(signed)),
                                   np.where(signed < 0.0, np.pi, 0.0))
    colours = {360.0: "#7b3294", 440.0: "#2c7bb6", 550.0: "#1a9641", 680.0: "#d7191c"}
    fig, axes = plt.subplots(2, len(PLOT_SUN_ZENITH_DEG), figsize=(13, 6.2), sharex=True,
                             gridspec_kw={"height_ratios": [2.2, 1]})
    for j, theta_s_deg in enumerate(PLOT_SUN_ZENITH_DEG):
        theta_s = np.radians(theta_s_deg)
        sun = local_frame_directions(theta_s, 0.0)
        ours = solver.sky_radiance(position, views, sun)
        view_zenith, reference = disort_sky_radiance(
            profile, theta_s, np.array([0.0, np.pi]), np.radians(MAX_VIEW_ZENITH_DEG),
            n_streams=n_streams, layers=layers)
        node_signed = np.concatenate([-np.degrees(view_zenith)[::-1], np.degrees(view_zenith)])
        node_reference = np.concatenate([reference[::-1, 1], reference[:, 0]])
        node_views = local_frame_directions(np.radians(np.abs(node_signed)),
                                            np.where(node_signed < 0.0, np.pi, 0.0))
        node_ours = solver.sky_radiance(position, node_views, sun)
        top, bottom = axes[0, j], axes[1, j]
        for w, wl in enumerate(profile.wavelengths_nm):
            colour = colours.get(float(wl), "k")
            top.plot(signed, ours[:, w], color=colour, lw=1.4, label=f"{wl:.0f} nm ours")
            top.plot(node_signed, node_reference[:, w], "o", color=colour, ms=3.5, mfc="none",
                     label=f"{wl:.0f} nm DISORT")
            bottom.plot(node_signed, 100 * (node_ours[:, w] / node_reference[:, w] - 1), "o-",
                        color=colour, ms=3, lw=0.8)
        if theta_s_deg <= MAX_VIEW_ZENITH_DEG:
            top.axvline(theta_s_deg, color="0.6", lw=0.8, ls=":")
            bottom.axvline(theta_s_deg, color="0.6", lw=0.8, ls=":")
        top.set_yscale("log")
        top.set_title(f"sun zenith {theta_s_deg:.0f}°")
        bottom.axhline(0.0, color="0.3", lw=0.6)
        bottom.set_ylim(-3.5, 7)
        bottom.set_xlabel("view zenith [deg] (+: towards the sun)")
        top.grid(alpha=0.3, which="both")
        bottom.grid(alpha=0.3)
    axes[0, 0].set_ylabel("diffuse radiance [W m⁻² sr⁻¹ nm⁻¹]")
    axes[1, 0].set_ylabel("ours / DISORT − 1 [%]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels) // 2,
               fontsize=8, frameon=False)
    fig.suptitle("Earth preset, ground, principal plane: table solver (lines) vs "
                 "PythonicDISORT plane-parallel (points)", fontsize=11)
    fig.tight_layout(rect=(0, 0.06, 1, 0.97))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, metadata={"Software": None})
    plt.close(fig)
    print(f"\nwrote {path}")


def curvature(profile, layers, sun_zenith_rad: np.ndarray, view_zenith_rad: np.ndarray,
              azimuth_rad: np.ndarray) -> np.ndarray:
    """|ray-marched spherical / plane-parallel closed-form single scattering - 1| per sun
    zenith, (n_sun, n_view, n_az, n_wl): what the plane-parallel geometry alone changes."""
    marcher = SingleScatteringSolver(profile, n_samples=512)
    position = observer_position(0.0, profile.bottom_radius_m)
    zenith, phi = np.meshgrid(view_zenith_rad, azimuth_rad, indexing="ij")
    views = local_frame_directions(zenith, phi)
    result = []
    for theta_s in sun_zenith_rad:
        closed = plane_parallel_single_scattering(layers, profile.toa_irradiance, theta_s,
                                                  view_zenith_rad, azimuth_rad)
        marched = marcher.sky_radiance(position, views, local_frame_directions(theta_s, 0.0))
        result.append(np.abs(marched / closed - 1.0))
    return np.stack(result)


def angle_from_sun_deg(comparison: DisortComparison) -> np.ndarray:
    """Scattering angle between each line of sight and the sun, (n_sun, n_view, n_az). [deg]"""
    theta = comparison.view_zenith_rad[None, :, None]
    theta_s = comparison.sun_zenith_rad[:, None, None]
    phi = comparison.relative_azimuth_rad[None, None, :]
    cosine = (np.cos(theta) * np.cos(theta_s)
              + np.sin(theta) * np.sin(theta_s) * np.cos(phi))
    return np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))


def truncation_sweep(args: argparse.Namespace) -> None:
    """Tables for each truncation angle against one DISORT reference (module docstring)."""
    atmosphere = benchmark_atmosphere(args.atmosphere)
    orders = atmosphere.scattering_orders if args.orders is None else args.orders
    profile = atmosphere.optical_profile(WAVELENGTHS_NM, monochromatic=True)
    suns = np.radians(args.suns)
    azimuths = np.radians(AZIMUTH_DEG)
    start = time.perf_counter()
    layers = plane_parallel_layers(profile, n_layers=args.layers, n_moments=args.moments)
    print(f"{args.atmosphere}: {orders} orders; column optical depth "
          + ", ".join(f"{wl:.0f} nm {tau:.3f}" for wl, tau in zip(
              WAVELENGTHS_NM, layers.optical_depth[-1], strict=True)))
    cache = (None if args.reference_cache is None else
             args.reference_cache / f"disort_{args.atmosphere}_{args.streams}.npz")
    if cache is not None and cache.exists():
        reference = DisortComparison(**dict(np.load(cache)))
    else:
        reference = disort_reference(profile, suns, azimuths, np.radians(MAX_VIEW_ZENITH_DEG),
                                     n_streams=args.streams, layers=layers)
        if cache is not None:
            cache.parent.mkdir(parents=True, exist_ok=True)
            np.savez(cache, **dataclasses.asdict(reference))
    print(f"DISORT: {args.streams} streams, {args.moments} moments, "
          f"{layers.optical_depth.shape[0]} layers, {time.perf_counter() - start:.0f} s "
          "; view zenith nodes [deg]: "
          + ", ".join(f"{z:.1f}" for z in np.degrees(reference.view_zenith_rad)))
    geometry = curvature(profile, layers, suns, reference.view_zenith_rad, azimuths)
    for i, theta_s in enumerate(suns):
        print(f"  plane-parallel geometry, sun zenith {np.degrees(theta_s):.0f}: spherical / "
              f"plane-parallel single scattering - 1: median {100 * np.median(geometry[i]):.2f}"
              f" %, max {100 * geometry[i].max():.2f} %")
    away = angle_from_sun_deg(reference) > AWAY_DEG
    results, solvers = {}, {}
    for angle in args.truncation:
        start = time.perf_counter()
        tables = precompute_tables(profile, TableResolution(truncation_angle_deg=angle), orders)
        solver = LutSolver(profile, tables=tables, orders=orders)
        results[angle] = solver_on_nodes(solver, profile, reference).relative_difference
        solvers[angle] = solver
        print(f"  tables, truncation {angle:g} deg: {time.perf_counter() - start:.0f} s, "
              f"{tables.orders_computed} orders computed, tail share "
              + ", ".join(f"{100 * t:.2f} %" for t in tables.tail_share)
              + "; median / 95th pct per sun zenith: " + ", ".join(
                  f"{100 * np.median(np.abs(r)):.2f} / {100 * np.percentile(np.abs(r), 95):.1f} %"
                  for r in results[angle]) + f"; beyond {AWAY_DEG:g} deg from the sun: "
              + ", ".join(f"{100 * np.median(np.abs(r[a])):.2f} / "
                          f"{100 * np.percentile(np.abs(r[a]), 95):.1f} %"
                          for r, a in zip(results[angle], away, strict=True)), flush=True)
    print(f"\n{args.atmosphere}: |tables / DISORT - 1|, median / 95th percentile over view "
          f"zenith x azimuth, per truncation angle\n")
    print("| sun zenith | band | " + " | ".join(f"{a:g} deg" for a in args.truncation) + " |")
    print("|---|---|" + "---|" * len(args.truncation))
    for i, theta_s in enumerate(args.suns):
        for w, wl in enumerate([*WAVELENGTHS_NM, None]):
            cells = []
            for angle in args.truncation:
                values = np.abs(results[angle][i] if wl is None else results[angle][i, ..., w])
                cells.append(f"{100 * np.median(values):.2f} / "
                             f"{100 * np.percentile(values, 95):.1f} %")
            label = "all" if wl is None else f"{wl:.0f} nm"
            print(f"| {theta_s:g} | {label} | " + " | ".join(cells) + " |")
    if args.check_streams:
        # the reference's convergence: the same statistics against DISORT with another stream
        # count (on its own nodes; Gauss nodes of two counts do not coincide)
        check = disort_reference(profile, suns, azimuths, np.radians(MAX_VIEW_ZENITH_DEG),
                                 n_streams=args.check_streams, layers=plane_parallel_layers(
                                     profile, n_layers=args.layers,
                                     n_moments=max(args.moments, 2 * args.check_streams)))
        print(f"\nthe same, all bands, against DISORT with {args.check_streams} streams "
              f"(view zenith nodes " + ", ".join(
                  f"{z:.1f}" for z in np.degrees(check.view_zenith_rad)) + ")\n")
        print("| sun zenith | " + " | ".join(f"{a:g} deg" for a in args.truncation) + " |")
        print("|---|" + "---|" * len(args.truncation))
        moved = {a: np.abs(solver_on_nodes(solvers[a], profile, check).relative_difference)
                 for a in args.truncation}
        for i, theta_s in enumerate(args.suns):
            print(f"| {theta_s:g} | " + " | ".join(
                f"{100 * np.median(moved[a][i]):.2f} / {100 * np.percentile(moved[a][i], 95):.1f}"
                " %" for a in args.truncation) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmosphere", default="earth",
                        help="a preset, or mars-hg-dust (benchmarks/bench_forward_peak.py)")
    parser.add_argument("--orders", type=int, default=None,
                        help="scattering orders (default: 10 for earth, else the preset's)")
    parser.add_argument("--streams", type=int, default=32, help="DISORT NQuad")
    parser.add_argument("--check-streams", type=int, default=0,
                        help="a second NQuad whose reference is compared (convergence)")
    parser.add_argument("--moments", type=int, default=128,
                        help="Legendre moments of the layers (delta-M, Nakajima-Tanaka)")
    parser.add_argument("--layers", type=int, default=60, help="plane-parallel layers")
    parser.add_argument("--truncation", type=float, nargs="+", default=None,
                        help="truncation angles [deg] to compare (0: none)")
    parser.add_argument("--suns", type=float, nargs="+", default=[0.0, 20.0, 40.0, 60.0])
    parser.add_argument("--reference-cache", type=Path, default=None,
                        help="folder that keeps the DISORT reference between runs")
    parser.add_argument("--plot", type=Path, default=DEFAULT_PLOT)
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args()
    args.moments = max(args.moments, 2 * args.streams)
    if args.truncation is not None:
        truncation_sweep(args)
        return
    args.orders = 10 if args.orders is None else args.orders

    profile = benchmark_atmosphere(args.atmosphere).optical_profile(WAVELENGTHS_NM,
                                                                   monochromatic=True)
    start = time.perf_counter()
    solver = LutSolver(profile, orders=args.orders)
    lut_seconds = time.perf_counter() - start
    tables = solver.tables
    zenith_orders = tables.order_zenith_radiance
    ratio = zenith_orders[-1] / zenith_orders[-2]
    tail = zenith_orders[-1] * ratio / (1 - ratio) / zenith_orders.sum(axis=0)
    print(f"tables: {args.orders} orders in {lut_seconds:.0f} s; orders left out (geometric "
          f"tail, zenith, sun overhead): "
          + ", ".join(f"{wl:.0f} nm {100 * t:.1e} %" for wl, t in zip(WAVELENGTHS_NM, tail,
                                                                    strict=True)))
    n_mu_s = tables.resolution.scattering_mu_s
    nodes = [np.degrees(np.arccos(scattering_mu_s_from_u(
        (k + 0.5) / n_mu_s, profile.bottom_radius_m, profile.top_radius_m,
        tables.min_cos_sun_zenith, tables.sun_angle_share, n_mu_s)))
        for k in range(n_mu_s - 1, n_mu_s - 6, -1)]
    print("sun-zenith nodes of the scattering tables nearest the zenith [deg]: "
          + ", ".join(f"{z:.1f}" for z in nodes))

    start = time.perf_counter()
    layers = plane_parallel_layers(profile, n_layers=args.layers, n_moments=args.moments)
    comparison = compare_with_disort(solver, profile, np.radians(SUN_ZENITH_DEG),
                                     np.radians(AZIMUTH_DEG), np.radians(MAX_VIEW_ZENITH_DEG),
                                     n_streams=args.streams, layers=layers)
    print(f"DISORT: {args.streams} streams, {layers.optical_depth.shape[0]} layers, "
          f"{time.perf_counter() - start:.0f} s; view zenith nodes [deg]: "
          + ", ".join(f"{z:.1f}" for z in np.degrees(comparison.view_zenith_rad)))
    print("column optical depth: " + ", ".join(
        f"{wl:.0f} nm {tau:.3f}" for wl, tau in zip(WAVELENGTHS_NM, layers.optical_depth[-1],
                                                     strict=True)))
    print_agreement(comparison)
    single = LutSolver(profile, tables=None, orders=1)
    print_single_scattering_split(profile, comparison, single, layers)
    if not args.no_plot:
        plot_principal_plane(profile, solver, layers, args.plot, args.streams)


if __name__ == "__main__":
    main()
