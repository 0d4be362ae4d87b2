"""Density profiles: how much of a constituent there is at each altitude.

Three shapes cover the configs: an exponential with a scale height, Bruneton's piecewise layers
(exponential + linear terms, clamped to [0, 1]; Bruneton 2017, `DensityProfileLayer`), and a
table of altitude -> density. Profiles are multiplied by a factor to reach a given column
(Dobson units, optical depth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "ExponentialProfile",
    "LayeredProfile",
    "ProfileLayer",
    "ScaledProfile",
    "TabulatedProfile",
    "vertical_column",
]


@dataclass(frozen=True)
class ExponentialProfile:
    """density(h) = surface_density * exp(-h / scale_height_m)."""

    scale_height_m: float
    surface_density: float = 1.0

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        h = np.asarray(altitude_m, dtype=np.float64)
        return self.surface_density * np.exp(-h / self.scale_height_m)


@dataclass(frozen=True)
class ProfileLayer:
    """One layer of Bruneton's density profile, used below `top_altitude_m`.

    density(h) = clamp(exp_term * exp(exp_scale_per_m * h) + linear_per_m * h + constant, 0, 1)
    Bruneton (2017), precomputed_atmospheric_scattering, definitions.glsl `DensityProfileLayer`.
    """

    top_altitude_m: float
    exp_term: float = 0.0
    exp_scale_per_m: float = 0.0
    linear_per_m: float = 0.0
    constant: float = 0.0

    def density(self, altitude_m: np.ndarray) -> np.ndarray:
        value = (self.exp_term * np.exp(self.exp_scale_per_m * altitude_m)
                 + self.linear_per_m * altitude_m + self.constant)
        return np.clip(value, 0.0, 1.0)


@dataclass(frozen=True)
class LayeredProfile:
    """Layers stacked from the ground up; the last layer extends to the top of the atmosphere."""

    layers: tuple[ProfileLayer, ...]

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        h = np.asarray(altitude_m, dtype=np.float64)
        result = self.layers[-1].density(h)
        for layer in reversed(self.layers[:-1]):
            result = np.where(h < layer.top_altitude_m, layer.density(h), result)
        return result


@dataclass(frozen=True)
class TabulatedProfile:
    """A table altitude [m] -> density, interpolated linearly in log(density) ("log",
    exact for piecewise exponential profiles) or linearly ("linear"). Below the table the first
    value holds; above it the density is zero."""

    altitudes_m: tuple[float, ...]
    densities: tuple[float, ...]
    interpolation: str = "log"

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        h = np.asarray(altitude_m, dtype=np.float64)
        z = np.asarray(self.altitudes_m)
        d = np.asarray(self.densities)
        if self.interpolation == "log":
            positive = np.where(d > 0.0, d, np.finfo(np.float64).tiny)
            value = np.exp(np.interp(h, z, np.log(positive)))
            value = np.where(value <= np.finfo(np.float64).tiny * 1e3, 0.0, value)
        else:
            value = np.interp(h, z, d)
        return np.where(h > z[-1], 0.0, value)


@dataclass(frozen=True)
class ScaledProfile:
    """Another profile times a constant factor (to reach a column or a peak density)."""

    profile: object  # DensityProfile
    factor: float

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        return self.factor * self.profile.density(altitude_m)


def vertical_column(profile: object, top_altitude_m: float, n_levels: int = 20001) -> float:
    """Integral of density from the ground to `top_altitude_m` [density x m], trapezoid rule
    on `n_levels` uniform levels (the solvers interpolate linearly between levels, so this is
    the column they see when they use the same levels)."""
    h = np.linspace(0.0, top_altitude_m, n_levels)
    return float(np.trapezoid(profile.density(h), h))
