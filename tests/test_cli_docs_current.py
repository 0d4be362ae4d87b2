"""docs/cli.md is the --help of every command: regenerate it in memory and compare."""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "make_cli_docs.py"


def _load_script():
    spec = importlib.util.spec_from_file_location("make_cli_docs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cli_docs_are_current():
    script = _load_script()
    current = script.DOCS_PATH.read_text(encoding="utf-8")
    made_with = f"(Python {script.python_version()},"
    if made_with not in current:
        pytest.skip("docs/cli.md was generated under another Python version, whose argparse "
                    f"lays out help differently; compare under that version ({sys.version})")
    assert script.render_cli_docs() == current, (
        "docs/cli.md is stale: run `python scripts/make_cli_docs.py` and commit docs/cli.md")


def test_cli_docs_do_not_depend_on_the_terminal_width(monkeypatch):
    script = _load_script()
    monkeypatch.setenv("COLUMNS", "40")
    narrow = script.render_cli_docs()
    monkeypatch.setenv("COLUMNS", "250")
    assert script.render_cli_docs() == narrow
    assert "## `skyscatter radiance`" in narrow and "--view-azimuth" in narrow
