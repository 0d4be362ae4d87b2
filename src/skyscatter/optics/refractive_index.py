"""Refractivity n - 1 of gases, and the number density at which each dispersion formula holds.

Rayleigh cross-sections (`optics.rayleigh`) need n - 1 together with the number density N_s of the
gas it was measured at, because (n^2 - 1)/N_s is (to first order) independent of density.

- air: Peck & Reeder (1972), J. Opt. Soc. Am. 62, 958, doi:10.1364/JOSA.62.000958, at 15 °C,
  1013.25 hPa and 300 ppm CO2, with the CO2 correction of Bodhaine et al. (1999), J. Atmos.
  Oceanic Technol. 16, 1854, eq. 19, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
- co2: Bideau-Mehu, Guern, Abjean & Johannin-Gilles (1973), Opt. Commun. 9, 432,
  doi:10.1016/0030-4018(73)90289-7, at 0 °C and 101325 Pa.

`gas_refractivity(gas, wavelengths_nm)` picks one of these by name.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError

__all__ = [
    "AIR_NUMBER_DENSITY_288K_M3",
    "GASES",
    "LOSCHMIDT_M3",
    "gas_refractivity",
    "refractivity_air_bodhaine_1999",
    "refractivity_air_peck_reeder_1972",
    "refractivity_co2_bideau_mehu_1973",
]

# m^-3, dry air at 288.15 K and 1013.25 hPa; Bodhaine et al. (1999), N_s below their eq. 2.
AIR_NUMBER_DENSITY_288K_M3 = 2.546899e25
# m^-3, ideal gas at 273.15 K and 101325 Pa; CODATA 2018 Loschmidt constant.
LOSCHMIDT_M3 = 2.6867811e25


def _inverse_square_micrometres(wavelengths_nm: ArrayLike) -> np.ndarray:
    """sigma^2 = (1 / lambda[µm])^2 [µm^-2]; rejects non-positive or non-finite wavelengths."""
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0.0):
        raise InputError(f"wavelengths must be finite and > 0 nm, got {wl!r}",
                         key="wavelengths_nm", value=wl, allowed="> 0 nm")
    return (1.0e3 / wl) ** 2


def refractivity_air_peck_reeder_1972(wavelengths_nm: ArrayLike) -> np.ndarray:
    r"""Refractivity of standard dry air with 300 ppm CO2, at 15 °C and 1013.25 hPa.

    (n - 1) 10^8 = 8060.51 + 2480990 / (132.274 - sigma^2) + 17455.7 / (39.32957 - sigma^2),
    sigma = 1 / lambda[µm]. Peck & Reeder (1972), J. Opt. Soc. Am. 62, 958,
    doi:10.1364/JOSA.62.000958, as quoted by Bodhaine et al. (1999). Fitted to measurements
    from 230 nm to 1690 nm. Holds at the number density `AIR_NUMBER_DENSITY_288K_M3`.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]

    Returns
    -------
    ndarray, shape S
        n - 1. [-]
    """
    s2 = _inverse_square_micrometres(wavelengths_nm)
    return 1.0e-8 * (8060.51 + 2480990.0 / (132.274 - s2) + 17455.7 / (39.32957 - s2))


def refractivity_air_bodhaine_1999(wavelengths_nm: ArrayLike,
                                   co2_ppm: float = 360.0) -> np.ndarray:
    r"""Refractivity of dry air at 15 °C and 1013.25 hPa with `co2_ppm` of CO2.

    (n - 1)_CO2 = (n - 1)_300 (1 + 0.54 (C_CO2 - 0.0003)), C_CO2 the CO2 volume fraction [-],
    (n - 1)_300 from `refractivity_air_peck_reeder_1972`. Bodhaine et al. (1999), J. Atmos.
    Oceanic Technol. 16, 1854, eq. 19, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
    Holds at the number density `AIR_NUMBER_DENSITY_288K_M3`.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    co2_ppm : float
        CO2 volume mixing ratio. [ppm]

    Returns
    -------
    ndarray, shape S
        n - 1. [-]
    """
    if not np.isfinite(co2_ppm) or co2_ppm < 0.0:
        raise InputError(f"co2_ppm = {co2_ppm!r} must be >= 0", key="co2_ppm", value=co2_ppm,
                         allowed=">= 0 ppm")
    c_co2 = co2_ppm * 1.0e-6
    return refractivity_air_peck_reeder_1972(wavelengths_nm) * (1.0 + 0.54 * (c_co2 - 0.0003))


def refractivity_co2_bideau_mehu_1973(wavelengths_nm: ArrayLike) -> np.ndarray:
    r"""Refractivity of pure CO2 gas at 0 °C and 101325 Pa.

    n - 1 = 6.99100e-2 / (166.175 - sigma^2) + 1.44720e-3 / (79.609 - sigma^2)
          + 6.42941e-5 / (56.3064 - sigma^2) + 5.21306e-5 / (46.0196 - sigma^2)
          + 1.46847e-6 / (0.0584738 - sigma^2),           sigma = 1 / lambda[µm].
    Bideau-Mehu et al. (1973), Opt. Commun. 9, 432, doi:10.1016/0030-4018(73)90289-7; measured
    from 181 nm to 1695 nm. Holds at the number density `LOSCHMIDT_M3`. Costa et al. (2020),
    Table 1, print n_CO2 = (1.00044661, 1.00045019, 1.00045558) at (680, 550, 440) nm; this
    formula gives the first two to every printed digit and 1.00045588 at 440 nm (the printed
    value is reached at 444.3 nm: 0.07 % of n - 1, probably a transposed digit).

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]

    Returns
    -------
    ndarray, shape S
        n - 1. [-]
    """
    s2 = _inverse_square_micrometres(wavelengths_nm)
    return (6.99100e-2 / (166.175 - s2) + 1.44720e-3 / (79.609 - s2)
            + 6.42941e-5 / (56.3064 - s2) + 5.21306e-5 / (46.0196 - s2)
            + 1.46847e-6 / (0.0584738 - s2))


def _air(wavelengths_nm: ArrayLike, co2_ppm: float) -> tuple[np.ndarray, float]:
    return refractivity_air_bodhaine_1999(wavelengths_nm, co2_ppm), AIR_NUMBER_DENSITY_288K_M3


def _co2(wavelengths_nm: ArrayLike, co2_ppm: float) -> tuple[np.ndarray, float]:
    return refractivity_co2_bideau_mehu_1973(wavelengths_nm), LOSCHMIDT_M3


# name -> (refractivity function, description); co2_ppm only affects "air".
GASES: dict[str, tuple[Callable[[ArrayLike, float], tuple[np.ndarray, float]], str]] = {
    "air": (_air, "dry air, Peck & Reeder 1972 + Bodhaine 1999 CO2 correction, 288.15 K"),
    "co2": (_co2, "carbon dioxide, Bideau-Mehu et al. 1973, 273.15 K"),
}


def gas_refractivity(gas: str, wavelengths_nm: ArrayLike,
                     co2_ppm: float = 360.0) -> tuple[np.ndarray, float]:
    """Refractivity of a named gas and the number density at which it holds.

    Parameters
    ----------
    gas : str
        One of `GASES`: "air" or "co2".
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    co2_ppm : float
        CO2 mixing ratio of "air"; ignored for other gases. [ppm]

    Returns
    -------
    n_minus_1 : ndarray, shape S
        n - 1. [-]
    reference_number_density_m3 : float
        Number density of the gas at the temperature and pressure of the formula. [m^-3]
    """
    key = str(gas).strip().lower()
    if key not in GASES:
        allowed = ", ".join(sorted(GASES))
        raise InputError(f"unknown gas {gas!r}; known gases: {allowed}", key="gas", value=gas,
                         allowed=allowed)
    return GASES[key][0](wavelengths_nm, co2_ppm)
