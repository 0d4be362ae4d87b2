"""The table cache: round trip, every bad file detected (never silently used), the size limit
with least-recently-used eviction, and the temporaries of killed writers swept."""

from __future__ import annotations

import dataclasses
import io
import os
import signal
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest
from transport_cases import exponential_earth

from skyscatter.disk_cache import DEFAULT_MAX_BYTES, MAX_BYTES_VARIABLE
from skyscatter.errors import InputError
from skyscatter.output_files import temporary_path
from skyscatter.transport.cache import TableCache, profile_fingerprint

METADATA = {"fingerprint": "abc", "resolution": [32, 128, 32, 8], "version": "0.1.0",
            "wavelengths_nm": [440.0, 550.0]}


@pytest.fixture
def cache(tmp_path):
    return TableCache(tmp_path / "cache")


def arrays():
    rng = np.random.default_rng(3)
    return {"scattering": rng.random((4, 5, 2)).astype(np.float32), "irradiance": rng.random(7)}


def test_round_trip_is_bit_exact(cache):
    cache.store("earth", arrays(), METADATA)
    loaded, status = cache.load("earth", METADATA)
    assert status == "ok"
    for name, array in arrays().items():
        np.testing.assert_array_equal(loaded[name], array)
        assert loaded[name].dtype == array.dtype


def test_missing_entry_is_reported(cache):
    assert cache.load("nothing", METADATA) == (None, "not cached yet")


def test_other_inputs_are_detected_and_named(cache):
    cache.store("earth", arrays(), METADATA)
    other = dict(METADATA, version="0.2.0")
    loaded, status = cache.load("earth", other)
    assert loaded is None and "version" in status


def test_truncated_file_is_detected(cache):
    path = cache.store("earth", arrays(), METADATA)
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    loaded, status = cache.load("earth", METADATA)
    assert loaded is None and "unreadable" in status


def test_changed_array_in_a_valid_file_is_caught_by_the_checksum(cache):
    path = cache.store("earth", arrays(), METADATA)
    data = path.read_bytes()
    # Rewrite one array inside a valid zip so only the checksum can tell.
    with np.load(path) as stored:
        payload = {name: stored[name] for name in stored.files}
    payload["irradiance"] = payload["irradiance"] + 1e-12
    np.savez(path, **payload)
    assert data != path.read_bytes()
    loaded, status = cache.load("earth", METADATA)
    assert loaded is None and "checksum" in status


def test_garbage_file_is_detected(cache):
    cache.directory.mkdir(parents=True)
    cache.path("earth").write_text("not a cache file")
    loaded, status = cache.load("earth", METADATA)
    assert loaded is None and "unreadable" in status


def test_failed_write_keeps_the_old_entry_and_leaves_no_temporary(cache, monkeypatch):
    cache.store("earth", arrays(), METADATA)

    def broken_savez(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", broken_savez)
    with pytest.raises(OSError):
        cache.store("earth", {"x": np.zeros(3)}, METADATA)
    monkeypatch.undo()
    loaded, status = cache.load("earth", METADATA)
    assert status == "ok" and set(loaded) == set(arrays())
    assert [p.name for p in cache.directory.iterdir()] == ["earth.npz"]


def test_unsafe_keys_are_refused(cache):
    for key in ("../escape", "", ".hidden", "a/b"):
        with pytest.raises(InputError):
            cache.path(key)


def test_fingerprint_changes_with_the_atmosphere_and_not_otherwise():
    profile = exponential_earth()
    same = exponential_earth()
    assert profile_fingerprint(profile) == profile_fingerprint(same)
    hazier = dataclasses.replace(profile, density=profile.density * np.array([[1.0], [2.0]]))
    assert profile_fingerprint(hazier) != profile_fingerprint(profile)
    brighter = dataclasses.replace(profile, ground_albedo=profile.ground_albedo + 0.1)
    assert profile_fingerprint(brighter) != profile_fingerprint(profile)


# --- size limit and least-recently-used eviction ---------------------------------------------

def _entry_bytes(tmp_path) -> int:
    probe = TableCache(tmp_path / "probe")
    return probe.store("probe", arrays(), METADATA).stat().st_size


def _age(cache, key, seconds_ago):
    when = time.time() - seconds_ago
    os.utime(cache.path(key), (when, when))


def test_least_recently_used_entries_go_first_and_never_the_new_one(tmp_path):
    size = _entry_bytes(tmp_path)
    cache = TableCache(tmp_path / "lru", max_bytes=3 * size)  # room for three entries
    for age, key in ((300, "a"), (200, "b"), (100, "c")):
        cache.store(key, arrays(), METADATA)
        _age(cache, key, age)
    assert cache.load("a", METADATA)[1] == "ok"  # a is now the most recently used
    cache.store("d", arrays(), METADATA)
    assert sorted(p.stem for p in cache.directory.glob("*.npz")) == ["a", "c", "d"]
    # A limit below one entry keeps only the entry just written
    small = TableCache(cache.directory, max_bytes=size // 2)
    small.store("e", arrays(), METADATA)
    assert [p.stem for p in cache.directory.glob("*.npz")] == ["e"]


def test_eviction_counts_and_removes_only_cache_entries(tmp_path):
    cache = TableCache(tmp_path / "mixed", max_bytes=0)
    cache.directory.mkdir()
    (cache.directory / "notes.txt").write_text("mine")
    np.savez(cache.directory / "my-own.npz", x=np.zeros(10))  # an npz that is not an entry
    cache.store("a", arrays(), METADATA)
    cache.store("b", arrays(), METADATA)
    assert sorted(p.name for p in cache.directory.iterdir()) == ["b.npz", "my-own.npz",
                                                                 "notes.txt"]
    assert [entry.key for entry in cache.entries()] == ["b"]


def test_subfolders_count_towards_the_limit(tmp_path):
    # The Mie tables live in <cache>/mie/: the root's limit covers them.
    size = _entry_bytes(tmp_path)
    root = TableCache(tmp_path / "root", max_bytes=2 * size)
    mie = TableCache(root.directory / "mie", max_bytes=10 * size)
    mie.store("m1", arrays(), METADATA)
    _age(mie, "m1", 100)
    mie.store("m2", arrays(), METADATA)
    root.store("t", arrays(), METADATA)
    assert sorted(e.key for e in root.entries()) == ["m2", "t"]
    assert sum(e.size_bytes for e in root.entries()) <= root.max_bytes


def test_clear_older_than_removes_only_old_entries(tmp_path):
    cache = TableCache(tmp_path / "clear")
    cache.store("old", arrays(), METADATA)
    cache.store("new", arrays(), METADATA)
    _age(cache, "old", 3 * 86400)
    assert [e.key for e in cache.clear(older_than_s=2 * 86400)] == ["old"]
    assert [e.key for e in cache.entries()] == ["new"]
    assert [e.key for e in cache.clear()] == ["new"] and cache.entries() == []


def test_the_limit_comes_from_the_environment_and_bad_values_are_named(monkeypatch, tmp_path):
    monkeypatch.setenv(MAX_BYTES_VARIABLE, "500M")
    assert TableCache(tmp_path).max_bytes == 500 * 1024**2
    monkeypatch.setenv(MAX_BYTES_VARIABLE, "1073741824")
    assert TableCache(tmp_path).max_bytes == 2**30
    monkeypatch.delenv(MAX_BYTES_VARIABLE)
    assert TableCache(tmp_path).max_bytes == DEFAULT_MAX_BYTES == 2 * 2**30
    for bad in ("lots", "-1", "nan", "1e400", "9" * 30):
        monkeypatch.setenv(MAX_BYTES_VARIABLE, bad)
        with pytest.raises(InputError, match=MAX_BYTES_VARIABLE):
            TableCache(tmp_path)
    with pytest.raises(InputError, match="max_bytes"):
        TableCache(tmp_path, max_bytes=-1)


# --- robustness -------------------------------------------------------------------------------

def test_a_folder_in_place_of_an_entry_is_reported_and_replaced_when_empty(cache):
    cache.path("earth").mkdir(parents=True)
    assert cache.load("earth", METADATA) == (None, "not a file (a folder or device is in its "
                                                   "place)")
    cache.store("earth", arrays(), METADATA)
    assert cache.load("earth", METADATA)[1] == "ok"
    cache.path("full").mkdir()
    (cache.path("full") / "something").write_text("x")
    with pytest.raises(InputError, match="is a folder with files in it"):
        cache.store("full", arrays(), METADATA)


def test_a_header_declaring_7_tib_is_corrupt_not_a_memory_error(cache):
    path = cache.store("earth", arrays(), METADATA)
    with zipfile.ZipFile(path) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    header = io.BytesIO()
    np.lib.format.write_array_header_2_0(header, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (2**40 - 1, 7)})
    members["irradiance.npy"] = header.getvalue() + b"\0" * 56
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    loaded, status = cache.load("earth", METADATA)
    assert loaded is None and "corrupt" in status and "declares" in status
    cache.store("earth", arrays(), METADATA)  # repaired by the next store
    assert cache.load("earth", METADATA)[1] == "ok"


def test_a_file_as_cache_directory_is_refused_and_a_folder_is_writable(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        TableCache(tmp_path / "file").check_writable()
    assert TableCache(tmp_path / "new" / "folder").check_writable() is None
    assert list((tmp_path / "new" / "folder").iterdir()) == []  # the probe is gone


# --- temporaries ------------------------------------------------------------------------------

def test_temporaries_of_dead_writers_and_day_old_ones_are_swept_by_the_next_load(cache):
    cache.store("earth", arrays(), METADATA)
    mine = temporary_path(cache.path("earth"))
    assert mine.parent == cache.directory and mine.name.startswith(".earth.npz.")
    assert f".{os.getpid()}." in mine.name and mine.name.endswith(".tmp")
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    orphan = cache.directory / f".earth.npz.{int(dead.stdout)}.0123abcd.tmp"
    old_style = cache.directory / ".earth.k2j4h5g6.npz.tmp"  # mkstemp's, before pids
    fresh_old_style = cache.directory / ".earth.a1b2c3d4.npz.tmp"
    for path in (mine, orphan, old_style, fresh_old_style, cache.directory / "keep.tmp"):
        path.write_bytes(b"partial")
    day_old = time.time() - 2 * 86400
    os.utime(old_style, (day_old, day_old))
    assert cache.load("earth", METADATA)[1] == "ok"
    assert sorted(p.name for p in cache.directory.iterdir()) == sorted(
        [mine.name, fresh_old_style.name, "earth.npz", "keep.tmp"])


_SLOW_WRITER = """
import sys, numpy as np
from skyscatter.disk_cache import TableCache
real_savez = np.savez
def slow_savez(stream, **payload):
    stream.write(b"PK partial " * 100_000)
    stream.flush()
    print("writing", flush=True)
    sys.stdin.readline()  # until killed
    real_savez(stream, **payload)
np.savez = slow_savez
TableCache(sys.argv[1]).store("earth", {"x": np.ones(1000)}, {"run": 2})
"""


@pytest.mark.parametrize("signal_number", [signal.SIGKILL, signal.SIGTERM])
def test_a_writer_killed_mid_write_leaves_the_old_entry_and_no_temporary(cache, signal_number):
    cache.store("earth", arrays(), METADATA)
    writer = subprocess.Popen([sys.executable, "-c", _SLOW_WRITER, str(cache.directory)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert writer.stdout.readline().strip() == "writing"
        (temporary,) = cache.directory.glob(".earth.npz.*.tmp")
        assert f".{writer.pid}." in temporary.name and temporary.stat().st_size > 1e6
        writer.send_signal(signal_number)
        writer.wait(timeout=30)
    finally:
        writer.kill()
        writer.wait()
    assert temporary.exists()  # what the kill leaves behind ...
    loaded, status = cache.load("earth", METADATA)  # ... the next load sweeps
    assert status == "ok" and set(loaded) == set(arrays())
    assert [p.name for p in cache.directory.iterdir()] == ["earth.npz"]
