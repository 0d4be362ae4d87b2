"""A disk cache for precomputed arrays: atomic, checked, never stale.

Used by the scattering tables (`transport.table_store`) and the Mie tables (`optics.mie`); a base
module that every layer may import. Each entry is one .npz file holding the arrays, a JSON
metadata record (what the arrays were made from: input fingerprints, resolution, wavelengths,
versions) and a SHA-256 of both.
`load` returns None, with the reason, for a file that is missing, truncated, corrupt, or made
from other inputs, so the caller recomputes it; `store` writes a temporary file and renames it,
so a reader never sees half a file.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import os
import tempfile
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.errors import InputError

__all__ = ["TableCache", "cache_directory_override", "default_cache_directory"]

_METADATA = "__metadata__"
_CHECKSUM = "__checksum__"


# The cache root of the code running in this thread/context, when a caller fixed it
# (`cache_directory_override`): the viewer keeps everything, Mie tables included, in its own
_OVERRIDE: contextvars.ContextVar[Path | None] = contextvars.ContextVar("cache_root",
                                                                         default=None)


@contextlib.contextmanager
def cache_directory_override(directory: str | Path) -> Iterator[None]:
    """Within the block (this thread), `default_cache_directory()` is `directory`."""
    token = _OVERRIDE.set(Path(directory))
    try:
        yield
    finally:
        _OVERRIDE.reset(token)


def default_cache_directory() -> Path:
    """The override of `cache_directory_override`, else $SKYSCATTER_CACHE_DIR, else
    $XDG_CACHE_HOME/skyscatter, else ~/.cache/skyscatter."""
    if _OVERRIDE.get() is not None:
        return _OVERRIDE.get()
    if os.environ.get("SKYSCATTER_CACHE_DIR"):
        return Path(os.environ["SKYSCATTER_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "skyscatter"


def _checksum(arrays: dict[str, np.ndarray], metadata_json: str) -> str:
    digest = hashlib.sha256(metadata_json.encode())
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        digest.update(name.encode())
        digest.update(str((array.dtype.str, array.shape)).encode())
        digest.update(array.reshape(-1).view(np.uint8))  # the same bytes, without a copy
    return digest.hexdigest()


class TableCache:
    """Entries named by a key (a file-name-safe string) in one directory."""

    def __init__(self, directory: str | Path | None = None) -> None:
        self.directory = Path(directory) if directory is not None else default_cache_directory()

    def path(self, key: str) -> Path:
        if not key or any(c in key for c in "/\\\0") or key.startswith("."):
            raise InputError(f"cache key {key!r} must be a plain file name", key="key",
                             value=key)
        return self.directory / f"{key}.npz"

    def load(self, key: str, expected: dict[str, Any]) -> tuple[dict[str, np.ndarray] | None,
                                                                str]:
        """(arrays, "ok") for a valid entry made from `expected` metadata, else (None, reason)."""
        path = self.path(key)
        if not path.exists():
            return None, "not cached yet"
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {name: data[name] for name in data.files
                          if name not in (_METADATA, _CHECKSUM)}
                metadata_json = str(data[_METADATA])
                stored_checksum = str(data[_CHECKSUM])
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as error:
            return None, f"unreadable cache file ({type(error).__name__}: {error})"
        if _checksum(arrays, metadata_json) != stored_checksum:
            return None, "checksum mismatch (corrupt cache file)"
        metadata = json.loads(metadata_json)
        expected = json.loads(json.dumps(expected))  # same normalisation as stored
        if metadata != expected:
            changed = sorted(k for k in set(metadata) | set(expected)
                             if metadata.get(k) != expected.get(k))
            return None, f"made from other inputs (differs in: {', '.join(changed)})"
        return arrays, "ok"

    def store(self, key: str, arrays: dict[str, np.ndarray], metadata: dict[str, Any]) -> Path:
        """Write an entry atomically (temporary file in the same directory, then rename)."""
        path = self.path(key)
        metadata_json = json.dumps(metadata, sort_keys=True)
        payload = dict(arrays)
        payload[_METADATA] = np.array(metadata_json)
        payload[_CHECKSUM] = np.array(_checksum(arrays, metadata_json))
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            handle, temporary = tempfile.mkstemp(prefix=f".{key}.", suffix=".npz.tmp",
                                                 dir=self.directory)
        except OSError as error:
            raise InputError(f"cannot write the cache directory {self.directory}: "
                             f"{error.strerror} (set SKYSCATTER_CACHE_DIR or --cache-dir to a "
                             "writable folder)", key="cache_dir",
                             value=str(self.directory)) from None
        try:
            with os.fdopen(handle, "wb") as stream:
                np.savez(stream, **payload)
            os.replace(temporary, path)
        except BaseException:
            Path(temporary).unlink(missing_ok=True)
            raise
        return path
