"""Compiling the numerical kernels before the first real run (`skyscatter compile`).

numba compiles each kernel on its first call and keeps the machine code in its cache (beside
the sources, or where `jit_cache` points it), so only the first run on a machine pays for it:
about a minute of CPU before the first picture of a fresh install. `compile_kernels` runs, at a
tiny size (16 x 16 pixels, one wavelength, tables in a temporary folder), the commands a new
user runs first: a render of each camera, the sky at a date, Mars's Mie dust, clouds, a
radiance table. Every later run loads those kernels from the cache. The Makefile calls it at install
time; a package installed with pip can call it once, or let the first run compile.

A marker file in the cache folder records that the kernels were compiled (by this command or
by a run that finished), so that the command line announces the compilation only when it is
about to happen (`FIRST_RUN_NOTE`). numba itself decides what to recompile: a kernel whose
source changed is compiled again although the marker stays.
"""

from __future__ import annotations

import contextlib
import io
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numba

from skyscatter import __version__
from skyscatter.errors import SkyscatterError
from skyscatter.jit_cache import kernel_cache_folder

__all__ = ["FIRST_RUN_NOTE", "WARM_UP_COMMANDS", "compile_kernels", "kernels_compiled",
           "mark_compiled", "marker_path"]

FIRST_RUN_NOTE = ("skyscatter: first run on this machine: compiling the numerical kernels "
                  "(about a minute of CPU, once; `skyscatter compile` does it ahead of time)")

_TINY = ("--size", "16", "--wavelengths", "1")
# A frame of at least `lut_solver.SKY_GRID_MIN_RAYS` sky rays from one observer takes the
# sky-view grid and the aureole's per-frame table, which the tiny frames never reach: the
# panorama's upper half (384 x 768 pixels) does; one with `lut_solver.SUN_GRID_MIN_RAYS` of
# them within 20 deg of the sun takes the sun grid: a perspective frame of 683 x 384 pixels,
# 40 deg high, centred on the default sun (30 deg high in the south).
_FULL_FRAME = ("--size", "384", "--wavelengths", "1")
# A terrain frame of at least `terrain.HORIZON_MIN_RAYS` rays culls them with the terrain's
# horizon, one with `lut_solver.AERIAL_GRID_MIN_POINTS` rays on the terrain takes the
# aerial-perspective grid: 683 x 384 pixels (110 000 on the mountains).
_TERRAIN_FRAME = ("--size", "384", "--wavelengths", "1")
# (what it compiles, the command line's arguments without the output and cache options)
WARM_UP_COMMANDS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("tables and the fisheye", ("render", "earth", *_TINY)),
    ("the panorama and a full frame's sky-view grid", ("render", "earth", "--camera",
                                                       "panorama", *_FULL_FRAME)),
    ("a full frame around the sun, its sun grid", ("render", "earth", "--camera", "perspective",
                                                   "--fov", "40", "--pitch", "30",
                                                   *_FULL_FRAME)),
    ("a low sun: single scattering marched along the views", (
        "render", "earth", "--camera", "panorama", "--sun-elevation", "2", *_FULL_FRAME)),
    ("the perspective camera and terrain", ("render", "earth", "--camera", "perspective",
                                            "--terrain", "demo", "--altitude", "300",
                                            *_TERRAIN_FRAME)),
    ("the view from orbit", ("render", "earth", "--camera", "orbit", "--distance-km", "20000",
                             *_TINY)),
    ("the sky at a date: sun, moon, stars", ("render", "earth", "--time",
                                             "2024-01-25T23:00+01:00", "--lat", "52.52",
                                             "--lon", "13.40", *_TINY)),
    ("Mie dust", ("render", "mars-physical", *_TINY)),
    ("clouds, their shadows on the ground", ("render", "earth", "--clouds", "cumulus",
                                             "--altitude", "2", *_TINY)),
    ("the Hillaire 2020 solver and its sky-view table", (
        "render", "earth", "--solver", "hillaire", "--camera", "panorama", *_FULL_FRAME)),
    ("radiance", ("radiance", "earth", "--sun-zenith", "30", "--wavelengths", "550")),
)


def marker_path() -> Path:
    """The marker file in numba's cache folder for this package, numba and Python version
    and machine."""
    folder = kernel_cache_folder()
    python = f"{sys.version_info.major}{sys.version_info.minor}"
    name = (f"skyscatter-{__version__}-numba-{numba.__version__}-py{python}-"
            f"{platform.machine() or 'cpu'}.compiled")
    return Path(folder) / name


def kernels_compiled() -> bool:
    """Whether this machine's kernels were compiled before (the marker exists)."""
    return marker_path().is_file()


def mark_compiled() -> None:
    """Write the marker (to a temporary file, then renamed); a cache folder that cannot be
    written only means that the next run announces the compilation again."""
    marker = marker_path()
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=marker.parent, delete=False,
                                         suffix=".tmp") as handle:
            handle.write(f"compiled {time.strftime('%Y-%m-%dT%H:%M:%S%z')}\n")
        os.replace(handle.name, marker)
    except OSError:
        pass


def compile_kernels(run: Callable[[Sequence[str]], int],
                    report: Callable[[str], None] = print) -> float:
    """Run WARM_UP_COMMANDS through `run` (the command line's entry point: arguments ->
    exit code) with their outputs and tables in a temporary folder, write the marker, and
    return the seconds it took. A command that fails raises SkyscatterError."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="skyscatter-compile-") as folder:
        for index, (what, arguments) in enumerate(WARM_UP_COMMANDS, start=1):
            started = time.perf_counter()
            outputs = (("-o", str(Path(folder) / f"{index}.png"))
                       if arguments[0] == "render" else ())
            said = io.StringIO()  # the command's own lines: shown only if it fails
            with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
                code = run([*arguments, *outputs, "--cache-dir", folder])
            if code != 0:
                raise SkyscatterError(f"compiling the kernels failed in `skyscatter "
                                      f"{' '.join(arguments)}` (exit code {code}): "
                                      f"{said.getvalue().strip()}")
            report(f"compiled {index}/{len(WARM_UP_COMMANDS)}: {what} "
                   f"({time.perf_counter() - started:.0f} s)")
    mark_compiled()
    return time.perf_counter() - start
