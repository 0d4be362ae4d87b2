"""A small sweep dataset in the layout of `skyscatter sweep` (docs/fit.md), for the fit's tests
and benchmarks/bench_fit_coverage.py: one config dimension named after its dotted key
(`[i]` -> `_i`, `.` -> `_`, attribute `config_key`), then sun_zenith, view_zenith, azimuth,
wavelength; `radiance` over all, `direct_transmittance` over (config, sun_zenith, wavelength),
both from `api.radiance_dataset` / `api.irradiance_dataset` of one solver per value."""

from __future__ import annotations

from collections.abc import Sequence

import xarray

from skyscatter import api
from skyscatter.atmosphere.config_overrides import atmosphere_with, load_document


def dimension_name(key: str) -> str:
    """constituent[2].optics.optical_depth -> constituent_2_optics_optical_depth."""
    return key.replace("[", "_").replace("]", "").replace(".", "_")


def build_sweep(config: str, key: str, values: Sequence[float], sun_zeniths: Sequence[float],
                view_zeniths: Sequence[float], azimuths: Sequence[float],
                wavelengths: Sequence[float], solver: str = "hillaire") -> xarray.Dataset:
    """The sweep of `config` over `key` = `values` by `solver` (module docstring)."""
    document, path = load_document(config)
    parts = []
    for value in values:
        atmosphere = atmosphere_with(document, path, {key: float(value)})
        options = api.solver_options(atmosphere, use_cache=False)
        sky = api.radiance_dataset(atmosphere, sun_zeniths, view_zeniths, azimuths,
                                   wavelengths, solver=solver, options=options)
        surface = api.irradiance_dataset(atmosphere, sun_zeniths, wavelengths,
                                         solver="single", options=options)
        parts.append(xarray.Dataset({"radiance": sky["radiance"],
                                     "direct_transmittance": surface["direct_transmittance"]}))
    name = dimension_name(key)
    dataset = xarray.concat(parts, dim=name)
    dataset = dataset.assign_coords({name: (name, [float(v) for v in values],
                                            {"config_key": key})})
    dataset.attrs["solver"] = solver
    return dataset
