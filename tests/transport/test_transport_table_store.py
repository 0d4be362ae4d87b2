"""Tables through the cache: a stored entry comes back bit for bit; anything that changes the
tables (orders, resolution, wavelengths, atmosphere) makes a new entry; a damaged entry is
reported and recomputed, never used."""

from __future__ import annotations

import dataclasses
import io
import os
import zipfile

import numpy as np
import pytest
from transport_cases import SMALL, exponential_earth, homogeneous_shell

from skyscatter.errors import InputError
from skyscatter.optics.phase import HenyeyGreensteinPhase
from skyscatter.transport import table_store
from skyscatter.transport.cache import TableCache
from skyscatter.transport.table_packing import LOG_FLOOR
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import precompute_tables

ARRAYS = ("transmittance", "scattering", "irradiance", "phase", "order_mean_radiance")


@pytest.fixture
def cache(tmp_path):
    return TableCache(tmp_path / "cache")


def declare_huge_array(path, member, shape):
    """Rewrite the .npy header of `member` in the npz at `path` to declare `shape` (float32),
    keeping its few real bytes: the file stays a valid zip of the same size."""
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    stream = io.BytesIO(members[member])
    np.lib.format.read_magic(stream)
    np.lib.format.read_array_header_1_0(stream)
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f4", "fortran_order": False,
                                                  "shape": shape})
    members[member] = header.getvalue() + stream.read()
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)


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


def test_the_stored_tables_are_the_computed_ones_within_half_a_code_step(cache):
    # the scattering table is stored as 16-bit logarithmic codes (transport/table_packing.py):
    # each value within ln(1e30) / (2 * 65534) = 0.053 % of the exact table's
    profile = exponential_earth()
    exact = precompute_tables(profile, SMALL, 2)
    stored, _ = _tables(profile, cache)
    above = exact.scattering >= exact.scattering.max() * LOG_FLOOR
    error = np.abs(stored.scattering[above] / exact.scattering[above].astype(float) - 1.0)
    assert error.max() <= np.expm1(np.log(1.0 / LOG_FLOOR) / (2 * 65534)) + 1e-7
    np.testing.assert_array_equal(stored.transmittance, exact.transmittance)


def test_a_packed_shape_its_bytes_cannot_hold_is_refused_before_it_is_allocated(cache):
    profile = exponential_earth()
    tables, _ = _tables(profile, cache)
    arrays = table_store.tables_to_arrays(tables)
    arrays["scattering_shape"] = np.array([tables.scattering.shape[0], 2**20, 2**20, 2**20, 3,
                                           16])
    with pytest.raises(ValueError, match="cannot hold its shape"):
        table_store.tables_from_arrays(arrays, {"min_cos_sun_zenith": -0.2, "orders": 2,
                                                "resolution": dataclasses.asdict(SMALL)})


def test_a_stored_entry_reports_the_resolution_its_tables_were_computed_at(cache):
    # HG particles of g 0.65 and optical depth 0.5 get 16 view-sun slices
    # (tables.forward_scattering_resolution); the entry read back says so too
    shell = dataclasses.replace(homogeneous_shell(0.5 / 10_000.0),
                                phases=(HenyeyGreensteinPhase(0.65),))
    first, _ = _tables(shell, cache)
    second, message = _tables(shell, cache)
    assert "using" in message
    assert first.resolution.scattering_nu == second.resolution.scattering_nu == 16
    assert second.resolution == first.resolution


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


@pytest.mark.parametrize("damage", ["truncate", "flip", "huge header", "folder"])
def test_a_damaged_entry_is_recomputed_and_replaced(cache, damage):
    profile = exponential_earth()
    reference, _ = _tables(profile, cache)
    (path,) = cache.directory.glob("*.npz")
    data = path.read_bytes()
    if damage == "truncate":
        path.write_bytes(data[: len(data) // 2])
    elif damage == "flip":  # one bit in the middle of the scattering table
        middle = len(data) // 2
        path.write_bytes(data[:middle] + bytes([data[middle] ^ 0x10]) + data[middle + 1:])
    elif damage == "huge header":  # the scattering member declares 7 TiB
        declare_huge_array(path, "scattering_packed.npy", (7 * 2**40 // 4,))
    else:  # an (empty) folder in the entry's place
        path.unlink()
        path.mkdir()
    recomputed, message = _tables(profile, cache)
    assert "precomputing" in message
    assert any(word in message for word in ("unreadable", "checksum", "corrupt", "not a file"))
    np.testing.assert_array_equal(recomputed.scattering, reference.scattering)
    _, message = _tables(profile, cache)
    assert "using" in message  # the damaged file was replaced by a good one



def test_a_file_as_cache_directory_is_refused_before_any_work(tmp_path, monkeypatch):
    # --cache-dir pointing at a file used to throw the finished tables away (106 s for Earth)
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")

    def no_work(*args, **kwargs):
        raise AssertionError("the tables were computed before the cache was checked")

    monkeypatch.setattr(table_store, "precompute_tables", no_work)
    for directory in (blocker, blocker / "below"):
        with pytest.raises(InputError, match="not a directory"):
            cached_tables(exponential_earth(), SMALL, 2, cache=TableCache(directory))


def test_an_unwritable_cache_computes_and_says_the_tables_are_not_stored(cache, monkeypatch):
    # As a read-only folder behaves (root ignores permission bits, so the probe is made to fail)
    def refuse(self):
        return f"cannot write in {self.directory}: Read-only file system"

    monkeypatch.setattr(TableCache, "check_writable", refuse)
    tables, message = _tables(exponential_earth(), cache)
    assert "not stored: cannot write" in message and "Read-only" in message
    assert tables.orders == 2 and not list(cache.directory.glob("*.npz"))


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write into a read-only folder")
def test_a_read_only_cache_folder_is_reported_before_the_work(cache):
    cache.directory.mkdir()
    cache.directory.chmod(0o555)
    try:
        assert "cannot write" in cache.check_writable()
        _, message = _tables(exponential_earth(), cache)
        assert "not stored" in message
    finally:
        cache.directory.chmod(0o755)


def test_a_folder_with_files_in_an_entrys_place_is_reported_before_the_work(cache):
    profile = exponential_earth()
    _tables(profile, cache)
    (path,) = cache.directory.glob("*.npz")
    path.unlink()
    path.mkdir()
    (path / "user-file").write_text("keep me")
    tables, message = _tables(profile, cache)
    assert "precomputing" in message and "not stored" in message and "folder with files" \
        in message
    assert tables.orders == 2 and (path / "user-file").exists()
