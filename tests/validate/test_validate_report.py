"""The report writer and the suite: Markdown and JSON from case results, written atomically;
the case registry and its errors."""

from __future__ import annotations

import json

import pytest

from skyscatter.errors import InputError
from skyscatter.validate import suite
from skyscatter.validate.report import (
    CaseResult,
    Check,
    Figure,
    Table,
    ValidationSettings,
    atomic_write_text,
    write_report,
)


def _result(key: str, value: float) -> CaseResult:
    return CaseResult(key, f"Case {key}", "what was compared",
                      tables=[Table("caption", ["a", "b"], [["1", "2"]])],
                      figures=[Figure(f"{key}.png", "one message")],
                      metrics={"value": value},
                      checks=[Check(f"{key} error", value, 2.0, "%")], seconds=1.5)


def test_report_and_summary_say_what_passed_and_what_failed(tmp_path):
    settings = ValidationSettings(tmp_path)
    report, summary = write_report([_result("good", 1.0), _result("bad", 3.0)], settings, 3.0)
    text = report.read_text()
    assert "result: **FAILED**" in text
    assert "- FAILED: bad error: 3% > limit 2%" in text
    assert "| a | b |" in text and "![one message](good.png)" in text
    data = json.loads(summary.read_text())
    assert data["passed"] is False
    assert [c["passed"] for c in data["cases"]] == [True, False]
    assert data["cases"][1]["checks"][0] == {"name": "bad error", "value": 3.0, "limit": 2.0,
                                             "unit": "%", "passed": False}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.md", "summary.json"]


def test_an_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "report.md"
    target.write_text("old report")

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("os.replace", broken)
    with pytest.raises(InputError, match="cannot write .*report.md: disk full"):
        atomic_write_text(target, "new report")
    assert target.read_text() == "old report"
    assert [p.name for p in tmp_path.iterdir()] == ["report.md"]  # no temporary file left


def test_unknown_cases_and_missing_packages_are_input_errors(monkeypatch):
    with pytest.raises(InputError, match="unknown validation case 'cie'; choose from"):
        suite.selected_cases(["cie"])
    assert suite.selected_cases(["spectrl2", "disort"]) == ["disort", "spectrl2"]
    monkeypatch.setattr(suite.importlib.util, "find_spec",
                        lambda name: None if name == "pvlib" else object())
    with pytest.raises(InputError, match=r"needs pvlib: pip install 'skyscatter\[validate\]'"):
        suite.check_dependencies()
