"""Image files: OpenEXR for linear HDR data, PNG for display images.

EXR goes through the OpenEXR 3.x Python bindings (`OpenEXR.File`), never imageio: each
channel is written as its own scanline channel ("R", "G", "B" or "Y", ...), ZIP-compressed,
float32 (float16 arrays stay half), so other tools see a standard RGB or luminance image.
PNG goes through Pillow. No timestamps are written: the same image gives the same bytes.

Display images are PNG or JPEG, chosen by the file name's suffix (`display_format`; any other
suffix is refused, never written as PNG under another name). `exr_writer` and
`display_image_writer` return the function that writes one file, so that a caller can stage
several outputs and replace them together (`skyscatter.output_files.staged_outputs`).
Every writer is atomic through `output_files`: a temporary file in the target directory, renamed
onto the target when complete, so a reader never sees a partial file and a failed write leaves
the previous file as it was. Missing parent directories are created. A path that cannot be
written raises `InputError("cannot write <path>: <reason>")`.

Sources: OpenEXR file layout and standard attributes, "Reading and Writing OpenEXR Image
Files with the OpenEXR Library" (openexr.com); PNG, ISO/IEC 15948:2004.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import BinaryIO

import numpy as np
import OpenEXR
from numpy.typing import ArrayLike
from PIL import Image
from PIL.PngImagePlugin import PngInfo

from skyscatter.errors import InputError
from skyscatter.output_files import atomic_write
from skyscatter.render.icc_profile import icc_profile

__all__ = ["DISPLAY_FORMATS", "atomic_write", "display_format", "display_image_writer",
           "exr_writer", "read_exr", "read_exr_attributes", "write_exr", "write_png"]

# The colour spaces whose display images are sRGB (same primaries, white and curve)
SRGB_TAGGED = ("srgb", "rec709")
# Display image formats by file suffix (Pillow's format names)
DISPLAY_FORMATS = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG", ".tif": "TIFF",
                   ".tiff": "TIFF", ".webp": "WEBP"}
JPEG_QUALITY = 95  # with full-resolution chroma: sky gradients without visible blocks

_DEFAULT_CHANNELS = {1: ("Y",), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}
# Channels read back in this order; any others follow in the file's (alphabetical) order.
_CANONICAL_ORDER = ("R", "G", "B", "A")
# Header entries OpenEXR manages itself; user attributes may not replace them.
_RESERVED_ATTRIBUTES = frozenset({
    "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
    "screenWindowCenter", "screenWindowWidth", "type", "tiles", "name", "version", "chunkCount",
})


def write_exr(path: str | os.PathLike[str], image: ArrayLike,
              channel_names: Sequence[str] | None = None,
              attributes: Mapping[str, str] | None = None) -> Path:
    """Write a linear image to an OpenEXR file (scanline, ZIP), atomically; parent directories
    are created. The other arguments as `exr_writer`. Returns the written file."""
    return atomic_write(path, exr_writer(image, channel_names, attributes))


def exr_writer(image: ArrayLike, channel_names: Sequence[str] | None = None,
               attributes: Mapping[str, str] | None = None, *,
               chromaticities: Sequence[float] | None = None,
               white_luminance: float | None = None) -> Callable[[str], None]:
    """Check a linear image for an OpenEXR file; returns `write(path)`, which writes it there.

    Parameters
    ----------
    image : array_like, shape (h, w, c)
        Pixel values, stored as float32 (float16 input stays half). Linear units of the
        caller's choice, e.g. radiance [W m⁻² sr⁻¹] or luminance [cd m⁻²]; say which in
        `attributes`.
    channel_names : sequence of str, length c, optional
        Default ("Y",), ("R", "G", "B") or ("R", "G", "B", "A") for c = 1, 3, 4.
    attributes : mapping of str to str, optional
        Extra string attributes for the header (e.g. {"units": "cd/m^2"}).
    chromaticities : sequence of 8 floats, optional
        CIE xy of the R, G, B primaries and the white (OpenEXR's standard `chromaticities`
        attribute, which compositors and engines read to know the colour space).
    white_luminance : float, optional
        Luminance [cd m⁻²] of RGB = (1, 1, 1) (OpenEXR's `whiteLuminance`).
    """
    arr = np.asarray(image)
    if arr.ndim != 3 or arr.shape[0] < 1 or arr.shape[1] < 1 or arr.shape[2] < 1:
        raise InputError(f"an EXR image must have shape (height, width, channels), got "
                         f"{arr.shape}", key="image", value=arr.shape)
    if not (np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)):
        raise InputError(f"an EXR image must hold numbers, got dtype {arr.dtype}",
                         key="image", value=str(arr.dtype))
    arr = arr if arr.dtype == np.float16 else arr.astype(np.float32, copy=False)
    if channel_names is None:
        if arr.shape[2] not in _DEFAULT_CHANNELS:
            raise InputError(f"give channel_names for an image with {arr.shape[2]} channels",
                             key="channel_names", value=None)
        channel_names = _DEFAULT_CHANNELS[arr.shape[2]]
    names = tuple(channel_names)
    if (len(names) != arr.shape[2] or len(set(names)) != len(names)
            or not all(isinstance(n, str) and n for n in names)):
        raise InputError(f"channel_names {names!r} must be {arr.shape[2]} distinct non-empty "
                         "strings, one per channel", key="channel_names", value=names)
    header: dict[str, object] = {"compression": OpenEXR.ZIP_COMPRESSION,
                                 "type": OpenEXR.scanlineimage}
    for key, value in (attributes or {}).items():
        if not isinstance(key, str) or not isinstance(value, str) or key in _RESERVED_ATTRIBUTES:
            raise InputError(f"EXR attribute {key!r}: {value!r} must map a string that is not a "
                             f"standard header name to a string", key="attributes", value=key)
        header[key] = value
    if chromaticities is not None:
        header["chromaticities"] = tuple(float(v) for v in chromaticities)
    if white_luminance is not None:
        header["whiteLuminance"] = float(white_luminance)
    channels = {name: np.ascontiguousarray(arr[..., k]) for k, name in enumerate(names)}
    return lambda path: OpenEXR.File(header, channels).write(path)


def _open_exr(path: str | os.PathLike[str]) -> OpenEXR.File:
    source = Path(path)
    if not source.is_file():
        raise InputError(f"cannot read {source}: no such file", key="path", value=str(source))
    try:
        return OpenEXR.File(str(source), separate_channels=True)
    except RuntimeError as exc:
        raise InputError(f"cannot read {source}: not a readable OpenEXR file ({exc})",
                         key="path", value=str(source)) from exc


def read_exr(path: str | os.PathLike[str]) -> tuple[np.ndarray, tuple[str, ...]]:
    """Read the first part of an OpenEXR file.

    Returns
    -------
    image : ndarray, shape (h, w, c), float32
        Channel values as stored (half channels are widened to float32).
    channel_names : tuple of str, length c
        R, G, B, A first in that order when present, then the others in file order
        (OpenEXR stores channels alphabetically).
    """
    exr = _open_exr(path)
    channels = exr.channels()
    names = tuple([n for n in _CANONICAL_ORDER if n in channels]
                  + [n for n in channels if n not in _CANONICAL_ORDER])
    planes = [np.asarray(channels[n].pixels) for n in names]
    if any(p.shape != planes[0].shape or p.ndim != 2 for p in planes):
        raise InputError(f"cannot read {path}: subsampled or non-scalar channels are not "
                         "supported", key="path", value=str(path))
    return np.stack(planes, axis=-1).astype(np.float32, copy=False), names


def read_exr_attributes(path: str | os.PathLike[str]) -> dict[str, str]:
    """String attributes of an OpenEXR file's header (those `write_exr` stores)."""
    header = _open_exr(path).header()
    return {k: v for k, v in header.items() if isinstance(v, str) and k not in _RESERVED_ATTRIBUTES}


def display_format(path: str | os.PathLike[str]) -> str:
    """Pillow's format name ("PNG", "JPEG") for a display image at `path`, from its suffix;
    InputError naming the supported suffixes for any other."""
    suffix = Path(path).suffix.lower()
    if suffix not in DISPLAY_FORMATS:
        hint = "; a linear EXR is written with --exr" if suffix == ".exr" else ""
        raise InputError(f"cannot write a display image as {str(path)!r}: name it "
                         f"{', '.join(DISPLAY_FORMATS)}{hint}", key="path", value=str(path),
                         allowed=", ".join(DISPLAY_FORMATS))
    return DISPLAY_FORMATS[suffix]


def display_image_writer(rgb8: ArrayLike, text: Mapping[str, str] | None = None,
                         image_format: str = "PNG", *,
                         colour_space: str = "srgb") -> Callable[[str | BinaryIO], None]:
    """Check an 8-bit image (sRGB-encoded codes of `colour_space`); returns `write(target)`,
    which writes it to a path or a binary stream as PNG (with `text` as tEXt chunks), JPEG
    (quality 95, no chroma subsampling, alpha dropped, `text` as one comment), TIFF (8 bits a
    channel, deflate, `text` as its ImageDescription) or WebP (lossless, the codes exactly;
    no `text`). sRGB and Rec. 709 images are tagged sRGB in a PNG (its `sRGB` chunk) and
    untagged (read as sRGB) in the others; the wide gamuts carry an ICC profile of their
    primaries (`render.icc_profile`), so viewers show their colours.

    Parameters
    ----------
    rgb8 : array_like of uint8, shape (h, w, 3) or (h, w, 4)
        sRGB-encoded codes (see `tonemap.to_srgb8`); a 4th channel is alpha.
    text : mapping of str to str, optional
        Metadata (e.g. {"Software": "skyscatter", "Description": ...}).
    image_format : {"PNG", "JPEG", "TIFF", "WEBP"}
        A value of `DISPLAY_FORMATS` (see `display_format`).
    colour_space : str
        The RGB space of the codes (`spectrum.colour.RGB_SPACES`).
    """
    arr = np.asarray(rgb8)
    if arr.dtype != np.uint8 or arr.ndim != 3 or arr.shape[2] not in (3, 4) or 0 in arr.shape:
        raise InputError(f"a PNG image must be uint8 of shape (height, width, 3 or 4), got "
                         f"{arr.dtype} {arr.shape}", key="rgb8", value=(str(arr.dtype), arr.shape))
    picture = Image.fromarray(np.ascontiguousarray(arr))  # uint8 (h, w, 3|4) -> RGB|RGBA
    profile = {} if colour_space in SRGB_TAGGED else {"icc_profile": icc_profile(colour_space)}
    comment = "; ".join(f"{key}: {value}" for key, value in (text or {}).items())
    if image_format == "JPEG":
        rgb = picture.convert("RGB")
        return lambda target: rgb.save(target, format="JPEG", quality=JPEG_QUALITY,
                                       subsampling=0, comment=comment, **profile)
    if image_format == "TIFF":
        return lambda target: picture.save(target, format="TIFF", compression="tiff_deflate",
                                           description=comment, software="skyscatter",
                                           **profile)
    if image_format == "WEBP":
        return lambda target: picture.save(target, format="WEBP", lossless=True, exact=True,
                                           **profile)
    info = PngInfo()
    if not profile:
        info.add(b"sRGB", b"\0")  # rendering intent: perceptual
    for key, value in (text or {}).items():
        info.add_text(str(key), str(value))
    return lambda target: picture.save(target, format="PNG", pnginfo=info, **profile)


def write_png(path: str | os.PathLike[str], rgb8: ArrayLike,
              text: Mapping[str, str] | None = None, *, colour_space: str = "srgb") -> Path:
    """Write an 8-bit image to a PNG file, atomically; parent directories are created.
    The other arguments as `display_image_writer`. Returns the written file."""
    return atomic_write(path, display_image_writer(rgb8, text, "PNG",
                                                   colour_space=colour_space))
