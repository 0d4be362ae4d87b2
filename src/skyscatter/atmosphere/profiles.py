"""Density profiles: how much of a constituent there is at each altitude.

Four shapes cover the configs: an exponential with a scale height, Bruneton's piecewise layers
(exponential + linear terms, clamped to [0, 1]; Bruneton 2017, `DensityProfileLayer`), a
table of altitude -> density, and a uniform layer between a base and a top (a cloud, fog or
dust-storm deck). Profiles are multiplied by a factor to reach a given column
(Dobson units, optical depth).

A profile may say how finely it must be sampled (`altitude_step_m`, the largest level spacing
that resolves it); `Atmosphere.optical_profile` takes the finest any constituent asks for.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError

__all__ = [
    "ExponentialProfile",
    "LayeredProfile",
    "ProfileLayer",
    "ScaledProfile",
    "TabulatedProfile",
    "UniformLayerProfile",
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
class UniformLayerProfile:
    r"""A horizontally uniform layer: `peak_density` between `base_altitude_m` and
    `top_altitude_m`, zero outside.

    With `edge_m` = w > 0 each boundary above the ground becomes a raised-cosine ramp of width w
    centred on it, s(u) = (1 + sin(pi u)) / 2 for u = (h - boundary) / w in [-1/2, 1/2] (rising
    at the base, falling at the top); a base on the ground (0 m) stays sharp. The ramp is
    point-symmetric about the boundary, so the column is peak_density x (top - base) for every
    w, the same as the sharp layer's (`column`). A sharp boundary above the ground has half the
    density (the mean of both sides), so that trapezoid levels on it keep the column exact.
    Requires 0 <= base < top, w <= top - base (the ramps do not overlap) and, for a base above
    the ground, w / 2 <= base.
    """

    base_altitude_m: float
    top_altitude_m: float
    peak_density: float = 1.0
    edge_m: float = 0.0

    # Levels across the layer's thickness and across each smooth edge that `altitude_step_m`
    # asks for. Thickness: 40 levels smear a sharp boundary over 1/40 of the thickness (the
    # column stays exact: `Constituent.vertical_column`); edge: with 8 levels the linear
    # interpolant of the ramp's sine is within 1 % of the peak density (pi^2 / (16 x 8^2)).
    LEVELS_PER_THICKNESS = 40
    LEVELS_PER_EDGE = 8

    def __post_init__(self) -> None:
        base, top, edge = self.base_altitude_m, self.top_altitude_m, self.edge_m
        if not (0.0 <= base < top) or not (0.0 <= edge <= top - base) or (
                base > 0.0 and edge / 2.0 > base):
            raise InputError(
                f"UniformLayerProfile(base_altitude_m={base!r}, top_altitude_m={top!r}, "
                f"edge_m={edge!r}): needs 0 <= base < top, 0 <= edge <= top - base and "
                "edge / 2 <= base for a base above the ground", key="base_altitude_m",
                value=base, allowed="0 <= base < top; 0 <= edge <= top - base")

    def density(self, altitude_m: ArrayLike) -> np.ndarray:
        h = np.asarray(altitude_m, dtype=np.float64)
        base, top, w = self.base_altitude_m, self.top_altitude_m, self.edge_m
        if base == 0.0:
            rise = np.heaviside(h, 1.0)  # the ground belongs to a layer based on it
        else:
            rise = _ramp((h - base) / w) if w > 0.0 else np.heaviside(h - base, 0.5)
        fall = _ramp((top - h) / w) if w > 0.0 else np.heaviside(top - h, 0.5)
        return self.peak_density * rise * fall

    @property
    def column(self) -> float:
        """Vertical column, exact: peak_density x (top - base). [density x m]"""
        return self.peak_density * (self.top_altitude_m - self.base_altitude_m)

    @property
    def altitude_step_m(self) -> float:
        """Largest uniform level spacing that resolves the layer (class constants). [m]"""
        step = (self.top_altitude_m - self.base_altitude_m) / self.LEVELS_PER_THICKNESS
        if self.edge_m > 0.0:
            step = min(step, self.edge_m / self.LEVELS_PER_EDGE)
        return step


def _ramp(u: np.ndarray) -> np.ndarray:
    """(1 + sin(pi u)) / 2 on [-1/2, 1/2], 0 below, 1 above: `UniformLayerProfile`'s edge."""
    return 0.5 * (1.0 + np.sin(np.pi * np.clip(u, -0.5, 0.5)))


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
