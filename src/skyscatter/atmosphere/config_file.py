"""Read a config file into a TOML document, refusing what is not one before parsing it.

Python's `tomllib` is given only text it parses in bounded time and memory; everything else is
a `ConfigError` that names the file and says what it is instead:

- not a regular file (a directory, a device such as /dev/zero);
- larger than `MAX_CONFIG_BYTES`;
- empty, or only comments;
- not UTF-8 text: a UTF-16 or UTF-32 file (from a Windows editor) is named as such, a NUL byte
  or an invalid UTF-8 sequence means a binary file or another encoding (a UTF-8 byte-order
  mark is skipped);
- a dotted key or table header of more than `MAX_KEY_PARTS` parts: tomllib's memory grows with
  the square of their number (measured: 40 000 parts, an 80 kB line, take 6 GiB and 32 s);
- arrays or inline tables nested deeper than Python's recursion limit (tomllib recurses once per
  level and raises RecursionError) and integers longer than Python converts (4300 digits).

`read_utf8` reads the CSV files a config names with the same checks.

Public names: `MAX_CONFIG_BYTES`, `MAX_KEY_PARTS`, `read_toml`, `read_utf8`.
"""

from __future__ import annotations

import codecs
import difflib
import re
import sys
import tomllib
from pathlib import Path
from typing import Any

from skyscatter.errors import ConfigError, InputError

__all__ = ["MAX_CONFIG_BYTES", "MAX_KEY_PARTS", "preset_or_file", "read_toml", "read_utf8"]

# The largest shipped preset is 4 kB and the docs' worked example, with two inline profile
# tables, 4 kB; 1 MiB holds an inline table of ~50 000 rows. Longer tables belong in a CSV file
# next to the config (`density = { type = "table", file = ... }`).
MAX_CONFIG_BYTES = 2**20
# The schema's deepest key has 4 parts (`constituent.optics.phase.g`); 64 leave room for any
# dotted key a person writes and keep tomllib's quadratic cost negligible.
MAX_KEY_PARTS = 64

_BOMS = ((codecs.BOM_UTF32_LE, "UTF-32"), (codecs.BOM_UTF32_BE, "UTF-32"),
         (codecs.BOM_UTF16_LE, "UTF-16"), (codecs.BOM_UTF16_BE, "UTF-16"))
_KEY_PART = r"""(?:[A-Za-z0-9_-]+|"[^"\\\n]*"|'[^'\n]*')"""
_DOTTED = re.compile(rf"{_KEY_PART}(?:[ \t]*\.[ \t]*{_KEY_PART})*")


def preset_or_file(name_or_path: str | Path, folder: Path, *, kind: str, file_kind: str,
                   keys: tuple[str, str], listing: str | None = None) -> Path:
    """The TOML file of a preset named `name_or_path` in `folder`, or the path itself.
    InputError for an unknown preset (`kind`, naming the closest name, `listing` or else the
    names, key `keys[0]`) or a file that does not exist (`file_kind`, key `keys[1]`)."""
    text = str(name_or_path)
    path = Path(text)
    if not path.suffix and not path.exists():
        path = folder / f"{text}.toml"
        if not path.exists():
            names = sorted(p.stem for p in folder.glob("*.toml"))
            close = difflib.get_close_matches(text, names, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            where = listing or f"presets: {', '.join(names)}"
            raise InputError(f"unknown {kind} '{text}'{hint} ({where}; or give the path of a "
                             ".toml file)", key=keys[0], value=text, allowed=", ".join(names))
    if not path.exists():
        raise InputError(f"{file_kind} '{path}' does not exist", key=keys[1], value=text)
    return path


def read_toml(path: Path) -> dict[str, Any]:
    """The TOML document in the file `path`, or ConfigError naming the file and the problem
    (module docstring). A missing file is the caller's to report (it may be a preset name)."""
    try:
        text = read_utf8(path, MAX_CONFIG_BYTES)
    except OSError as error:
        raise ConfigError(f"cannot read: {error.strerror}", path=path) from None
    except ValueError as error:
        allowed = "UTF-8 TOML text of at most 1 MiB"
        raise ConfigError(f"{error}; a config is {allowed} (long profile tables go in a CSV "
                          "file next to it)", path=path, allowed=allowed) from None
    document = _parse(text, path)
    if not document:
        raise ConfigError("is empty: a config needs [planet], [star], [atmosphere] and "
                          "[[constituent]] tables (docs/config.md; `skyscatter presets` lists "
                          "complete examples to copy)", path=path)
    return document


def read_utf8(path: Path, max_bytes: int) -> str:
    """The text of the regular file `path`, UTF-8 without a byte-order mark, at most
    `max_bytes`; ValueError saying what the file is instead (a directory, too large, UTF-16,
    binary), OSError when it cannot be read."""
    if path.is_dir():
        raise ValueError("is a directory, not a file")
    if path.exists() and not path.is_file():
        raise ValueError("is not a regular file (a device or a pipe?)")
    with path.open("rb") as handle:
        data = handle.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise ValueError(f"is larger than {max_bytes / 2**20:g} MiB, the limit")
    for bom, encoding in _BOMS:
        if data.startswith(bom):
            raise ValueError(f"is {encoding} text, not UTF-8")
    nul = data.find(0)
    if nul >= 0:
        raise ValueError(f"is not UTF-8 text: a NUL byte at offset {nul} (a binary file, or "
                         "UTF-16 text without a byte-order mark?)")
    try:
        return data.decode("utf-8").removeprefix("\ufeff")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise ValueError(f"is not UTF-8 text: byte 0x{data[error.start]:02x} on line {line} "
                         "(a binary file, or text in another encoding such as Latin-1?)"
                         ) from None


def _parse(text: str, path: Path) -> dict[str, Any]:
    """`tomllib.loads(text)` with every way it can fail as a ConfigError naming `path`."""
    for match in _DOTTED.finditer(text):
        if match.group().count(".") >= MAX_KEY_PARTS and len(
                re.findall(_KEY_PART, match.group())) > MAX_KEY_PARTS:
            line = text.count("\n", 0, match.start()) + 1
            raise ConfigError(f"not valid here: a dotted key of more than {MAX_KEY_PARTS} "
                              f"parts on line {line}; no key of a config has more than 4",
                              path=path, allowed=f"<= {MAX_KEY_PARTS} key parts")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ConfigError(f"not valid TOML: {error}", path=path) from None
    except RecursionError:
        raise ConfigError("not valid here: arrays or inline tables nested too deeply for the "
                          "TOML reader (it stops near 400 levels); a config nests at most 4",
                          path=path) from None
    except ValueError:  # int() of more digits than sys.get_int_max_str_digits()
        raise ConfigError(f"not valid here: an integer with more than "
                          f"{sys.get_int_max_str_digits()} digits; no number of a config "
                          "needs more than 20", path=path) from None
