"""`skyscatter cache list | size | clear` against the files it finds on disk."""

from __future__ import annotations

import json
import os
import time

import numpy as np
import pytest

from skyscatter.cli import main
from skyscatter.disk_cache import TableCache

TABLE_METADATA = {"orders": 4, "constituents": ["rayleigh", "mie"],
                  "wavelengths_nm": [400.0, 550.0, 700.0]}


@pytest.fixture
def cache(tmp_path):
    cache = TableCache(tmp_path / "cache")
    cache.store("tables-a", {"x": np.zeros(1000)}, TABLE_METADATA)
    TableCache(cache.directory / "mie").store("m", {"y": np.zeros(10)},
                                              {"distribution": "lognormal"})
    old = time.time() - 10 * 86400
    os.utime(cache.path("tables-a"), (old, old))
    (cache.directory / "notes.txt").write_text("not an entry")
    return cache


def test_list_as_json_names_each_entry_and_what_it_holds(cache, capsys):
    assert main(["cache", "list", "--format", "json", "--cache-dir", str(cache.directory)]) == 0
    listing = json.loads(capsys.readouterr().out)
    assert listing["directory"] == str(cache.directory)
    tables, mie = listing["entries"]  # least recently used first
    assert tables["key"] == "tables-a" and tables["what"] == "tables" and tables["orders"] == 4
    assert tables["constituents"] == ["rayleigh", "mie"]
    assert tables["wavelengths_nm"] == {"count": 3, "first": 400.0, "last": 700.0}
    assert tables["size_bytes"] == cache.path("tables-a").stat().st_size
    assert mie["folder"] == "mie" and mie["what"] == "Mie tables"


def test_text_list_size_and_clear_older_than_honour_the_environment(cache, capsys,
                                                                    monkeypatch):
    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(cache.directory))
    assert main(["cache", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 2 and "tables of rayleigh+mie, 4 orders, 3 wavelengths 400-700 nm" \
        in lines[0] and lines[1].startswith("mie/m ")
    assert main(["cache", "size"]) == 0
    assert "in 2 entries" in capsys.readouterr().out
    assert main(["cache", "clear", "--older-than", "5"]) == 0
    assert capsys.readouterr().out.startswith("removed 1 entries")
    assert [entry.key for entry in cache.entries()] == ["m"]
    assert main(["cache", "clear"]) == 0
    assert cache.entries() == [] and (cache.directory / "notes.txt").exists()


@pytest.mark.parametrize("argv", [["cache", "size", "--older-than", "2"],
                                  ["cache", "clear", "--older-than", "-1"],
                                  ["cache", "clear", "--older-than", "nan"],
                                  ["cache", "shrink"]])
def test_bad_arguments_exit_2_with_one_message(argv, capsys, tmp_path):
    try:
        code = main([*argv, "--cache-dir", str(tmp_path)])
    except SystemExit as exit_:  # argparse's own refusals
        code = exit_.code
    assert code == 2
    error = capsys.readouterr().err
    assert "Traceback" not in error and ("older-than" in error or "shrink" in error)
