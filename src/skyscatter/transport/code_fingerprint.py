"""Fingerprint of the code a computation runs: the key of cached results made by it.

`code_fingerprint(roots)` follows, with `ast` and without importing anything, the names that
each root function uses (its calls, the constants it reads, the classes it builds) through the
skyscatter modules that define them, resolving `from skyscatter... import` (modules and
names, re-exports included), and hashes the code of exactly the functions, classes and
module-level constants reached (`ast.unparse`: comments, docstrings and formatting do not
count; nor do type annotations and `raise` statements, which cannot change a result). So an
edit to any code the computation runs changes the fingerprint, and an edit elsewhere in the
same files (a lookup used only at render time) does not. Names bound locally (arguments,
assignments) and names from outside skyscatter (numpy, numba, builtins) are not followed.
Methods called on objects passed in (`phase.evaluate`) are found only when the caller gives
their class as a root.

The walk parses and unparses every module it reaches (about 0.5 s). Given folders, the
fingerprint is kept there (`MEMO_FILE`) with a SHA-256 of each module source the walk read,
and taken from there while all of those sources are unchanged: a few milliseconds per process.
The tables' key keeps it in the table cache and beside the compiled kernels, where
`skyscatter compile` leaves it at install time (`table_store`).
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import importlib.util
import json
from collections.abc import Callable, Iterable, Iterator
from functools import cache, lru_cache
from pathlib import Path

from skyscatter.errors import InputError
from skyscatter.output_files import atomic_write

__all__ = ["MEMO_FILE", "code_fingerprint", "reached_definitions"]

_PACKAGE = "skyscatter"
# The memo of fingerprints in a cache folder: {roots: {"modules": {module: SHA-256 of its
# source, or null where it is not a source module}, "fingerprint": ...}}
MEMO_FILE = "code-fingerprints.json"

Definition = tuple[str, str]  # (module, top-level name)


@cache
def _module_source(module: str) -> str | None:
    """Source text of a skyscatter module, None when it is not a plain source module."""
    try:
        spec = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.origin or not spec.origin.endswith(".py"):
        return None
    with open(spec.origin, encoding="utf-8") as stream:
        return stream.read()


class _Module:
    """The top-level definitions and skyscatter imports of one module's source."""

    def __init__(self, name: str, source: str, is_module: Callable[[str], bool]) -> None:
        self.name = name
        self.definitions: dict[str, ast.AST] = {}
        self.imports: dict[str, Definition | str] = {}  # alias -> (module, name) or module
        for node in ast.parse(source).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                self.definitions[node.name] = node
            elif isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    for leaf in ast.walk(target):
                        if isinstance(leaf, ast.Name):
                            self.definitions[leaf.id] = node
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""  # skyscatter imports absolutely (no level)
                if node.level or base != _PACKAGE and not base.startswith(_PACKAGE + "."):
                    continue
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    self.imports[alias.asname or alias.name] = (
                        full if is_module(full) else (base, alias.name))
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith(_PACKAGE + ".") and alias.asname:
                        self.imports[alias.asname] = alias.name


def _without_docstrings(node: ast.AST) -> ast.AST:
    """A copy of `node` without the docstrings of its functions and classes."""
    node = ast.parse(ast.unparse(node)).body[0]
    for inner in ast.walk(node):
        if isinstance(inner, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = inner.body
            if (body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant)
                    and isinstance(body[0].value.value, str)):
                inner.body = body[1:] or [ast.Pass()]
    return node


def _executed(node: ast.AST) -> Iterator[ast.AST]:
    """The nodes of `node` (`ast.walk`) that can decide a result: type annotations are left
    out, and so are `raise` statements (they end the computation, so the exception classes
    and their messages cannot change what it returns)."""
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        for field, value in ast.iter_fields(current):
            if field in ("annotation", "returns") or isinstance(value, ast.Raise):
                continue
            children = value if isinstance(value, list) else [value]
            stack.extend(child for child in children
                         if isinstance(child, ast.AST) and not isinstance(child, ast.Raise))


def _free_names(node: ast.AST) -> tuple[set[str], set[tuple[str, str]]]:
    """(names read but not bound inside `node`, (name, attribute) pairs `name.attribute`)."""
    bound: set[str] = set()
    for inner in _executed(node):
        if isinstance(inner, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            arguments = inner.args
            for argument in (arguments.posonlyargs + arguments.args + arguments.kwonlyargs
                             + [a for a in (arguments.vararg, arguments.kwarg) if a]):
                bound.add(argument.arg)
        elif isinstance(inner, ast.Name) and isinstance(inner.ctx, (ast.Store, ast.Del)):
            bound.add(inner.id)
    if isinstance(node, (ast.Assign, ast.AnnAssign)):
        bound = set()  # a module-level constant binds only itself
    names = {inner.id for inner in _executed(node)
             if isinstance(inner, ast.Name) and isinstance(inner.ctx, ast.Load)}
    attributes = {(inner.value.id, inner.attr) for inner in _executed(node)
                  if isinstance(inner, ast.Attribute) and isinstance(inner.value, ast.Name)}
    return names - bound, {pair for pair in attributes if pair[0] not in bound}


def reached_definitions(roots: Iterable[Definition],
                        read_source: Callable[[str], str | None] = _module_source
                        ) -> dict[Definition, str]:
    """{(module, name): code without docstrings} of every skyscatter function, class and
    module-level constant reached from `roots` ((module, name) pairs) through the names they
    use (module docstring). `read_source(module)` gives a module's source (None: not one)."""
    modules: dict[str, _Module | None] = {}

    def module_of(name: str) -> _Module | None:
        if name not in modules:
            source = read_source(name)
            modules[name] = (None if source is None else
                             _Module(name, source, lambda m: read_source(m) is not None))
        return modules[name]

    def resolve(module: str, name: str, depth: int = 0) -> Definition | None:
        """The module that defines `name` as seen from `module` (following re-exports)."""
        parsed = module_of(module)
        if parsed is None or depth > 20:
            return None
        if name in parsed.definitions:
            return module, name
        target = parsed.imports.get(name)
        if isinstance(target, tuple):
            return resolve(*target, depth + 1)
        return None

    reached: dict[Definition, str] = {}
    pending = [d for d in (resolve(*root) for root in roots) if d is not None]
    while pending:
        module, name = pending.pop()
        if (module, name) in reached:
            continue
        node = module_of(module).definitions[name]
        reached[(module, name)] = ast.unparse(_without_docstrings(node))
        names, attributes = _free_names(node)
        imports = module_of(module).imports
        found = [resolve(module, n) for n in names]
        found += [resolve(imports[alias], attribute) for alias, attribute in attributes
                  if isinstance(imports.get(alias), str)]
        pending.extend(d for d in found if d is not None and d not in reached)
    return reached


def _digest(text: str | None) -> str | None:
    return None if text is None else hashlib.sha256(text.encode()).hexdigest()


def _read_memo(path: Path) -> dict:
    """The memo at `path`; empty when it is missing or unreadable (it is only a shortcut)."""
    try:
        memo = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return memo if isinstance(memo, dict) else {}


def _remembered(memo: dict, key: str) -> tuple[str, dict[str, str | None]] | None:
    """(fingerprint, module digests) that `memo` holds for `key` when every module source it
    was made from is unchanged, else None."""
    entry = memo.get(key)
    try:
        modules, fingerprint = entry["modules"], entry["fingerprint"]
        unchanged = all(_digest(_module_source(m)) == d for m, d in modules.items())
    except (TypeError, KeyError, AttributeError):
        return None
    return (fingerprint, modules) if unchanged and isinstance(fingerprint, str) else None


def _remember(path: Path, memo: dict, key: str, entry: dict) -> None:
    """Write `memo` (as read from `path`) with `entry` for `key` back to `path`
    (`atomic_write`); a folder that cannot be written is left alone."""
    text = json.dumps({**memo, key: entry}, sort_keys=True)
    with contextlib.suppress(InputError):
        atomic_write(path, lambda temporary: Path(temporary).write_text(text, encoding="utf-8"))


@lru_cache(maxsize=32)
def code_fingerprint(roots: tuple[Definition, ...], memo_folders: tuple[Path, ...] = ()) -> str:
    """SHA-256 (16 hex digits) of the code reached from `roots` (`reached_definitions`), in
    a fixed order: the same code gives the same fingerprint in every process. With
    `memo_folders` it is taken from the first memo there that holds it, else computed, and
    kept in each of those folders whose memo lacked it (module docstring)."""
    key = json.dumps(roots)
    memos = [(Path(folder) / MEMO_FILE, _read_memo(Path(folder) / MEMO_FILE))
             for folder in memo_folders]
    known = next((found for _, memo in memos if (found := _remembered(memo, key))), None)
    fingerprint, modules = known or _walked(roots)
    entry = {"modules": modules, "fingerprint": fingerprint}
    for path, memo in memos:  # an equal entry was validated above or made just now
        if memo.get(key) != entry and path.parent.is_dir():
            _remember(path, memo, key, entry)
    return fingerprint


def _walked(roots: tuple[Definition, ...]) -> tuple[str, dict[str, str | None]]:
    """(fingerprint, {module: SHA-256 of each source the walk read}) of `roots`."""
    read: dict[str, str | None] = {}

    def recorded_source(module: str) -> str | None:
        source = _module_source(module)
        read[module] = _digest(source)
        return source

    digest = hashlib.sha256()
    for (module, name), code in sorted(reached_definitions(roots, recorded_source).items()):
        digest.update(f"{module}:{name}\n{code}\n".encode())
    return digest.hexdigest()[:16], read
