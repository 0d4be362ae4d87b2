"""The measured solar spectrum at 1 AU (ASTM G173-03 extraterrestrial), put on a wavelength grid.

Data: `data/solar_astm_g173_etr.npz`, the extraterrestrial column of ASTM G173-03 ("Standard Tables
for Reference Solar Spectral Irradiances", derived from SMARTS v2.9.2, Gueymard 2001/2004),
280–4000 nm on 2002 wavelengths (0.5 nm steps below 400 nm, 1 nm to 1700 nm, coarser beyond),
W m⁻² nm⁻¹ at the mean Sun–Earth distance; taken from pvlib's copy (BSD-3-Clause) by
`scripts/make_data/solar_g173.py`. Its integral over 280–4000 nm is 1347.93 W m⁻² (the other
≈ 13 W m⁻² of the 1361 W m⁻² solar constant lie outside that range).

On a grid the spectrum is the exact average over each cell (`grid.cell_average`), so coarse grids
keep the energy of Fraunhofer lines instead of aliasing them.

Public names: `solar_irradiance_1au`, `solar_spectrum_table`, `SOLAR_DATA_FILE`.
"""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.spectrum.grid import cell_average

__all__ = ["SOLAR_DATA_FILE", "solar_irradiance_1au", "solar_spectrum_table"]

SOLAR_DATA_FILE = "solar_astm_g173_etr.npz"  # in skyscatter/data; see data/PROVENANCE.md


@lru_cache(maxsize=1)
def solar_spectrum_table() -> tuple[np.ndarray, np.ndarray]:
    """The tabulated ASTM G173-03 extraterrestrial spectrum, as shipped (read-only arrays).

    Source: ASTM G173-03 ETR column (SMARTS v2.9.2) via pvlib `pvlib/data/ASTMG173.csv`;
    see data/PROVENANCE.md.

    Returns
    -------
    wavelength_nm : ndarray, shape (2002,)
        280–4000 nm, ascending. [nm]
    irradiance : ndarray, shape (2002,)
        Spectral irradiance normal to the beam at 1 AU, outside the atmosphere. [W m⁻² nm⁻¹]
    """
    path = resources.files("skyscatter").joinpath("data", SOLAR_DATA_FILE)
    with path.open("rb") as handle, np.load(handle, allow_pickle=False) as data:
        wavelength_nm = np.array(data["wavelength_nm"], dtype=np.float64)
        irradiance = np.array(data["irradiance"], dtype=np.float64)
    wavelength_nm.flags.writeable = False
    irradiance.flags.writeable = False
    return wavelength_nm, irradiance


def solar_irradiance_1au(wavelengths_nm: ArrayLike) -> np.ndarray:
    """Solar spectral irradiance at 1 AU, averaged over each grid cell.

        E_j = 1/(e_{j+1} - e_j) ∫_{e_j}^{e_{j+1}} E_G173(λ) dλ

    E_G173 is the ASTM G173-03 extraterrestrial spectrum read as piecewise linear between its
    tabulated points and as 0 outside 280–4000 nm; cells e_j are `grid.cell_edges`. So
    Σ_j E_j (e_{j+1} - e_j) is the exact integral of the table over the grid's range, whatever
    the grid.

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid, strictly ascending. [nm]

    Returns
    -------
    ndarray, shape (n_wl,)
        Spectral irradiance normal to the beam at 1 AU (mean Sun–Earth distance), top of the
        atmosphere. [W m⁻² nm⁻¹]
    """
    table_wavelength_nm, table_irradiance = solar_spectrum_table()
    return cell_average(table_wavelength_nm, table_irradiance, wavelengths_nm)
