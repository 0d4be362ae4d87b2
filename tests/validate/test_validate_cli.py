"""`skyscatter validate` from the command line: the quick suite end to end, the exit codes,
and bad arguments."""

from __future__ import annotations

import json

from skyscatter.cli import main
from skyscatter.validate import optical_depth
from skyscatter.validate.report import CaseResult, Check

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_quick_suite_writes_report_summary_and_plots_and_passes(tmp_path, capsys):
    # The reduced suite of every case (about 1.5-2 min on 2 cores): the thresholds
    # hold, and every figure the report names exists as a PNG.
    out = tmp_path / "validation"
    assert main(["validate", "--quick", "--output", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["passed"] is True and summary["mode"] == "quick"
    assert [c["key"] for c in summary["cases"]] == [
        "optical-depth", "lut-vs-montecarlo", "disort", "cie-sky", "spectrl2", "mars-pathfinder",
        "mars-mer-colour", "mars-mer-transmittance", "mars-blue-aureole"]
    figures = [f for case in summary["cases"] for f in case["figures"]]
    assert len(figures) >= 8
    for name in figures:
        assert (out / name).read_bytes()[:8] == PNG_SIGNATURE
    report = (out / "report.md").read_text()
    assert "result: **PASSED**" in report
    assert all(f"]({name})" in report for name in figures)
    lut = next(c for c in summary["cases"] if c["key"] == "lut-vs-montecarlo")
    assert lut["metrics"]["monte_carlo_paths_per_second"] > 0
    assert "PASSED" in capsys.readouterr().out


def test_a_failed_check_exits_with_3(tmp_path, monkeypatch, capsys):
    def failing(settings):
        return CaseResult("optical-depth", "Optical depth", "forced failure",
                          checks=[Check("tau error", 5.0, 1.0, "%")])

    monkeypatch.setattr(optical_depth, "run", failing)
    assert main(["validate", "--cases", "optical-depth", "--output", str(tmp_path)]) == 3
    out = capsys.readouterr().out
    assert "FAILED tau error: 5% > 1%" in out
    assert json.loads((tmp_path / "summary.json").read_text())["passed"] is False


def test_bad_arguments_get_one_line(tmp_path, capsys):
    assert main(["validate", "--cases", "cie", "--output", str(tmp_path)]) == 2
    assert "unknown validation case 'cie'; choose from optical-depth" in capsys.readouterr().err
    a_file = tmp_path / "report"
    a_file.write_text("not a directory")
    assert main(["validate", "--output", str(a_file)]) == 2
    assert "is a file; give a directory" in capsys.readouterr().err
