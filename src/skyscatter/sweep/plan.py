"""What a sweep computes: its axes, its atmospheres, its chunks and its fingerprint.

The grid is the product, outermost first, of the config axes (in the order given) and the
geometry: sun zenith, view zenith, azimuth relative to the sun, wavelength. A sweep over times
(`times_utc`) has a time dimension in place of sun zenith: the sun's zenith angle and azimuth at
each time, from the ephemeris, are given with it (`sun_zeniths_deg`, `sun_azimuths_deg`), and
the view azimuths stay relative to the sun. Atmosphere `a` is the combination at
`numpy.unravel_index(a, atmosphere_shape)` of the config axes; chunk `c = a n_sun + s` is
atmosphere `a` at sun zenith (or time) `s`, with every view direction and wavelength. The
fingerprint (SHA-256 of everything that changes a number of the result) names the chunk
store's sweep, so that chunks of another sweep are never mixed in.

Public names: `GEOMETRY_DIMENSIONS`, `SweepPlan`, `dimension_name`.
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter import __version__
from skyscatter.atmosphere.config_overrides import atmosphere_with
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.errors import InputError
from skyscatter.transport.cache import TableCache
from skyscatter.transport.solvers import SolverOptions

__all__ = ["GEOMETRY_DIMENSIONS", "SweepPlan", "dimension_name"]

# the dimensions after the config axes, in this order
GEOMETRY_DIMENSIONS = ("sun_zenith", "view_zenith", "azimuth", "wavelength")


def dimension_name(key: str) -> str:
    """The dataset dimension of a config key: `constituent[2].optics.optical_depth` ->
    `constituent_2_optics_optical_depth` (`[i]` -> `_i`, `.` -> `_`)."""
    return re.sub(r"\[(\d+)\]", r"_\1", key).replace(".", "_")


@dataclass(frozen=True)
class SweepPlan:
    """A sweep: the config `document` (read from `path`; `config` as the user named it), the
    config `axes` ((dotted key, values) pairs), the geometry [deg], wavelengths [nm], the
    observer's altitude [m] and the solver with its settings (`orders` None: each
    atmosphere's config's; tables cached in `cache_dir` unless not `use_cache`). A sweep over
    times has `times_utc` (ISO 8601 in UTC, one per sun zenith: the sun's zenith angle and
    azimuth `sun_azimuths_deg` then, and its distance `sun_distances_m` [m], which scales the
    light by the inverse-square law) at `place_deg` (latitude, longitude)."""

    config: str
    document: dict[str, Any]
    path: str
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    sun_zeniths_deg: tuple[float, ...]
    view_zeniths_deg: tuple[float, ...]
    relative_azimuths_deg: tuple[float, ...]
    wavelengths_nm: tuple[float, ...]
    altitude_m: float = 0.0
    solver: str = "lut"
    orders: int | None = None
    n_samples: int = 64
    seed: int = 0
    cache_dir: str | None = None
    use_cache: bool = True
    times_utc: tuple[str, ...] = ()
    sun_azimuths_deg: tuple[float, ...] = ()
    place_deg: tuple[float, float] | None = None
    sun_distances_m: tuple[float, ...] = ()
    dimensions: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        names: dict[str, str] = {}
        for key, values in self.axes:
            name = dimension_name(key)
            if name in names or name in (*GEOMETRY_DIMENSIONS, "time"):
                other = names.get(name, "the geometry")
                raise InputError(f"--set {key} and {other} both make the dimension {name!r}; "
                                 "sweep each config value once", key="key", value=key)
            names[name] = key
            for value in values:
                if isinstance(value, dict | list):
                    raise InputError(f"--set {key}: {value!r} cannot label a dataset axis; "
                                     "sweep numbers or words", key=key, value=value,
                                     allowed="numbers or words")
        object.__setattr__(self, "dimensions", tuple(names))
        n_times = len(self.times_utc)
        if n_times and (self.place_deg is None or not n_times == len(self.sun_zeniths_deg)
                        == len(self.sun_azimuths_deg)):
            raise ValueError("a sweep over times needs one sun zenith and azimuth per time "
                             "and the place")

    @property
    def geometry_dimensions(self) -> tuple[str, ...]:
        """The dimensions after the config axes: `GEOMETRY_DIMENSIONS`, with time in place of
        sun_zenith in a sweep over times."""
        first = "time" if self.times_utc else "sun_zenith"
        return (first, *GEOMETRY_DIMENSIONS[1:])

    @property
    def atmosphere_shape(self) -> tuple[int, ...]:
        """The lengths of the config axes (() without any: one atmosphere)."""
        return tuple(len(values) for _, values in self.axes)

    @property
    def n_atmospheres(self) -> int:
        return int(np.prod(self.atmosphere_shape, dtype=np.int64))

    @property
    def n_chunks(self) -> int:
        return self.n_atmospheres * len(self.sun_zeniths_deg)

    def atmosphere_values(self, index: int) -> dict[str, Any]:
        """The config values of atmosphere `index`: dotted key -> value."""
        position = np.unravel_index(index, self.atmosphere_shape) if self.axes else ()
        return {key: values[int(i)] for (key, values), i in zip(self.axes, position,
                                                                 strict=True)}

    def atmosphere(self, index: int) -> Atmosphere:
        """The atmosphere of `index` (`config_overrides.atmosphere_with`)."""
        return atmosphere_with(self.document, Path(self.path), self.atmosphere_values(index))

    def chunk(self, index: int) -> tuple[int, int]:
        """(atmosphere, sun zenith index) of chunk `index`."""
        return divmod(index, len(self.sun_zeniths_deg))

    def chunks_of(self, atmosphere: int) -> range:
        """The chunks of one atmosphere."""
        n_sun = len(self.sun_zeniths_deg)
        return range(atmosphere * n_sun, (atmosphere + 1) * n_sun)

    def solver_options(self, atmosphere: Atmosphere) -> SolverOptions:
        """The solver's options for `atmosphere` (no progress callbacks: they run on workers)."""
        return SolverOptions(
            n_samples=self.n_samples, seed=self.seed,
            orders=atmosphere.scattering_orders if self.orders is None else self.orders,
            cache=TableCache(self.cache_dir) if self.use_cache else None)

    def fingerprint(self) -> str:
        """SHA-256 of everything that changes a number of the result (not the table cache)."""
        described = {"version": __version__, "document": self.document, "path": self.path,
                     "axes": [[key, list(values)] for key, values in self.axes],
                     "sun_zeniths_deg": self.sun_zeniths_deg,
                     "view_zeniths_deg": self.view_zeniths_deg,
                     "relative_azimuths_deg": self.relative_azimuths_deg,
                     "wavelengths_nm": self.wavelengths_nm, "altitude_m": self.altitude_m,
                     "solver": self.solver, "orders": self.orders, "n_samples": self.n_samples,
                     "seed": self.seed}
        if self.times_utc:
            described.update(times_utc=self.times_utc, sun_azimuths_deg=self.sun_azimuths_deg,
                             place_deg=self.place_deg, sun_distances_m=self.sun_distances_m)
        text = json.dumps(described, sort_keys=True, default=str, allow_nan=True)
        return hashlib.sha256(text.encode("utf-8")).hexdigest()
