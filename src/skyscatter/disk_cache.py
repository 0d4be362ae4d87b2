"""A disk cache for precomputed arrays: atomic, checked, never stale, bounded in size.

Used by the scattering tables (`transport.table_store`), the Mie tables (`optics.mie`) and the
star catalogue; a base module that every layer may import. Each entry is one .npz file holding
the arrays, a JSON metadata record (what the arrays were made from: input fingerprints,
resolution, wavelengths, versions) and a SHA-256 of both.

- `load` returns None, with the reason, for a file that is missing, truncated, corrupt (a
  header that declares more data than the file holds is caught before anything is read), not
  a file (a folder in its place), or made from other inputs, so the caller recomputes it.
- `store` writes a pid-tagged hidden temporary (`output_files.temporary_path`, the one naming of
  skyscatter's temporaries) and renames it, so a reader never sees half a file; temporaries
  that a killed process left behind are removed on the next load or store in the folder
  (`output_files.sweep_stale_temporaries`).
- The cache holds at most `max_bytes` (default 2 GiB, or $SKYSCATTER_CACHE_MAX_BYTES, e.g.
  `500M`): after each store the least recently used entries (modification time; `load`
  touches what it reads) of the folder and its direct subfolders (mie/) are removed until the
  rest fits, never the entry just written. Only files that are cache entries (with the
  metadata and checksum members) are counted or removed. Several processes may share a folder:
  a file that vanishes meanwhile is simply skipped.
- `check_writable` says before a long computation whether its result can be stored.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import json
import math
import os
import re
import time
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.errors import InputError
from skyscatter.output_files import (
    STALE_AFTER_S,
    sweep_stale_temporaries,
    temporary_path,
)

__all__ = [
    "DEFAULT_MAX_BYTES",
    "MAX_BYTES_VARIABLE",
    "CacheEntry",
    "TableCache",
    "cache_directory_override",
    "default_cache_directory",
    "default_max_bytes",
    "parse_byte_size",
]

_METADATA = "__metadata__"
_CHECKSUM = "__checksum__"
DEFAULT_MAX_BYTES = 2 * 1024**3  # 2 GiB: eight Earth presets at full resolution (255 MB each)
MAX_BYTES_VARIABLE = "SKYSCATTER_CACHE_MAX_BYTES"
_UNITS = {"": 1, "K": 1024, "M": 1024**2, "G": 1024**3, "T": 1024**4}
# Temporaries of earlier versions (tempfile.mkstemp, no pid): removed once a day old
_OLD_TEMPORARY = re.compile(r"\..+\.npz\.tmp")


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


def parse_byte_size(text: str, name: str = MAX_BYTES_VARIABLE) -> int:
    """Bytes from `text`: a whole number with an optional binary unit K, M, G or T (KiB, MiB,
    ...; `2G`, `500MiB`, `1073741824`). InputError naming `name` otherwise."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([KMGT]?)(?:i?B)?\s*", str(text), re.IGNORECASE)
    allowed = "a size in bytes such as 2G, 500M or 1073741824 (units K, M, G, T: powers of 1024)"
    if match is None:
        raise InputError(f"{name} = {text!r} is not allowed: {allowed}", key=name, value=text,
                         allowed=allowed)
    size = float(match.group(1)) * _UNITS[match.group(2).upper()]
    if not math.isfinite(size) or size >= 2**63:
        raise InputError(f"{name} = {text!r} is too large: {allowed}", key=name, value=text,
                         allowed=allowed)
    return int(size)


def default_max_bytes() -> int:
    """$SKYSCATTER_CACHE_MAX_BYTES (`parse_byte_size`) when set, else `DEFAULT_MAX_BYTES`."""
    text = os.environ.get(MAX_BYTES_VARIABLE, "").strip()
    return parse_byte_size(text) if text else DEFAULT_MAX_BYTES


def _sweep(directory: str | Path) -> None:
    """Remove the stale temporaries in `directory` (`output_files.sweep_stale_temporaries`:
    of processes that are gone, or a day old), and the pid-less ones of earlier versions
    (`.<key>.<random>.npz.tmp`) once they are a day old."""
    sweep_stale_temporaries(directory)
    now = time.time()
    with contextlib.suppress(OSError):
        for entry in os.scandir(directory):
            if _OLD_TEMPORARY.fullmatch(entry.name):
                with contextlib.suppress(OSError):
                    if now - entry.stat(follow_symlinks=False).st_mtime > STALE_AFTER_S:
                        os.unlink(entry.path)


def _checksum(arrays: dict[str, np.ndarray], metadata_json: str) -> str:
    digest = hashlib.sha256(metadata_json.encode())
    for name in sorted(arrays):
        array = np.ascontiguousarray(arrays[name])
        digest.update(name.encode())
        digest.update(str((array.dtype.str, array.shape)).encode())
        digest.update(array.reshape(-1).view(np.uint8))  # the same bytes, without a copy
    return digest.hexdigest()


def _declared_sizes_problem(path: Path) -> str | None:
    """Why the .npy members of the zip at `path` cannot hold the arrays their headers declare
    (a header claiming 7 TiB in a 200 MB file would otherwise be allocated), or None."""
    with zipfile.ZipFile(path) as archive:
        for info in archive.infolist():
            if not info.filename.endswith(".npy"):
                return f"unexpected member {info.filename!r}"
            with archive.open(info) as member:
                version = np.lib.format.read_magic(member)
                if version == (1, 0):
                    shape, _, dtype = np.lib.format.read_array_header_1_0(member)
                else:
                    shape, _, dtype = np.lib.format.read_array_header_2_0(member)
                offset = member.tell()
            if dtype.hasobject:
                return f"member {info.filename!r} holds Python objects"
            declared = math.prod(shape) * dtype.itemsize
            if declared != info.file_size - offset:
                return (f"member {info.filename!r} declares {declared} bytes but holds "
                        f"{info.file_size - offset}")
    return None


def _is_entry(path: Path) -> bool:
    """True for a regular .npz file with the cache's metadata and checksum members."""
    try:
        if not path.is_file() or path.is_symlink():
            return False
        with zipfile.ZipFile(path) as archive:
            names = set(archive.namelist())
    except (OSError, zipfile.BadZipFile, ValueError):
        return False
    return {f"{_METADATA}.npy", f"{_CHECKSUM}.npy"} <= names


@dataclass(frozen=True)
class CacheEntry:
    """One entry on disk: where, how big [bytes], when last used [s since the epoch]."""

    path: Path
    size_bytes: int
    last_used: float

    @property
    def key(self) -> str:
        return self.path.stem

    def metadata(self) -> dict[str, Any] | None:
        """The entry's metadata record (what it was made from), None when unreadable."""
        try:
            with np.load(self.path, allow_pickle=False) as data:
                return json.loads(str(data[_METADATA]))
        except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
            return None

    def summary(self, root: Path) -> dict[str, Any]:
        """JSON-ready description: key, folder (relative to `root`), size_bytes, last_used
        (ISO 8601, UTC) and what the metadata says it holds: `what` (tables, Mie tables or
        another entry), constituents, orders and wavelengths_nm (count, first, last) where
        given."""
        metadata = self.metadata() or {}
        parent = self.path.parent
        folder = "." if parent == root else parent.relative_to(root).as_posix()
        what = ("tables" if "orders" in metadata else
                "Mie tables" if "distribution" in metadata else "entry")
        row: dict[str, Any] = {
            "key": self.key, "folder": folder, "size_bytes": self.size_bytes,
            "last_used": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(self.last_used)),
            "what": what}
        if metadata.get("constituents"):
            row["constituents"] = [str(name) for name in metadata["constituents"]]
        if "orders" in metadata:
            row["orders"] = metadata["orders"]
        wavelengths = metadata.get("wavelengths_nm")
        if isinstance(wavelengths, list) and wavelengths:
            row["wavelengths_nm"] = {"count": len(wavelengths), "first": wavelengths[0],
                                     "last": wavelengths[-1]}
        return row


class TableCache:
    """Entries named by a key (a file-name-safe string) in one directory, at most `max_bytes`
    [bytes] in all (None: `default_max_bytes()`; module docstring)."""

    def __init__(self, directory: str | Path | None = None, max_bytes: int | None = None
                 ) -> None:
        self.directory = Path(directory) if directory is not None else default_cache_directory()
        if max_bytes is None:
            max_bytes = default_max_bytes()
        if isinstance(max_bytes, bool) or not isinstance(max_bytes, int | np.integer) or (
                max_bytes < 0):
            raise InputError(f"max_bytes = {max_bytes!r} is not allowed: a whole number of "
                             "bytes >= 0", key="max_bytes", value=max_bytes,
                             allowed="a whole number >= 0")
        self.max_bytes = int(max_bytes)

    def path(self, key: str) -> Path:
        if not key or any(c in key for c in "/\\\0") or key.startswith("."):
            raise InputError(f"cache key {key!r} must be a plain file name", key="key",
                             value=key)
        return self.directory / f"{key}.npz"

    def check_writable(self) -> str | None:
        """None when entries can be stored here, else why not (permission denied, read-only
        file system): the caller may compute without storing. Raises InputError when the
        cache directory is a file (or lies under one): a mistake to fix before any work."""
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise InputError(f"the cache directory {self.directory} is not a directory (a file "
                             "is in the way); give --cache-dir or SKYSCATTER_CACHE_DIR a "
                             "folder", key="cache_dir", value=str(self.directory)) from None
        except OSError as error:
            return f"cannot create {self.directory}: {error.strerror}"
        probe = temporary_path(self.directory / "write-check")
        try:
            probe.open("xb").close()
            probe.unlink()
        except OSError as error:
            return f"cannot write in {self.directory}: {error.strerror}"
        return None

    def entry_problem(self, key: str) -> str | None:
        """Why the entry `key` cannot be stored although the directory can be written (a
        folder with files in its place), or None."""
        path = self.path(key)
        try:
            if path.is_dir() and not path.is_symlink() and any(path.iterdir()):
                return f"the cache entry {path} is a folder with files in it; remove it"
        except OSError as error:
            return f"cannot read the folder in place of the cache entry {path}: {error.strerror}"
        return None

    def load(self, key: str, expected: dict[str, Any]) -> tuple[dict[str, np.ndarray] | None,
                                                                str]:
        """(arrays, "ok") for a valid entry made from `expected` metadata, else (None, reason).
        A valid entry is marked as used now (for the least-recently-used eviction)."""
        path = self.path(key)
        _sweep(self.directory)
        if not path.exists():
            return None, "not cached yet"
        if not path.is_file():
            return None, "not a file (a folder or device is in its place)"
        try:
            problem = _declared_sizes_problem(path)
            if problem is not None:
                return None, f"corrupt cache file ({problem})"
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
        with contextlib.suppress(OSError):  # a read-only cache still serves its entries
            os.utime(path)
        return arrays, "ok"

    def store(self, key: str, arrays: dict[str, np.ndarray], metadata: dict[str, Any]) -> Path:
        """Write an entry atomically (a pid-tagged temporary in the same directory, then
        rename), then evict the least recently used others beyond `max_bytes`. An empty
        folder in the entry's place is removed; a non-empty one is an InputError."""
        path = self.path(key)
        metadata_json = json.dumps(metadata, sort_keys=True)
        payload = dict(arrays)
        payload[_METADATA] = np.array(metadata_json)
        payload[_CHECKSUM] = np.array(_checksum(arrays, metadata_json))
        problem = self.check_writable() or self.entry_problem(key)
        if problem is not None:
            raise InputError(f"{problem} (or set SKYSCATTER_CACHE_DIR or --cache-dir to a "
                             "writable folder)", key="cache_dir", value=str(self.directory))
        if path.is_dir() and not path.is_symlink():
            path.rmdir()  # empty (`check_writable`)
        _sweep(self.directory)
        temporary = temporary_path(path)
        try:
            with open(temporary, "xb") as stream:
                np.savez(stream, **payload)
            os.replace(temporary, path)
        except BaseException:
            temporary.unlink(missing_ok=True)
            raise
        self.evict(keep=path)
        return path

    def entries(self) -> list[CacheEntry]:
        """The entries in the directory and its direct subfolders, least recently used first.
        Only files that are cache entries count; one that vanishes meanwhile is left out."""
        found = []
        folders = [self.directory]
        with contextlib.suppress(OSError):
            folders += sorted(p for p in self.directory.iterdir()
                              if p.is_dir() and not p.is_symlink())
        for folder in folders:
            try:
                candidates = sorted(folder.glob("*.npz"))
            except OSError:
                continue
            for path in candidates:
                if path.name.startswith(".") or not _is_entry(path):
                    continue
                try:
                    status = path.stat()
                except OSError:
                    continue
                found.append(CacheEntry(path, status.st_size, status.st_mtime))
        return sorted(found, key=lambda entry: (entry.last_used, str(entry.path)))

    def evict(self, keep: Path | None = None) -> list[CacheEntry]:
        """Remove the least recently used entries (`entries`) until the rest fit in
        `max_bytes`, never `keep`. Returns those removed."""
        entries = self.entries()
        total = sum(entry.size_bytes for entry in entries)
        removed = []
        for entry in entries:
            if total <= self.max_bytes:
                break
            if keep is not None and entry.path == Path(keep):
                continue
            try:
                entry.path.unlink()
            except FileNotFoundError:
                pass  # another process removed it
            except OSError:
                continue
            total -= entry.size_bytes
            removed.append(entry)
        return removed

    def clear(self, older_than_s: float = 0.0) -> list[CacheEntry]:
        """Remove the entries not used for `older_than_s` [s] (0: all) and the stale
        temporaries; returns the entries removed."""
        removed = []
        cutoff = time.time() - older_than_s
        for entry in self.entries():
            if older_than_s > 0.0 and entry.last_used > cutoff:
                continue
            try:
                entry.path.unlink()
            except OSError:
                continue
            removed.append(entry)
        for folder in {self.directory} | {entry.path.parent for entry in removed}:
            _sweep(folder)
        return removed
