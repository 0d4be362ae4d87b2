"""The command line's progress bars (`skyscatter.cli_progress`): silent off a terminal,
complete when forced on."""

import io
import sys

from skyscatter.cli_progress import progress


def test_progress_is_silent_when_stderr_is_not_a_terminal(capsys):
    # pytest captures stderr, so it is not a TTY: auto mode shows nothing.
    assert list(progress(["a", "b", "c"], "rendering")) == ["a", "b", "c"]
    assert capsys.readouterr().err == ""


def test_progress_over_a_total_yields_the_range_and_accepts_updates(capsys):
    assert list(progress(4, "rows", enabled=False)) == [0, 1, 2, 3]
    with progress(10, "rows", enabled=False) as bar:
        bar.update(10)
    assert capsys.readouterr().err == ""


def test_progress_forced_on_writes_the_description_to_stderr(monkeypatch):
    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    with progress(3, "rendering sky", enabled=True) as bar:
        bar.update(3)
    assert "rendering sky" in stream.getvalue()
