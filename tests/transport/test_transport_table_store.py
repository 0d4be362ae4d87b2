"""Tables through the cache: a stored entry comes back bit for bit; anything that changes the
tables (orders, resolution, wavelengths, atmosphere) makes a new entry; a damaged entry is
reported and recomputed, never used."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from transport_cases import SMALL, exponential_earth

from skyscatter.transport.cache import TableCache
from skyscatter.transport.table_store import cached_tables

ARRAYS = ("transmittance", "scattering", "irradiance", "phase", "order_mean_radiance")


@pytest.fixture
def cache(tmp_path):
    return TableCache(tmp_path / "cache")


def _tables(profile, cache, orders=2, resolution=SMALL):
    messages = []
    tables = cached_tables(profile, resolution, orders, cache=cache, log=messages.append)
    return tables, messages[0]


def test_second_call_loads_the_stored_tables_bit_for_bit(cache):
    profile = exponential_earth()
    first, message = _tables(profile, cache)
    assert "precomputing" in message and "not cached yet" in message
    second, message = _tables(profile, cache)
    assert "using" in message
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(second, name), getattr(first, name))
    assert second.resolution == first.resolution and second.orders == first.orders
    assert second.scattering_names == first.scattering_names
    assert len(list(cache.directory.glob("*.npz"))) == 1


@pytest.mark.parametrize("change", ["orders", "resolution", "albedo", "wavelengths"])
def test_anything_that_changes_the_tables_makes_a_new_entry(cache, change):
    profile = exponential_earth()
    _tables(profile, cache)
    orders, resolution = 2, SMALL
    if change == "orders":
        orders = 3
    elif change == "resolution":
        resolution = dataclasses.replace(SMALL, scattering_nu=6)
    elif change == "albedo":
        profile = dataclasses.replace(profile, ground_albedo=profile.ground_albedo + 0.1)
    else:
        profile = dataclasses.replace(profile, wavelengths_nm=profile.wavelengths_nm + 1.0)
    _, message = _tables(profile, cache, orders, resolution)
    assert "precomputing" in message
    assert len(list(cache.directory.glob("*.npz"))) == 2


@pytest.mark.parametrize("damage", ["truncate", "flip"])
def test_a_damaged_entry_is_recomputed_and_replaced(cache, damage):
    profile = exponential_earth()
    reference, _ = _tables(profile, cache)
    (path,) = cache.directory.glob("*.npz")
    data = path.read_bytes()
    if damage == "truncate":
        path.write_bytes(data[: len(data) // 2])
    else:  # one bit in the middle of the scattering table
        middle = len(data) // 2
        path.write_bytes(data[:middle] + bytes([data[middle] ^ 0x10]) + data[middle + 1:])
    recomputed, message = _tables(profile, cache)
    assert "precomputing" in message
    assert ("unreadable" in message) or ("checksum" in message)
    np.testing.assert_array_equal(recomputed.scattering, reference.scattering)
    _, message = _tables(profile, cache)
    assert "using" in message  # the damaged file was replaced by a good one

