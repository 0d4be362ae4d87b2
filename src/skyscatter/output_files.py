"""Output files written whole or not at all, checked before work starts, never left behind.

The one output-writing path of skyscatter (images, videos, time-lapse frames, validation
reports); a base module that every layer may import.

- Temporaries. A file is written to a temporary beside its target, named
  `.<target name>.<pid>.<8 hex digits>.tmp` (`temporary_path`), and renamed onto the target
  when complete, so a reader never sees half a file and a failed write leaves the old file.
- Together. `staged_outputs()` collects several outputs (a PNG and its EXR; a video and its
  frames folder) and renames them onto their targets only when every one is complete, one
  right after the other with SIGINT and SIGTERM held back, so that a failure or an interrupt
  in any write leaves all old outputs as they were. A folder is swapped in whole: the old one
  is renamed aside, the new one renamed in, the old one removed.
- Left-overs. A process killed with SIGKILL leaves its temporaries. Each write into a folder
  (and `check_writable_*`) first removes the temporaries there whose writing process is gone
  or that are older than a day (`sweep_stale_temporaries`); only names that match our pattern.
- Up front. `check_writable_file` and `check_writable_folder` refuse, before any computation,
  a path that is a directory (or a file where a folder is wanted), a read-only file, a folder
  that cannot be written (probed with a temporary file, so the reason is the system's own:
  "Permission denied", "Read-only file system"). Missing parent folders are not an error:
  they are created when the output is written.
- SIGTERM. Within `sigterm_as_interrupt()` SIGTERM raises `Terminated`, a KeyboardInterrupt,
  so a terminated run cleans up its temporaries as Ctrl-C does.
"""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
import signal
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from skyscatter.errors import InputError

__all__ = [
    "STALE_AFTER_S",
    "TEMPORARY_NAME",
    "StagedOutputs",
    "Terminated",
    "atomic_write",
    "check_writable_file",
    "check_writable_folder",
    "sigterm_as_interrupt",
    "staged_outputs",
    "sweep_stale_temporaries",
    "temporary_path",
]

# `.<target name>.<pid>.<token>.tmp`: hidden, recognisably ours, with the writer's process id.
TEMPORARY_NAME = re.compile(r"\.(?P<name>.+)\.(?P<pid>[0-9]+)\.(?P<token>[0-9a-f]{8})\.tmp")
STALE_AFTER_S = 86400.0  # a temporary this old is stale even if its pid is alive (pid reuse)
_MAX_NAME = 200  # of the target's name inside a temporary's name (file names: 255 bytes)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C's KeyboardInterrupt so that the same cleanup runs."""


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises `Terminated` in the main thread (elsewhere: no change)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def handler(signum: int, frame: object) -> None:
        raise Terminated(signum)

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def temporary_path(target: str | os.PathLike[str]) -> Path:
    """A fresh temporary name beside `target`: `.<name>.<pid>.<8 hex digits>.tmp`."""
    target = Path(target)
    return target.with_name(f".{target.name[:_MAX_NAME]}.{os.getpid()}."
                            f"{secrets.token_hex(4)}.tmp")


def _process_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's process
        return True
    except (OverflowError, OSError):  # not a pid this system can have
        return False
    return True


def sweep_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporaries in `folder` (files or folders named as `temporary_path` makes
    them) whose process is no longer running or that are older than `STALE_AFTER_S`; never
    this process's own. Returns what was removed; a folder that cannot be read is skipped."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = TEMPORARY_NAME.fullmatch(entry.name)
        if match is None or int(match["pid"]) == os.getpid():
            continue
        try:
            age = time.time() - entry.stat(follow_symlinks=False).st_mtime
            if _process_alive(int(match["pid"])) and age < STALE_AFTER_S:
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
        except OSError:
            continue  # gone meanwhile, or not ours to remove
        removed.append(Path(entry.path))
    return removed


def _sweep(folder: Path) -> None:
    """Sweep `folder` before writing there, unless it is itself one of our temporaries (a
    folder of frames being made: nothing stale can be in it)."""
    if not TEMPORARY_NAME.fullmatch(folder.absolute().name):
        sweep_stale_temporaries(folder)


def _cannot_write(target: Path, reason: str) -> InputError:
    return InputError(f"cannot write {target}: {reason}", key="path", value=str(target))


def _existing_ancestor(path: Path) -> Path:
    """`path` or its nearest ancestor that exists (whatever it is)."""
    while not os.path.lexists(path) and path != path.parent:
        path = path.parent
    return path


def _probe_folder_of(target: Path) -> None:
    """Create and remove a temporary where `target`'s folder is (or its nearest existing
    ancestor, in which the missing folders would be made); InputError with the system's reason
    when that fails."""
    folder = _existing_ancestor(target.parent)
    probe = temporary_path(folder / target.name)
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        os.unlink(probe)
    except OSError as error:
        where = "" if folder == target.parent else f" (in {folder})"
        raise _cannot_write(target, f"{error.strerror or error}{where}") from None
    _sweep(folder)


def check_writable_file(path: str | os.PathLike[str]) -> Path:
    """Raise InputError, naming the path and why, unless a file can be written at `path`:
    refused are a directory, a read-only file, and a folder that cannot be written (or a file
    in the way of a missing folder). Missing folders are fine (they are made on writing)."""
    target = Path(path)
    if target.is_dir():
        raise _cannot_write(target, "it is a directory; give a file name")
    if os.path.lexists(target) and not os.access(target, os.W_OK, follow_symlinks=False):
        raise _cannot_write(target, "the file is read-only")
    _probe_folder_of(target)
    return target


def check_writable_folder(path: str | os.PathLike[str], owned: re.Pattern[str]) -> Path:
    """Raise InputError unless `path` can be replaced as a whole by a folder of outputs: it
    must be a folder (or not exist yet) holding nothing but names that match `owned` (and our
    temporaries), in a folder that can be written."""
    target = Path(path)
    if os.path.lexists(target) and not target.is_dir():
        raise _cannot_write(target, "it is a file; give a folder")
    if target.is_dir():
        _sweep(target)
        try:
            foreign = sorted(name for name in os.listdir(target)
                             if not (owned.fullmatch(name) or TEMPORARY_NAME.fullmatch(name)))
        except OSError as error:
            raise _cannot_write(target, str(error.strerror or error)) from None
        if foreign:
            raise _cannot_write(target, f"it holds other files ({', '.join(foreign[:3])}"
                                f"{', ...' if len(foreign) > 3 else ''}) and is replaced as a "
                                "whole; give a new or empty folder")
    _probe_folder_of(target)
    return target


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM wait until the block is done, then act as they would have (only in
    the main thread, the one where Python runs signal handlers)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[int] = []
    previous = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGTERM)}
    for number in previous:
        signal.signal(number, lambda signum, frame: pending.append(signum))
    try:
        yield
    finally:
        for number, handler in previous.items():
            if handler is not None:
                signal.signal(number, handler)
        for number in pending:
            signal.raise_signal(number)


class StagedOutputs:
    """Outputs written to temporaries (`write`, `folder`) that `commit` moves onto their
    targets together; `discard` removes the temporaries. Use through `staged_outputs()`."""

    def __init__(self) -> None:
        self._files: list[tuple[Path, Path]] = []  # (temporary, target)
        self._folders: list[tuple[Path, Path]] = []

    def reserve(self, target: str | os.PathLike[str]) -> Path:
        """An empty temporary file beside `target` (folders made), to be written by the caller
        and moved onto `target` by `commit`."""
        target = Path(target)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            _sweep(target.parent)
            temporary = temporary_path(target)
            os.close(os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except OSError as error:
            raise _cannot_write(target, str(error.strerror or error)) from None
        self._files.append((temporary, target))
        return temporary

    def write(self, target: str | os.PathLike[str], write: Callable[[str], None]) -> Path:
        """Call `write(temporary_path)` for `target`; an OSError or RuntimeError of the writer
        (OpenEXR raises those) becomes an InputError naming `target`."""
        temporary = self.reserve(target)
        try:
            write(str(temporary))
        except (OSError, RuntimeError) as error:
            reason = getattr(error, "strerror", None) or str(error)
            raise _cannot_write(Path(target), reason) from error
        return temporary

    def folder(self, target: str | os.PathLike[str]) -> Path:
        """An empty temporary folder beside `target`, swapped in for `target` by `commit`."""
        target = Path(target)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            _sweep(target.parent)
            temporary = temporary_path(target)
            temporary.mkdir()
        except OSError as error:
            raise _cannot_write(target, str(error.strerror or error)) from None
        self._folders.append((temporary, target))
        return temporary

    def commit(self) -> None:
        """Move every temporary onto its target, one right after the other, signals held. If
        a rename fails, the folders already swapped go back; files already renamed stay."""
        swapped: list[tuple[Path, Path, Path | None]] = []  # (temporary, target, old one aside)
        try:
            with _signals_held():
                current = None
                try:
                    for temporary, current in self._folders:
                        aside = temporary_path(current) if current.is_dir() else None
                        if aside is not None:
                            os.rename(current, aside)
                        swapped.append((temporary, current, aside))
                        os.rename(temporary, current)
                    for temporary, current in self._files:
                        os.replace(temporary, current)
                except OSError as error:
                    for temporary, target, aside in reversed(swapped):
                        with contextlib.suppress(OSError):
                            if not os.path.lexists(temporary):
                                os.rename(target, temporary)
                            if aside is not None:
                                os.rename(aside, target)
                    raise _cannot_write(current, str(error.strerror or error)) from None
                finally:
                    self.discard()
        finally:  # also when a signal held back during the renames is raised now
            for _, _, aside in swapped:
                if aside is not None:
                    shutil.rmtree(aside, ignore_errors=True)

    def discard(self) -> None:
        """Remove the temporaries not (yet) moved onto their targets."""
        for temporary, _ in self._files:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(temporary)
        for temporary, _ in self._folders:
            shutil.rmtree(temporary, ignore_errors=True)
        self._files, self._folders = [], []


@contextlib.contextmanager
def staged_outputs() -> Iterator[StagedOutputs]:
    """A `StagedOutputs` committed when the block ends normally, discarded when it raises
    (Ctrl-C and `Terminated` included)."""
    stage = StagedOutputs()
    try:
        yield stage
    except BaseException:
        stage.discard()
        raise
    stage.commit()


def atomic_write(path: str | os.PathLike[str], write: Callable[[str], None]) -> Path:
    """Call `write(temporary_path)`, then rename the result onto `path` (folders made); on
    failure the temporary is removed and the old file stays. An OSError or RuntimeError
    becomes an InputError naming the file."""
    with staged_outputs() as stage:
        stage.write(path, write)
    return Path(path)
