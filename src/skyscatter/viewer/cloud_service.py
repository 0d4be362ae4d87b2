"""The viewer's clouds: which a page may ask for, checked, and their messages, made once.

A page asks /api/clouds?clouds=NAME&atmosphere=NAME for the cloud layers NAME (a preset of
`atmosphere.cloud_presets`, or the clouds file `skyscatter view --clouds FILE` offered under
its own name) over the planet of the atmosphere NAME (its radius and its star, whose spectrum
weights the optics: `gpu_clouds`). A request never names a file: only the names offered here.
A message is made in 7-10 s on 2 cores (`cloud_field`: the noise tile of each seed, Mie optics
on `DEFAULT_WAVELENGTH_BINS` wavelengths, the far field's column statistics) and kept in memory
(MEMORY_ENTRIES, least recently used dropped); one is made at a time.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Mapping
from pathlib import Path

from skyscatter.atmosphere.cloud_config import Clouds, list_cloud_presets, load_clouds
from skyscatter.errors import InputError
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.viewer.gpu_clouds import encode_clouds, gpu_clouds
from skyscatter.viewer.table_service import TableService

__all__ = ["CloudService", "MEMORY_ENTRIES", "NO_CLOUDS"]

MEMORY_ENTRIES = 4  # cloud messages kept (a one-layer message is 8.5 MiB)
NO_CLOUDS = "none"  # the page's choice for a clear sky (never asked of the server)


class CloudService:
    """The clouds a viewer offers (module docstring); atmospheres come from `tables`."""

    def __init__(self, tables: TableService) -> None:
        self.tables = tables
        self._descriptions = dict(list_cloud_presets())
        self._files: dict[str, Path] = {}
        self._loaded: dict[str, Clouds] = {}
        self.default = NO_CLOUDS
        self._lock = threading.Lock()
        self._messages: OrderedDict[tuple[str, str], bytes] = OrderedDict()

    def offer(self, name_or_path: str | Path) -> str:
        """Offer the clouds preset or file `name_or_path` (`load_clouds`: ConfigError for a
        bad file) and make it the page's first choice; returns its name."""
        clouds = load_clouds(name_or_path)
        text = str(name_or_path)
        name = Path(text).stem if Path(text).suffix else text
        self._loaded[name] = clouds
        self._descriptions.setdefault(name, clouds.description)
        self.default = name
        return name

    def describe(self) -> dict:
        """What the page offers (JSON-able)."""
        return {"default": self.default, "none": NO_CLOUDS,
                "clouds": [{"name": name, "description": text}
                           for name, text in sorted(self._descriptions.items())]}

    def clouds(self, name: str) -> Clouds:
        """The offered clouds `name` (loaded once); InputError for a name not offered."""
        if name not in self._descriptions:
            raise InputError(f"unknown clouds {name!r}; choose one of: "
                             f"{', '.join(sorted(self._descriptions))}", key="clouds",
                             value=name, allowed=", ".join(sorted(self._descriptions)))
        if name not in self._loaded:
            self._loaded[name] = load_clouds(name)
        return self._loaded[name]

    def parse(self, query: Mapping[str, str]) -> tuple[str, str]:
        """(clouds, atmosphere) of a page's query; InputError naming the first bad parameter."""
        allowed = ("atmosphere", "clouds")
        for key in query:
            if key not in allowed:
                raise InputError(f"unknown parameter {key!r}; known: {', '.join(allowed)}",
                                 key=key, value=query[key], allowed=", ".join(allowed))
        if "clouds" not in query:
            raise InputError("missing parameter 'clouds'", key="clouds")
        name = query["clouds"]
        self.clouds(name)
        atmosphere = query.get("atmosphere", self.tables.default)
        self.tables.atmosphere(atmosphere)
        return name, atmosphere

    def message(self, name: str, atmosphere: str) -> bytes:
        """The encoded clouds `name` over the planet of `atmosphere` (`gpu_clouds`)."""
        key = (name, atmosphere)
        with self._lock:
            if key not in self._messages:
                planet = self.tables.atmosphere(atmosphere).planet
                wavelengths = wavelength_grid(DEFAULT_WAVELENGTH_BINS)
                self._messages[key] = encode_clouds(gpu_clouds(
                    self.clouds(name), planet.radius_m, wavelengths,
                    planet.star.irradiance_toa(wavelengths), name))
                while len(self._messages) > MEMORY_ENTRIES:
                    self._messages.popitem(last=False)
            self._messages.move_to_end(key)
            return self._messages[key]
