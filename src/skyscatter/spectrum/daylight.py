"""Spectra of daylight from a chromaticity: the CIE daylight basis functions.

S(lambda) = S0(lambda) + M1 S1(lambda) + M2 S2(lambda),
M  = 0.0241 + 0.2562 x - 0.7341 y,
M1 = (-1.3515 - 1.7703 x + 5.9114 y) / M,
M2 = (0.0300 - 31.4424 x + 30.0717 y) / M
(CIE 015:2018 "Colorimetry", 4th ed., eqs. 4.7-4.9 and Table 6; Judd, MacAdam & Wyszecki
1964, J. Opt. Soc. Am. 54, 1031, doi:10.1364/JOSA.54.001031). M1, M2 are not rounded to three
decimals as the standard does for the tabulated D illuminants (a 1e-3 change of M1 moves the
spectrum by < 0.05 %). Meant for chromaticities near the daylight locus (x 0.25-0.40); the
basis is tabulated from 300 to 830 nm, outside it the spectrum is 0.
Data: `data/cie_daylight_basis.npz` (CIE 015:2018 Table 6 via colour-science;
data/PROVENANCE.md).
"""

from __future__ import annotations

from functools import lru_cache
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["daylight_basis", "daylight_spectrum", "daylight_weights"]

DAYLIGHT_DATA_FILE = "cie_daylight_basis.npz"  # in skyscatter/data; see data/PROVENANCE.md


@lru_cache(maxsize=1)
def _basis_table() -> tuple[np.ndarray, np.ndarray]:
    path = resources.files("skyscatter").joinpath("data", DAYLIGHT_DATA_FILE)
    with path.open("rb") as file, np.load(file, allow_pickle=False) as data:
        return data["wavelengths_nm"], data["basis"]


def daylight_basis(wavelengths_nm: ArrayLike) -> np.ndarray:
    """S0, S1, S2 [relative] (3, n_wl) at `wavelengths_nm` [nm], linear between the 5 nm
    entries of CIE 015:2018 Table 6, 0 outside 300-830 nm."""
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    grid, basis = _basis_table()
    return np.stack([np.interp(wl, grid, row, left=0.0, right=0.0) for row in basis])


def daylight_weights(x: ArrayLike, y: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(M1, M2) [-] of daylight of chromaticity (x, y) (module docstring), broadcast."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    m = 0.0241 + 0.2562 * x - 0.7341 * y
    return (-1.3515 - 1.7703 * x + 5.9114 * y) / m, (0.0300 - 31.4424 * x + 30.0717 * y) / m


def daylight_spectrum(x: ArrayLike, y: ArrayLike, wavelengths_nm: ArrayLike) -> np.ndarray:
    """Relative spectral power of daylight of chromaticity (x, y) (CIE 1931), shape
    S + (n_wl,) for x, y broadcast to S, on `wavelengths_nm` [nm] (module docstring); 100 at
    560 nm, where S1 = S2 = 0."""
    m1, m2 = daylight_weights(x, y)
    s0, s1, s2 = daylight_basis(wavelengths_nm)
    return s0 + m1[..., None] * s1 + m2[..., None] * s2
