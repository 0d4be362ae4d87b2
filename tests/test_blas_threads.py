"""OpenBLAS's idle threads: the thread timeout set before numpy loads it, a user's kept."""

from __future__ import annotations

import sys

import pytest

from skyscatter import blas_threads


@pytest.mark.parametrize(("chosen", "numpy_loaded", "value", "sleeping"), [
    (None, False, "4", True),  # ours, before numpy loads OpenBLAS
    (None, True, "4", False),  # too late: OpenBLAS read no value, its default spin
    ("10", False, "10", True),  # a user's short spin is kept
    ("28", True, "28", False),  # a user's long one too, and said so
    ("often", False, "often", False),  # not a number: OpenBLAS's default
])
def test_the_timeout_is_set_unless_chosen_and_in_effect_only_before_numpy(
        monkeypatch, chosen, numpy_loaded, value, sleeping):
    if chosen is None:
        monkeypatch.delenv(blas_threads.TIMEOUT_VARIABLE, raising=False)
    else:
        monkeypatch.setenv(blas_threads.TIMEOUT_VARIABLE, chosen)
    if not numpy_loaded:
        monkeypatch.delitem(sys.modules, "numpy", raising=False)
    monkeypatch.setattr(blas_threads, "_sleeping", None)
    blas_threads.let_idle_threads_sleep()
    assert blas_threads.os.environ[blas_threads.TIMEOUT_VARIABLE] == value
    assert blas_threads.idle_threads_sleep() is sleeping
