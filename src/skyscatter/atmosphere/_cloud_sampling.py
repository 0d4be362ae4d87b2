"""The kernels that sample cloud fields (`atmosphere.cloud_field` has the equations): the noise
tile, trilinearly and periodically; a layer's coverage map at a point's latitude and longitude;
the water content of a layer at a point; the index of a scattering angle in the layers' phase
tables. The renderer (`transport._cloud_kernels`) and the Monte Carlo reference read clouds
only through these.

Each layer's user data rides in its rows of `CloudField.profiles` after the profile's
`MAX_PROFILE_NODES` nodes, two numbers a row (`layer_datum`): first the layer's column
statistics, `COLUMN_VALUES` numbers for each of the map factors i / (COLUMN_NODES - 1) (the
cloudy column fraction, then the mean water paths [g m^-2] of the `COLUMN_SHARES` of the
cloudy columns, thinnest first; for the far field of `transport._cloud_kernels`), then its
coverage map (row-major, north row first) or, for a grid layer, its water grid (C order:
index (i ny + j) nz + k of cell (i, j, k), as `water_g_m3.ravel()`). So the kernels'
signatures stay those of a procedural field. (The alternative, the grid in the layer's slot
of the noise textures, would resample it to the textures' n^3 cube and lose data.)

A grid layer (`GRID_NX` > 0, `atmosphere.cloud_grids`) replaces the noise by its grid: the
world point p, moved against the wind (p - u t), is projected on the observer's east and
north axes (`GRID_AXES`: the tangent plane, centred on the observer) and its height above the
layer's base is |p| - r_base (the box follows the planet's curvature), in cells

    u = (p - u t).east / dx + nx / 2,  v = (p - u t).north / dy + ny / 2,  s = (|p| - r_base) / dz

and w = trilinear interpolation between cell centres (u, v, s) = (i, j, k) + 1/2, wrapping
around horizontally when `GRID_PERIODIC`, otherwise 0 outside 0 <= u <= nx, 0 <= v <= ny
and each index clamped to the box (the outer half cells keep the edge cells' value); 0 on
the far side of the planet (p.up <= 0).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from skyscatter.atmosphere.cloud_config import MAX_PROFILE_NODES

__all__ = [
    "ALONG_X",
    "ALONG_Y",
    "ALONG_Z",
    "BASE_R",
    "COLUMN_BINS",
    "COLUMN_NODES",
    "COLUMN_SHARES",
    "COLUMN_VALUES",
    "COVERAGE",
    "COVERAGE_TILE_RATIO",
    "DETAIL",
    "EDGE",
    "FAR_END",
    "FAR_START",
    "GRID_AXES",
    "GRID_DX",
    "GRID_NX",
    "GRID_PERIODIC",
    "MAP_HEIGHT",
    "MAP_WIDTH",
    "INV_DETAIL_SCALE",
    "INV_SCALE",
    "N_PARAMS",
    "N_PROFILE",
    "OFFSET_X",
    "OFFSET_Y",
    "OFFSET_Z",
    "PHASE_ANGLES",
    "PLANET",
    "SHEET",
    "STRETCH_MINUS_ONE",
    "TOP_R",
    "VARIATION",
    "WATER",
    "column_cover",
    "column_statistics",
    "coverage_map_factor",
    "coverage_map_factors",
    "edge_margin",
    "grid_water",
    "layer_datum",
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
PLANET = 18  # 18-26: the rotation world -> planet-fixed, row-major (coverage maps)
MAP_WIDTH, MAP_HEIGHT = 27, 28  # the coverage map's size in pixels (0: none)
FAR_START, FAR_END = 29, 30  # the far field's blend, view-ray distances [m] (cloud_field)
GRID_AXES = 31  # 31-39: the observer's east, north and up axes in the world frame (grids)
GRID_NX, GRID_NY, GRID_NZ = 40, 41, 42  # a grid layer's cells (GRID_NX 0: noise, no grid)
GRID_DX, GRID_DY, GRID_DZ = 43, 44, 45  # its cells' size [m]
GRID_PERIODIC = 46  # 1: the grid repeats horizontally, 0: no water outside its box
N_PARAMS = 47
COLUMN_NODES = 17  # map factors 0, 1/16, ..., 1 of the column statistics (module docstring)
# The far field's columns: shares of the cloudy columns sorted by water path, thinnest first,
# doubling: the thin edges let most of the light through (stratocumulus: 5 % of the cloudy
# columns have optical depths below 2), so they get fine shares. With these shares the mean
# transmittance of the cumulus and stratocumulus presets' columns comes within 0.003 of that
# of all 16 384 columns taken one by one; 4 equal shares were 0.014-0.027 too low.
COLUMN_SHARES = (0.02, 0.04, 0.08, 0.16, 0.70)
COLUMN_BINS = 5
COLUMN_VALUES = 6  # numbers per map factor: the fraction, then each share's mean path


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


@njit(cache=True, inline="always")
def layer_datum(profiles, layer, index):
    """The layer's user datum `index` (module docstring): two a row after the profile."""
    return profiles[layer, MAX_PROFILE_NODES + (index >> 1), index & 1]


@njit(cache=True)
def coverage_map_factor(params, profiles, layer, x, y, z):
    """The layer's coverage map [0-1] at the planetocentric latitude and longitude of the
    world point (x, y, z), bilinear between pixel centres, wrapping in longitude (column 0
    starts at -180 deg, row 0 at +90 deg); 1 without a map."""
    width = int(params[layer, MAP_WIDTH])
    if width == 0:
        return 1.0
    height = int(params[layer, MAP_HEIGHT])
    q = PLANET
    px = params[layer, q] * x + params[layer, q + 1] * y + params[layer, q + 2] * z
    py = params[layer, q + 3] * x + params[layer, q + 4] * y + params[layer, q + 5] * z
    pz = params[layer, q + 6] * x + params[layer, q + 7] * y + params[layer, q + 8] * z
    latitude = math.atan2(pz, math.sqrt(px * px + py * py))
    longitude = math.atan2(py, px)
    row = min(max((0.5 - latitude / math.pi) * height - 0.5, 0.0), height - 1.0)
    column = (longitude + math.pi) / (2.0 * math.pi) * width - 0.5
    r0 = min(int(row), height - 2)
    c = math.floor(column)
    b = column - c
    c0 = int(c) % width
    c1 = (c0 + 1) % width
    a = row - r0
    start = COLUMN_VALUES * COLUMN_NODES
    top = (layer_datum(profiles, layer, start + r0 * width + c0) * (1.0 - b)
           + layer_datum(profiles, layer, start + r0 * width + c1) * b)
    bottom = (layer_datum(profiles, layer, start + (r0 + 1) * width + c0) * (1.0 - b)
              + layer_datum(profiles, layer, start + (r0 + 1) * width + c1) * b)
    return top * (1.0 - a) + bottom * a


@njit(cache=True, inline="always")
def _grid_index(s, n, periodic):
    """(i0, i1, weight of i1) of the cell-centred coordinate s [cells] on n cells: wrapped
    around when `periodic`, else clamped to 0 .. n - 1."""
    s -= 0.5
    f = math.floor(s)
    t = s - f
    i0 = int(f)
    if periodic:
        i0 %= n
        return i0, (i0 + 1) % n, t
    return min(max(i0, 0), n - 1), min(max(i0 + 1, 0), n - 1), t


@njit(cache=True)
def grid_water(params, profiles, layer, x, y, z, r):
    """Water content w [g m^-3] of the grid layer `layer` at the world point (x, y, z),
    |p| = r [m] (module docstring), trilinear between cell centres; 0 outside its shell."""
    base = params[layer, BASE_R]
    if r < base or r > params[layer, TOP_R]:
        return 0.0
    q = GRID_AXES
    if params[layer, q + 6] * x + params[layer, q + 7] * y + params[layer, q + 8] * z <= 0.0:
        return 0.0
    x -= params[layer, OFFSET_X]
    y -= params[layer, OFFSET_Y]
    z -= params[layer, OFFSET_Z]
    nx, ny, nz = int(params[layer, GRID_NX]), int(params[layer, GRID_NY]), int(params[layer,
                                                                                   GRID_NZ])
    u = (params[layer, q] * x + params[layer, q + 1] * y + params[layer, q + 2] * z) / params[
        layer, GRID_DX] + 0.5 * nx
    v = (params[layer, q + 3] * x + params[layer, q + 4] * y + params[layer, q + 5] * z) / params[
        layer, GRID_DY] + 0.5 * ny
    periodic = params[layer, GRID_PERIODIC] > 0.0
    if not periodic and (u < 0.0 or u > nx or v < 0.0 or v > ny):
        return 0.0
    i0, i1, a = _grid_index(u, nx, periodic)
    j0, j1, b = _grid_index(v, ny, periodic)
    k0, k1, c = _grid_index((r - base) / params[layer, GRID_DZ], nz, False)
    start = COLUMN_VALUES * COLUMN_NODES
    total = 0.0
    for di in range(2):
        i = i1 if di else i0
        wi = a if di else 1.0 - a
        for dj in range(2):
            j = j1 if dj else j0
            wj = b if dj else 1.0 - b
            row = start + (i * ny + j) * nz
            total += wi * wj * (layer_datum(profiles, layer, row + k0) * (1.0 - c)
                                + layer_datum(profiles, layer, row + k1) * c)
    return total


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
    return _water(params, profiles, textures, layer, x, y, z, r, True, False)


@njit(cache=True)
def smooth_layer_water(params, profiles, textures, layer, x, y, z, r):
    """`layer_water` without the detail noise's erosion: the water the renderer's light paths
    march (the erosion's small-scale holes hardly change a path's total, and skipping it
    saves one of three texture reads)."""
    return _water(params, profiles, textures, layer, x, y, z, r, False, False)


@njit(cache=True)
def edge_margin(params, profiles, textures, layer, x, y, z, r):
    """Where the point lies on the layer's edge ramp, in ramps: the shape noise's excess over
    the coverage threshold divided by the ramp's width (> 0 inside the smooth cloud, < 0
    outside: -1 is a ramp's width of noise below the threshold; -1e9 where the coverage is
    0, outside the shell and for grid layers)."""
    if params[layer, GRID_NX] > 0.0:
        return -1e9
    return _water(params, profiles, textures, layer, x, y, z, r, False, True)


@njit(cache=True, inline="always")
def _water(params, profiles, textures, layer, x, y, z, r, detail, margin):
    """`layer_water`, with the detail noise's erosion when `detail`; a grid layer's
    `grid_water`; with `margin`, `edge_margin` instead."""
    if params[layer, GRID_NX] > 0.0:
        return grid_water(params, profiles, layer, x, y, z, r)
    base, top = params[layer, BASE_R], params[layer, TOP_R]
    if r < base or r > top:
        return -1e9 if margin else 0.0
    h = 0.5 if params[layer, SHEET] > 0.0 else (r - base) / (top - base)
    # the coverage map is fixed to the planet: read at p, before the wind moves the noise
    factor = 1.0
    if params[layer, MAP_WIDTH] > 0.0:
        factor = coverage_map_factor(params, profiles, layer, x, y, z)
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
    coverage *= factor
    variation = params[layer, VARIATION]
    if variation > 0.0:
        large = tile / COVERAGE_TILE_RATIO
        # a different slice of the same tile: axes permuted, so no common period
        weather = sample_texture(textures, layer, 0, z * large, x * large, y * large)
        coverage *= 1.0 + variation * (2.0 * weather - 1.0)
    if coverage <= 0.0:
        return -1e9 if margin else 0.0
    coverage = min(coverage, 1.0)
    shape = sample_texture(textures, layer, 0, x * tile, y * tile, z * tile)
    d = (shape - (1.0 - coverage)) / (params[layer, EDGE] * coverage)
    if margin:
        return d
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


@njit(cache=True)
def column_cover(profiles, layer, m, paths):
    """The cloudy column fraction [-] of `layer` at map factor m [0-1] (returned) and the
    mean water paths [g m^-2] of its `COLUMN_SHARES` of cloudy columns (into `paths`),
    linear between the nodes of the column statistics (module docstring)."""
    x = min(max(m, 0.0), 1.0) * (COLUMN_NODES - 1)
    i = min(int(x), COLUMN_NODES - 2)
    w = x - i
    a, b = COLUMN_VALUES * i, COLUMN_VALUES * (i + 1)
    for k in range(COLUMN_BINS):
        paths[k] = (layer_datum(profiles, layer, a + 1 + k) * (1.0 - w)
                    + layer_datum(profiles, layer, b + 1 + k) * w)
    return layer_datum(profiles, layer, a) * (1.0 - w) + layer_datum(profiles, layer, b) * w


@njit(cache=True)
def column_statistics(params, profiles, textures, layer, side, n_columns, n_heights, out):
    """The layer's column statistics (out (COLUMN_NODES, COLUMN_VALUES), module docstring) at
    map factors m_i = i / (COLUMN_NODES - 1): the water `_water` gives (its detail erosion
    included; `params` without map or wind offset, the layer's coverage times m_i) summed
    with midpoint steps over `n_heights` levels in `n_columns` vertical columns at the points
    of the R2 low-discrepancy sequence (Roberts 2018, http://extremelearning.com.au/
    unreasonable-effectiveness-of-quasirandom-sequences/) across a square of `side` [m]
    (flat: the noise is read at (x, y, r), the height from r). A column with any water
    counts as cloudy; the cloudy ones, sorted by water path, are split into the
    `COLUMN_SHARES` and each share's mean path is kept."""
    base, top = params[layer, BASE_R], params[layer, TOP_R]
    dh = (top - base) / n_heights
    coverage = params[layer, COVERAGE]
    a1, a2 = 0.7548776662466927, 0.5698402909980532  # 1/g, 1/g^2, g the plastic number
    paths = np.empty(n_columns)
    for i in range(COLUMN_NODES):
        params[layer, COVERAGE] = coverage * i / (COLUMN_NODES - 1)
        cloudy = 0
        for j in range(n_columns):
            x = ((0.5 + a1 * j) % 1.0 - 0.5) * side
            y = ((0.5 + a2 * j) % 1.0 - 0.5) * side
            path = 0.0
            for k in range(n_heights):
                r = base + (k + 0.5) * dh
                path += _water(params, profiles, textures, layer, x, y, r, r, True, False) * dh
            if path > 0.0:
                paths[cloudy] = path
                cloudy += 1
        out[i, :] = 0.0
        out[i, 0] = cloudy / n_columns
        if cloudy == 0:
            continue
        ordered = np.sort(paths[:cloudy])
        edge = 0.0
        for b in range(COLUMN_BINS):
            lo = min(int(edge * cloudy), cloudy - 1)
            edge += COLUMN_SHARES[b]
            hi = max(min(int(round(edge * cloudy)), cloudy), lo + 1)
            out[i, 1 + b] = ordered[lo:hi].mean()
    params[layer, COVERAGE] = coverage


@njit(cache=True)
def coverage_map_factors(params, profiles, layer, points, out):
    """`coverage_map_factor` of `layer` at each world point of `points` (n, 3), into out (n,)."""
    for i in range(points.shape[0]):
        out[i] = coverage_map_factor(params, profiles, layer, points[i, 0], points[i, 1],
                                     points[i, 2])
