r"""A KTX 2.0 writer for uncompressed float textures (2-D and 3-D, one mip level), the container
engines and glTF tools load without conversion.

Khronos KTX File Format Specification, version 2.0 (registry.khronos.org/KTX/specs/2.0/
ktxspec.v2.html), section numbers below are that document's; the data format descriptor is a
Khronos Data Format Specification 1.3 basic descriptor block (registry.khronos.org/
DataFormat/specs/1.3/dataformat.1.3.html, section 5). Little-endian throughout.

  identifier (§3.1)   «KTX 20»\r\n\x1A\n (12 bytes)
  header (§3.2)       vkFormat, typeSize, pixelWidth, pixelHeight, pixelDepth (0 for 2-D),
                      layerCount 0, faceCount 1, levelCount 1, supercompressionScheme 0: uint32
  index (§3.3)        dfdByteOffset, dfdByteLength, kvdByteOffset, kvdByteLength: uint32;
                      sgdByteOffset, sgdByteLength: uint64 (0: no supercompression data)
  level index (§3.4)  byteOffset, byteLength, uncompressedByteLength: uint64 per level
  DFD (§3.5)          uint32 dfdTotalSize, then one basic block: vendorId 0 | descriptorType 0,
                      versionNumber 2 | descriptorBlockSize 24 + 16 n, colorModel RGBSDA (1),
                      colorPrimaries, transferFunction LINEAR (1), flags 0, texel block 1x1x1x1
                      (stored as 0s), bytesPlane0 = texel size; per channel a 16-byte sample:
                      bitOffset uint16, bitLength - 1 uint8, channelType (channel id R 0, G 1,
                      B 2, A 15, with the FLOAT 0x80 and SIGNED 0x40 qualifiers), position 0,
                      sampleLower -1.0 and sampleUpper 1.0 as IEEE 754 binary32 bits (the
                      float formats' normalised range, Data Format spec §5.19-5.20)
  key/value (§3.6)    uint32 keyAndValueByteLength, key NUL value NUL, padded to 4 bytes
  level data (§3.9)   starts at a multiple of lcm(texel size, 4) (§3.8, no supercompression);
                      z slices of y rows of x texels, row 0 first (texture coordinate 0)

Formats: VK_FORMAT_R16G16B16A16_SFLOAT (97, typeSize 2) and VK_FORMAT_R32G32B32A32_SFLOAT
(109, typeSize 4): Vulkan 1.3 specification, VkFormat.
"""

from __future__ import annotations

import math
import struct

import numpy as np

__all__ = ["IDENTIFIER", "PRIMARIES", "VK_FORMATS", "ktx2_bytes"]

IDENTIFIER = b"\xabKTX 20\xbb\r\n\x1a\n"
VK_FORMATS = {np.dtype(np.float16): 97, np.dtype(np.float32): 109}  # RGBA SFLOAT
# Data Format spec §5.7, khr_df_primaries_e: what a colour table's channels are
PRIMARIES = {"unspecified": 0, "bt709": 1, "bt2020": 4, "ciexyz": 5, "aces": 6, "acescc": 7,
             "displayp3": 10}
_MODEL_RGBSDA = 1
_TRANSFER_LINEAR = 1
_CHANNEL_IDS = (0, 1, 2, 15)  # R, G, B, A
_FLOAT_SIGNED = 0x80 | 0x40
_MINUS_ONE, _ONE = 0xBF800000, 0x3F800000  # -1.0f, 1.0f


def _dfd(texel_bytes: int, channel_bytes: int, primaries: int) -> bytes:
    """The data format descriptor of an RGBA float format (module docstring)."""
    block = struct.pack("<IHHBBBB4B8B", 0, 2, 24 + 16 * 4, _MODEL_RGBSDA, primaries,
                        _TRANSFER_LINEAR, 0, 0, 0, 0, 0, texel_bytes, 0, 0, 0, 0, 0, 0, 0)
    for k, channel in enumerate(_CHANNEL_IDS):
        block += struct.pack("<HBB4BII", 8 * channel_bytes * k, 8 * channel_bytes - 1,
                             _FLOAT_SIGNED | channel, 0, 0, 0, 0, _MINUS_ONE, _ONE)
    return struct.pack("<I", 4 + len(block)) + block


def _key_values(entries: dict[str, str]) -> bytes:
    """Key/value data, keys sorted (§3.6: sorted by key's code points), each padded to 4."""
    out = b""
    for key in sorted(entries):
        pair = key.encode() + b"\0" + entries[key].encode() + b"\0"
        out += struct.pack("<I", len(pair)) + pair + b"\0" * (-len(pair) % 4)
    return out


def ktx2_bytes(texels: np.ndarray, primaries: str = "unspecified",
               writer: str = "skyscatter") -> bytes:
    """The KTX 2.0 file of `texels`, shape (height, width, 4) for a 2-D texture or (depth,
    height, width, 4) for a 3-D one, float16 or float32 (RGBA SFLOAT), one mip level;
    `primaries` one of PRIMARIES (the DFD's colorPrimaries), `writer` the KTXwriter entry."""
    texels = np.ascontiguousarray(texels)
    if texels.dtype not in VK_FORMATS or texels.ndim not in (3, 4) or texels.shape[-1] != 4:
        raise ValueError(f"ktx2_bytes: need float16/float32 texels (..., 4), got "
                         f"{texels.dtype} {texels.shape}")
    depth = texels.shape[0] if texels.ndim == 4 else 0
    height, width = texels.shape[-3:-1]
    channel_bytes = texels.dtype.itemsize
    texel_bytes = 4 * channel_bytes
    dfd = _dfd(texel_bytes, channel_bytes, PRIMARIES[primaries])
    kvd = _key_values({"KTXwriter": writer, "KTXorientation": "rdi" if depth else "rd"})
    data = texels.astype(texels.dtype.newbyteorder("<"), copy=False).tobytes()
    dfd_offset = 12 + 9 * 4 + 4 * 4 + 2 * 8 + 3 * 8  # identifier, header, index, 1 level
    kvd_offset = dfd_offset + len(dfd)
    alignment = math.lcm(texel_bytes, 4)
    data_offset = -(-(kvd_offset + len(kvd)) // alignment) * alignment
    header = struct.pack("<9I", VK_FORMATS[texels.dtype], channel_bytes, width, height, depth,
                         0, 1, 1, 0)
    index = struct.pack("<4I2Q", dfd_offset, len(dfd), kvd_offset, len(kvd), 0, 0)
    level = struct.pack("<3Q", data_offset, len(data), len(data))
    head = IDENTIFIER + header + index + level + dfd + kvd
    return head + b"\0" * (data_offset - len(head)) + data
