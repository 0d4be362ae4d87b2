"""The command line's progress bars (renders, time-lapses, table precomputation), shown on a
terminal only.

A thin wrapper around tqdm (https://tqdm.github.io): the bar goes to stderr and appears only
when stderr is a TTY (unless forced), so logs, pipes and tests stay clean.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import TypeVar

from tqdm import tqdm

__all__ = ["progress", "stderr_is_terminal"]

T = TypeVar("T")


def stderr_is_terminal() -> bool:
    """True when stderr is an interactive terminal."""
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError):  # replaced by an object without isatty, or closed
        return False


def progress(iterable_or_total: Iterable[T] | int, description: str,
             enabled: bool | None = None, *, unit: str = "row") -> tqdm:
    """A progress bar over an iterable, or over `range(total)` when given an int.

    Iterate over the result as over the input, or call `.update(n)` on it (use it as a
    context manager so it closes) when the work is done in chunks, e.g. rows rendered by a
    parallel kernel. A disabled bar costs nothing and prints nothing.

    Parameters
    ----------
    iterable_or_total : iterable or int
        The items, or the number of steps.
    description : str
        Label in front of the bar, e.g. "rendering".
    enabled : bool, optional
        True/False forces the bar on/off; None shows it only when stderr is a terminal.
    unit : str
        Name of one step, e.g. "row".
    """
    if enabled is None:
        enabled = stderr_is_terminal()
    if isinstance(iterable_or_total, int):
        items: Iterable[object] = range(iterable_or_total)
        total: int | None = iterable_or_total
    else:
        items = iterable_or_total
        total = None
    return tqdm(items, total=total, desc=description, unit=unit, disable=not enabled,
                file=sys.stderr, dynamic_ncols=True, leave=False)
