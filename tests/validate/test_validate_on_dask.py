"""`skyscatter validate --workers N`: the cases run at once on a local Dask cluster give the
serial run's results (every metric and check but the timings) and the same figures."""

from __future__ import annotations

import json

import pytest

from skyscatter.cli import main

pytest.importorskip("distributed")

CASES = ["validate", "--quick", "--cases", "optical-depth,spectrl2", "-q"]
TIMINGS = {"seconds"}  # wall times differ from run to run; nothing else may


def _without_timings(summary: dict) -> dict:
    summary = {key: value for key, value in summary.items() if key not in TIMINGS}
    summary["cases"] = [{key: value for key, value in case.items() if key not in TIMINGS}
                        for case in summary["cases"]]
    return summary


@pytest.mark.slow  # two quick cases twice, and a cluster: about a minute on 2 cores
def test_cases_on_two_workers_give_the_serial_results(tmp_path):
    assert main([*CASES, "--output", str(tmp_path / "serial")]) == 0
    assert main([*CASES, "--output", str(tmp_path / "dask"), "--workers", "2"]) == 0
    serial = json.loads((tmp_path / "serial" / "summary.json").read_text())
    parallel = json.loads((tmp_path / "dask" / "summary.json").read_text())
    assert [case["key"] for case in parallel["cases"]] == ["optical-depth", "spectrl2"]
    assert _without_timings(parallel) == _without_timings(serial)
    figures = [name for case in serial["cases"] for name in case["figures"]]
    assert len(figures) >= 3
    for name in figures:
        assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "serial" / name).read_bytes()
