"""A config's values changed by dotted keys: the parameters of sweeps and fits.

A key names a value of the TOML document the way a person reads it: tables by name, arrays of
tables by index, e.g. `planet.ground_albedo`, `constituent[1].optics.optical_depth`,
`gas.surface_pressure_pa`, `tables.orders`. A value is written as in TOML (`0.3`, `5`,
`"mie"`, `{ real = 1.5, imaginary = 0.01 }`) or as a bare word (`mie`, read as text).

A sweep axis lists values: `0,0.1,0.3`, a linear range `START:STOP:COUNT` (both ends included),
or a logarithmic one `START:STOP:COUNT:log`.

The changed document goes through the same parser and checks as a config file
(`config.parse_atmosphere`), so a wrong key or value gets the config's own message.

Public names: `MAX_AXIS_VALUES`, `load_document`, `get_value`, `with_values`, `parse_value`,
`parse_values`, `atmosphere_with`.
"""

from __future__ import annotations

import copy
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.atmosphere.config import PRESETS_DIR, parse_atmosphere
from skyscatter.atmosphere.config_file import preset_or_file, read_toml
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.errors import InputError

__all__ = ["MAX_AXIS_VALUES", "atmosphere_with", "get_value", "load_document", "parse_value",
           "parse_values", "with_values"]

# One axis of a sweep: 10 000 values is more than any look-up table or retrieval grid needs
# (AERONET's inversion uses tens per parameter); a typo such as 0:1:1e9 must not fill memory.
MAX_AXIS_VALUES = 10_000
_PART = re.compile(r"([A-Za-z0-9_-]+)((?:\[\d+\])*)")
_INDEX = re.compile(r"\[(\d+)\]")
_KEY_HELP = ("a dotted key of the config such as planet.ground_albedo or "
             "constituent[1].optics.optical_depth")


def load_document(name_or_path: str | Path) -> tuple[dict[str, Any], Path]:
    """The TOML document of a preset (by name) or config file (by path), and its path."""
    path = preset_or_file(name_or_path, PRESETS_DIR, kind="preset", file_kind="config file",
                          keys=("preset", "config"), listing="`skyscatter presets` lists them")
    return read_toml(path), path


def _parts(key: str) -> list[str | int]:
    """'constituent[1].optics.optical_depth' -> ['constituent', 1, 'optics', 'optical_depth']."""
    parts: list[str | int] = []
    for text in str(key).split("."):
        match = _PART.fullmatch(text.strip())
        if match is None:
            raise InputError(f"{key!r} is not a config key: give {_KEY_HELP}", key="key",
                             value=key, allowed=_KEY_HELP)
        parts.append(match.group(1))
        parts.extend(int(index) for index in _INDEX.findall(match.group(2)))
    return parts


def _shown(parts: list[str | int]) -> str:
    text = ""
    for part in parts:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text


def _child(node: Any, part: str | int, walked: list[str | int], key: str, *,
           create: bool) -> Any:
    """`node[part]`, with an InputError naming what is there instead."""
    where = _shown(walked) or "the config"
    if isinstance(part, int):
        if not isinstance(node, list):
            raise InputError(f"{key}: {where} is not an array of tables, so [{part}] means "
                             "nothing", key="key", value=key, allowed=_KEY_HELP)
        if part >= len(node):
            raise InputError(f"{key}: {where} has {len(node)} entries "
                             f"({where}[0] to {where}[{len(node) - 1}])", key="key",
                             value=key, allowed=f"an index below {len(node)}")
        return node[part]
    if not isinstance(node, dict):
        raise InputError(f"{key}: {where} is a value, not a table", key="key", value=key,
                         allowed=_KEY_HELP)
    if part not in node:
        if not create:
            raise InputError(f"{key}: {where} has no {part!r}; it has "
                             f"{', '.join(map(str, node)) or 'nothing'}", key="key",
                             value=key, allowed=", ".join(map(str, node)))
        node[part] = {}
    return node[part]


def get_value(document: Mapping[str, Any], key: str) -> Any:
    """The value at `key` in `document`; InputError naming the part that is missing."""
    node: Any = document
    parts = _parts(key)
    for index, part in enumerate(parts):
        node = _child(node, part, parts[:index], key, create=False)
    return node


def with_values(document: Mapping[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of `document` with each dotted key of `values` set. Missing tables on the way are
    created (the config's parser says if they mean nothing); array indices must exist."""
    changed = copy.deepcopy(dict(document))
    for key, value in values.items():
        parts = _parts(key)
        node: Any = changed
        for index, part in enumerate(parts[:-1]):
            node = _child(node, part, parts[:index], key,
                          create=not isinstance(parts[index + 1], int))
        last = parts[-1]
        if isinstance(last, int):
            _child(node, last, parts[:-1], key, create=False)
        elif not isinstance(node, dict):
            raise InputError(f"{key}: {_shown(parts[:-1])} is a value, not a table", key="key",
                             value=key, allowed=_KEY_HELP)
        node[last] = _plain(value)
    return changed


def _plain(value: Any) -> Any:
    """numpy scalars as Python numbers (the config parser checks Python types)."""
    return value.item() if isinstance(value, np.generic) else value


def atmosphere_with(document: Mapping[str, Any], path: Path,
                    values: Mapping[str, Any]) -> Atmosphere:
    """The atmosphere of `document` (read from `path`, which relative data files are found
    from) with `values` set by dotted key."""
    return parse_atmosphere(with_values(document, values), path)


def parse_value(text: str) -> Any:
    """A value written as in TOML (number, boolean, quoted text, array, inline table), or a bare
    word as text."""
    try:
        return tomllib.loads(f"value = {text.strip()}")["value"]
    except tomllib.TOMLDecodeError:
        return text.strip()


def parse_values(text: str) -> list[Any]:
    """The values of one sweep axis: `A,B,C`, `START:STOP:COUNT` or `START:STOP:COUNT:log`
    (`MAX_AXIS_VALUES` at most)."""
    fields = text.split(":")
    if len(fields) in (3, 4) and not any(c in text for c in "{[\"'"):
        values = _range(text, fields)
    else:
        values = [parse_value(item) for item in _split_top_level(text)]
    if not values or any(value == "" for value in values):
        raise InputError(f"{text!r}: no value; give A,B,C or START:STOP:COUNT", key="values",
                         value=text, allowed="A,B,C or START:STOP:COUNT[:log]")
    if len(values) > MAX_AXIS_VALUES:
        raise InputError(f"{text!r} gives {len(values)} values, more than {MAX_AXIS_VALUES} "
                         "on one axis", key="values", value=text,
                         allowed=f"<= {MAX_AXIS_VALUES} values")
    return values


def _range(text: str, fields: list[str]) -> list[float]:
    allowed = "START:STOP:COUNT or START:STOP:COUNT:log, COUNT a whole number >= 2"
    if len(fields) == 4 and fields[3].strip() != "log":
        raise InputError(f"{text!r}: the fourth field may only be 'log'", key="values",
                         value=text, allowed=allowed)
    try:
        start, stop = float(fields[0]), float(fields[1])
        count = int(fields[2])
    except ValueError:
        raise InputError(f"{text!r} is not a range: give {allowed}", key="values", value=text,
                         allowed=allowed) from None
    if not (np.isfinite(start) and np.isfinite(stop)) or not 2 <= count <= MAX_AXIS_VALUES:
        raise InputError(f"{text!r}: give finite ends and a COUNT from 2 to "
                         f"{MAX_AXIS_VALUES}", key="values", value=text, allowed=allowed)
    if len(fields) == 3:
        return [float(v) for v in np.linspace(start, stop, count)]
    if start <= 0.0 or stop <= 0.0:
        raise InputError(f"{text!r}: a logarithmic range needs positive ends", key="values",
                         value=text, allowed=allowed)
    return [float(v) for v in np.geomspace(start, stop, count)]


def _split_top_level(text: str) -> list[str]:
    """`text` split at the commas outside brackets, braces and quotes."""
    items, depth, quote, start = [], 0, "", 0
    for index, char in enumerate(text):
        if quote:
            quote = "" if char == quote else quote
        elif char in "\"'":
            quote = char
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
        elif char == "," and depth == 0:
            items.append(text[start:index])
            start = index + 1
    items.append(text[start:])
    return [item.strip() for item in items]
