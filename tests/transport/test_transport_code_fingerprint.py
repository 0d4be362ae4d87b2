"""The table cache's code key covers exactly the code the precomputation runs.

References: the functions `precompute_tables` calls, read off its source by hand (the kernels
of each table, `geometry.sun_visible_fraction` through the single-scattering table) and the
lookups that only `LutSolver` calls at render time (`sky_radiance_rays`, `transmittance_rays`);
the split of the table kernels by job, read off the modules' own top-level definitions: the key
must cover all of `_table_build_kernels` and `_table_common_kernels` and none of
`_table_lookup_kernels`.
"""

from __future__ import annotations

import ast
import json

import pytest
from transport_cases import exponential_earth

from skyscatter.transport import code_fingerprint as fingerprint_module
from skyscatter.transport.code_fingerprint import code_fingerprint, reached_definitions
from skyscatter.transport.table_store import table_metadata
from skyscatter.transport.tables import TableResolution

ROOT = ("skyscatter.transport.tables", "precompute_tables")
BUILD = "skyscatter.transport._table_build_kernels"
COMMON = "skyscatter.transport._table_common_kernels"
LOOKUP = "skyscatter.transport._table_lookup_kernels"


@pytest.fixture(scope="module")
def reached():
    return set(reached_definitions([ROOT]))


def test_precomputation_kernels_and_sun_visible_fraction_are_covered(reached):
    for name in ("single_scattering_table", "multiple_scattering_table", "indirect_irradiance",
                 "direct_ground_irradiance", "incoming_radiance"):
        assert (BUILD, name) in reached
    assert ("skyscatter.transport.geometry", "sun_visible_fraction") in reached
    assert ("skyscatter.transport._kernels", "column_table") in reached
    # a module-level constant the precomputation reads
    assert ("skyscatter.transport.tables", "DIRECT_GROUND_SAMPLES") in reached


def test_render_time_lookups_and_error_classes_are_not_covered(reached):
    for name in ("sky_radiance_rays", "transmittance_rays", "aerial_perspective_points",
                 "ground_irradiance_points"):
        assert (LOOKUP, name) not in reached
    assert not any(module == "skyscatter.transport.lut_solver" for module, _ in reached)
    assert ("skyscatter.errors", "InputError") not in reached  # only raised


def _top_level_names(module: str) -> set[str]:
    """The functions and module-level constants `module` defines, read with `ast`."""
    names = set()
    for node in ast.parse(fingerprint_module._module_source(module)).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.Assign):
            names.update(target.id for target in node.targets if isinstance(target, ast.Name))
    return names


def test_the_key_covers_the_build_kernels_whole_and_no_lookup_kernel(reached):
    # The modules split the table kernels by job: everything in the build and common modules
    # runs in the precomputation, nothing in the lookup module does.
    for module in (BUILD, COMMON):
        names = _top_level_names(module)
        assert names, module
        assert {name for name in names if (module, name) not in reached} == set(), module
    lookups = _top_level_names(LOOKUP)
    assert {"sky_radiance_rays", "lit_single_scattering", "EXACT_SINGLE_SAMPLES"} <= lookups
    assert {name for name in lookups if (LOOKUP, name) in reached} == set()


def _edited(module: str, old: str, new: str):
    """A source reader that returns `module` with `old` replaced by `new`."""
    original = fingerprint_module._module_source

    def read(name: str) -> str | None:
        source = original(name)
        if name != module:
            return source
        assert old in source
        return source.replace(old, new, 1)
    return read


def _fingerprint(read=fingerprint_module._module_source) -> dict:
    return reached_definitions([ROOT], read)


def test_an_edit_to_a_lookup_keeps_the_key_and_one_to_precomputed_code_changes_it():
    base = _fingerprint()
    lookup = _fingerprint(_edited(LOOKUP, "def sky_radiance_rays(",
                                  "def unused_helper():\n    return 1\n\n\ndef sky_radiance_rays("))
    assert lookup == base
    comment_only = _fingerprint(_edited("skyscatter.transport.geometry",
                                        "def sun_visible_fraction(r, mu_s, bottom_radius, "
                                        "sun_angular_radius):\n",
                                        "def sun_visible_fraction(r, mu_s, bottom_radius, "
                                        "sun_angular_radius):  # a comment\n"))
    assert comment_only == base
    physics = _fingerprint(_edited("skyscatter.transport.geometry",
                                   "return disk_fraction_above(mu_s,",
                                   "return 0.5 * disk_fraction_above(mu_s,"))
    assert physics != base
    shared = _fingerprint(_edited(COMMON, "i = min(int(f), n - 2)", "i = min(int(f), n - 3)"))
    assert shared[(COMMON, "linear_axis")] != base[(COMMON, "linear_axis")]
    assert (physics[("skyscatter.transport.geometry", "sun_visible_fraction")]
            != base[("skyscatter.transport.geometry", "sun_visible_fraction")])


def test_key_is_deterministic_and_includes_the_phase_function_classes():
    profile = exponential_earth()
    first = table_metadata(profile, TableResolution(), 2, -0.5)["code"]
    code_fingerprint.cache_clear()
    assert table_metadata(profile, TableResolution(), 2, -0.5)["code"] == first
    with_phase = set(reached_definitions([ROOT, ("skyscatter.optics.phase", "RayleighPhase")]))
    assert ("skyscatter.optics.phase", "rayleigh") in with_phase


def test_the_key_covers_the_order_of_the_kernels_record_fields():
    # The typed records the build kernels take are build code: a change to one (here the
    # order of two fields, which numba's typed tuple follows) must change the key.
    base = _fingerprint()
    swapped = _fingerprint(_edited(BUILD, "    bottom_radius: float  # R_b [m]\n"
                                          "    top_radius: float  # R_t [m]\n",
                                   "    top_radius: float  # R_t [m]\n"
                                   "    bottom_radius: float  # R_b [m]\n"))
    assert swapped[(BUILD, "TableGrid")] != base[(BUILD, "TableGrid")]
    assert swapped != base


def test_the_memo_serves_the_fingerprint_until_a_source_the_walk_read_changes(tmp_path,
                                                                              monkeypatch):
    # Reference: the walk itself (no memo). The memo must be read (a forged entry is served
    # while the sources are unchanged) and must give way to the walk when one changes.
    walk = code_fingerprint.__wrapped__
    walked = walk((ROOT,))
    assert walk((ROOT,), (tmp_path,)) == walked
    memo_path = tmp_path / fingerprint_module.MEMO_FILE
    memo = json.loads(memo_path.read_text())
    (entry,) = memo.values()
    assert {BUILD, COMMON} <= set(entry["modules"])
    entry["fingerprint"] = "forged"
    memo_path.write_text(json.dumps(memo))
    assert walk((ROOT,), (tmp_path,)) == "forged"
    edit = _edited(COMMON, "i = min(int(f), n - 2)", "i = min(int(f), n - 3)")
    monkeypatch.setattr(fingerprint_module, "_module_source", edit)
    edited = walk((ROOT,), (tmp_path,))
    assert edited not in ("forged", walked)
    assert walk((ROOT,)) == edited
    memo_path.write_text("{not json")  # a damaged memo is only a miss
    assert walk((ROOT,), (tmp_path,)) == edited


def test_a_memo_beside_the_kernels_serves_a_new_table_cache_and_is_copied_into_it(tmp_path):
    # What `skyscatter compile` leaves beside the kernels serves the first run with a new
    # table cache (a forged entry shows that it was read, not walked), which keeps a copy;
    # the walk itself is the reference for what the copy holds.
    walk = code_fingerprint.__wrapped__
    kernels, tables = tmp_path / "kernels", tmp_path / "tables"
    kernels.mkdir()
    tables.mkdir()
    walked = walk((ROOT,), (kernels,))
    memo_path = kernels / fingerprint_module.MEMO_FILE
    memo = json.loads(memo_path.read_text())
    (entry,) = memo.values()
    entry["fingerprint"] = "from-install"
    memo_path.write_text(json.dumps(memo))
    assert walk((ROOT,), (tables, kernels)) == "from-install"
    copied = json.loads((tables / fingerprint_module.MEMO_FILE).read_text())
    assert copied == memo
    assert walk((ROOT,)) == walked
