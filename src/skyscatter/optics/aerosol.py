"""Aerosol (and other) extinction that follows a power law in wavelength: the Ångström law.

beta_e(lambda) = beta_e(lambda_0) (lambda / lambda_0)^-alpha   (Ångström 1929)
`AngstromOptics` is a `ConstituentOptics` with that extinction, a single-scattering albedo and a
phase function. It covers the parameterised aerosols of the seed documents (Bruneton 2017's Mie
layer: alpha = 0, optical depth beta = 5.328e-3 over a 1.2 km scale height, i.e. 4.44e-6 m^-1 at
the ground, albedo 0.9, Cornette-Shanks g = 0.8) and, with alpha = 4,
albedo 1 and a Rayleigh phase function, Bruneton's Rayleigh beta = 1.24062e-6 lambda[µm]^-4
m^-1 (extinction 1.24062e-6 at a 1000 nm reference).

References: Ångström (1929), Geogr. Ann. 11, 156, doi:10.1080/20014422.1929.11880498;
Bruneton (2017), precomputed_atmospheric_scattering, atmosphere/demo/demo.cc.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.phase import PhaseFunction
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = ["AngstromOptics", "angstrom_law"]


def angstrom_law(wavelengths_nm: ArrayLike, value_at_reference: float, reference_nm: float,
                 exponent: float) -> np.ndarray:
    r"""Ångström's power law, value(lambda) = value(lambda_0) (lambda / lambda_0)^-alpha.

    Ångström (1929), Geogr. Ann. 11, 156, doi:10.1080/20014422.1929.11880498. alpha ~ 0-2 for
    aerosols (1.3 is Ångström's average), 4 for Rayleigh scattering without dispersion.

    Parameters
    ----------
    wavelengths_nm : array_like, shape S
        Wavelength. [nm]
    value_at_reference : float
        Value at `reference_nm` (optical depth, coefficient or cross-section). [any]
    reference_nm : float
        Reference wavelength lambda_0. [nm]
    exponent : float
        Ångström exponent alpha. [-]

    Returns
    -------
    ndarray, shape S
        Value at each wavelength, in the unit of `value_at_reference`.
    """
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0.0):
        raise InputError(f"wavelengths must be finite and > 0 nm, got {wl!r}",
                         key="wavelengths_nm", value=wl, allowed="> 0 nm")
    return value_at_reference * (wl / reference_nm) ** (-exponent)


@dataclass(frozen=True, kw_only=True)
class AngstromOptics:
    """Extinction by the Ångström law, scattering = single-scattering albedo x extinction.

    The per-density unit is whatever the constituent's profile implies: m^-1 (the coefficient at
    density 1) for a relative profile, m^2 for a number density.

    Parameters
    ----------
    extinction_at_reference : float
        Extinction per unit density at `reference_wavelength_nm`. [m^-1 or m^2]
    reference_wavelength_nm : float
        Reference wavelength. [nm]
    angstrom_exponent : float
        Ångström exponent alpha. [-]
    single_scattering_albedo : SpectralParameter or float
        Scattering / extinction, in [0, 1]. [-]
    phase : PhaseFunction
        Phase function of the scattered light.
    """

    extinction_at_reference: float
    reference_wavelength_nm: float = 550.0
    angstrom_exponent: float
    single_scattering_albedo: SpectralParameter = SpectralParameter.constant(1.0)
    phase: PhaseFunction

    def __post_init__(self) -> None:
        for name, low, closed in (("extinction_at_reference", 0.0, True),
                                  ("reference_wavelength_nm", 0.0, False)):
            value = getattr(self, name)
            ok = np.isfinite(value) and (value >= low if closed else value > low)
            if not ok:
                relation = ">=" if closed else ">"
                raise InputError(f"{name} = {value!r} must be finite and {relation} {low}",
                                 key=name, value=value, allowed=f"{relation} {low}")
        if not np.isfinite(self.angstrom_exponent):
            raise InputError(f"angstrom_exponent = {self.angstrom_exponent!r} must be finite",
                             key="angstrom_exponent", value=self.angstrom_exponent)
        ssa = self.single_scattering_albedo
        if not isinstance(ssa, SpectralParameter):
            ssa = SpectralParameter.constant(ssa)
            object.__setattr__(self, "single_scattering_albedo", ssa)
        values = np.asarray(ssa.values)
        if not np.all((values >= 0.0) & (values <= 1.0)):
            raise InputError(f"single_scattering_albedo = {list(values)} must lie in [0, 1]",
                             key="single_scattering_albedo", value=ssa.values,
                             allowed="[0, 1]")

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction per unit density on `wavelengths_nm` [nm]. [m^-1 or m^2]"""
        return angstrom_law(wavelengths_nm, self.extinction_at_reference,
                            self.reference_wavelength_nm, self.angstrom_exponent)

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Scattering per unit density, albedo x extinction. [m^-1 or m^2]"""
        return (self.single_scattering_albedo.at(wavelengths_nm)
                * self.extinction_per_density(wavelengths_nm))
