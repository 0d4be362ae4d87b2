"""Running the `skyscatter` command in the tests: in this process (`run_cli`), or in a child
process under which file permissions apply even for root (`unprivileged_prefix`)."""

from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from skyscatter.cli import main


def run_cli(capsys, argv: list[str]) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of `skyscatter argv`, in this process."""
    try:
        code = main(argv)
    except SystemExit as exit_:
        code = 0 if exit_.code is None else exit_.code
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def unprivileged_prefix() -> list[str]:
    """A command prefix under which folder and file permissions apply (root ignores them);
    skips the test where there is none."""
    if os.geteuid() != 0:
        return []
    prefix = ["setpriv", "--inh-caps=-all", "--bounding-set=-all"]
    if shutil.which("setpriv") is None or subprocess.run([*prefix, "true"]).returncode != 0:
        pytest.skip("running as root without setpriv: read-only folders are writable")
    return prefix
