"""Benchmark: precompute time and peak memory of the tables of `earth` (default), `mars-physical`
and `earth-overcast`, for two source trees in one run (issue 17: Earth's may grow by at most
30 %).

Each (tree, atmosphere) runs in its own Python process with `PYTHONPATH=TREE/src`, one after
the other: it first precomputes a tiny table (1 wavelength, 2 orders) so that numba's compilation
is not timed, then the atmosphere's tables at the default resolution, `DEFAULT_WAVELENGTH_BINS`
bands and the config's own orders (what `skyscatter precompute` does; the orders iterated
before the geometric tail took over are reported beside them). Reported: wall time, CPU
time (user + system of all threads: less sensitive to other jobs on a shared machine), the
peak resident memory of the process while precomputing (`ru_maxrss`) and above the process's
memory before it, and the size of the tables. An atmosphere a tree does not know
(a preset added later) is reported as such.

Run: python benchmarks/bench_precompute_media.py --trees BEFORE_TREE AFTER_TREE
     [--atmospheres earth mars-physical earth-overcast]
e.g. `git worktree add /tmp/base a6a0871` (the commit before issue 17's table changes) and
`--trees /tmp/base .`; run it on an otherwise idle machine, or read the times as relative.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

CHILD = """
import json, resource, sys, time
from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.tables import precompute_tables

def cpu_s():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime

def rss_mib():
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * resource.getpagesize() / 2**20

atmosphere = load_atmosphere(sys.argv[1])
precompute_tables(atmosphere.optical_profile(wavelength_grid(1)), orders=2)  # compile
profile = atmosphere.optical_profile(wavelength_grid(DEFAULT_WAVELENGTH_BINS))
before, cpu = rss_mib(), cpu_s()
start = time.perf_counter()
tables = precompute_tables(profile, orders=atmosphere.scattering_orders)
seconds, cpu = time.perf_counter() - start, cpu_s() - cpu
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "cpu_seconds": cpu, "peak_mib": peak,
                  "added_mib": peak - before, "tables_mib": tables.nbytes / 2**20,
                  "orders": atmosphere.scattering_orders,
                  "orders_computed": getattr(tables, "orders_computed",
                                             atmosphere.scattering_orders)}))
"""


def measure(tree: Path, atmosphere: str) -> dict | None:
    """The child's measurement, or None when `tree` has no such atmosphere."""
    env = dict(os.environ, PYTHONPATH=str(tree / "src"))
    done = subprocess.run([sys.executable, "-c", CHILD, atmosphere], env=env,
                          capture_output=True, text=True, check=False)
    if done.returncode != 0:
        reason = done.stderr.strip().splitlines()[-1] if done.stderr.strip() else "failed"
        print(f"  {tree} {atmosphere}: {reason}", flush=True)
        return None
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trees", nargs=2, type=Path, required=True,
                        metavar=("BEFORE", "AFTER"))
    parser.add_argument("--atmospheres", nargs="+",
                        default=["earth", "mars-physical", "earth-overcast"])
    args = parser.parse_args()
    rows = []
    for atmosphere in args.atmospheres:
        for label, tree in zip(("before", "after"), args.trees, strict=True):
            result = measure(tree.resolve(), atmosphere)
            rows.append((atmosphere, label, result))
            print(f"{atmosphere} {label}: {result}", flush=True)
    print("\n| atmosphere | tree | orders (iterated) | precompute [s] | CPU [s] | peak RSS [MiB] "
          "| added [MiB] | tables [MiB] |")
    print("|---|---|---|---|---|---|---|---|")
    for atmosphere, label, r in rows:
        if r is None:
            print(f"| {atmosphere} | {label} | – | not available | | | | |")
            continue
        print(f"| {atmosphere} | {label} | {r['orders']} ({r['orders_computed']}) "
              f"| {r['seconds']:.1f} "
              f"| {r['cpu_seconds']:.1f} | {r['peak_mib']:.0f} | {r['added_mib']:.0f} "
              f"| {r['tables_mib']:.0f} |")


if __name__ == "__main__":
    main()
