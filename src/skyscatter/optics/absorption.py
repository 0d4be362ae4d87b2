"""Molecular absorption cross-sections and the optics of a purely absorbing gas.

Ozone: the 295 K cross-section of Malicet et al. (1995), J. Atmos. Chem. 21, 263,
doi:10.1007/BF00696758 (195-345 nm) and Brion et al. (1998), J. Atmos. Chem. 30, 291,
doi:10.1023/A:1006036924364 (345-830 nm), shipped as `data/o3_cross_section_malicet_brion_295k.npz`
(0.1-nm bin means of the 0.01-nm data in PyPI musica 0.17.2; see data/PROVENANCE.md).
`ozone_cross_section` averages it over the cell each grid wavelength stands for;
`AbsorberOptics` is a `ConstituentOptics` whose density profile is a number density [m^-3].
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.grid import cell_edges
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "CROSS_SECTIONS",
    "DOBSON_UNIT_M2",
    "OZONE_DATA_FILE",
    "AbsorberOptics",
    "ozone_cross_section",
]

# molecules m^-2: 1 DU = a 0.01 mm layer of pure O3 at 273.15 K and 101325 Pa, i.e.
# 1e-5 m x Loschmidt 2.6867811e25 m^-3 (CODATA 2018) = 2.6867811e20 m^-2.
DOBSON_UNIT_M2 = 2.6867811e20
OZONE_DATA_FILE = "o3_cross_section_malicet_brion_295k.npz"  # in skyscatter/data


@cache
def _ozone_table() -> tuple[np.ndarray, np.ndarray]:
    """Bin edges [nm] and the running integral of sigma over wavelength at them [m^2 nm]."""
    path = resources.files("skyscatter").joinpath("data", OZONE_DATA_FILE)
    with resources.as_file(path) as p, np.load(p) as data:
        edges = np.asarray(data["bin_edges_nm"], dtype=np.float64)
        sigma = np.asarray(data["cross_section_m2"], dtype=np.float64)
    running = np.concatenate(([0.0], np.cumsum(sigma * np.diff(edges))))
    return edges, running


def ozone_cross_section(wavelengths_nm: ArrayLike, single_cell_width_nm: float = 1.0) -> np.ndarray:
    r"""O3 absorption cross-section at 295 K, averaged over the cell of each grid wavelength.

    sigma_k = int_{a_k}^{b_k} sigma(lambda) dlambda / (b_k - a_k), with cell edges a_k, b_k halfway
    between neighbouring wavelengths (the end cells extend as far outwards as inwards; a lone
    wavelength gets a cell `single_cell_width_nm` wide; `spectrum.grid.cell_edges`). A 10-nm grid
    thus gets
    10-nm band means, the way Bruneton (2017) bins Serdyuchenko's data. Data: Malicet et al.
    (1995), doi:10.1007/BF00696758, and Brion et al. (1998), doi:10.1023/A:1006036924364, 295 K,
    195-830 nm (`data/o3_cross_section_malicet_brion_295k.npz`, from PyPI musica 0.17.2).

    Outside 195-830 nm the data end: a cell is averaged over its part inside the data, and a cell
    wholly outside gets 0. Past 830 nm the true cross-section (Wulf bands, ~1e-26 m^2, tau ~ 0.001
    for 300 DU) is small; below 195 nm the atmosphere is opaque anyway (O2), which we do not model.
    The data are at 295 K; stratospheric ozone (~220 K) differs by a few percent in the Chappuis
    band and more in the Huggins band (310-350 nm).

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,) or scalar
        Wavelength grid, strictly ascending. [nm]
    single_cell_width_nm : float
        Cell width used when the last axis has a single wavelength. [nm]

    Returns
    -------
    ndarray, shape (..., n_wl)
        Absorption cross-section per molecule. [m^2]
    """
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0.0):
        raise InputError(f"wavelengths must be finite and > 0 nm, got {wl!r}",
                         key="wavelengths_nm", value=wl, allowed="> 0 nm")
    if not single_cell_width_nm > 0.0:
        raise InputError(f"single_cell_width_nm = {single_cell_width_nm!r} must be > 0",
                         key="single_cell_width_nm", value=single_cell_width_nm,
                         allowed="> 0 nm")
    edges, running = _ozone_table()
    cells = cell_edges(np.atleast_1d(wl), single_cell_width_nm)
    lower, upper = cells[:-1].reshape(wl.shape), cells[1:].reshape(wl.shape)
    lower = np.clip(lower, edges[0], edges[-1])
    upper = np.clip(upper, edges[0], edges[-1])
    width = upper - lower
    integral = np.interp(upper, edges, running) - np.interp(lower, edges, running)
    return np.divide(integral, width, out=np.zeros_like(width), where=width > 0.0)


# name -> (cross-section function of wavelengths_nm [nm] -> m^2, description)
CROSS_SECTIONS: dict[str, tuple[Callable[[np.ndarray], np.ndarray], str]] = {
    "o3-malicet-brion": (ozone_cross_section,
                         "ozone, Malicet 1995 + Brion 1998, 295 K, 195-830 nm"),
}


@dataclass(frozen=True)
class AbsorberOptics:
    """Optics of a gas that only absorbs; its density profile is a number density [m^-3].

    extinction_per_density = the absorption cross-section [m^2], scattering_per_density = 0,
    phase = None.

    Parameters
    ----------
    cross_section : str or SpectralParameter
        A name in `CROSS_SECTIONS` ("o3-malicet-brion", averaged over each grid cell by
        `ozone_cross_section`) or a cross-section table. [m^2]
    """

    cross_section: str | SpectralParameter = "o3-malicet-brion"
    phase: None = None

    def __post_init__(self) -> None:
        if isinstance(self.cross_section, SpectralParameter):
            values = np.asarray(self.cross_section.values)
            if not np.all(np.isfinite(values)) or np.any(values < 0.0):
                raise InputError(f"cross_section = {list(values)} must be finite and >= 0 m^2",
                                 key="cross_section", value=self.cross_section, allowed=">= 0")
            return
        key = str(self.cross_section).strip().lower()
        if key not in CROSS_SECTIONS:
            allowed = ", ".join(sorted(CROSS_SECTIONS))
            raise InputError(f"unknown cross-section {self.cross_section!r}; known: {allowed} "
                             "(or give a SpectralParameter in m^2)", key="cross_section",
                             value=self.cross_section, allowed=allowed)
        object.__setattr__(self, "cross_section", key)

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Absorption cross-section on `wavelengths_nm` [nm]. [m^2]"""
        if isinstance(self.cross_section, SpectralParameter):
            return self.cross_section.at(wavelengths_nm)
        return CROSS_SECTIONS[self.cross_section][0](np.asarray(wavelengths_nm, dtype=np.float64))

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Zero: an absorber scatters no light. [m^2]"""
        return np.zeros(np.shape(wavelengths_nm))
