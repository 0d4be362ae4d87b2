"""Cloud layers given as a 3-D grid of water content read from a file (`type = "grid"`).

A grid file is a numpy `.npz` archive (`np.savez("cloud.npz", water_g_m3=w, spacing_m=(dx,
dy, dz))`) with

    water_g_m3   (nx, ny, nz) float    liquid or ice water content [g m^-3] at the centres of
                                       the cells, x east, y north, z up
    spacing_m    (3,) float            dx, dy, dz [m], the cells' size
    periodic     () bool, optional     true (default): the field repeats horizontally, as
                                       the doubly periodic domains of large-eddy simulations;
                                       false: no water outside the box

The box (nx dx by ny dy by nz dz) stands on the layer's `base_altitude_m`, horizontally
centred on the observer (`atmosphere.cloud_field`); `_cloud_sampling.grid_water` reads it
trilinearly between cell centres (the half cell at the box's sides and at its bottom and
top keeps the edge cells' value).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skyscatter.errors import InputError

__all__ = ["GRID_ARRAYS", "MAX_GRID_CELLS", "MAX_GRID_SPACING_M", "MAX_GRID_WATER_G_M3",
           "read_cloud_grid"]

GRID_ARRAYS = ("water_g_m3", "spacing_m", "periodic")
# The grid rides in CloudField.profiles as float64 (8 bytes a cell, `_cloud_sampling` module
# docstring), copied once per render and once per layer row: 2^24 cells (256^3, or an LES
# domain of 512 x 512 x 64) are 128 MiB. Coarsen larger fields (every second cell).
MAX_GRID_CELLS = 2**24
MAX_GRID_SPACING_M = 10_000.0  # a cell wider than 10 km is a climate model's, not a cloud's
# as cloud_config.WATER_CONTENT_G_M3: ~5 g m^-3 in deep convection; 50 catches kg for g
MAX_GRID_WATER_G_M3 = 50.0
_ALLOWED = ("a numpy .npz archive with water_g_m3 (nx, ny, nz) floats [g m^-3] >= 0, "
            "spacing_m (3,) [m] > 0 and optionally periodic (true or false): "
            "np.savez(path, water_g_m3=w, spacing_m=(dx, dy, dz))")


def read_cloud_grid(path: str | Path) -> tuple[np.ndarray, tuple[float, float, float], bool]:
    """(water_g_m3 (nx, ny, nz) float64 [g m^-3], spacing (dx, dy, dz) [m], periodic) of the
    grid file `path` (module docstring). InputError naming the file, the array and how to fix
    it for a file that is missing or not an .npz archive, an array that is missing or has the
    wrong shape or type, water that is not finite, negative or above `MAX_GRID_WATER_G_M3`,
    a spacing that is not in (0, `MAX_GRID_SPACING_M`], or more than `MAX_GRID_CELLS` cells."""
    source = Path(path)
    if not source.is_file():
        raise _error(source, "no such file")
    try:
        archive = np.load(source, allow_pickle=False)
        if not isinstance(archive, np.lib.npyio.NpzFile):
            raise _error(source, "a single .npy array, not an .npz archive of named arrays")
        with archive:
            arrays = {name: np.asarray(archive[name]) for name in archive.files}
    except InputError:
        raise
    except Exception as error:  # any decoder's complaint about a bad file
        raise _error(source, f"cannot read it ({type(error).__name__}: {error})") from None
    for name in GRID_ARRAYS[:2]:
        if name not in arrays:
            found = ", ".join(sorted(arrays)) or "none"
            raise _error(source, f"has no array '{name}' (it has: {found})", name)
    water = arrays["water_g_m3"]
    if water.ndim != 3 or water.size == 0:
        raise _error(source, f"water_g_m3 has shape {water.shape}: give (nx, ny, nz), x east, "
                     "y north, z up, at least 1 cell along each", "water_g_m3")
    if water.size > MAX_GRID_CELLS:
        raise _error(source, f"water_g_m3 has {water.size} cells {water.shape}, more than "
                     f"{MAX_GRID_CELLS} (256^3; 8 bytes a cell in memory): coarsen it, e.g. "
                     "w[::2, ::2, ::2] with spacing_m doubled", "water_g_m3")
    water = _real(source, water, "water_g_m3")
    if not np.all(np.isfinite(water)):
        raise _error(source, f"water_g_m3 has {int(np.sum(~np.isfinite(water)))} values that "
                     "are not finite (NaN or inf): fill them, e.g. np.nan_to_num(w)",
                     "water_g_m3")
    if water.min() < 0.0 or water.max() > MAX_GRID_WATER_G_M3:
        raise _error(source, f"water_g_m3 ranges {water.min():.3g} .. {water.max():.3g}: give "
                     f"0 to {MAX_GRID_WATER_G_M3:g} g m^-3 (kg m^-3 times 1000; clip small "
                     "negative values from advection schemes with np.clip(w, 0, None))",
                     "water_g_m3")
    spacing = _real(source, arrays["spacing_m"], "spacing_m")
    if (spacing.shape != (3,) or not np.all(np.isfinite(spacing)) or np.any(spacing <= 0.0)
            or np.any(spacing > MAX_GRID_SPACING_M)):
        raise _error(source, f"spacing_m = {spacing.tolist()} is not allowed: give (dx, dy, dz),"
                     f" three cell sizes in (0, {MAX_GRID_SPACING_M:g}] m", "spacing_m")
    periodic = True
    if "periodic" in arrays:
        flag = arrays["periodic"]
        if flag.shape != () or flag.dtype.kind not in "bi" or int(flag) not in (0, 1):
            raise _error(source, f"periodic = {flag.tolist()} is not allowed: give true or "
                         "false (np.savez(..., periodic=False))", "periodic")
        periodic = bool(flag)
    dx, dy, dz = (float(s) for s in spacing)
    return np.ascontiguousarray(water), (dx, dy, dz), periodic


def _real(source: Path, values: np.ndarray, name: str) -> np.ndarray:
    """`values` as float64; InputError unless they are real numbers."""
    if values.dtype.kind not in "iuf":
        raise _error(source, f"{name} holds {values.dtype}, not real numbers", name)
    return values.astype(np.float64)


def _error(source: Path, problem: str, array: str | None = None) -> InputError:
    return InputError(f"cloud grid {source}: {problem}; give {_ALLOWED}" if array is None
                      else f"cloud grid {source}: {problem}", key="grid", value=str(source),
                      allowed=_ALLOWED)
