"""Measurement rows from an image: the luminance of N sky pixels of a linear EXR.

The EXR is one `skyscatter render --exr` writes (`api.save_image`): "rgb" content (linear
RGB of the colour space in its header attribute `skyscatter_colour_space`, Y = 1 for
1 cd m^-2; colours outside the gamut were desaturated at constant luminance, so Y survives)
or "luminance" content (channel Y [cd m^-2]). The camera is the one that took it (the render
command's camera options), which gives each pixel's view direction in the local east-north-up
frame; with the sun's zenith angle and azimuth (from north towards east) each pixel becomes a
luminance row at its view zenith and azimuth relative to the sun.

Pixels are drawn at random (`seed`) among those inside the camera's image, above the horizon
by `MIN_ELEVATION_DEG`, at least `MIN_SUN_DISTANCE_DEG` from the sun (whose disk and aureole
a camera saturates or blurs), finite and positive.

Public names: `MIN_ELEVATION_DEG`, `MIN_SUN_DISTANCE_DEG`, `image_rows`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skyscatter.errors import InputError
from skyscatter.render.camera import Camera
from skyscatter.render.image_io import read_exr, read_exr_attributes
from skyscatter.render.scene import sun_direction
from skyscatter.spectrum.colour import rgb_to_xyz

__all__ = ["MIN_ELEVATION_DEG", "MIN_SUN_DISTANCE_DEG", "image_rows"]

MIN_ELEVATION_DEG = 2.0  # the horizon's last pixels mix ground and sky
MIN_SUN_DISTANCE_DEG = 5.0  # outside the sun's disk (0.27 deg) and a lens's glare


def image_rows(exr_path: str | Path, camera: Camera, sun_zenith_deg: float,
               sun_azimuth_deg: float = 180.0, *, pixels: int = 200, seed: int = 0
               ) -> list[dict[str, float]]:
    """`pixels` luminance rows (sun_zenith_deg, view_zenith_deg, relative_azimuth_deg,
    luminance [cd m^-2]) sampled from the EXR (module docstring); InputError for an EXR
    without luminance, one whose size is not the camera's, or too few sky pixels."""
    image, names = read_exr(exr_path)
    attributes = read_exr_attributes(exr_path)
    if "Y" in names:
        luminance = image[..., names.index("Y")].astype(np.float64)
    elif all(c in names for c in "RGB"):
        space = attributes.get("skyscatter_colour_space", "srgb")
        rgb = np.stack([image[..., names.index(c)] for c in "RGB"], axis=-1)
        luminance = rgb_to_xyz(rgb.astype(np.float64), space)[..., 1]
    else:
        raise InputError(f"image {exr_path}: no luminance: give an EXR of `skyscatter render "
                         "--exr` (rgb or luminance content)", key="image", value=str(exr_path))
    directions, inside = camera.directions()
    if directions.shape[:2] != luminance.shape:
        raise InputError(f"image {exr_path} is {luminance.shape[1]} x {luminance.shape[0]} "
                         f"pixels, the camera {directions.shape[1]} x {directions.shape[0]}: "
                         "give the camera options it was rendered with", key="image",
                         value=str(exr_path))
    sun = sun_direction(sun_zenith_deg, sun_azimuth_deg)
    view_zenith = np.degrees(np.arccos(np.clip(directions[..., 2], -1.0, 1.0)))
    from_sun = np.degrees(np.arccos(np.clip(directions @ sun, -1.0, 1.0)))
    usable = (inside & (view_zenith <= 90.0 - MIN_ELEVATION_DEG)
              & (from_sun >= MIN_SUN_DISTANCE_DEG) & np.isfinite(luminance) & (luminance > 0))
    candidates = np.flatnonzero(usable)
    if candidates.size < pixels:
        raise InputError(f"image {exr_path}: {candidates.size} sky pixels (above the horizon, "
                         f"{MIN_SUN_DISTANCE_DEG:g} deg from the sun), fewer than {pixels}",
                         key="pixels", value=pixels)
    chosen = np.sort(np.random.default_rng(seed).choice(candidates, pixels, replace=False))
    view = directions.reshape(-1, 3)[chosen]
    azimuth = np.degrees(np.arctan2(view[:, 0], view[:, 1])) - sun_azimuth_deg
    return [{"sun_zenith_deg": float(sun_zenith_deg), "view_zenith_deg": float(z),
             "relative_azimuth_deg": float(a), "luminance": float(y)}
            for z, a, y in zip(view_zenith.ravel()[chosen], azimuth,
                               luminance.ravel()[chosen], strict=True)]
