"""The package layout is the data flow (docs/architecture.md): no import may point backwards.

`LAYERS` is the one table of what each layer may import. `layering_violations(root)` reads the
imports of every module under a package root with `ast` - every form: `import skyscatter.x`,
`from skyscatter import x`, `from skyscatter.x import y`, relative imports, imports inside
functions and `importlib.import_module("skyscatter...")` - and names each one the table does not
allow, and each module that belongs to no layer. The tests at the end inject a backward import of
each form into a copy of the package and expect it to be named: a checker that cannot fail checks
nothing.
"""

from __future__ import annotations

import ast
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "skyscatter"

# Layer -> the layers its modules may import besides their own. Left to right along the data
# flow of docs/architecture.md: config -> atmosphere -> solver (transport) -> scene (render) ->
# image / viewer.
LAYERS: dict[str, set[str]] = {
    # errors, checks, files and caches every layer uses; the package's own __init__
    "base": set(),
    "spectrum": {"base"},
    "optics": {"base", "spectrum"},
    "atmosphere": {"base", "optics", "spectrum"},
    "transport": {"base", "atmosphere", "optics", "spectrum"},
    "astro": {"base"},
    "render": {"base", "transport", "astro", "spectrum"},
    "viewer": {"base", "render", "transport", "atmosphere", "spectrum"},
    # compares the solvers and their images with references; no viewer, no API
    "validate": {"base", "spectrum", "optics", "atmosphere", "transport", "astro", "render"},
    # sweeps over config values and geometry: atmospheres, their solvers, the radiance grid
    "sweep": {"base", "spectrum", "optics", "atmosphere", "transport", "render"},
    # estimates config values from measurements with the solvers' forward models
    "fit": {"base", "spectrum", "optics", "atmosphere", "transport", "astro", "render"},
    # the facade: every layer below it
    "api": {"base", "spectrum", "optics", "atmosphere", "transport", "astro", "render", "viewer",
            "validate", "sweep", "fit"},
    # a thin skin: the public API (api, api_constants), the base modules, its own cli_progress
    "cli": {"base", "api"},
}

# Modules directly in skyscatter/ -> their layer (a subpackage is the layer of its name).
TOP_LEVEL = {
    "__init__": "base",  # `skyscatter` itself: __version__ and the exceptions
    "errors": "base",
    "checks": "base",
    "disk_cache": "base",
    "output_files": "base",
    "jit_cache": "base",
    "blas_threads": "base",  # OpenBLAS's idle threads, set before numpy loads it
    "row_output": "base",  # rows of numbers as JSON/CSV text, with their metadata
    "dask_cluster": "base",  # the Dask client of batch work (sweep): local or a scheduler's
    "api": "api",
    "output_metadata": "api",  # units, solver, version of a table of results
    "datasets": "api",  # tables of results as xarray Datasets / NetCDF
    "api_constants": "api",  # the API's constants that the CLI's help names, cheap to import
    "cli": "cli",
    "cli_progress": "cli",
    "cli_completion": "cli",  # `skyscatter completion`: scripts from the parser
    "compile_ahead": "cli",  # `skyscatter compile`: runs command lines ahead of the first run
}


def _module_parts(root: Path, path: Path) -> tuple[str, ...]:
    """skyscatter/optics/phase.py -> ("skyscatter", "optics", "phase"); __init__ stays a part."""
    return (root.name, *path.relative_to(root).with_suffix("").parts)


def _layer(root: Path, parts: tuple[str, ...]) -> str | None:
    """The layer of the module `parts` (`("skyscatter", "optics", "phase")`), None if none."""
    if len(parts) == 1:
        return TOP_LEVEL["__init__"]
    first = parts[1]
    if (root / first).is_dir():
        return first if first in LAYERS else None
    return TOP_LEVEL.get(first)


def _in_root(root: Path, parts: tuple[str, ...], name: str) -> tuple[str, ...]:
    """`from <parts> import name`: the module `parts + (name,)` where that is a module or a
    package, else `parts` itself (the name is an attribute, e.g. `skyscatter.__version__`)."""
    path = root.joinpath(*parts[1:], name)
    if path.is_dir() or path.with_suffix(".py").is_file():
        return (*parts, name)
    return parts


def _import_module_argument(node: ast.Call) -> str | None:
    """The module text of `importlib.import_module("...")` / `__import__("...")`; of an
    f-string its constant start ("skyscatter.validate." of f"skyscatter.validate.{name}")."""
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
    if name not in ("import_module", "__import__") or not node.args:
        return None
    argument = node.args[0]
    if isinstance(argument, ast.Constant) and isinstance(argument.value, str):
        return argument.value
    if (isinstance(argument, ast.JoinedStr) and argument.values
            and isinstance(argument.values[0], ast.Constant)):
        return str(argument.values[0].value).rstrip(".")
    return None


def imported_modules(root: Path, path: Path) -> Iterator[tuple[int, tuple[str, ...]]]:
    """(line, module parts) of every skyscatter module that the file `path` imports."""
    package = _module_parts(root, path)[:-1]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, tuple(alias.name.split("."))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                if node.level > len(package):
                    yield node.lineno, ("..",) * node.level  # beyond the package: no layer
                    continue
                base = package[:len(package) - node.level + 1]
            else:
                base = ()
            parts = (*base, *(node.module.split(".") if node.module else ()))
            for alias in node.names:
                yield node.lineno, (_in_root(root, parts, alias.name)
                                    if parts[:1] == (root.name,) else parts)
        elif isinstance(node, ast.Call):
            text = _import_module_argument(node)
            if text and not text.startswith("."):
                yield node.lineno, tuple(text.split("."))


def layering_violations(root: Path) -> list[str]:
    """Every import under the package `root` that points backwards in `LAYERS`, and every
    module that belongs to no layer, as lines 'optics/phase.py:12 imports skyscatter.transport
    (layer transport); optics may import base, spectrum'."""
    wrong = []
    for path in sorted(root.rglob("*.py")):
        name = path.relative_to(root).as_posix()
        layer = _layer(root, _module_parts(root, path))
        if layer is None:
            wrong.append(f"{name} belongs to no layer: add it to LAYERS or TOP_LEVEL")
            continue
        allowed = LAYERS[layer] | {layer}
        for line, parts in dict.fromkeys(imported_modules(root, path)):  # once per line
            if parts[0] != root.name and parts[0] != "..":
                continue  # the standard library and third-party packages
            target = _layer(root, parts) if parts[0] == root.name else None
            if target not in allowed:
                wrong.append(f"{name}:{line} imports {'.'.join(parts)} (layer {target}); "
                             f"{layer} may import {', '.join(sorted(allowed))}")
    return wrong


def test_no_module_imports_a_later_layer():
    wrong = layering_violations(PACKAGE)
    assert not wrong, "imports pointing backwards in the data flow:\n" + "\n".join(wrong)


def test_the_layers_form_no_cycle():
    # Topological order: peel off the layers whose allowed imports are all placed already.
    placed: set[str] = set()
    while len(placed) < len(LAYERS):
        ready = {layer for layer, allowed in LAYERS.items()
                 if layer not in placed and allowed <= placed}
        assert ready, f"the layers {sorted(set(LAYERS) - placed)} import each other"
        placed |= ready


def test_the_command_line_uses_only_names_the_api_lists():
    # cli.py reaches the library through `api`; every name it takes must be public there.
    tree = ast.parse((PACKAGE / "cli.py").read_text(encoding="utf-8"))
    used = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)
            and isinstance(node.value, ast.Name) and node.value.id == "api"}
    used |= {alias.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
             and node.module == "skyscatter.api" for alias in node.names}
    assert used, "the checker found no use of the API in cli.py"
    api_all = _dunder_all(PACKAGE / "api.py")
    assert used <= api_all, f"cli.py uses api names outside api.__all__: {sorted(used - api_all)}"


def _dunder_all(path: Path) -> set[str]:
    """The names in a module's `__all__ = [...]`, read without importing it."""
    for node in ast.parse(path.read_text(encoding="utf-8")).body:
        if isinstance(node, ast.Assign) and any(getattr(target, "id", None) == "__all__"
                                                for target in node.targets):
            return set(ast.literal_eval(node.value))
    raise AssertionError(f"{path.name} has no __all__")


# ---- the checker fails where it should: backward imports injected into a copy -------------


@pytest.fixture
def package_copy(tmp_path: Path) -> Path:
    """The package's Python files, copied under tmp_path/skyscatter."""
    copy = tmp_path / PACKAGE.name
    shutil.copytree(PACKAGE, copy, ignore=lambda folder, names: [
        name for name in names
        if not name.endswith(".py") and not (Path(folder) / name).is_dir()
        or name == "__pycache__"])
    return copy


def _inject(copy: Path, module: str, code: str) -> None:
    path = copy / module
    path.write_text(path.read_text(encoding="utf-8") + "\n" + code + "\n", encoding="utf-8")


def test_the_unchanged_copy_is_clean(package_copy):
    # The reference for the injections below: the copy alone has no violation.
    assert layering_violations(package_copy) == []


INJECTED = [  # (module, code, the imported module named in the violation)
    ("optics/phase.py", "from skyscatter import transport", "skyscatter.transport"),
    ("spectrum/grid.py", "from skyscatter.render import camera", "skyscatter.render.camera"),
    ("optics/phase.py", "import skyscatter.transport.geometry", "skyscatter.transport.geometry"),
    ("optics/phase.py", "from ..transport import geometry", "skyscatter.transport.geometry"),
    ("optics/phase.py", "from ..transport.geometry import ray_sphere",
     "skyscatter.transport.geometry"),
    ("spectrum/grid.py", "from .. import render", "skyscatter.render"),
    ("checks.py", "from . import api", "skyscatter.api"),
    ("errors.py", "from .spectrum.grid import wavelength_grid", "skyscatter.spectrum.grid"),
    ("optics/phase.py", "def _late():\n    import skyscatter.transport.geometry\n",
     "skyscatter.transport.geometry"),
    ("spectrum/grid.py",
     "def _late():\n    import importlib\n    return importlib.import_module("
     "'skyscatter.render.camera')\n", "skyscatter.render.camera"),
    ("spectrum/grid.py", "def _late(name):\n    import importlib\n    return importlib."
     "import_module(f'skyscatter.transport.{name}')\n", "skyscatter.transport"),
    ("atmosphere/__init__.py", "from skyscatter.transport import tables",
     "skyscatter.transport.tables"),
    ("viewer/server.py", "from skyscatter.validate import report", "skyscatter.validate.report"),
    ("validate/suite.py", "from skyscatter import api", "skyscatter.api"),
    ("render/scene.py", "from skyscatter.api import render", "skyscatter.api"),
    ("api.py", "from skyscatter import cli", "skyscatter.cli"),
    ("cli.py", "from skyscatter.render import camera", "skyscatter.render.camera"),
    ("cli.py", "def _late():\n    from skyscatter import transport\n", "skyscatter.transport"),
    ("cli.py", "def _late():\n    from .validate.suite import CASES\n",
     "skyscatter.validate.suite"),
    ("cli_progress.py", "import skyscatter.render.tonemap", "skyscatter.render.tonemap"),
]


@pytest.mark.parametrize(("module", "code", "target"), INJECTED,
                         ids=[f"{module}: {code.strip().splitlines()[-1].strip()}"
                              for module, code, _ in INJECTED])
def test_an_injected_backward_import_is_named(package_copy, module, code, target):
    _inject(package_copy, module, code)
    wrong = layering_violations(package_copy)
    assert len(wrong) == 1, wrong
    assert wrong[0].startswith(f"{module}:") and f" imports {target} " in wrong[0], wrong


def test_a_module_outside_every_layer_is_named(package_copy):
    (package_copy / "clouds").mkdir()
    (package_copy / "clouds" / "field.py").write_text('"""A new layer nobody placed."""\n')
    (package_copy / "colour_tools.py").write_text('"""A new top-level module."""\n')
    wrong = layering_violations(package_copy)
    assert wrong == ["clouds/field.py belongs to no layer: add it to LAYERS or TOP_LEVEL",
                     "colour_tools.py belongs to no layer: add it to LAYERS or TOP_LEVEL"]


def test_a_relative_import_above_the_package_is_named(package_copy):
    _inject(package_copy, "optics/phase.py", "from ... import elsewhere")
    wrong = layering_violations(package_copy)
    assert len(wrong) == 1 and wrong[0].startswith("optics/phase.py:"), wrong
