"""Rows of numbers as text: JSON and CSV, with or without the metadata of their run.

The default formats are the contract of `skyscatter radiance` and `irradiance` (docs/cli.md):

- JSON: an array of objects, one per row, keys in column order, `indent=1`, strict (no NaN).
- CSV: a header of the column names, then one line per row.

Metadata (`output_metadata` in the API: units, atmosphere, solver, wavelengths, version, time)
is opt-in, in one of three places that leave a reader of the default formats undisturbed:

- "envelope" (JSON): `{"metadata": {...}, "rows": [...]}`, the rows as above;
- "comments" (CSV): `# key: value` lines before the header, nested keys joined with dots
  (`# columns.radiance.units: W m-2 sr-1 nm-1`), values that are not text as JSON; readers
  skip them with `pandas.read_csv(..., comment="#")` or `numpy.genfromtxt(..., comments="#")`;
- "sidecar": the metadata as JSON in a file beside the rows (`sidecar_path`).

Numbers are printed to `SIGNIFICANT_DIGITS` significant digits (`tidy`): the CSV's format since
its first version, now the JSON's too, so both carry the same numbers and neither carries the
float noise of the arithmetic (1.7974999999999852 is printed 1.7975). Ten digits keep every
digit the solvers can mean (their accuracy is 1e-4 to 1e-2 relative, docs/validation.md) and
the differences between neighbouring rows of a fine sweep, and drop the last six digits of a
float64, where rounding noise lives. Columns stay floats (30.0, not 30).
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = ["METADATA_PLACES", "SIGNIFICANT_DIGITS", "metadata_json", "rows_csv", "rows_json",
           "sidecar_path", "tidy"]

SIGNIFICANT_DIGITS = 10
METADATA_PLACES = ("envelope", "comments", "sidecar")


def tidy(value: Any) -> Any:
    """`value` with every float rounded to `SIGNIFICANT_DIGITS` significant digits, in lists
    and dicts too; other values as they are."""
    if isinstance(value, float):
        return float(f"{value:.{SIGNIFICANT_DIGITS}g}")
    if isinstance(value, Mapping):
        return {key: tidy(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [tidy(item) for item in value]
    return value


def rows_json(rows: Sequence[Mapping[str, float]], metadata: Mapping | None = None) -> str:
    """The rows as a strict JSON array of objects, or with `metadata` an envelope
    `{"metadata": ..., "rows": [...]}`; ends with a newline."""
    document: Any = tidy(list(rows))
    if metadata is not None:
        document = {"metadata": tidy(dict(metadata)), "rows": document}
    return json.dumps(document, indent=1, allow_nan=False) + "\n"  # strict JSON: jq, JSON.parse


def metadata_json(metadata: Mapping) -> str:
    """The metadata alone as JSON (a sidecar file's text); ends with a newline."""
    return json.dumps(tidy(dict(metadata)), indent=1, allow_nan=False) + "\n"


def rows_csv(rows: Sequence[Mapping[str, float]], metadata: Mapping | None = None) -> str:
    """The rows as CSV (header of the first row's keys), after `# key: value` lines of
    `metadata` when given."""
    text = io.StringIO()
    for key, value in _flattened(tidy(dict(metadata or {}))):
        shown = value if isinstance(value, str) else json.dumps(value, allow_nan=False)
        shown = " ".join(shown.splitlines())  # one line per key, whatever a name holds
        text.write(f"# {key}: {shown}\n")
    writer = csv.DictWriter(text, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows({key: f"{value:.{SIGNIFICANT_DIGITS}g}" for key, value in row.items()}
                     for row in rows)
    return text.getvalue()


def _flattened(metadata: Mapping, prefix: str = "") -> list[tuple[str, Any]]:
    """[(dotted key, value)] of the nested dicts' leaves, in order."""
    items = []
    for key, value in metadata.items():
        if isinstance(value, Mapping):
            items += _flattened(value, f"{prefix}{key}.")
        else:
            items.append((f"{prefix}{key}", value))
    return items


def sidecar_path(path: str | Path) -> Path:
    """Where the metadata of the rows in `path` go: `<path>.meta.json` (out.csv ->
    out.csv.meta.json)."""
    path = Path(path)
    return path.with_name(path.name + ".meta.json")
