"""A planet's gas layer from what is known about it: composition, surface temperature and
pressure, gravity (Costa et al. 2020, "advanced mode", Eq. 11 and section 4.1).

The gas is ideal, isothermal at the surface temperature T and in hydrostatic equilibrium under
a constant gravity g, so its number density falls off exponentially:

    N0 = P / (k T)            (or N_A rho / M from a mass density rho)
    H  = R T / (M g)          (R = k N_A; M the mean molar mass of the mixture)
    N(h) = N0 exp(-h / H)
    column = N0 H (1 - exp(-h_top / H))  ->  P N_A / (M g) for h_top >> H
    tau_R(lambda) = sigma_mix(lambda) x column

g = G M_p / R_p^2 when the planet's mass M_p and radius R_p are given instead. Costa, Bock,
Emmart, Hansen, Ynnerman & Silva (2021), IEEE TVCG 27(2), 785, doi:10.1109/TVCG.2020.3030333.
Real atmospheres are not isothermal (Earth's U.S. Standard Atmosphere 1976 cools by 6.5 K/km
up to 11 km); the isothermal layer keeps the surface density and the column P / g (within the
variation of g with height) and changes only how the gas is spread over height.

`GasLayer` is that layer; it is the density profile of the constituent it makes, so
`describe_gas(atmosphere)` can report the derived numbers of a loaded atmosphere.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import Atmosphere, Constituent
from skyscatter.atmosphere.profiles import ExponentialProfile
from skyscatter.errors import InputError
from skyscatter.optics.gases import GasMixture
from skyscatter.spectrum.star import BOLTZMANN

__all__ = [
    "AVOGADRO",
    "GRAVITATIONAL_CONSTANT",
    "MOLAR_GAS_CONSTANT",
    "STANDARD_GRAVITY",
    "GasLayer",
    "describe_gas",
    "number_density_from_mass_density",
    "number_density_from_pressure",
    "scale_height",
    "surface_gravity",
]

AVOGADRO = 6.02214076e23  # mol⁻¹, exact (SI 2019)
MOLAR_GAS_CONSTANT = AVOGADRO * BOLTZMANN  # J mol⁻¹ K⁻¹, exact (SI 2019): 8.314462618...
GRAVITATIONAL_CONSTANT = 6.67430e-11  # m³ kg⁻¹ s⁻², CODATA 2018
STANDARD_GRAVITY = 9.80665  # m s⁻², exact by definition (3rd CGPM, 1901)


def _check_positive(**values: float) -> None:
    for key, value in values.items():
        if isinstance(value, bool) or not math.isfinite(value) or value <= 0.0:
            raise InputError(f"{key} = {value!r} must be > 0", key=key, value=value,
                             allowed="> 0")


def scale_height(temperature_k: float, molar_mass_kg_mol: float, gravity_m_s2: float) -> float:
    r"""Scale height of an isothermal atmosphere, H = R T / (M g) [m].

    Costa et al. (2020), section 4.1; R = k N_A (`MOLAR_GAS_CONSTANT`).

    Parameters
    ----------
    temperature_k : float
        Temperature T. [K]
    molar_mass_kg_mol : float
        Mean molar mass M. [kg mol^-1]
    gravity_m_s2 : float
        Gravitational acceleration g. [m s^-2]
    """
    _check_positive(temperature_k=temperature_k, molar_mass_kg_mol=molar_mass_kg_mol,
                    gravity_m_s2=gravity_m_s2)
    return MOLAR_GAS_CONSTANT * temperature_k / (molar_mass_kg_mol * gravity_m_s2)


def number_density_from_pressure(pressure_pa: float, temperature_k: float) -> float:
    """Number density of an ideal gas, N = P / (k T) [m^-3]; P [Pa], T [K]."""
    _check_positive(pressure_pa=pressure_pa, temperature_k=temperature_k)
    return pressure_pa / (BOLTZMANN * temperature_k)


def number_density_from_mass_density(mass_density_kg_m3: float,
                                     molar_mass_kg_mol: float) -> float:
    """Number density from a mass density, N = N_A rho / M [m^-3] (Costa et al. 2020,
    section 4.1); rho [kg m^-3], M [kg mol^-1]."""
    _check_positive(mass_density_kg_m3=mass_density_kg_m3, molar_mass_kg_mol=molar_mass_kg_mol)
    return AVOGADRO * mass_density_kg_m3 / molar_mass_kg_mol


def surface_gravity(mass_kg: float, radius_m: float) -> float:
    """Gravitational acceleration at the surface of a spherical planet, g = G M / R^2
    [m s^-2]; M [kg], R [m]. No rotation (the centrifugal term lowers g at the equator)."""
    _check_positive(mass_kg=mass_kg, radius_m=radius_m)
    return GRAVITATIONAL_CONSTANT * mass_kg / radius_m**2


@dataclass(frozen=True)
class GasLayer:
    """An isothermal, hydrostatic layer of a gas mixture; a density profile [m^-3].

    density(h) = N0 exp(-h / H), H = R T / (M g) (`scale_height`), M from the mixture.

    Parameters
    ----------
    mixture : GasMixture
        The gases and their Rayleigh optics.
    surface_temperature_k : float
        Temperature T of the whole layer. [K]
    surface_number_density_m3 : float
        Number density N0 at the ground. [m^-3]
    gravity_m_s2 : float
        Gravitational acceleration g, constant with height. [m s^-2]
    """

    mixture: GasMixture
    surface_temperature_k: float
    surface_number_density_m3: float
    gravity_m_s2: float

    def __post_init__(self) -> None:
        _check_positive(surface_temperature_k=self.surface_temperature_k,
                        surface_number_density_m3=self.surface_number_density_m3,
                        gravity_m_s2=self.gravity_m_s2)

    @property
    def molar_mass_kg_mol(self) -> float:
        """Mean molar mass M of the mixture. [kg mol^-1]"""
        return self.mixture.molar_mass_kg_mol

    @property
    def scale_height_m(self) -> float:
        """H = R T / (M g). [m]"""
        return scale_height(self.surface_temperature_k, self.molar_mass_kg_mol,
                            self.gravity_m_s2)

    @property
    def surface_pressure_pa(self) -> float:
        """P = N0 k T. [Pa]"""
        return self.surface_number_density_m3 * BOLTZMANN * self.surface_temperature_k

    @property
    def surface_mass_density_kg_m3(self) -> float:
        """rho = N0 M / N_A. [kg m^-3]"""
        return self.surface_number_density_m3 * self.molar_mass_kg_mol / AVOGADRO

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        """Number density N0 exp(-h / H) at `altitude_m` [m], same shape. [m^-3]"""
        return ExponentialProfile(self.scale_height_m,
                                  self.surface_number_density_m3).density(altitude_m)

    def column_m2(self, top_altitude_m: float) -> float:
        """Vertical column N0 H (1 - exp(-h_top / H)) from the ground to `top_altitude_m`
        [m]. [m^-2]"""
        h = self.scale_height_m
        return self.surface_number_density_m3 * h * -math.expm1(-top_altitude_m / h)

    def optical_depth(self, wavelengths_nm: ArrayLike, top_altitude_m: float) -> np.ndarray:
        """Vertical Rayleigh optical depth sigma_mix x column, same shape as
        `wavelengths_nm` [nm]. [-]"""
        return self.mixture.scattering_per_density(wavelengths_nm) * self.column_m2(
            top_altitude_m)

    def constituent(self, name: str = "gas") -> Constituent:
        """The atmosphere constituent: this layer as profile, the mixture as optics."""
        return Constituent(name=name, profile=self, optics=self.mixture)


def describe_gas(atmosphere: Atmosphere,
                 wavelengths_nm: Sequence[float] = (440.0, 550.0, 680.0)) -> list[dict]:
    """The derived numbers of each gas layer of `atmosphere` (a [gas] table in its config).

    One dict per constituent whose profile is a `GasLayer` (none: an empty list), with keys
    name, composition {gas: mole fraction}, molar_mass_g_mol, surface_temperature_k,
    surface_pressure_pa, surface_number_density_m3, surface_mass_density_kg_m3, gravity_m_s2,
    scale_height_m, column_m2 (ground to top), mass_column_kg_m2, and rayleigh_optical_depth
    {wavelength_nm: vertical tau_R from the ground to the top}.
    """
    result = []
    top = atmosphere.top_altitude_m
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    for constituent in atmosphere.constituents:
        layer = constituent.profile
        if not isinstance(layer, GasLayer):
            continue
        column = layer.column_m2(top)
        tau = layer.optical_depth(wl, top)
        result.append({
            "name": constituent.name,
            "composition": layer.mixture.composition,
            "molar_mass_g_mol": layer.molar_mass_kg_mol * 1.0e3,
            "surface_temperature_k": layer.surface_temperature_k,
            "surface_pressure_pa": layer.surface_pressure_pa,
            "surface_number_density_m3": layer.surface_number_density_m3,
            "surface_mass_density_kg_m3": layer.surface_mass_density_kg_m3,
            "gravity_m_s2": layer.gravity_m_s2,
            "scale_height_m": layer.scale_height_m,
            "column_m2": column,
            "mass_column_kg_m2": column * layer.molar_mass_kg_mol / AVOGADRO,
            "rayleigh_optical_depth": {float(w): float(t) for w, t in zip(wl, tau,
                                                                          strict=True)},
        })
    return result
