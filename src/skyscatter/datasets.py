"""Tables of results as labelled arrays: `xarray.Dataset`s that can be written to NetCDF.

`rows_dataset` turns rows (`sky_radiance_rows`, `irradiance_rows`: one dict per combination of
the inputs, in the order of `itertools.product`) into a Dataset whose dimensions are the
inputs (sun_zenith, view_zenith, azimuth, wavelength) and whose data variables are the other
columns, each with the `units` and `long_name` attributes of the CF conventions (CF-1.8,
https://cfconventions.org/; units in UDUNITS spelling, `output_metadata.COLUMNS`). The
global attributes are the run's metadata (`output_metadata`), nested keys joined with "_"
(NetCDF attributes are flat: text, numbers or lists of numbers).

`grid_dataset` makes one of arrays already on a grid (a sweep's: `sweep.assemble`), with the
same attributes.

`write_netcdf` writes one with scipy's NetCDF-3 writer (`engine="scipy"`, no netCDF4 library
needed), `write_zarr` as a Zarr store (a folder, https://zarr.dev; the `[dask]` extra), each to
a temporary renamed when complete (`output_files`).

xarray is an optional dependency (`pip install "skyscatter[science]"`), imported only here and
only when a Dataset is made.
"""

from __future__ import annotations

import importlib.util
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter.errors import InputError
from skyscatter.output_files import atomic_write, staged_outputs
from skyscatter.output_metadata import COLUMNS

__all__ = ["grid_dataset", "import_xarray", "rows_dataset", "write_netcdf", "write_zarr"]

EXTRA = 'pip install "skyscatter[science]"'
ZARR_EXTRA = 'pip install "skyscatter[dask]"'


def import_xarray():
    """The xarray module; InputError naming the extra that installs it when it is missing."""
    try:
        import xarray
    except ImportError:
        raise InputError(f"datasets and NetCDF files need xarray: {EXTRA} (or pip install "
                         "xarray)", key="xarray", allowed=EXTRA) from None
    return xarray


def rows_dataset(rows: Sequence[Mapping[str, float]], dimensions: Mapping[str, str],
                 shape: Sequence[int], metadata: Mapping[str, Any], *,
                 reduced: Mapping[str, tuple[str, ...]] | None = None):
    """A Dataset of `rows` in product order over the columns `dimensions` (column -> dimension
    name, outermost first) of sizes `shape`. Every other column is a data variable over all
    dimensions, or over `reduced[column]` (a subset, e.g. ("wavelength",)) where it does not
    depend on the rest; () makes it a scalar coordinate. `metadata` (`output_metadata`) gives
    the global attributes, `output_metadata.COLUMNS` the units."""
    xarray = import_xarray()
    columns = list(rows[0])
    table = np.array([[row[name] for name in columns] for row in rows], dtype=np.float64)
    names = list(dimensions)
    cube = table.reshape(*shape, len(columns))
    dims = [dimensions[name] for name in names]
    coords = {}
    for axis, name in enumerate(names):
        index = [0] * len(names)
        index[axis] = slice(None)
        coords[dimensions[name]] = (dimensions[name], cube[(*index, columns.index(name))],
                                    _attributes(name))
    variables, scalars = {}, {}
    for name in columns:
        if name in dimensions:
            continue
        keep = tuple(dims) if reduced is None else reduced.get(name, tuple(dims))
        index = tuple(slice(None) if dim in keep else 0 for dim in dims)
        values = cube[(*index, columns.index(name))]
        if keep:
            variables[name] = (keep, values, _attributes(name))
        else:
            scalars[name] = ((), values, _attributes(name))
    attributes = {"Conventions": "CF-1.8", **_flat_attributes(
        {key: value for key, value in metadata.items() if key != "columns"})}
    return xarray.Dataset(variables, coords={**coords, **scalars}, attrs=attributes)


# times (numpy datetime64, UTC) on disk: CF seconds since the Unix epoch, as float64 (NetCDF-3
# has no int64, and int32 seconds end in 2038; float64 keeps microseconds for centuries)
TIME_ENCODING = {"units": "seconds since 1970-01-01", "calendar": "proleptic_gregorian",
                 "dtype": "float64"}


def grid_dataset(variables: Mapping[str, tuple[Sequence[str], np.ndarray]],
                 coordinates: Mapping[str, tuple[Sequence[object], str | Mapping[str, str]]],
                 metadata: Mapping[str, Any], *,
                 aligned: Mapping[str, tuple[str, Sequence[float], str]] | None = None):
    """A Dataset of `variables` (column name in `output_metadata.COLUMNS` -> (dimensions,
    array)) on `coordinates` (dimension -> (values, the column whose units and long name it
    takes, or its attributes)), with the non-dimension coordinates `aligned` (name ->
    (dimension, values, column)); `metadata` gives the global attributes as in
    `rows_dataset`."""
    xarray = import_xarray()
    coords = {}
    for name, (values, described) in coordinates.items():
        attributes = _attributes(described) if isinstance(described, str) else dict(described)
        coords[name] = (name, np.asarray(values), attributes)
    for name, (dimension, values, column) in (aligned or {}).items():
        coords[name] = (dimension, np.asarray(values, dtype=np.float64), _attributes(column))
    data = {name: (tuple(dims), np.asarray(values), _attributes(name))
            for name, (dims, values) in variables.items()}
    attributes = {"Conventions": "CF-1.8", **_flat_attributes(
        {key: value for key, value in metadata.items() if key != "columns"})}
    dataset = xarray.Dataset(data, coords=coords, attrs=attributes)
    for name in coordinates:
        if np.issubdtype(dataset[name].dtype, np.datetime64):
            dataset[name].encoding.update(TIME_ENCODING)
    return dataset


def _attributes(column: str) -> dict[str, str]:
    units, long_name = COLUMNS[column]
    return {"units": units, "long_name": long_name}


def _flat_attributes(metadata: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """NetCDF-ready attributes: nested keys joined with "_", lists as float64 arrays."""
    flat: dict[str, Any] = {}
    for key, value in metadata.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            flat.update(_flat_attributes(value, f"{name}_"))
        elif isinstance(value, list | tuple):
            flat[name] = np.asarray(value, dtype=np.float64)
        elif isinstance(value, bool):
            flat[name] = int(value)
        elif value is not None:
            flat[name] = value
    return flat


def write_netcdf(dataset, path: str | Path) -> Path:
    """Write `dataset` to `path` as NetCDF-3 (scipy), whole or not at all."""
    if Path(path).suffix.lower() != ".nc":
        raise InputError(f"cannot write a dataset as {str(path)!r}: name it .nc (NetCDF)",
                         key="path", value=str(path), allowed=".nc")
    return atomic_write(path, lambda temporary: dataset.to_netcdf(temporary, engine="scipy"))


def write_zarr(dataset, path: str | Path) -> Path:
    """Write `dataset` to `path` as a Zarr store (a folder), whole or not at all: written into
    a temporary folder that replaces `path` when complete. InputError naming the extra when
    zarr is missing."""
    if Path(path).suffix.lower() != ".zarr":
        raise InputError(f"cannot write a Zarr store as {str(path)!r}: name it .zarr",
                         key="path", value=str(path), allowed=".zarr")
    if importlib.util.find_spec("zarr") is None:
        raise InputError(f"Zarr stores need zarr: {ZARR_EXTRA} (or pip install zarr)",
                         key="zarr", allowed=ZARR_EXTRA)
    with staged_outputs() as stage, warnings.catch_warnings():
        # zarr 3 notes that consolidated metadata (which xarray writes for fast opening) is
        # not in the Zarr 3 specification; xarray and zarr read it
        warnings.filterwarnings("ignore", message="Consolidated metadata")
        dataset.to_zarr(stage.folder(path), mode="w")
    return Path(path)
