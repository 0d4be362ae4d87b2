"""The calling contract: no public function takes more than `MAX_POSITIONAL` positional
parameters; the rest are keyword-only, so a call names its options
(`render(atmosphere, camera, 60.0, wavelengths_nm=..., options=...)`) and options can be added
or reordered without silently shifting a caller's arguments.

Two checks: `api.__all__` by `inspect` (what a user of the facade calls), and every module of
the package by `ast` (`crowded_functions`): each public function, each public method of a public
class and each public class's `__init__` (the constructor), `self`/`cls` not counted. Numba
kernels are exempt, named by their decorator (`JIT_DECORATORS`): numba cannot bind keyword-only
parameters when one jitted function calls another (`test_numba_cannot_pass_keyword_only_...`
holds that true), and kernels call kernels; they are private (`transport/_*kernels.py`) or the
table-coordinate mappings of `transport/table_parameterisation.py`, and bundle their arguments
into typed records where numba allows (docs/architecture.md).
"""

import ast
import datetime
import inspect
from pathlib import Path

import numba
import pytest

from skyscatter import api
from skyscatter.errors import InputError

MAX_POSITIONAL = 5
PACKAGE = Path(__file__).resolve().parents[1] / "src" / "skyscatter"
JIT_DECORATORS = {"njit", "jit"}  # numba.njit, @njit(cache=True), numba.jit(nopython=True)


def positional_count(function) -> int:
    """The parameters of `function` that a caller may pass by position (not *args)."""
    kinds = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    return sum(p.kind in kinds for p in inspect.signature(function).parameters.values())


PUBLIC_FUNCTIONS = sorted(name for name in api.__all__
                          if inspect.isfunction(getattr(api, name)))


def test_the_count_sees_positional_and_keyword_only_parameters():
    def six(a, b, c, d, e, f=1, *, g=2): ...

    def five(a, b, /, c, d=1, e=2, *args, f=3, **kwargs): ...

    assert positional_count(six) == 6
    assert positional_count(five) == 5


def test_the_facade_has_its_functions():
    assert {"render", "render_at", "timelapse", "save_image", "sky_radiance_rows",
            "solver_options", "demo_mountains", "viewer_server"} <= set(PUBLIC_FUNCTIONS)


@pytest.mark.parametrize("name", PUBLIC_FUNCTIONS)
def test_no_public_function_takes_more_than_five_positional_parameters(name):
    count = positional_count(getattr(api, name))
    assert count <= MAX_POSITIONAL, (
        f"api.{name} takes {count} positional parameters: make those after the first "
        f"{MAX_POSITIONAL} keyword-only (*)")


def test_options_after_the_leading_ones_cannot_be_passed_by_position():
    with pytest.raises(TypeError):
        api.render(api.load_atmosphere("earth"), api.FisheyeCamera(8), 30.0, 180.0, 0.0,
                   [550.0])


WHEN = [datetime.datetime(2024, 1, 1, tzinfo=datetime.UTC)]


@pytest.mark.parametrize("image, key", [
    (api.ImageOptions(ev100=10.0), "ev100"),  # a time-lapse meters each frame itself
    ("aces", "image"),
])
def test_timelapse_refuses_image_options_it_cannot_follow_before_any_work(tmp_path, image, key):
    with pytest.raises(InputError) as raised:
        api.timelapse(api.load_atmosphere("earth"), api.FisheyeCamera(8), WHEN, 0.0, 0.0,
                      video_path=tmp_path / "x.mp4", frames_dir=tmp_path / "frames",
                      image=image)
    assert raised.value.key == key
    assert list(tmp_path.iterdir()) == []


# The whole package, by `ast` -------------------------------------------------------------------

def _decorator_name(decorator: ast.expr) -> str:
    target = decorator.func if isinstance(decorator, ast.Call) else decorator
    if isinstance(target, ast.Attribute):
        return target.attr
    return target.id if isinstance(target, ast.Name) else ""


def _public_functions(tree: ast.Module) -> list[tuple[str, ast.FunctionDef, bool]]:
    """(qualified name, definition, is a method) of the module's public functions, the public
    methods and constructors of its public classes (nested classes included); functions defined
    inside functions are local, not public."""
    found = []

    def visit(body: list[ast.stmt], prefix: str, in_class: bool) -> None:
        for node in body:
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                if not node.name.startswith("_") or (in_class and node.name == "__init__"):
                    found.append((prefix + node.name, node, in_class))
            elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                visit(node.body, f"{prefix}{node.name}.", True)

    visit(tree.body, "", False)
    return found


def positional_parameters(function: ast.FunctionDef, method: bool) -> int:
    """The parameters a caller may pass by position (not *args); a method's `self`/`cls` is not
    counted (a static method has none)."""
    count = len(function.args.posonlyargs) + len(function.args.args)
    static = any(_decorator_name(d) == "staticmethod" for d in function.decorator_list)
    return count - 1 if method and not static and count else count


def crowded_functions(source: str, module: str) -> tuple[list[str], list[str]]:
    """(crowded, exempt): "module.name (n positional)" of each public function of `source` with
    more than `MAX_POSITIONAL` positional parameters; exempt: those that are numba kernels."""
    crowded, exempt = [], []
    for name, function, method in _public_functions(ast.parse(source)):
        count = positional_parameters(function, method)
        if count > MAX_POSITIONAL:
            jitted = any(_decorator_name(d) in JIT_DECORATORS for d in function.decorator_list)
            (exempt if jitted else crowded).append(f"{module}.{name} ({count} positional)")
    return crowded, exempt


def package_signatures() -> tuple[list[str], list[str]]:
    """`crowded_functions` over every module of the package."""
    crowded, exempt = [], []
    for path in sorted(PACKAGE.rglob("*.py")):
        module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        found, jitted = crowded_functions(path.read_text(encoding="utf-8"), module)
        crowded += found
        exempt += jitted
    return crowded, exempt


def test_no_public_function_of_the_package_takes_more_than_five_positional_parameters():
    crowded, exempt = package_signatures()
    assert not crowded, (
        f"{len(crowded)} public functions take more than {MAX_POSITIONAL} positional "
        "parameters; make those after the leading ones keyword-only (*):\n" + "\n".join(crowded))
    assert exempt  # the kernels are seen (and exempt), not missed


def test_the_exempt_kernels_are_private_or_the_table_mappings():
    _, exempt = package_signatures()
    modules = {name.split(" ")[0].rsplit(".", 1)[0] for name in exempt}
    assert all(m.split(".")[-1].startswith("_")
               or m == "skyscatter.transport.table_parameterisation" for m in modules), modules


SIX_POSITIONAL = '''
import numba
from numba import njit


def crowded(a, b, c, d, e, f=1): ...
def five(a, b, c, d, e, *args, g=1, h=2, **kwargs): ...
def positional_only(a, b, /, c, d, e, f): ...
def _private(a, b, c, d, e, f): ...


def outer(a):
    def local(a, b, c, d, e, f): ...


class Public:
    def __init__(self, a, b, c, d, e, f): ...
    def method(self, a, b, c, d, e): ...
    def crowded_method(self, a, b, c, d, e, f): ...
    @staticmethod
    def static(a, b, c, d, e, f): ...
    @classmethod
    def build(cls, a, b, c, d, e): ...

    class Inner:
        def crowded_inner(self, a, b, c, d, e, f): ...


class _Private:
    def method(self, a, b, c, d, e, f): ...


@njit(cache=True)
def kernel(a, b, c, d, e, f): ...
@numba.njit
def bare_kernel(a, b, c, d, e, f): ...
'''


def test_the_checker_reports_a_function_with_six_positional_parameters():
    crowded, exempt = crowded_functions(SIX_POSITIONAL, "m")
    assert crowded == ["m.crowded (6 positional)", "m.positional_only (6 positional)",
                       "m.Public.__init__ (6 positional)",
                       "m.Public.crowded_method (6 positional)",
                       "m.Public.static (6 positional)",
                       "m.Public.Inner.crowded_inner (6 positional)"]
    assert exempt == ["m.kernel (6 positional)", "m.bare_kernel (6 positional)"]


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="the limitation is numba's compiler's")
def test_numba_cannot_pass_keyword_only_parameters_between_kernels():
    # The reason kernels are exempt: numba (0.68) binds a keyword-only parameter from Python,
    # but a call from one jitted function to another that has one fails to compile. Should
    # numba learn it, this fails: then hold the kernels to the rule too.
    @numba.njit(cache=False)
    def inner(a, *, c):
        return a * c

    @numba.njit(cache=False)
    def outer(a):
        return inner(a, c=3.0)

    assert inner(2.0, c=3.0) == 6.0
    with pytest.raises(numba.core.errors.TypingError, match="Cannot bind"):
        outer(2.0)
