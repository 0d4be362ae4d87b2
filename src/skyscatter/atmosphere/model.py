"""Planet and Atmosphere objects, and the sampled optical profile that solvers consume.

An atmosphere is a spherical shell of constituents (air, ozone, aerosol, ...). Each constituent
is separable: coefficient(h, lambda) = density(h) * per_density(lambda), where density(h) is the
constituent's profile (a number density in m^-3, or a dimensionless relative density) and
per_density(lambda) an extinction/scattering cross-section (m^2 when the density is a number
density, m^-1 when it is relative). Separability lets solvers integrate wavelength-free column
densities along rays and apply all wavelengths at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.phase import PhaseFunction
from skyscatter.spectrum.star import Star
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "DEFAULT_PROFILE_LEVELS",
    "DEFAULT_SCATTERING_ORDERS",
    "MAX_PROFILE_LEVELS",
    "MAX_SCATTERING_ORDERS",
    "Atmosphere",
    "Constituent",
    "ConstituentOptics",
    "DensityProfile",
    "OpticalProfile",
    "Planet",
]

# Scattering orders of the tables when a config does not say: Earth's value in Bruneton 2017
# (github.com/ebruneton/precomputed_atmospheric_scattering, atmosphere/model.h,
# `Model::Init(num_scattering_orders = 4)`);
# docs/physics/orders.md measures what thicker atmospheres need.
DEFAULT_SCATTERING_ORDERS = 4
# The most scattering orders the tables may iterate ([tables] orders, --orders, the API's
# `orders`): 1 is single scattering only. Each order costs about as much as the single-
# scattering table (seconds at the default size); the presets need 6-21
# (docs/physics/orders.md), and diffuse light through a vertical optical depth tau takes about
# tau^2 orders, so the thickest atmosphere a config may describe (tau up to 1000, Venus-like
# decks ~30) can use hundreds. Past 1000 a typo is likelier than a need.
MAX_SCATTERING_ORDERS = 1000
# Uniform altitude levels of `Atmosphere.optical_profile` when the caller does not say: 2001
# (50 m for Earth's 100 km), or more where a constituent's profile asks for a finer spacing
# (`altitude_step_m`: a 300 m fog layer asks for 7.5 m, 13 335 levels), up to the maximum
# (0.5 m for 100 km; 1.6 MB of densities per constituent).
DEFAULT_PROFILE_LEVELS = 2001
MAX_PROFILE_LEVELS = 200_001


class DensityProfile(Protocol):
    """Density of one constituent as a function of altitude above the ground. A profile with
    features thinner than the default levels resolve may also have `altitude_step_m`, the
    largest level spacing [m] that samples it well (`Atmosphere.profile_levels`)."""

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        """Density at `altitude_m` [m]; same shape as the input. [m^-3 or relative]"""
        ...


class ConstituentOptics(Protocol):
    """Optical cross-sections of one unit of a constituent's density."""

    phase: PhaseFunction | None  # None for pure absorbers

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Extinction per unit density, shape (n_wl,). [m^2 or m^-1]"""
        ...

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Scattering per unit density, shape (n_wl,). [m^2 or m^-1]"""
        ...


@dataclass(frozen=True)
class Constituent:
    """One constituent: a name, a density profile and its optics."""

    name: str
    profile: DensityProfile
    optics: ConstituentOptics
    # When set, the sampled density is scaled so that its vertical column on the solver's own
    # altitude levels is exactly this [density x m] (a Dobson column, or 1 for an optical depth).
    vertical_column: float | None = None


@dataclass(frozen=True)
class Planet:
    """A spherical planet lit by one star."""

    name: str
    radius_m: float
    ground_albedo: SpectralParameter  # Lambertian reflectance [-]
    star: Star
    # Which solar-system body the planet is, for skies at a date and time (astro/): "earth",
    # "mars", or "" (an imagined planet: no ephemeris, the sun is placed by hand)
    body: str = ""


@dataclass(frozen=True)
class Atmosphere:
    """A planet with a shell atmosphere from the ground up to `top_altitude_m`."""

    planet: Planet
    top_altitude_m: float
    constituents: tuple[Constituent, ...]
    name: str = "atmosphere"
    description: str = ""
    source: str = ""  # file or preset it came from, for messages
    # Scattering orders the table solver iterates by default ([tables] orders in a config;
    # thick or dusty air needs more than Earth's 4: docs/physics/orders.md)
    scattering_orders: int = DEFAULT_SCATTERING_ORDERS

    def __post_init__(self) -> None:
        orders = self.scattering_orders
        if isinstance(orders, bool) or not isinstance(orders, int | np.integer) or not (
                1 <= orders <= MAX_SCATTERING_ORDERS):
            allowed = f"an integer from 1 to {MAX_SCATTERING_ORDERS}"
            raise InputError(f"Atmosphere.scattering_orders = {orders!r} must be {allowed}",
                             key="scattering_orders", value=orders, allowed=allowed)

    @property
    def bottom_radius_m(self) -> float:
        return self.planet.radius_m

    @property
    def top_radius_m(self) -> float:
        return self.planet.radius_m + self.top_altitude_m

    @property
    def profile_levels(self) -> int:
        """Uniform altitude levels that resolve every constituent: `DEFAULT_PROFILE_LEVELS`, or
        enough for the finest `altitude_step_m` a profile asks for, at most
        `MAX_PROFILE_LEVELS`."""
        step = min((getattr(c.profile, "altitude_step_m", math.inf) for c in self.constituents),
                   default=math.inf)
        # a step that underflows to 0 (an edge of 1e-320 m) asks for as many as allowed
        spans = self.top_altitude_m / step if step > 0.0 else math.inf
        if spans >= MAX_PROFILE_LEVELS:
            return MAX_PROFILE_LEVELS
        needed = math.ceil(spans) + 1  # 1 when no profile asks (step inf)
        return max(DEFAULT_PROFILE_LEVELS, needed)

    def optical_profile(self, wavelengths_nm: ArrayLike, n_levels: int | None = None,
                        monochromatic: bool = False) -> OpticalProfile:
        """Sample every constituent on a uniform altitude grid and a wavelength grid.

        `n_levels` uniform levels from the ground to the top; None: `profile_levels`.

        Tabulated spectra (sun, absorption cross-sections) are averaged over each grid cell
        (edges halfway between neighbouring wavelengths), the right thing for a spectral grid
        that is integrated into colour. `monochromatic=True` treats each wavelength on its own
        (a 1 nm cell), for users who ask for values at a few chosen wavelengths."""
        wl = np.atleast_1d(np.asarray(wavelengths_nm, dtype=np.float64))
        n_levels = self.profile_levels if n_levels is None else n_levels
        altitudes = np.linspace(0.0, self.top_altitude_m, n_levels)
        density = np.array([c.profile.density(altitudes) for c in self.constituents],
                           dtype=np.float64).reshape(len(self.constituents), n_levels)
        for row, constituent in zip(density, self.constituents, strict=True):
            if constituent.vertical_column is not None:
                sampled = np.trapezoid(row, altitudes)
                if sampled <= 0.0 < constituent.vertical_column:
                    needed = self.profile_levels
                    raise InputError(
                        f"n_levels = {n_levels} misses constituent {constituent.name!r}: its "
                        f"density is zero on every level; use n_levels >= {needed} (or None)",
                        key="n_levels", value=n_levels, allowed=f">= {needed}")
                row *= constituent.vertical_column / sampled

        def spectrum(function) -> np.ndarray:
            if monochromatic:
                return np.concatenate([np.atleast_1d(function(wl[i:i + 1]))
                                       for i in range(wl.size)])
            return np.asarray(function(wl), dtype=np.float64).reshape(wl.size)

        extinction = np.array([spectrum(c.optics.extinction_per_density)
                               for c in self.constituents]).reshape(-1, wl.size)
        scattering = np.array([spectrum(c.optics.scattering_per_density)
                               for c in self.constituents]).reshape(-1, wl.size)
        return OpticalProfile(
            wavelengths_nm=wl,
            bottom_radius_m=self.bottom_radius_m,
            top_radius_m=self.top_radius_m,
            altitudes_m=altitudes,
            density=density,
            extinction_per_density=extinction,
            scattering_per_density=scattering,
            phases=tuple(c.optics.phase for c in self.constituents),
            names=tuple(c.name for c in self.constituents),
            ground_albedo=self.planet.ground_albedo.at(wl),
            toa_irradiance=spectrum(self.planet.star.irradiance_toa),
            sun_angular_radius_rad=self.planet.star.angular_radius_rad,
        )


@dataclass(frozen=True)
class OpticalProfile:
    """An atmosphere sampled for the solvers: arrays only, SI units, wavelength last.

    extinction(h, lambda) = sum_c density[c, h] * extinction_per_density[c, lambda]  [m^-1]
    Densities are linearly interpolated between the uniform `altitudes_m` levels.
    """

    wavelengths_nm: np.ndarray  # (n_wl,) [nm]
    bottom_radius_m: float
    top_radius_m: float
    altitudes_m: np.ndarray  # (n_z,) uniform, from 0 to top [m]
    density: np.ndarray  # (n_c, n_z) [m^-3 or relative]
    extinction_per_density: np.ndarray  # (n_c, n_wl) [m^2 or m^-1]
    scattering_per_density: np.ndarray  # (n_c, n_wl) [m^2 or m^-1]
    phases: tuple[PhaseFunction | None, ...]  # (n_c,)
    names: tuple[str, ...]  # (n_c,)
    ground_albedo: np.ndarray  # (n_wl,) [-]
    toa_irradiance: np.ndarray  # (n_wl,) normal to the beam at the top [W m^-2 nm^-1]
    sun_angular_radius_rad: float

    @property
    def n_wavelengths(self) -> int:
        return self.wavelengths_nm.size

    def extinction_at(self, altitude_m: ArrayLike) -> np.ndarray:
        """Total extinction coefficient at `altitude_m`, shape S + (n_wl,). [m^-1]"""
        h = np.asarray(altitude_m, dtype=np.float64)
        dens = np.stack([np.interp(h, self.altitudes_m, d, right=0.0) for d in self.density],
                        axis=-1)
        return dens @ self.extinction_per_density
