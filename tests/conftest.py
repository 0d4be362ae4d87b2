"""Test-session settings: precomputed tables go to one temporary cache directory shared by the
whole session (never the user's cache), so each atmosphere/wavelength set is computed once."""

import pytest


@pytest.fixture(scope="session", autouse=True)
def table_cache_directory(tmp_path_factory):
    directory = tmp_path_factory.mktemp("table-cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("SKYSCATTER_CACHE_DIR", str(directory))
        yield directory
