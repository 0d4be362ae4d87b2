"""Test-session settings: precomputed tables go to one temporary cache directory shared by the
whole session (never the user's cache), so each atmosphere/wavelength set is computed once.

The property-based tests (hypothesis) draw new hostile values on every local run, to keep
finding what nobody thought of; under CI (CI=true) they replay one fixed sequence, so that a
landing is decided by the code, not by the draw.
"""

import os

import pytest
from hypothesis import settings

settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
    settings.load_profile("ci")


@pytest.fixture(scope="session", autouse=True)
def table_cache_directory(tmp_path_factory):
    directory = tmp_path_factory.mktemp("table-cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SKYSCATTER_CACHE_DIR", str(directory))
        yield directory


@pytest.fixture(scope="session", autouse=True)
def kernels_compiled_marker(tmp_path_factory):
    """The tests run with compiled kernels: the command line's first-run note would be an
    extra stderr line in the tests that read stderr (tests/test_compile_ahead.py checks it)."""
    from skyscatter import compile_ahead
    marker = tmp_path_factory.mktemp("numba") / "compiled"
    marker.touch()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(compile_ahead, "marker_path", lambda: marker)
        yield marker
