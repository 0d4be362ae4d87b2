"""The scattering table on disk: 16-bit logarithmic codes, differenced and deflated.

Earth's default scattering table holds 63 million float32 values (240 MiB). On disk each
value becomes a 16-bit code of its logarithm: codes 1 .. 65535 step evenly through
[ln(m · LOG_FLOOR), ln(m)], m the table's largest value, so a value comes back within half a
step, a relative error of at most ln(1 / LOG_FLOOR) / (2 · 65534) = 0.053 %; code 0 is zero
(and every value below m · LOG_FLOOR, 30 orders of magnitude under the brightest sky). The
table's values vary smoothly along the view-zenith axis, so each code is stored as its
difference to the one before it on that axis (modulo 2¹⁶); the high and the low bytes of
those differences are deflated (zlib, RFC 1950/1951) apart, one radius slice at a time, the
slices in threads. Earth's table: 240 → 27.6 MiB.

`round_and_pack` rounds the table in place to the values its codes hold, so the run that
computed the tables and every run that reads them back see the same numbers.
"""

from __future__ import annotations

import os
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["LOG_FLOOR", "PackedTable", "round_and_pack", "unpack"]

LOG_FLOOR = 1e-30  # values below this fraction of the table's largest are stored as zero
_CODE_STEPS = 65534  # codes 1 .. 65535; 0 is zero
_ZLIB_LEVEL = 1  # Earth's table: 27.6 MiB in 0.9 s of CPU; level 6: 24.5 MiB in 2.8 s
# ln of a float32 value from its bits, (exponent - 127) ln 2 + ln(1 + mantissa), the second
# term interpolated linearly in a table of ln(1 + k / 2^12): within (2^-12)^2 / 8 = 7.5e-9
# (|d^2 ln(1 + x) / dx^2| <= 1 on [0, 1]), 7e-6 of a code step; Earth's table in half the time
_MANTISSA_TABLE_BITS = 12
_LN2 = float(np.log(2.0))
_LN_MANTISSA = np.log1p(np.arange(2**_MANTISSA_TABLE_BITS + 1) / 2**_MANTISSA_TABLE_BITS)


@dataclass(frozen=True)
class PackedTable:
    """A packed table: its shape, the logarithms its codes span, and per slice along the first
    axis the deflated high and low bytes of the code differences."""

    shape: tuple[int, ...]
    log_low: float
    log_high: float
    high_bytes: tuple[bytes, ...]
    low_bytes: tuple[bytes, ...]


def round_and_pack(table: np.ndarray) -> PackedTable:
    """Pack a float32 `table` (axes: radius, view zenith, any others; values >= 0) and round
    it in place to the values the packed form holds (`unpack` gives them back exactly)."""
    if table.dtype != np.float32 or table.ndim < 2 or not table.flags.c_contiguous:
        raise ValueError("round_and_pack takes a C-contiguous float32 table of >= 2 axes, "
                         f"not {table.dtype} of shape {table.shape}")
    largest = float(table.max(initial=0.0))
    log_high = np.log(largest) if largest > 0.0 else 0.0
    log_low = log_high + np.log(LOG_FLOOR) if largest > 0.0 else 0.0
    values = _code_values(log_low, log_high)
    step = _code_step(log_low, log_high)
    slices = table.reshape(table.shape[0], table.shape[1], -1)

    def pack_slice(i: int) -> tuple[bytes, bytes]:
        high = np.empty(slices[i].size, dtype=np.uint8)
        low = np.empty(slices[i].size, dtype=np.uint8)
        _encode_slice(slices[i], slices[i].view(np.uint32), log_low, step, values,
                      _LN_MANTISSA, high, low)
        return zlib.compress(high, _ZLIB_LEVEL), zlib.compress(low, _ZLIB_LEVEL)

    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:
        packed = list(pool.map(pack_slice, range(table.shape[0])))
    return PackedTable(tuple(table.shape), float(log_low), float(log_high),
                       tuple(high for high, _ in packed), tuple(low for _, low in packed))


def unpack(packed: PackedTable) -> np.ndarray:
    """The float32 table `packed` holds. Raises ValueError when a slice does not inflate to
    exactly its size (a damaged or foreign entry)."""
    shape = packed.shape
    if len(shape) < 2 or min(shape) < 0 or len(packed.high_bytes) != shape[0] or len(
            packed.low_bytes) != shape[0] or not packed.log_low <= packed.log_high:
        raise ValueError(f"packed table of shape {shape} with {len(packed.high_bytes)} and "
                         f"{len(packed.low_bytes)} slices, logarithms {packed.log_low} to "
                         f"{packed.log_high}")
    table = np.empty(shape, dtype=np.float32)
    slices = table.reshape(shape[0], shape[1], -1)
    values = _code_values(packed.log_low, packed.log_high)

    def unpack_slice(i: int) -> None:
        size = slices[i].size
        high = _inflate(packed.high_bytes[i], size)
        low = _inflate(packed.low_bytes[i], size)
        _decode_slice(high, low, values, slices[i])

    with ThreadPoolExecutor(os.cpu_count() or 1) as pool:
        list(pool.map(unpack_slice, range(shape[0])))
    return table


def _inflate(data: bytes, size: int) -> np.ndarray:
    """The `size` bytes deflated in `data`; ValueError unless it holds exactly that many."""
    inflater = zlib.decompressobj()
    try:
        raw = inflater.decompress(data, size)
    except zlib.error as error:
        raise ValueError(f"a packed slice does not inflate ({error})") from None
    if len(raw) != size or not inflater.eof or inflater.unconsumed_tail or inflater.unused_data:
        raise ValueError(f"a packed slice inflates to other than its {size} bytes")
    return np.frombuffer(raw, dtype=np.uint8)


def _code_step(log_low: float, log_high: float) -> float:
    """The step in ln(value) from one code to the next."""
    return (log_high - log_low) / _CODE_STEPS


def _code_values(log_low: float, log_high: float) -> np.ndarray:
    """The float32 value of each code: 0 for code 0, exp(log_low + (k - 1) step) for k >= 1."""
    steps = np.arange(_CODE_STEPS + 1, dtype=np.float64)
    values = np.exp(log_low + steps * _code_step(log_low, log_high))
    return np.concatenate(([0.0], values)).astype(np.float32)


@njit(cache=True, nogil=True)
def _encode_slice(table, bits, log_low, step, values, ln_mantissa, high, low):
    """Codes of `table` (view zenith, the rest; `bits`: the same memory as uint32) differenced
    along its first axis into the `high` and `low` bytes; each value rounded in place to its
    code's value. ln from the bits (`_LN_MANTISSA`)."""
    n_mu, n_rest = table.shape
    previous = np.zeros(n_rest, dtype=np.int64)
    floor = np.exp(log_low) if step > 0.0 else np.inf
    shift = 23 - _MANTISSA_TABLE_BITS
    to_fraction = 1.0 / (1 << shift)
    for i in range(n_mu):
        for j in range(n_rest):
            value = table[i, j]
            code = 0
            if value >= floor:
                word = np.int64(bits[i, j])
                exponent = (word >> 23) & 0xFF
                if exponent == 0:  # subnormal
                    ln = np.log(np.float64(value))
                else:
                    mantissa = word & 0x7FFFFF
                    k = mantissa >> shift
                    below = ln_mantissa[k]
                    ln = ((exponent - 127) * _LN2 + below
                          + (mantissa & ((1 << shift) - 1)) * to_fraction
                          * (ln_mantissa[k + 1] - below))
                code = min(1 + int(np.rint((ln - log_low) / step)), _CODE_STEPS + 1)
            table[i, j] = values[code]
            difference = (code - previous[j]) & 0xFFFF
            previous[j] = code
            high[i * n_rest + j] = difference >> 8
            low[i * n_rest + j] = difference & 0xFF


@njit(cache=True, nogil=True)
def _decode_slice(high, low, values, table):
    """Inverse of `_encode_slice`: the running sums of the differences, as values."""
    n_mu, n_rest = table.shape
    code = np.zeros(n_rest, dtype=np.int64)
    for i in range(n_mu):
        for j in range(n_rest):
            k = i * n_rest + j
            code[j] = (code[j] + (np.int64(high[k]) << 8) + low[k]) & 0xFFFF
            table[i, j] = values[code[j]]
