"""Numba kernels that march rays through the profile: column densities, which every solver
shares (the tables build their column table with them, the Monte Carlo reference and
`transport/transmittance.py` march with them), and the single-scattering solver's
in-scattering.

Conventions (docs/physics/single_scattering.md):
- A constituent's density is linearly interpolated between uniform altitude levels
  h_k = k * h_step, k = 0..n_z-1, and is zero above the top.
- Along a ray, samples are dense near the lowest point of the segment (the tangent point, or
  an end): the segment is split at the tangent point and each part is sampled at
  t = t_low +- length * (k / m)^2, so exponential profiles are resolved near the ground for
  observers on the ground and in space alike. Integrals use the trapezoid rule on these samples.
- Columns to the sun are read from a table over (r, mu_s) in Bruneton's transmittance
  parameterisation (x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min); Bruneton 2017,
  functions.glsl `GetTransmittanceTextureUvFromRMu`), built once per atmosphere.
Kernels take arrays and floats only; `transport/reference_numpy.py` holds slow literal twins.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport.geometry import (
    atmosphere_segment,
    horizon_cos_zenith,
    sun_visible_fraction,
)
from skyscatter.transport.table_parameterisation import (
    distance_to_top_boundary,
    transmittance_r_mu_from_x,
    transmittance_x_from_r_mu,
)


@njit(cache=True, inline="always")
def level_weights(altitude, h_step, n_z):
    """(k, w_k, w_k+1): the two levels of a profile of n_z >= 2 levels h_step [m] apart around
    `altitude` [m] and their weights: linear between levels, the lowest level's density below
    it, none above the top (weights 0). Branch-free, so that loops over it vectorise."""
    x = altitude / h_step
    inside = 1.0 if x <= n_z - 1 + 1e-9 else 0.0
    x = min(max(x, 0.0), n_z - 1.0)
    k = min(int(x), n_z - 2)
    f = x - k
    return k, (1.0 - f) * inside, f * inside


@njit(cache=True)
def density_at(altitude, h_step, density, out):
    """Densities of all constituents at `altitude` [m] into out (n_c,) (`level_weights`)."""
    k, below, above = level_weights(altitude, h_step, density.shape[1])
    for c in range(density.shape[0]):
        out[c] = density[c, k] * below + density[c, k + 1] * above


def cumulative_columns(density: np.ndarray, h_step: float) -> np.ndarray:
    """int_0^h_k n_c dh [density x m] of every constituent at every level k, (n_c, n_z): the
    trapezoid rule, exact for densities linear between levels (`column_below`)."""
    steps = 0.5 * (density[:, 1:] + density[:, :-1]) * h_step
    return np.concatenate([np.zeros((density.shape[0], 1)), np.cumsum(steps, axis=1)], axis=1)


@njit(cache=True)
def column_below(altitude, h_step, density, cumulative, out):
    """int_0^altitude n_c dh [density x m] of every constituent into out (n_c,), exact for the
    densities of `density_at` (linear between levels, zero above the top); `cumulative` from
    `cumulative_columns`. 0 at and below the ground."""
    n_z = density.shape[1]
    x = altitude / h_step
    if x <= 0.0:
        for c in range(density.shape[0]):
            out[c] = 0.0
        return
    k = int(x)
    if k >= n_z - 1:
        for c in range(density.shape[0]):
            out[c] = cumulative[c, n_z - 1]
        return
    f = x - k
    for c in range(density.shape[0]):
        out[c] = cumulative[c, k] + h_step * f * (
            density[c, k] + 0.5 * f * (density[c, k + 1] - density[c, k]))


@njit(cache=True)
def split_sample_count(r, mu, t_start, t_end, n_samples):
    """(t_split, m1, m2): the segment [t_start, t_end] is split at the tangent point -r mu when
    it lies inside; m1 and m2 samples (intervals) go to the parts before and after it."""
    t_tangent = -r * mu
    if t_tangent <= t_start or t_tangent >= t_end:
        return (t_start if t_tangent <= t_start else t_end), 0, 0
    m1 = max(2, int(round(n_samples * (t_tangent - t_start) / (t_end - t_start))))
    m2 = max(2, n_samples - m1)
    return t_tangent, m1, m2


@njit(cache=True)
def sample_distance(j, r, mu, t_start, t_end, n_samples, t_split, m1, m2):
    """Distance of sample j (0..n_total-1, increasing) along the segment; see module doc."""
    if m1 > 0:
        if j <= m1:
            k = m1 - j
            return t_split - (t_split - t_start) * (k / m1) ** 2
        k = j - m1
        return t_split + (t_end - t_split) * (k / m2) ** 2
    if t_split <= t_start:  # lowest point at the start: dense near the start
        return t_start + (t_end - t_start) * (j / n_samples) ** 2
    k = n_samples - j  # lowest point at the end: dense near the end
    return t_end - (t_end - t_start) * (k / n_samples) ** 2


@njit(cache=True)
def sample_total(m1, m2, n_samples):
    """Number of sample points for a segment split as returned by `split_sample_count`."""
    return (m1 + m2 + 1) if m1 > 0 else (n_samples + 1)


@njit(cache=True)
def radius_along(r, mu, t):
    """Radius [m] at distance t [m] along the ray (r, mu)."""
    return math.sqrt(max(r * r + t * t + 2.0 * r * mu * t, 0.0))


@njit(cache=True)
def columns_along_segment(r, mu, t_start, t_end, n_samples, bottom_radius, h_step, density,
                          out):
    """Column densities [density x m] of each constituent along the ray (r, mu) between
    t_start and t_end, into out (n_c,): the trapezoid rule on the samples of
    `sample_distance`, the densities linear between the profile's levels (`level_weights`).
    The samples' positions first, then each constituent's sum: loops that vectorise (3.6 x
    faster than a sample at a time)."""
    n_c, n_z = density.shape
    for c in range(n_c):
        out[c] = 0.0
    if t_end <= t_start:
        return
    t_split, m1, m2 = split_sample_count(r, mu, t_start, t_end, n_samples)
    total = sample_total(m1, m2, n_samples)
    t = np.empty(total)
    level = np.empty(total, dtype=np.int64)
    below = np.empty(total)
    above = np.empty(total)
    for j in range(total):
        t[j] = sample_distance(j, r, mu, t_start, t_end, n_samples, t_split, m1, m2)
    for j in range(total):
        level[j], below[j], above[j] = level_weights(radius_along(r, mu, t[j]) - bottom_radius,
                                                     h_step, n_z)
    for c in range(n_c):
        row = density[c]
        previous = row[level[0]] * below[0] + row[level[0] + 1] * above[0]
        column = 0.0
        for j in range(1, total):
            current = row[level[j]] * below[j] + row[level[j] + 1] * above[j]
            column += 0.5 * (previous + current) * (t[j] - t[j - 1])
            previous = current
        out[c] = column


@njit(parallel=True, cache=True)
def column_table(n_r, n_mu, n_samples, bottom_radius, top_radius, h_step, density):
    """Column densities [density x m] from each node of the transmittance table to the top,
    (n_c, n_r, n_mu); node (i, j) is x_r = i / (n_r - 1), x_mu = j / (n_mu - 1). Used for the
    single-scattering solver's sun columns and for the transmittance table."""
    n_c = density.shape[0]
    table = np.empty((n_c, n_r, n_mu))
    for index in prange(n_r * n_mu):
        i = index // n_mu
        j = index % n_mu
        r, mu = transmittance_r_mu_from_x(j / (n_mu - 1), i / (n_r - 1), bottom_radius,
                                          top_radius)
        out = np.empty(n_c)
        columns_along_segment(r, mu, 0.0, distance_to_top_boundary(r, mu, top_radius),
                              n_samples, bottom_radius, h_step, density, out)
        for c in range(n_c):
            table[c, i, j] = out[c]
    return table


@njit(cache=True)
def sun_columns(r, mu_s, bottom_radius, top_radius, table, out):
    """Columns from radius r towards the sun (zenith cosine mu_s) to the top, into out (n_c,).
    Below the horizon the horizon ray's column is used; `sun_visible_fraction` cuts the light."""
    mu = max(mu_s, horizon_cos_zenith(r, bottom_radius))
    x_mu, x_r = transmittance_x_from_r_mu(r, mu, bottom_radius, top_radius)
    n_r = table.shape[1]
    n_mu = table.shape[2]
    fr = x_r * (n_r - 1)
    fm = x_mu * (n_mu - 1)
    i = min(int(fr), n_r - 2)
    j = min(int(fm), n_mu - 2)
    a = fr - i
    b = fm - j
    for c in range(table.shape[0]):
        out[c] = ((1.0 - a) * ((1.0 - b) * table[c, i, j] + b * table[c, i, j + 1])
                  + a * ((1.0 - b) * table[c, i + 1, j] + b * table[c, i + 1, j + 1]))


@njit(cache=True)
def ray_segment(ox, oy, oz, dx, dy, dz, bottom_radius, top_radius):
    """(r, mu, t_start, t_end, hits_ground) of the ray from the point o along the unit
    direction d: its radius [m] and zenith cosine at o and its part inside the atmosphere
    (`geometry.atmosphere_segment`)."""
    r = math.sqrt(ox * ox + oy * oy + oz * oz)
    mu = (ox * dx + oy * dy + oz * dz) / r
    t_start, t_end, hits_ground = atmosphere_segment(r, mu, bottom_radius, top_radius)
    return r, mu, t_start, t_end, hits_ground


@njit(cache=True)
def sun_cosines(ox, oy, oz, r, dx, dy, dz, sun_direction):
    """(mu_s, nu): the sun's zenith cosine at the point o (radius r) and the cosine between
    the direction d and the sun, both unit."""
    mu_s = (ox * sun_direction[0] + oy * sun_direction[1] + oz * sun_direction[2]) / r
    nu = dx * sun_direction[0] + dy * sun_direction[1] + dz * sun_direction[2]
    return mu_s, nu


@njit(cache=True)
def view_end(t_start, t_end, hits_ground, max_distance):
    """(t_end, hits_ground) of a view ray that stops after `max_distance` [m] (inf: where it
    leaves the atmosphere or meets the ground): one stopped short does not reach the ground."""
    if max_distance < t_end:
        return max(max_distance, t_start), False
    return t_end, hits_ground


@njit(cache=True)
def path_end(t_end, hits_ground, distance):
    """(blocked, t_end) of a path `distance` [m] long (inf: towards a light source) along a
    ray whose part in the atmosphere ends at t_end: blocked when the ground comes before the
    path's end, else where the path leaves the air or ends."""
    if hits_ground and distance > t_end * (1.0 + 1e-12):
        return True, t_end
    return False, min(t_end, distance)


@njit(cache=True)
def single_scattering_outputs(n_ray, n_c, n_wl):
    """The arrays a single-scattering march fills, before any ray: inscatter (n_ray, n_c, n_wl)
    zeros, transmittance (n_ray, n_wl) ones, ground (n_ray, n_wl) zeros (`single_scattering`
    has their meaning)."""
    return np.zeros((n_ray, n_c, n_wl)), np.ones((n_ray, n_wl)), np.zeros((n_ray, n_wl))


RAYS_PER_BLOCK = 64  # rays that share scratch arrays in the parallel loop


@njit(parallel=True, cache=True)
def single_scattering(origins, directions, max_distances, sun_direction, n_samples,
                      bottom_radius, top_radius, h_step, density, extinction, sun_table,
                      sun_angular_radius):
    """Single scattering along many rays with one sun direction, each ray ending where it
    leaves the atmosphere, at the ground, or after `max_distances` [m] (inf: no limit).

    Returns
    - inscatter (n_ray, n_c, n_wl): integral over the ray of T(x, p) density_c(p) T_sun(p) ds
      [density x m]; radiance = E_sun * sum_c scattering_c * phase_c(nu) * inscatter_c.
    - transmittance (n_ray, n_wl): along the whole segment inside the atmosphere [-].
    - ground (n_ray, n_wl): T(x, g) T_sun(g) max(mu_s(g), 0) at the ground hit g (0 if the ray
      misses the ground or ends before it); Lambertian radiance = E_sun * albedo / pi * ground.
    """
    n_ray = origins.shape[0]
    n_c, n_wl = extinction.shape
    inscatter, transmittance, ground = single_scattering_outputs(n_ray, n_c, n_wl)
    n_blocks = (n_ray + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        view_column = np.empty(n_c)
        dens_prev = np.empty(n_c)
        dens = np.empty(n_c)
        sun_col = np.empty(n_c)
        tau = np.empty(n_wl)
        attenuation = np.empty(n_wl)
        integrand_prev = np.empty((n_c, n_wl))
        for i in range(block * RAYS_PER_BLOCK, min(n_ray, (block + 1) * RAYS_PER_BLOCK)):
            ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
            dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
            r, mu, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz,
                                                             bottom_radius, top_radius)
            mu_s0, nu = sun_cosines(ox, oy, oz, r, dx, dy, dz, sun_direction)
            t_end, hits_ground = view_end(t_start, t_end, hits_ground, max_distances[i])
            if t_end <= t_start:
                if hits_ground:  # standing on the ground, looking down: the lit ground
                    sun_fraction = sun_visible_fraction(r, mu_s0, bottom_radius,
                                                        sun_angular_radius)
                    if sun_fraction > 0.0:
                        sun_columns(r, mu_s0, bottom_radius, top_radius, sun_table, sun_col)
                        for w in range(n_wl):
                            tau_sun = 0.0
                            for c in range(n_c):
                                tau_sun += extinction[c, w] * sun_col[c]
                            ground[i, w] = (math.exp(-tau_sun) * sun_fraction
                                            * max(mu_s0, 0.0))
                continue
            t_split, m1, m2 = split_sample_count(r, mu, t_start, t_end, n_samples)
            total = sample_total(m1, m2, n_samples)
            view_column[:] = 0.0
            sun_col[:] = 0.0
            integrand_prev[:, :] = 0.0
            t_prev = 0.0
            mu_s = mu_s0
            for j in range(total):
                t = sample_distance(j, r, mu, t_start, t_end, n_samples, t_split, m1, m2)
                radius = radius_along(r, mu, t)
                density_at(radius - bottom_radius, h_step, density, dens)
                dt = t - t_prev
                if j > 0:
                    for c in range(n_c):
                        view_column[c] += 0.5 * (dens_prev[c] + dens[c]) * dt
                mu_s = (r * mu_s0 + t * nu) / radius
                visible = sun_visible_fraction(radius, mu_s, bottom_radius, sun_angular_radius)
                if visible > 0.0:
                    sun_columns(radius, mu_s, bottom_radius, top_radius, sun_table, sun_col)
                tau[:] = 0.0
                for c in range(n_c):
                    column = view_column[c] + sun_col[c]
                    for w in range(n_wl):
                        tau[w] += extinction[c, w] * column
                for w in range(n_wl):
                    attenuation[w] = math.exp(-tau[w]) * visible
                for c in range(n_c):
                    weight = 0.5 * dt if j > 0 else 0.0
                    for w in range(n_wl):
                        value = dens[c] * attenuation[w]
                        inscatter[i, c, w] += weight * (integrand_prev[c, w] + value)
                        integrand_prev[c, w] = value
                for c in range(n_c):
                    dens_prev[c] = dens[c]
                t_prev = t
            for w in range(n_wl):
                tau_view = 0.0
                for c in range(n_c):
                    tau_view += extinction[c, w] * view_column[c]
                transmittance[i, w] = math.exp(-tau_view)
                if hits_ground:
                    ground[i, w] = attenuation[w] * max(mu_s, 0.0)
    return inscatter, transmittance, ground


@njit(parallel=True, cache=True)
def transmittance_rays(origins, directions, distances, n_samples, bottom_radius, top_radius,
                       h_step, density, extinction):
    """Transmittance (n_ray, n_wl) from each origin along its direction over `distances` [m]
    (inf: out of the atmosphere, towards a light source; a ray blocked by the ground, before
    the distance or with an infinite one, gets 0)."""
    n_ray = origins.shape[0]
    n_c, n_wl = extinction.shape
    result = np.ones((n_ray, n_wl))
    for i in prange(n_ray):
        r, mu, t_start, t_end, hits_ground = ray_segment(
            origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0], directions[i, 1],
            directions[i, 2], bottom_radius, top_radius)
        blocked, t_end = path_end(t_end, hits_ground, distances[i])
        if blocked:
            for w in range(n_wl):
                result[i, w] = 0.0
            continue
        if t_end <= t_start:
            continue
        column = np.empty(n_c)
        columns_along_segment(r, mu, t_start, t_end, n_samples, bottom_radius, h_step, density,
                              column)
        for w in range(n_wl):
            tau = 0.0
            for c in range(n_c):
                tau += extinction[c, w] * column[c]
            result[i, w] = math.exp(-tau)
    return result
