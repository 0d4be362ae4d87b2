"""Numba kernels of the cloud Monte Carlo reference: backward path tracing through the air of an
`OpticalProfile` and the cloud layers of a `CloudField` (`transport/cloud_monte_carlo.py`
describes the estimator).

Conventions (as `_monte_carlo_kernels`, whose path states, phase, sun and first-collision
kernels these call):
- A path follows the view direction d (observer -> scene); nu = d . s is the cosine of the
  scattering angle towards the sun s, and d . d' that of a new direction d'.
- Regions: the shells between consecutive radii of `radii` (ground, each cloud layer's base
  and top, top of the atmosphere), each with the cloud layer it holds (`region_layer`, -1 for
  none) and a majorant per wavelength (`majorant` (n_region, n_wl) [m^-1]): the largest air
  extinction on the levels that bracket it plus k_ext * params[layer, WATER] of its layer.
  Free flights are delta tracked region by region (Woodcock et al. 1965; Novák et al. 2018,
  Comput. Graph. Forum 37(2), 551, §5.1, doi:10.1111/cgf.13383): where a tentative distance
  passes the region's boundary the flight restarts there with the next region's majorant
  (exact: exponential distances have no memory).
- Cloud phase functions are the field's tables at theta_i = pi (i / (n - 1))^2 (`PHASE_ANGLES`
  nodes, dense at the forward peak), interpolated linearly in the node index i as the renderer
  reads them (`cloud_field.phase_table_index`); directions are drawn uniformly in cos(theta)
  within an interval chosen with mass 2 pi (p_i + p_i+1) / 2 (cos theta_i - cos theta_i+1)
  (`_monte_carlo_kernels.tabulated_phase_cdf`) and weighted by p / proposal, so the estimate
  is unbiased for the interpolated table.
- Random numbers: numba's per-thread Mersenne Twister, re-seeded at the start of every work
  unit (one ray, one wavelength, one batch of paths) from (seed, unit): the results do not
  depend on the number of threads.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.atmosphere.cloud_field import BASE_R, TOP_R, layer_water, phase_table_index
from skyscatter.transport._kernels import density_at
from skyscatter.transport._monte_carlo_kernels import (
    FLIGHT,
    GROUND,
    LEAVE,
    SCATTER,
    first_collision,
    phase_value,
    proposal_density,
    rotate,
    sample_phase,
    sun_attenuation,
)
from skyscatter.transport.geometry import (
    atmosphere_segment,
    horizon_cos_zenith,
    sun_visible_fraction,
)

TWO_PI = 2.0 * math.pi
# What scatters at the first collision of a branch (`random_walk`); later collisions: both.
AIR, CLOUD, BOTH = 1, 2, 3
ROULETTE_WEIGHT = 0.1  # paths lighter than this play Russian roulette (`importance_roulette`)
SPLIT_WEIGHT = 2.0  # paths heavier than this split into copies (`random_walk`)
STACK_SIZE = 64  # paths waiting per work unit (branches run first: a few are waiting)
PEAK_DEG = 10.0  # the sun-centred proposal: the cloud phase functions' first PEAK_DEG degrees
RATIO_ROULETTE = 0.05  # ratio tracking plays Russian roulette below this transmittance


@njit(cache=True)
def cloud_phase(table, nu):
    """A cloud phase table (PHASE_ANGLES,) [sr^-1] at nu = cos(theta), linear in the node index
    (as the renderer, `_cloud_kernels.march_clouds`)."""
    j, f = phase_table_index(nu)
    return table[j] * (1.0 - f) + table[j + 1] * f


@njit(cache=True)
def cloud_proposal_density(cdf, cos_grid, nu):
    """Density [sr^-1] at nu = cos(theta) of the directions `sample_phase` draws from the
    cumulative masses `cdf` (n,) of a cloud table on its first n nodes `cos_grid` (n <=
    PHASE_ANGLES: a table cut at node n - 1 has density 0 beyond)."""
    j, _ = phase_table_index(nu)
    if j >= cdf.shape[0] - 1:
        return 0.0
    return (cdf[j + 1] - cdf[j]) / (TWO_PI * (cos_grid[j] - cos_grid[j + 1]))


@njit(cache=True)
def region_of(r, radii):
    """Index of the region (radii[i] <= r < radii[i + 1]) that holds the radius r [m]; the
    lowest for r below the ground, the highest for r at or above the top."""
    n = radii.shape[0] - 1
    for i in range(n):
        if r < radii[i + 1]:
            return i
    return n - 1


@njit(cache=True)
def air_extinction(r, w, bottom_radius, air, dens):
    """Extinction coefficient of the air [m^-1] at radius r, its densities into `dens` (n_c,)."""
    h_step, density, extinction = air[0], air[1], air[2]
    density_at(r - bottom_radius, h_step, density, dens)
    be = 0.0
    for c in range(density.shape[0]):
        be += extinction[c, w] * dens[c]
    return be


@njit(cache=True)
def cloud_extinction(layer, w, x, y, z, r, cloud):
    """Extinction coefficient of cloud `layer` [m^-1] at the point (x, y, z), |p| = r:
    k_ext w(p) (`cloud_field.layer_water`)."""
    params, profiles, textures, k_ext = cloud[0], cloud[1], cloud[2], cloud[3]
    return k_ext[layer, w] * layer_water(params, profiles, textures, layer, x, y, z, r)


@njit(cache=True)
def free_flight(ox, oy, oz, dx, dy, dz, w, bottom_radius, air, cloud, regions, dens):
    """(state, x, y, z) after a free flight from o (inside the atmosphere) along d by
    region-wise delta tracking (module doc): SCATTER at a collision, GROUND at the ground
    point, or LEAVE through the top."""
    radii, region_layer, majorant = regions[0], regions[1], regions[2]
    n_region = region_layer.shape[0]
    b = ox * dx + oy * dy + oz * dz
    c = ox * ox + oy * oy + oz * oz
    region = region_of(math.sqrt(c), radii)
    t = 0.0
    while True:
        r_low, r_high = radii[region], radii[region + 1]
        t_exit = -b + math.sqrt(max(b * b - c + r_high * r_high, 0.0))
        down = False
        disc = b * b - c + r_low * r_low
        if disc >= 0.0:
            t_in = -b - math.sqrt(disc)
            if t_in > t:  # the line meets the lower sphere ahead: it leaves downwards
                t_exit = t_in
                down = True
        m = majorant[region, w]
        layer = region_layer[region]
        while m > 0.0:
            t -= math.log(1.0 - np.random.random()) / m
            if t >= t_exit:
                break
            x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
            r = math.sqrt(x * x + y * y + z * z)
            be = air_extinction(r, w, bottom_radius, air, dens)
            if layer >= 0:
                be += cloud_extinction(layer, w, x, y, z, r, cloud)
            if np.random.random() * m < be:
                return SCATTER, x, y, z
        t = t_exit
        if down:
            if region == 0:
                x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
                scale = bottom_radius / math.sqrt(x * x + y * y + z * z)
                return GROUND, x * scale, y * scale, z * scale
            region -= 1
        else:
            if region == n_region - 1:
                return LEAVE, ox, oy, oz
            region += 1


@njit(cache=True)
def _add_interval(lo, hi, layer, out, count):
    """Row (lo, hi, layer) appended to `out` at `count` when hi > lo; the new count."""
    if hi > lo:
        out[count, 0], out[count, 1], out[count, 2] = lo, hi, layer
        count += 1
    return count


@njit(cache=True)
def cloud_intervals(ox, oy, oz, dx, dy, dz, t_low, t_high, params, out):
    """The pieces of [t_low, t_high] where o + t d (d a unit vector) lies in a cloud layer's
    shell (at most two per layer), as rows (t0, t1, layer) of `out` (2 n_layers, 3) sorted by
    t0; returns their number."""
    b = ox * dx + oy * dy + oz * dz
    c = ox * ox + oy * oy + oz * oz
    count = 0
    for layer in range(params.shape[0]):
        top = params[layer, TOP_R]
        disc = b * b - c + top * top
        if disc <= 0.0:
            continue
        root = math.sqrt(disc)
        t_in, t_out = -b - root, -b + root
        base = params[layer, BASE_R]
        disc = b * b - c + base * base
        s_in, s_out = t_out, t_out  # the line misses the inner sphere: one piece
        if disc > 0.0:
            root = math.sqrt(disc)
            s_in, s_out = -b - root, -b + root
        count = _add_interval(max(t_in, t_low), min(s_in, t_high), layer, out, count)
        count = _add_interval(max(s_out, t_low), min(t_out, t_high), layer, out, count)
    for i in range(1, count):  # insertion sort: a handful of rows
        j = i
        while j > 0 and out[j - 1, 0] > out[j, 0]:
            for k in range(3):
                out[j - 1, k], out[j, k] = out[j, k], out[j - 1, k]
            j -= 1
    return count


@njit(cache=True)
def cloud_transmittance(ox, oy, oz, dx, dy, dz, t_low, t_high, w, cloud, cloud_majorant,
                        scratch):
    """Unbiased estimate of the clouds' transmittance [-] along o + t d over [t_low, t_high]
    [m] by ratio tracking (Novák et al. 2014, "Residual ratio tracking for estimating
    attenuation in participating media", ACM TOG 33(6), 179, doi:10.1145/2661229.2661292, §3
    without a control): tentative points at the rate m = k_ext params[layer, WATER] of each
    layer crossed, T = prod (1 - sigma(t_j) / m). Below `RATIO_ROULETTE` Russian roulette
    ends it (T -> 0 with probability 1 - T / RATIO_ROULETTE, else T -> RATIO_ROULETTE)."""
    count = cloud_intervals(ox, oy, oz, dx, dy, dz, t_low, t_high, cloud[0], scratch)
    transmittance = 1.0
    for k in range(count):
        layer = int(scratch[k, 2])
        m = cloud_majorant[layer, w]
        if m <= 0.0:
            continue
        t, t_end = scratch[k, 0], scratch[k, 1]
        while True:
            t -= math.log(1.0 - np.random.random()) / m
            if t >= t_end:
                break
            x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
            r = math.sqrt(x * x + y * y + z * z)
            transmittance *= 1.0 - cloud_extinction(layer, w, x, y, z, r, cloud) / m
            if transmittance < RATIO_ROULETTE:
                if np.random.random() * RATIO_ROULETTE >= transmittance:
                    return 0.0
                transmittance = RATIO_ROULETTE
    return transmittance


@njit(cache=True)
def first_cloud_collision(ox, oy, oz, dx, dy, dz, t_low, t_high, w, cloud, cloud_majorant,
                          scratch):
    """(t [m], layer) of the first collision with a cloud along o + t d in [t_low, t_high],
    drawn with the density sigma_c(t) T_c(t_low, t) by delta tracking against the clouds alone;
    (-1, -1) when the path passes every cloud."""
    count = cloud_intervals(ox, oy, oz, dx, dy, dz, t_low, t_high, cloud[0], scratch)
    for k in range(count):
        layer = int(scratch[k, 2])
        m = cloud_majorant[layer, w]
        if m <= 0.0:
            continue
        t, t_end = scratch[k, 0], scratch[k, 1]
        while True:
            t -= math.log(1.0 - np.random.random()) / m
            if t >= t_end:
                break
            x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
            r = math.sqrt(x * x + y * y + z * z)
            if np.random.random() * m < cloud_extinction(layer, w, x, y, z, r, cloud):
                return t, layer
    return -1.0, -1


@njit(cache=True)
def sun_transmittance(x, y, z, w, sun, air, cloud, regions, light, work):
    """T_air V T_c [-] at the point p: the air's transmittance towards the sun times the
    visible part of its disk (`_monte_carlo_kernels.sun_attenuation`, ray marched) and the
    clouds' (`cloud_transmittance`, unbiased) along the same ray: towards the sun, or, for a
    sun whose centre is below the geometric horizon, along the horizon at its azimuth. The air
    is marched only where T_c > 0."""
    bottom_radius, top_radius, sun_radius, n_sun_samples = light[0], light[1], light[2], light[3]
    r = math.sqrt(x * x + y * y + z * z)
    mu_s = (x * sun[0] + y * sun[1] + z * sun[2]) / r
    if sun_visible_fraction(r, mu_s, bottom_radius, sun_radius) <= 0.0:
        return 0.0
    sx, sy, sz = sun[0], sun[1], sun[2]
    mu_h = horizon_cos_zenith(r, bottom_radius)
    if mu_s < mu_h:  # the visible top of a setting sun: along the horizon
        hx, hy, hz = sx - mu_s * x / r, sy - mu_s * y / r, sz - mu_s * z / r
        norm = math.sqrt(hx * hx + hy * hy + hz * hz)
        sine = math.sqrt(1.0 - mu_h * mu_h)
        sx = mu_h * x / r + sine * hx / norm
        sy = mu_h * y / r + sine * hy / norm
        sz = mu_h * z / r + sine * hz / norm
    clouds = cloud_transmittance(x, y, z, sx, sy, sz, 0.0, math.inf, w, cloud, regions[3],
                                 work[2])
    if clouds <= 0.0:
        return 0.0
    return clouds * sun_attenuation(x, y, z, sun, w, bottom_radius, top_radius, air[0], air[1],
                                    air[2], air[8], sun_radius, n_sun_samples, work[1])


@njit(cache=True)
def mixed_phase(w, nu, dens, bs_cloud, layer, air, cloud):
    """sum_c beta_s,c p_c(nu) [m^-1 sr^-1] over the air constituents (densities `dens`) and the
    cloud `layer` (scattering coefficient `bs_cloud` [m^-1]; none when layer < 0)."""
    scattering, scatterers, phase = air[3], air[4], air[5]
    total = 0.0
    for s in range(scatterers.shape[0]):
        bs = scattering[scatterers[s], w] * dens[scatterers[s]]
        if bs > 0.0:
            total += bs * phase_value(phase[s, w], nu)
    if layer >= 0 and bs_cloud > 0.0:
        total += bs_cloud * cloud_phase(cloud[5][layer, w], nu)
    return total


@njit(cache=True)
def sun_proposal_density(w, nu_sun, guide, cloud):
    """Density [sr^-1] of the sun-centred proposal at nu_sun = cos(angle to the sun):
    sum_l share[l, w] (proposal of layer l's forward peak about the sun)."""
    share, cloud_cdf, cloud_grid = guide[1], guide[2], cloud[7]
    total = 0.0
    for layer in range(share.shape[0]):
        if share[layer, w] > 0.0:
            total += share[layer, w] * cloud_proposal_density(cloud_cdf[layer, w], cloud_grid,
                                                              nu_sun)
    return total


@njit(cache=True)
def sun_centred_direction(w, sun, guide, cloud):
    """A direction drawn from the sun-centred proposal: a layer with probability share[l, w],
    then its forward peak's proposal (the table cut at PEAK_DEG) about the sun direction."""
    share, cloud_cdf, cloud_grid = guide[1], guide[2], cloud[7]
    pick = np.random.random()
    chosen = share.shape[0] - 1
    for layer in range(share.shape[0]):
        pick -= share[layer, w]
        if pick < 0.0:
            chosen = layer
            break
    mu = sample_phase(cloud_cdf[chosen, w], cloud_grid, np.random.random())
    return rotate(sun[0], sun[1], sun[2], mu, TWO_PI * np.random.random())


@njit(cache=True)
def phase_direction(dx, dy, dz, w, bs, dens, bs_cloud, layer, air, cloud):
    """A new direction after a scattering coming along d: a component (air constituent or
    cloud) in proportion to its scattering coefficient (the sum is `bs` [m^-1]), then a
    direction from its phase table's proposal about d."""
    scattering, scatterers, cdf, cos_grid = air[3], air[4], air[6], air[7]
    pick = np.random.random() * bs
    if pick < bs_cloud:
        mu = sample_phase(cloud[6][layer, w], cloud[7], np.random.random())
    else:
        pick -= bs_cloud
        chosen = scatterers.shape[0] - 1
        for s in range(scatterers.shape[0]):
            pick -= scattering[scatterers[s], w] * dens[scatterers[s]]
            if pick < 0.0:
                chosen = s
                break
        mu = sample_phase(cdf[chosen, w], cos_grid, np.random.random())
    return rotate(dx, dy, dz, mu, TWO_PI * np.random.random())


@njit(cache=True)
def scatter_factor(dx, dy, dz, nx, ny, nz, w, bs, dens, bs_cloud, layer, eps, sun, guide, air,
                   cloud):
    """(p / (q + eps q_sun), q_sun) [-, sr^-1] at the new direction d' after a scattering
    coming along d: p = sum_c beta_s,c p_c(d.d') / beta_s, q the density of
    `phase_direction`, q_sun that of `sun_centred_direction` (0 without the proposal)."""
    scattering, scatterers, cdf, cos_grid = air[3], air[4], air[6], air[7]
    nu = dx * nx + dy * ny + dz * nz
    p = mixed_phase(w, nu, dens, bs_cloud, layer, air, cloud)
    q = 0.0
    for s in range(scatterers.shape[0]):
        b = scattering[scatterers[s], w] * dens[scatterers[s]]
        if b > 0.0:
            q += b * proposal_density(cdf[s, w], cos_grid, nu)
    if bs_cloud > 0.0:
        q += bs_cloud * cloud_proposal_density(cloud[6][layer, w], cloud[7], nu)
    q_sun = 0.0
    if guide[0] > 0.0:
        q_sun = sun_proposal_density(w, nx * sun[0] + ny * sun[1] + nz * sun[2], guide, cloud)
    q += eps * bs * q_sun
    return (p / q if q > 0.0 else 0.0), q_sun


@njit(cache=True)
def reflect_factor(nx, ny, nz, x, y, z, w, eps, sun, guide, cloud):
    """(p / (q + eps q_sun), q_sun) [-, sr^-1] at the new direction (x, y, z) after a
    Lambertian reflection at the ground point with normal n: p = q = max(0, n.d') / pi (the
    cosine-distributed proposal), q_sun as `scatter_factor`."""
    cos_normal = nx * x + ny * y + nz * z
    q_sun = 0.0
    if guide[0] > 0.0:
        q_sun = sun_proposal_density(w, x * sun[0] + y * sun[1] + z * sun[2], guide, cloud)
    if cos_normal <= 0.0:
        return 0.0, q_sun
    p = cos_normal / math.pi
    return p / (p + eps * q_sun), q_sun


@njit(cache=True)
def importance_roulette(weight, importance):
    """Russian roulette on the weight times the path's `importance` [-] (`random_walk`): below
    `ROULETTE_WEIGHT` the path ends with probability 1 - weight importance / ROULETTE_WEIGHT,
    else goes on with the weight ROULETTE_WEIGHT / importance; unbiased."""
    effective = weight * importance
    if effective >= ROULETTE_WEIGHT:
        return weight
    if np.random.random() * ROULETTE_WEIGHT >= effective:
        return 0.0
    return ROULETTE_WEIGHT / importance


@njit(cache=True)
def scatter_event(x, y, z, dx, dy, dz, weight, parts, w, sun, air, cloud, regions, light,
                  guide, work):
    """A collision at p coming along d by `parts` (AIR, CLOUD or BOTH: what may scatter
    there): (next-event estimate [sr^-1 per unit sun irradiance], then the path that goes on
    (weight, d', q_sun(d')) and the branch (weight, d', q_sun(d'); weight 0: none)). The
    weight is multiplied by beta_s / beta_e, then by p / (q + eps q_sun) for both
    (`random_walk`), eps = guide[0]."""
    bottom_radius = light[0]
    scattering, scatterers = air[3], air[4]
    dens = work[0]
    r = math.sqrt(x * x + y * y + z * z)
    layer = regions[1][region_of(r, regions[0])]
    be = 0.0
    bs = 0.0
    if parts & AIR:
        be = air_extinction(r, w, bottom_radius, air, dens)
        for s in range(scatterers.shape[0]):
            bs += scattering[scatterers[s], w] * dens[scatterers[s]]
    else:
        dens[:] = 0.0
    bs_cloud = 0.0
    if parts & CLOUD and layer >= 0:
        sigma = cloud_extinction(layer, w, x, y, z, r, cloud)
        be += sigma
        bs_cloud = sigma * cloud[4][layer, w]
        bs += bs_cloud
    if be <= 0.0 or bs <= 0.0:
        return 0.0, 0.0, dx, dy, dz, 0.0, 0.0, dx, dy, dz, 0.0
    weight *= bs / be
    estimate = weight * mixed_phase(w, dx * sun[0] + dy * sun[1] + dz * sun[2], dens,
                                    bs_cloud, layer, air, cloud) / bs
    if estimate > 0.0:
        estimate *= sun_transmittance(x, y, z, w, sun, air, cloud, regions, light, work)
    eps = guide[0]
    nx, ny, nz = phase_direction(dx, dy, dz, w, bs, dens, bs_cloud, layer, air, cloud)
    factor, q_sun = scatter_factor(dx, dy, dz, nx, ny, nz, w, bs, dens, bs_cloud, layer, eps,
                                   sun, guide, air, cloud)
    branch, bx, by, bz, b_sun = 0.0, dx, dy, dz, 0.0
    if eps > 0.0 and np.random.random() < eps:
        bx, by, bz = sun_centred_direction(w, sun, guide, cloud)
        branch, b_sun = scatter_factor(dx, dy, dz, bx, by, bz, w, bs, dens, bs_cloud, layer,
                                       eps, sun, guide, air, cloud)
    return estimate, weight * factor, nx, ny, nz, q_sun, weight * branch, bx, by, bz, b_sun


@njit(cache=True)
def ground_event(x, y, z, weight, w, sun, air, cloud, regions, light, guide, work):
    """A Lambertian reflection at the ground point p (`profile.ground_albedo`): (next-event
    estimate weight albedo / pi mu_s T_air V T_c, then the path and the branch as
    `scatter_event`, their weights times the albedo)."""
    bottom_radius, albedo = light[0], light[4][w]
    nx, ny, nz = x / bottom_radius, y / bottom_radius, z / bottom_radius
    mu_s = nx * sun[0] + ny * sun[1] + nz * sun[2]
    estimate = 0.0
    if mu_s > 0.0 and albedo > 0.0:
        estimate = weight * albedo / math.pi * mu_s * sun_transmittance(
            x, y, z, w, sun, air, cloud, regions, light, work)
    weight *= albedo
    eps = guide[0]
    dx, dy, dz = rotate(nx, ny, nz, math.sqrt(np.random.random()), TWO_PI * np.random.random())
    factor, q_sun = reflect_factor(nx, ny, nz, dx, dy, dz, w, eps, sun, guide, cloud)
    branch, bx, by, bz, b_sun = 0.0, dx, dy, dz, 0.0
    if eps > 0.0 and np.random.random() < eps:
        bx, by, bz = sun_centred_direction(w, sun, guide, cloud)
        branch, b_sun = reflect_factor(nx, ny, nz, bx, by, bz, w, eps, sun, guide, cloud)
    return (estimate, weight * factor, dx, dy, dz, q_sun, weight * branch, bx, by, bz, b_sun)


@njit(cache=True)
def push(stack, stacked, x, y, z, dx, dy, dz, weight, order):
    """Put a path on `stack` at `stacked` (the caller checks for room); the new count."""
    stack[stacked, 0], stack[stacked, 1], stack[stacked, 2] = x, y, z
    stack[stacked, 3], stack[stacked, 4], stack[stacked, 5] = dx, dy, dz
    stack[stacked, 6], stack[stacked, 7] = weight, order
    return stacked + 1


@njit(cache=True)
def random_walk(x, y, z, dx, dy, dz, weight, state, parts, w, sun, settings, air, cloud,
                regions, light, guide, work):
    """Sum of the next-event estimates towards the sun [sr^-1, per unit sun irradiance] of a
    path that starts at p in `state`, and of its branches and copies:
    SCATTER  a collision at p, coming along d, by `parts` (AIR, CLOUD or BOTH: what may scatter
             there); `weight` is the path weight before the single-scattering albedo;
    GROUND   at the ground point p, reached along d, with `weight`.
    `settings` = (max_orders, rr_start); `light` = (bottom and top radius [m], sun angular
    radius [rad], sun samples, ground albedo (n_wl,), sun irradiance (n_wl,)); `guide` = (eps,
    the layers' shares (n_layers, n_wl) and their forward peaks' cumulative proposal masses
    (n_layers, n_wl, n_peak) in the sun-centred proposal); `work` = scratch arrays (densities,
    columns, intervals, stack of waiting paths (STACK_SIZE, 8)).

    Sun-centred branches (`cloud_monte_carlo` module doc): after each event the path goes on
    in a direction drawn from its phase function (density q) and, with probability eps, a
    branch starts in a direction drawn from the sun-centred proposal (density q_sun); both
    weights are multiplied by p / (q + eps q_sun), the balance heuristic of multiple importance
    sampling for these expected sample counts (Veach & Guibas 1995, SIGGRAPH, 419,
    doi:10.1145/218380.218498), so the sum is unbiased and no weight grows. A branch runs
    first (the path waits on the stack) and branches in turn. Then each path has the
    importance J = max(1, 4 pi eps q_sun(d')) [-] (heading into the sun's forward peak its
    next estimate is up to p(0) / (1 / 4 pi) times the average), plays `importance_roulette`
    from order rr_start on, and splits into n = min(floor(weight / SPLIT_WEIGHT) + 1, free
    places + 1) copies of weight / n when heavier than SPLIT_WEIGHT."""
    max_orders, rr_start = settings
    stack = work[3]
    importance_scale = 2.0 * TWO_PI * guide[0]
    result = 0.0
    order = 0
    stacked = 0
    while True:
        if state == FLIGHT:
            state, x, y, z = free_flight(x, y, z, dx, dy, dz, w, light[0], air, cloud, regions,
                                         work[0])
            parts = BOTH
        else:
            if state == SCATTER:
                (estimate, weight, dx, dy, dz, q_sun, branch, bx, by, bz,
                 b_sun) = scatter_event(x, y, z, dx, dy, dz, weight, parts, w, sun, air,
                                        cloud, regions, light, guide, work)
            else:
                (estimate, weight, dx, dy, dz, q_sun, branch, bx, by, bz,
                 b_sun) = ground_event(x, y, z, weight, w, sun, air, cloud, regions, light,
                                       guide, work)
            result += estimate
            order += 1
            if order >= max_orders:
                weight = branch = 0.0
            if order >= rr_start:
                if weight > 0.0:
                    weight = importance_roulette(weight, max(1.0, importance_scale * q_sun))
                if branch > 0.0:
                    branch = importance_roulette(branch, max(1.0, importance_scale * b_sun))
            if branch > 0.0:  # the branch goes first, the path waits on the stack
                if weight <= 0.0:
                    dx, dy, dz, weight = bx, by, bz, branch
                elif stacked < stack.shape[0]:
                    stacked = push(stack, stacked, x, y, z, dx, dy, dz, weight, order)
                    dx, dy, dz, weight = bx, by, bz, branch
                elif np.random.random() < 0.5:  # no room: one of the two at double weight
                    dx, dy, dz, weight = bx, by, bz, 2.0 * branch
                else:
                    weight *= 2.0
            state = FLIGHT if weight > 0.0 else LEAVE
            if weight > SPLIT_WEIGHT:
                copies = min(int(weight / SPLIT_WEIGHT) + 1, stack.shape[0] - stacked + 1)
                weight /= copies
                for _ in range(copies - 1):
                    stacked = push(stack, stacked, x, y, z, dx, dy, dz, weight, order)
        if state == LEAVE:
            if stacked == 0:
                return result
            stacked -= 1
            x, y, z = stack[stacked, 0], stack[stacked, 1], stack[stacked, 2]
            dx, dy, dz = stack[stacked, 3], stack[stacked, 4], stack[stacked, 5]
            weight, order = stack[stacked, 6], int(stack[stacked, 7])
            state = FLIGHT


@njit(cache=True)
def view_transmittance(n, t_nodes, tau, t):
    """T [-] of the air from the start of a view ray to the distance t [m], linear in optical
    depth between its n nodes (`_monte_carlo_kernels.view_ray_nodes`); 1 without nodes."""
    if n < 2:
        return 1.0
    k = min(max(np.searchsorted(t_nodes[:n], t, side="right") - 1, 0), n - 2)
    f = min(1.0, max(0.0, (t - t_nodes[k]) / (t_nodes[k + 1] - t_nodes[k])))
    return math.exp(-(tau[k] + f * (tau[k + 1] - tau[k])))


@njit(parallel=True, cache=True)
def trace_rays(origins, directions, ray_offset, sun, counts, seed, settings, air, cloud,
               regions, light, guide, nodes, first):
    """Sums and sums of squares (n_ray, n_wl, n_batch) of the path estimates [W m^-2 sr^-1
    nm^-1]: `counts` = (paths per ray and wavelength, paths per batch); `nodes` and `first`
    are what `_monte_carlo_kernels.view_ray_nodes` and `first_collision_tables` return for
    these rays and the air. Each path sums three branches (`cloud_monte_carlo` module doc):
    a collision with the air drawn from the air's first-collision table, seen through the
    clouds (ratio tracking); a collision with a cloud drawn by delta tracking through the
    clouds alone, seen through the air; and, when the view ray meets the ground, the ground
    seen through both. The work unit (ray i, wavelength w, batch b) is seeded from seed and
    ((ray_offset + i) n_wl + w) n_batch + b (unique below 2^32 units, 7919 being odd): the
    numbers of the k-th ray depend on k and the seed, not on the other rays nor the threads.
    Units are handed out ray by ray in turn, so that each thread gets cloudy and clear rays."""
    n_paths, batch = counts
    n_ray = origins.shape[0]
    n_c, n_wl = air[2].shape
    n_batch = (n_paths + batch - 1) // batch
    sums = np.zeros((n_ray, n_wl, n_batch))
    squares = np.zeros((n_ray, n_wl, n_batch))
    bottom_radius, top_radius, sun_irradiance = light[0], light[1], light[5]
    cloud_majorant = regions[3]
    count, hits, t_nodes = nodes[0], nodes[1], nodes[2]
    in_air_all, tau_all, cdf_all = first
    for unit in prange(n_ray * n_wl * n_batch):
        i = unit % n_ray
        w = (unit // n_ray) % n_wl
        b = unit // (n_ray * n_wl)
        index = ((ray_offset + i) * n_wl + w) * n_batch + b
        np.random.seed((seed * 1_000_003 + index * 7_919 + 12_345) % 4_294_967_296)
        work = (np.empty(n_c), np.empty(n_c), np.empty((2 * cloud[0].shape[0], 3)),
                np.empty((STACK_SIZE, 8)))
        scratch = work[2]
        n = count[i]
        tau = tau_all[i, w]
        ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        r0 = math.sqrt(ox * ox + oy * oy + oz * oz)
        t_start, t_end, _ = atmosphere_segment(r0, (ox * dx + oy * dy + oz * dz) / r0,
                                               bottom_radius, top_radius)
        t_ground = t_nodes[i, n - 1] if n > 0 else t_nodes[i, 0]
        total = 0.0
        total_sq = 0.0
        for _ in range(b * batch, min(n_paths, (b + 1) * batch)):
            value = 0.0
            if in_air_all[i, w]:
                t, transmittance, inverse_pdf = first_collision(n, cdf_all[i, w], tau,
                                                                t_nodes[i], np.random.random())
                clouds = cloud_transmittance(ox, oy, oz, dx, dy, dz, 0.0, t, w, cloud,
                                             cloud_majorant, scratch)
                if clouds > 0.0:
                    x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
                    be = air_extinction(math.sqrt(x * x + y * y + z * z), w, bottom_radius,
                                        air, work[0])
                    value += random_walk(x, y, z, dx, dy, dz,
                                         clouds * transmittance * be * inverse_pdf, SCATTER,
                                         AIR, w, sun, settings, air, cloud, regions, light,
                                         guide, work)
            if n > 0 and t_end > t_start:
                t, layer = first_cloud_collision(ox, oy, oz, dx, dy, dz, t_start, t_end, w,
                                                 cloud, cloud_majorant, scratch)
                if layer >= 0:
                    value += random_walk(ox + t * dx, oy + t * dy, oz + t * dz, dx, dy, dz,
                                         view_transmittance(n, t_nodes[i], tau, t), SCATTER,
                                         CLOUD, w, sun, settings, air, cloud, regions, light,
                                         guide, work)
            if hits[i]:
                clouds = cloud_transmittance(ox, oy, oz, dx, dy, dz, 0.0, t_ground, w, cloud,
                                             cloud_majorant, scratch)
                if clouds > 0.0:
                    gx, gy, gz = ox + t_ground * dx, oy + t_ground * dy, oz + t_ground * dz
                    scale = bottom_radius / math.sqrt(gx * gx + gy * gy + gz * gz)
                    value += random_walk(gx * scale, gy * scale, gz * scale, dx, dy, dz,
                                         clouds * (math.exp(-tau[n - 1]) if n > 0 else 1.0),
                                         GROUND, BOTH, w, sun, settings, air, cloud, regions,
                                         light, guide, work)
            value *= sun_irradiance[w]
            total += value
            total_sq += value * value
        sums[i, w, b] = total
        squares[i, w, b] = total_sq
    return sums, squares
