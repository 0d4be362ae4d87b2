"""The package as pip installs it: one version string, dependencies that cover the imports, and
a wheel and sdist (built here with `build`, read back with zipfile/tarfile) that carry every
file the code opens."""

from __future__ import annotations

import ast
import importlib.metadata
import re
import shutil
import subprocess
import sys
import tarfile
import tomllib
import zipfile
from pathlib import Path

import pytest

import skyscatter
from skyscatter.cli import main

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "skyscatter"
PROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
# modules imported only where an extra is needed; each must name its extra where it fails
EXTRA_ONLY = {"imageio_ffmpeg": "video", "matplotlib": "validate", "pvlib": "validate",
              "PythonicDISORT": "validate", "xarray": "science", "dask": "dask",
              "distributed": "dask", "zarr": "dask"}
# where each extra's modules may be imported (a prefix, or a tuple of them): only there does a
# missing extra make itself felt
EXTRA_HOME = {"video": "render/video_io.py", "validate": "validate/", "science": "datasets.py",
              "dask": ("dask_cluster.py",)}


def _requirement_name(requirement: str) -> str:
    return re.split(r"[<>=!~\[;\s]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def test_one_version_string(capsys):
    """pyproject reads the version from skyscatter.__version__; the installed metadata (an
    independent reader of the build) and `skyscatter --version` say the same."""
    assert "version" not in PROJECT and "version" in PROJECT["dynamic"]
    assert importlib.metadata.version("skyscatter") == skyscatter.__version__
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"skyscatter {skyscatter.__version__}"


def _third_party_imports() -> dict[str, set[str]]:
    """Top-level module -> the source files that import it, for modules outside the standard
    library and the package."""
    found: dict[str, set[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top != "skyscatter":
                    found.setdefault(top, set()).add(str(path.relative_to(PACKAGE)))
    return found


def _distributions(module: str) -> set[str]:
    """The installed distributions that provide the top-level `module`, from their own file
    lists (packages_distributions misses an extension module such as OpenEXR's .so)."""
    found = set(importlib.metadata.packages_distributions().get(module, []))
    for distribution in importlib.metadata.distributions():
        if any(file.parts[0].split(".")[0] == module for file in distribution.files or ()):
            found.add(distribution.metadata["Name"])
    return {name.lower().replace("_", "-") for name in found}


def test_every_import_is_a_core_dependency_or_its_extra():
    """Each third-party module the package imports belongs (by the installed distributions'
    own file lists) to a core dependency, or is one of `EXTRA_ONLY`,
    imported only where its extra is needed and listed in that extra."""
    core = {_requirement_name(r) for r in PROJECT["dependencies"]}
    extras = {name: {_requirement_name(r) for r in requirements}
              for name, requirements in PROJECT["optional-dependencies"].items()}
    for module, files in _third_party_imports().items():
        distributions = _distributions(module)
        assert distributions, f"{module} (imported in {files}) is not installed"
        if module in EXTRA_ONLY:
            extra = EXTRA_ONLY[module]
            assert distributions & extras[extra], f"{module} is not in [{extra}]"
            assert not distributions & core
            assert all(f.startswith(EXTRA_HOME[extra]) for f in files), files
        else:
            assert distributions & core, f"{module} ({files}) is not a core dependency"
    assert "imageio-ffmpeg" not in core
    test_extra = " ".join(PROJECT["optional-dependencies"]["test"])
    assert all(extra in test_extra for extra in ("video", "viewer", "validate", "science",
                                                 "dask"))


@pytest.mark.slow  # builds an sdist and a wheel from a copy of the tree: about 10 s
def test_wheel_and_sdist_carry_the_package_and_its_files(tmp_path):
    if shutil.which("git") is None:
        pytest.skip("git lists the tracked files to copy")
    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout.split()
    source = tmp_path / "source"
    for name in tracked:
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    pytest.importorskip("build")
    subprocess.run([sys.executable, "-m", "build", "--no-isolation", "--outdir",
                    str(tmp_path / "dist"), str(source)], check=True, capture_output=True)
    version = skyscatter.__version__
    wheel = zipfile.ZipFile(tmp_path / "dist" / f"skyscatter-{version}-py3-none-any.whl")
    names = set(wheel.namelist())
    expected = {name.removeprefix("src/") for name in tracked if name.startswith("src/")}
    assert expected <= names, sorted(expected - names)  # every tracked file of the package
    for part in ("skyscatter/py.typed", "skyscatter/viewer/static/shaders/sky.glsl",
                 "skyscatter/viewer/static/index.html", "skyscatter/data/PROVENANCE.md",
                 "skyscatter/atmosphere/presets/earth.toml"):
        assert part in names
    assert f"skyscatter-{version}.dist-info/licenses/LICENSE" in names
    metadata = wheel.read(f"skyscatter-{version}.dist-info/METADATA").decode()
    assert f"Version: {version}" in metadata
    assert "License-Expression: MIT" in metadata
    assert "Requires-Dist: imageio-ffmpeg>=0.5; extra == \"video\"" in metadata
    assert "Classifier: Typing :: Typed" in metadata
    assert "Description-Content-Type: text/markdown" in metadata
    with tarfile.open(tmp_path / "dist" / f"skyscatter-{version}.tar.gz") as sdist:
        members = {name.split("/", 1)[1] for name in sdist.getnames() if "/" in name}
    # the README's pictures travel with it in the sdist
    images = re.findall(r"\]\((docs/images/[^)]+)\)", (ROOT / "README.md").read_text())
    assert images and set(images) <= members
    assert {"LICENSE", "Makefile", "tests/conftest.py", "docs/notebook.ipynb"} <= members


def test_the_api_imports_no_plotting():
    """matplotlib is [validate]'s, imported where a report draws: importing the api must not
    load it (nor pick its Agg backend, which would silence a notebook's inline plots)."""
    program = "import sys, skyscatter.api; print('matplotlib' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                            check=True)
    assert result.stdout.strip() == "False"
