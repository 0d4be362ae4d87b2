"""Ground albedo from an equirectangular map: what a planet looks like from space.

The map covers the globe: column 0 starts at longitude -180 deg, row 0 at latitude +90 deg
(the layout of NASA's Blue Marble and of most planetary mosaics). Planet-centred coordinates:
z towards the north pole, x towards longitude 0 (`render/scene.py`). Pixels are RGB
reflectances (an sRGB-encoded PNG/JPEG is decoded to linear; EXR and .npy are read as linear)
or one grey channel; each becomes a spectral reflectance with
`spectrum.reflectance.reflectance_from_rgb`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError, read_user_file
from skyscatter.render.image_io import read_exr
from skyscatter.spectrum.colour import decode_srgb_transfer
from skyscatter.spectrum.reflectance import reflectance_from_rgb

__all__ = ["AlbedoMap"]


@dataclass(frozen=True, eq=False)
class AlbedoMap:
    """Linear RGB reflectance (h, w, 3) in [0, 1] over the globe (module docstring)."""

    rgb: np.ndarray

    def __post_init__(self) -> None:
        rgb = np.asarray(self.rgb, dtype=np.float64)
        if rgb.ndim != 3 or rgb.shape[2] != 3 or min(rgb.shape[:2]) < 2:
            raise InputError(f"albedo map: expected an (h, w, 3) image of at least 2 x 2 "
                             f"pixels, got shape {rgb.shape}", key="albedo_map")
        if not np.all(np.isfinite(rgb)) or rgb.min() < 0.0 or rgb.max() > 1.0:
            raise InputError("albedo map: reflectances must be finite and lie in [0, 1] "
                             f"(found {np.nanmin(rgb):.3g} .. {np.nanmax(rgb):.3g}); scale the "
                             "image to reflectance", key="albedo_map", allowed="[0, 1]")
        object.__setattr__(self, "rgb", rgb)

    @classmethod
    def from_image(cls, path: str | os.PathLike[str]) -> AlbedoMap:
        """Read a PNG/JPEG (8 or 16 bit, sRGB-encoded), EXR or .npy (linear) map."""
        source = Path(path)
        rgb = read_user_file(source, _read_linear_rgb, what="albedo map", key="albedo_map",
                             allowed="a PNG, JPEG, EXR or .npy image")
        try:
            return cls(rgb)
        except InputError as error:
            raise InputError(f"{source}: {error}", key="albedo_map", value=str(source)) from None

    def rgb_at(self, points: ArrayLike) -> np.ndarray:
        """Bilinear RGB (..., 3) at the latitude/longitude of planet-centred `points` (..., 3),
        wrapping in longitude."""
        p = np.asarray(points, dtype=np.float64)
        latitude = np.arcsin(np.clip(p[..., 2] / np.linalg.norm(p, axis=-1), -1.0, 1.0))
        longitude = np.arctan2(p[..., 1], p[..., 0])
        h, w = self.rgb.shape[:2]
        row = np.clip((0.5 - latitude / np.pi) * h - 0.5, 0.0, h - 1.0)
        column = ((longitude + np.pi) / (2.0 * np.pi) * w - 0.5) % w
        r0 = np.minimum(row.astype(np.int64), h - 2)
        c0 = column.astype(np.int64) % w
        c1 = (c0 + 1) % w
        a = (row - r0)[..., None]
        b = (column - np.floor(column))[..., None]
        top = (1.0 - b) * self.rgb[r0, c0] + b * self.rgb[r0, c1]
        bottom = (1.0 - b) * self.rgb[r0 + 1, c0] + b * self.rgb[r0 + 1, c1]
        return (1.0 - a) * top + a * bottom

    def spectral(self, points: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
        """Spectral reflectance (..., n_wl) at planet-centred `points` (..., 3)."""
        return reflectance_from_rgb(self.rgb_at(points), wavelengths_nm)


def _read_linear_rgb(source: Path) -> np.ndarray:
    suffix = source.suffix.lower()
    if suffix == ".npy":
        data = np.load(source, allow_pickle=False).astype(np.float64)
    elif suffix == ".exr":
        data, names = read_exr(source)
        data = np.asarray(data, dtype=np.float64)
        if data.ndim == 3 and data.shape[2] != 3 and {"R", "G", "B"} <= set(names):
            data = data[..., [names.index(c) for c in "RGB"]]
    else:
        from PIL import Image

        with Image.open(source) as image:
            sixteen_bit = image.mode in ("I;16", "I;16B", "I")
            if sixteen_bit:
                data = np.asarray(image, dtype=np.float64) / 65535.0
            else:
                data = np.asarray(image.convert("RGB"), dtype=np.float64) / 255.0
        data = decode_srgb_transfer(data)
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[..., 0]
    if data.ndim == 2:
        data = np.repeat(data[..., None], 3, axis=2)
    return data
