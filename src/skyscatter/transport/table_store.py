"""Precomputed tables on disk: load them from the cache when they match, else compute and store.

An entry is keyed by a hash of its metadata: the atmosphere's fingerprint (a hash of every
number of its optical profile, so of everything in the config that changes the tables), the
table resolution, the orders, mu_s_min, the wavelengths, the package version and a hash of the
code the precomputation runs (`code_fingerprint`: the functions `precompute_tables` reaches,
not whole files, so an edit to a lookup keeps the tables and one to a precomputation kernel
replaces them). A file that is corrupt, truncated or made from other inputs is reported and
recomputed, never used (`transport/cache.py`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from skyscatter import __version__
from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS, OpticalProfile
from skyscatter.errors import InputError
from skyscatter.jit_cache import kernel_cache_folder
from skyscatter.transport.cache import TableCache, profile_fingerprint
from skyscatter.transport.code_fingerprint import code_fingerprint
from skyscatter.transport.table_packing import PackedTable, round_and_pack, unpack
from skyscatter.transport.table_parameterisation import COS_SUN_ZENITH_MIN
from skyscatter.transport.tables import (
    AtmosphereTables,
    TableResolution,
    precompute_tables,
    thick_layer_resolution,
)

__all__ = ["cached_tables", "table_metadata", "tables_from_arrays", "tables_to_arrays"]

# bump when the arrays stored change meaning (2: truncated peaks, the orders' tail, the aureole;
# 3: the radius axis's warp; 4: the scattering table packed, `table_packing`; 5: the peaks'
# blur of light scattered once in the smooth part, `aureole_blur`; 6: the mu_s axis's share
# uniform in the sun's angle stored, `sun_angle_share`; 7: the clipped constituents' peak
# corrections as tables of their own, `peak_correction_phase`)
TABLE_FORMAT = 7
_ARRAYS = ("wavelengths_nm", "transmittance", "irradiance", "phase", "peak_correction_phase",
           "order_mean_radiance",
           "order_zenith_radiance", "tail_share", "peak_transmittance", "aureole_shape",
           "aureole_blur", "aureole_limits", "radius_warp")
_MAX_DEFLATE_RATIO = 1100
# Where the precomputation starts: the key covers the code it reaches (`code_fingerprint`).
_PRECOMPUTATION = ("skyscatter.transport.tables", "precompute_tables")


def _code_fingerprint(profile: OpticalProfile, memo_folder: Path | None) -> str:
    """Fingerprint of the code `precompute_tables` runs for `profile`: its call graph, plus
    the classes of the profile's phase functions (called through the objects, so found by
    type, not by name); remembered in `memo_folder` and beside the compiled kernels, where
    `skyscatter compile` leaves the fingerprints of its commands' atmospheres at install time
    (`code_fingerprint`)."""
    phases = sorted({(type(phase).__module__, type(phase).__name__)
                     for phase in profile.phases if phase is not None})
    folders = (() if memo_folder is None else (Path(memo_folder),)) + (kernel_cache_folder(),)
    return code_fingerprint((_PRECOMPUTATION, *phases), folders)


def table_metadata(profile: OpticalProfile, resolution: TableResolution, orders: int,
                   min_cos_sun_zenith: float, memo_folder: Path | None = None
                   ) -> dict[str, Any]:
    """What an entry was made from; two entries with equal metadata hold equal tables. The
    code's fingerprint is remembered in `memo_folder` (the cache's folder)."""
    return {"format": TABLE_FORMAT, "version": __version__,
            "code": _code_fingerprint(profile, memo_folder),
            "atmosphere_fingerprint": profile_fingerprint(profile),
            "constituents": list(profile.names),
            "resolution": dataclasses.asdict(resolution), "orders": int(orders),
            "min_cos_sun_zenith": float(min_cos_sun_zenith),
            "wavelengths_nm": [float(w) for w in profile.wavelengths_nm]}


def _key(metadata: dict[str, Any]) -> str:
    text = json.dumps(metadata, sort_keys=True)
    return "tables-" + hashlib.sha256(text.encode()).hexdigest()[:24]


def tables_to_arrays(tables: AtmosphereTables) -> dict[str, np.ndarray]:
    """The arrays of `tables` plus its scalars, for `TableCache.store`; the scattering table
    packed (`table_packing`), and rounded in place to the values the packed form holds."""
    arrays = {name: getattr(tables, name) for name in _ARRAYS}
    arrays.update(_packed_arrays(round_and_pack(tables.scattering)))
    arrays["radii_m"] = np.array([tables.bottom_radius_m, tables.top_radius_m])
    arrays["orders_computed"] = np.array(tables.orders_computed, dtype=np.int64)
    arrays["sun_angle_share"] = np.array(tables.sun_angle_share)
    arrays["scattering_constituents"] = np.array(tables.scattering_constituents, dtype=np.int64)
    arrays["scattering_names"] = np.array(tables.scattering_names, dtype=np.str_)
    arrays["peak_correction_names"] = np.array(tables.peak_correction_names, dtype=np.str_)
    return arrays


def _packed_arrays(packed: PackedTable) -> dict[str, np.ndarray]:
    slices = packed.high_bytes + packed.low_bytes
    return {"scattering_shape": np.array(packed.shape, dtype=np.int64),
            "scattering_log_range": np.array([packed.log_low, packed.log_high]),
            "scattering_slice_bytes": np.array([len(data) for data in slices], dtype=np.int64),
            "scattering_packed": np.frombuffer(b"".join(slices), dtype=np.uint8)}


def _unpacked_scattering(arrays: dict[str, np.ndarray]) -> np.ndarray:
    """The scattering table of `_packed_arrays`; ValueError when the arrays do not fit."""
    shape = tuple(int(n) for n in arrays["scattering_shape"])
    sizes = arrays["scattering_slice_bytes"]
    data = arrays["scattering_packed"].tobytes()
    if len(shape) != 6 or min(shape) < 1 or sizes.ndim != 1 or sizes.size != 2 * shape[0] or (
            np.any(sizes < 0) or int(sizes.sum()) != len(data)):
        raise ValueError("the packed scattering table's slices do not add up to its bytes")
    # deflate shrinks by at most 1032:1 (RFC 1951's longest match per 2 bits), so a shape
    # beyond that is damaged: refused before it is allocated
    if 2 * math.prod(shape) > _MAX_DEFLATE_RATIO * len(data):
        raise ValueError(f"the packed scattering table cannot hold its shape {shape}")
    ends = np.cumsum(sizes)
    slices = tuple(data[end - size:end] for end, size in zip(ends, sizes, strict=True))
    log_low, log_high = (float(v) for v in arrays["scattering_log_range"])
    return unpack(PackedTable(shape, log_low, log_high, slices[:shape[0]], slices[shape[0]:]))


def tables_from_arrays(arrays: dict[str, np.ndarray],
                       metadata: dict[str, Any]) -> AtmosphereTables:
    """Inverse of `tables_to_arrays` (with the metadata the entry was checked against)."""
    scattering = _unpacked_scattering(arrays)
    bottom, top = (float(v) for v in arrays["radii_m"])
    return AtmosphereTables(
        bottom_radius_m=bottom, top_radius_m=top,
        min_cos_sun_zenith=float(metadata["min_cos_sun_zenith"]),
        # as `precompute_tables` widened it: the thick layer's quadrature, and the view-sun
        # slices (`forward_scattering_resolution`) that the table's shape holds
        resolution=dataclasses.replace(
            thick_layer_resolution(TableResolution(**metadata["resolution"]),
                                   arrays["radius_warp"]),
            scattering_nu=int(scattering.shape[3])),
        orders=int(metadata["orders"]),
        scattering_names=tuple(str(n) for n in arrays["scattering_names"]),
        scattering_constituents=tuple(int(c) for c in arrays["scattering_constituents"]),
        peak_correction_names=tuple(str(n) for n in arrays["peak_correction_names"]),
        orders_computed=int(arrays["orders_computed"]), scattering=scattering,
        sun_angle_share=float(arrays["sun_angle_share"]),
        **{name: arrays[name] for name in _ARRAYS})


def cached_tables(profile: OpticalProfile, resolution: TableResolution | None = None,
                  orders: int = DEFAULT_SCATTERING_ORDERS, *,
                  min_cos_sun_zenith: float = COS_SUN_ZENITH_MIN,
                  cache: TableCache | None = None, force: bool = False,
                  progress: Callable[[int, int, str], None] | None = None,
                  log: Callable[[str], None] | None = None) -> AtmosphereTables:
    """The tables of `profile`: from `cache` when a valid entry exists (and not `force`),
    otherwise precomputed (`precompute_tables`) and stored. `log` gets one line saying which
    happened and why. Without a cache the tables are computed and kept in memory only.

    Whether the cache can be written is checked before the precomputation: a cache directory
    that is a file raises InputError up front; one that cannot be written (permissions, a
    read-only file system) is reported through `log` and the tables are computed and returned
    without being stored, as they are when storing fails afterwards (a full disk)."""
    resolution = resolution or TableResolution()
    say = log or (lambda message: None)
    if cache is None:
        return precompute_tables(profile, resolution, orders,
                                 min_cos_sun_zenith=min_cos_sun_zenith, progress=progress)
    # Before the work: a file as cache dir is refused, an unwritable one reported
    unwritable = cache.check_writable()
    metadata = table_metadata(profile, resolution, orders, min_cos_sun_zenith,
                              cache.directory)
    key = _key(metadata)
    path = cache.path(key)
    unwritable = unwritable or cache.entry_problem(key)
    if force:
        reason = "recomputing as asked"
    else:
        arrays, reason = cache.load(key, metadata)
        if arrays is not None:
            try:
                tables = tables_from_arrays(arrays, metadata)
            except (KeyError, ValueError, TypeError, InputError) as error:
                reason = f"incomplete cache file ({type(error).__name__}: {error})"
            else:
                say(f"tables: using {path}")
                return tables
    where = (f"will be stored in {path}" if unwritable is None
             else f"not stored: {unwritable}")
    say(f"tables: precomputing {orders} orders for {profile.n_wavelengths} wavelengths "
        f"({reason}; {where})")
    tables = precompute_tables(profile, resolution, orders,
                               min_cos_sun_zenith=min_cos_sun_zenith, progress=progress)
    if tables.orders_computed < orders:
        say(f"tables: {tables.orders_computed} orders iterated, the orders beyond added as "
            "their geometric series or extrapolated limit (up to "
            f"{100 * float(tables.tail_share.max()):.0f} % of the orders >= 2)")
    if unwritable is None:
        try:
            cache.store(key, tables_to_arrays(tables), metadata)
        except (OSError, InputError) as error:  # e.g. the disk filled up meanwhile
            say(f"tables: not stored in {path}: {error}")
    return tables
