"""Benchmark: a table entry on disk. Its size, the time to store it and to read it back (from
the page cache, and from the disk after the file was dropped from the page cache), and how
far the tables read back are from the ones computed, for two source trees in one run.

Each (tree, atmosphere) runs in its own Python process with `PYTHONPATH=TREE/src`, one after
the other: it precomputes and stores a one-wavelength table first (so that numba's
compilation is not timed), then the atmosphere's tables at the default resolution and
`DEFAULT_WAVELENGTH_BINS` bands, and stores and loads them three times each (best reported;
store = `tables_to_arrays` + `TableCache.store`, load = `TableCache.load` with its checksum +
`tables_from_arrays`). The cold load asks the kernel to drop the entry's pages first
(`posix_fadvise(DONTNEED)`). Error: |loaded / computed − 1| of the scattering table's values
above 1e-30 of its largest.

Run: python benchmarks/bench_table_cache.py --trees BEFORE_TREE AFTER_TREE
     [--atmospheres earth mars-physical]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

CHILD = """
import json, os, sys, tempfile, time
from pathlib import Path
import numpy as np
from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport import table_store
from skyscatter.transport.cache import TableCache
from skyscatter.transport.table_parameterisation import COS_SUN_ZENITH_MIN
from skyscatter.transport.tables import TableResolution, precompute_tables

def store(tables, profile, orders, folder):
    metadata = table_store.table_metadata(profile, TableResolution(), orders,
                                          COS_SUN_ZENITH_MIN)
    cache = TableCache(folder)
    start = time.perf_counter()
    cache.store("entry", table_store.tables_to_arrays(tables), metadata)
    return time.perf_counter() - start, cache, metadata

def load(cache, metadata, cold):
    if cold:
        with open(cache.path("entry"), "rb") as stream:
            os.fsync(stream.fileno())
            os.posix_fadvise(stream.fileno(), 0, 0, os.POSIX_FADV_DONTNEED)
    start = time.perf_counter()
    arrays, reason = cache.load("entry", metadata)
    tables = table_store.tables_from_arrays(arrays, metadata)
    return time.perf_counter() - start, tables

atmosphere = load_atmosphere(sys.argv[1])
orders = atmosphere.scattering_orders
with tempfile.TemporaryDirectory() as folder:
    small = atmosphere.optical_profile(wavelength_grid(1))
    seconds, cache, metadata = store(precompute_tables(small, orders=2), small, 2, folder)
    load(cache, metadata, False)  # compile
profile = atmosphere.optical_profile(wavelength_grid(DEFAULT_WAVELENGTH_BINS))
tables = precompute_tables(profile, orders=orders)
computed = tables.scattering.copy()
stores, warm, cold = [], [], []
for _ in range(3):
    with tempfile.TemporaryDirectory(dir=Path.home()) as folder:
        seconds, cache, metadata = store(tables, profile, orders, folder)
        stores.append(seconds)
        size = cache.path("entry").stat().st_size
        seconds, loaded = load(cache, metadata, True)
        cold.append(seconds)
        seconds, loaded = load(cache, metadata, False)
        warm.append(seconds)
above = computed >= computed.max() * 1e-30
error = np.abs(loaded.scattering[above] / computed[above].astype(float) - 1.0)
print(json.dumps({"entry_mib": size / 2**20, "store_s": min(stores), "load_warm_s": min(warm),
                  "load_cold_s": min(cold), "median_error": float(np.median(error)),
                  "max_error": float(error.max())}))
"""


def measure(tree: Path, atmosphere: str) -> dict | None:
    environment = dict(os.environ, PYTHONPATH=str(tree / "src"))
    result = subprocess.run([sys.executable, "-c", CHILD, atmosphere], env=environment,
                            capture_output=True, text=True, check=False)
    if result.returncode != 0:
        print(f"  {tree} {atmosphere}: failed\n{result.stderr[-2000:]}", file=sys.stderr)
        return None
    return json.loads(result.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trees", nargs="+", type=Path, default=[Path(".")])
    parser.add_argument("--atmospheres", nargs="+", default=["earth", "mars-physical"])
    args = parser.parse_args()
    print("| atmosphere | tree | entry [MiB] | store [s] | load, page cache [s] | "
          "load, from disk [s] | median / largest error |")
    print("|---|---|---|---|---|---|---|")
    for atmosphere in args.atmospheres:
        for tree in args.trees:
            row = measure(tree.resolve(), atmosphere)
            if row is None:
                continue
            print(f"| {atmosphere} | {tree} | {row['entry_mib']:.1f} | {row['store_s']:.2f} | "
                  f"{row['load_warm_s']:.2f} | {row['load_cold_s']:.2f} | "
                  f"{100 * row['median_error']:.3f} / {100 * row['max_error']:.3f} % |",
                  flush=True)


if __name__ == "__main__":
    main()
