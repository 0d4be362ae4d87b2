"""Heightfield terrain on a spherical planet: ray hits, surface normals, sun shadows.

A `Heightfield` is a regular grid of heights above the planet's sphere, laid on the sphere
around an anchor point with azimuthal-equidistant coordinates: a point whose direction from
the planet centre makes the angle theta with the anchor's up axis U, at the bearing of the
unit vector (e, n) = (u·E, u·N) / |(u·E, u·N)|, has map coordinates

    (x, y) = R theta (e, n)   [m east, m north],    altitude = |p| - R,

exact on the sphere (Snyder 1987, "Map Projections - A Working Manual", USGS PP 1395, ch. 25,
doi:10.3133/pp1395). Distances along great circles through the anchor are true; across them
they are stretched by theta / sin(theta) (1 + 2.5e-5 at 200 km).

Grid layout: `heights_m[i, j]` lies at x = (j - (nx - 1) / 2) spacing, y = ((ny - 1) / 2 - i)
spacing: columns run east, ROW 0 IS THE NORTH EDGE (the layout of maps, images and DEM
rasters, so files load without flipping), and the grid centre sits on the anchor. Heights
between samples are bilinear. Outside the grid the terrain is the bare sphere (height 0): the
grid is framed by zero samples, so its border slopes to 0 across one cell and the planet goes on.

Ray casting (`intersect`, `shadowed`) marches from the ray's entry into the shell between the
lowest and highest terrain and stops where it leaves the shell, meets its inner sphere or
reaches `max_distance_m`, so rays that miss the shell cost two square roots. Inside, a
maximum mip-map (the highest sample of each 2^k x 2^k block of cells; Tevs, Ihrke & Seidel
2008, "Maximum mipmaps for fast, accurate, and scalable dynamic height field rendering",
I3D '08, doi:10.1145/1342250.1342279) lets the ray hop over the largest block it passes
above: to the block's edge along the ray's map-space direction, or down to the sphere of the
block's maximum when that comes first. Where the ray is below the top of its cell, it steps
within the cell: along the ray the bilinear height is quadratic and the altitude is
quadratic to second order, so the clearance (altitude minus height) is a quadratic whose
first root in the cell (or else the cell's exit) ends the step; a landing within
`REFINE_HEIGHT_TOLERANCE_M` of the surface is the hit, and a step that ends below it (rare:
the quadratic is exact to ~1e-6 m) is refined by the Illinois method. Beyond the grid the
bare sphere is met exactly. A hop follows the straight map-space line of its start, off the
ray's true map path by about the hop length times its altitude change / R; a hop that ends
more than `HOP_SLACK_CELLS` beyond its block is halved. Accuracy: every crossing of the
bilinear surface is found, except a dip of the ray below it that starts and ends within the
slack of a hop or within `HOP_PAST_EDGE_CELLS` past a cell's edge.

Many rays from one origin (a camera): `intersect` first bounds the terrain's elevation angle
seen from there per azimuth bin (`_horizon`: each mip block's top at its nearest distance,
distances and azimuths widened to cover the map's distortion), and rays above that bound are
misses without a march: the sky costs nothing. Results are the same with or without it.

Normals: the gradient of the bilinear heights by central differences one cell apart (read as
the bilinear interpolation of the samples' central differences, which is the same thing), as
slopes per metre of ground at the surface's radius (dh/dx R / r), tilt the local up:
n = normalize(up - s_x east' - s_y north'), where east' and north' are the anchor's east and
north carried along the great circle from the anchor to the point (the directions of growing
x and y; their tangential stretch theta / sin(theta) is neglected, < 3e-4 in slope at 300 km).

The kernels live here rather than in a `_kernels.py` so that this module stays the one place
to read for terrain; they use `transport.geometry.distance_to_sphere` for every ray-sphere
distance.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.render.image_io import read_exr
from skyscatter.transport.geometry import distance_to_sphere

__all__ = ["Heightfield", "demo_mountains"]

FINE_STEP_CELLS = 0.5  # steps beyond the grid; a hop shorter than 5 % of it is not taken [cells]
HOP_PAST_EDGE_CELLS = 1e-3  # a hop ends this far beyond its block's edge [cells]
HOP_SLACK_CELLS = 0.1  # a hop that ends farther beyond its block is halved [cells]
REFINE_TOLERANCE_M = 1e-2  # the hit is refined until its bracket is shorter than this [m]
REFINE_HEIGHT_TOLERANCE_M = 1e-3  # ... or the ray is this close to the surface [m]
PAD_CELLS = 2  # zero samples framing the grid: the outer ring of cells is exactly flat
HORIZON_MIN_RAYS = 4096  # intersect() from one origin culls with a horizon from this many rays
HORIZON_BINS = 4096  # azimuth bins of that horizon
HORIZON_BLOCKS = 300  # it bounds the terrain by mip blocks, at most this many across the grid
HORIZON_MAX_RANGE_M = 500e3  # no culling from points farther than this from the anchor [m]
EARTH_RADIUS_M = 6_371_000.0  # as atmosphere/presets/earth.toml (IUGG mean radius, Moritz 2000)

# Index of each scalar in the `params` array handed to the kernels.
_RADIUS, _SPACING, _COL0, _ROW0, _R_INNER, _R_OUTER, _CELLS_PER_RADIAN = range(7)


# --------------------------------------------------------------------------------------------
# Kernels: arrays and floats in, no Python objects. `terrain` is the tuple
# (padded heights (H, W), mip values (flat), mip offsets (K+1,), mip shapes (K+1, 2),
#  frame (3, 3) with columns east, north, up, params (7,) indexed by _RADIUS ...,
#  central-difference slopes (H, W, 2) at the samples [m per cell]).
# A ray o + t d (d unit) enters the inner functions as the float tuple
# (o.E, o.N, o.U, d.E, d.N, d.U, o.o, o.d) on the anchor's axes E, N, U (`_anchor_ray`).
# --------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _anchor_ray(ox, oy, oz, dx, dy, dz, frame):
    """The ray o + t d as the tuple described above."""
    return (ox * frame[0, 0] + oy * frame[1, 0] + oz * frame[2, 0],
            ox * frame[0, 1] + oy * frame[1, 1] + oz * frame[2, 1],
            ox * frame[0, 2] + oy * frame[1, 2] + oz * frame[2, 2],
            dx * frame[0, 0] + dy * frame[1, 0] + dz * frame[2, 0],
            dx * frame[0, 1] + dy * frame[1, 1] + dz * frame[2, 1],
            dx * frame[0, 2] + dy * frame[1, 2] + dz * frame[2, 2],
            ox * ox + oy * oy + oz * oz, ox * dx + oy * dy + oz * dz)


@njit(cache=True, inline="always")
def _grid_state(t, ray, params):
    """At distance t [m] along `ray`: (r, mu, gx, gy, vx, vy).

    r = |p| [m]; mu = cos(angle between d and the local up) [-]; (gx, gy) = padded grid
    column and row [cells]; (vx, vy) = their rates along the ray [cells m^-1] (a ray with
    d = 0 gives the point alone). With (e, n, c) = p / r on the anchor's east, north, up:
    (x, y) = R g (e, n), g = theta / sin(theta), theta = atan2(s, c), s^2 = e^2 + n^2."""
    o_e, o_n, o_u, d_e, d_n, d_u, oo, od = ray
    inv_r = 1.0 / math.sqrt(oo + t * (2.0 * od + t))
    e = (o_e + t * d_e) * inv_r
    n = (o_n + t * d_n) * inv_r
    c = (o_u + t * d_u) * inv_r
    mu = (od + t) * inv_r
    de = (d_e - mu * e) * inv_r  # du/dt = (d - mu u) / r
    dn = (d_n - mu * n) * inv_r
    s2 = e * e + n * n
    ds2 = 2.0 * (e * de + n * dn)
    if c > 0.0 and s2 < 0.0025:
        # theta / sin(theta) = asin(s) / s = 1 + s^2/6 + 3 s^4/40 + 5 s^6/112 + 35 s^8/1152
        # + O(s^10) (Abramowitz & Stegun 4.4.40); the rest is < 3e-15 for s < 0.05 (318 km).
        g = 1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * (5.0 / 112.0 + s2 * 35.0 / 1152.0)))
        dg = ds2 * (1.0 / 6.0 + s2 * (3.0 / 20.0 + s2 * (15.0 / 112.0 + s2 * 35.0 / 288.0)))
    elif s2 > 1e-24:
        s = math.sqrt(s2)
        dc = (d_u - mu * c) * inv_r
        g = math.atan2(s, c) / s
        ds = 0.5 * ds2 / s
        dg = (c * ds - s * dc - g * ds) / s  # d(theta / s) with dtheta = c ds - s dc
    else:
        return 1.0 / inv_r, mu, -1e30, -1e30, 0.0, 0.0  # the antipode: outside any grid
    scale = params[_CELLS_PER_RADIAN]
    return (1.0 / inv_r, mu, params[_COL0] + scale * g * e, params[_ROW0] - scale * g * n,
            scale * (dg * e + g * de), -scale * (dg * n + g * dn))


@njit(cache=True, inline="always")
def _height(padded, gx, gy):
    """Bilinear height [m] at padded grid column gx, row gy [cells]; 0 outside the grid."""
    n_rows, n_cols = padded.shape
    if not (0.0 <= gx <= n_cols - 1.0 and 0.0 <= gy <= n_rows - 1.0):
        return 0.0
    j = min(int(gx), n_cols - 2)
    i = min(int(gy), n_rows - 2)
    fx = gx - j
    fy = gy - i
    top = padded[i, j] * (1.0 - fx) + padded[i, j + 1] * fx
    bottom = padded[i + 1, j] * (1.0 - fx) + padded[i + 1, j + 1] * fx
    return top * (1.0 - fy) + bottom * fy


@njit(cache=True, inline="always")
def _exit_distance(gx, gy, vx, vy, x0, x1, y0, y1):
    """Ray length [m] until the map-space line (gx, gy) + t (vx, vy) is HOP_PAST_EDGE_CELLS
    beyond the box [x0, x1] x [y0, y1] [cells]; inf when it never leaves."""
    t = math.inf
    if vx > 0.0:
        t = (x1 + HOP_PAST_EDGE_CELLS - gx) / vx
    elif vx < 0.0:
        t = (x0 - HOP_PAST_EDGE_CELLS - gx) / vx
    if vy > 0.0:
        t = min(t, (y1 + HOP_PAST_EDGE_CELLS - gy) / vy)
    elif vy < 0.0:
        t = min(t, (y0 - HOP_PAST_EDGE_CELLS - gy) / vy)
    return t


@njit(cache=True, inline="always")
def _entry_distance(gx, gy, vx, vy, x1, y1):
    """Ray length [m] until the map-space line from outside is HOP_PAST_EDGE_CELLS inside
    [0, x1] x [0, y1] [cells]; inf when it does not enter."""
    t_in, t_out = 0.0, math.inf
    for g, v, hi in ((gx, vx, x1), (gy, vy, y1)):
        if v == 0.0:
            if g < 0.0 or g > hi:
                return math.inf
        else:
            a, b = (0.0 - g) / v, (hi - g) / v
            t_in = max(t_in, min(a, b))
            t_out = min(t_out, max(a, b))
    if t_in > t_out:
        return math.inf
    return t_in + HOP_PAST_EDGE_CELLS / math.sqrt(vx * vx + vy * vy)


@njit(cache=True, inline="always")
def _cell_step(padded, i, j, gx, gy, vx, vy, f, mu, r):
    """Ray length [m] to the first zero of the clearance in cell (i, j) of the padded grid,
    or to HOP_PAST_EDGE_CELLS past the cell's exit when there is none.

    Along the ray from (gx, gy) [cells] with rates (vx, vy) [cells m^-1] the bilinear height
    is quadratic in the length s, and the altitude is a0 + mu s + (1 - mu^2) s^2 / (2 r) to
    second order, so the clearance is f + b s + a s^2 (to ~1e-6 m within a cell)."""
    h00, h01 = padded[i, j], padded[i, j + 1]
    h10, h11 = padded[i + 1, j], padded[i + 1, j + 1]
    twist = h00 - h01 - h10 + h11
    fx, fy = gx - j, gy - i
    b = mu - ((h01 - h00 + twist * fy) * vx + (h10 - h00 + twist * fx) * vy)
    a = 0.5 * (1.0 - mu * mu) / r - twist * vx * vy
    step = _exit_distance(gx, gy, vx, vy, float(j), j + 1.0, float(i), i + 1.0)
    discriminant = b * b - 4.0 * a * f
    if discriminant >= 0.0:
        # Roots q / a and f / q with q = -(b + sign(b) sqrt(disc)) / 2 (no cancellation).
        q = -0.5 * (b + math.copysign(math.sqrt(discriminant), b))
        if a != 0.0 and 0.0 < q / a < step:
            step = q / a
        if q != 0.0 and 0.0 < f / q < step:
            step = f / q
    return step


@njit(cache=True)
def _march(ray, t_min, t_max, terrain):
    """First crossing of the terrain by `ray` for t in [t_min, t_max].

    Returns (status, t_lo, f_lo, t_hi, f_hi, r, gx, gy): status 0 = no crossing; 1 = the
    clearance f (altitude above the terrain) is f_lo > 0 at t_lo and f_hi <= 0 at t_hi;
    2 = hit at t_hi (on the surface within REFINE_HEIGHT_TOLERANCE_M, on the bare sphere
    beyond the grid, or a ray that starts below the surface). (r, gx, gy) are those of
    `_grid_state` at t_hi."""
    padded, mip, mip_offset, mip_shape, _, params, _ = terrain
    radius = params[_RADIUS]
    n_rows, n_cols = padded.shape
    x_max, y_max = n_cols - 1.0, n_rows - 1.0
    n_levels = mip_offset.shape[0]
    fine_sq = FINE_STEP_CELLS * FINE_STEP_CELLS

    r0 = math.sqrt(ray[6])
    mu0 = ray[7] / r0
    t_far = distance_to_sphere(r0, mu0, params[_R_OUTER], True)
    if math.isnan(t_far) or t_far <= t_min:
        return 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    t = t_min
    if r0 > params[_R_OUTER]:  # from above the shell: start where the ray enters it
        t = max(t_min, distance_to_sphere(r0, mu0, params[_R_OUTER], False))
    t_end = min(t_max, t_far)
    t_inner = math.nan
    if mu0 < 0.0 or r0 < params[_R_INNER]:
        t_inner = distance_to_sphere(r0, mu0, params[_R_INNER], False)
    meets_inner = not math.isnan(t_inner) and t < t_inner <= t_end
    if meets_inner:
        t_end = t_inner  # on the sphere of the lowest terrain: crossed by then
    if t_end < t:
        return 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0

    r, mu, gx, gy, vx, vy = _grid_state(t, ray, params)
    f = r - radius - _height(padded, gx, gy)
    if f < 0.0:
        return 2, t, f, t, f, r, gx, gy
    level = n_levels // 2
    for _ in range(10_000_000):  # each pass advances t (see below); this only guards NaN
        speed_sq = vx * vx + vy * vy  # [cells^2 m^-2]
        altitude = r - radius
        inside = 0.0 <= gx < x_max and 0.0 <= gy < y_max
        k = 0
        block_max = 0.0  # outside the grid: the bare sphere
        x0, x1, y0, y1 = 0.0, x_max, 0.0, y_max
        dt = math.inf
        if inside:
            # The largest block under the ray whose top lies below it: block maxima grow with
            # the level, so walk up or down from the level of the previous step.
            j, i = int(gx), int(gy)
            k = level
            block_max = mip[mip_offset[k] + (i >> k) * mip_shape[k, 1] + (j >> k)]
            if block_max < altitude:
                while k + 1 < n_levels:
                    above = mip[mip_offset[k + 1] + (i >> (k + 1)) * mip_shape[k + 1, 1]
                                + (j >> (k + 1))]
                    if above >= altitude:
                        break
                    k += 1
                    block_max = above
            else:
                while k >= 0:
                    k -= 1
                    if k < 0:
                        break
                    block_max = mip[mip_offset[k] + (i >> k) * mip_shape[k, 1] + (j >> k)]
                    if block_max < altitude:
                        break
            if k >= 0:
                size = float(1 << k)
                x0, y0 = (j >> k) * size, (i >> k) * size
                x1, y1 = min(x0 + size, x_max), min(y0 + size, y_max)
                dt = _exit_distance(gx, gy, vx, vy, x0, x1, y0, y1)
        else:
            dt = _entry_distance(gx, gy, vx, vy, x_max, y_max)
        if k >= 0:  # hop over the block (or the bare sphere outside the grid)
            if mu < 0.0:
                dt_v = distance_to_sphere(r, mu, radius + block_max, False)
                if not math.isnan(dt_v) and dt_v <= dt:
                    if not inside and t + dt_v <= t_end:  # meets the bare sphere: exact
                        r, mu, gx, gy, vx, vy = _grid_state(t + dt_v, ray, params)
                        return 2, t, f, t + dt_v, 0.0, r, gx, gy
                    dt = dt_v
            if dt * dt * speed_sq < 0.0025 * fine_sq:  # hardly moves (< 5 %): march instead
                k = -1
        if k < 0:
            if inside:  # to the crossing the bilinear cell predicts, or to the next cell
                dt = _cell_step(padded, int(gy), int(gx), gx, gy, vx, vy, f, mu, r)
            else:
                dt = FINE_STEP_CELLS / math.sqrt(speed_sq) if speed_sq > 0.0 else math.inf
        while True:
            t_new = min(t + dt, t_end)
            r, mu, gx, gy, vx, vy = _grid_state(t_new, ray, params)
            if k < 0 or dt * dt * speed_sq <= fine_sq:
                break
            # The hop followed the map-space line of its start; if its end strays more than
            # HOP_SLACK_CELLS beyond the block (into the grid, from outside), halve it.
            if inside:
                stray = max(x0 - gx, gx - x1, y0 - gy, gy - y1)
            else:
                stray = min(gx, x_max - gx, gy, y_max - gy)
            if stray <= HOP_SLACK_CELLS:
                break
            dt *= 0.5
        f_new = r - radius - _height(padded, gx, gy)
        if f_new <= REFINE_HEIGHT_TOLERANCE_M or (meets_inner and t_new >= t_end):
            if f_new > -REFINE_HEIGHT_TOLERANCE_M:
                return 2, t, f, t_new, 0.0, r, gx, gy  # on the surface (e.g. a flat block)
            return 1, t, f, t_new, f_new, r, gx, gy
        if t_new >= t_end:
            break
        t, f, level = t_new, f_new, max(k, 0)
    return 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0


@njit(cache=True)
def _refine(ray, t_lo, f_lo, t_hi, f_hi, padded, params):
    """(t, r, gx, gy) where the clearance changes sign in [t_lo, t_hi] (f_lo > 0 >= f_hi),
    to REFINE_TOLERANCE_M in t or REFINE_HEIGHT_TOLERANCE_M in clearance: Illinois variant
    of regula falsi (Dowell & Jarratt 1971, BIT 11, 168, doi:10.1007/BF01934364)."""
    radius = params[_RADIUS]
    side = 0
    t = t_hi
    for _ in range(100):
        t = t_hi - f_hi * (t_hi - t_lo) / (f_hi - f_lo)
        if not (t_lo < t < t_hi):
            t = 0.5 * (t_lo + t_hi)
        r, _, gx, gy, _, _ = _grid_state(t, ray, params)
        f = r - radius - _height(padded, gx, gy)
        if abs(f) <= REFINE_HEIGHT_TOLERANCE_M:
            break
        if f > 0.0:
            t_lo, f_lo = t, f
            if side == 1:
                f_hi *= 0.5
            side = 1
        else:
            t_hi, f_hi = t, f
            if side == -1:
                f_lo *= 0.5
            side = -1
        if t_hi - t_lo <= REFINE_TOLERANCE_M:
            break
    return t, r, gx, gy


@njit(cache=True)
def _normal(ux, uy, uz, r, gx, gy, slopes, frame, params, normals, index):
    """World-space unit surface normal into normals[index] at the surface point along the
    unit vector u, at radius r [m] and padded grid position (gx, gy) [cells]."""
    # Slopes per metre of ground at radius r, east and north (the row index grows southwards).
    scale = params[_RADIUS] / (params[_SPACING] * r)
    slope_x, slope_y = 0.0, 0.0
    n_rows, n_cols = slopes.shape[0], slopes.shape[1]
    if 0.0 <= gx <= n_cols - 1.0 and 0.0 <= gy <= n_rows - 1.0:
        j = min(int(gx), n_cols - 2)
        i = min(int(gy), n_rows - 2)
        fx = gx - j
        fy = gy - i
        w00, w01 = (1.0 - fx) * (1.0 - fy), fx * (1.0 - fy)
        w10, w11 = (1.0 - fx) * fy, fx * fy
        slope_x = (w00 * slopes[i, j, 0] + w01 * slopes[i, j + 1, 0]
                   + w10 * slopes[i + 1, j, 0] + w11 * slopes[i + 1, j + 1, 0]) * scale
        slope_y = -(w00 * slopes[i, j, 1] + w01 * slopes[i, j + 1, 1]
                    + w10 * slopes[i + 1, j, 1] + w11 * slopes[i + 1, j + 1, 1]) * scale
    if slope_x == 0.0 and slope_y == 0.0:  # flat (the bare sphere, a valley floor): up
        normals[index, 0], normals[index, 1], normals[index, 2] = ux, uy, uz
        return
    # Carry east and north from the anchor's up U to u: rotation about a = U x u,
    # v' = c v + a x v + a (a.v) / (1 + c) (Rodrigues' formula with |a| = sin, c = cos);
    # same as _carried_frame, inlined in the kernel.
    cx = frame[1, 2] * uz - frame[2, 2] * uy
    cy = frame[2, 2] * ux - frame[0, 2] * uz
    cz = frame[0, 2] * uy - frame[1, 2] * ux
    c = frame[0, 2] * ux + frame[1, 2] * uy + frame[2, 2] * uz
    nx, ny, nz = ux, uy, uz
    inv_1c = 1.0 / (1.0 + c)
    for axis in range(2):
        slope = slope_x if axis == 0 else slope_y
        vx, vy, vz = frame[0, axis], frame[1, axis], frame[2, axis]
        w = (cx * vx + cy * vy + cz * vz) * inv_1c
        nx -= slope * (c * vx + cy * vz - cz * vy + cx * w)
        ny -= slope * (c * vy + cz * vx - cx * vz + cy * w)
        nz -= slope * (c * vz + cx * vy - cy * vx + cz * w)
    inv_norm = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    normals[index, 0] = nx * inv_norm
    normals[index, 1] = ny * inv_norm
    normals[index, 2] = nz * inv_norm


_CHUNK = 32  # rays per work item of the parallel loops
_COLUMNS = 16  # work items are dealt out column-wise from a (rows x _COLUMNS) table


@njit(cache=True)
def _chunk_layout(n):
    """(number of work items, table rows) for n rays in chunks of _CHUNK."""
    rows = -(-n // (_CHUNK * _COLUMNS))
    return rows * _COLUMNS, rows


@njit(cache=True)
def _chunk_start(b, rows):
    """First ray of work item b. Neighbouring b lie _COLUMNS chunks apart, so each thread's
    share of b (numba splits the range evenly) spans the whole image: rays that cost much
    (the horizon band) spread over all threads, while each chunk reads contiguous memory."""
    return ((b % rows) * _COLUMNS + b // rows) * _CHUNK


@njit(cache=True)
def _height_kernel(points, terrain, out):
    """Terrain height [m] under each point (n, 3) into out (n,)."""
    padded, frame, params = terrain[0], terrain[4], terrain[5]
    for index in range(points.shape[0]):
        point = _anchor_ray(points[index, 0], points[index, 1], points[index, 2], 0.0, 0.0,
                            0.0, frame)
        _, _, gx, gy, _, _ = _grid_state(0.0, point, params)
        out[index] = _height(padded, gx, gy)


@njit(parallel=True, cache=True)
def _intersect_kernel(origins, directions, max_distance, terrain, horizon, view_frame,
                      distance, points, normals, hit):
    """Fill distance (n,), points (n, 3), normals (n, 3), hit (n,) for directions (n, 3)
    (normalised here; a zero or non-finite one gets distance NaN). A non-empty `horizon`
    (from `_horizon`, origins (1, 3)) culls the rays that pass above it; view_frame holds
    the origin's local east', north', up in its columns."""
    padded, frame, params, slopes = terrain[0], terrain[4], terrain[5], terrain[6]
    n = directions.shape[0]
    shared_origin = origins.shape[0] == 1
    n_bins = horizon.shape[0]
    lowest = horizon.min() if n_bins > 0 else 0.0
    highest = horizon.max() if n_bins > 0 else 0.0
    n_chunks, columns = _chunk_layout(n)
    for b in prange(n_chunks):
        start = _chunk_start(b, columns)
        for index in range(start, min(start + _CHUNK, n)):
            k = 0 if shared_origin else index
            ox, oy, oz = origins[k, 0], origins[k, 1], origins[k, 2]
            dx, dy, dz = directions[index, 0], directions[index, 1], directions[index, 2]
            length = math.sqrt(dx * dx + dy * dy + dz * dz)
            status = 0
            if not (length > 0.0 and math.isfinite(length)):
                status = -1
            else:
                inv_length = 1.0 / length
                dx, dy, dz = dx * inv_length, dy * inv_length, dz * inv_length
                if n_bins == 0 or not _above_horizon(dx, dy, dz, horizon, lowest, highest,
                                                     view_frame):
                    ray = _anchor_ray(ox, oy, oz, dx, dy, dz, frame)
                    status, t_lo, f_lo, t, f, r, gx, gy = _march(ray, 0.0, max_distance,
                                                                 terrain)
                    if status == 1:
                        t, r, gx, gy = _refine(ray, t_lo, f_lo, t, f, padded, params)
            if status <= 0:
                distance[index] = math.inf if status == 0 else math.nan
                hit[index] = False
                for a in range(3):
                    points[index, a] = math.nan
                    normals[index, a] = math.nan
                continue
            distance[index] = t
            hit[index] = True
            px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
            points[index, 0], points[index, 1], points[index, 2] = px, py, pz
            inv_norm = 1.0 / math.sqrt(px * px + py * py + pz * pz)
            _normal(px * inv_norm, py * inv_norm, pz * inv_norm, r, gx, gy, slopes, frame,
                    params, normals, index)


@njit(cache=True, inline="always")
def _above_horizon(dx, dy, dz, horizon, lowest, highest, view_frame):
    """Whether the unit direction d rises above the horizon bound of its azimuth bin;
    `lowest` and `highest` are the bound's extremes (no azimuth needed outside them)."""
    up = dx * view_frame[0, 2] + dy * view_frame[1, 2] + dz * view_frame[2, 2]
    if up <= lowest or up > highest:
        return up > highest
    east = dx * view_frame[0, 0] + dy * view_frame[1, 0] + dz * view_frame[2, 0]
    north = dx * view_frame[0, 1] + dy * view_frame[1, 1] + dz * view_frame[2, 1]
    n_bins = horizon.shape[0]
    b = int((math.atan2(east, north) + math.pi) * (n_bins / (2.0 * math.pi)))
    return up > horizon[min(max(b, 0), n_bins - 1)]


@njit(cache=True)
def _horizon(terrain, gx0, gy0, altitude, level, n_bins, distance_margin, azimuth_margin):
    """Upper bound of the sine of the elevation angle of the terrain seen from a point at
    padded grid position (gx0, gy0) [cells] and `altitude` [m], per azimuth bin (n_bins,):
    bin b covers azimuths (from north through east) [-pi + 2 pi b / n_bins, ... (b + 1)).

    Each mip block of `level` bounds its terrain by its highest sample m; its points lie at
    great-circle angles theta in [theta_min, theta_max] from the point (map distances over R,
    widened by the factors 1 -+ `distance_margin` for the map's stretch; their azimuths are
    the map's, widened by `azimuth_margin` [rad] for its distortion), so with r0 = R + altitude,
    v = (R + h) cos(theta) - r0 and w = (R + h) sin(theta) (the rise and the run seen from
    the point): tan(elevation) <= v(m, theta_min) / w(lowest, theta_min) when that v >= 0,
    else <= v(m, theta_min) / w(m, theta_max). Beyond the grid the bare sphere's horizon
    dip bounds everything: sin(elevation) = -sqrt(1 - (R / r0)^2)."""
    padded, mip, mip_offset, mip_shape, _, params, _ = terrain
    radius = params[_RADIUS]
    spacing = params[_SPACING]
    lowest = params[_R_INNER] - radius
    r0 = radius + altitude
    base = -math.sqrt(max(0.0, 1.0 - (radius / r0) ** 2))
    horizon = np.full(n_bins, base)
    rows, cols = mip_shape[level, 0], mip_shape[level, 1]
    size = float(1 << level)
    x_max, y_max = padded.shape[1] - 1.0, padded.shape[0] - 1.0
    bins_per_rad = n_bins / (2.0 * math.pi)
    for bi in range(rows):
        y0 = bi * size
        y1 = min(y0 + size, y_max)
        for bj in range(cols):
            x0 = bj * size
            x1 = min(x0 + size, x_max)
            m = mip[mip_offset[level] + bi * cols + bj]
            near_x = max(x0 - gx0, 0.0, gx0 - x1)
            near_y = max(y0 - gy0, 0.0, gy0 - y1)
            far_x = max(abs(x0 - gx0), abs(x1 - gx0))
            far_y = max(abs(y0 - gy0), abs(y1 - gy0))
            theta_min = (math.hypot(near_x, near_y) * spacing / radius
                         * (1.0 - distance_margin))
            theta_max = (math.hypot(far_x, far_y) * spacing / radius
                         * (1.0 + distance_margin))
            v = (radius + m) * math.cos(theta_min) - r0
            if v >= 0.0:
                w = (radius + lowest) * math.sin(theta_min)
            else:
                w = (radius + m) * math.sin(theta_max)
            bound = v / math.sqrt(v * v + w * w) if v != 0.0 or w != 0.0 else 1.0
            if bound <= base:
                continue
            if near_x == 0.0 and near_y == 0.0:  # the block holds the point: every azimuth
                for b in range(n_bins):
                    horizon[b] = max(horizon[b], bound)
                continue
            # Azimuths of the corners, unwrapped around the block centre's; a block that does
            # not hold the point spans less than pi, between two of its corners.
            centre = math.atan2(0.5 * (x0 + x1) - gx0, gy0 - 0.5 * (y0 + y1))
            low, high = 0.0, 0.0
            for corner in range(4):
                cx = x0 if corner % 2 == 0 else x1
                cy = y0 if corner < 2 else y1
                delta = math.atan2(cx - gx0, gy0 - cy) - centre
                delta -= 2.0 * math.pi * round(delta / (2.0 * math.pi))
                low, high = min(low, delta), max(high, delta)
            first = int(math.floor((centre + low - azimuth_margin + math.pi)
                                   * bins_per_rad))
            last = int(math.floor((centre + high + azimuth_margin + math.pi)
                                  * bins_per_rad))
            for b in range(first, last + 1):
                wrapped = b % n_bins
                horizon[wrapped] = max(horizon[wrapped], bound)
    return horizon


@njit(parallel=True, cache=True)
def _shadow_kernel(points, direction, offset, terrain, shadowed):
    """shadowed (n,) = the terrain crosses the ray from each point (raised by `offset` [m]
    along its local up) along the unit `direction`; non-finite points are not shadowed."""
    frame = terrain[4]
    n = points.shape[0]
    n_chunks, columns = _chunk_layout(n)
    for b in prange(n_chunks):
        start = _chunk_start(b, columns)
        for index in range(start, min(start + _CHUNK, n)):
            px, py, pz = points[index, 0], points[index, 1], points[index, 2]
            r = math.sqrt(px * px + py * py + pz * pz)
            if not (math.isfinite(r) and r > 0.0):
                shadowed[index] = False
                continue
            lift = 1.0 + offset / r
            ray = _anchor_ray(px * lift, py * lift, pz * lift, direction[0], direction[1],
                              direction[2], frame)
            shadowed[index] = _march(ray, 0.0, math.inf, terrain)[0] != 0


# --------------------------------------------------------------------------------------------
# The heightfield.
# --------------------------------------------------------------------------------------------


def _max_mipmap(padded: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Highest height of each cell (its 4 corners bound the bilinear patch), then of each
    2^k x 2^k block; flattened with per-level offsets and (rows, columns)."""
    level = np.maximum(np.maximum(padded[:-1, :-1], padded[:-1, 1:]),
                       np.maximum(padded[1:, :-1], padded[1:, 1:]))
    levels = [level]
    while level.shape[0] > 1 or level.shape[1] > 1:
        rows, cols = -(-level.shape[0] // 2), -(-level.shape[1] // 2)
        even = np.full((2 * rows, 2 * cols), -np.inf)
        even[: level.shape[0], : level.shape[1]] = level
        level = even.reshape(rows, 2, cols, 2).max(axis=(1, 3))
        levels.append(level)
    shapes = np.array([lv.shape for lv in levels], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(shapes[:, 0] * shapes[:, 1])[:-1]]).astype(np.int64)
    return np.concatenate([lv.ravel() for lv in levels]), offsets, shapes


def _central_slopes(padded: np.ndarray) -> np.ndarray:
    """(H, W, 2): central differences (h[i, j+1] - h[i, j-1]) / 2 and (h[i+1, j] - h[i-1, j]) / 2
    at each sample [m per cell], zero beyond the grid. Their bilinear interpolation equals
    the central difference one cell apart of the bilinear heights."""
    framed = np.pad(padded, 1)
    return np.ascontiguousarray(np.stack([(framed[1:-1, 2:] - framed[1:-1, :-2]) / 2.0,
                                          (framed[2:, 1:-1] - framed[:-2, 1:-1]) / 2.0],
                                         axis=-1))


def _carried_frame(frame: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Columns east', north', up at the unit direction u: the anchor frame's east and north
    carried along the great circle from its up to u (Rodrigues' formula, as in `_normal`)."""
    east, north, up = frame.T
    axis, c = np.cross(up, u), float(up @ u)
    carried = [c * v + np.cross(axis, v) + axis * (axis @ v) / (1.0 + c) for v in (east, north)]
    return np.column_stack([*carried, u])


def _check_frame(frame: ArrayLike) -> np.ndarray:
    f = np.asarray(frame, dtype=np.float64)
    if f.shape != (3, 3) or not np.all(np.isfinite(f)):
        raise InputError(f"frame must be a finite 3x3 matrix (columns east, north, up), got "
                         f"shape {f.shape}", key="frame", value=f.shape)
    if not np.allclose(f.T @ f, np.eye(3), atol=1e-9) or np.linalg.det(f) < 0.0:
        raise InputError("frame must be a rotation: orthonormal columns east, north, up with "
                         "east x north = up", key="frame", value=f.tolist())
    return f


def _as_rays(name: str, values: ArrayLike) -> np.ndarray:
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{name} must have shape (3,) or (n, 3), got {arr.shape}", key=name,
                         value=arr.shape, allowed="(n, 3)")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite", key=name)
    return arr


def _unit_rows(name: str, values: ArrayLike) -> np.ndarray:
    arr = _as_rays(name, values)
    norm = np.linalg.norm(arr, axis=1, keepdims=True)
    if np.any(norm == 0.0):
        raise InputError(f"{name} must not contain zero vectors", key=name)
    return np.ascontiguousarray(arr / norm)


@dataclass(frozen=True, eq=False)
class Heightfield:
    """Terrain heights above a spherical planet on a square grid centred on an anchor point.

    See the module docstring for the map, the grid layout (row 0 = north edge, columns east)
    and the algorithms.

    Parameters
    ----------
    heights_m : array_like, shape (ny, nx), ny, nx >= 2
        Terrain height above the sphere of radius `planet_radius_m` at each sample. [m]
    spacing_m : float
        Distance between neighbouring samples, east and north alike. [m]
    planet_radius_m : float
        Radius of the planet's sphere (the bottom of the atmosphere). [m]
    frame : array_like, shape (3, 3), optional
        Columns east, north, up at the anchor, the ground point under the grid centre, in
        planet-centred coordinates (a `Viewpoint.to_world`); default identity = north pole.
    """

    heights_m: np.ndarray
    spacing_m: float
    planet_radius_m: float
    frame: np.ndarray = field(default_factory=lambda: np.eye(3))
    _terrain: tuple = field(init=False, repr=False)

    def __post_init__(self) -> None:
        heights = np.array(self.heights_m, dtype=np.float64)
        if heights.ndim != 2 or min(heights.shape) < 2:
            raise InputError(f"heights_m must be a 2-D grid of at least 2 x 2 samples, got "
                             f"shape {heights.shape}", key="heights_m", value=heights.shape)
        if not np.all(np.isfinite(heights)):
            raise InputError("heights_m must be finite (found NaN or infinity)", key="heights_m")
        for key in ("spacing_m", "planet_radius_m"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float, np.number)) and math.isfinite(value)
                    and value > 0.0):
                raise InputError(f"{key} = {value!r} must be a finite number > 0", key=key,
                                 value=value, allowed="> 0")
        radius = float(self.planet_radius_m)
        if heights.min() <= -radius:
            raise InputError("heights_m must stay above the planet's centre "
                             f"(> -{radius:g} m)", key="heights_m", value=float(heights.min()))
        frame = _check_frame(self.frame)
        heights.flags.writeable = False
        frame.flags.writeable = False
        object.__setattr__(self, "heights_m", heights)
        object.__setattr__(self, "frame", frame)

        padded = np.pad(heights, PAD_CELLS)
        mip, offsets, shapes = _max_mipmap(padded)
        ny, nx = heights.shape
        lowest, highest = min(0.0, float(heights.min())), max(0.0, float(heights.max()))
        params = np.array([radius, float(self.spacing_m), (nx - 1) / 2.0 + PAD_CELLS,
                           (ny - 1) / 2.0 + PAD_CELLS, radius + lowest, radius + highest + 1.0,
                           radius / float(self.spacing_m)])
        object.__setattr__(self, "_terrain", (padded, mip, offsets, shapes, frame, params,
                                              _central_slopes(padded)))

    @property
    def extent_m(self) -> tuple[float, float]:
        """(east-west, north-south) size of the grid from first to last sample. [m]"""
        ny, nx = self.heights_m.shape
        return (nx - 1) * self.spacing_m, (ny - 1) * self.spacing_m

    def viewpoint_at(self, east_m: float, north_m: float,
                     above_ground_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Position (3,) [m] `above_ground_m` over the terrain at map coordinates (east_m,
        north_m) from the anchor, and the local frame (3, 3) there (columns east', north',
        up, as in the module docstring): what `Viewpoint(position, frame)` takes."""
        rho = math.hypot(east_m, north_m)
        theta = rho / self.planet_radius_m
        east, north, up = self.frame.T
        bearing = (east_m * east + north_m * north) / rho if rho > 0.0 else east
        u = math.cos(theta) * up + math.sin(theta) * bearing
        ground = self.height_at(u * self.planet_radius_m)[0]
        position = (self.planet_radius_m + ground + above_ground_m) * u
        return position, _carried_frame(self.frame, u)

    def height_at(self, points: ArrayLike) -> np.ndarray:
        """Terrain height [m] (n,) under world points (3,) or (n, 3) [m] (bilinear)."""
        pts = np.ascontiguousarray(_as_rays("points", points))
        out = np.empty(pts.shape[0])
        _height_kernel(pts, self._terrain, out)
        return out

    def intersect(self, origins: ArrayLike, directions: ArrayLike,
                  max_distance_m: float = math.inf
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """First hits of rays on the terrain (or the bare sphere around it).

        Parameters
        ----------
        origins : array_like, shape (3,), (1, 3) or (n, 3)
            Ray starts, planet-centred. [m]
        directions : array_like, shape (n, 3)
            Ray directions (normalised here), planet-centred.
        max_distance_m : float
            Hits farther than this are misses. [m]

        Returns
        -------
        distance : ndarray (n,)
            Distance to the hit along the unit direction, inf for misses; 0 for a ray that
            starts below the surface. [m]
        points : ndarray (n, 3)
            Hit points [m]; NaN for misses.
        normals : ndarray (n, 3)
            World-space unit surface normals; NaN for misses.
        hit : ndarray (n,) bool
        """
        dirs = np.ascontiguousarray(_as_rays("directions", directions))
        starts = np.ascontiguousarray(_as_rays("origins", origins))
        if starts.shape[0] not in (1, dirs.shape[0]):
            raise InputError(f"origins must be one point or one per direction ({dirs.shape[0]})"
                             f", got {starts.shape[0]}", key="origins", value=starts.shape)
        if not max_distance_m > 0.0:
            raise InputError(f"max_distance_m = {max_distance_m!r} must be > 0",
                             key="max_distance_m", value=max_distance_m, allowed="> 0")
        n = dirs.shape[0]
        horizon, view_frame = np.empty(0), np.eye(3)
        if starts.shape[0] == 1 and n >= HORIZON_MIN_RAYS:
            horizon, view_frame = self._horizon_bound(starts[0])
        distance, hit = np.empty(n), np.empty(n, dtype=np.bool_)
        points, normals = np.empty((n, 3)), np.empty((n, 3))
        if n:
            _intersect_kernel(starts, dirs, float(max_distance_m), self._terrain, horizon,
                              view_frame, distance, points, normals, hit)
        if np.isnan(distance).any():
            raise InputError("directions must not contain zero vectors", key="directions")
        return distance, points, normals, hit

    def _horizon_bound(self, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(sin of the terrain's highest elevation per azimuth bin, the origin's local frame)
        for culling rays from `origin`; an empty bound where culling does not apply."""
        padded, _, _, shapes, frame, params, _ = self._terrain
        point = _anchor_ray(*origin, 0.0, 0.0, 0.0, frame)
        r, _, gx, gy, _, _ = _grid_state(0.0, point, params)
        altitude = r - self.planet_radius_m
        u = origin / r
        rho = math.acos(min(1.0, float(u @ frame[:, 2]))) * self.planet_radius_m
        if not (altitude > 0.0 and rho <= HORIZON_MAX_RANGE_M):
            return np.empty(0), np.eye(3)
        level = 0
        while level + 1 < len(shapes) and max(shapes[level]) > HORIZON_BLOCKS:
            level += 1
        # The map stretches lengths by at most theta / sin(theta) < 1 + theta^2 / 6 and turns
        # directions by less than theta^2 / 6 (theta = angle from the anchor), and a great
        # circle's image bends from its chord by about its length / R times theta; the margins
        # cover the farthest sample (and the origin) several times over.
        reach = (math.hypot(*padded.shape) / 2.0 * self.spacing_m + rho) / self.planet_radius_m
        horizon = _horizon(self._terrain, gx, gy, altitude, level, HORIZON_BINS,
                           1e-3 + reach**2 / 3.0, 2e-3 + 2.0 * reach**2)
        return horizon, _carried_frame(frame, u)

    def shadowed(self, points: ArrayLike, direction: ArrayLike,
                 offset_m: float | None = None) -> np.ndarray:
        """Whether the terrain (or the planet) blocks the way from each point towards the sun.

        Parameters
        ----------
        points : array_like, shape (3,) or (n, 3)
            Points on or above the surface (e.g. `intersect` hits) [m]; NaN rows give False.
        direction : array_like, shape (3,)
            Direction towards the light, planet-centred (normalised here).
        offset_m : float, optional
            The ray starts this far above each point along its local up, clear of the surface
            the point lies on (refined to 1 mm); default 1 % of the grid spacing. [m]

        Returns
        -------
        ndarray (n,) bool
        """
        pts = np.asarray(points, dtype=np.float64)
        pts = np.ascontiguousarray(pts[None, :] if pts.ndim == 1 else pts)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise InputError(f"points must have shape (3,) or (n, 3), got {pts.shape}",
                             key="points", value=pts.shape)
        sun = _unit_rows("direction", direction)
        if sun.shape[0] != 1:
            raise InputError("direction must be one vector (3,)", key="direction")
        offset = 0.01 * self.spacing_m if offset_m is None else float(offset_m)
        out = np.zeros(pts.shape[0], dtype=np.bool_)
        if pts.shape[0]:
            _shadow_kernel(pts, sun[0], offset, self._terrain, out)
        return out

    @classmethod
    def from_image(cls, path: str | os.PathLike[str], spacing_m: float, vertical_scale_m: float,
                   planet_radius_m: float, frame: ArrayLike | None = None) -> Heightfield:
        """Read heights from a grayscale image or array file; row 0 = north edge.

        height = value x `vertical_scale_m`, where value is
        * PNG (or another grayscale image Pillow reads): 8-bit code / 255 or 16-bit code /
          65535, so `vertical_scale_m` is the height of full white;
        * OpenEXR: the one channel (or the "Y" channel) as stored (read with
          `image_io.read_exr`);
        * .npy: the 2-D array as stored.

        Raises `InputError` naming the file when it is missing, unreadable, not 2-D
        grayscale, smaller than 2 x 2 or holds NaN or infinity.
        """
        source = Path(path)
        values = _read_grid(source)
        if values.ndim != 2 or min(values.shape) < 2:
            raise InputError(f"{source}: heights must be a 2-D grid of at least 2 x 2 samples, "
                             f"got shape {values.shape}", key="path", value=str(source))
        if not np.all(np.isfinite(values)):
            raise InputError(f"{source}: heights must be finite (found NaN or infinity)",
                             key="path", value=str(source))
        if not (math.isfinite(vertical_scale_m)):
            raise InputError(f"vertical_scale_m = {vertical_scale_m!r} must be finite",
                             key="vertical_scale_m", value=vertical_scale_m)
        return cls(values * float(vertical_scale_m), spacing_m, planet_radius_m,
                   np.eye(3) if frame is None else frame)


_IMAGE_FULL_SCALE = {"L": 255.0, "I;16": 65535.0, "I;16L": 65535.0, "I;16B": 65535.0,
                     "I": 65535.0}  # Pillow opens 16-bit grayscale PNGs as I;16 or I


def _read_grid(source: Path) -> np.ndarray:
    """Values of a height file as float64 (normalised for integer images)."""
    if not source.is_file():
        raise InputError(f"cannot read {source}: no such file", key="path", value=str(source))
    suffix = source.suffix.lower()
    if suffix == ".exr":
        image, names = read_exr(source)
        if len(names) == 1:
            return image[..., 0].astype(np.float64)
        if "Y" in names:
            return image[..., names.index("Y")].astype(np.float64)
        raise InputError(f"{source}: a height EXR needs one channel (or a 'Y' channel), got "
                         f"{', '.join(names)}", key="path", value=str(source))
    if suffix == ".npy":
        try:
            values = np.load(source, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise InputError(f"cannot read {source}: not a readable .npy array ({exc})",
                             key="path", value=str(source)) from exc
        if not (np.issubdtype(values.dtype, np.integer)
                or np.issubdtype(values.dtype, np.floating)):
            raise InputError(f"{source}: heights must be real numbers, got dtype "
                             f"{values.dtype}", key="path", value=str(source))
        return values.astype(np.float64)
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(source) as picture:
            mode = picture.mode
            values = np.asarray(picture)
    except (UnidentifiedImageError, OSError) as exc:
        raise InputError(f"cannot read {source}: not a PNG, EXR or .npy height map ({exc})",
                         key="path", value=str(source), allowed=".png, .exr, .npy") from exc
    if mode not in _IMAGE_FULL_SCALE:
        raise InputError(f"{source}: a height image must be 8- or 16-bit grayscale, got Pillow "
                         f"mode {mode!r}; convert it to grayscale first", key="path",
                         value=str(source))
    return values.astype(np.float64) / _IMAGE_FULL_SCALE[mode]


# --------------------------------------------------------------------------------------------
# A procedural range for demos.
# --------------------------------------------------------------------------------------------


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _spectral_noise(rng: np.random.Generator, size: int, spacing_m: float, beta: float,
                    longest_m: float, shortest_m: float, stretch: float,
                    along: np.ndarray) -> np.ndarray:
    """Gaussian random field (size, size) with power spectrum ~ k^-beta between wavelengths
    `shortest_m` and `longest_m`, its features `stretch` times longer along the unit
    direction `along` (x east, y north) than across it; zero mean, unit deviation.
    Spectral synthesis (Saupe 1988, in "The Science of Fractal Images", ch. 2)."""
    k = np.fft.fftfreq(size, d=spacing_m)
    kx, ky = k[None, :], -k[:, None]  # row index grows southwards
    wavenumber = np.hypot((kx * along[0] + ky * along[1]) * stretch,
                          -kx * along[1] + ky * along[0])
    band = (wavenumber >= 1.0 / longest_m) & (wavenumber <= 1.0 / shortest_m)
    amplitude = np.where(band, np.maximum(wavenumber, 1e-30) ** (-beta / 2.0), 0.0)
    white = rng.standard_normal((size, size)) + 1j * rng.standard_normal((size, size))
    field_ = np.fft.ifft2(white * amplitude).real
    return (field_ - field_.mean()) / field_.std()


def demo_mountains(size: int = 512, *, spacing_m: float = 250.0, peak_m: float = 4500.0,
                   seed: int = 0, planet_radius_m: float = EARTH_RADIUS_M,
                   range_azimuth_deg: float = 180.0,
                   frame: ArrayLike | None = None) -> Heightfield:
    """A deterministic procedural mountain range around a flat valley at the anchor.

    Three Gaussian random fields made by spectral synthesis, their features stretched
    across the line of sight from the anchor: a broad uplift (spectral exponent 3,
    wavelengths 4-60 km), crest lines (1 - |n| / 2.5)^3 of a second field (3-24 km) and
    roughness down to two cells (exponent 2.4). The relief uplift (0.3 + 0.7 crests)
    (1 + 0.12 roughness) stands under an envelope that is exactly 0 within 8 km of the
    anchor (a flat valley floor at height 0, where an observer can stand), rises to the full
    range over 8-20 km towards `range_azimuth_deg` (from north through east), to foothills
    of a third of that height over 12-32 km in every other direction, and fades out over
    the outer 8 % of the grid so the border does not end in a wall. Scaled so the highest
    sample is `peak_m`. Default: 512 x 512 samples 250 m apart (128 km), peaks of 4.5 km
    10-60 km away, due south. Same arguments, same heights (numpy's PCG64 `seed`).
    """
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 16:
        raise InputError(f"size = {size!r} must be an integer >= 16 (samples)", key="size",
                         value=size, allowed=">= 16")
    for key, value in (("spacing_m", spacing_m), ("peak_m", peak_m)):
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(f"{key} = {value!r} must be a finite number > 0", key=key,
                             value=value, allowed="> 0")
    rng = np.random.default_rng(seed)
    azimuth = math.radians(range_azimuth_deg)
    towards = np.array([math.sin(azimuth), math.cos(azimuth)])
    across = np.array([towards[1], -towards[0]])
    massif = _spectral_noise(rng, size, spacing_m, 3.0, 60e3, 4e3, 2.0, across)
    crests = _spectral_noise(rng, size, spacing_m, 3.0, 24e3, 3e3, 1.6, across)
    rough = _spectral_noise(rng, size, spacing_m, 2.4, 8e3, 2.0 * spacing_m, 1.0, across)
    uplift = _smoothstep((massif + 2.0) / 4.0)
    ridged = (1.0 - np.minimum(np.abs(crests) / 2.5, 1.0)) ** 3
    relief = uplift * (0.3 + 0.7 * ridged) * (1.0 + 0.12 * rough)

    offsets = (np.arange(size) - (size - 1) / 2.0) * spacing_m
    x, y = offsets[None, :], -offsets[:, None]
    main = _smoothstep(((x * towards[0] + y * towards[1]) - 8e3) / 12e3)
    foothills = _smoothstep((np.hypot(x, y) - 12e3) / 20e3) / 3.0
    half = (size - 1) / 2.0 * spacing_m
    edge = _smoothstep((half - np.maximum(np.abs(x), np.abs(y))) / (0.08 * half))
    heights = np.maximum(np.maximum(main, foothills) * edge * relief, 0.0)
    heights *= peak_m / heights.max()
    return Heightfield(heights, spacing_m, planet_radius_m, np.eye(3) if frame is None else frame)
