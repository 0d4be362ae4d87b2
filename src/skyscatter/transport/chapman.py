"""Column densities along rays in closed form: Schüler's approximation of the Chapman function,
and each constituent of a profile fitted to an exponential or a thin layer.

Symbols: r distance to the planet centre [m], mu cosine of the ray's zenith angle chi [-],
R bottom radius [m], H scale height [m], x = r / H [-].

The column of an exponential density n0 exp(-(r' - R) / H) along the ray (r, mu) out to
infinity is (Chapman 1931; Schüler 2012, eqs. 2-5)

    m(r, mu) = n0 H exp(-(r - R) / H) Ch(x, chi).

Schüler's approximation (C. Schüler, "An Approximation to the Chapman Grazing-Incidence
Function for Atmospheric Scattering", GPU Pro 3, ed. W. Engel, CRC Press 2012, pp. 105-118):
a rational function of cos chi above the horizon, with Ch = 1 at the zenith and the exact
horizontal value c = Ch(x, 90 deg) = (1 / (2 x) + 1) sqrt(pi x / 2):

    Ch(x, chi) ~ c / ((c - 1) cos chi + 1),                          0 <= chi <= 90 deg,

and below the horizon the whole line's column less the part behind the observer, with the
perigee x0 = x sin chi:

    Ch(x, chi) = 2 exp(x - x0) Ch(x0, 90 deg) - Ch(x, 180 deg - chi),  90 < chi <= 180 deg.

Both are evaluated in the scaled form Ch(x, chi) exp(-(r - R) / H) (Schüler's first
modification), so nothing overflows while the perigee is above the ground; a ray that meets
the ground is taken backwards (upwards) instead by the callers. Deliberate departures from the
published shader: base e instead of base 2 with the "50 % height" (the shader's exp2 with
H ln 2 and beta ln 2 scales the optical depth by (ln 2)^3 ~ 0.33), and the horizontal value
c of eq. 11 in place of the shader's c = sqrt(x) ("nearly equal paths", about 20 % low at
the horizon). Accuracy, measured against the numerical integral at x = 795 (Earth's air,
tests/transport/test_chapman.py): exact at 0 and 90 deg, -0.4 % at 30 deg, -2.4 % at 60 deg,
-8.6 % at 80 deg, -13.8 % at 88 deg (the approximation's largest error, just above the
horizon).

A constituent of the profile whose density is largest at the ground is fitted with the
exponential of its ground density n0 and the scale height H that keeps its vertical column
on the profile's levels, n0 H (1 - exp(-z_top / H)) (`fit_constituents`). Any other (an ozone
layer, an elevated aerosol layer) is a thin absorbing shell at its column's centroid altitude
z_c with its whole vertical column N, crossed at the local zenith cosine mu_c with the slant
factor 1 / sqrt(mu_c^2 + w / (R + z_c)), w the layer's standard deviation in altitude: 1 / mu_c
away from grazing, sqrt((R + z_c) / w) at grazing (a thin shell's 1 / mu_c has no limit). The
share of the layer a ray crosses is that of a Gaussian of width w about z_c (the part above
the ray's start going up; going down, the part between the perigee and the start and then all
above the perigee), so that the column changes smoothly with the observer's height and the
ray's perigee (a hard shell draws rings in twilight skies, where the sun's rays graze it). Its
limits: the slant factor is the shell's, not the layer's (the lower half's longer paths near
the horizon are missed), the Gaussian puts ~0.6 % of the preset's ozone below the ground, and
the inscattering of a layered scatterer still uses its true density
(`transport/schuler.py`). Earth's ozone (the earth preset, centroid 22.5 km, w 9 km) from the
ground: the optical depth 0.7 % low at the zenith, 2.7 % at 80 deg, 14 % at 88 deg and 23 % at
the horizon (tests/transport/test_schuler.py).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from skyscatter.atmosphere.model import OpticalProfile

__all__ = [
    "EXPONENTIAL",
    "LAYER",
    "ColumnModel",
    "chapman_horizontal",
    "chapman_schuler_2012",
    "exponential_column",
    "fit_constituents",
    "layer_column",
]

EXPONENTIAL = 0  # `ColumnModel.kind`: n0 exp(-z / H)
LAYER = 1  # a thin shell of column N at z_c, width w
# fixed-point iterations of H = N / (n0 (1 - exp(-z_top / H))); each gains the factor
# exp(-z_top / H) z_top / H (< 0.01 for z_top > 7 H), so 50 reach rounding for z_top > 2 H
_FIT_ITERATIONS = 50


class ColumnModel(NamedTuple):
    """Per constituent (n_c,) arrays of the closed-form column model (module docstring).

    kind           EXPONENTIAL or LAYER
    ground_density n0 of an exponential [density]; 0 for a layer
    scale_height   H of an exponential [m]; 1 for a layer
    layer_radius   R + z_c of a layer [m]; 0 for an exponential
    layer_width    w of a layer [m]
    layer_column   N of a layer [density x m]
    """

    kind: np.ndarray
    ground_density: np.ndarray
    scale_height: np.ndarray
    layer_radius: np.ndarray
    layer_width: np.ndarray
    layer_column: np.ndarray


def fit_constituents(profile: OpticalProfile) -> ColumnModel:
    """Each constituent of `profile` as an exponential or a thin layer (module docstring)."""
    z = profile.altitudes_m
    top = float(z[-1])
    n_c = profile.density.shape[0]
    kind = np.zeros(n_c, dtype=np.int64)
    n0, height = np.zeros(n_c), np.ones(n_c)
    radius, width, column = np.zeros(n_c), np.ones(n_c), np.zeros(n_c)
    for c, density in enumerate(profile.density):
        total = float(np.trapezoid(density, z))
        if total <= 0.0:
            continue
        if density[0] >= density.max():
            n0[c] = density[0]
            h = total / n0[c]
            for _ in range(_FIT_ITERATIONS):
                h = total / (n0[c] * -math.expm1(-top / h))
            height[c] = h
        else:
            kind[c] = LAYER
            centroid = float(np.trapezoid(density * z, z)) / total
            spread = float(np.trapezoid(density * (z - centroid) ** 2, z)) / total
            radius[c] = profile.bottom_radius_m + centroid
            width[c] = max(math.sqrt(spread), 1.0)
            column[c] = total
    return ColumnModel(kind, n0, height, radius, width, column)


@njit(cache=True, inline="always")
def chapman_horizontal(x):
    """Ch(x, 90 deg) = (1 / (2 x) + 1) sqrt(pi x / 2) [-], x = r / H (Schüler 2012, eq. 11;
    exact for an exponential atmosphere to O(1 / x^2))."""
    return (0.5 / x + 1.0) * math.sqrt(0.5 * math.pi * x)


@njit(cache=True)
def chapman_schuler_2012(x, cos_chi):
    """Schüler's approximation of the Chapman function Ch(x, chi) [-] (module docstring),
    x = r / H [-], cos_chi the ray's zenith cosine; the unscaled form (use
    `exponential_column` along rays: exp(x - x0) overflows for x of thousands)."""
    c = chapman_horizontal(x)
    if cos_chi >= 0.0:
        return c / ((c - 1.0) * cos_chi + 1.0)
    x0 = x * math.sqrt(max(1.0 - cos_chi * cos_chi, 0.0))
    return (2.0 * math.exp(x - x0) * chapman_horizontal(x0)
            - c / ((c - 1.0) * -cos_chi + 1.0))


@njit(cache=True, inline="always")
def exponential_column(r, mu, bottom_radius, scale_height):
    """Column [m per unit ground density] of exp(-(r' - R) / H) along the ray (r, mu) to
    infinity, Schüler's Ch(x, chi) exp(-(r - R) / H) times H (module docstring); finite for rays
    whose perigee is above the ground (or little below it)."""
    x = r / scale_height
    c = chapman_horizontal(x)
    above = math.exp(-(r - bottom_radius) / scale_height)
    if mu >= 0.0:
        return scale_height * above * c / ((c - 1.0) * mu + 1.0)
    r0 = r * math.sqrt(max(1.0 - mu * mu, 0.0))
    whole = 2.0 * math.exp(-(r0 - bottom_radius) / scale_height) * chapman_horizontal(
        r0 / scale_height)
    return scale_height * (whole - above * c / ((c - 1.0) * -mu + 1.0))


@njit(cache=True, inline="always")
def layer_column(r, mu, layer_radius, layer_width):
    """Column [per unit vertical column] of a layer centred on the radius `layer_radius` with
    the width (standard deviation) `layer_width` [m] along the ray (r, mu) to infinity, the
    planet ignored: the slant factor 1 / sqrt(mu_c^2 + w / R_c) of its crossing (mu_c the
    zenith cosine at R_c; 0 where the line passes above it) times the share of the layer the
    ray crosses, a Gaussian's: a(r) = erfc((r - R_c) / (sqrt(2) w)) / 2 above r upwards, and
    2 a(p) - a(r) downwards through the perigee p (module docstring)."""
    p2 = r * r * (1.0 - mu * mu)  # perigee radius squared
    cos2 = max(1.0 - p2 / (layer_radius * layer_radius), 0.0)
    scale = math.sqrt(2.0) * layer_width
    above = 0.5 * math.erfc((r - layer_radius) / scale)
    if mu < 0.0:
        share = 2.0 * 0.5 * math.erfc((math.sqrt(p2) - layer_radius) / scale) - above
    else:
        share = above
    return share / math.sqrt(cos2 + layer_width / layer_radius)
