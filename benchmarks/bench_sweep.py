"""Benchmark: `api.sweep` throughput on 1 and 2 local Dask workers, and the scaling law.

A retrieval-style look-up table on the earth preset's tables ("lut" solver, the config's 8
orders, table cache off so that every atmosphere builds its tables): aerosol optical depth
(4 values, log-spaced) x ground albedo (2) = 8 atmospheres, on a sky grid of 5 sun zeniths x
18 view zeniths x 7 azimuths (630 geometries) at 4 wavelengths. The scaling law

    time per atmosphere = table build + geometries x cost per geometry

can be measured term by term: one atmosphere's table build and chunks in this process (the
functions a worker runs, `sweep.tasks`), then the whole sweep on each cluster, beside the
law's prediction (atmospheres / workers, rounded up, x time per atmosphere); the speedup is
the 1-worker time over the N-worker time. The local cluster is started first (its start is
timed apart) and reached by its address, so that each worker's peak resident memory
(`ru_maxrss`, read on the worker by `client.run`) can be read after the sweep. The load
average is printed beside each number: on a shared machine the other processes' load is part
of what is measured.

Run: python benchmarks/bench_sweep.py [--workers 1 2] (docs/sweep.md quotes its output)
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import tempfile
import time

from skyscatter import api
from skyscatter.atmosphere.config_overrides import load_document
from skyscatter.dask_cluster import dask_client
from skyscatter.sweep.plan import SweepPlan
from skyscatter.sweep.tasks import build_solver, compute_chunk

VALUES = {"constituent[2].optics.optical_depth": "0.05:0.8:4:log",
          "planet.ground_albedo": "0,0.3"}
SUN = list(range(0, 81, 20))  # 5
VIEW = [5.0 * i for i in range(18)]  # 0-85
AZIMUTH = [30.0 * i for i in range(7)]  # 0-180
WAVELENGTHS = [400.0, 500.0, 600.0, 700.0]


def peak_rss_mib() -> float:
    """This process's peak resident memory [MiB] (Linux: ru_maxrss in KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def timed_sweep(address: str) -> tuple[float, int]:
    """(wall seconds, atmospheres) of the sweep on the cluster at `address`."""
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        result = api.sweep("earth", VALUES, SUN, VIEW, AZIMUTH, wavelengths_nm=WAVELENGTHS,
                           solver="lut", use_cache=False, scheduler=address,
                           output_path=os.path.join(folder, "lut.nc"))
        seconds = time.perf_counter() - start
    sizes = result.dataset.sizes
    return seconds, sizes["planet_ground_albedo"] * sizes["constituent_2_optics_optical_depth"]


def law_terms() -> tuple[float, float, float, float]:
    """(table build wall [s], its CPU [s], cost per geometry wall [s], its CPU [s]) of one
    atmosphere in this process: `sweep.tasks` as a worker runs them."""
    plan = SweepPlan("earth", *load_document("earth"), (), tuple(map(float, SUN)),
                     tuple(VIEW), tuple(AZIMUTH), tuple(WAVELENGTHS), use_cache=False)
    wall, cpu = time.perf_counter(), time.process_time()
    built = build_solver(plan, 0)
    build = (time.perf_counter() - wall, time.process_time() - cpu)
    compute_chunk(built, plan, 0)  # first call: kernels loaded, caches warm
    wall, cpu = time.perf_counter(), time.process_time()
    for chunk in plan.chunks_of(0):
        compute_chunk(built, plan, chunk)
    geometries = len(SUN) * len(VIEW) * len(AZIMUTH)
    return (*build, (time.perf_counter() - wall) / geometries,
            (time.process_time() - cpu) / geometries)


def load() -> str:
    return "/".join(f"{value:.1f}" for value in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    geometries = len(SUN) * len(VIEW) * len(AZIMUTH)
    print(f"{os.cpu_count()} CPU cores, load average {load()} (1/5/15 min); 8 atmospheres x "
          f"{geometries} geometries x {len(WAVELENGTHS)} wavelengths, earth tables (8 orders), "
          "no table cache")
    build, build_cpu, per_geometry, per_geometry_cpu = law_terms()
    print(f"one atmosphere in-process: table build {build:.1f} s wall ({build_cpu:.1f} s CPU), "
          f"{per_geometry * 1e3:.3f} ms wall ({per_geometry_cpu * 1e3:.3f} ms CPU) per "
          f"geometry; load {load()}")
    print("workers | cluster start [s] | sweep [s] | law [s] | atmospheres/h | geometries/s "
          "| peak RSS per worker [MiB] | speedup | load after")
    baseline = None
    for workers in args.workers:
        start = time.perf_counter()
        with dask_client(workers=workers) as client:
            started = time.perf_counter() - start
            client.run(lambda: None)  # the workers answer
            seconds, atmospheres = timed_sweep(client.scheduler.address)
            peaks = sorted(client.run(peak_rss_mib).values())
        law = math.ceil(atmospheres / workers) * (build + geometries * per_geometry)
        baseline = baseline or seconds
        print(f"{workers} | {started:.1f} | {seconds:.1f} | {law:.1f} | "
              f"{atmospheres / seconds * 3600:.0f} | {atmospheres * geometries / seconds:.0f} | "
              f"{', '.join(f'{p:.0f}' for p in peaks)} | {baseline / seconds:.2f} | {load()}",
              flush=True)


if __name__ == "__main__":
    main()
