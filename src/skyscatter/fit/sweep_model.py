"""The forward model of a fit from a sweep: interpolation in a precomputed dataset.

A sweep (`skyscatter sweep`, an xarray Dataset) has one dimension per swept config value
(its coordinate's attribute `config_key` is the dotted key), then sun_zenith, view_zenith,
azimuth (relative to the sun) [deg] and wavelength [nm]; `radiance` spans them all,
`direct_transmittance` (config..., sun_zenith, wavelength). Interpolation is multilinear
(`scipy.interpolate.RegularGridInterpolator`) in log(value) - radiance and transmittance vary
nearly exponentially with an optical depth - on the swept grid; a config axis of positive
values is taken in log too, since radiance grows about as the optical depth while that is
small: log-linear in the optical depth alone was 1-2 % low between the sweep values 0.12 and
0.18 of the synthetic retrieval (docs/fit.md), log-log within 0.5 %. A sweep dimension of one
value is held at it. Every swept config dimension with more than one value must be a free
parameter, and every free parameter a swept dimension whose range covers its bounds; each
row's geometry and wavelength must lie inside the grid (no extrapolation). Chromaticity needs
spectra over the visible, which a sweep at a few wavelengths does not hold: fit it with a
solver.

The model error is that of the solver that made the sweep (its `solver_name` attribute, as
`skyscatter sweep` writes it, or a `solver` attribute), plus the interpolation's, which the
grid's spacing sets: check it by fitting with the solver (`--refine`) or a denser sweep.

Public names: `GEOMETRY_DIMENSIONS`, `SweepModel`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from skyscatter.errors import InputError
from skyscatter.fit.forward import folded_azimuth_deg
from skyscatter.fit.measurements import Measurements
from skyscatter.fit.model_error import model_error
from skyscatter.fit.parameters import FreeParameter

__all__ = ["GEOMETRY_DIMENSIONS", "SweepModel"]

GEOMETRY_DIMENSIONS = ("sun_zenith", "view_zenith", "azimuth", "wavelength")
_COLUMNS = {"sun_zenith": "sun_zenith_deg", "view_zenith": "view_zenith_deg",
            "azimuth": "relative_azimuth_deg", "wavelength": "wavelength_nm"}
_SURFACE_DIMENSIONS = ("sun_zenith", "wavelength")
_TOLERANCE = 1e-6  # a row on a held (one-valued) axis must match it this closely [deg, nm]


class SweepModel:
    """Interpolation in `dataset` (module docstring) for the free parameters `free`;
    `model_error_override` replaces the model error of the sweep's solver."""

    def __init__(self, dataset: Any, free: Sequence[FreeParameter], *,
                 model_error_override: float | None = None, label: str = "sweep") -> None:
        if "radiance" not in dataset.data_vars:
            raise InputError(f"{label}: no 'radiance' variable; is it the output of "
                             "`skyscatter sweep`?", key="model", value=label)
        self.label, self.free = label, list(free)
        self.model_error_override = model_error_override
        self.solver = _solver_name(dataset.attrs.get("solver_name", dataset.attrs.get("solver")))
        self.name = f"sweep ({self.solver or 'solver not named'})"
        radiance = dataset["radiance"]
        self.config_dims = [d for d in radiance.dims if d not in GEOMETRY_DIMENSIONS]
        missing = [d for d in GEOMETRY_DIMENSIONS if d not in radiance.dims]
        if "time" in radiance.dims:
            raise InputError(f"{label} is a sweep over times; a fit's sweep must be over sun "
                             "zenith angles: sweep again with --sun-zenith instead of --start/"
                             "--end", key="model", value=label, allowed="a sweep over --sun-zenith")
        if missing:
            raise InputError(f"{label}: radiance lacks the dimension(s) {', '.join(missing)}",
                             key="model", value=label)
        keys = {dim: str(dataset[dim].attrs.get("config_key", dim)) for dim in self.config_dims}
        self.dim_of: dict[str, str] = {}
        for parameter in self.free:
            dims = [d for d, k in keys.items() if k == parameter.key]
            if not dims:
                raise InputError(f"{label} does not sweep {parameter.key} (it sweeps "
                                 f"{', '.join(keys.values()) or 'no config value'}): fit it "
                                 "with a solver (--solver) or sweep it", key="free",
                                 value=parameter.key)
            axis = np.asarray(dataset[dims[0]].values, dtype=np.float64)
            if parameter.low < axis.min() - 1e-12 or parameter.high > axis.max() + 1e-12:
                raise InputError(f"--free {parameter.key}: the bounds {parameter.low:g}:"
                                 f"{parameter.high:g} reach outside the sweep's "
                                 f"{axis.min():g}-{axis.max():g}", key="free",
                                 value=parameter.key)
            self.dim_of[parameter.key] = dims[0]
        held = [d for d in self.config_dims if d not in self.dim_of.values()
                and dataset.sizes[d] > 1]
        if held:
            raise InputError(f"{label} varies {', '.join(keys[d] for d in held)}, which is not "
                             "free: make it free (--free) or use a sweep that holds it",
                             key="free", value=held)
        self._radiance = _Grid(dataset["radiance"].sortby(list(radiance.dims)))
        self._transmittance = None
        if "direct_transmittance" in dataset.data_vars:
            variable = dataset["direct_transmittance"]
            self._transmittance = _Grid(variable.sortby(list(variable.dims)))

    def check(self, measurements: Measurements) -> None:
        """InputError for a kind the sweep cannot give or a row outside its grid."""
        if measurements.where("chromaticity").size or measurements.where("luminance").size:
            raise InputError(f"{self.label}: a sweep holds no spectra, so it cannot give "
                             "chromaticity or luminance; fit them with a solver (--solver)",
                             key="model", value=self.label)
        for kind, grid in (("radiance", self._radiance), ("transmittance",
                                                          self._transmittance)):
            index = measurements.where(kind)
            if index.size and grid is None:
                raise InputError(f"{self.label} has no direct_transmittance: sweep with a "
                                 "solver that lights surfaces (lut, single, hillaire)",
                                 key="model", value=self.label)
            if index.size:
                grid.check_rows(measurements, index, self.label)

    def predict(self, values: Mapping[str, float], measurements: Measurements
                ) -> tuple[np.ndarray, np.ndarray]:
        """(predicted value, its model error sigma_model) of each measured value."""
        config = {self.dim_of[key]: float(value) for key, value in values.items()}
        predicted = np.full(measurements.size, np.nan)
        for kind, grid in (("radiance", self._radiance), ("transmittance",
                                                          self._transmittance)):
            index = measurements.where(kind)
            if index.size:
                predicted[index] = grid(config, measurements, index)
        sigma = model_error(self.solver or "lut", measurements.kind, predicted,
                            self.model_error_override, sweep=True)
        return predicted, sigma


class _Grid:
    """Log-linear interpolation of one variable over its (sorted) dimensions."""

    def __init__(self, variable: Any) -> None:
        from scipy.interpolate import RegularGridInterpolator

        values = np.asarray(variable.values, dtype=np.float64)
        self.dims = list(variable.dims)
        self.axes = [np.asarray(variable[d].values, dtype=np.float64) for d in self.dims]
        keep = [i for i, axis in enumerate(self.axes) if axis.size > 1]
        values = values.reshape([self.axes[i].size for i in keep])
        self.log = bool(np.all(values > 0.0))
        self.free_dims = [self.dims[i] for i in keep]
        # config axes of positive values in log (module docstring); geometry axes linear
        self.log_axes = {self.dims[i] for i in keep if self.dims[i] not in _COLUMNS
                         and np.all(self.axes[i] > 0.0)}
        self.interpolator = RegularGridInterpolator(
            [np.log(self.axes[i]) if self.dims[i] in self.log_axes else self.axes[i]
             for i in keep], np.log(values) if self.log else values,
            bounds_error=False, fill_value=np.nan)

    def _column(self, measurements: Measurements, dim: str, index: np.ndarray) -> np.ndarray:
        values = getattr(measurements, _COLUMNS[dim])[index]
        return folded_azimuth_deg(values) if dim == "azimuth" else values

    def check_rows(self, measurements: Measurements, index: np.ndarray, label: str) -> None:
        for dim, axis in zip(self.dims, self.axes, strict=True):
            if dim not in _COLUMNS:
                continue
            values = self._column(measurements, dim, index)
            outside = (values < axis.min() - _TOLERANCE) | (values > axis.max() + _TOLERANCE)
            if np.any(outside):
                row = int(measurements.row[index[np.argmax(outside)]])
                raise InputError(f"row {row}: {_COLUMNS[dim]} = "
                                 f"{values[np.argmax(outside)]:g} lies outside {label}'s "
                                 f"{dim} {axis.min():g}-{axis.max():g}; the fit does not "
                                 "extrapolate", key=_COLUMNS[dim])

    def __call__(self, config: Mapping[str, float], measurements: Measurements,
                 index: np.ndarray) -> np.ndarray:
        columns = [np.full(index.size, np.log(config[d]) if d in self.log_axes else config[d])
                   if d in config else self._column(measurements, d, index)
                   for d in self.free_dims]
        result = self.interpolator(np.stack(columns, axis=-1))
        return np.exp(result) if self.log else result


def _solver_name(attribute: Any) -> str | None:
    """The solver's name from a dataset's `solver` attribute: a name, or the JSON text or
    dict of `output_metadata`'s {"name": ...}."""
    if isinstance(attribute, Mapping):
        return str(attribute.get("name")) if attribute.get("name") else None
    if isinstance(attribute, str) and attribute.strip().startswith("{"):
        try:
            return _solver_name(json.loads(attribute))
        except json.JSONDecodeError:
            return None
    return attribute if isinstance(attribute, str) and attribute else None
