"""Benchmark: how the precomputed sky converges with the number of scattering orders.

For each atmosphere the tables are precomputed once with many orders N (default resolution,
wavelengths 440 / 550 / 680 nm), and the tables truncated at every order n = 1 .. N are kept on
the way (`precompute_tables` adds one order to its `scattering` and `irradiance` arrays per
step; the tables after step n are exactly those of `precompute_tables(orders=n)`). For a ground
observer and the sun at zenith angles 0, 60 and 85 deg, each truncation gives
  (a) the zenith sky radiance,
  (b) the sky radiance averaged over the upper hemisphere (solid-angle weighted; 18 x 24
      directions, view zenith 2.5-87.5 deg), and the largest error of any one of them,
  (c) the diffuse (sky) irradiance of horizontal ground,
and the truncation error of order n is |Q_n / Q_N - 1|. The error left at N itself is estimated
from the last two increments as a geometric series (ratio q = dQ_N / dQ_(N-1), tail
dQ_N q / (1 - q)); it must be small against the threshold for N to serve as the reference.
Prints the table, the wall time of each order, the orders each atmosphere needs for a
truncation error below --threshold (max over a, b, c, sun zeniths and wavelengths), and writes a
plot of the error against the order.

Run: python benchmarks/bench_orders.py [--atmospheres earth mars-costa:dust*5 ...]
     [--orders 16 28 ...] [--threshold 0.5] [--plot docs/images/orders_convergence.png]
An atmosphere is a preset, a config path, or NAME:CONSTITUENT*FACTOR (that constituent's density
times FACTOR: `mars-costa:dust*5` is a dusty Mars).
About 2-5 s per order on 2 cores (3 wavelengths); the defaults take 7-15 minutes.
Results and the chosen preset orders: docs/physics/orders.md.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numba
import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.variants import load_variant
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.tables import AtmosphereTables, TableResolution, precompute_tables

# preset -> orders of the reference precomputation (enough that its own tail is < 0.05 %)
DEFAULT_ORDERS = {"earth": 16, "earth-bruneton": 14, "mars-costa": 14, "mars-costa:dust*5": 28,
                  "super-earth-10bar": 44}
SUN_ZENITHS_DEG = (0.0, 60.0, 85.0)
WAVELENGTHS_NM = (440.0, 550.0, 680.0)
VIEW_ZENITH_BANDS, VIEW_AZIMUTHS = 18, 24
PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "orders_convergence.png"


class OrderSnapshots:
    """`on_order` hook of `precompute_tables` that copies the tables truncated at each order.

    After order n (one wavelength batch) `multiple` holds the orders 2 .. n and
    `irradiance` the sky light of orders 1 .. n - 1, from `precompute_tables`' `on_order`
    hook (one pass of N orders instead of N(N + 1)/2 for separate precomputations)."""

    def __init__(self) -> None:
        self.multiple: list[np.ndarray] = []
        self.irradiance: list[np.ndarray] = []
        self.seconds: list[float] = []  # wall time of each order (order 1 with transmittance)
        self._last = time.perf_counter()

    def __call__(self, order: int, batch: slice, multiple: np.ndarray,
                 irradiance: np.ndarray) -> None:
        now = time.perf_counter()
        self.multiple.append(multiple.copy())
        self.irradiance.append(irradiance.copy())
        self.seconds.append(now - self._last)
        self._last = time.perf_counter()  # the copies are not the precomputation's time


@dataclass
class Convergence:
    """The quantities of the module docstring for every truncation order n = 1 .. N."""

    name: str
    optical_depth: np.ndarray  # (n_wl,) vertical, extinction [-]
    single_scattering_albedo: np.ndarray  # (n_wl,) column-weighted [-]
    seconds: list[float]
    zenith: np.ndarray  # (N, n_sun, n_wl) [W m^-2 sr^-1 nm^-1]
    hemisphere: np.ndarray  # (N, n_sun, n_wl)
    directions: np.ndarray  # (N, n_sun, n_dir, n_wl)
    diffuse: np.ndarray  # (N, n_sun, n_wl) [W m^-2 nm^-1]
    errors: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (N, n_sun, n_wl)
    tails: dict[str, float] = field(default_factory=dict)  # name -> estimated error left at N

    def __post_init__(self) -> None:
        for key, values in (("zenith", self.zenith), ("hemisphere", self.hemisphere),
                            ("any direction", self.directions), ("diffuse", self.diffuse)):
            error = np.abs(values / values[-1] - 1.0)
            self.errors[key] = error.max(axis=2) if values.ndim == 4 else error
            step = np.diff(values, axis=0)
            with np.errstate(divide="ignore", invalid="ignore"):
                q = np.clip(np.nan_to_num(step[-1] / step[-2]), 0.0, 0.999)
            self.tails[key] = float(np.max(np.abs(step[-1] * q / (1.0 - q) / values[-1])))

    @property
    def orders(self) -> int:
        return self.zenith.shape[0]

    def criterion(self) -> np.ndarray:
        """(N,) max truncation error of (a), (b) and (c) over sun zeniths and wavelengths."""
        return np.max([self.errors[k].max(axis=(1, 2))
                       for k in ("zenith", "hemisphere", "diffuse")], axis=0)

    def needed(self, threshold: float, error: np.ndarray | None = None) -> int:
        """Smallest n whose error and every later one's are below `threshold`."""
        error = self.criterion() if error is None else error
        above = np.nonzero(error >= threshold)[0]
        return int(above[-1]) + 2 if above.size else 1


def hemisphere_views() -> tuple[np.ndarray, np.ndarray]:
    """(directions (n_dir, 3), solid-angle weights (n_dir,) summing to 1) of the upper sky."""
    zenith = (np.arange(VIEW_ZENITH_BANDS) + 0.5) * (0.5 * np.pi / VIEW_ZENITH_BANDS)
    azimuth = np.arange(VIEW_AZIMUTHS) * (2.0 * np.pi / VIEW_AZIMUTHS)
    z, a = np.meshgrid(zenith, azimuth, indexing="ij")
    weights = np.sin(z).reshape(-1)
    return local_frame_directions(z, a).reshape(-1, 3), weights / weights.sum()


def truncated(tables: AtmosphereTables, snapshots: OrderSnapshots, order: int,
              work: np.ndarray) -> AtmosphereTables:
    """The tables of `precompute_tables(orders=order)`, built in the buffer `work`."""
    work[..., -1, :] = snapshots.multiple[order - 1]
    return replace(tables, scattering=work, irradiance=snapshots.irradiance[order - 1],
                   orders=order)


def measure(name: str, orders: int, wavelengths_nm: np.ndarray) -> Convergence:
    """Precompute `name` (`load_variant`) with `orders` orders and evaluate every truncation."""
    atmosphere = load_variant(name)
    profile = atmosphere.optical_profile(wavelengths_nm, monochromatic=True)
    column = np.trapezoid(profile.density, profile.altitudes_m, axis=1)
    depth = column @ profile.extinction_per_density
    albedo = (column @ profile.scattering_per_density) / depth
    snapshots = OrderSnapshots()
    tables = precompute_tables(profile, TableResolution(), orders=orders,
                               wavelength_batch=wavelengths_nm.size, on_order=snapshots)
    if not np.array_equal(snapshots.multiple[-1], tables.scattering[..., -1, :]):
        raise RuntimeError("the last snapshot differs from the returned tables")
    origin = observer_position(0.0, profile.bottom_radius_m)
    views, weights = hemisphere_views()
    suns = [local_frame_directions(np.radians(z), 0.0) for z in SUN_ZENITHS_DEG]
    n_sun, n_wl = len(suns), wavelengths_nm.size
    zenith = np.empty((orders, n_sun, n_wl))
    hemisphere = np.empty((orders, n_sun, n_wl))
    directions = np.empty((orders, n_sun, views.shape[0], n_wl))
    diffuse = np.empty((orders, n_sun, n_wl))
    work = tables.scattering.copy()
    for n in range(1, orders + 1):
        solver = LutSolver(profile, tables=truncated(tables, snapshots, n, work))
        for i, sun in enumerate(suns):
            zenith[n - 1, i] = solver.sky_radiance(origin, np.array([0.0, 0.0, 1.0]), sun)
            directions[n - 1, i] = solver.sky_radiance(origin, views, sun)
            hemisphere[n - 1, i] = weights @ directions[n - 1, i]
            diffuse[n - 1, i] = solver.ground_irradiance(origin, sun)[1]
    return Convergence(name, depth, albedo, snapshots.seconds, zenith, hemisphere, directions,
                       diffuse)


def report(result: Convergence, threshold: float) -> None:
    """Print the convergence table of one atmosphere."""
    wl = ", ".join(f"{w:.0f}" for w in WAVELENGTHS_NM)
    print(f"\n{result.name}: vertical optical depth {np.round(result.optical_depth, 3)} and "
          f"single-scattering albedo {np.round(result.single_scattering_albedo, 3)} at {wl} nm; "
          f"reference N = {result.orders} orders")
    print("truncation error [%], max over sun zenith "
          + "/".join(f"{z:.0f}" for z in SUN_ZENITHS_DEG) + f" deg and {wl} nm")
    print(f"{'order':>5} {'time s':>7} {'zenith':>9} {'hemisph.':>9} {'any dir.':>9} "
          f"{'diffuse E':>9}")
    for n in range(result.orders):
        cells = " ".join(f"{100 * result.errors[k][n].max():9.3f}"
                         for k in ("zenith", "hemisphere", "any direction", "diffuse"))
        print(f"{n + 1:5d} {result.seconds[n]:7.2f} {cells}")
    tails = ", ".join(f"{k} {100 * v:.3f} %" for k, v in result.tails.items())
    print(f"error left at N (geometric tail estimate): {tails}")
    if max(result.tails[k] for k in ("zenith", "hemisphere", "diffuse")) > threshold / 5:
        print(f"WARNING: the error left at N is not small against {100 * threshold:.2g} %: "
              "raise --orders")
    per_order = np.mean(result.seconds[2:]) if result.orders > 3 else float("nan")
    print(f"wall time: order 1 (with transmittance) {result.seconds[0]:.1f} s, order 2 "
          f"{result.seconds[1]:.1f} s, later orders {per_order:.1f} s each; numba threads "
          f"{numba.get_num_threads()}")
    chosen = result.needed(threshold)
    at = max(chosen, 3) - 1  # index of the order whose increment is compared with the previous
    step = np.diff(result.zenith, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):  # float32 tables: steps can vanish
        ratio = step[at - 1] / step[at - 2]
    print(f"ratio of successive orders' zenith radiance at order {at + 1}, sun zenith "
          + "/".join(f"{z:.0f}" for z in SUN_ZENITHS_DEG) + f" deg x {wl} nm: "
          + str(np.round(ratio, 3).tolist()))
    for name in ("zenith", "hemisphere", "diffuse"):
        print(f"  error of {name} with 4 / {chosen} orders [%], same layout: "
              f"{np.round(100 * result.errors[name][3], 2).tolist()} / "
              f"{np.round(100 * result.errors[name][chosen - 1], 3).tolist()}")
    for limit in (threshold, 2 * threshold, 0.2 * threshold):
        print(f"orders needed for < {100 * limit:.2g} %: {result.needed(limit)}  (per sun zenith, "
              f"{wl} nm: "
              + "; ".join(f"{z:.0f} deg: " + "/".join(
                  str(result.needed(limit, np.max([result.errors[k][:, i, w] for k in
                                                    ("zenith", "hemisphere", "diffuse")],
                                                   axis=0)))
                  for w in range(len(WAVELENGTHS_NM)))
                  for i, z in enumerate(SUN_ZENITHS_DEG)) + ")")


def plot(results: list[Convergence], threshold: float, path: Path) -> None:
    """Error against order, log scale, one colour per atmosphere (module docstring)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(7.5, 4.6), dpi=120)
    for index, result in enumerate(results):
        colour = f"C{index}"
        # the last orders approach the reference itself (error 0): plot up to N - 3
        n = np.arange(1, result.orders - 2)
        radiance = np.maximum(result.errors["zenith"], result.errors["hemisphere"])
        needed = result.needed(threshold)
        tau = ", ".join(f"{t:.2g}" for t in result.optical_depth)
        label = result.name.replace(":", ", ").replace("*", " ×")
        axes.semilogy(n, 100 * radiance.max(axis=(1, 2))[:n.size], "-o", color=colour,
                      markersize=3, label=f"{label} (τ {tau}): {needed}")
        axes.semilogy(n, 100 * result.errors["diffuse"].max(axis=(1, 2))[:n.size], "--",
                      color=colour)
        axes.axvline(needed, color=colour, linewidth=0.8, alpha=0.5)
    axes.plot([], [], "-o", color="0.3", markersize=3, label="sky radiance: zenith, hemisphere")
    axes.plot([], [], "--", color="0.3", label="diffuse ground irradiance")
    axes.axhline(100 * threshold, color="k", linewidth=0.8, linestyle=":")
    axes.text(0.99, 100 * threshold, f"{100 * threshold:.2g} %", ha="right", va="bottom",
              transform=axes.get_yaxis_transform())
    axes.set_xlabel("scattering orders n (tables truncated at n)")
    axes.set_ylabel("truncation error [%] (max over sun zenith\n0/60/85 deg and 440/550/680 nm)")
    axes.set_title("Convergence of the precomputed sky with scattering orders (legend: "
                   f"orders needed\nfor < {100 * threshold:.2g} %, vertical lines; τ: vertical "
                   "optical depth at 440, 550, 680 nm)", fontsize=9)
    axes.set_ylim(1e-3, 150.0)
    axes.set_xlim(0.5, max(r.orders for r in results) - 2.5)
    axes.grid(True, which="major", alpha=0.3)
    axes.legend(fontsize=7, loc="upper right", title="atmosphere: orders needed",
                title_fontsize=7)
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path)
    print(f"\nwrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmospheres", nargs="+", default=list(DEFAULT_ORDERS))
    parser.add_argument("--orders", nargs="+", type=int,
                        help="reference orders N, one per atmosphere (defaults: "
                             + ", ".join(f"{k} {v}" for k, v in DEFAULT_ORDERS.items()) + ")")
    parser.add_argument("--threshold", type=float, default=0.5, help="in percent")
    parser.add_argument("--plot", type=Path, default=PLOT)
    args = parser.parse_args()
    orders = args.orders or [DEFAULT_ORDERS.get(name, 30) for name in args.atmospheres]
    if len(orders) != len(args.atmospheres):
        parser.error("give one --orders value per atmosphere")
    wavelengths = np.array(WAVELENGTHS_NM)
    small = TableResolution(scattering_r=4, scattering_mu=8, scattering_mu_s=4,
                            scattering_nu=2, transmittance_r=4, transmittance_mu=8)
    warm = load_atmosphere("earth").optical_profile(wavelengths, monochromatic=True)
    LutSolver(warm, small, orders=2).ground_irradiance(  # JIT warm-up (cached after a run)
        observer_position(0.0, warm.bottom_radius_m), np.array([0.0, 0.0, 1.0]))
    threshold = args.threshold / 100.0
    results = []
    for name, n in zip(args.atmospheres, orders, strict=True):
        start = time.perf_counter()
        results.append(measure(name, n, wavelengths))
        report(results[-1], threshold)
        print(f"({time.perf_counter() - start:.0f} s for {name})")
    if args.plot:
        plot(results, threshold, args.plot)


if __name__ == "__main__":
    main()
