"""Benchmark: Mie optics of Meyran 2022's Mars dust, 48 wavelengths (360-830 nm) x 5000 radii.

ModifiedGamma(1.6 µm, 0.2) with 3 % hematite (Maxwell Garnett) in 1.5 + 0i, C_sca-weighted phase
function on the 861 angles of `MIE_ANGLES_DEG`. `--cloud`: the liquid-water droplets of the
earth-overcast and earth-fog presets instead, ModifiedGamma(10 µm, 0.1) in Segelstein's water on
the 55 wavelengths of a config's Mie table (360-900 nm), size parameters up to 630 (one warm
call instead of the best of 3). Prints the wall time of the first call in this
process (import of miepython and its numba kernels: compiled, or loaded from numba's cache),
the best of 3 warm calls without the disk cache, the first call with a cache (compute + store)
and a cached load; then the peak traced memory of one warm call (tracemalloc: numpy and Python
allocations) and the peak resident set of the process (ru_maxrss).

Run: python benchmarks/bench_mie.py [--fresh-numba-cache] [--cloud]
`--fresh-numba-cache` points NUMBA_CACHE_DIR at a new temporary folder, so that the first call
compiles miepython's kernels from scratch (the cost of a first run after installation).
Goal: warm call < 5 s on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import resource
import tempfile
import time
import tracemalloc
from pathlib import Path


def timed(function) -> tuple[float, object]:
    start = time.perf_counter()
    result = function()
    return time.perf_counter() - start, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fresh-numba-cache", action="store_true",
                        help="compile miepython's numba kernels from scratch (first call)")
    parser.add_argument("--cloud", action="store_true",
                        help="water droplets r_eff 10 µm (earth-overcast) instead of Mars dust")
    args = parser.parse_args()
    if args.fresh_numba_cache:
        os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="bench-mie-numba-")

    import numba
    import numpy as np

    from skyscatter.atmosphere.particle_config import MIE_WAVELENGTHS_NM
    from skyscatter.optics.mie import particle_optics
    from skyscatter.optics.particle_index import load_material, maxwell_garnett
    from skyscatter.optics.size_distribution import ModifiedGamma

    if args.cloud:
        wavelengths = MIE_WAVELENGTHS_NM
        dust = ModifiedGamma(10e-6, 0.1)
        index = load_material("water")
        what, checked, repeats = "water cloud r_eff 10 µm (earth-overcast)", [4, 19, 32], 1
    else:
        wavelengths = np.linspace(360.0, 830.0, 48)
        dust = ModifiedGamma(1.6e-6, 0.2)
        index = maxwell_garnett(1.5 + 0j, load_material("hematite"), 0.03)
        what, checked, repeats = "Mars dust (Meyran 2022)", [8, 19, 32], 3

    def compute(cache_directory=False):
        return particle_optics(dust, index, wavelengths, n_radii=5000,
                               cache_directory=cache_directory)

    print(f"numba threads: {numba.get_num_threads()}; {wavelengths.size} wavelengths x 5000 "
          f"radii, {what}, C_sca-weighted phase")
    first, table = timed(compute)
    print(f"first call (miepython import + JIT{' compile' if args.fresh_numba_cache else ''}): "
          f"{first:6.2f} s")
    warm = min(timed(compute)[0] for _ in range(repeats))
    print(f"warm compute (best of {repeats}):          {warm:6.2f} s   goal < 5 s (dust)")
    with tempfile.TemporaryDirectory(prefix="bench-mie-cache-") as directory:
        store, _ = timed(lambda: compute(Path(directory)))
        load, cached = timed(lambda: compute(Path(directory)))
        size_kib = sum(p.stat().st_size for p in Path(directory, "mie").glob("*.npz")) / 1024
    print(f"compute + store in the cache:      {store:6.2f} s   ({size_kib:.0f} KiB)")
    print(f"cached load:                       {load:6.3f} s")
    assert np.array_equal(cached.phase, table.phase)

    tracemalloc.start()
    compute()
    peak_traced = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    peak_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # Linux: KiB
    print(f"peak traced memory of one call:    {peak_traced:6.1f} MiB")
    print(f"peak resident set of the process:  {peak_rss:6.1f} MiB")
    albedo = table.single_scattering_albedo[checked]
    print(f"check: albedo at {'/'.join(f'{w:g}' for w in wavelengths[checked])} nm = "
          f"{albedo.round(6).tolist()}, g = {table.asymmetry[checked].round(4).tolist()}")


if __name__ == "__main__":
    main()
