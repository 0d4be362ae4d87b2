"""numba's kernel cache finds a writable folder when the install and the home are read-only.

Before: `import skyscatter.optics.phase` from a read-only install with an unwritable home raised
"RuntimeError: cannot cache function 'rayleigh': no locator available", so every command ended
in an internal error.
"""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numba
import pytest

import skyscatter
from cli_runner import unprivileged_prefix
from skyscatter.jit_cache import use_writable_cache_folder


@pytest.fixture
def clean_environment(monkeypatch, tmp_path):
    """No NUMBA_CACHE_DIR; numba's own setting and the temporary folder restored afterwards."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", numba.core.config.CACHE_DIR)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    return monkeypatch


def test_a_writable_install_keeps_numbas_own_choice(clean_environment, tmp_path):
    package = tmp_path / "package"
    package.mkdir()
    assert use_writable_cache_folder(package) is None
    assert "NUMBA_CACHE_DIR" not in os.environ


def test_a_given_numba_cache_dir_is_kept(clean_environment, tmp_path):
    clean_environment.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert use_writable_cache_folder(tmp_path / "missing") is None
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "mine")


def test_an_unwritable_install_uses_the_users_cache_folder(clean_environment, tmp_path):
    # A package folder that does not exist cannot be written, by root either.
    clean_environment.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    chosen = use_writable_cache_folder(tmp_path / "missing" / "skyscatter")
    assert chosen == tmp_path / "cache" / "skyscatter" / "numba" and chosen.is_dir()
    assert os.environ["NUMBA_CACHE_DIR"] == str(chosen) == numba.core.config.CACHE_DIR


def test_without_a_writable_home_a_private_temporary_folder_is_used(clean_environment,
                                                                    tmp_path):
    (tmp_path / "afile").write_text("x")  # a cache home below a file: unwritable for anyone
    clean_environment.setenv("XDG_CACHE_HOME", str(tmp_path / "afile" / "cache"))
    chosen = use_writable_cache_folder(tmp_path / "missing")
    assert chosen == tmp_path / "tmp" / f"skyscatter-numba-{os.getuid()}"
    assert chosen.stat().st_mode & 0o777 == 0o700


def test_a_temporary_folder_others_can_write_is_not_trusted(clean_environment, tmp_path):
    # Another account could plant compiled code there: take a fresh folder instead.
    (tmp_path / "afile").write_text("x")
    clean_environment.setenv("XDG_CACHE_HOME", str(tmp_path / "afile" / "cache"))
    shared = tmp_path / "tmp" / f"skyscatter-numba-{os.getuid()}"
    shared.mkdir()
    shared.chmod(0o777)
    chosen = use_writable_cache_folder(tmp_path / "missing")
    assert chosen != shared and chosen.parent == tmp_path / "tmp"
    assert chosen.name.startswith("skyscatter-numba-") and os.listdir(chosen) == []


def test_kernels_import_from_a_read_only_install_with_a_read_only_home(tmp_path):
    source = tmp_path / "site"
    shutil.copytree(Path(skyscatter.__file__).parent, source / "skyscatter",
                    ignore=shutil.ignore_patterns("__pycache__"))
    home, scratch = tmp_path / "home", tmp_path / "scratch"
    home.mkdir()
    scratch.mkdir()
    subprocess.run(["chmod", "-R", "a-w", str(source), str(home)], check=True)
    environment = {key: value for key, value in os.environ.items()
                   if key not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "PYTHONPATH")}
    environment.update(HOME=str(home), TMPDIR=str(scratch), PYTHONPATH=str(source),
                       PYTHONDONTWRITEBYTECODE="1")
    try:
        result = subprocess.run(
            [*unprivileged_prefix(), sys.executable, "-c",
             "import os, skyscatter.optics.phase as p; print(p.__file__);"
             "print(os.environ['NUMBA_CACHE_DIR'])"],
            env=environment, capture_output=True, text=True, timeout=120)
    finally:
        subprocess.run(["chmod", "-R", "u+w", str(source), str(home)], check=True)
    assert result.returncode == 0, result.stderr
    module_file, cache_folder = result.stdout.split()
    assert module_file.startswith(str(source))
    assert cache_folder == str(scratch / f"skyscatter-numba-{os.getuid()}")
