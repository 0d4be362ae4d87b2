"""The arrays of a whole sweep, put together from its chunk store.

Dimensions, outermost first: one per config axis (`plan.dimension_name` of its key), then
sun_zenith (a sweep over times: time), view_zenith, azimuth (relative to the sun), wavelength:

    radiance              (config..., sun_zenith, view_zenith, azimuth, wavelength)
    standard_error        as radiance (Monte Carlo solver only)
    toa_irradiance        (wavelength), or (config..., wavelength) where a config value
                          changes it (the star's distance, say)
    direct_normal, diffuse_horizontal, global_horizontal, direct_transmittance
                          (config..., sun_zenith, wavelength) (solvers that light surfaces)

`grid_variables` returns them as name -> (dimensions, array), `grid_coordinates` the values
of every dimension, with the attributes of the config axes (`config_key`: the dotted key).
A sweep over times has a time coordinate (numpy datetime64 in UTC; xarray writes it as CF
"<units> since <date>") and `time_coordinates` gives sun_zenith(time), sun_azimuth(time) and
sun_distance(time) [m] (the radiance and surface irradiances are at that distance, the
toa_irradiance at the config's).

Public names: `grid_coordinates`, `grid_variables`, `time_coordinates`.
"""

from __future__ import annotations

import numpy as np

from skyscatter.sweep.plan import GEOMETRY_DIMENSIONS, SweepPlan
from skyscatter.sweep.store import ChunkStore

__all__ = ["grid_coordinates", "grid_variables", "time_coordinates"]

# column of the units and long name of each geometry dimension (`output_metadata.COLUMNS`)
_GEOMETRY_COLUMNS = dict(zip(GEOMETRY_DIMENSIONS, ("sun_zenith_deg", "view_zenith_deg",
                                                   "relative_azimuth_deg", "wavelength_nm"),
                             strict=True))
_SURFACE = ("direct_normal", "diffuse_horizontal", "global_horizontal", "direct_transmittance")


def grid_coordinates(plan: SweepPlan) -> dict[str, tuple[list, str | dict[str, str]]]:
    """Dimension -> (values, column of its units or its attributes), in dimension order."""
    coordinates: dict[str, tuple[list, str | dict[str, str]]] = {}
    for name, (key, values) in zip(plan.dimensions, plan.axes, strict=True):
        coordinates[name] = (list(values), {"config_key": key,
                                            "long_name": f"config value {key}"})
    geometry = (plan.sun_zeniths_deg, plan.view_zeniths_deg, plan.relative_azimuths_deg,
                plan.wavelengths_nm)
    for name, values in zip(GEOMETRY_DIMENSIONS, geometry, strict=True):
        coordinates[name] = (list(values), _GEOMETRY_COLUMNS[name])
    if plan.times_utc:
        del coordinates["sun_zenith"]
        times = [np.datetime64(text.removesuffix("+00:00"), "ns") for text in plan.times_utc]
        coordinates = {**dict(list(coordinates.items())[:len(plan.dimensions)]),
                       "time": (times, {"standard_name": "time", "long_name": "time (UTC)"}),
                       **dict(list(coordinates.items())[len(plan.dimensions):])}
    return coordinates


def time_coordinates(plan: SweepPlan) -> dict[str, tuple[str, list[float], str]]:
    """sun_zenith and sun_azimuth (from north towards east) [deg] and sun_distance [m] along
    the time of a sweep over times (none otherwise): name -> (dimension, values, column of its
    units)."""
    if not plan.times_utc:
        return {}
    return {"sun_zenith": ("time", list(plan.sun_zeniths_deg), "sun_zenith_deg"),
            "sun_azimuth": ("time", list(plan.sun_azimuths_deg), "sun_azimuth_deg"),
            "sun_distance": ("time", list(plan.sun_distances_m), "sun_distance_m")}


def grid_variables(plan: SweepPlan, store: ChunkStore
                   ) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
    """Every variable of the sweep from the chunks in `store` (all of them must be there)."""
    config = plan.dimensions
    shape = plan.atmosphere_shape
    n_sun, n_view, n_az, n_wl = (len(plan.sun_zeniths_deg), len(plan.view_zeniths_deg),
                                 len(plan.relative_azimuths_deg), len(plan.wavelengths_nm))
    sky = (*config, *plan.geometry_dimensions)
    surface = (*config, plan.geometry_dimensions[0], "wavelength")
    cubes: dict[str, tuple[tuple[str, ...], np.ndarray]] = {}
    for chunk in range(plan.n_chunks):
        arrays = store.read(chunk)
        atmosphere, sun = plan.chunk(chunk)
        where = tuple(int(i) for i in np.unravel_index(atmosphere, shape)) if shape else ()
        for name, values in arrays.items():
            if name not in cubes:
                if name in ("radiance", "standard_error"):
                    dims, size = sky, (*shape, n_sun, n_view, n_az, n_wl)
                elif name == "toa_irradiance":
                    dims, size = (*config, "wavelength"), (*shape, n_wl)
                else:
                    dims, size = surface, (*shape, n_sun, n_wl)
                cubes[name] = (dims, np.full(size, np.nan))
            index = where if name == "toa_irradiance" else (*where, sun)
            cubes[name][1][index] = values
    dims, toa = cubes["toa_irradiance"]
    flat = toa.reshape(-1, n_wl)
    if np.array_equal(flat, np.broadcast_to(flat[0], flat.shape)):
        cubes["toa_irradiance"] = (("wavelength",), flat[0].copy())
    order = ["radiance", "standard_error", "toa_irradiance", *_SURFACE]
    return {name: cubes[name] for name in order if name in cubes}
