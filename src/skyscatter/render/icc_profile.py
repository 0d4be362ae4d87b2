"""ICC display profiles of the RGB spaces, for the PNGs of wide gamuts.

A PNG's pixels are 8-bit codes of linear RGB in `--colour-space` through the sRGB transfer
curve (`tonemap.to_srgb8`). An image viewer takes untagged pixels for sRGB, so Display P3 or
Rec. 2020 pixels would be shown with sRGB's narrower primaries: washed out. Those PNGs carry
an ICC profile (ICC.1:2022, version 4.4, "Image technology colour management - Architecture,
profile format and data structure", www.color.org) of the matrix/TRC kind that says exactly
what the pixels are:

- `rXYZ`, `gXYZ`, `bXYZ`: the columns of the space's normalised primary matrix (its primaries
  and white, `spectrum.colour`), adapted from its white to the profile connection space's D50
  (X, Y, Z) = (0.9642, 1, 0.8249) by the Bradford transform, which `chad` records;
- `rTRC`, `gTRC`, `bTRC`: the sRGB curve as a parametric curve (type 3, IEC 61966-2-1:
  Y = ((X + 0.055) / 1.055)^2.4 above 0.04045, X / 12.92 below);
- `wtpt` (D50, as version 4 has it), `desc` and `cprt`.

sRGB PNGs get the standard `sRGB` chunk instead (PNG 1.2, ISO/IEC 15948:2004, 11.3.3.5,
rendering intent perceptual). Numbers are s15Fixed16 (ICC.1 4.6). Read back by Pillow's
littleCMS in tests/render/test_icc_profile.py.
"""

from __future__ import annotations

import struct

import numpy as np

from skyscatter.spectrum.colour import (
    RGB_SPACES,
    chromatic_adaptation,
    normalised_primary_matrix,
    rgb_space_chromaticities,
)

__all__ = ["PCS_WHITE_XYZ", "icc_profile"]

PCS_WHITE_XYZ = (0.9642, 1.0, 0.8249)  # ICC.1 7.2.16: the D50 of the connection space
# IEC 61966-2-1 as ICC parametric curve type 3: g, a, b, c, d
_SRGB_CURVE = (2.4, 1.0 / 1.055, 0.055 / 1.055, 1.0 / 12.92, 0.04045)


def _s15(value: float) -> bytes:
    return struct.pack(">i", round(value * 65536.0))


def _xyz_tag(xyz) -> bytes:
    return b"XYZ \0\0\0\0" + b"".join(_s15(v) for v in xyz)


def _text_tag(text: str) -> bytes:
    """multiLocalizedUnicodeType with one en-US record."""
    data = text.encode("utf-16-be")
    return (b"mluc\0\0\0\0" + struct.pack(">II", 1, 12) + b"enUS"
            + struct.pack(">II", len(data), 28) + data)


def _curve_tag() -> bytes:
    return b"para\0\0\0\0" + struct.pack(">HH", 3, 0) + b"".join(_s15(v) for v in _SRGB_CURVE)


def _padded(data: bytes) -> bytes:
    return data + b"\0" * (-len(data) % 4)


def icc_profile(space: str) -> bytes:
    """An ICC version 4 display profile (module docstring) of one of `RGB_SPACES` with the
    sRGB transfer curve: the bytes to embed in a PNG."""
    xy = np.array(rgb_space_chromaticities(space)).reshape(4, 2)
    white = np.array([xy[3, 0] / xy[3, 1], 1.0, (1.0 - xy[3].sum()) / xy[3, 1]])
    colorants = normalised_primary_matrix(xy[:3], xy[3]).T  # rows: the primaries' XYZ
    adapted = chromatic_adaptation(colorants, white, np.array(PCS_WHITE_XYZ))
    chad = chromatic_adaptation(np.eye(3), white, np.array(PCS_WHITE_XYZ)).T
    curve = _curve_tag()
    tags = [(b"desc", _text_tag(f"skyscatter {RGB_SPACES[space]} (sRGB curve)")),
            (b"cprt", _text_tag("No copyright, use freely")),
            (b"wtpt", _xyz_tag(PCS_WHITE_XYZ)),
            (b"rXYZ", _xyz_tag(adapted[0])), (b"gXYZ", _xyz_tag(adapted[1])),
            (b"bXYZ", _xyz_tag(adapted[2])),
            (b"rTRC", curve), (b"gTRC", curve), (b"bTRC", curve),
            (b"chad", b"sf32\0\0\0\0" + b"".join(_s15(v) for v in chad.ravel()))]
    offset = 128 + 4 + 12 * len(tags)
    table, body, placed = b"", b"", {}
    for signature, data in tags:
        if data not in placed:  # the three curves share one copy
            placed[data] = offset + len(body)
            body += _padded(data)
        table += signature + struct.pack(">II", placed[data], len(data))
    size = offset + len(body)
    header = (struct.pack(">I", size) + b"\0\0\0\0" + bytes([4, 0x40, 0, 0]) + b"mntr"
              + b"RGB XYZ " + struct.pack(">6H", 2026, 1, 1, 0, 0, 0) + b"acsp"
              + b"\0" * 24 + struct.pack(">I", 0) + b"".join(_s15(v) for v in PCS_WHITE_XYZ)
              + b"\0" * 4 + b"\0" * 16 + b"\0" * 28)
    return header + struct.pack(">I", len(tags)) + table + body
