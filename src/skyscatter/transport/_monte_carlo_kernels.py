"""Numba kernels of the Monte Carlo solver: backward path tracing in a spherical shell.

Conventions (the estimator is described in `transport/monte_carlo.py`):
- A path starts where the view ray is inside the atmosphere and follows the view direction d
  (observer -> scene). A photon that reaches the observer travels along -d, so the scattering
  angle between sunlight (travelling along -s) and the path is nu = d . s, and after sampling a
  new direction d' at a collision, cos(scattering angle) = d . d'.
- Free flights use delta tracking with a constant majorant per wavelength (Woodcock et al.
  1965; Novák et al. 2018, §5.1): exact for any density that the majorant bounds. The density is
  `_kernels.density_at` (linear between levels, zero above the top level), whose maximum is at
  a level, so the largest level extinction is a true majorant.
- Phase functions are tables at theta_i = pi i / (n_angle - 1): p(theta) is interpolated
  linearly in theta (as `transport/tables.py` does); directions are drawn from a proposal that
  is uniform in cos(theta) on each interval with mass 2 pi (p_i + p_i+1) / 2 (cos theta_i -
  cos theta_i+1), and weighted by p / proposal, so the estimate is unbiased for the tabulated p.
- Random numbers: numba's per-thread Mersenne Twister, re-seeded at the start of every work unit
  (one ray, one wavelength, one batch of paths) with a seed derived from (seed, unit). Within a
  unit the draws are sequential, so results do not depend on the number of threads or on which
  thread runs which unit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport._kernels import columns_along_segment, density_at
from skyscatter.transport.geometry import (
    atmosphere_segment,
    distance_to_sphere,
    horizon_cos_zenith,
    sun_visible_fraction,
)

TWO_PI = 2.0 * math.pi
RR_WEIGHT_MAX = 0.95  # largest survival probability of Russian roulette


@njit(cache=True)
def phase_cdf(phase):
    """Cumulative proposal masses (n_s, n_wl, n_angle) from phase tables (n_s, n_wl, n_angle)
    [sr^-1] sampled at theta_i = pi i / (n_angle - 1); see the module doc. A row whose table is
    zero everywhere gets a uniform (isotropic) proposal."""
    n_s, n_wl, n_angle = phase.shape
    cdf = np.zeros((n_s, n_wl, n_angle))
    for s in range(n_s):
        for w in range(n_wl):
            total = 0.0
            for i in range(n_angle - 1):
                c0 = math.cos(math.pi * i / (n_angle - 1))
                c1 = math.cos(math.pi * (i + 1) / (n_angle - 1))
                total += TWO_PI * 0.5 * (phase[s, w, i] + phase[s, w, i + 1]) * (c0 - c1)
                cdf[s, w, i + 1] = total
            for i in range(n_angle):
                if total > 0.0:
                    cdf[s, w, i] /= total
                else:
                    cdf[s, w, i] = 0.5 * (1.0 - math.cos(math.pi * i / (n_angle - 1)))
    return cdf


@njit(cache=True)
def phase_value(table, nu):
    """Tabulated phase function (n_angle,) [sr^-1] at nu = cos(theta), linear in theta."""
    n_angle = table.shape[0]
    x = math.acos(min(1.0, max(-1.0, nu))) * (n_angle - 1) / math.pi
    k = min(int(x), n_angle - 2)
    f = x - k
    return table[k] * (1.0 - f) + table[k + 1] * f


@njit(cache=True)
def sample_phase(cdf, cos_grid, u):
    """(mu, proposal pdf [sr^-1]) drawn with uniform u from the cumulative masses `cdf`
    (n_angle,) over the nodes cos_grid = cos(theta_i)."""
    n_angle = cdf.shape[0]
    k = np.searchsorted(cdf, u, side="right") - 1
    k = min(max(k, 0), n_angle - 2)
    mass = cdf[k + 1] - cdf[k]
    while mass <= 0.0 and k < n_angle - 2:  # u on a flat stretch (rounding): move on
        k += 1
        mass = cdf[k + 1] - cdf[k]
    f = min(1.0, max(0.0, (u - cdf[k]) / mass)) if mass > 0.0 else 0.5
    mu = cos_grid[k] + f * (cos_grid[k + 1] - cos_grid[k])
    pdf = mass / (TWO_PI * (cos_grid[k] - cos_grid[k + 1]))
    return mu, pdf


@njit(cache=True)
def rotate(dx, dy, dz, mu, phi):
    """Unit vector at angle acos(mu) from the unit vector d and azimuth phi about it, using the
    orthonormal basis of Duff et al. (2017), JCGT 6(1), 1, listing 3."""
    sign = 1.0 if dz >= 0.0 else -1.0
    a = -1.0 / (sign + dz)
    b = dx * dy * a
    t1x, t1y, t1z = 1.0 + sign * dx * dx * a, sign * b, -sign * dx
    t2x, t2y, t2z = b, sign + dy * dy * a, -dy
    s = math.sqrt(max(0.0, 1.0 - mu * mu))
    c = s * math.cos(phi)
    e = s * math.sin(phi)
    x = mu * dx + c * t1x + e * t2x
    y = mu * dy + c * t1y + e * t2y
    z = mu * dz + c * t1z + e * t2z
    norm = math.sqrt(x * x + y * y + z * z)
    return x / norm, y / norm, z / norm


@njit(cache=True)
def sun_attenuation(px, py, pz, sun, w, bottom_radius, top_radius, h_step, density,
                    extinction, sun_angular_radius, n_sun_samples, column):
    """T_sun V at the point p: transmittance [-] to the top of the atmosphere towards the sun,
    ray marched (`_kernels.columns_along_segment`), times the visible part of the sun disk
    (`geometry.sun_visible_fraction`; a point sun when the radius is 0). As in the other solvers
    a sun below the horizon is attenuated like the horizon ray."""
    r = math.sqrt(px * px + py * py + pz * pz)
    mu_s = (px * sun[0] + py * sun[1] + pz * sun[2]) / r
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible <= 0.0:
        return 0.0
    r = min(r, top_radius)
    mu = max(mu_s, horizon_cos_zenith(r, bottom_radius))
    t_top = distance_to_sphere(r, mu, top_radius, True)
    columns_along_segment(r, mu, 0.0, t_top, n_sun_samples, bottom_radius, h_step, density,
                          column)
    tau = 0.0
    for c in range(density.shape[0]):
        tau += extinction[c, w] * column[c]
    return math.exp(-tau) * visible


@njit(cache=True)
def roulette(weight):
    """Russian roulette: 0 (the path ends) with probability 1 - q, else weight / q, with
    q = min(RR_WEIGHT_MAX, weight); unbiased."""
    survive = min(RR_WEIGHT_MAX, weight)
    if np.random.random() >= survive:
        return 0.0
    return weight / survive


@njit(cache=True)
def trace_path(ox, oy, oz, dx, dy, dz, w, sun, max_orders, rr_start, bottom_radius,
               top_radius, h_step, density, extinction, scattering, scatterers, phase, cdf,
               cos_grid, majorant, albedo, sun_angular_radius, n_sun_samples, dens, column):
    """Radiance estimate of one path at wavelength index w, per unit sun irradiance
    [sr^-1]: the sum over its scattering events of the next-event estimates towards the sun."""
    n_c = density.shape[0]
    n_s = scatterers.shape[0]
    result = 0.0
    weight = 1.0
    order = 0
    while True:
        r = math.sqrt(ox * ox + oy * oy + oz * oz)
        mu = (ox * dx + oy * dy + oz * dz) / r
        t_start, t_end, hits_ground = atmosphere_segment(r, mu, bottom_radius, top_radius)
        if t_end <= t_start and not hits_ground:
            return result  # misses the atmosphere
        # Delta tracking from the entry point (t_start > 0 only for observers in space).
        t = t_start
        collided = False
        be = 0.0
        px, py, pz = ox, oy, oz
        while majorant[w] > 0.0:
            t -= math.log(1.0 - np.random.random()) / majorant[w]
            if t >= t_end:
                break
            px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
            radius = math.sqrt(px * px + py * py + pz * pz)
            density_at(radius - bottom_radius, h_step, density, dens)
            be = 0.0
            for c in range(n_c):
                be += extinction[c, w] * dens[c]
            if np.random.random() * majorant[w] < be:
                collided = True
                break
        if collided:
            ox, oy, oz = px, py, pz
            bs = 0.0
            for s in range(n_s):
                bs += scattering[scatterers[s], w] * dens[scatterers[s]]
            weight *= bs / be
            if weight <= 0.0:
                return result
            nu_sun = dx * sun[0] + dy * sun[1] + dz * sun[2]
            attenuation = sun_attenuation(ox, oy, oz, sun, w, bottom_radius, top_radius,
                                          h_step, density, extinction, sun_angular_radius,
                                          n_sun_samples, column)
            if attenuation > 0.0:
                p_mix = 0.0
                for s in range(n_s):
                    p_mix += (scattering[scatterers[s], w] * dens[scatterers[s]]
                              * phase_value(phase[s, w], nu_sun))
                result += weight * p_mix / bs * attenuation
            order += 1
            if order >= max_orders:
                return result
            if order >= rr_start:
                weight = roulette(weight)
                if weight == 0.0:
                    return result
            # Constituent in proportion to its scattering coefficient, then its phase function.
            pick = np.random.random() * bs
            chosen = n_s - 1
            for s in range(n_s):
                pick -= scattering[scatterers[s], w] * dens[scatterers[s]]
                if pick < 0.0:
                    chosen = s
                    break
            mu_new, pdf = sample_phase(cdf[chosen, w], cos_grid, np.random.random())
            weight *= phase_value(phase[chosen, w], mu_new) / pdf
            dx, dy, dz = rotate(dx, dy, dz, mu_new, TWO_PI * np.random.random())
            continue
        if not hits_ground:
            return result  # leaves the atmosphere
        # Lambertian ground: next-event estimate, then a cosine-distributed new direction.
        gx, gy, gz = ox + t_end * dx, oy + t_end * dy, oz + t_end * dz
        scale = bottom_radius / math.sqrt(gx * gx + gy * gy + gz * gz)
        ox, oy, oz = gx * scale, gy * scale, gz * scale
        nx, ny, nz = ox / bottom_radius, oy / bottom_radius, oz / bottom_radius
        mu_s = nx * sun[0] + ny * sun[1] + nz * sun[2]
        if mu_s > 0.0:
            attenuation = sun_attenuation(ox, oy, oz, sun, w, bottom_radius, top_radius,
                                          h_step, density, extinction, sun_angular_radius,
                                          n_sun_samples, column)
            result += weight * albedo[w] / math.pi * mu_s * attenuation
        order += 1
        if order >= max_orders:
            return result
        weight *= albedo[w]
        if weight <= 0.0:
            return result
        if order >= rr_start:
            weight = roulette(weight)
            if weight == 0.0:
                return result
        dx, dy, dz = rotate(nx, ny, nz, math.sqrt(np.random.random()),
                            TWO_PI * np.random.random())


@njit(parallel=True, cache=True)
def trace_rays(origins, directions, ray_offset, sun, n_paths, batch, seed, max_orders, rr_start,
               bottom_radius, top_radius, h_step, density, extinction, scattering, scatterers,
               phase, cdf, majorant, sun_irradiance, albedo, sun_angular_radius,
               n_sun_samples):
    """Sums and sums of squares (n_ray, n_wl, n_batch) of the path estimates [W m^-2 sr^-1
    nm^-1] of `n_paths` paths per ray and wavelength, in batches of `batch` paths. The work unit
    (ray, wavelength, batch) is seeded with (seed, its index counted from ray `ray_offset`), so
    a call on part of the rays gives the same numbers as one call on all of them."""
    n_ray = origins.shape[0]
    n_c, n_wl = extinction.shape
    n_angle = phase.shape[2]
    n_batch = (n_paths + batch - 1) // batch
    sums = np.zeros((n_ray, n_wl, n_batch))
    squares = np.zeros((n_ray, n_wl, n_batch))
    cos_grid = np.cos(np.linspace(0.0, math.pi, n_angle))
    for unit in prange(n_ray * n_wl * n_batch):
        i = unit // (n_wl * n_batch)
        w = (unit // n_batch) % n_wl
        b = unit % n_batch
        index = ray_offset * n_wl * n_batch + unit
        np.random.seed((seed * 1_000_003 + index * 7_919 + 12_345) % 4_294_967_296)
        dens = np.empty(n_c)
        column = np.empty(n_c)
        total = 0.0
        total_sq = 0.0
        for _ in range(b * batch, min(n_paths, (b + 1) * batch)):
            value = sun_irradiance[w] * trace_path(
                origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0],
                directions[i, 1], directions[i, 2], w, sun, max_orders, rr_start,
                bottom_radius, top_radius, h_step, density, extinction, scattering,
                scatterers, phase, cdf, cos_grid, majorant, albedo, sun_angular_radius,
                n_sun_samples, dens, column)
            total += value
            total_sq += value * value
        sums[i, w, b] = total
        squares[i, w, b] = total_sq
    return sums, squares
