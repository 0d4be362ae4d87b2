"""Citations point at primary sources a reader can get, not at notes outside the repository.

Presets, docstrings, docs, tests and benchmarks cite papers (with DOI), theses, standards,
datasets and public code by file; a reference to the project's private research notes (the
"seed" digests of theses, the "anchor" studies, the reference-data notes, anything under a
sibling `shared` folder) means nothing to a user. The observable: no shipped or tracked text
file names one.
"""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# The patterns are assembled so that this file does not match itself.
FORBIDDEN = re.compile("|".join([
    r"shared" + "/research",
    r"\.\./" + "shared",
    r"\bseed[-_ ]0\d\d\b",
    r"\banchor" + r"-(?:bruneton|realtime)",
    r"reference-" + r"data\.md",
    r"ecosystem-" + "probe",
    r"\b(?:DES" + r"IGN|STY" + r"LE)\.md",  # the design notes, not in the repository
]), re.IGNORECASE)
TEXT_SUFFIXES = {".py", ".md", ".toml", ".csv", ".glsl", ".js", ".json", ".html", ".txt", ".cfg"}
SKIP_PARTS = {"__pycache__", ".pytest_cache", ".ruff_cache", "generated"}
SEARCHED = ["src", "docs", "benchmarks", "scripts", "tests", "README.md"]


def _text_files() -> list[Path]:
    files = []
    for name in SEARCHED:
        top = ROOT / name
        candidates = [top] if top.is_file() else sorted(top.rglob("*"))
        for path in candidates:
            parts = set(path.relative_to(ROOT).parts)
            if (path.is_file() and path.suffix in TEXT_SUFFIXES and not parts & SKIP_PARTS
                    and not any(part.endswith(".egg-info") for part in parts)):
                files.append(path)
    return files


def test_the_search_covers_the_tree():
    # Guards against a vacuous pass: the walk must find the presets, this file and the README.
    names = {path.relative_to(ROOT).as_posix() for path in _text_files()}
    assert {"README.md", "tests/test_citations.py",
            "src/skyscatter/atmosphere/presets/mars-hybrid.toml"} <= names


def test_pattern_catches_each_kind_of_private_reference():
    # The forms found in the tree before issue 16, one per pattern.
    for text in ["shared" + "/rese" + "arch/se" + "ed-004.md §2.13",
                 "../" + "shared" + "/DES" + "IGN.md", "se" + "ed 004 §4", "(se" + "ed-004 §8.6)",
                 "anchor" + "-bruneton.md §1.2",
                 "reference-" + "data.md §4.3", "ecosystem-" + "probe.md", "(STY" + "LE.md §10)"]:
        assert FORBIDDEN.search(text), text
    for text in ["numpy.random.default_rng(1)", "--seed 0", "docs/physics/mie.md#anchor"]:
        assert not FORBIDDEN.search(text), text


def test_no_reference_to_notes_outside_the_repository():
    hits = [f"{path.relative_to(ROOT)}:{number}: {line.strip()[:120]}"
            for path in _text_files()
            for number, line in enumerate(path.read_text(encoding="utf-8",
                                                         errors="replace").splitlines(), 1)
            if FORBIDDEN.search(line)]
    assert not hits, ("cite the primary source (paper and DOI, thesis, standard, dataset, code "
                      "file) instead of notes outside the repository:\n" + "\n".join(hits))
