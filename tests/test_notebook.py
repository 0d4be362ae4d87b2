"""docs/notebook.ipynb runs from top to bottom in a real Jupyter kernel (nbclient + ipykernel),
stored without outputs; its plot and its picture come back as PNGs that Pillow reads.

The kernel is this interpreter (jupyter_client runs a kernel spec's "python" as
`sys.executable`) and inherits this process's environment: the session's table cache
(`SKYSCATTER_CACHE_DIR`, tests/conftest.py) and the source tree on PYTHONPATH.
"""

from __future__ import annotations

import base64
import io
import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

NOTEBOOK = Path(__file__).resolve().parents[1] / "docs" / "notebook.ipynb"


def test_notebook_is_stored_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(notebook)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert code and all(not cell.outputs and cell.execution_count is None for cell in code)


def _png(output) -> Image.Image:
    return Image.open(io.BytesIO(base64.b64decode(output["data"]["image/png"])))


@pytest.mark.slow  # a kernel and two sets of earth tables: 100 s alone, less where cached
def test_notebook_runs_in_a_kernel(monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    source = str(Path(__file__).resolve().parents[1] / "src")
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [source, *filter(None, [os.environ.get("PYTHONPATH")])]))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    # iopub_timeout: on a loaded machine a plot's PNG can reach the client seconds after the
    # cell's reply; nbclient's default (4 s) would drop it silently
    client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                                     iopub_timeout=120, raise_on_iopub_timeout=True,
                                     resources={"metadata": {"path": str(NOTEBOOK.parent)}})
    client.execute()  # raises CellExecutionError, with the cell and its traceback, on error
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert all(output.output_type != "error" for cell in code for output in cell.outputs)
    # the almucantar plot: a line in each of the three colours matplotlib was given
    plot = next(o for o in code[2].outputs if "image/png" in o.get("data", {}))
    pixels = np.asarray(_png(plot).convert("RGB"), dtype=int)
    for colour in ((31, 119, 180), (44, 160, 44), (214, 39, 40)):  # tab:blue, green, red
        assert (np.abs(pixels - colour).max(axis=2) <= 8).sum() > 50, colour
    # the picture: SkyImage._repr_png_, 96 x 96, a blue clear sky at the zenith
    picture = next(o for o in code[-1].outputs if "image/png" in o.get("data", {}))
    assert "SkyImage(96 x 96 pixels" in picture["data"]["text/plain"]
    image = _png(picture).convert("RGB")
    assert image.size == (96, 96)
    red, _, blue = image.getpixel((48, 48))
    assert blue > red  # Rayleigh scattering: the clear sky is blue overhead
