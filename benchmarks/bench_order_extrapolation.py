"""Benchmark: how well the sum of the scattering orders of a cloud deck is known after n orders,
with the geometric series of the last order (`tables._geometric_tail`'s ratio) and with
reduced-rank extrapolation (`transport.order_extrapolation`), against many orders.

The tables of one band (`--wavelength`, one wavelength) are precomputed with `--orders`
orders and neither rule allowed to stop them early; the sums of the orders >= 2 after every
order are kept (`precompute_tables`' `on_order` hook). The reference is the last of them plus
its own geometric tail (below 0.05 % of the sum for the stratus at 70 orders). For stops n, each
estimate's |estimate / reference - 1| over the cells brighter than 1e-3 of the median: median,
95th and 99th percentile; RRE with k + 1 = 4, 6 and 7 orders. Then `OrderExtrapolation` as the
tables use it is fed the same orders: where it stops and how far that is from the reference.

Run: python benchmarks/bench_order_extrapolation.py [--atmosphere earth-overcast]
     [--wavelength 550] [--orders 70]
About 2 minutes on 2 cores for the stratus at 70 orders; 1-2 GB for the kept sums.
Results: docs/physics/tables.md ("Cloud decks").
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.transport import order_extrapolation, tables
from skyscatter.transport.tables import precompute_tables

STOPS = (12, 14, 16, 18, 20, 24, 30)
RRE_DELTAS = (4, 6, 7)


def kept_sums(atmosphere: str, wavelength_nm: float, orders: int) -> tuple[np.ndarray, ...]:
    """(sums of the orders >= 2 after orders 1 .. N (N, cells), ground irradiance after each
    (N, cells_e), reference (cells,), reference irradiance, mean radiance per order)."""
    profile = load_atmosphere(atmosphere).optical_profile(np.array([wavelength_nm]),
                                                          monochromatic=True)
    sums, ground = [], []

    def keep(order, batch, multiple, irradiance):
        sums.append(np.array(multiple[..., 0], dtype=np.float32).ravel())
        ground.append(np.array(irradiance[..., 0]).ravel())

    # neither rule may stop the iteration early: the series only at the last order, RRE never
    tolerance = tables.TAIL_TOLERANCE
    tables.TAIL_TOLERANCE = 0.0
    tables.OrderExtrapolation = lambda: order_extrapolation.OrderExtrapolation(orders + 1)
    try:
        computed = precompute_tables(profile, orders=orders, on_order=keep)
    finally:
        tables.TAIL_TOLERANCE = tolerance
        tables.OrderExtrapolation = order_extrapolation.OrderExtrapolation
    return (np.array(sums), np.array(ground), computed.scattering[..., -1, 0].ravel(),
            computed.irradiance[..., 0].ravel(), computed.order_mean_radiance[:, 0])


def error(estimate: np.ndarray, reference: np.ndarray) -> str:
    lit = reference > 1e-3 * np.median(reference[reference > 0.0])
    e = 100.0 * np.abs(estimate[lit] / reference[lit] - 1.0)
    return f"{np.median(e):.2f} / {np.percentile(e, 95):.2f} / {np.percentile(e, 99):.2f} %"


def geometric(sums: np.ndarray, means: np.ndarray, n: int) -> np.ndarray:
    """Orders >= 2 after n orders plus order n's geometric series (ratio of the mean radiance)."""
    ratio = means[n - 1] / means[n - 2]
    return sums[n - 1] + (sums[n - 1] - sums[n - 2]) * ratio / (1.0 - ratio)


def rre(sums: np.ndarray, n: int, deltas: int) -> np.ndarray:
    """The tables' estimate after n orders from the last `deltas` orders."""
    window = sums[n - deltas - 1:n].astype(np.float64)
    steps = np.diff(window, axis=0)[:, :, None]
    cumulative = order_extrapolation._rre_cumulative_weights(steps)
    return window[-1] + order_extrapolation._tail(cumulative, list(steps))[:, 0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--atmosphere", default="earth-overcast")
    parser.add_argument("--wavelength", type=float, default=550.0)
    parser.add_argument("--orders", type=int, default=70)
    args = parser.parse_args()
    start = time.perf_counter()
    sums, ground, reference, reference_ground, means = kept_sums(
        args.atmosphere, args.wavelength, args.orders)
    print(f"{args.atmosphere}, {args.wavelength:g} nm: {args.orders} orders in "
          f"{time.perf_counter() - start:.0f} s; |e| of the orders >= 2, median / 95th / 99th "
          "percentile over the cells\n")
    print("| orders | summed | geometric series | "
          + " | ".join(f"RRE, {d} orders" for d in RRE_DELTAS) + " |")
    print("|---" * (3 + len(RRE_DELTAS)) + "|")
    for n in STOPS:
        if n >= args.orders:
            continue
        cells = [error(sums[n - 1], reference), error(geometric(sums, means, n), reference)]
        cells += [error(rre(sums, n, d), reference) for d in RRE_DELTAS]
        print(f"| {n} | " + " | ".join(cells) + " |")
    extrapolation = order_extrapolation.OrderExtrapolation()
    for order in range(2, args.orders + 1):
        tails = extrapolation.add(order, sums[order - 1][:, None],
                                  (sums[order - 1] - sums[order - 2])[:, None],
                                  (ground[order - 1] - ground[order - 2])[:, None])
        if tails is not None:
            print(f"\nOrderExtrapolation stops at order {order}: orders >= 2 "
                  f"{error(sums[order - 1] + tails[0][:, 0], reference)}, ground irradiance "
                  f"{error(ground[order - 1] + tails[1][:, 0], reference_ground)}")
            break
    else:
        print(f"\nOrderExtrapolation did not stop within {args.orders} orders")


if __name__ == "__main__":
    main()
