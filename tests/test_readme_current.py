"""The README and docs say what the code does: the number of presets, each preset's scattering
orders wherever a page states them, the default orders, and links that lead to files of the
repository. The presets are read as the code loads them (`api.list_presets`,
`api.load_atmosphere`), the numbers from the pages' text."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

import pytest

from skyscatter import api
from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
PRESETS = list(api.list_presets())
NAMES = "|".join(re.escape(name) for name in sorted(PRESETS, key=len, reverse=True))


@cache
def _orders(name: str) -> int:
    return api.load_atmosphere(name).scattering_orders


def _text(page: Path) -> str:
    return page.read_text(encoding="utf-8")


def test_preset_count():
    """`skyscatter presets ... (N)` and every "N presets" state the shipped count."""
    readme = _text(ROOT / "README.md")
    listed = re.search(r"skyscatter presets +# [^\n]*\((\d+)\)", readme)
    assert listed is not None, "README: the `skyscatter presets` line ends with the count"
    assert int(listed.group(1)) == len(PRESETS)
    for page in PAGES:
        for count in re.findall(r"\b(\d{1,3}) (?:shipped |atmosphere )?presets\b", _text(page)):
            assert int(count) == len(PRESETS), f"{page.name}: {count} presets"  # not a year


def _table_claims(text: str) -> list[tuple[str, str]]:
    """(preset, cell) of every markdown table row that starts with a preset and has a column
    headed `orders` or `[tables] orders`."""
    claims = []
    column = None
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if not line.lstrip().startswith("|"):
            column = None
        elif column is None and ("`orders`" in cells or "`[tables] orders`" in cells):
            column = cells.index("`orders`" if "`orders`" in cells else "`[tables] orders`")
        elif column is not None and re.fullmatch(rf"`({NAMES})`", cells[0]):
            claims.append((cells[0].strip("`"), cells[column]))
    return claims


def _prose_claims(text: str, page: Path) -> list[tuple[str, str]]:
    """(preset, number) from the sentences that give a preset's orders."""
    patterns = [rf"`({NAMES})` \((\d+) orders",  # `earth` (8 orders, 6 iterated)
                rf"\((\d+) for `({NAMES})`",  # (10 for `mars-physical`
                rf"^\| `({NAMES})` \|[^\n]*?(\d+) scattering orders"]  # a README table row
    if page.name == "config.md":  # its list of the presets' orders (elsewhere such a list
        patterns.append(rf"`({NAMES})` (\d+)[,)]")  # can be of orders iterated)
    claims = []
    for pattern in patterns:
        for match in re.finditer(pattern, text, flags=re.MULTILINE):
            first, second = match.groups()
            claims.append((second, first) if first.isdigit() else (first, second))
    return claims


def test_documented_orders_are_the_presets():
    """Each stated count of a preset's orders is its `[tables] orders` as loaded; the pages
    state at least the ones they state today (a rewording that hides them fails here)."""
    found = 0
    for page in PAGES:
        text = _text(page)
        for name, cell in _table_claims(text) + _prose_claims(text, page):
            number = re.match(r"\**(\d+)", cell)
            assert number is not None, f"{page.name}: {name}: {cell!r}"
            assert int(number.group(1)) == _orders(name), (
                f"{page.relative_to(ROOT)} says {name} has {number.group(1)} orders; "
                f"it has {_orders(name)}")
            found += 1
    assert found >= 20, found


def test_documented_default_orders():
    """docs/config.md's `[tables] orders` default and the README's `earth` tables."""
    config = _text(ROOT / "docs" / "config.md")
    row = re.search(r"^\| `orders` \| integer \| `(\d+)` \|", config, flags=re.MULTILINE)
    assert row is not None and int(row.group(1)) == DEFAULT_SCATTERING_ORDERS
    readme = _text(ROOT / "README.md")
    earth = re.search(r"its default (\d+) orders and (\d+) wavelengths", readme)
    assert earth is not None and int(earth.group(1)) == _orders("earth")
    assert int(earth.group(2)) == api.DEFAULT_WAVELENGTH_BINS


def _links(text: str) -> list[str]:
    """Targets of markdown links and images, and of HTML src/href attributes."""
    return (re.findall(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text)
            + re.findall(r"(?:src|href)=\"([^\"]+)\"", text))


@pytest.mark.parametrize("page", PAGES, ids=lambda page: str(page.relative_to(ROOT)))
def test_relative_links_lead_to_files_in_the_repository(page):
    for target in _links(_text(page)):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue  # a web address, or an anchor on the same page
        path = (page.parent / target.split("#", 1)[0]).resolve()
        assert path.is_relative_to(ROOT), f"{page.name}: {target} leaves the repository"
        assert path.exists(), f"{page.name}: {target} does not exist"
