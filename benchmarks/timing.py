"""Timing helper shared by the benchmark scripts (run as `python benchmarks/NAME.py`, so this
directory is on the import path)."""

from __future__ import annotations

import time
import tracemalloc
from collections.abc import Callable


def best_of(function: Callable[[], object], repeats: int = 3,
            warm_up: bool = False) -> tuple[float, float, float]:
    """(best wall time [s], its CPU time [s], peak traced numpy/python memory of one call [MiB]);
    `warm_up` calls `function` once first, untimed (caches, page faults)."""
    if warm_up:
        function()
    best = (float("inf"), 0.0)
    for _ in range(repeats):
        wall, cpu = time.perf_counter(), time.process_time()
        function()
        best = min(best, (time.perf_counter() - wall, time.process_time() - cpu))
    tracemalloc.start()
    function()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return best[0], best[1], peak
