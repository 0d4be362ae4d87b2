"""Airglow: the faint light the upper atmosphere of the Earth emits all night.

Chemiluminescence in thin layers 85-300 km up makes most of the natural moonless night sky's
light (Roach & Gordon 1973, *The Light of the Night Sky*, Reidel; Leinert et al. 1998, A&AS
127, 1, §6, doi:10.1051/aas:1998105). Each emission is a thin shell at height h_e with a zenith
intensity I (in rayleighs; 1 R = 10¹⁰/4π photons s⁻¹ m⁻² sr⁻¹, a column emission rate of 10⁶
photons cm⁻² s⁻¹). Seen from radius r_0 at zenith angle z, a thin shell is brightened by the
longer slant path through it (van Rhijn 1921, Publ. Astron. Lab. Groningen 31):

    L(z) = L_zenith / sqrt(1 - (r_0 / (R + h_e))² sin² z)

and the air below dims it by the transmittance along the line of sight (the caller's, from the
tables). Typical zenith intensities at mid latitudes, mid solar cycle (Leinert et al. 1998 §6 and
Roach & Gordon 1973; each varies by a factor of about two with the season, the solar cycle and
the night):

| emission | λ [nm] | height [km] | zenith [R] |
|---|---|---|---|
| [OI] green line | 557.7 | 97 | 250 |
| Na D | 589.3 | 92 | 50 |
| [OI] red lines | 630.0, 636.4 | 250 | 60, 20 |
| OH Meinel bands (lumped at band centres) | 731, 777, 791, 828 | 87 | 150, 250, 200, 600 |
| pseudo-continuum (mostly NO₂ + O) | 400-830 | 90 | 0.5 R Å⁻¹ = 5 R nm⁻¹ |

A line falls wholly into the wavelength cell that contains it (radiance per nm = line radiance
over the cell width), so the band-integrated radiance is right on any grid. Zenith V-band
brightness of this model, above the air: 22.1 mag arcsec⁻² (162 µcd m⁻²; the test), against
21.9 for the whole dark sky at La Palma (Benn & Ellison 1998, New Astron. Rev. 42, 503) and
22.0 for the natural sky of Falchi et al. (2016), of which airglow is the largest part,
zodiacal light and starlight the rest: our airglow is at the bright end of its range.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.spectrum.grid import cell_edges, checked_grid
from skyscatter.spectrum.star import PLANCK, SPEED_OF_LIGHT

__all__ = ["AIRGLOW_LINES", "CONTINUUM_R_PER_NM", "airglow_radiance", "van_rhijn_factor"]

# (wavelength [nm], emission height [m], zenith intensity [R]); module docstring
AIRGLOW_LINES = (
    (557.7, 97e3, 250.0),
    (589.3, 92e3, 50.0),
    (630.0, 250e3, 60.0),
    (636.4, 250e3, 20.0),
    (731.0, 87e3, 150.0),
    (777.0, 87e3, 250.0),
    (791.0, 87e3, 200.0),
    (828.0, 87e3, 600.0),
)
CONTINUUM_R_PER_NM = 5.0  # R nm⁻¹ (0.5 R Å⁻¹), 400-830 nm, at 90 km
_CONTINUUM_HEIGHT_M = 90e3
_CONTINUUM_RANGE_NM = (400.0, 830.0)
_PHOTONS_PER_RAYLEIGH = 1e10 / (4.0 * math.pi)  # photons s⁻¹ m⁻² sr⁻¹ per R


def van_rhijn_factor(cos_zenith: ArrayLike, observer_radius_m: float,
                     shell_radius_m: float) -> np.ndarray:
    """Brightening of a thin emitting shell seen at zenith angle z from radius r_0 below it:
    1 / sqrt(1 - (r_0 / r_e)² sin² z) (van Rhijn 1921). [-]"""
    mu = np.asarray(cos_zenith, dtype=np.float64)
    sin2 = np.clip(1.0 - mu * mu, 0.0, 1.0)
    return 1.0 / np.sqrt(1.0 - (observer_radius_m / shell_radius_m) ** 2 * sin2)


def _zenith_spectra(wavelengths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(shell heights (n_h,) [m], zenith spectral radiance of each shell (n_h, n_wl)
    [W m⁻² sr⁻¹ nm⁻¹]) on the grid: lines in their cells, the continuum over its range."""
    edges = cell_edges(wavelengths)
    widths = np.diff(edges)
    heights = sorted({height for _, height, _ in AIRGLOW_LINES} | {_CONTINUUM_HEIGHT_M})
    spectra = np.zeros((len(heights), wavelengths.size))
    photon_energy = PLANCK * SPEED_OF_LIGHT / (wavelengths * 1e-9)  # J per photon per cell
    low, high = _CONTINUUM_RANGE_NM
    in_range = np.clip(np.minimum(edges[1:], high) - np.maximum(edges[:-1], low), 0.0, None)
    spectra[heights.index(_CONTINUUM_HEIGHT_M)] += (
        CONTINUUM_R_PER_NM * in_range / widths * _PHOTONS_PER_RAYLEIGH * photon_energy)
    for wavelength, height, rayleighs in AIRGLOW_LINES:
        cell = int(np.searchsorted(edges, wavelength)) - 1
        if 0 <= cell < wavelengths.size:
            spectra[heights.index(height), cell] += (
                rayleighs * _PHOTONS_PER_RAYLEIGH * PLANCK * SPEED_OF_LIGHT
                / (wavelength * 1e-9) / widths[cell])
    return np.array(heights), spectra


def airglow_radiance(cos_zenith: ArrayLike, wavelengths_nm: ArrayLike, observer_radius_m: float,
                     planet_radius_m: float) -> np.ndarray:
    """Airglow spectral radiance above the air below the layers, along view directions with
    cos(zenith) `cos_zenith` (shape S) from `observer_radius_m`; 0 for views below the
    horizontal (the layers seen through the planet). Shape S + (n_wl,): the van Rhijn factor
    of each shell times its zenith spectrum, one matrix product. [W m⁻² sr⁻¹ nm⁻¹]"""
    wl = checked_grid(wavelengths_nm)
    heights, spectra = _zenith_spectra(wl)
    mu = np.asarray(cos_zenith, dtype=np.float64)
    brightening = van_rhijn_factor(mu[..., None], observer_radius_m,
                                   planet_radius_m + heights)  # S + (n_h,)
    brightening[mu <= 0.0] = 0.0
    return brightening @ spectra
