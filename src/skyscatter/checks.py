"""The one validation layer: every number a user gives is checked here before work starts.

The CLI's argument types, the config loader and the public API call these functions, so a value
is refused with the same one-line message whichever door it came through: the name, the value,
what is allowed. Each raises `InputError` (a `SkyscatterError`): the CLI prints it as one line
with exit code 2, the library's caller gets the exception with `key`, `value` and `allowed`.
A base module: it imports no layer.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skyscatter.errors import InputError

__all__ = ["checked_array", "checked_integer", "checked_number"]


def _bounds_text(low: float | None, high: float | None, low_open: bool,
                 high_open: bool) -> str:
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    return "a finite number" + (" " + " and ".join(parts) if parts else "")


def checked_number(name: str, value: Any, low: float | None = None, high: float | None = None,
                   *, low_open: bool = False, high_open: bool = False) -> float:
    """`value` as a float when it is a finite real number within the bounds, else InputError
    naming `name`, the value and the allowed range. Booleans and strings are refused."""
    allowed = _bounds_text(low, high, low_open, high_open)
    if isinstance(value, bool | str | bytes) or not isinstance(value, int | float | np.number):
        raise InputError(f"{name} = {value!r} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    number = float(value)
    inside = math.isfinite(number) and (
        low is None or (number > low if low_open else number >= low)) and (
        high is None or (number < high if high_open else number <= high))
    if not inside:
        raise InputError(f"{name} = {value!r} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    return number


def checked_integer(name: str, value: Any, low: int, high: int) -> int:
    """`value` as an int when it is a whole number (not a bool, not a float) in [low, high]."""
    allowed = f"a whole number from {low} to {high}"
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not (
            low <= value <= high):
        raise InputError(f"{name} = {value!r} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    return int(value)


def checked_array(name: str, values: Any, low: float | None = None, high: float | None = None,
                  *, low_open: bool = False, high_open: bool = False) -> np.ndarray:
    """`values` as a float64 array when every element is finite and within the bounds, else
    InputError naming `name` and the first offending element."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(f"{name} = {values!r} is not allowed: numbers", key=name,
                         value=values, allowed="numbers") from None
    for element in array.reshape(-1):
        checked_number(name, float(element), low, high, low_open=low_open,
                       high_open=high_open)
    return array
