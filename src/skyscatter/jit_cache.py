"""A writable folder for numba's cache of compiled kernels, for read-only installs.

`@njit(cache=True)` keeps compiled kernels in `__pycache__` beside the sources, else in
$NUMBA_CACHE_DIR or the user's cache folder (~/.cache/numba). Where none of them can be
written (a read-only install used by an account without a writable home: a container, a
system service, a shared lab machine), numba refuses at import time: "cannot cache function
...: no locator available". `use_writable_cache_folder`, called by `skyscatter/__init__.py`
before any kernel module is imported, then sets NUMBA_CACHE_DIR to the first folder that can be
written: $XDG_CACHE_HOME/skyscatter/numba (default ~/.cache/skyscatter/numba), else a private
folder in the temporary directory (owned by this user, mode 0700, so no other account can
plant compiled code in it), else a new temporary folder for this run. A base module.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

__all__ = ["kernel_cache_folder", "use_writable_cache_folder"]


def kernel_cache_folder() -> Path:
    """The folder of this package's compiled kernels: $NUMBA_CACHE_DIR (the user's, or the one
    `use_writable_cache_folder` chose), else `__pycache__` beside its sources. What is made at
    install time for the code as installed is kept there too (`compile_ahead`)."""
    return Path(os.environ.get("NUMBA_CACHE_DIR") or Path(__file__).parent / "__pycache__")


def _can_write_in(folder: Path) -> bool:
    """Whether a file can be created in `folder` (made if missing)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            return True
    except OSError:
        return False


def _private_temporary_folder() -> Path | None:
    """<tmp>/skyscatter-numba-<uid>, if it is a real folder of this user that nobody else can
    write; None otherwise."""
    uid = os.getuid()
    folder = Path(tempfile.gettempdir()) / f"skyscatter-numba-{uid}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
        status = folder.lstat()
    except OSError:
        return None
    private = (folder.is_dir() and not folder.is_symlink() and status.st_uid == uid
               and status.st_mode & 0o077 == 0)
    return folder if private and _can_write_in(folder) else None


def _candidates() -> list[Path]:
    try:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    except RuntimeError:  # no home directory known
        return []
    return [base / "skyscatter" / "numba"]


def use_writable_cache_folder(package_folder: Path) -> Path | None:
    """Set NUMBA_CACHE_DIR to a writable folder when numba could not cache beside the sources
    in `package_folder` and none is set; returns the folder chosen (None: nothing changed)."""
    in_tree = package_folder / "__pycache__"
    if os.environ.get("NUMBA_CACHE_DIR") or os.access(
            in_tree if in_tree.is_dir() else package_folder, os.W_OK | os.X_OK):
        return None
    folder = next((c for c in _candidates() if _can_write_in(c)), None)
    if folder is None and hasattr(os, "getuid"):
        folder = _private_temporary_folder()
    if folder is None:
        folder = Path(tempfile.mkdtemp(prefix="skyscatter-numba-"))
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    if "numba" in sys.modules:  # numba read its configuration at import: tell it too
        sys.modules["numba"].core.config.CACHE_DIR = str(folder)
    return folder
