"""Spectral reflectance from an RGB colour, for albedo maps given as ordinary images.

A reflectance is built from three box spectra that split 360-830 nm into blue (< 490 nm),
green (490-590 nm) and red (> 590 nm) bands: rho(lambda) = sum_c k_c box_c(lambda). The
weights k solve A k = rgb, where column c of A is the linear sRGB colour of box_c lit by CIE
D65 (white normalised to Y = 1), so the reflectance reproduces the pixel's colour under D65
(CIE 1931 observer). The boxes add up to 1, hence a grey pixel gives a flat spectrum of the
same value (to 0.03 %: the tabulated D65 is not exactly sRGB's white). Saturated colours that
box spectra cannot make are clipped to [0, 1]. (An RGB-to-spectrum "upsampling" in the spirit
of Smits 1999, J. Graphics Tools 4(4), with a smaller basis.)
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.spectrum.colour import illuminant_spectrum, spectral_to_xyz, xyz_to_rgb
from skyscatter.spectrum.grid import cell_edges, checked_grid

__all__ = ["BAND_EDGES_NM", "reflectance_from_rgb"]

BAND_EDGES_NM = (0.0, 490.0, 590.0, np.inf)  # blue | green | red; our choice of band limits
_FINE_GRID_NM = np.arange(360.0, 831.0, 1.0)


def _band_fractions(wavelengths_nm: np.ndarray) -> np.ndarray:
    """(n_wl, 3): the share of each wavelength's cell (`grid.cell_edges`) in each band."""
    edges = cell_edges(wavelengths_nm)
    low, high = edges[:-1, None], edges[1:, None]
    band_low = np.array(BAND_EDGES_NM[:-1])[None, :]
    band_high = np.array(BAND_EDGES_NM[1:])[None, :]
    overlap = np.clip(np.minimum(high, band_high) - np.maximum(low, band_low), 0.0, None)
    return overlap / (high - low)


@lru_cache(maxsize=1)
def _box_colours() -> np.ndarray:
    """A (3, 3): column c = linear sRGB of box_c under D65, white at Y = 1."""
    illuminant = illuminant_spectrum("D65", _FINE_GRID_NM)
    boxes = _band_fractions(_FINE_GRID_NM)  # (n, 3)
    white_y = spectral_to_xyz(illuminant, _FINE_GRID_NM)[1]
    xyz = spectral_to_xyz((illuminant[:, None] * boxes).T, _FINE_GRID_NM) / white_y  # (3, 3)
    return xyz_to_rgb(xyz, "srgb").T


def reflectance_from_rgb(rgb: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
    """Spectral reflectance (..., n_wl) in [0, 1] whose colour under D65 is the linear sRGB
    `rgb` (..., 3) (module docstring), on the cells of `wavelengths_nm`."""
    colours = np.asarray(rgb, dtype=np.float64)
    weights = np.linalg.solve(_box_colours(), colours.reshape(-1, 3).T).T  # (n, 3)
    spectra = weights @ _band_fractions(checked_grid(wavelengths_nm)).T
    return np.clip(spectra, 0.0, 1.0).reshape(colours.shape[:-1] + (-1,))
