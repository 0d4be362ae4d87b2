"""The viewer's generated files match what `python -m skyscatter.viewer.codegen` writes now
(STYLE §11): a change to a shared constant in Python must be regenerated for the GLSL."""

import json

import numpy as np
import pytest

from skyscatter.render import tonemap
from skyscatter.viewer import codegen
from skyscatter.viewer.gpu_tables import FORMAT_VERSION, PHASE_ROW


def test_generated_files_are_current(tmp_path):
    written = codegen.write_generated(tmp_path)
    for path in written:
        shipped = codegen.GENERATED / path.name
        assert shipped.read_text() == path.read_text(), (
            f"{shipped} is stale: run python -m skyscatter.viewer.codegen")


def test_layout_names_the_message_format():
    layout = json.loads(codegen.layout_json())
    assert layout["format_version"] == FORMAT_VERSION
    assert layout["phase_row"] == PHASE_ROW
    assert set(layout["arrays"]) == {"transmittance", "irradiance", "scattering", "phase"}
    assert "#define OPERATOR_ACES 0" in codegen.constants_glsl()


def test_ev100_range_holds_what_the_meter_chooses():
    """The page's EV100 slider spans its meter's extremes: a black night sky (every pixel held
    at the natural night sky's luminance, night-compensated: render.tonemap) and the sun above
    the air metered by the incident-light meter, 133.8 klx (extraterrestrial illuminance,
    Darula, Kittler & Gueymard 2005, Leukos 1(4), 39)."""
    low, high = json.loads(codegen.layout_json())["exposure"]["ev100_range"]
    metered, night = tonemap.night_adapted_exposure(np.zeros((4, 4)), np.ones((4, 4), bool))
    assert low <= metered - night < low + 3.0  # the darkest sky is near the slider's end
    assert metered - night == pytest.approx(-7.69, abs=0.01)  # log2(174e-6 * 8) + 1.80
    assert low <= tonemap.incident_ev100(133.8e3) <= high
