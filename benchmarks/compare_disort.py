"""Accuracy: the table solver against PythonicDISORT (plane-parallel, all orders) for the
`earth` preset. Prints the agreement per sun zenith and wavelength, splits the plane-parallel
radiance into single and multiple scattering to show where the differences come from, and draws
the principal plane (docs/images/disort_comparison.png).

Run: python benchmarks/compare_disort.py [--orders 10] [--streams 32] [--plot PATH | --no-plot]
Needs PythonicDISORT (pip install PythonicDISORT; 1.8 used) and matplotlib for the plot.
Grid: diffuse sky radiance at the ground, view zenith 6-69 deg (DISORT's 10 nodes up to 70 deg),
relative azimuth 0, 45, 90, 135, 180 deg, sun zenith 0, 20, 40, 60, 80 deg, 360/440/550/680 nm.
40-50 s on 2 cores (the tables with 10 orders: 22-36 s; DISORT: 5 s).
docs/physics/disort_comparison.md discusses the numbers.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import SingleScatteringSolver, observer_position
from skyscatter.transport.table_parameterisation import (
    COS_SUN_ZENITH_MIN_EARTH,
    scattering_mu_s_from_u,
)
from skyscatter.validate.disort import (
    DisortComparison,
    compare_with_disort,
    disort_sky_radiance,
    plane_parallel_layers,
    plane_parallel_single_scattering,
)

WAVELENGTHS_NM = np.array([360.0, 440.0, 550.0, 680.0])
SUN_ZENITH_DEG = np.array([0.0, 20.0, 40.0, 60.0, 80.0])
AZIMUTH_DEG = np.array([0.0, 45.0, 90.0, 135.0, 180.0])
MAX_VIEW_ZENITH_DEG = 70.0
PLOT_SUN_ZENITH_DEG = (0.0, 20.0, 60.0, 80.0)
DEFAULT_PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "disort_comparison.png"


def stats(values: np.ndarray) -> str:
    """Median of the signed difference, then median / 95th percentile / max of |difference|."""
    a = np.abs(values)
    return (f"{100 * np.median(values):+6.2f} {100 * np.median(a):6.2f} "
            f"{100 * np.percentile(a, 95):6.2f} {100 * a.max():6.2f}")


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--orders", type=int, default=10)
    parser.add_argument("--streams", type=int, default=32, help="DISORT NQuad")
    parser.add_argument("--layers", type=int, default=60, help="plane-parallel layers")
    parser.add_argument("--plot", type=Path, default=DEFAULT_PLOT)
    parser.add_argument("--no-plot", action="store_true")
    args = parser.parse_args()

    profile = load_atmosphere("earth").optical_profile(WAVELENGTHS_NM, monochromatic=True)
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
        COS_SUN_ZENITH_MIN_EARTH, n_mu_s))) for k in range(n_mu_s - 1, n_mu_s - 6, -1)]
    print("sun-zenith nodes of the scattering tables nearest the zenith [deg]: "
          + ", ".join(f"{z:.1f}" for z in nodes))

    start = time.perf_counter()
    layers = plane_parallel_layers(profile, n_layers=args.layers,
                                   n_moments=max(128, 2 * args.streams))
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
