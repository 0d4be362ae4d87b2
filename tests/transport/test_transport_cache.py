"""The table cache: round trip, and every bad file detected (never silently used)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from transport_cases import exponential_earth

from skyscatter.errors import InputError
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
