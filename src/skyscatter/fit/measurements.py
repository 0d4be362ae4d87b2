"""Measurements to fit, read from CSV or JSON rows (docs/fit.md, "The measurement file").

One file holds rows of three kinds, mixed in any order; a row's kind is the value column it
fills (exactly one of them):

    kind           value column(s)                  geometry columns
    radiance       radiance [W m^-2 sr^-1 nm^-1]    sun_zenith_deg, view_zenith_deg,
                                                    relative_azimuth_deg, wavelength_nm
    transmittance  direct_transmittance [-]         sun_zenith_deg, wavelength_nm
    chromaticity   chromaticity_x, chromaticity_y   sun_zenith_deg, view_zenith_deg,
                   (CIE 1931 x, y of the sky) [-]   relative_azimuth_deg
    luminance      luminance [cd m^-2]              sun_zenith_deg, view_zenith_deg,
                                                    relative_azimuth_deg

Each row may give its 1-sigma uncertainty, in the unit of its value, as `uncertainty` (or
`standard_error`, the column `skyscatter radiance --solver montecarlo` writes); a chromaticity
row's applies to x and to y. Rows without one take `relative_uncertainty` times their value.
The output of `skyscatter radiance` (CSV, JSON array, or JSON envelope `{"metadata", "rows"}`)
is a measurement file as it is; its other columns (toa_irradiance, ...) are ignored. In CSV an
empty cell is an absent value, so the kinds share one header.

Public names: `KINDS`, `Measurements`, `read_measurements`, `read_rows`,
`measurements_from_rows`.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.errors import InputError, read_user_file

__all__ = ["KINDS", "Measurements", "measurements_from_rows", "read_measurements", "read_rows"]

KINDS = ("radiance", "transmittance", "chromaticity", "luminance")
_VALUES = {"radiance": ("radiance",), "transmittance": ("direct_transmittance",),
           "chromaticity": ("chromaticity_x", "chromaticity_y"), "luminance": ("luminance",)}
_GEOMETRY = {"radiance": ("sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg",
                          "wavelength_nm"),
             "transmittance": ("sun_zenith_deg", "wavelength_nm"),
             "chromaticity": ("sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg"),
             "luminance": ("sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg")}
_UNCERTAINTY = ("uncertainty", "standard_error")
_FORMAT = "docs/fit.md lists the columns"


@dataclass(frozen=True)
class Measurements:
    """Measured values, one entry per fitted number (a chromaticity row gives two: x, then y).

    kind : (n,) str
        "radiance", "transmittance", "chromaticity_x", "chromaticity_y" or "luminance".
    row : (n,) int
        The row of the file (from 1) each value came from.
    sun_zenith_deg, view_zenith_deg, relative_azimuth_deg, wavelength_nm : (n,) float
        Geometry [deg] and wavelength [nm]; NaN where the kind has none.
    value, uncertainty : (n,) float
        The measured value and its 1-sigma uncertainty, in the unit of the kind.
    """

    kind: np.ndarray
    row: np.ndarray
    sun_zenith_deg: np.ndarray
    view_zenith_deg: np.ndarray
    relative_azimuth_deg: np.ndarray
    wavelength_nm: np.ndarray
    value: np.ndarray
    uncertainty: np.ndarray

    @property
    def size(self) -> int:
        """The number of fitted values."""
        return int(self.value.size)

    def where(self, kind: str) -> np.ndarray:
        """Indices of the values of one kind ("chromaticity" selects x and y)."""
        return np.flatnonzero(np.char.startswith(self.kind.astype(str), kind))


def read_measurements(path: str | Path, relative_uncertainty: float | None = None
                      ) -> Measurements:
    """The measurements of a CSV (`.csv`) or JSON file (module docstring); InputError naming
    the file and row for a missing file, garbled text, a missing column or a bad value."""
    source = Path(path)
    rows = read_rows(source)
    try:
        return measurements_from_rows(rows, relative_uncertainty)
    except InputError as error:
        raise InputError(f"{source}: {error}", key="measurements", value=str(source),
                         allowed=_FORMAT) from None


def read_rows(path: str | Path) -> list[dict[str, Any]]:
    """The rows of a measurement file as dicts, unchecked; InputError for a missing file or
    one that is not CSV or JSON rows."""
    return read_user_file(Path(path), _rows_of, what="measurement file", key="measurements",
                          allowed="a CSV or JSON file of measurement rows (docs/fit.md)")


def _rows_of(path: Path) -> list[dict[str, Any]]:
    text = path.read_text(encoding="utf-8")
    if path.suffix.lower() == ".json":
        document = json.loads(text)
        if isinstance(document, Mapping) and "rows" in document:
            document = document["rows"]
        if not isinstance(document, list) or not all(isinstance(r, Mapping) for r in document):
            raise InputError(f"{path}: a JSON measurement file is an array of row objects "
                             "(or {\"rows\": [...]})", key="measurements", value=str(path))
        return [dict(row) for row in document]
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    reader = csv.DictReader(io.StringIO("\n".join(lines)))
    rows = []
    for row in reader:
        if None in row:
            raise InputError(f"{path}: CSV row {len(rows) + 1} has more cells than the header",
                             key="measurements", value=str(path))
        rows.append({key.strip(): value for key, value in row.items()
                     if value is not None and value.strip() != ""})
    return rows


def measurements_from_rows(rows: Sequence[Mapping[str, Any]],
                           relative_uncertainty: float | None = None) -> Measurements:
    """The measurements of rows as dicts (module docstring); InputError naming the row."""
    if not rows:
        raise InputError("no measurement rows", key="measurements", allowed=_FORMAT)
    if relative_uncertainty is not None and not (math.isfinite(relative_uncertainty)
                                                 and 0.0 < relative_uncertainty < 1.0):
        raise InputError(f"relative_uncertainty = {relative_uncertainty!r} must be in (0, 1)",
                         key="relative_uncertainty", value=relative_uncertainty,
                         allowed="a fraction in (0, 1), e.g. 0.03")
    columns: dict[str, list[Any]] = {name: [] for name in Measurements.__dataclass_fields__}
    for number, row in enumerate(rows, start=1):
        kind = _kind(row, number)
        uncertainty = _uncertainty(row, number)
        for value_key in _VALUES[kind]:
            value = _number(row, value_key, number)
            if kind == "transmittance" and not 0.0 < value <= 1.0:
                raise InputError(f"row {number}: direct_transmittance = {value!r} must be in "
                                 "(0, 1]", key="direct_transmittance", value=value)
            if kind in ("radiance", "luminance") and value <= 0.0:
                raise InputError(f"row {number}: {value_key} = {value!r} must be > 0",
                                 key=value_key, value=value)
            sigma = uncertainty
            if sigma is None:
                if relative_uncertainty is None:
                    raise InputError(f"row {number} has no uncertainty: add an uncertainty "
                                     "column or give a relative uncertainty "
                                     "(--relative-uncertainty)", key="uncertainty")
                sigma = relative_uncertainty * abs(value)
            columns["kind"].append(value_key if kind == "chromaticity" else kind)
            columns["row"].append(number)
            columns["value"].append(value)
            columns["uncertainty"].append(sigma)
            for name in ("sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg",
                         "wavelength_nm"):
                columns[name].append(_geometry(row, name, number) if name in _GEOMETRY[kind]
                                     else math.nan)
    arrays = {name: np.array(values) for name, values in columns.items()}
    return Measurements(**arrays)


def _kind(row: Mapping[str, Any], number: int) -> str:
    present = [kind for kind, keys in _VALUES.items() if any(k in row for k in keys)]
    if len(present) != 1:
        given = "none" if not present else " and ".join(present)
        raise InputError(f"row {number} gives {given} of radiance, direct_transmittance, "
                         "chromaticity_x/chromaticity_y, luminance: give exactly one",
                         key="measurements",
                         allowed=_FORMAT)
    return present[0]


def _number(row: Mapping[str, Any], key: str, number: int) -> float:
    if key not in row:
        raise InputError(f"row {number} has no {key}", key=key, allowed=_FORMAT)
    text = row[key]
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(f"row {number}: {key} = {text!r} is not a number", key=key,
                         value=text) from None
    if not math.isfinite(value):
        raise InputError(f"row {number}: {key} = {text!r} is not finite", key=key, value=text)
    return value


def _geometry(row: Mapping[str, Any], key: str, number: int) -> float:
    value = _number(row, key, number)
    if key.endswith("zenith_deg") and not 0.0 <= value <= 180.0:
        raise InputError(f"row {number}: {key} = {value!r} must be in [0, 180]", key=key,
                         value=value)
    if key == "wavelength_nm" and value <= 0.0:
        raise InputError(f"row {number}: wavelength_nm = {value!r} must be > 0", key=key,
                         value=value)
    return value


def _uncertainty(row: Mapping[str, Any], number: int) -> float | None:
    for key in _UNCERTAINTY:
        if key in row:
            sigma = _number(row, key, number)
            if sigma <= 0.0:
                raise InputError(f"row {number}: {key} = {sigma!r} must be > 0", key=key,
                                 value=sigma)
            return sigma
    return None
