"""One table of a TOML config being read: checked values with messages that name the key.

`ConfigTable` hands out numbers, strings, flags, spectral values, sub-tables and arrays of
tables, each checked (type, range from `atmosphere.config_ranges`, length), and `finish()`
rejects the keys nobody asked for, suggesting the closest known one. Every problem is a
`ConfigError` naming the file, the key, the value (shortened: a message stays one readable
line, whatever the file holds) and what is allowed. `atmosphere.config` reads whole files with
it.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.atmosphere.config_ranges import (
    MAX_LIST_LENGTH,
    MAX_POLYNOMIAL_COEFFICIENTS,
    MAX_TEXT_LENGTH,
    WAVELENGTH_NM,
)
from skyscatter.checks import Bounds, shown
from skyscatter.errors import ConfigError, InputError
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = ["POLYNOMIAL_STEP_NM", "ConfigTable"]

# A spectral polynomial is tabulated in steps of at most this [nm] over its range_nm and held
# constant beyond: a quadratic with |c2| < 1e-5 nm^-2 is then interpolated to within
# |c2| (10 nm)^2 / 8 < 1.3e-4. range_nm lies within `WAVELENGTH_NM`: at most 1e4 points.
POLYNOMIAL_STEP_NM = 10.0

# Characters that make a string print as something else: controls (newline, NUL, escape) and
# the bidirectional overrides of "Trojan source" text.
_HIDDEN = {chr(c) for c in range(32)} | {"\x7f"} | set("\u202a\u202b\u202c\u202d\u202e"
                                                       "\u2066\u2067\u2068\u2069")


@dataclasses.dataclass
class ConfigTable:
    """One TOML table being read: hands out checked values, then rejects the keys left over."""

    data: dict[str, Any]
    path: Path
    prefix: str
    asked: set[str] = dataclasses.field(default_factory=set)  # keys looked up, for suggestions

    def _key(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def wrap(self, error: InputError) -> ConfigError:
        """An InputError raised while building an object from this table, as a ConfigError
        that names the file and the key under this table's prefix."""
        return ConfigError(f"{self.prefix}: {error}", path=self.path,
                           key=f"{self.prefix}.{error.key}", value=error.value,
                           allowed=error.allowed)

    def error(self, key: str, value: Any, allowed: str) -> ConfigError:
        return ConfigError(f"{self._key(key)} = {shown(value)} is not allowed: {allowed}",
                           path=self.path, key=self._key(key), value=value, allowed=allowed)

    def missing(self, key: str, detail: str = "", allowed: str | None = None,
                table: bool = False) -> ConfigError:
        """The error for a required `key` that is absent (`[key]` for a `table`), naming a key
        of this table that nobody asked for and looks like its misspelling."""
        name = f"[{self._key(key)}]" if table else self._key(key)
        strays = [other for other in self.data if other not in self.asked]
        close = difflib.get_close_matches(key, strays, n=1)
        hint = f"; the file has {shown(self._key(close[0]))}: misspelt?" if close else ""
        return ConfigError(f"{name} is missing{detail}{hint}", path=self.path,
                           key=self._key(key), allowed=allowed)

    def has(self, key: str) -> bool:
        self.asked.add(key)
        return key in self.data

    def _checked(self, key: str, value: Any, bounds: Bounds) -> float:
        """`value` as a float within `bounds`, else the error naming `key`."""
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e300:
            raise self.error(key, value, bounds.allowed)  # float() would overflow
        try:
            return bounds.check(self._key(key), value)
        except InputError:
            raise self.error(key, value, bounds.allowed) from None

    def number(self, key: str, bounds: Bounds, default: float | None = None) -> float:
        """A finite number within `bounds` (`config_ranges`); `default` when absent, or a
        ConfigError when there is none."""
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                raise self.missing(key, f" (a number is required: {bounds.allowed})",
                                   bounds.allowed)
            return default
        return self._checked(key, self.data.pop(key), bounds)

    def integer(self, key: str, default: int, *, low: int, high: int) -> int:
        """An integer in [low, high]; floats (even 4.0), booleans and strings are rejected."""
        self.asked.add(key)
        if key not in self.data:
            return default
        value = self.data.pop(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, value, f"an integer from {low} to {high}")
        if not low <= value <= high:
            raise self.error(key, value, f"must be >= {low} and <= {high}")
        return value

    def text(self, key: str, default: str | None = None, choices: tuple[str, ...] = ()) -> str:
        """A string of at most `MAX_TEXT_LENGTH` characters without control characters, one of
        `choices` when given."""
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                allowed = f" (one of: {', '.join(choices)})" if choices else ""
                raise self.missing(key, allowed)
            return default
        value = self.data.pop(key)
        if not isinstance(value, str):
            raise self.error(key, value, "a string")
        if choices and value not in choices:
            raise self.error(key, value, "one of: " + ", ".join(choices))
        if len(value) > MAX_TEXT_LENGTH or not _HIDDEN.isdisjoint(value):
            raise self.error(key, value, f"a string of at most {MAX_TEXT_LENGTH} characters "
                             "without control characters (newlines, tabs, escapes)")
        return value

    def flag(self, key: str, default: bool) -> bool:
        self.asked.add(key)
        if key not in self.data:
            return default
        value = self.data.pop(key)
        if not isinstance(value, bool):
            raise self.error(key, value, "true or false")
        return value

    def table(self, key: str, required: bool = True) -> ConfigTable | None:
        self.asked.add(key)
        if key not in self.data:
            if required:
                raise self.missing(key, table=True)
            return None
        value = self.data.pop(key)
        if not isinstance(value, dict):
            raise self.error(key, value, "a table")
        return ConfigTable(dict(value), self.path, self._key(key))

    def tables(self, key: str, max_length: int, what: str) -> list[ConfigTable]:
        """An array of at most `max_length` tables (`what` says why the cap), each a
        ConfigTable named `key[i]`; [] when absent."""
        self.asked.add(key)
        items = self.data.pop(key, [])
        if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
            raise self.error(key, items, "an array of tables")
        if len(items) > max_length:
            raise ConfigError(f"{self._key(key)} has {len(items)} entries, more than "
                              f"{max_length}: {what}", path=self.path, key=self._key(key),
                              value=len(items), allowed=f"<= {max_length} entries")
        return [ConfigTable(dict(item), self.path, f"{self._key(key)}[{index}]")
                for index, item in enumerate(items)]

    def numbers(self, key: str, bounds: Bounds) -> np.ndarray:
        """A non-empty list of at most `MAX_LIST_LENGTH` numbers, each within `bounds`."""
        self.asked.add(key)
        value = self.data.pop(key, None)
        allowed = f"a non-empty list of at most {MAX_LIST_LENGTH} numbers, each {bounds.allowed}"
        if not isinstance(value, list) or not value or len(value) > MAX_LIST_LENGTH:
            raise self.error(key, value, allowed)
        for element in value:
            try:
                self._checked(key, element, bounds)
            except ConfigError:
                raise self.error(key, value, f"{allowed}; {shown(element)} is not") from None
        return np.asarray(value, dtype=np.float64)

    def spectral(self, key: str, bounds: Bounds, default: float | None = None
                 ) -> SpectralParameter:
        """A number, {wavelength_nm = [...], value = [...]}, or {polynomial_nm = [c0, c1, ...],
        range_nm = [low, high]}: c0 + c1 lambda + c2 lambda^2 ... with lambda in nm inside the
        range, held constant outside. Values within `bounds`, wavelengths within
        `config_ranges.WAVELENGTH_NM`."""
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                raise self.missing(key)
            return SpectralParameter.constant(default)
        if isinstance(self.data[key], dict) and "polynomial_nm" in self.data[key]:
            return self._polynomial(key, bounds)
        if isinstance(self.data[key], dict):
            sub = self.table(key)
            wavelengths = sub.numbers("wavelength_nm", WAVELENGTH_NM)
            values = sub.numbers("value", bounds)
            sub.finish()
            if wavelengths.size != values.size or np.unique(wavelengths).size != values.size:
                raise self.error(key, {"wavelength_nm": wavelengths.tolist(),
                                       "value": values.tolist()},
                                 "wavelength_nm (all different) and value of the same length")
            return SpectralParameter.table(wavelengths, values)
        return SpectralParameter.constant(self.number(key, bounds))

    def _polynomial(self, key: str, bounds: Bounds) -> SpectralParameter:
        sub = self.table(key)
        coefficients = sub.numbers("polynomial_nm", Bounds())
        limits = sub.numbers("range_nm", WAVELENGTH_NM)
        sub.finish()
        if coefficients.size > MAX_POLYNOMIAL_COEFFICIENTS:
            raise sub.error("polynomial_nm", coefficients.tolist(),
                            f"at most {MAX_POLYNOMIAL_COEFFICIENTS} coefficients (degree "
                            f"{MAX_POLYNOMIAL_COEFFICIENTS - 1}: higher powers of lambda [nm] "
                            "cancel below float64 precision; give a table instead)")
        if limits.size != 2 or not limits[0] < limits[1]:
            raise sub.error("range_nm", limits.tolist(),
                            f"[low, high] with low < high, within {WAVELENGTH_NM.allowed} [nm]")
        count = int(math.ceil((limits[1] - limits[0]) / POLYNOMIAL_STEP_NM)) + 1
        grid = np.linspace(limits[0], limits[1], count)
        with np.errstate(over="ignore", invalid="ignore"):
            values = np.polynomial.polynomial.polyval(grid, coefficients)
            inside = np.isfinite(values)
            if bounds.low is not None:
                inside &= values > bounds.low if bounds.low_open else values >= bounds.low
            if bounds.high is not None:
                inside &= values < bounds.high if bounds.high_open else values <= bounds.high
        outside = ~inside
        if np.any(outside):
            wavelength = float(grid[np.argmax(outside)])
            raise self.error(key, {"polynomial_nm": coefficients.tolist()},
                             f"a polynomial whose values over {limits[0]:g}-{limits[1]:g} "
                             f"nm are each {bounds.allowed} (at {wavelength:g} nm it is "
                             f"{float(values[np.argmax(outside)]):g})")
        return SpectralParameter.table(grid, values)

    def finish(self) -> None:
        """Reject keys nobody asked for, suggesting the closest known one."""
        for key in self.data:
            close = difflib.get_close_matches(key, sorted(self.asked), n=1)
            hint = f"; did you mean '{self._key(close[0])}'?" if close else ""
            raise ConfigError(f"unknown key {shown(self._key(key))}{hint}", path=self.path,
                              key=self._key(key), value=self.data[key])
