"""`skyscatter export-tables`: bad arguments refused in one line with exit code 2 before any
table is computed, and a folder written whole (the files read back in tests/viewer/
test_table_export.py)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from cli_runner import run_cli, unprivileged_prefix
from skyscatter import api
from skyscatter.errors import InputError

# The tables of tests/test_cli.py's render (--wavelengths 4 --orders 2): one computation a session
TABLES = ["--wavelengths", "4", "--orders", "2"]


@pytest.mark.parametrize(("option", "value", "message"), [
    ("--format", "png", "unknown format 'png'; choose one of exr, ktx2, npz"),
    ("--colour", "lab", "unknown colour 'lab'; choose one of rgb, xyz, spectral"),
    ("--colour-space", "adobe", "unknown colour space 'adobe'; choose one of srgb"),
    ("--precision", "double", "unknown precision 'double'; choose one of half, float"),
])
def test_unknown_choices_are_named_in_one_line(capsys, tmp_path, option, value, message):
    code, out, err = run_cli(capsys, ["export-tables", "earth", option, value, "-o",
                                      str(tmp_path / "out"), "--no-cache"])
    assert code == 2 and out == ""
    assert err.startswith(f"skyscatter: {message}") and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_an_existing_file_or_a_folder_of_other_files_is_refused(capsys, tmp_path):
    (tmp_path / "file").write_text("keep")
    code, _, err = run_cli(capsys, ["export-tables", "earth", "-o", str(tmp_path / "file")])
    assert code == 2 and err == f"skyscatter: cannot write {tmp_path / 'file'}: it is a file; " \
        "give a folder\n"
    (tmp_path / "photos").mkdir()
    (tmp_path / "photos" / "holiday.jpg").write_text("keep")
    code, _, err = run_cli(capsys, ["export-tables", "earth", "-o", str(tmp_path / "photos")])
    assert code == 2 and "it holds other files (holiday.jpg)" in err and err.count("\n") == 1
    assert (tmp_path / "file").read_text() == "keep"
    assert (tmp_path / "photos" / "holiday.jpg").read_text() == "keep"


def test_an_unwritable_folder_is_refused_before_any_work(tmp_path):
    prefix = unprivileged_prefix()
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        result = subprocess.run([*prefix, sys.executable, "-m", "skyscatter.cli", "export-tables",
                                 "earth", "-o", str(locked / "tables"), "--no-cache"],
                                capture_output=True, text=True, timeout=120)
    finally:
        locked.chmod(0o755)
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1] == (f"skyscatter: cannot write {locked / 'tables'}: "
                                              "Permission denied")
    assert "Traceback" not in result.stderr


def test_export_writes_the_folder_and_replaces_an_earlier_export(capsys, tmp_path):
    folder = tmp_path / "earth-tables"
    code, _, err = run_cli(capsys, ["export-tables", "earth", *TABLES, "--format", "ktx2",
                                    "-o", str(folder)])
    assert code == 0, err
    assert sorted(p.name for p in folder.iterdir()) == [
        "irradiance.ktx2", "phase.ktx2", "scattering.ktx2", "skyscatter_tables.glsl",
        "skyscatter_tables.hlsl", "tables.json", "transmittance.ktx2"]
    assert err.splitlines()[-1].startswith("earth: 7 files, ") and str(folder) in err
    code, _, err = run_cli(capsys, ["export-tables", "earth", *TABLES, "--format", "npz",
                                    "--colour", "spectral", "--precision", "float", "-o",
                                    str(folder)])
    assert code == 0, err
    assert sorted(p.name for p in folder.iterdir()) == [
        "skyscatter_tables.glsl", "skyscatter_tables.hlsl", "tables.json", "tables.npz"]
    sidecar = json.loads((folder / "tables.json").read_text())
    assert sidecar["orders"] == 2 and sidecar["channels"] == [
        "S0.418,750000nm", "S0.536,250000nm", "S0.653,750000nm", "S0.771,250000nm"]
    assert sidecar["wavelengths_nm"] == list(api.wavelength_grid(4))
    with np.load(folder / "tables.npz") as archive:
        assert archive["transmittance"].shape == (64, 256, 4)  # Bruneton 2017's sizes
        assert archive["scattering"].shape == (3 * 32, 128, 8 * 40, 4)
        assert archive["scattering"].dtype == np.float32


@pytest.mark.parametrize(("arguments", "message"), [
    (("npz", "lab"), "unknown colour 'lab'"),
    (("tiff", "rgb"), "unknown format 'tiff'"),
])
def test_the_api_refuses_unknown_choices_before_any_work(tmp_path, arguments, message):
    with pytest.raises(InputError, match=message):
        api.export_tables(api.load_atmosphere("earth"), tmp_path / "out", *arguments,
                          options=api.solver_options(api.load_atmosphere("earth"),
                                                     cache_dir=tmp_path / "cache"))
    assert sorted(tmp_path.iterdir()) == []  # no folder, no table cache
