"""An image of the whole sky as a renderer's light: the sun as a directional light and the
rest as diffuse irradiance in spherical harmonics.

The diffuse irradiance E(n) = int L(w) max(n . w, 0) dw of a surface facing n, for the sky
without the sun's disk, is kept as the 9 real spherical-harmonic coefficients of orders
l <= 2 per colour channel (Ramamoorthi & Hanrahan 2001, "An efficient representation for
irradiance environment maps", SIGGRAPH, doi:10.1145/383259.383317, eqs. 3, 7-8):

    L_lm = sum_pixels L Y_lm(w) dOmega,   E_lm = A_l L_lm,   A_0 = pi, A_1 = 2 pi / 3, A_2 = pi / 4
    E(n) = sum_lm E_lm Y_lm(n)

with Y_00 = 0.282095; Y_1-1, Y_10, Y_11 = 0.488603 (y, z, x); Y_2-2, Y_2-1, Y_21 = 1.092548
(x y, y z, x z); Y_20 = 0.315392 (3 z^2 - 1); Y_22 = 0.546274 (x^2 - y^2), in that order
(l, then m from -l to l). The directions are those of the cube map (`render.cube_map`): x east,
y up, z south. The sun's disk, where the image holds it, is taken out as the delta function it
nearly is: its direct irradiance E_sun adds E_sun Y_lm(s) to L_lm, which is subtracted (its disk,
a quarter of a degree across, is far below the resolution of order 2); the sun is given as a
directional light: its
direction, its illuminance E_v = 683 lm/W int E_sun V d(lambda) [lux] and its linear RGB, in
the units of the image's EXR (1.0 = 1 cd m^-2 of luminance: the RGB of an irradiance is then in
lux, its luminance the illuminance), colours outside the space's gamut (a setting sun's)
desaturated into it at constant luminance as in the EXR (`spectrum.colour.into_gamut`).
"""

from __future__ import annotations

import numpy as np

from skyscatter.render.scene import SkyImage
from skyscatter.spectrum.colour import (
    into_gamut,
    spectral_to_xyz,
    white_balance,
    xyz_to_rgb,
)

__all__ = ["SH_ORDER_NAMES", "environment_light", "sh_basis", "sh_irradiance"]

SH_ORDER_NAMES = ("00", "1-1", "10", "11", "2-2", "2-1", "20", "21", "22")
_CONVOLUTION = np.array([np.pi] + [2.0 * np.pi / 3.0] * 3 + [np.pi / 4.0] * 5)
# ENU (east, north, up) -> the map's axes (east, up, south)
_ENU_TO_MAP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def sh_basis(directions: np.ndarray) -> np.ndarray:
    """The 9 real spherical harmonics (..., 9) of unit `directions` (..., 3) in the map's axes
    (module docstring)."""
    x, y, z = directions[..., 0], directions[..., 1], directions[..., 2]
    return np.stack([np.full_like(x, 0.282095), 0.488603 * y, 0.488603 * z, 0.488603 * x,
                     1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3.0 * z * z - 1.0),
                     1.092548 * x * z, 0.546274 * (x * x - y * y)], axis=-1)


def sh_irradiance(radiance: np.ndarray, directions_enu: np.ndarray,
                  solid_angles: np.ndarray) -> np.ndarray:
    """E_lm (9, n_channels) of the irradiance from `radiance` (h, w, n_channels) seen along
    unit ENU `directions_enu` (h, w, 3) over pixels of `solid_angles` (h, w) [sr] (0 where a
    pixel is not part of the sphere)."""
    basis = sh_basis(directions_enu @ _ENU_TO_MAP.T)
    weighted = basis * solid_angles[..., None]
    moments = np.einsum("hwk,hwc->kc", weighted, radiance)
    return _CONVOLUTION[:, None] * moments


def environment_light(image: SkyImage, directions_enu: np.ndarray, solid_angles: np.ndarray,
                      colour_space: str = "srgb", balance_to_light: bool = False) -> dict:
    """The sun as a directional light and the sky's diffuse irradiance as spherical harmonics
    (module docstring), as a JSON-ready dict, from a `SkyImage` of the whole sphere (a cube map
    or a panorama) with its pixels' directions (h, w, 3) and solid angles (h, w) [sr], in
    `colour_space`, white-balanced to the star's light with `balance_to_light` as its EXR."""
    rgb = into_gamut(xyz_to_rgb(image.xyz(balance_to_light), colour_space), colour_space)
    coefficients = sh_irradiance(np.where(image.valid[..., None], rgb, 0.0), directions_enu,
                                 solid_angles)
    light: dict = {"units": {"sun.illuminance": "lux, on a surface facing the sun",
                             "sun.rgb": "lux: linear RGB whose luminance is the illuminance",
                             "sh_irradiance.rgb": "lux: linear RGB, E(n) = sum E_lm Y_lm(n)"},
                   "colour_space": colour_space,
                   "axes": "x east, y up, z south (the cube map's)"}
    if image.sun is not None:
        sun_xyz = spectral_to_xyz(image.sun.irradiance, image.wavelengths_nm)
        if balance_to_light:
            sun_xyz = white_balance(sun_xyz, image.light_spectrum, image.wavelengths_nm)
        sun_rgb = into_gamut(xyz_to_rgb(sun_xyz, colour_space), colour_space)
        s = _ENU_TO_MAP @ np.asarray(image.sun.direction, dtype=np.float64)
        if image.sun.in_image:
            coefficients -= _CONVOLUTION[:, None] * np.outer(sh_basis(s), sun_rgb)
        light["sun"] = {"direction": _rounded(s), "illuminance": _rounded(sun_xyz[1]),
                        "rgb": _rounded(sun_rgb),
                        "angular_radius_deg": _rounded(np.degrees(image.sun.angular_radius_rad))}
    light["sh_irradiance"] = {"order": list(SH_ORDER_NAMES),
                              "rgb": [_rounded(row) for row in coefficients]}
    return light


def _rounded(values) -> list[float] | float:
    """Numbers to 6 significant digits, for a JSON file people read."""
    array = np.asarray(values, dtype=np.float64)
    rounded = [float(f"{v:.6g}") for v in array.ravel()]
    return rounded[0] if array.ndim == 0 else rounded
