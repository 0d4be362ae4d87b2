"""What a validation case returns, and the report written from all of them.

Each case (`validate/cases.py` lists them) is a function `run(settings) -> CaseResult`. The
result carries the numbers (`metrics`, written to the JSON summary), the pass/fail checks with
their limits, Markdown tables, and the figures the case saved into `settings.output_dir`.
`write_report` turns the results into `report.md` and `summary.json` (both written to a
temporary file and renamed, so an interrupted run never leaves half a report).

Public names: `Check`, `Table`, `Figure`, `CaseResult`, `ValidationSettings`, `write_report`,
`format_percent`, `atomic_write_text`.
"""

from __future__ import annotations

import json
import os
import platform
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "CaseResult",
    "Check",
    "Figure",
    "Table",
    "ValidationSettings",
    "atomic_write_text",
    "format_percent",
    "write_report",
]


@dataclass(frozen=True)
class Check:
    """A measured value against the limit that fails the suite (`value <= limit` passes)."""

    name: str  # what is measured, e.g. "earth, sun zenith 60 deg, 440 nm: median |rel. error|"
    value: float
    limit: float
    unit: str = ""  # "%" or a unit; percentages are stored in percent

    @property
    def passed(self) -> bool:
        return bool(self.value <= self.limit)


@dataclass(frozen=True)
class Table:
    """A Markdown table: a caption, a header row and rows of already formatted cells."""

    caption: str
    header: list[str]
    rows: list[list[str]]

    def markdown(self) -> str:
        lines = [f"*{self.caption}*", "", "| " + " | ".join(self.header) + " |",
                 "|" + "---|" * len(self.header)]
        lines += ["| " + " | ".join(row) + " |" for row in self.rows]
        return "\n".join(lines)


@dataclass(frozen=True)
class Figure:
    """A PNG the case wrote, relative to the output directory, with its one-line message."""

    path: str
    caption: str


@dataclass
class CaseResult:
    """Everything one validation case reports."""

    key: str  # short identifier, e.g. "lut-vs-montecarlo"
    title: str
    summary: str  # Markdown: what was compared, with what, and how close it came
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    metrics: dict[str, Any] = field(default_factory=dict)  # JSON-able numbers
    checks: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # why a figure is worse, caveats
    seconds: float = 0.0

    @property
    def passed(self) -> bool:
        return all(check.passed for check in self.checks)


@dataclass(frozen=True)
class ValidationSettings:
    """How a validation run is done.

    output_dir  where figures, report.md and summary.json go
    quick       the reduced suite (fewer angles, wavelengths and paths; < 2 min on 2 cores)
    cache       `transport.table_store.TableCache` for precomputed tables, or None
    log         called with one line of progress text
    seed        seed of the Monte Carlo solver
    """

    output_dir: Path
    quick: bool = False
    cache: Any = None
    log: Callable[[str], None] = print
    seed: int = 0


def format_percent(fraction: float, digits: int = 2) -> str:
    """A fraction as a percentage string, e.g. 0.0123 -> '1.23 %'."""
    return f"{100.0 * fraction:.{digits}f} %"


def atomic_write_text(path: Path, text: str) -> None:
    """Write `text` to `path` through a temporary file and a rename (`render.image_io`)."""
    # imported here: `skyscatter --help` reads the case list through this module
    from skyscatter.render.image_io import atomic_write

    atomic_write(path, lambda temporary: Path(temporary).write_text(text, encoding="utf-8"))


def _case_markdown(result: CaseResult) -> str:
    status = "passed" if result.passed else "FAILED"
    if not result.checks:
        status = "reported (no pass/fail limits)"
    parts = [f"## {result.title}", "",
             f"`{result.key}` - {status} - {result.seconds:.1f} s", "", result.summary]
    for table in result.tables:
        parts += ["", table.markdown()]
    failed = [c for c in result.checks if not c.passed]
    if result.checks:
        parts += ["", f"Checks: {len(result.checks) - len(failed)} of {len(result.checks)} "
                      "within their limits."]
    for check in failed:
        parts.append(f"- FAILED: {check.name}: {check.value:.3g}{check.unit} > limit "
                     f"{check.limit:.3g}{check.unit}")
    for figure in result.figures:
        parts += ["", f"![{figure.caption}]({figure.path})", "", f"*{figure.caption}*"]
    for note in result.notes:
        parts += ["", f"> {note}"]
    return "\n".join(parts)


def write_report(results: list[CaseResult], settings: ValidationSettings, seconds: float,
                 header: str = "") -> tuple[Path, Path]:
    """Write `report.md` and `summary.json` into `settings.output_dir`; return their paths."""
    out = Path(settings.output_dir)
    passed = all(r.passed for r in results)
    mode = "quick" if settings.quick else "standard"
    lines = ["# skyscatter validation report", "",
             f"Suite: {mode}; {len(results)} cases; {seconds:.0f} s on "
             f"{os.cpu_count()} cores ({platform.processor() or platform.machine()}); "
             f"result: **{'PASSED' if passed else 'FAILED'}**.", ""]
    if header:
        lines += [header, ""]
    lines += ["| case | result | checks | time |", "|---|---|---|---|"]
    for r in results:
        state = "passed" if r.passed else "FAILED"
        if not r.checks:
            state = "reported"
        lines.append(f"| [{r.title}](#{_anchor(r.title)}) | {state} | "
                     f"{sum(c.passed for c in r.checks)}/{len(r.checks)} | {r.seconds:.1f} s |")
    body = "\n\n".join(_case_markdown(r) for r in results)
    report = out / "report.md"
    atomic_write_text(report, "\n".join(lines) + "\n\n" + body + "\n")
    summary = {
        "passed": passed,
        "mode": mode,
        "seconds": round(seconds, 2),
        "cases": [{
            "key": r.key, "title": r.title, "passed": r.passed,
            "seconds": round(r.seconds, 2), "metrics": r.metrics,
            "checks": [{"name": c.name, "value": c.value, "limit": c.limit, "unit": c.unit,
                        "passed": c.passed} for c in r.checks],
            "figures": [f.path for f in r.figures],
        } for r in results],
    }
    summary_path = out / "summary.json"
    atomic_write_text(summary_path, json.dumps(summary, indent=2, default=_json_number) + "\n")
    return report, summary_path


def _anchor(title: str) -> str:
    """GitHub's Markdown heading anchor of `title`."""
    kept = "".join(ch for ch in title.lower() if ch.isalnum() or ch in " -_")
    return kept.replace(" ", "-")


def _json_number(value: Any) -> Any:
    """numpy scalars and arrays as plain JSON numbers and lists."""
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")
