"""The scattering table's packed form (`transport/table_packing.py`): every value comes back
within half a step of its 16-bit logarithmic code, the closed-form bound
ln(1 / LOG_FLOOR) / (2 · 65534); values under the floor come back as zero; the table is rounded
in place to exactly what comes back; a damaged slice is refused, never read as numbers."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.transport.table_packing import LOG_FLOOR, PackedTable, round_and_pack, unpack

# half of one code step in ln, as the largest relative error of a value above the floor (plus
# float32's own rounding of the value, 6e-8)
HALF_STEP = np.expm1(np.log(1.0 / LOG_FLOOR) / (2 * 65534)) + 1e-7


def radiance_like_table(seed=1):
    """Values over 36 decades and exact zeros, smooth along the second (view-zenith) axis,
    as the scattering table is."""
    rng = np.random.default_rng(seed)
    shape = (5, 64, 7, 3)
    zenith = np.linspace(0.0, 1.0, shape[1])[None, :, None, None]
    exponent = rng.uniform(-34.0, 0.3, (5, 1, 7, 3)) + 2.0 * np.sin(3.0 * zenith)
    table = (10.0 ** exponent).astype(np.float32)
    table[rng.random(shape) < 0.1] = 0.0
    return table


def test_values_come_back_within_half_a_code_step_and_the_table_is_rounded_to_them():
    exact = radiance_like_table()
    table = exact.copy()
    restored = unpack(round_and_pack(table))
    np.testing.assert_array_equal(restored, table)  # rounded in place to what comes back
    above = exact >= exact.max() * LOG_FLOOR
    error = np.abs(restored[above] / exact[above].astype(float) - 1.0)
    assert error.max() <= HALF_STEP
    assert error.max() > 0.5 * HALF_STEP  # the bound is the codes', not a loose one
    assert np.all(restored[~above] == 0.0)
    assert np.count_nonzero(~above & (exact > 0)) > 0  # the floor was exercised


def test_the_largest_value_and_an_all_zero_table_survive():
    table = radiance_like_table()
    largest = float(table.max())
    restored = unpack(round_and_pack(table))
    assert abs(float(restored.max()) / largest - 1.0) <= HALF_STEP
    zeros = np.zeros((2, 3, 4), dtype=np.float32)
    assert np.array_equal(unpack(round_and_pack(zeros)), zeros)


def test_smooth_tables_shrink():
    # a table smooth along its view-zenith axis packs to a fraction of its float32 bytes
    table = radiance_like_table()
    table[table == 0.0] = 1e-3
    packed = round_and_pack(table)
    stored = sum(len(b) for b in packed.high_bytes + packed.low_bytes)
    assert stored < 0.5 * table.nbytes


@pytest.mark.parametrize("damage", ["truncated", "garbage", "longer", "slices"])
def test_a_damaged_packed_table_is_refused(damage):
    packed = round_and_pack(radiance_like_table())
    high = list(packed.high_bytes)
    if damage == "truncated":
        high[2] = high[2][: len(high[2]) // 2]
    elif damage == "garbage":
        high[2] = bytes(range(256)) * 4
    elif damage == "longer":  # a slice that inflates to more than its size
        high[2] = round_and_pack(np.ones((2, 64, 7, 3), np.float32)).high_bytes[0] * 2
    else:
        high = high[:-1]
    with pytest.raises(ValueError, match="slice|packed"):
        unpack(PackedTable(packed.shape, packed.log_low, packed.log_high, tuple(high),
                           packed.low_bytes))


def test_only_contiguous_float32_tables_are_packed():
    with pytest.raises(ValueError, match="float32"):
        round_and_pack(np.ones((3, 4, 5)))
    with pytest.raises(ValueError, match="float32"):
        round_and_pack(np.ones((3, 4, 5), np.float32)[:, ::2])
