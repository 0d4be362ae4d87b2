"""Numba kernels of the Schüler solver (`transport/schuler.py`): single scattering marched
along view rays with every transmittance from the closed-form columns of `transport/chapman.py`.

Columns between two points of one ray are differences of columns to infinity along the ray's
line (Schüler 2012, "aerial perspective"): forwards, m(a, v) - m(b, v), for rays that leave
the atmosphere; backwards, m(b, -v) - m(a, -v), for rays that meet the ground (descending all
the way, so the backward rays point up and their perigee is never below the ground).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport._kernels import (
    density_at,
    path_end,
    ray_segment,
    single_scattering_outputs,
)
from skyscatter.transport._table_common_kernels import table_ray_distances
from skyscatter.transport.chapman import LAYER, exponential_column, layer_column
from skyscatter.transport.geometry import sun_visible_fraction


@njit(cache=True, inline="always")
def columns_to_infinity(r, mu, bottom_radius, kind, ground_density, scale_height, layer_radius,
                        layer_width, layer_column_, out):
    """Column [density x m] of every constituent (`chapman.ColumnModel` arrays) along the ray
    (r, mu) to infinity, into out (n_c,)."""
    for c in range(kind.size):
        if kind[c] == LAYER:
            out[c] = layer_column_[c] * layer_column(r, mu, layer_radius[c], layer_width[c])
        elif ground_density[c] > 0.0:
            out[c] = ground_density[c] * exponential_column(r, mu, bottom_radius,
                                                            scale_height[c])
        else:
            out[c] = 0.0


@njit(cache=True, inline="always")
def _point_columns(ox, oy, oz, dx, dy, dz, t, sign, bottom_radius, model, out):
    """Columns to infinity from the point o + t d along sign * d."""
    px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
    r = math.sqrt(px * px + py * py + pz * pz)
    mu = sign * (px * dx + py * dy + pz * dz) / r
    columns_to_infinity(r, min(max(mu, -1.0), 1.0), bottom_radius, model[0], model[1],
                        model[2], model[3], model[4], model[5], out)


@njit(cache=True, inline="always")
def sun_columns(px, py, pz, sun_direction, bottom_radius, sun_angular_radius, model, out):
    """Columns (n_c,) from the point p towards the sun to infinity (the part beyond the top,
    < 1e-5 of them for Earth's 100 km, is kept), into out; returns the visible part of the
    sun's disk (0: the planet hides it, out untouched)."""
    r = math.sqrt(px * px + py * py + pz * pz)
    mu_s = (px * sun_direction[0] + py * sun_direction[1] + pz * sun_direction[2]) / r
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible > 0.0:
        horizon = (-math.sqrt(max(1.0 - (bottom_radius / r) ** 2, 0.0))
                   if r > bottom_radius else 0.0)
        columns_to_infinity(r, min(max(mu_s, horizon), 1.0), bottom_radius, model[0],
                            model[1], model[2], model[3], model[4], model[5], out)
    return visible


RAYS_PER_BLOCK = 64  # rays that share scratch arrays in the parallel loop


@njit(cache=True)
def _march_ray(ox, oy, oz, dx, dy, dz, sun_direction, n_samples, bottom_radius, top_radius,
               h_step, density, extinction, sun_angular_radius, model, scratch, inscatter,
               transmittance, ground):
    """One ray of `single_scattering` into its rows inscatter (n_c, n_wl), transmittance and
    ground (n_wl,); scratch = (samples, columns (4, n_c), densities, t_sun, t_view, previous)."""
    samples, cols, dens, t_sun, t_view, previous = scratch
    n_c, n_wl = extinction.shape
    _, _, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz, bottom_radius,
                                                    top_radius)
    if t_end <= t_start and not hits_ground:  # misses the atmosphere
        return
    sign = -1.0 if hits_ground else 1.0
    first, here = cols[0], cols[1]
    previous[:, :] = 0.0
    sx, sy, sz = ox + t_start * dx, oy + t_start * dy, oz + t_start * dz
    r_start = math.sqrt(sx * sx + sy * sy + sz * sz)
    mu_start = (sx * dx + sy * dy + sz * dz) / r_start
    count = table_ray_distances(r_start, mu_start, t_end - t_start, hits_ground, n_samples,
                                samples)
    _point_columns(ox, oy, oz, dx, dy, dz, t_start, sign, bottom_radius, model, first)
    last = count - 1
    for k in range(count):
        t = t_start + samples[k]
        _point_columns(ox, oy, oz, dx, dy, dz, t, sign, bottom_radius, model, here)
        px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
        visible = sun_columns(px, py, pz, sun_direction, bottom_radius, sun_angular_radius,
                              model, cols[2])
        # T(x, p) T_sun(p) in one exponential per wavelength
        for w in range(n_wl):
            tau_view = 0.0
            tau_sun = 0.0
            for c in range(n_c):
                tau_view += extinction[c, w] * max(sign * (first[c] - here[c]), 0.0)
                tau_sun += extinction[c, w] * cols[2, c]
            t_sun[w] = visible * math.exp(-(tau_view + tau_sun)) if visible > 0.0 else 0.0
            if k == last:
                t_view[w] = math.exp(-tau_view)
        altitude = math.sqrt(px * px + py * py + pz * pz) - bottom_radius
        density_at(altitude, h_step, density, dens)
        step = 0.5 * (samples[k] - samples[k - 1]) if k > 0 else 0.0
        for c in range(n_c):
            if dens[c] == 0.0 and previous[c, 0] == 0.0:
                continue
            for w in range(n_wl):
                value = dens[c] * t_sun[w]
                inscatter[c, w] += step * (previous[c, w] + value)
                previous[c, w] = value
    for w in range(n_wl):
        transmittance[w] = t_view[w]
    if hits_ground:
        gx, gy, gz = ox + t_end * dx, oy + t_end * dy, oz + t_end * dz
        mu_s = (gx * sun_direction[0] + gy * sun_direction[1]
                + gz * sun_direction[2]) / math.sqrt(gx * gx + gy * gy + gz * gz)
        for w in range(n_wl):
            ground[w] = t_sun[w] * max(mu_s, 0.0)  # t_sun holds T(x, g) T_sun(g) here


@njit(parallel=True, cache=True)
def single_scattering(origins, directions, sun_direction, n_samples, bottom_radius, top_radius,
                      h_step, density, extinction, sun_angular_radius, model):
    """(inscatter (n, n_c, n_wl), transmittance (n, n_wl), ground (n, n_wl)) along rays from
    origins (n, 3) along unit directions (n, 3) through the atmosphere:
    inscatter[c] = int T(x, p) n_c(p) T_sun(p) dt (trapezoid on `table_ray_distances`' samples,
    n_c the profile's density), T the transmittance to the ray's end, ground =
    T(x, g) T_sun(g) max(mu_s(g), 0) where the ray meets the ground (else 0). `model`: the
    `chapman.ColumnModel` arrays."""
    n_ray = directions.shape[0]
    n_c, n_wl = extinction.shape
    inscatter, transmittance, ground = single_scattering_outputs(n_ray, n_c, n_wl)
    n_blocks = (n_ray + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        scratch = (np.empty(n_samples + 1), np.empty((4, n_c)), np.empty(n_c), np.empty(n_wl),
                   np.empty(n_wl), np.zeros((n_c, n_wl)))
        for i in range(block * RAYS_PER_BLOCK, min(n_ray, (block + 1) * RAYS_PER_BLOCK)):
            _march_ray(origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0],
                       directions[i, 1], directions[i, 2], sun_direction, n_samples,
                       bottom_radius, top_radius, h_step, density, extinction,
                       sun_angular_radius, model, scratch, inscatter[i], transmittance[i],
                       ground[i])
    return inscatter, transmittance, ground


@njit(parallel=True, cache=True)
def transmittance_rays(origins, directions, distances, bottom_radius, top_radius, extinction,
                       model):
    """Transmittance (n, n_wl) from origins (n, 3) along unit directions (n, 3) over
    `distances` (n,) [m] (inf: out of the atmosphere; 0 when the ground blocks the path), from
    the closed-form columns."""
    n_ray = origins.shape[0]
    n_c, n_wl = extinction.shape
    result = np.ones((n_ray, n_wl))
    for i in prange(n_ray):
        ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        _, _, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz, bottom_radius,
                                                        top_radius)
        blocked, t_end = path_end(t_end, hits_ground, distances[i])
        if blocked:
            for w in range(n_wl):
                result[i, w] = 0.0
            continue
        if t_end <= t_start:
            continue
        sign = -1.0 if hits_ground else 1.0
        first, last = np.empty(n_c), np.empty(n_c)
        _point_columns(ox, oy, oz, dx, dy, dz, t_start, sign, bottom_radius, model, first)
        _point_columns(ox, oy, oz, dx, dy, dz, t_end, sign, bottom_radius, model, last)
        for w in range(n_wl):
            tau = 0.0
            for c in range(n_c):
                tau += extinction[c, w] * max(sign * (first[c] - last[c]), 0.0)
            result[i, w] = math.exp(-tau)
    return result
