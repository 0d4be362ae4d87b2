"""Radiance HDR files (.hdr, RGBE): the HDR format every engine and image tool reads.

Ward's RGBE encoding (Ward 1991, "Real pixels", Graphics Gems II, 80-83; the Radiance file
format, radsite.lbl.gov, "Radiance File Formats"): each pixel is three 8-bit mantissas sharing
one 8-bit exponent, v = (m + 0.5) / 256 * 2^(e - 128), a relative precision of about 1 % of
the pixel's largest channel; values below 1e-32 are 0. The header

    #?RADIANCE
    FORMAT=32-bit_rle_rgbe
    PRIMARIES=xr yr xg yg xb yb xw yw
    EXPOSURE=179
    (blank line)
    -Y height +X width

names the RGB space's primaries and white, and EXPOSURE = 179 lm/W tells Radiance's own tools
(which read a pixel of 1 as 179 cd m^-2) that the stored values are luminance-scaled: as in the
EXR, 1.0 = 1 cd m^-2, which engines and viewers read as is. Scanlines are written flat (not
run-length encoded), which every reader accepts. Negative channels are written as 0 (the
image is brought into its gamut first: `spectrum.colour.into_gamut`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

__all__ = ["RADIANCE_EFFICACY_LM_PER_W", "hdr_writer", "rgbe_encode"]

RADIANCE_EFFICACY_LM_PER_W = 179.0  # Radiance's white luminous efficacy (Ward 1994, SIGGRAPH)


def rgbe_encode(rgb: np.ndarray) -> np.ndarray:
    """RGBE bytes (h, w, 4) uint8 of non-negative linear RGB (h, w, 3) (module docstring)."""
    rgb = np.maximum(np.nan_to_num(np.asarray(rgb, dtype=np.float64), nan=0.0), 0.0)
    largest = rgb.max(axis=-1)
    mantissa, exponent = np.frexp(largest)  # largest = mantissa 2^exponent, mantissa in [0.5, 1)
    lit = largest > 1e-32
    scale = np.where(lit, mantissa * 256.0 / np.where(lit, largest, 1.0), 0.0)
    out = np.zeros(rgb.shape[:-1] + (4,), dtype=np.uint8)
    out[..., :3] = np.clip(np.floor(rgb * scale[..., None]), 0, 255).astype(np.uint8)
    out[..., 3] = np.where(lit, np.clip(exponent + 128, 0, 255), 0).astype(np.uint8)
    return out


def hdr_writer(rgb: np.ndarray, chromaticities: Sequence[float]) -> Callable[[str], None]:
    """`write(path)` of a Radiance HDR file of linear RGB (h, w, 3) in the space of
    `chromaticities` (xy of R, G, B and white), 1.0 = 1 cd m^-2 (module docstring)."""
    pixels = rgbe_encode(rgb)
    height, width = pixels.shape[:2]
    primaries = " ".join(f"{v:.5f}" for v in chromaticities)
    header = ("#?RADIANCE\n# skyscatter: 1.0 = 1 cd/m^2 of luminance\n"
              "FORMAT=32-bit_rle_rgbe\n"
              f"PRIMARIES={primaries}\nEXPOSURE={RADIANCE_EFFICACY_LM_PER_W:g}\n\n"
              f"-Y {height} +X {width}\n").encode("ascii")
    return lambda path: Path(path).write_bytes(header + pixels.tobytes())
