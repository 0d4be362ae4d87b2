"""The package layout is the data flow (STYLE.md section 1): no import may point backwards."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "skyscatter"

# Base modules every layer may import; they import no layer themselves.
BASE = {"errors", "disk_cache", "checks", "output_files", "jit_cache"}

# Subpackage -> the skyscatter subpackages it may import (besides itself and BASE).
ALLOWED = {
    "spectrum": set(),
    "optics": {"spectrum"},
    "atmosphere": {"optics", "spectrum"},
    "transport": {"atmosphere", "optics", "spectrum"},
    "astro": set(),
    "render": {"transport", "astro", "spectrum"},
    "viewer": {"render", "transport", "atmosphere", "spectrum"},
}


def imported_subpackages(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            modules = [node.module]
        else:
            continue
        for module in modules:
            parts = module.split(".")
            if parts[0] == "skyscatter" and len(parts) > 1:
                names.add(parts[1])
    return names


def test_no_module_imports_a_later_layer():
    wrong = []
    for layer, allowed in ALLOWED.items():
        for path in sorted((PACKAGE / layer).rglob("*.py")):
            bad = imported_subpackages(path) - allowed - {layer} - BASE
            if bad:
                wrong.append(f"{path.relative_to(PACKAGE)} imports {sorted(bad)}")
    assert not wrong, "imports pointing backwards in the data flow:\n" + "\n".join(wrong)


def test_base_modules_import_no_layer():
    for name in sorted(BASE):
        bad = imported_subpackages(PACKAGE / f"{name}.py") - BASE
        assert not bad, f"{name}.py imports {sorted(bad)}"


def test_layering_check_sees_imports():
    # The checker itself must find the imports it is meant to police.
    assert "spectrum" in imported_subpackages(PACKAGE / "atmosphere" / "model.py")
