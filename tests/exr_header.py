"""The header of a single-part OpenEXR file read by a parser of the file layout written here
("OpenEXR File Layout", openexr.com), for the tests that check what the library wrote."""

from __future__ import annotations

import struct


def exr_header(data: bytes) -> tuple[dict[str, tuple[str, bytes]], int]:
    """(name -> (type, value bytes), offset after the header) of the OpenEXR file `data`: the
    magic number 20000630 and a version field, then attributes (name NUL, type NUL, int32
    size, value) up to an empty name."""
    assert struct.unpack_from("<i", data, 0)[0] == 20000630
    position, attributes = 8, {}
    while data[position] != 0:
        name_end = data.index(b"\0", position)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        start = type_end + 5
        attributes[data[position:name_end].decode()] = (data[name_end + 1:type_end].decode(),
                                                        data[start:start + size])
        position = start + size
    return attributes, position + 1
