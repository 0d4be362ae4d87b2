"""Gases and gas mixtures: molar mass and Rayleigh cross-section of each gas, and of a mixture.

Each `GasSpecies` knows its molar mass M [kg mol^-1] and its Rayleigh cross-section
sigma(lambda) [m^2], from its refractivity n - 1 at a number density N_s
(`optics.refractive_index`, `rayleigh.rayleigh_cross_section`) or from its polarisability
volume alpha' (`rayleigh.rayleigh_cross_section_from_polarizability`), times its King factor F.
A `GasMixture` of mole fractions x_i scatters as one gas (Costa et al. 2020, Eq. 11, with the
cross-sections of the gases added):

    sigma_mix(lambda) = sum_i x_i sigma_i(lambda)        M_mix = sum_i x_i M_i

`SPECIES` holds N2, O2, Ar, CO2, H2, He and CH4; `custom_species` makes any other gas from its
molar mass and refractivity (or polarisability) and depolarisation ratio.

Molar masses: the conventional standard atomic weights of IUPAC/CIAAW, Prohaska et al. (2022),
Pure Appl. Chem. 94, 573, doi:10.1515/pac-2019-0603 (H 1.008, He 4.0026, C 12.011, N 14.007,
O 15.999, Ar 39.95 g/mol).
King factors: N2, O2 Bates (1984) and Ar, CO2 Bodhaine et al. (1999) (`optics.rayleigh`); He and
CH4 F = 1 (an atom and a spherical top scatter without depolarisation); H2 F = 1 too, which
leaves out its small depolarisation (we found no value we could check: give H2 as a custom
species with `depolarization` to include one).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.phase import PhaseFunction
from skyscatter.optics.rayleigh import (
    KING_FACTOR_MODELS,
    king_factor_from_depolarization,
    rayleigh_cross_section,
    rayleigh_cross_section_from_polarizability,
    rayleigh_phase,
)
from skyscatter.optics.refractive_index import gas_refractivity
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "MOLE_FRACTION_TOLERANCE",
    "SPECIES",
    "GasMixture",
    "GasSpecies",
    "custom_species",
]

# Mole fractions must add up to 1 within this (else normalise explicitly): loose enough for
# rounded published compositions (dry air N2 + O2 + Ar + 400 ppm CO2: 1.00004), tight enough to
# catch a missing or mistyped gas.
MOLE_FRACTION_TOLERANCE = 1.0e-3


@dataclass(frozen=True)
class GasSpecies:
    """One gas: its molar mass and how to get its Rayleigh cross-section.

    Exactly one of `refractivity` and `polarizability_m3` is set.

    Parameters
    ----------
    name : str
        Lower-case name ("n2", or a custom one).
    molar_mass_kg_mol : float
        Molar mass M. [kg mol^-1]
    king_factor : callable
        wavelengths_nm [nm] -> King factor F, same shape. [-]
    refractivity : callable or None
        wavelengths_nm [nm] -> (n - 1 [-], same shape; number density N_s at which it holds
        [m^-3]).
    polarizability_m3 : float or None
        Polarisability volume alpha' (wavelength-independent). [m^3]
    description : str
        Where the numbers come from, for people.
    """

    name: str
    molar_mass_kg_mol: float
    king_factor: Callable[[np.ndarray], np.ndarray]
    refractivity: Callable[[np.ndarray], tuple[np.ndarray, float]] | None = None
    polarizability_m3: float | None = None
    description: str = ""

    def __post_init__(self) -> None:
        if (self.refractivity is None) == (self.polarizability_m3 is None):
            raise InputError(f"gas {self.name!r}: give exactly one of refractivity and "
                             "polarizability_m3", key="refractivity", value=None,
                             allowed="refractivity or polarizability_m3")
        _positive(self.molar_mass_kg_mol, "molar_mass_g_mol", self.molar_mass_kg_mol * 1e3)

    def cross_section(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        """Rayleigh scattering cross-section sigma on `wavelengths_nm` [nm], same shape. [m^2]"""
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        king = self.king_factor(wl)
        if self.polarizability_m3 is not None:
            return rayleigh_cross_section_from_polarizability(wl, self.polarizability_m3, king)
        n_minus_1, n_s = self.refractivity(wl)
        return rayleigh_cross_section(wl, n_minus_1, n_s, king)


def _positive(value: float, key: str, shown: float | None = None) -> None:
    if not np.isfinite(value) or value <= 0.0:
        raise InputError(f"{key} = {shown if shown is not None else value!r} must be > 0",
                         key=key, value=shown if shown is not None else value, allowed="> 0")


def _builtin(name: str, molar_mass_g_mol: float, description: str,
             king: Callable[[np.ndarray], np.ndarray] | None = None) -> GasSpecies:
    """A gas of `refractive_index.GASES`, King factor from Bodhaine 1999 or F = 1."""
    if king is None:
        bodhaine = KING_FACTOR_MODELS["bodhaine-1999"][name]

        def king(wl: np.ndarray) -> np.ndarray:
            return bodhaine(wl, 0.0)

    return GasSpecies(name, molar_mass_g_mol * 1.0e-3, king,
                      refractivity=lambda wl: gas_refractivity(name, wl),
                      description=description)


def _unity(wl: np.ndarray) -> np.ndarray:
    return np.ones(np.shape(wl))


# Built-in gases by name; molar masses [g/mol] from the CIAAW conventional atomic weights.
SPECIES: dict[str, GasSpecies] = {
    "ar": _builtin("ar", 39.95, "argon: Peck & Fisher 1964; F = 1.00 (Bodhaine 1999)"),
    "ch4": _builtin("ch4", 16.043, "methane: n - 1 = 4.44e-4 (Kaye & Laby, 589 nm, no "
                    "dispersion); F = 1 (spherical top)", _unity),
    "co2": _builtin("co2", 44.009, "carbon dioxide: Bideau-Mehu et al. 1973; F = 1.15 "
                    "(Bodhaine 1999)"),
    "h2": _builtin("h2", 2.016, "hydrogen: Peck & Huang 1977; F = 1 (depolarisation left out)",
                   _unity),
    "he": _builtin("he", 4.0026, "helium: Mansfield & Peck 1969; F = 1 (atom)", _unity),
    "n2": _builtin("n2", 28.014, "nitrogen: Peck & Khanna 1966 / Bates 1984; F: Bates 1984"),
    "o2": _builtin("o2", 31.998, "oxygen: Zhang et al. 2008; F: Bates 1984"),
}


def custom_species(name: str, molar_mass_g_mol: float, *,
                   refractivity: float | SpectralParameter | None = None,
                   refractivity_number_density_m3: float | None = None,
                   polarizability_m3: float | None = None,
                   depolarization: float = 0.0) -> GasSpecies:
    """A gas that is not in `SPECIES`, from numbers a user knows.

    Give either `refractivity` (n - 1, one number or a SpectralParameter over wavelength, with
    the number density N_s at which it was measured: sigma from `rayleigh_cross_section`) or
    `polarizability_m3` (alpha': sigma = 128 pi^5 alpha'^2 F / (3 lambda^4)). The King factor
    is F = (6 + 3 delta) / (6 - 7 delta) (`king_factor_from_depolarization`).

    Parameters
    ----------
    name : str
        Name used in the composition; must not be one of `SPECIES`.
    molar_mass_g_mol : float
        Molar mass. [g mol^-1]
    refractivity : float or SpectralParameter or None
        n - 1 at `refractivity_number_density_m3`. [-]
    refractivity_number_density_m3 : float or None
        Number density N_s at which `refractivity` holds, e.g. `LOSCHMIDT_M3` for 0 °C and
        101325 Pa. [m^-3]
    polarizability_m3 : float or None
        Polarisability volume alpha' = alpha / (4 pi eps0); 1 Å^3 = 1e-30 m^3. [m^3]
    depolarization : float
        Depolarisation ratio delta for natural light, 0 <= delta < 6/7. [-]

    Returns
    -------
    GasSpecies
    """
    key = str(name).strip().lower()
    if not key:
        raise InputError("a custom gas needs a name", key="name", value=name,
                         allowed="a non-empty string")
    if key in SPECIES:
        allowed = ", ".join(sorted(SPECIES))
        raise InputError(f"name = {name!r} is a built-in gas; a custom gas needs another name "
                         f"(built-in: {allowed})", key="name", value=name,
                         allowed=f"not one of {allowed}")
    _positive(molar_mass_g_mol, "molar_mass_g_mol")
    factor = float(king_factor_from_depolarization(depolarization))

    def king(wl: np.ndarray) -> np.ndarray:
        return np.full(np.shape(wl), factor)

    if (refractivity is None) == (polarizability_m3 is None):
        raise InputError(f"gas {name!r}: give exactly one of refractivity and "
                         "polarizability_m3", key="refractivity", value=refractivity,
                         allowed="refractivity (with refractivity_number_density_m3) or "
                         "polarizability_m3")
    if polarizability_m3 is not None:
        if refractivity_number_density_m3 is not None:
            raise InputError("refractivity_number_density_m3 goes with refractivity, not "
                             "with polarizability_m3", key="refractivity_number_density_m3",
                             value=refractivity_number_density_m3, allowed="only with "
                             "refractivity")
        _positive(polarizability_m3, "polarizability_m3")
        return GasSpecies(key, molar_mass_g_mol * 1.0e-3, king,
                          polarizability_m3=float(polarizability_m3),
                          description=f"custom: alpha' = {polarizability_m3:g} m^3, "
                          f"delta = {depolarization:g}")
    table = (refractivity if isinstance(refractivity, SpectralParameter)
             else SpectralParameter.constant(refractivity))
    if not np.all(np.isfinite(table.values)) or np.any(np.asarray(table.values) <= 0.0):
        raise InputError(f"refractivity = {list(table.values)} must be > 0 (n - 1, not n)",
                         key="refractivity", value=list(table.values), allowed="> 0")
    if refractivity_number_density_m3 is None:
        raise InputError("refractivity needs refractivity_number_density_m3, the number "
                         "density at which n - 1 was measured (2.6867811e25 m^-3 at 0 °C and "
                         "101325 Pa)", key="refractivity_number_density_m3", value=None,
                         allowed="> 0 m^-3")
    _positive(refractivity_number_density_m3, "refractivity_number_density_m3")
    n_s = float(refractivity_number_density_m3)
    return GasSpecies(key, molar_mass_g_mol * 1.0e-3, king,
                      refractivity=lambda wl: (table.at(wl), n_s),
                      description=f"custom: n - 1 at {n_s:g} m^-3, delta = {depolarization:g}")


@dataclass(frozen=True)
class GasMixture:
    """Rayleigh optics of a gas mixture whose density profile is a number density [m^-3].

    extinction_per_density = scattering_per_density = sigma_mix = sum_i x_i sigma_i [m^2],
    molar mass M = sum_i x_i M_i. The fractions are divided by their sum, which must lie within
    `MOLE_FRACTION_TOLERANCE` of 1 (`GasMixture.from_composition(..., normalize=True)` accepts
    any positive sum).

    Parameters
    ----------
    species : tuple of GasSpecies
        The gases, names unique.
    mole_fractions : tuple of float
        Mole (volume) fraction x_i of each gas, >= 0. [-]
    phase : str or PhaseFunction
        "rayleigh" or "penndorf", or any PhaseFunction object.
    """

    species: tuple[GasSpecies, ...]
    mole_fractions: tuple[float, ...]
    phase: PhaseFunction | str = "rayleigh"

    def __post_init__(self) -> None:
        species = tuple(self.species)
        fractions = tuple(float(x) for x in self.mole_fractions)
        if not species or len(species) != len(fractions):
            raise InputError("a gas mixture needs one mole fraction per gas, and at least one "
                             "gas", key="composition", value=dict(zip(
                                 [s.name for s in species], fractions, strict=False)),
                             allowed="{ gas = mole fraction, ... }")
        names = [s.name for s in species]
        if len(set(names)) != len(names):
            raise InputError(f"gas names must be unique, got {names}", key="composition",
                             value=names, allowed="unique names")
        composition = dict(zip(names, fractions, strict=True))
        for name, x in composition.items():
            if not np.isfinite(x) or x < 0.0 or x > 1.0:
                raise InputError(f"mole fraction of {name} = {x!r} must lie in [0, 1]",
                                 key=name, value=x, allowed="0 ... 1")
        total = sum(fractions)
        if abs(total - 1.0) > MOLE_FRACTION_TOLERANCE:
            raise InputError(f"mole fractions {composition} add up to {total:.6g}, not 1 "
                             f"(within {MOLE_FRACTION_TOLERANCE:g}); fix them, or normalise "
                             "explicitly (normalize = true in a [gas] table)",
                             key="composition", value=composition,
                             allowed=f"a sum within {MOLE_FRACTION_TOLERANCE:g} of 1")
        phase = rayleigh_phase(self.phase)
        object.__setattr__(self, "species", species)
        object.__setattr__(self, "mole_fractions", tuple(x / total for x in fractions))
        object.__setattr__(self, "phase", phase)

    @classmethod
    def from_composition(cls, composition: Mapping[str, float],
                         custom: Sequence[GasSpecies] = (), *, normalize: bool = False,
                         phase: PhaseFunction | str = "rayleigh") -> GasMixture:
        """A mixture from {gas name: mole fraction}; names from `SPECIES` or `custom`.

        `normalize=True` divides the fractions by their sum, whatever it is (> 0); otherwise
        the sum must lie within `MOLE_FRACTION_TOLERANCE` of 1. A custom gas that has no
        fraction in `composition` is an error (probably a typo).
        """
        known = dict(SPECIES)
        for gas in custom:
            if gas.name in known:
                raise InputError(f"gas {gas.name!r} is defined twice", key="name",
                                 value=gas.name, allowed="unique names")
            known[gas.name] = gas
        species, fractions = [], []
        for name, x in composition.items():
            key = str(name).strip().lower()
            if key not in known:
                allowed = ", ".join(sorted(known))
                raise InputError(f"unknown gas {name!r}; known gases: {allowed} (or define it "
                                 "as a custom species)", key=str(name), value=x,
                                 allowed=allowed)
            species.append(known[key])
            fractions.append(x)
        used = {s.name for s in species}
        for gas in custom:
            if gas.name not in used:
                raise InputError(f"custom gas {gas.name!r} has no mole fraction in the "
                                 "composition", key="composition", value=dict(composition),
                                 allowed=f"a composition that includes {gas.name!r}")
        if normalize:
            total = sum(float(x) for x in fractions)
            if not np.isfinite(total) or total <= 0.0:
                raise InputError(f"mole fractions add up to {total!r}; normalising needs a "
                                 "sum > 0", key="composition", value=dict(composition),
                                 allowed="a sum > 0")
            fractions = [float(x) / total for x in fractions]
        return cls(tuple(species), tuple(fractions), phase)

    @property
    def composition(self) -> dict[str, float]:
        """{gas name: mole fraction}, the fractions adding up to 1. [-]"""
        return {s.name: x for s, x in zip(self.species, self.mole_fractions, strict=True)}

    @property
    def molar_mass_kg_mol(self) -> float:
        """Mean molar mass M = sum_i x_i M_i. [kg mol^-1]"""
        return float(sum(x * s.molar_mass_kg_mol
                         for s, x in zip(self.species, self.mole_fractions, strict=True)))

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """sigma_mix = sum_i x_i sigma_i on `wavelengths_nm` [nm], same shape. [m^2]"""
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        total = np.zeros(wl.shape)
        for gas, x in zip(self.species, self.mole_fractions, strict=True):
            if x > 0.0:
                total = total + x * gas.cross_section(wl)
        return total

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction cross-section per molecule (= scattering: no absorption). [m^2]"""
        return self.scattering_per_density(wavelengths_nm)
