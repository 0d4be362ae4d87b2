"""The viewer's generated files match what `python -m skyscatter.viewer.codegen` writes now
(STYLE §11): a change to a shared constant in Python must be regenerated for the GLSL."""

import json

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
