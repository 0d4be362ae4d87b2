"""Exceptions that carry a message a user can act on.

The CLI turns every `SkyscatterError` into one stderr line and exit code 2; anything else is a
bug in skyscatter (exit code 1).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["ConfigError", "InputError", "SkyscatterError"]


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
