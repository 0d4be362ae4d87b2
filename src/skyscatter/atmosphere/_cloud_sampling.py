"""The kernels that sample cloud fields (`atmosphere.cloud_field` has the equations): the noise
tile, trilinearly and periodically; the water content of a layer at a point; the index of a
scattering angle in the layers' phase tables. The renderer (`transport._cloud_kernels`) and the
Monte Carlo reference read clouds only through these.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = [
    "ALONG_X",
    "ALONG_Y",
    "ALONG_Z",
    "BASE_R",
    "COVERAGE",
    "COVERAGE_TILE_RATIO",
    "DETAIL",
    "EDGE",
    "INV_DETAIL_SCALE",
    "INV_SCALE",
    "N_PARAMS",
    "N_PROFILE",
    "OFFSET_X",
    "OFFSET_Y",
    "OFFSET_Z",
    "PHASE_ANGLES",
    "SHEET",
    "STRETCH_MINUS_ONE",
    "TOP_R",
    "VARIATION",
    "WATER",
    "layer_water",
    "phase_table_index",
    "smooth_layer_water",
    "sample_texture",
]

PHASE_ANGLES = 1024  # phase table nodes, theta = pi (i / (n - 1))^2: 0.0017 deg steps at 0
COVERAGE_TILE_RATIO = 7.31  # the coverage varies on tiles this much larger (no common period)

# Columns of `CloudField.params`
BASE_R, TOP_R, COVERAGE, WATER, INV_SCALE, INV_DETAIL_SCALE, DETAIL = 0, 1, 2, 3, 4, 5, 6
EDGE, VARIATION, SHEET, N_PROFILE, OFFSET_X, OFFSET_Y, OFFSET_Z = 7, 8, 9, 10, 11, 12, 13
ALONG_X, ALONG_Y, ALONG_Z, STRETCH_MINUS_ONE = 14, 15, 16, 17
N_PARAMS = 18


@njit(cache=True, inline="always")
def sample_texture(textures, tile, channel, x, y, z):
    """Trilinear sample of `textures[tile, ..., channel]` ((n_tiles, n, n, n, 2), n a power
    of two) at texel coordinates (x, y, z), wrapping around (texel centres at i + 0.5)."""
    mask = textures.shape[1] - 1
    x -= 0.5
    y -= 0.5
    z -= 0.5
    fx, fy, fz = math.floor(x), math.floor(y), math.floor(z)
    tx, ty, tz = x - fx, y - fy, z - fz
    i0, j0, k0 = int(fx) & mask, int(fy) & mask, int(fz) & mask
    i1, j1, k1 = (i0 + 1) & mask, (j0 + 1) & mask, (k0 + 1) & mask
    c00 = textures[tile, i0, j0, k0, channel] * (1 - tz) + textures[tile, i0, j0, k1, channel] * tz
    c01 = textures[tile, i0, j1, k0, channel] * (1 - tz) + textures[tile, i0, j1, k1, channel] * tz
    c10 = textures[tile, i1, j0, k0, channel] * (1 - tz) + textures[tile, i1, j0, k1, channel] * tz
    c11 = textures[tile, i1, j1, k0, channel] * (1 - tz) + textures[tile, i1, j1, k1, channel] * tz
    return ((c00 * (1 - ty) + c01 * ty) * (1 - tx)) + ((c10 * (1 - ty) + c11 * ty) * tx)


@njit(cache=True, inline="always")
def phase_table_index(nu):
    """(index, weight) of cos(scattering angle) `nu` in the phase table's angle nodes."""
    theta = np.arccos(min(1.0, max(-1.0, nu)))
    x = np.sqrt(theta / np.pi) * (PHASE_ANGLES - 1)
    i = min(int(x), PHASE_ANGLES - 2)
    return i, x - i


@njit(cache=True)
def _profile(profiles, layer, n_nodes, h):
    """Piecewise-linear profile factor at height fraction h in [0, 1]."""
    for k in range(1, n_nodes):
        h1 = profiles[layer, k, 0]
        if h <= h1:
            h0 = profiles[layer, k - 1, 0]
            t = (h - h0) / (h1 - h0)
            return profiles[layer, k - 1, 1] * (1.0 - t) + profiles[layer, k, 1] * t
    return profiles[layer, n_nodes - 1, 1]


@njit(cache=True)
def layer_water(params, profiles, textures, layer, x, y, z, r):
    """Water content w [g m^-3] of `layer` at the world point (x, y, z), |p| = r [m]
    (module docstring); 0 outside the layer's shell."""
    return _water(params, profiles, textures, layer, x, y, z, r, True)


@njit(cache=True)
def smooth_layer_water(params, profiles, textures, layer, x, y, z, r):
    """`layer_water` without the detail noise's erosion: the water the renderer's light paths
    march (the erosion's small-scale holes hardly change a path's total, and skipping it
    saves one of three texture reads)."""
    return _water(params, profiles, textures, layer, x, y, z, r, False)


@njit(cache=True, inline="always")
def _water(params, profiles, textures, layer, x, y, z, r, detail):
    """`layer_water`, with the detail noise's erosion when `detail`."""
    base, top = params[layer, BASE_R], params[layer, TOP_R]
    if r < base or r > top:
        return 0.0
    h = 0.5 if params[layer, SHEET] > 0.0 else (r - base) / (top - base)
    # moved by the wind, stretched along it
    x -= params[layer, OFFSET_X]
    y -= params[layer, OFFSET_Y]
    z -= params[layer, OFFSET_Z]
    ax, ay, az = params[layer, ALONG_X], params[layer, ALONG_Y], params[layer, ALONG_Z]
    shrink = params[layer, STRETCH_MINUS_ONE] / (1.0 + params[layer, STRETCH_MINUS_ONE])
    along = (x * ax + y * ay + z * az) * shrink
    x -= along * ax
    y -= along * ay
    z -= along * az
    n = textures.shape[1]
    tile = params[layer, INV_SCALE] * n
    coverage = params[layer, COVERAGE] * _profile(profiles, layer, int(params[layer, N_PROFILE]),
                                                  h)
    variation = params[layer, VARIATION]
    if variation > 0.0:
        large = tile / COVERAGE_TILE_RATIO
        # a different slice of the same tile: axes permuted, so no common period
        weather = sample_texture(textures, layer, 0, z * large, x * large, y * large)
        coverage *= 1.0 + variation * (2.0 * weather - 1.0)
    if coverage <= 0.0:
        return 0.0
    coverage = min(coverage, 1.0)
    shape = sample_texture(textures, layer, 0, x * tile, y * tile, z * tile)
    d = (shape - (1.0 - coverage)) / (params[layer, EDGE] * coverage)
    if d <= 0.0:
        return 0.0
    d = min(d, 1.0)
    strength = params[layer, DETAIL]
    if detail and strength > 0.0:
        fine = params[layer, INV_DETAIL_SCALE] * n
        erosion = strength * sample_texture(textures, layer, 1, x * fine, y * fine, z * fine)
        d = (d - erosion) / (1.0 - erosion)
        if d <= 0.0:
            return 0.0
    return params[layer, WATER] * d
