"""Rayleigh scattering by gas molecules: King factors, cross-sections and the optics of a gas.

sigma(lambda) = 24 pi^3 (n^2 - 1)^2 / (lambda^4 N_s^2 (n^2 + 2)^2) F(lambda)   (Bodhaine 1999 eq. 2)
from the refractivity n - 1 at number density N_s (`optics.refractive_index`) and the King
factor F, which corrects for the anisotropy of the molecules (Bodhaine et al. 1999, eqs. 23-27;
Young 1980; Costa et al. 2020 Eq. 11). `RayleighOptics` turns this into the per-molecule
cross-sections of a constituent whose density profile is a number density [m^-3].
`TabulatedScatteringOptics` carries coefficients that a paper tabulates directly (Costa 2020,
Bruneton 2017 presets). `rayleigh_optical_depth_bodhaine1999` (eq. 30) is kept as the outside
reference the tests compare against.

References: Bodhaine, Wood, Dutton & Slusser (1999), J. Atmos. Oceanic Technol. 16, 1854,
doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2. Young (1980), Appl. Opt. 19, 3427,
doi:10.1364/AO.19.003427. Costa, Bock, Emmart, Hansen, Ynnerman & Silva (2021), "Interactive
visualization of atmospheric effects for celestial bodies", IEEE TVCG 27(2), 785,
doi:10.1109/TVCG.2020.3030333, arXiv:2010.03534.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.phase import PenndorfPhase, PhaseFunction, RayleighPhase
from skyscatter.optics.refractive_index import (
    GASES,
    gas_refractivity,
    inverse_square_micrometres,
)
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "KING_FACTOR_AR_BODHAINE_1999",
    "KING_FACTOR_CO2_BODHAINE_1999",
    "KING_FACTOR_MODELS",
    "KingFactorPolynomial",
    "RAYLEIGH_PHASES",
    "RayleighOptics",
    "TabulatedScatteringOptics",
    "king_factor_air_bodhaine_1999",
    "king_factor_from_depolarization",
    "king_factor_n2_bates_1984",
    "king_factor_o2_bates_1984",
    "rayleigh_cross_section",
    "rayleigh_cross_section_from_polarizability",
    "rayleigh_optical_depth_bodhaine1999",
    "rayleigh_phase",
]

KING_FACTOR_CO2_BODHAINE_1999 = 1.15  # -, Bodhaine et al. (1999), F(CO2) in eq. 23
KING_FACTOR_AR_BODHAINE_1999 = 1.00  # -, Bodhaine et al. (1999), F(Ar) in eqs. 23-27


def king_factor_from_depolarization(depolarization: ArrayLike) -> np.ndarray:
    r"""King correction factor from the depolarisation ratio, F = (6 + 3 delta) / (6 - 7 delta).

    Costa et al. (2020), IEEE TVCG, Eq. 11; Young (1980), Appl. Opt. 19, 3427,
    doi:10.1364/AO.19.003427. delta is the depolarisation ratio for natural (unpolarised)
    light; e.g. delta = 0.0279 (Young 1980, air) gives F = 1.0480.

    Parameters
    ----------
    depolarization : array_like, shape S
        Depolarisation ratio delta, 0 <= delta < 6/7. [-]

    Returns
    -------
    ndarray, shape S
        King factor F. [-]
    """
    delta = np.asarray(depolarization, dtype=np.float64)
    if not np.all(np.isfinite(delta)) or np.any(delta < 0.0) or np.any(delta >= 6.0 / 7.0):
        raise InputError(f"depolarization = {delta!r} must lie in [0, 6/7)",
                         key="depolarization", value=delta, allowed="[0, 6/7)")
    return (6.0 + 3.0 * delta) / (6.0 - 7.0 * delta)


@dataclass(frozen=True)
class KingFactorPolynomial:
    r"""A King factor polynomial in sigma^2 = lam^-2 (lam in µm), F = sum_k a_k sigma^(2k).

    Each instance below names its source. Calling one returns F.

    Parameters (of the call)
    ------------------------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]

    Returns (of the call)
    ---------------------
    ndarray, shape S
        King factor F. [-]
    """

    coefficients: tuple[float, ...]  # a_0, a_1, ...; a_k in µm^(2k)
    source: str

    def __call__(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        inv2 = inverse_square_micrometres(wavelengths_nm)
        total = np.full(inv2.shape, self.coefficients[0])
        for power, coefficient in enumerate(self.coefficients[1:], start=1):
            term = coefficient
            for _ in range(power):
                term = term * inv2
            total = total + term
        return total


king_factor_n2_bates_1984 = KingFactorPolynomial((1.034, 3.17e-4), source="""King factor of N2,
    F_N2 = 1.034 + 3.17e-4 lam^-2. Bates (1984), Planet. Space Sci. 32, 785,
    doi:10.1016/0032-0633(84)90102-8, as quoted by Bodhaine et al. (1999), J. Atmos. Oceanic
    Technol. 16, 1854, eqs. 23-27, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
    F_N2(550 nm) = 1.0350.""")

king_factor_o2_bates_1984 = KingFactorPolynomial((1.096, 1.385e-3, 1.448e-4), source="""King
    factor of O2, F_O2 = 1.096 + 1.385e-3 lam^-2 + 1.448e-4 lam^-4. Bates (1984), Planet. Space
    Sci. 32, 785, doi:10.1016/0032-0633(84)90102-8, as quoted by Bodhaine et al. (1999), J. Atmos.
    Oceanic Technol. 16, 1854, eqs. 23-27, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2.
    F_O2(550 nm) = 1.1021.""")


def king_factor_air_bodhaine_1999(wavelengths_nm: ArrayLike, co2_ppm: float = 360.0) -> np.ndarray:
    r"""King factor of dry air, a mixing-ratio-weighted mean over its gases.

    F_air = (78.084 F_N2 + 20.946 F_O2 + 0.934 F_Ar + C F_CO2) / (78.084 + 20.946 + 0.934 + C),
    F_N2 = 1.034 + 3.17e-4 lam^-2, F_O2 = 1.096 + 1.385e-3 lam^-2 + 1.448e-4 lam^-4,
    F_Ar = 1.00, F_CO2 = 1.15; lam in µm, C the CO2 mixing ratio in percent by volume
    (`king_factor_n2_bates_1984`, `king_factor_o2_bates_1984`).
    Bodhaine et al. (1999), J. Atmos. Oceanic Technol. 16, 1854, eqs. 23-27,
    doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2 (F_N2 and F_O2 from Bates 1984).
    F_air(550 nm, 360 ppm) = 1.0488.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    co2_ppm : float
        CO2 volume mixing ratio. [ppm]

    Returns
    -------
    ndarray, shape S
        King factor F. [-]
    """
    f_n2 = king_factor_n2_bates_1984(wavelengths_nm)
    f_o2 = king_factor_o2_bates_1984(wavelengths_nm)
    c_percent = co2_ppm * 1.0e-4
    f_ar = KING_FACTOR_AR_BODHAINE_1999
    f_co2 = KING_FACTOR_CO2_BODHAINE_1999
    return ((78.084 * f_n2 + 20.946 * f_o2 + 0.934 * f_ar + c_percent * f_co2)
            / (78.084 + 20.946 + 0.934 + c_percent))


def rayleigh_cross_section(wavelengths_nm: ArrayLike, n_minus_1: ArrayLike,
                           reference_number_density_m3: float,
                           king_factor: ArrayLike) -> np.ndarray:
    r"""Rayleigh scattering cross-section per molecule.

    sigma = 24 pi^3 (n^2 - 1)^2 / (lambda^4 N_s^2 (n^2 + 2)^2) F,
    with lambda in metres inside. Bodhaine et al. (1999), J. Atmos. Oceanic Technol. 16, 1854,
    eq. 2, doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2. n must be the refractive index
    at the number density N_s; the ratio (n^2 - 1)/N_s makes sigma independent of the density.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    n_minus_1 : array_like, broadcastable to S
        Refractivity n - 1 at `reference_number_density_m3`. [-]
    reference_number_density_m3 : float
        Number density N_s at which `n_minus_1` holds. [m^-3]
    king_factor : array_like, broadcastable to S
        King correction factor F. [-]

    Returns
    -------
    ndarray, shape S
        Scattering cross-section. [m^2]
    """
    lam_m = np.asarray(wavelengths_nm, dtype=np.float64) * 1.0e-9
    nm1 = np.asarray(n_minus_1, dtype=np.float64)
    n2_minus_1 = nm1 * (nm1 + 2.0)  # n^2 - 1 without cancellation
    n2_plus_2 = n2_minus_1 + 3.0
    return (24.0 * np.pi**3 * n2_minus_1**2
            / (lam_m**4 * reference_number_density_m3**2 * n2_plus_2**2)
            * np.asarray(king_factor, dtype=np.float64))


def rayleigh_cross_section_from_polarizability(wavelengths_nm: ArrayLike,
                                               polarizability_m3: ArrayLike,
                                               king_factor: ArrayLike) -> np.ndarray:
    r"""Rayleigh scattering cross-section per molecule from its polarisability volume.

    sigma = 128 pi^5 alpha'^2 F / (3 lambda^4),
    alpha' = alpha / (4 pi eps0) the polarisability volume [m^3]; lambda in metres inside.
    This is `rayleigh_cross_section` (Bodhaine et al. 1999, eq. 2) with the Lorentz-Lorenz
    relation (n^2 - 1) / (n^2 + 2) = 4 pi N alpha' / 3 substituted, so both give the same sigma
    for the same molecule; in a dilute gas n - 1 = 2 pi N alpha' to first order.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    polarizability_m3 : array_like, broadcastable to S
        Polarisability volume alpha'. [m^3]
    king_factor : array_like, broadcastable to S
        King correction factor F. [-]

    Returns
    -------
    ndarray, shape S
        Scattering cross-section. [m^2]
    """
    lam_m = np.asarray(wavelengths_nm, dtype=np.float64) * 1.0e-9
    alpha = np.asarray(polarizability_m3, dtype=np.float64)
    return (128.0 * np.pi**5 * alpha**2 / (3.0 * lam_m**4)
            * np.asarray(king_factor, dtype=np.float64))


def rayleigh_optical_depth_bodhaine1999(wavelength_nm: ArrayLike) -> np.ndarray:
    r"""Sea-level Rayleigh optical depth of the standard Earth atmosphere.

    tau_R = 0.0021520 (1.0455996 - 341.29061 lam^-2 - 0.90230850 lam^2)
                    / (1 + 0.0027059889 lam^-2 - 85.968563 lam^2),   lam in µm
    Bodhaine et al. (1999), J. Atmos. Oceanic Technol. 16, 1854, eq. 30,
    doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2. A fit for 1013.25 hPa, 45° latitude
    and 360 ppm CO2; for other air use `optics.rayleigh.rayleigh_cross_section`.

    Parameters
    ----------
    wavelength_nm : array_like, shape (..., n_wl)
        Wavelength. [nm]

    Returns
    -------
    ndarray, shape (..., n_wl)
        Vertical optical depth, sea level to space. [-]
    """
    lam = np.asarray(wavelength_nm, dtype=np.float64) * 1.0e-3
    lam2 = lam * lam
    return (0.0021520 * (1.0455996 - 341.29061 / lam2 - 0.90230850 * lam2)
            / (1.0 + 0.0027059889 / lam2 - 85.968563 * lam2))


# King-factor models by name: gas -> F(wavelengths_nm, co2_ppm). Bodhaine 1999 (eqs. 23-27)
# gives F for air and its four main gases; for the other gases give a depolarisation ratio.
KING_FACTOR_MODELS = {
    "bodhaine-1999": {
        "air": king_factor_air_bodhaine_1999,
        "ar": lambda wl, co2_ppm: np.full(np.shape(wl), KING_FACTOR_AR_BODHAINE_1999),
        "co2": lambda wl, co2_ppm: np.full(np.shape(wl), KING_FACTOR_CO2_BODHAINE_1999),
        "n2": lambda wl, co2_ppm: king_factor_n2_bates_1984(wl),
        "o2": lambda wl, co2_ppm: king_factor_o2_bates_1984(wl),
    },
    "none": {
        gas: (lambda wl, co2_ppm: np.ones(np.shape(wl))) for gas in GASES
    },
}

RAYLEIGH_PHASES: dict[str, type] = {"rayleigh": RayleighPhase, "penndorf": PenndorfPhase}


def _choice(registry: dict, name: str, what: str) -> str:
    key = str(name).strip().lower()
    if key not in registry:
        allowed = ", ".join(sorted(registry))
        raise InputError(f"unknown {what} {name!r}; allowed: {allowed}", key=what, value=name,
                         allowed=allowed)
    return key


def rayleigh_phase(phase: PhaseFunction | str) -> PhaseFunction:
    """`phase` itself, or the phase function `RAYLEIGH_PHASES` names ("rayleigh",
    "penndorf"; any case and surrounding blanks)."""
    if isinstance(phase, str):
        return RAYLEIGH_PHASES[_choice(RAYLEIGH_PHASES, phase, "phase")]()
    return phase


@dataclass(frozen=True)
class RayleighOptics:
    """Rayleigh-scattering optics of a gas whose density profile is a number density [m^-3].

    extinction_per_density = scattering_per_density = sigma(lambda) [m^2] from
    `rayleigh_cross_section`, with n - 1 from `refractive_index.gas_refractivity` and the King
    factor from `king` (a name in `KING_FACTOR_MODELS`) or, when given, from `depolarization`
    (`king_factor_from_depolarization`).

    Parameters
    ----------
    gas : str
        A name in `refractive_index.GASES`: "air", "ar", "ch4", "co2", "h2", "he", "n2", "o2".
    king : str
        "bodhaine-1999" (air: Bodhaine eqs. 23-27; N2, O2: Bates 1984; Ar: 1.00; CO2: 1.15; no
        value for ch4, h2, he: give `depolarization`) or "none" (F = 1).
    depolarization : float or None
        Depolarisation ratio delta; overrides `king` when given (then `king` must be left at
        its default). [-]
    co2_ppm : float
        CO2 mixing ratio of "air" (refractivity and King factor). [ppm]
    phase : str or PhaseFunction
        "rayleigh" or "penndorf", or any PhaseFunction object.
    """

    gas: str = "air"
    king: str = "bodhaine-1999"
    depolarization: float | None = None
    co2_ppm: float = 360.0
    phase: PhaseFunction | str = "rayleigh"

    def __post_init__(self) -> None:
        gas = _choice(GASES, self.gas, "gas")
        king = _choice(KING_FACTOR_MODELS, self.king, "king")
        if gas not in KING_FACTOR_MODELS[king] and self.depolarization is None:
            allowed = ", ".join(sorted(KING_FACTOR_MODELS[king]))
            raise InputError(f"King-factor model {king!r} has no value for gas {gas!r}; it "
                             f"covers: {allowed} (or give depolarization=...)", key="king",
                             value=king, allowed=allowed)
        if self.depolarization is not None:
            if king != "bodhaine-1999":
                raise InputError("give either king or depolarization, not both", key="king",
                                 value=self.king)
            king_factor_from_depolarization(self.depolarization)  # validates the range
        if not np.isfinite(self.co2_ppm) or self.co2_ppm < 0.0:
            raise InputError(f"co2_ppm = {self.co2_ppm!r} must be >= 0", key="co2_ppm",
                             value=self.co2_ppm, allowed=">= 0 ppm")
        phase = rayleigh_phase(self.phase)
        object.__setattr__(self, "gas", gas)
        object.__setattr__(self, "king", king)
        object.__setattr__(self, "phase", phase)

    def king_factor(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        """King factor F on `wavelengths_nm` [nm], same shape. [-]"""
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        if self.depolarization is not None:
            return np.broadcast_to(king_factor_from_depolarization(self.depolarization),
                                   wl.shape).copy()
        return KING_FACTOR_MODELS[self.king][self.gas](wl, self.co2_ppm)

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Scattering cross-section per molecule, shape of `wavelengths_nm` [nm]. [m^2]"""
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        n_minus_1, n_s = gas_refractivity(self.gas, wl, co2_ppm=self.co2_ppm)
        return rayleigh_cross_section(wl, n_minus_1, n_s, self.king_factor(wl))

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction cross-section per molecule (= scattering: no absorption). [m^2]"""
        return self.scattering_per_density(wavelengths_nm)


@dataclass(frozen=True)
class TabulatedScatteringOptics:
    """Per-density coefficients given directly, e.g. tabulated at a few wavelengths by a paper.

    For a relative density profile (1 at the ground) the per-density values are the sea-level
    coefficients [m^-1]: Costa et al. (2020) Table 1 gives Earth's Rayleigh
    beta_s = (5.1768, 12.2588, 30.5964) 1e-6 m^-1 at (680, 550, 440) nm. Values are interpolated
    linearly in wavelength and held constant outside the table (`SpectralParameter.at`).
    No check that extinction >= scattering: some published presets violate it (Costa 2020's
    Earth Mie extinction = 0.1 x scattering), and presets reproduce them as printed.

    Parameters
    ----------
    scattering : SpectralParameter
        Scattering per unit density. [m^2 or m^-1]
    extinction : SpectralParameter or None
        Extinction per unit density; None means equal to `scattering` (no absorption).
        [m^2 or m^-1]
    phase : PhaseFunction or None
        Phase function of the scattered light.
    """

    scattering: SpectralParameter
    extinction: SpectralParameter | None = None
    phase: PhaseFunction | None = None

    def __post_init__(self) -> None:
        for name in ("scattering", "extinction"):
            param = getattr(self, name)
            if param is None:
                continue
            if not isinstance(param, SpectralParameter):
                param = SpectralParameter.constant(param)
                object.__setattr__(self, name, param)
            if not np.all(np.isfinite(param.values)) or min(param.values) < 0.0:
                raise InputError(f"{name} = {list(param.values)} must be finite and >= 0",
                                 key=name, value=param.values, allowed=">= 0")
        if self.phase is None and max(self.scattering.values) > 0.0:
            raise InputError("a scattering constituent needs a phase function", key="phase",
                             value=None, allowed="a PhaseFunction")

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Scattering per unit density on `wavelengths_nm` [nm]. [m^2 or m^-1]"""
        return self.scattering.at(wavelengths_nm)

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction per unit density on `wavelengths_nm` [nm]. [m^2 or m^-1]"""
        source = self.scattering if self.extinction is None else self.extinction
        return source.at(wavelengths_nm)
