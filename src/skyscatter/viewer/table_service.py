"""The viewer's atmospheres and their tables: what a page may ask for, checked, computed once,
one computation at a time, the newest request first.

A request names an atmosphere (a preset, or the config the viewer was started with), the
amount of each constituent as a factor of its configured density (aerosol, dust, ozone column,
the gas itself: `atmosphere.variants.scaled_constituent`), the ground albedo and a quality:

  preview  8 wavelength bins, the table sizes halved (`TableResolution.scaled(0.5)`), the
           config's orders: about a second for Earth, kept in memory only; the page shows it
           at once after a parameter change;
  full     `DEFAULT_WAVELENGTH_BINS` bins and the default sizes, the tables `skyscatter render`
           uses, from (and into) the table cache; the page swaps them in when they arrive.

The policy for table requests, whoever sends them: one computation at a time (a lock), so the
viewer never uses more than one table computation's CPU and memory; a newer request of the same
client (a page's own id, else its address) cancels that client's older one, computing or
waiting (its progress callback raises `SupersededError`, HTTP 409), so a user dragging a slider
waits for the last value only, while requests of other clients wait their turn instead of
cancelling each other; at most MAX_WAITING requests wait for the lock, more get `BusyError`
(HTTP 429) at once. Tables already in memory are answered without waiting.

What the viewer may add to the table cache is bounded twice: the cache's own size limit (least
recently used entries removed beyond `TableCache.max_bytes`) and, per service, VIEWER_CACHE_BYTES
of new entries (`ViewerCache`); beyond it full tables are computed and kept in memory only, so
a page stepping through parameters adds about 1 GiB at most, not 41 MiB (Earth) per step.

Nothing is written outside the service's cache directory: the full tables go through the table
cache, and the Mie tables that loading a dusty or hazy atmosphere computes go to its mie/ folder
(`disk_cache.cache_directory_override`; without a table cache, a temporary directory removed
with the service).
"""

from __future__ import annotations

import math
import shutil
import tempfile
import threading
import weakref
from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from skyscatter.atmosphere.config import list_presets, load_atmosphere, outline_atmosphere
from skyscatter.atmosphere.model import Atmosphere, OpticalProfile, SpectralParameter
from skyscatter.atmosphere.variants import scaled_constituent
from skyscatter.disk_cache import cache_directory_override
from skyscatter.errors import InputError
from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS, wavelength_grid
from skyscatter.transport.cache import TableCache
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import AtmosphereTables, TableResolution
from skyscatter.viewer.gpu_fast import encode_fast, fast_description, fast_profile
from skyscatter.viewer.gpu_tables import encode, gpu_tables

__all__ = ["BusyError", "QUALITIES", "SupersededError", "TableRequest", "TableService",
           "VIEWER_CACHE_BYTES", "ViewerCache"]

QUALITIES = {  # wavelength bins, table size factor
    "preview": (8, 0.5), "full": (DEFAULT_WAVELENGTH_BINS, 1.0)}
MAX_AMOUNT = 20.0  # largest factor on a constituent's amount
MAX_WAITING = 2  # table requests that may wait while another is computed
MEMORY_ENTRIES = 6  # table messages kept in memory (a full Earth one is about 25 MB)
VIEWER_CACHE_BYTES = 1 << 30  # new cache entries per service: four full Earth sets (243 MiB)


class SupersededError(Exception):
    """A newer table request arrived; this computation stops."""


class BusyError(Exception):
    """Too many table requests are waiting."""


@dataclass(frozen=True)
class TableRequest:
    """One set of tables: atmosphere name, constituent factors (sorted (name, factor)
    pairs), ground albedo (None: the config's) and quality."""

    atmosphere: str
    amounts: tuple[tuple[str, float], ...]
    albedo: float | None
    quality: str


def _number(name: str, text: str, low: float, high: float) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{name} = {text!r} is not a number", key=name, value=text) from None
    if not (math.isfinite(value) and low <= value <= high):
        raise InputError(f"{name} = {text} must lie in [{low:g}, {high:g}]", key=name,
                         value=text, allowed=f"[{low:g}, {high:g}]")
    return value


class ViewerCache(TableCache):
    """A table cache as the viewer uses it: it reads like `cache`, and stores until
    `budget_bytes` of new entries were written through it (the entry that crosses the line is
    still stored); then `check_writable` says why not, and the tables are kept in memory."""

    def __init__(self, cache: TableCache, budget_bytes: int = VIEWER_CACHE_BYTES) -> None:
        super().__init__(cache.directory, cache.max_bytes)
        self.budget_bytes = budget_bytes
        self.stored_bytes = 0

    def check_writable(self) -> str | None:
        if self.stored_bytes >= self.budget_bytes:
            return (f"the viewer has added {self.stored_bytes / 2**20:.0f} MiB to the cache, "
                    f"its limit of {self.budget_bytes / 2**20:.0f} MiB per session")
        return super().check_writable()

    def store(self, key: str, arrays: dict, metadata: dict) -> Path:
        path = super().store(key, arrays, metadata)
        self.stored_bytes += path.stat().st_size
        return path


class TableService:
    """The atmospheres a viewer offers and their tables (module docstring).

    `config` is a TOML file to offer besides the presets (under its own name); `cache` the
    table cache of the full-quality tables (None: kept in memory only)."""

    def __init__(self, config: str | Path | None = None, cache: TableCache | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        self.cache = ViewerCache(cache) if cache is not None else None
        if cache is not None:
            self.directory = Path(cache.directory)
        else:
            self.directory = Path(tempfile.mkdtemp(prefix="skyscatter-viewer-"))
            weakref.finalize(self, shutil.rmtree, self.directory, True)
        self._log = log or (lambda message: None)
        self._atmospheres: dict[str, Atmosphere] = {}
        self._descriptions = dict(list_presets())
        self._sources: dict[str, str | Path] = {name: name for name in self._descriptions}
        self._listing: list[dict] | None = None  # `describe`'s entries, read once
        self.default = "earth"
        if config is not None:
            with cache_directory_override(self.directory):
                atmosphere = load_atmosphere(config)
            name = Path(str(config)).stem if Path(str(config)).suffix else str(config)
            self._atmospheres[name] = atmosphere
            self._descriptions.setdefault(name, atmosphere.description)
            self._sources[name] = config
            self.default = name
        self._lock = threading.Lock()
        self._state = threading.Lock()
        self._generation = 0
        self._latest: dict[str, int] = {}  # client -> its newest request's generation
        self._waiting = 0
        self._messages: OrderedDict[TableRequest, bytes] = OrderedDict()
        self._fast: dict[str, bytes] = {}
        self.progress = {"busy": False, "stage": "", "done": 0, "total": 0, "label": ""}

    def atmosphere(self, name: str) -> Atmosphere:
        """The named atmosphere (loaded once); InputError for an unknown name."""
        if name not in self._descriptions:
            raise InputError(f"unknown atmosphere {name!r}; choose one of: "
                             f"{', '.join(sorted(self._descriptions))}", key="atmosphere",
                             value=name, allowed=", ".join(sorted(self._descriptions)))
        if name not in self._atmospheres:
            with cache_directory_override(self.directory):
                self._atmospheres[name] = load_atmosphere(name)
        return self._atmospheres[name]

    def describe(self) -> dict:
        """What the page offers: every atmosphere with its constituents, default albedo, sun
        size and whether it has an ephemeris (JSON-able). From the configs' outlines: no
        atmosphere's optics are built for it (the Mie tables of every preset took 20 s to
        2 minutes the first time), and read once: the atmospheres are, too."""
        if self._listing is None:
            self._listing = []
            for name in sorted(self._descriptions):
                outline = outline_atmosphere(self._sources[name])
                self._listing.append({
                    "name": name, "description": self._descriptions[name],
                    "body": outline.body, "constituents": list(outline.constituents),
                    "albedo": outline.mean_ground_albedo, "radius_m": outline.radius_m,
                    "top_altitude_m": outline.top_altitude_m,
                })
        return {"default": self.default, "atmospheres": self._listing,
                "max_amount": MAX_AMOUNT, "qualities": list(QUALITIES)}

    def parse(self, query: Mapping[str, str]) -> TableRequest:
        """The TableRequest of a page's query {atmosphere, quality, albedo, amount_NAME...};
        InputError naming the first bad parameter."""
        allowed = {"atmosphere", "quality", "albedo"}
        name = query.get("atmosphere", self.default)
        atmosphere = self.atmosphere(name)
        names = [c.name for c in atmosphere.constituents]
        allowed.update(f"amount_{c}" for c in names)
        for key in query:
            if key not in allowed:
                raise InputError(f"unknown parameter {key!r} for {name}; known: "
                                 f"{', '.join(sorted(allowed))}", key=key, value=query[key],
                                 allowed=", ".join(sorted(allowed)))
        quality = query.get("quality", "preview")
        if quality not in QUALITIES:
            raise InputError(f"quality = {quality!r}; choose one of: {', '.join(QUALITIES)}",
                             key="quality", value=quality, allowed=", ".join(QUALITIES))
        albedo = None if "albedo" not in query else _number("albedo", query["albedo"], 0.0, 1.0)
        amounts = tuple(sorted((c, _number(f"amount_{c}", query[f"amount_{c}"], 0.0, MAX_AMOUNT))
                               for c in names if f"amount_{c}" in query))
        return TableRequest(name, amounts, albedo, quality)

    def _atmosphere_of(self, request: TableRequest) -> Atmosphere:
        atmosphere = self.atmosphere(request.atmosphere)
        for constituent, factor in request.amounts:
            if factor != 1.0:
                atmosphere = scaled_constituent(atmosphere, constituent, factor)
        if request.albedo is not None:
            planet = replace(atmosphere.planet, ground_albedo=SpectralParameter((request.albedo,)))
            atmosphere = replace(atmosphere, planet=planet)
        return atmosphere

    def fast_message(self, name: str) -> bytes:
        """The fast model's description of atmosphere `name` at its configured amounts
        (`gpu_fast`; the page applies the factors and the albedo itself), made once: no
        table computation, so it is answered without waiting for the table lock."""
        if name not in self._fast:
            atmosphere = self.atmosphere(name)
            with cache_directory_override(self.directory):
                profile = fast_profile(atmosphere)
            self._fast[name] = encode_fast(*fast_description(atmosphere, profile, name))
        return self._fast[name]

    def tables(self, request: TableRequest, client: str = "") -> bytes:
        """The encoded GPU tables of `request` (`gpu_tables.encode`), computed unless in
        memory. Raises SupersededError when a newer request of the same `client` cancels it,
        BusyError when too many wait (module docstring)."""
        with self._state:
            if request in self._messages:
                self._messages.move_to_end(request)
                return self._messages[request]
            if self._waiting >= MAX_WAITING + 1:
                raise BusyError(f"{self._waiting} table requests are already waiting")
            self._generation += 1
            generation = self._generation
            self._latest[client] = generation
            self._waiting += 1
        try:
            with self._lock:
                if self._latest.get(client) != generation:
                    raise SupersededError("a newer table request arrived")
                message = self._compute(request, client, generation)
        finally:
            with self._state:
                self._waiting -= 1
                if self._latest.get(client) == generation:
                    del self._latest[client]
        with self._state:
            self._messages[request] = message
            while len(self._messages) > MEMORY_ENTRIES:
                self._messages.popitem(last=False)
        return message

    def spectral_tables(self, request: TableRequest,
                        progress: Callable[[int, int, str], None] | None = None
                        ) -> tuple[Atmosphere, OpticalProfile, AtmosphereTables]:
        """The atmosphere, optical profile and spectral tables of `request` (the full ones
        through the table cache); what the viewer's tables are made from, and what the CPU
        renderer needs to draw the same picture."""
        atmosphere = self._atmosphere_of(request)
        n_wavelengths, size = QUALITIES[request.quality]
        with cache_directory_override(self.directory):
            profile = atmosphere.optical_profile(wavelength_grid(n_wavelengths))
        resolution = TableResolution() if size == 1.0 else TableResolution().scaled(size)
        cache = self.cache if request.quality == "full" else None
        tables = cached_tables(profile, resolution, atmosphere.scattering_orders, cache=cache,
                               progress=progress, log=self._log)
        return atmosphere, profile, tables

    def _compute(self, request: TableRequest, client: str, generation: int) -> bytes:
        label = f"{request.atmosphere} ({request.quality})"

        def progress(done: int, total: int, stage: str) -> None:
            self.progress = {"busy": True, "stage": stage, "done": int(done),
                             "total": int(total), "label": label}
            if self._latest.get(client) != generation:
                raise SupersededError("a newer table request arrived")

        self.progress = {"busy": True, "stage": "starting", "done": 0, "total": 1,
                         "label": label}
        try:
            atmosphere, profile, tables = self.spectral_tables(request, progress)
            return encode(gpu_tables(tables, profile, atmosphere.planet.star, label))
        finally:
            self.progress = {"busy": False, "stage": "done", "done": 1, "total": 1,
                             "label": label}
