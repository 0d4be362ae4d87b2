"""OpenBLAS's idle threads, and the numba kernels that follow a matrix product.

After each matrix product OpenBLAS's worker threads spin for 2^n cycles before they sleep,
n = OPENBLAS_THREAD_TIMEOUT (4..30, default 28: ~0.1 s; OpenBLAS's docs/runtime_variables.md,
read once, when numpy loads OpenBLAS). A numba kernel started in that time shares its cores
with them: the tables' source function, built a few r nodes at a time with a product after
each node batch's incoming-radiance kernel (`transport.tables`), took 12-25 % longer on 2 cores
than built at once. `let_idle_threads_sleep`, called by `skyscatter/__init__.py` before numpy is
imported, sets n = 4 unless the user chose a value; `idle_threads_sleep` says whether OpenBLAS
runs that way in this process (not when numpy was imported before skyscatter with the default).
A base module.
"""

from __future__ import annotations

import os
import sys

__all__ = ["idle_threads_sleep", "let_idle_threads_sleep"]

TIMEOUT_VARIABLE = "OPENBLAS_THREAD_TIMEOUT"
SLEEP_AT_ONCE = "4"  # OpenBLAS's smallest: 2^4 cycles
# a spin taken as short: 2^16 cycles, ~20 us, against kernels of milliseconds (a threshold
# chosen, not measured: 2^4 and 2^28 are the values measured, docs/performance.md)
LONGEST_HARMLESS_SPIN = 16

_sleeping = False


def let_idle_threads_sleep() -> None:
    """Set OPENBLAS_THREAD_TIMEOUT to SLEEP_AT_ONCE unless it is set, and note whether the
    OpenBLAS of this process runs with a short spin (the value when numpy loaded it)."""
    global _sleeping
    chosen = os.environ.get(TIMEOUT_VARIABLE)
    os.environ.setdefault(TIMEOUT_VARIABLE, SLEEP_AT_ONCE)
    in_effect = chosen if "numpy" in sys.modules else os.environ[TIMEOUT_VARIABLE]
    _sleeping = in_effect is not None and _short_spin(in_effect)


def idle_threads_sleep() -> bool:
    """Whether OpenBLAS's idle threads sleep at once in this process (`let_idle_threads_sleep`)."""
    return _sleeping


def _short_spin(value: str) -> bool:
    try:
        return int(value) <= LONGEST_HARMLESS_SPIN
    except ValueError:
        return False
