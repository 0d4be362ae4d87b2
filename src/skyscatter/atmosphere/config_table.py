"""One table of a TOML config being read: checked values with messages that name the key.

`ConfigTable` hands out numbers, strings, flags, spectral values and sub-tables, each checked
(type and range), and `finish()` rejects the keys nobody asked for, suggesting the closest
known one. Every problem is a `ConfigError` naming the file, the key, the value and what is
allowed. `atmosphere.config` reads whole files with it.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.errors import ConfigError, InputError
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = ["POLYNOMIAL_STEP_NM", "ConfigTable"]

# A spectral polynomial is tabulated in steps of at most this [nm] over its range_nm and held
# constant beyond: a quadratic with |c2| < 1e-5 nm^-2 is then interpolated to within
# |c2| (10 nm)^2 / 8 < 1.3e-4.
POLYNOMIAL_STEP_NM = 10.0

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
        return ConfigError(f"{self._key(key)} = {value!r} is not allowed: {allowed}",
                           path=self.path, key=self._key(key), value=value, allowed=allowed)

    def has(self, key: str) -> bool:
        self.asked.add(key)
        return key in self.data

    def number(self, key: str, default: float | None = None, *, low: float | None = None,
               high: float | None = None, low_open: bool = False) -> float:
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                raise ConfigError(f"{self._key(key)} is missing (a number is required)",
                                  path=self.path, key=self._key(key))
            return default
        value = self.data.pop(key)
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(
                value):
            raise self.error(key, value, "a finite number")
        if (low is not None and (value < low or (low_open and value == low))) or (
                high is not None and value > high):
            relation = ">" if low_open else ">="
            parts = ([f"{relation} {low}"] if low is not None else []) + (
                [f"<= {high}"] if high is not None else [])
            raise self.error(key, value, "must be " + " and ".join(parts))
        return float(value)

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
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                allowed = f" (one of: {', '.join(choices)})" if choices else ""
                raise ConfigError(f"{self._key(key)} is missing{allowed}", path=self.path,
                                  key=self._key(key))
            return default
        value = self.data.pop(key)
        if not isinstance(value, str):
            raise self.error(key, value, "a string")
        if choices and value not in choices:
            raise self.error(key, value, "one of: " + ", ".join(choices))
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
                raise ConfigError(f"[{self._key(key)}] is missing", path=self.path,
                                  key=self._key(key))
            return None
        value = self.data.pop(key)
        if not isinstance(value, dict):
            raise self.error(key, value, "a table")
        return ConfigTable(dict(value), self.path, self._key(key))

    def numbers(self, key: str, *, low: float | None = None) -> np.ndarray:
        self.asked.add(key)
        value = self.data.pop(key, None)
        if (not isinstance(value, list) or not value or not all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in value)):
            raise self.error(key, value, "a non-empty list of finite numbers")
        array = np.asarray(value, dtype=np.float64)
        if low is not None and np.any(array < low):
            raise self.error(key, value, f"every value must be >= {low}")
        return array

    def spectral(self, key: str, default: float | None = None, *, low: float = -math.inf,
                 high: float = math.inf) -> SpectralParameter:
        """A number, {wavelength_nm = [...], value = [...]}, or {polynomial_nm = [c0, c1, ...],
        range_nm = [low, high]}: c0 + c1 lambda + c2 lambda^2 ... with lambda in nm inside the
        range, held constant outside."""
        self.asked.add(key)
        if key not in self.data:
            if default is None:
                raise ConfigError(f"{self._key(key)} is missing", path=self.path,
                                  key=self._key(key))
            return SpectralParameter.constant(default)
        if isinstance(self.data[key], dict) and "polynomial_nm" in self.data[key]:
            sub = self.table(key)
            coefficients = sub.numbers("polynomial_nm")
            bounds = sub.numbers("range_nm", low=1e-9)
            sub.finish()
            if bounds.size != 2 or not bounds[0] < bounds[1]:
                raise self.error(key, {"range_nm": bounds.tolist()},
                                 "range_nm = [low, high] with low < high [nm]")
            count = int(np.ceil((bounds[1] - bounds[0]) / POLYNOMIAL_STEP_NM)) + 1
            grid = np.linspace(bounds[0], bounds[1], count)
            values = np.polynomial.polynomial.polyval(grid, coefficients)
            if np.any(values < low) or np.any(values > high):
                raise self.error(key, {"polynomial_nm": coefficients.tolist()},
                                 f"a polynomial with values in [{low}, {high}] over "
                                 f"{bounds[0]:g}-{bounds[1]:g} nm")
            return SpectralParameter.table(grid, values)
        if isinstance(self.data[key], dict):
            sub = self.table(key)
            wavelengths = sub.numbers("wavelength_nm", low=1e-9)
            values = sub.numbers("value")
            sub.finish()
            if wavelengths.size != values.size:
                raise self.error(key, {"wavelength_nm": wavelengths.tolist(),
                                       "value": values.tolist()},
                                 "wavelength_nm and value of the same length")
            if np.any(values < low) or np.any(values > high):
                raise self.error(key, values.tolist(), f"values in [{low}, {high}]")
            return SpectralParameter.table(wavelengths, values)
        return SpectralParameter.constant(self.number(key, low=low, high=high))

    def finish(self) -> None:
        """Reject keys nobody asked for, suggesting the closest known one."""
        for key in self.data:
            close = difflib.get_close_matches(key, sorted(self.asked), n=1)
            hint = f"; did you mean '{self._key(close[0])}'?" if close else ""
            raise ConfigError(f"unknown key {self._key(key)!r}{hint}", path=self.path,
                              key=self._key(key), value=self.data[key])
