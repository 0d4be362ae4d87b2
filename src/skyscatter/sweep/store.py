"""The finished chunks of a sweep on disk, so that an interrupted sweep resumes.

A store is a folder beside the output (`OUT.nc.parts/`, made with the first finished chunk)
holding `sweep.json` (the sweep's fingerprint, `plan.SweepPlan.fingerprint`, and a short
description) and one `chunk_NNNNNN.npz` per finished chunk (numpy's npz: the chunk's named
arrays), each written to a temporary and renamed when complete (`output_files.atomic_write`):
a chunk file is whole or absent, whatever interrupts the sweep. A store of another sweep
(another fingerprint) is refused, never mixed in; `restart` empties it first.

Public names: `ChunkStore`, `parts_folder`.
"""

from __future__ import annotations

import json
import re
import shutil
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from skyscatter.errors import InputError
from skyscatter.output_files import atomic_write

__all__ = ["ChunkStore", "parts_folder"]

MANIFEST = "sweep.json"
CHUNK_NAME = re.compile(r"chunk_(?P<index>[0-9]{6,})\.npz")


def parts_folder(output: str | Path) -> Path:
    """The chunk store of the output `output`: `OUT.nc` -> `OUT.nc.parts`."""
    output = Path(output)
    return output.with_name(f"{output.name}.parts")


class ChunkStore:
    """The finished chunks of the sweep `fingerprint` in `folder` (made if missing).
    InputError when `folder` holds another sweep's chunks (unless `restart`, which empties it)
    or is not a store."""

    def __init__(self, folder: str | Path, fingerprint: str,
                 description: Mapping[str, object], *, restart: bool = False) -> None:
        self.folder = Path(folder)
        self.fingerprint = fingerprint
        self._description = dict(description)
        manifest = self.folder / MANIFEST
        if self.folder.exists() and not self.folder.is_dir():
            raise InputError(f"{self.folder} is a file, where the sweep keeps its finished "
                             "chunks; move it away", key="output", value=str(self.folder))
        if restart and manifest.is_file():
            self.remove()
        if self.folder.is_dir() and any(self.folder.iterdir()):
            found = self._fingerprint_there(manifest)
            if found != fingerprint:
                raise InputError(
                    f"{self.folder} holds the chunks of another sweep (other config, values, "
                    "geometry, wavelengths or solver); pass --restart to discard them "
                    "(Python: restart=True) or choose another output", key="output",
                    value=str(self.folder))

    def _fingerprint_there(self, manifest: Path) -> str | None:
        try:
            return str(json.loads(manifest.read_text(encoding="utf-8"))["fingerprint"])
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError(f"{self.folder} is not a sweep's chunk store (no readable "
                             f"{MANIFEST}); move it away or choose another output",
                             key="output", value=str(self.folder)) from None

    def finished(self) -> set[int]:
        """The indices of the chunks already stored."""
        if not self.folder.is_dir():
            return set()
        return {int(match["index"]) for path in self.folder.iterdir()
                if (match := CHUNK_NAME.fullmatch(path.name))}

    def _path(self, index: int) -> Path:
        return self.folder / f"chunk_{index:06d}.npz"

    def write(self, index: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Store chunk `index` (whole or not at all); the first one makes the folder and its
        `sweep.json`."""
        manifest = self.folder / MANIFEST
        if not manifest.is_file():
            text = json.dumps({"fingerprint": self.fingerprint, **self._description}, indent=1,
                              default=str) + "\n"
            atomic_write(manifest, lambda path: Path(path).write_text(text, encoding="utf-8"))

        def save(path: str) -> None:
            with open(path, "wb") as file:
                np.savez(file, **arrays)
        atomic_write(self._path(index), save)

    def read(self, index: int) -> dict[str, np.ndarray]:
        """The arrays of chunk `index`; InputError for a missing or unreadable file."""
        path = self._path(index)
        try:
            with np.load(path) as data:
                return {name: data[name] for name in data.files}
        except (OSError, ValueError) as error:
            raise InputError(f"cannot read the finished chunk {path} ({error}); pass --restart "
                             "to compute the sweep again", key="output", value=str(path)) from None

    def remove(self) -> None:
        """Delete the store and its chunks."""
        shutil.rmtree(self.folder, ignore_errors=True)
