"""The one validation layer: every number a user gives is checked here before work starts.

The CLI's argument types, the config loader and the public API call these functions, so a value
is refused with the same one-line message whichever door it came through: the name, the value,
what is allowed. Each raises `InputError` (a `SkyscatterError`): the CLI prints it as one line
with exit code 2, the library's caller gets the exception with `key`, `value` and `allowed`.
A base module: it imports no layer.
"""

from __future__ import annotations

import math
import reprlib
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from skyscatter.errors import InputError

__all__ = [
    "ALTITUDE_M",
    "ANGLE_DEG",
    "ANY_NUMBER",
    "ASPECT",
    "ELEVATION_ANGLE_DEG",
    "ELEVATION_M",
    "EV",
    "LATITUDE_DEG",
    "PERSPECTIVE_FOV_DEG",
    "ZENITH_DEG",
    "Bounds",
    "checked_array",
    "checked_choice",
    "checked_finite_array",
    "checked_instance",
    "checked_integer",
    "checked_number",
    "shown",
]


_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxlist, _SHORT.maxdict = 3, 8, 4
_SHORT.maxstring, _SHORT.maxlong, _SHORT.maxother = 60, 40, 60


def shown(value: Any) -> str:
    """`value` as a message shows it: `repr(value)` shortened to about 100 characters (a
    400-digit integer, nested lists or a long text cut with '...'), escaped: one readable line."""
    return _SHORT.repr(value)


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
        raise InputError(f"{name} = {shown(value)} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    try:
        number = float(value)
    except OverflowError:  # an integer beyond float range
        number = math.inf
    inside = math.isfinite(number) and (
        low is None or (number > low if low_open else number >= low)) and (
        high is None or (number < high if high_open else number <= high))
    if not inside:
        raise InputError(f"{name} = {shown(value)} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    return number


def checked_integer(name: str, value: Any, low: int, high: int) -> int:
    """`value` as an int when it is a whole number (not a bool, not a float) in [low, high]."""
    allowed = f"a whole number from {low} to {high}"
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not (
            low <= value <= high):
        raise InputError(f"{name} = {shown(value)} is not allowed: {allowed}", key=name,
                         value=value, allowed=allowed)
    return int(value)


def checked_choice(what: str, key: str, value: Any, allowed: Iterable[str], *,
                   fold_case: bool = False) -> str:
    """`value` when it is one of the names `allowed` (compared in lower case with `fold_case`),
    else InputError "unknown {what} {value!r}; choose one of: ..." with `key`. A membership
    test: nothing is run to see whether the name works."""
    names = tuple(allowed)
    text = value.lower() if fold_case and isinstance(value, str) else value
    if not isinstance(value, str) or text not in names:
        listed = ", ".join(names)
        raise InputError(f"unknown {what} {shown(value)}; choose one of: {listed}", key=key,
                         value=value, allowed=listed)
    return value


def _all_numbers(values: Any) -> bool:
    """Whether every element of nested lists and tuples is a real number, not a bool (numpy
    would read [550.0, True] as [550.0, 1.0])."""
    if isinstance(values, list | tuple):
        return all(_all_numbers(value) for value in values)
    if isinstance(values, np.ndarray):
        return values.dtype.kind in "iuf"
    return not isinstance(values, bool | np.bool_) and isinstance(values, int | float | np.number)


def checked_array(name: str, values: Any, low: float | None = None, high: float | None = None,
                  *, low_open: bool = False, high_open: bool = False) -> np.ndarray:
    """`values` as a float64 array when every element is finite and within the bounds, else
    InputError naming `name` and the first offending element. Text, booleans and other
    non-numbers are refused, as by `checked_number` (numpy would read "30" as 30.0)."""
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raw = np.asarray([None])
    if raw.dtype.kind not in "iuf" or not _all_numbers(values):
        raise InputError(f"{name} = {shown(values)} is not allowed: numbers", key=name,
                         value=values, allowed="numbers")
    array = raw.astype(np.float64)
    for element in array.reshape(-1):
        checked_number(name, float(element), low, high, low_open=low_open,
                       high_open=high_open)
    return array



def checked_finite_array(name: str, values: Any, unit: str, *,
                         positive: bool = False) -> np.ndarray:
    """`values` as a float64 array of any shape when every element is finite (and > 0 with
    `positive`), else InputError naming `name`, the first offending element, its index and
    `unit`. Vectorised, for large inputs (star catalogues, wavelength grids), where
    `checked_array` checks element by element."""
    allowed = f"0 < {name} < inf [{unit}]" if positive else f"finite numbers [{unit}]"
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name} must be numbers in {unit}; got {values!r}", key=name,
                         value=values, allowed=allowed) from exc
    good = np.isfinite(array) & (array > 0.0) if positive else np.isfinite(array)
    if not np.all(good):
        index = tuple(int(i) for i in np.argwhere(~good)[0])
        value = float(array[index])
        where = f" at index {index[0] if len(index) == 1 else index}" if array.ndim else ""
        what = "positive and finite" if positive else "finite"
        raise InputError(f"{name} must be {what}; got {value!r}{where} [{unit}]", key=name,
                         value=value, allowed=allowed)
    return array


def checked_instance(name: str, value: Any, kind: type, allowed: str, hint: str = "") -> Any:
    """`value` when it is an instance of `kind`, else InputError
    "{name} = {value!r} is not allowed: {allowed}{hint}" (hint: where to get one)."""
    if not isinstance(value, kind):
        raise InputError(f"{name} = {value!r} is not allowed: {allowed}{hint}", key=name,
                         value=value, allowed=allowed)
    return value


@dataclass(frozen=True)
class Bounds:
    """The allowed interval of one kind of quantity; the CLI's argument types and the API's
    checks use the same `Bounds`, so both doors refuse the same values."""

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False

    @property
    def allowed(self) -> str:
        """What is allowed, in words: "a finite number >= 0 and <= 180"."""
        return _bounds_text(self.low, self.high, self.low_open, self.high_open)

    def check(self, name: str, value: Any) -> float:
        """`checked_number(name, value)` within these bounds."""
        return checked_number(name, value, self.low, self.high, low_open=self.low_open,
                              high_open=self.high_open)

    def check_array(self, name: str, values: Any) -> np.ndarray:
        """`checked_array(name, values)` within these bounds."""
        return checked_array(name, values, self.low, self.high, low_open=self.low_open,
                             high_open=self.high_open)


# The quantities users give, in the units of their names. Angles in degrees: azimuths,
# headings, longitudes and rolls are periodic, so any finite number is one (numpy's sin and
# cos reduce any finite float into one turn); zenith angles go from zenith
# to nadir, elevations and pitches from nadir to zenith.
ANY_NUMBER = Bounds()
ZENITH_DEG = Bounds(0.0, 180.0)
ANGLE_DEG = ANY_NUMBER
LATITUDE_DEG = Bounds(-90.0, 90.0)
ELEVATION_ANGLE_DEG = Bounds(-90.0, 90.0)
# A pinhole's vertical field of view: tan(fov / 2) is infinite at 180 deg.
PERSPECTIVE_FOV_DEG = Bounds(0.0, 180.0, low_open=True, high_open=True)
# Perspective width / height: past 100 an image is a line of pixels.
ASPECT = Bounds(0.0, 100.0, low_open=True)
# Camera height above the ground [m]: from the surface out to 1e12 m (6.7 au); an observer's
# elevation may go below sea level, to -500 m (the Dead Sea shore is at -430 m).
ALTITUDE_M = Bounds(0.0, 1e12)
ELEVATION_M = Bounds(-500.0, 1e12)
# Exposure values and their compensation [EV]: a starless night sky meters near EV100 -10, the
# sun's disk near +24; +-40 leaves room and stops a typo before the image turns black or white.
EV = Bounds(-40.0, 40.0)
