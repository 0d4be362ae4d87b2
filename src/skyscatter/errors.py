"""Exceptions that carry a message a user can act on.

The CLI turns every `SkyscatterError` into one stderr line and exit code 2; anything else is a
bug in skyscatter (exit code 1).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

__all__ = ["ConfigError", "InputError", "SkyscatterError", "read_user_file"]

T = TypeVar("T")


class SkyscatterError(Exception):
    """Base class of the errors caused by what a user gave us."""


class InputError(SkyscatterError):
    """A bad argument: names the argument, the value and what is allowed."""

    def __init__(self, message: str, *, key: str | None = None, value: Any = None,
                 allowed: str | None = None) -> None:
        super().__init__(message)
        self.key = key
        self.value = value
        self.allowed = allowed


class ConfigError(SkyscatterError):
    """A bad configuration file: names the file, the key, the value and what is allowed."""

    def __init__(self, message: str, *, path: Path | str | None = None, key: str | None = None,
                 value: Any = None, allowed: str | None = None) -> None:
        prefix = f"{path}: " if path is not None else ""
        super().__init__(prefix + message)
        self.path = path
        self.key = key
        self.value = value
        self.allowed = allowed


def read_user_file(path: str | Path, read: Callable[[Path], T], *, what: str, key: str,
                   allowed: str) -> T:
    """`read(path)` of a file a user named as `what` (argument or config `key`), with an
    InputError naming the file for one that is missing or that `read` cannot decode (any
    decoder's exception), saying what to give instead (`allowed`)."""
    source = Path(path)
    if not source.is_file():
        raise InputError(f"{what} {source}: no such file", key=key, value=str(source),
                         allowed=allowed)
    try:
        return read(source)
    except InputError:
        raise
    except Exception as error:  # any decoder's complaint about a bad file
        raise InputError(f"{what} {source}: cannot read it ({type(error).__name__}: {error}); "
                         f"give {allowed}", key=key, value=str(source),
                         allowed=allowed) from None
