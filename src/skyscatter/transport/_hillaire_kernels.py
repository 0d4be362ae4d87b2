"""Numba kernels of the Hillaire 2020 solver (`transport/hillaire.py`): the multiple-scattering
table, the view-ray march with its single-scattering + multiple-scattering source, and the
sky-view table's lookup.

Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering Technique", Comput.
Graph. Forum 39(4), 13-22 (EGSR 2020), doi:10.1111/cgf.14050, section 5. Everything here is
per unit of sun irradiance E_sun (the solver multiplies by it), wavelength last, densities
and sample points as `transport/_kernels.py` (linear between levels; samples dense at the
segment's lowest point, trapezoid rule), columns to the sun from the transmittance table
(`_kernels.column_table`, `_kernels.sun_columns`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport._kernels import (
    density_at,
    radius_along,
    ray_segment,
    sample_distance,
    sample_total,
    split_sample_count,
    sun_columns,
    sun_cosines,
    view_end,
)
from skyscatter.transport.geometry import (
    atmosphere_segment,
    horizon_cos_zenith,
    sun_visible_fraction,
)

ISOTROPIC = 1.0 / (4.0 * math.pi)  # p_u [sr^-1]


@njit(cache=True)
def sunlight(r, mu_s, bottom_radius, top_radius, sun_table, extinction, sun_angular_radius,
             column, out):
    """T_sun V into out (n_wl,) at radius r with the sun at zenith cosine mu_s: the
    transmittance to the sun times the visible part of its disk (0 in the planet's shadow);
    `column` (n_c,) is scratch."""
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible <= 0.0:
        out[:] = 0.0
        return
    sun_columns(r, mu_s, bottom_radius, top_radius, sun_table, column)
    for w in range(out.shape[0]):
        tau = 0.0
        for c in range(column.shape[0]):
            tau += extinction[c, w] * column[c]
        out[w] = math.exp(-tau) * visible


@njit(cache=True)
def multiple_scattering_coordinates(r, mu_s, bottom_radius, top_radius, mu_s_centre):
    """(x_h, x_mu) in [0, 1] of radius r and sun zenith cosine mu_s in the multiple-scattering
    table, whose nodes are x = k / (n - 1) on each axis (`hillaire.multiple_scattering_nodes`
    inverts this): x_h = sqrt(h / H), rows crowded at the ground where the air is densest;
    x_mu = x_c +- (1 - x_c or x_c) sqrt(|mu_s - c| / (1 - c or 1 + c)), x_c = (1 + c) / 2,
    columns crowded at c = `mu_s_centre`, where Psi_ms falls by orders of magnitude as the
    Earth's shadow rises through the air (the sun just below the horizon)."""
    h = min(max((r - bottom_radius) / (top_radius - bottom_radius), 0.0), 1.0)
    mu = min(max(mu_s, -1.0), 1.0)
    c = mu_s_centre
    x_c = 0.5 * (1.0 + c)
    if mu >= c:
        x_mu = x_c + (1.0 - x_c) * math.sqrt((mu - c) / (1.0 - c))
    else:
        x_mu = x_c - x_c * math.sqrt((c - mu) / (1.0 + c))
    return math.sqrt(h), x_mu


@njit(cache=True)
def multiple_scattering_at(r, mu_s, bottom_radius, top_radius, log_ms_table, mu_s_centre,
                           out):
    """Psi_ms (n_wl,) at radius r and sun zenith cosine mu_s: exp of the bilinear
    interpolation of `log_ms_table` (log Psi_ms at the nodes of
    `multiple_scattering_coordinates`). In log, as Psi_ms falls by orders of magnitude
    between neighbouring nodes in twilight, where linear interpolation follows the brighter
    one."""
    n_h, n_mu = log_ms_table.shape[0], log_ms_table.shape[1]
    x_h, x_mu = multiple_scattering_coordinates(r, mu_s, bottom_radius, top_radius,
                                                mu_s_centre)
    fh = x_h * (n_h - 1)
    fm = x_mu * (n_mu - 1)
    i = min(int(fh), n_h - 2)
    j = min(int(fm), n_mu - 2)
    a = fh - i
    b = fm - j
    for w in range(out.shape[0]):
        out[w] = math.exp(
            (1.0 - a) * ((1.0 - b) * log_ms_table[i, j, w] + b * log_ms_table[i, j + 1, w])
            + a * ((1.0 - b) * log_ms_table[i + 1, j, w] + b * log_ms_table[i + 1, j + 1, w]))


@njit(parallel=True, cache=True)
def multiple_scattering_table(radius_nodes, mu_s_nodes, gauss_x, gauss_w, n_phi, n_samples,
                              bottom_radius, top_radius, h_step, density, extinction,
                              scattering, sun_table, albedo, sun_angular_radius):
    """(psi, second, f_ms), each (n_h, n_mu_s, n_wl): Hillaire 2020 eqs. 5-9 at the nodes
    `radius_nodes` [m] x `mu_s_nodes` (sun zenith cosines), for a unit sun irradiance.

    second = int_4pi L'(x, -w) p_u dw, L' the light scattered once towards x by an isotropic
    phase function, sunlit ground included (eq. 5-6); f_ms = int_4pi L_f(x, -w) p_u dw with
    L_f = int T(x, x_t) sigma_s(x_t) dt, the share of light scattered back to x (eq. 7-8),
    integrated exactly over each step with its mean coefficients (so f_ms < 1 however thick);
    psi = second / (1 - f_ms), the geometric sum of all orders >= 2 (eq. 9). The sphere is
    integrated with Gauss-Legendre nodes `gauss_x`, `gauss_w` (on [-1, 1]) in the zenith
    cosine on each side of the node's horizon (the light jumps there, from the ground to the
    sky) x `n_phi` (even) midpoint azimuths; the sun lies in the plane of azimuth 0, so the
    azimuths phi and -phi see the same light and only those in (0, pi) are marched, with
    twice the weight."""
    n_c, n_wl = extinction.shape
    n_mu_s = mu_s_nodes.size
    n_h = radius_nodes.size
    second = np.zeros((n_h, n_mu_s, n_wl))
    f_ms = np.zeros((n_h, n_mu_s, n_wl))
    for cell in prange(n_h * n_mu_s):
        i = cell // n_mu_s
        j = cell % n_mu_s
        r = radius_nodes[i]
        mu_s0 = mu_s_nodes[j]
        sin_s = math.sqrt(max(1.0 - mu_s0 * mu_s0, 0.0))
        dens = np.empty(n_c)
        column = np.empty(n_c)
        dens_prev = np.empty(n_c)
        sun = np.empty(n_wl)
        view = np.empty(n_wl)  # transmittance from the node to the sample
        lit_prev = np.empty(n_wl)
        lit = np.empty(n_wl)
        mu_h = horizon_cos_zenith(r, bottom_radius)
        for k in range(2 * gauss_x.size):
            low, high = (mu_h, 1.0) if k < gauss_x.size else (-1.0, mu_h)
            g = k % gauss_x.size
            mu = low + (high - low) * 0.5 * (gauss_x[g] + 1.0)
            sin_v = math.sqrt(max(1.0 - mu * mu, 0.0))
            for m in range(n_phi // 2):
                weight = (2.0 * 0.5 * (high - low) * gauss_w[g] * 2.0 * math.pi / n_phi
                          * ISOTROPIC)
                nu = sin_v * math.cos(2.0 * math.pi * (m + 0.5) / n_phi) * sin_s + mu * mu_s0
                t_start, t_end, hits_ground = atmosphere_segment(r, mu, bottom_radius,
                                                                 top_radius)
                view[:] = 1.0
                lit_prev[:] = 0.0
                t_prev = 0.0
                radius = r
                mu_s = mu_s0
                if t_end > t_start:
                    t_split, m1, m2 = split_sample_count(r, mu, t_start, t_end, n_samples)
                    for s in range(sample_total(m1, m2, n_samples)):
                        t = sample_distance(s, r, mu, t_start, t_end, n_samples, t_split, m1,
                                            m2)
                        radius = radius_along(r, mu, t)
                        mu_s = (r * mu_s0 + t * nu) / radius
                        density_at(radius - bottom_radius, h_step, density, dens)
                        dt = t - t_prev
                        sunlight(radius, mu_s, bottom_radius, top_radius, sun_table,
                                 extinction, sun_angular_radius, column, sun)
                        for w in range(n_wl):
                            sigma_s = 0.0
                            for c in range(n_c):
                                sigma_s += scattering[c, w] * dens[c]
                            if s > 0:
                                step_tau = 0.0
                                step_scattered = 0.0
                                for c in range(n_c):
                                    mean = 0.5 * (dens_prev[c] + dens[c]) * dt
                                    step_tau += extinction[c, w] * mean
                                    step_scattered += scattering[c, w] * mean
                                # L_f over the step with its mean coefficients, exactly:
                                # T_before sigma_s / sigma_t (1 - exp(-sigma_t dt)), so that
                                # f_ms stays below the single-scattering albedo (< 1)
                                step_loss = -math.expm1(-step_tau)
                                if step_tau > 1e-12:
                                    step_scattered *= step_loss / step_tau
                                f_ms[i, j, w] += weight * view[w] * step_scattered
                                view[w] *= 1.0 - step_loss
                            lit[w] = view[w] * sigma_s * sun[w] * ISOTROPIC
                            if s > 0:
                                second[i, j, w] += weight * 0.5 * (lit_prev[w] + lit[w]) * dt
                            lit_prev[w] = lit[w]
                        for c in range(n_c):
                            dens_prev[c] = dens[c]
                        t_prev = t
                if hits_ground:  # the sunlit Lambertian ground seen through the air
                    sunlight(radius, mu_s, bottom_radius, top_radius, sun_table, extinction,
                             sun_angular_radius, column, sun)
                    for w in range(n_wl):
                        second[i, j, w] += (weight * view[w] * albedo[w] / math.pi * sun[w]
                                            * max(mu_s, 0.0))
    # f_ms -> 1 only in conservative media of infinite depth, where L_2nd -> 0 too: the floor
    # keeps the rounding of f_ms = 1 from making 0 / 0
    return second / np.maximum(1.0 - f_ms, 1e-12), second, f_ms


RAYS_PER_BLOCK = 64  # rays that share scratch arrays in the parallel loop


@njit(parallel=True, cache=True)
def march_rays(origins, directions, max_distances, sun_direction, n_samples, bottom_radius,
               top_radius, h_step, density, extinction, scattering, phase_scattering,
               sun_table, log_ms_table, mu_s_centre, albedo, sun_angular_radius,
               with_ground):
    """(radiance, transmittance), each (n_ray, n_wl), per unit sun irradiance, along rays that
    end where they leave the atmosphere, at the ground or after `max_distances` [m]
    (Hillaire 2020 eq. 1 with the source of eq. 10):

        L = int T(x, x_t) [ sum_c n_c(x_t) beta_s,c p_c(nu) T_sun V
                            + sigma_s(x_t) Psi_ms(x_t, mu_s) ] dt
            + [ground, `with_ground`] T(x, g) albedo / pi T_sun(g) V(g) max(mu_s(g), 0)

    `phase_scattering` (n_ray or 1, n_c, n_wl) holds beta_s,c p_c(nu) of each ray
    (per unit density), `log_ms_table` log Psi_ms (`multiple_scattering_table`) on the nodes
    of `multiple_scattering_coordinates` with `mu_s_centre`."""
    n_ray = directions.shape[0]
    n_c, n_wl = extinction.shape
    radiance = np.zeros((n_ray, n_wl))
    transmittance = np.ones((n_ray, n_wl))
    n_blocks = (n_ray + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        dens = np.empty(n_c)
        dens_prev = np.empty(n_c)
        view_column = np.empty(n_c)
        column = np.empty(n_c)
        sun = np.empty(n_wl)
        psi = np.empty(n_wl)
        integrand_prev = np.empty(n_wl)
        view_tau = np.empty(n_wl)
        for i in range(block * RAYS_PER_BLOCK, min(n_ray, (block + 1) * RAYS_PER_BLOCK)):
            o = i if origins.shape[0] > 1 else 0
            p = i if phase_scattering.shape[0] > 1 else 0
            ox, oy, oz = origins[o, 0], origins[o, 1], origins[o, 2]
            dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
            r, mu, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz,
                                                             bottom_radius, top_radius)
            mu_s0, nu = sun_cosines(ox, oy, oz, r, dx, dy, dz, sun_direction)
            t_end, hits_ground = view_end(t_start, t_end, hits_ground, max_distances[i])
            view_column[:] = 0.0
            integrand_prev[:] = 0.0
            radius = r
            mu_s = mu_s0
            if t_end > t_start:
                t_split, m1, m2 = split_sample_count(r, mu, t_start, t_end, n_samples)
                t_prev = 0.0
                for s in range(sample_total(m1, m2, n_samples)):
                    t = sample_distance(s, r, mu, t_start, t_end, n_samples, t_split, m1, m2)
                    radius = radius_along(r, mu, t)
                    mu_s = (r * mu_s0 + t * nu) / radius
                    density_at(radius - bottom_radius, h_step, density, dens)
                    dt = t - t_prev
                    if s > 0:
                        for c in range(n_c):
                            view_column[c] += 0.5 * (dens_prev[c] + dens[c]) * dt
                    sunlight(radius, mu_s, bottom_radius, top_radius, sun_table, extinction,
                             sun_angular_radius, column, sun)
                    multiple_scattering_at(radius, mu_s, bottom_radius, top_radius,
                                           log_ms_table, mu_s_centre, psi)
                    for w in range(n_wl):
                        tau = 0.0
                        single = 0.0
                        sigma_s = 0.0
                        for c in range(n_c):
                            tau += extinction[c, w] * view_column[c]
                            single += phase_scattering[p, c, w] * dens[c]
                            sigma_s += scattering[c, w] * dens[c]
                        value = math.exp(-tau) * (single * sun[w] + sigma_s * psi[w])
                        if s > 0:
                            radiance[i, w] += 0.5 * (integrand_prev[w] + value) * dt
                        integrand_prev[w] = value
                    for c in range(n_c):
                        dens_prev[c] = dens[c]
                    t_prev = t
            for w in range(n_wl):
                tau = 0.0
                for c in range(n_c):
                    tau += extinction[c, w] * view_column[c]
                view_tau[w] = tau
                transmittance[i, w] = math.exp(-tau)
            if with_ground and hits_ground:
                sunlight(radius, mu_s, bottom_radius, top_radius, sun_table, extinction,
                         sun_angular_radius, column, sun)
                for w in range(n_wl):
                    radiance[i, w] += (transmittance[i, w] * albedo[w] / math.pi * sun[w]
                                       * max(mu_s, 0.0))
    return radiance, transmittance


@njit(cache=True)
def sky_view_coordinates(mu, phi, horizon_zenith, n_lat, n_lon):
    """Fractional (row, column) of the view (zenith cosine mu, azimuth from the sun phi in
    [0, pi]) in the sky-view table (Hillaire 2020 section 5.3): rows k = 0 .. n/2 - 1 (n =
    n_lat) above the horizon at s = k / (n/2 - 1/2) of s = 1 - sqrt(1 - theta / theta_h), from
    the zenith to half a row above the horizon; rows n/2 + k below it at
    s = (k + 1/2) / (n/2 - 1/2) of s = sqrt((theta - theta_h) / (pi - theta_h)), from half a
    row below the horizon to the nadir (dense at the horizon); columns phi = pi k / (n_lon - 1).
    The row is clamped to the view's half, so that the sky and the ground are never blended."""
    half = n_lat // 2
    theta = math.acos(min(max(mu, -1.0), 1.0))
    if theta < horizon_zenith:
        s = 1.0 - math.sqrt(max(1.0 - theta / horizon_zenith, 0.0))
        row = min(s * (half - 0.5), half - 1.0)
    else:
        s = math.sqrt(min((theta - horizon_zenith) / (math.pi - horizon_zenith), 1.0))
        row = half + max(s * (half - 0.5) - 0.5, 0.0)
    column = min(max(phi / math.pi, 0.0), 1.0) * (n_lon - 1)
    return row, column


@njit(parallel=True, cache=True)
def sky_view_lookup(table, frame, directions, horizon_zenith, out):
    """Bilinear lookups of the sky-view table (n_lat, n_lon, n_wl) along `directions` (n, 3)
    into out (n, n_wl); `frame` rows: the observer's horizontal towards the sun, the other
    horizontal, up (`sky_view_coordinates`)."""
    n_lat, n_lon = table.shape[0], table.shape[1]
    half = n_lat // 2
    for i in prange(directions.shape[0]):
        x = (directions[i, 0] * frame[0, 0] + directions[i, 1] * frame[0, 1]
             + directions[i, 2] * frame[0, 2])
        y = (directions[i, 0] * frame[1, 0] + directions[i, 1] * frame[1, 1]
             + directions[i, 2] * frame[1, 2])
        z = (directions[i, 0] * frame[2, 0] + directions[i, 1] * frame[2, 1]
             + directions[i, 2] * frame[2, 2])
        norm = math.sqrt(x * x + y * y + z * z)
        row, column = sky_view_coordinates(z / norm, math.atan2(abs(y), x), horizon_zenith,
                                           n_lat, n_lon)
        k = min(int(row), n_lat - 2)
        k = min(k, half - 2) if row < half else max(k, half)  # within the view's half
        a = row - k
        m = min(int(column), n_lon - 2)
        b = column - m
        for w in range(table.shape[2]):
            out[i, w] = ((1.0 - a) * ((1.0 - b) * table[k, m, w] + b * table[k, m + 1, w])
                         + a * ((1.0 - b) * table[k + 1, m, w] + b * table[k + 1, m + 1, w]))
