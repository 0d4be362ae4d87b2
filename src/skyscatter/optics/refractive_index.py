"""Refractivity n - 1 of gases, and the number density at which each dispersion formula holds.

Rayleigh cross-sections (`optics.rayleigh`) need n - 1 together with the number density N_s of the
gas it was measured at, because (n^2 - 1)/N_s is (to first order) independent of density.

- air: Peck & Reeder (1972), J. Opt. Soc. Am. 62, 958, doi:10.1364/JOSA.62.000958, at 15 °C,
  1013.25 hPa and 300 ppm CO2, with the CO2 correction of Bodhaine et al. (1999), J. Atmos.
  Oceanic Technol. 16, 1854, eq. 19, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
- co2: Bideau-Mehu, Guern, Abjean & Johannin-Gilles (1973), Opt. Commun. 9, 432,
  doi:10.1016/0030-4018(73)90289-7, at 0 °C and 101325 Pa.
- n2: Peck & Khanna (1966), J. Opt. Soc. Am. 56, 1059, doi:10.1364/JOSA.56.001059, and Bates
  (1984) below 468 nm, as quoted by Sneep & Ubachs (2005), JQSRT 92, 293,
  doi:10.1016/j.jqsrt.2004.07.025, at 15 °C and 1013.25 hPa.
- o2: Zhang, Lu & Wang (2008), Appl. Opt. 47, 3143, doi:10.1364/AO.47.003143, at 20 °C and
  101325 Pa.
- ar: Peck & Fisher (1964), J. Opt. Soc. Am. 54, 1362, doi:10.1364/JOSA.54.001362, at 15 °C.
- h2: Peck & Huang (1977), J. Opt. Soc. Am. 67, 1550, doi:10.1364/JOSA.67.001550, at 0 °C.
- he: Mansfield & Peck (1969), J. Opt. Soc. Am. 59, 199, doi:10.1364/JOSA.59.000199, at 0 °C.
- ch4: one value, n - 1 = 4.44e-4 at 589.3 nm and 0 °C (Kaye & Laby), without dispersion.

The coefficients of the Ar, H2, He and O2 formulas are those of the refractiveindex.info
database (Polyanskiy 2024, Sci. Data 11, 94, doi:10.1038/s41597-023-02898-2), files
`data/main/{Ar,H2,He,O2}/*.yml`; those of N2 are Sneep & Ubachs's (the database's own fit of
Peck & Khanna's data at 15 °C agrees within 0.02 %). Reference number densities are ideal-gas values
P / (k T); the gases' non-ideality at 1 atm (compressibility Z = 0.993 for CO2 at 0 °C, closer to
1 for the others) is left out, so CO2's cross-section is about 1.4 % high.

Each Sellmeier-form formula is one `DispersionFormula` (coefficients, number density, source);
`gas_refractivity(gas, wavelengths_nm)` picks one of these by name.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.star import BOLTZMANN

__all__ = [
    "AIR_NUMBER_DENSITY_288K_M3",
    "DispersionFormula",
    "GASES",
    "LOSCHMIDT_M3",
    "NUMBER_DENSITY_293K_M3",
    "REFRACTIVITY_CH4_KAYE_LABY",
    "gas_refractivity",
    "inverse_square_micrometres",
    "refractivity_air_bodhaine_1999",
    "refractivity_air_peck_reeder_1972",
    "refractivity_ar_peck_fisher_1964",
    "refractivity_ch4_kaye_laby",
    "refractivity_co2_bideau_mehu_1973",
    "refractivity_h2_peck_huang_1977",
    "refractivity_he_mansfield_peck_1969",
    "refractivity_n2_peck_khanna_1966",
    "refractivity_o2_zhang_2008",
]

# m^-3, dry air at 288.15 K and 1013.25 hPa; Bodhaine et al. (1999), N_s below their eq. 2.
AIR_NUMBER_DENSITY_288K_M3 = 2.546899e25
# m^-3, ideal gas at 273.15 K and 101325 Pa; CODATA 2018 Loschmidt constant.
LOSCHMIDT_M3 = 2.6867811e25
# m^-3, ideal gas at 293.15 K and 101325 Pa: P / (k T), k exact (SI 2019).
NUMBER_DENSITY_293K_M3 = 101325.0 / (BOLTZMANN * 293.15)
# -, n - 1 of methane at 589.3 nm, 0 °C and 101325 Pa: (n - 1) 10^6 = 444. Kaye & Laby, Tables
# of Physical and Chemical Constants (NPL), section 2.5.7 "Refractive index of gases".
REFRACTIVITY_CH4_KAYE_LABY = 4.44e-4


def inverse_square_micrometres(wavelengths_nm: ArrayLike) -> np.ndarray:
    """sigma^2 = (1 / lambda[µm])^2 [µm^-2]; rejects non-positive or non-finite wavelengths."""
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0.0):
        raise InputError(f"wavelengths must be finite and > 0 nm, got {wl!r}",
                         key="wavelengths_nm", value=wl, allowed="> 0 nm")
    return (1.0e3 / wl) ** 2


@dataclass(frozen=True)
class DispersionFormula:
    r"""A dispersion formula of Sellmeier form and the number density at which it holds.

    n - 1 = scale (constant + sum_i b_i / (c_i - x)),   x = sigma^2 x_per_sigma2,
    sigma = 1 / lambda[µm]; each instance below names its source. Calling one returns n - 1.

    Parameters (of the call)
    ------------------------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]

    Returns (of the call)
    ---------------------
    ndarray, shape S
        n - 1. [-]
    """

    constant: float
    terms: tuple[tuple[float, float], ...]  # (b_i, c_i), in the units of x
    number_density_m3: float  # m^-3, the density the formula holds at
    source: str
    scale: float = 1.0
    x_per_sigma2: float = 1.0  # 1e8 for x = nu^2 in cm^-2

    def __call__(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        x = inverse_square_micrometres(wavelengths_nm) * self.x_per_sigma2
        total = np.full(x.shape, self.constant)
        for b, c in self.terms:
            total = total + b / (c - x)
        return self.scale * total


refractivity_air_peck_reeder_1972 = DispersionFormula(
    8060.51, ((2480990.0, 132.274), (17455.7, 39.32957)), AIR_NUMBER_DENSITY_288K_M3, scale=1.0e-8,
    source="""Standard dry air with 300 ppm CO2, at 15 °C and 1013.25 hPa.
    (n - 1) 10^8 = 8060.51 + 2480990 / (132.274 - sigma^2) + 17455.7 / (39.32957 - sigma^2).
    Peck & Reeder (1972), J. Opt. Soc. Am. 62, 958, doi:10.1364/JOSA.62.000958, as quoted by
    Bodhaine et al. (1999). Fitted to measurements from 230 nm to 1690 nm.""")


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


refractivity_co2_bideau_mehu_1973 = DispersionFormula(
    0.0, ((6.99100e-2, 166.175), (1.44720e-3, 79.609), (6.42941e-5, 56.3064),
          (5.21306e-5, 46.0196), (1.46847e-6, 0.0584738)), LOSCHMIDT_M3,
    source="""Pure CO2 gas at 0 °C and 101325 Pa.
    n - 1 = 6.99100e-2 / (166.175 - sigma^2) + 1.44720e-3 / (79.609 - sigma^2)
          + 6.42941e-5 / (56.3064 - sigma^2) + 5.21306e-5 / (46.0196 - sigma^2)
          + 1.46847e-6 / (0.0584738 - sigma^2).
    Bideau-Mehu et al. (1973), Opt. Commun. 9, 432, doi:10.1016/0030-4018(73)90289-7; measured
    from 181 nm to 1695 nm. Costa et al. (2020), Table 1, print n_CO2 = (1.00044661, 1.00045019,
    1.00045558) at (680, 550, 440) nm; this formula gives the first two to every printed digit and
    1.00045588 at 440 nm (the printed value is reached at 444.3 nm: 0.07 % of n - 1, probably a
    transposed digit).""")

_N2_PECK_KHANNA_1966 = DispersionFormula(
    6498.2, ((307.43305e12, 14.4e9),), AIR_NUMBER_DENSITY_288K_M3, scale=1.0e-8,
    x_per_sigma2=1.0e8, source="N2, Peck & Khanna (1966); see refractivity_n2_peck_khanna_1966")
_N2_BATES_1984 = DispersionFormula(
    5677.465, ((318.81874e12, 14.4e9),), AIR_NUMBER_DENSITY_288K_M3, scale=1.0e-8,
    x_per_sigma2=1.0e8, source="N2, Bates (1984); see refractivity_n2_peck_khanna_1966")


def refractivity_n2_peck_khanna_1966(wavelengths_nm: ArrayLike) -> np.ndarray:
    r"""Refractivity of pure N2 at 15 °C and 1013.25 hPa.

    (n - 1) 10^8 = 6498.2   + 307.43305e12 / (14.4e9 - nu^2)   for nu <= 21360 cm^-1,
                 = 5677.465 + 318.81874e12 / (14.4e9 - nu^2)   for nu >  21360 cm^-1,
    nu = 1 / lambda [cm^-1]. The first branch (lambda >= 468.2 nm) is Peck & Khanna (1966),
    J. Opt. Soc. Am. 56, 1059, doi:10.1364/JOSA.56.001059 (measured 468-2058 nm); the second is
    Bates (1984), Planet. Space Sci. 32, 785, doi:10.1016/0032-0633(84)90102-8; both as quoted by
    Sneep & Ubachs (2005), JQSRT 92, 293, doi:10.1016/j.jqsrt.2004.07.025. The branches differ by
    1.5e-4 of n - 1 at 468.2 nm. Holds at the number density `AIR_NUMBER_DENSITY_288K_M3`.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]

    Returns
    -------
    ndarray, shape S
        n - 1. [-]
    """
    nu2 = inverse_square_micrometres(wavelengths_nm) * 1.0e8  # cm^-2
    return np.where(nu2 <= 21360.0**2, _N2_PECK_KHANNA_1966(wavelengths_nm),
                    _N2_BATES_1984(wavelengths_nm))


refractivity_o2_zhang_2008 = DispersionFormula(
    1.181494e-4, ((9.708931e-3, 75.4),), NUMBER_DENSITY_293K_M3,
    source="""Pure O2 at 20 °C and 101325 Pa.
    n - 1 = 1.181494e-4 + 9.708931e-3 / (75.4 - sigma^2).
    Zhang, Lu & Wang (2008), Appl. Opt. 47, 3143, doi:10.1364/AO.47.003143, with Křen (2011),
    Appl. Opt. 50, 6484, doi:10.1364/AO.50.006484; fitted from 400 nm to 1800 nm.""")

refractivity_ar_peck_fisher_1964 = DispersionFormula(
    6.432135e-5, ((2.8606021e-2, 144.0),), AIR_NUMBER_DENSITY_288K_M3,
    source="""Argon at 15 °C and 101325 Pa.
    n - 1 = 6.432135e-5 + 2.8606021e-2 / (144 - sigma^2).
    Peck & Fisher (1964), J. Opt. Soc. Am. 54, 1362, doi:10.1364/JOSA.54.001362; measured from
    468 nm to 2059 nm.""")

refractivity_h2_peck_huang_1977 = DispersionFormula(
    0.0, ((0.0148956, 180.7), (0.0049037, 92.0)), LOSCHMIDT_M3,
    source="""H2 at 0 °C and 101325 Pa.
    n - 1 = 0.0148956 / (180.7 - sigma^2) + 0.0049037 / (92 - sigma^2).
    Peck & Huang (1977), J. Opt. Soc. Am. 67, 1550, doi:10.1364/JOSA.67.001550; measured from
    168 nm to 1695 nm.""")

refractivity_he_mansfield_peck_1969 = DispersionFormula(
    0.0, ((0.01470091, 423.98),), LOSCHMIDT_M3,
    source="""Helium at 0 °C and 101325 Pa.
    n - 1 = 0.01470091 / (423.98 - sigma^2).
    Mansfield & Peck (1969), J. Opt. Soc. Am. 59, 199, doi:10.1364/JOSA.59.000199; measured from
    480 nm to 2059 nm.""")

refractivity_ch4_kaye_laby = DispersionFormula(
    REFRACTIVITY_CH4_KAYE_LABY, (), LOSCHMIDT_M3,
    source="""Methane at 0 °C and 101325 Pa, one value for every wavelength.
    n - 1 = 4.44e-4 (`REFRACTIVITY_CH4_KAYE_LABY`), measured at 589.3 nm: Kaye & Laby, Tables of
    Physical and Chemical Constants (NPL), section 2.5.7. A deliberate simplification: the
    dispersion is left out, for want of a formula whose coefficients we could check; that of
    comparable gases (N2: n - 1 is 1.3 % larger at 440 nm than at 589 nm) makes the cross-section
    a few percent low in the blue.""")


def _air(wavelengths_nm: ArrayLike, co2_ppm: float) -> tuple[np.ndarray, float]:
    return refractivity_air_bodhaine_1999(wavelengths_nm, co2_ppm), AIR_NUMBER_DENSITY_288K_M3


def _pure(formula: DispersionFormula) -> Callable[[ArrayLike, float], tuple[np.ndarray, float]]:
    """A pure gas's formula as a `GASES` entry (co2_ppm does not apply)."""
    def refractivity(wavelengths_nm: ArrayLike, co2_ppm: float) -> tuple[np.ndarray, float]:
        return formula(wavelengths_nm), formula.number_density_m3
    return refractivity


def _n2(wavelengths_nm: ArrayLike, co2_ppm: float) -> tuple[np.ndarray, float]:
    return refractivity_n2_peck_khanna_1966(wavelengths_nm), AIR_NUMBER_DENSITY_288K_M3


# name -> (refractivity function, description); co2_ppm only affects "air".
GASES: dict[str, tuple[Callable[[ArrayLike, float], tuple[np.ndarray, float]], str]] = {
    "air": (_air, "dry air, Peck & Reeder 1972 + Bodhaine 1999 CO2 correction, 288.15 K"),
    "ar": (_pure(refractivity_ar_peck_fisher_1964), "argon, Peck & Fisher 1964, 288.15 K"),
    "ch4": (_pure(refractivity_ch4_kaye_laby),
            "methane, Kaye & Laby (589.3 nm, no dispersion), 273.15 K"),
    "co2": (_pure(refractivity_co2_bideau_mehu_1973),
            "carbon dioxide, Bideau-Mehu et al. 1973, 273.15 K"),
    "h2": (_pure(refractivity_h2_peck_huang_1977), "hydrogen, Peck & Huang 1977, 273.15 K"),
    "he": (_pure(refractivity_he_mansfield_peck_1969), "helium, Mansfield & Peck 1969, 273.15 K"),
    "n2": (_n2, "nitrogen, Peck & Khanna 1966 / Bates 1984 (Sneep & Ubachs 2005), 288.15 K"),
    "o2": (_pure(refractivity_o2_zhang_2008), "oxygen, Zhang et al. 2008, 293.15 K"),
}


def gas_refractivity(gas: str, wavelengths_nm: ArrayLike,
                     co2_ppm: float = 360.0) -> tuple[np.ndarray, float]:
    """Refractivity of a named gas and the number density at which it holds.

    Parameters
    ----------
    gas : str
        One of `GASES`: "air", "ar", "ch4", "co2", "h2", "he", "n2" or "o2" (any case).
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
