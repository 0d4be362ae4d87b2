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
- New directions after a scattering or a ground reflection come from a mixture (detector
  directional importance sampling, Buras & Mayer 2011, doi:10.1016/j.jqsrt.2010.10.005): with
  probability 1 - eps the path's own proposal, with probability eps the sun-centred proposal,
  sum_c sun_share[c, w] (proposal of p_c about the sun direction s). The weight factor is
  p / q with q the density of the whole mixture at the new direction, evaluated for both parts
  (`proposal_density`), so the estimate is unbiased for any eps < 1.
- Random numbers: numba's per-thread Mersenne Twister, re-seeded at the start of every work unit
  (one ray, one wavelength, one batch of paths) with a seed derived from (seed, unit). Within a
  unit the draws are sequential, so results do not depend on the number of threads or on which
  thread runs which unit.
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
)
from skyscatter.transport.geometry import (
    distance_to_sphere,
    horizon_cos_zenith,
    sun_visible_fraction,
)

TWO_PI = 2.0 * math.pi
# The view ray's and the sun's intervals hold at most this optical depth (`interval_splits`),
# cut into at most this many parts each: the trapezoid rule and the first collision's
# transmittance, linear in optical depth inside an interval, misjudge a layer's edges.
INTERVAL_DEPTH = 0.05
MAX_INTERVAL_SPLITS = 64
ROULETTE_SHARE = 0.1  # Russian roulette below this share of a path's starting weight
# `aureole_estimate` runs wherever the forward-scattered beam T' - T is at least this share of
# the sun's light, and with probability (T' - T) / AUREOLE_SHARE where it is weaker.
AUREOLE_SHARE = 0.01
# eps of the aureole walk's own directions (`aureole_light`): half of them about the sun, so
# that a walk that has strayed a few degrees from it finds the peak towards it again.
AUREOLE_SUN_SAMPLING = 0.5
# States of a path in `random_walk`.
FLIGHT, SCATTER, GROUND, LEAVE = 0, 1, 2, 3


@njit(cache=True)
def phase_cdf(phase):
    """Cumulative proposal masses (n_s, n_wl, n_angle) from phase tables (n_s, n_wl, n_angle)
    [sr^-1] sampled at theta_i = pi i / (n_angle - 1); see the module doc."""
    n_angle = phase.shape[2]
    cos_grid = np.empty(n_angle)
    for i in range(n_angle):
        cos_grid[i] = math.cos(math.pi * i / (n_angle - 1))
    return tabulated_phase_cdf(phase, cos_grid)


@njit(cache=True)
def tabulated_phase_cdf(phase, cos_grid):
    """Cumulative proposal masses (n_t, n_wl, n) of phase tables (n_t, n_wl, n) [sr^-1] on the
    nodes cos_grid = cos(theta_i) (n,), theta increasing: the mass of interval i is
    2 pi (p_i + p_i+1) / 2 (cos theta_i - cos theta_i+1), normalised to 1 (uniform in cos(theta)
    where a table is zero)."""
    n_t, n_wl, n = phase.shape
    cdf = np.zeros((n_t, n_wl, n))
    for s in range(n_t):
        for w in range(n_wl):
            total = 0.0
            for i in range(n - 1):
                total += TWO_PI * 0.5 * (phase[s, w, i] + phase[s, w, i + 1]) * (
                    cos_grid[i] - cos_grid[i + 1])
                cdf[s, w, i + 1] = total
            for i in range(n):
                cdf[s, w, i] = (cdf[s, w, i] / total if total > 0.0
                                else 0.5 * (1.0 - cos_grid[i]))
    return cdf


@njit(cache=True)
def angle_interval(n_angle, nu):
    """(k, f): nu = cos(theta) lies in the table interval [theta_k, theta_k+1], at the fraction
    f of it (theta_i = pi i / (n_angle - 1))."""
    x = math.acos(min(1.0, max(-1.0, nu))) * (n_angle - 1) / math.pi
    k = min(int(x), n_angle - 2)
    return k, x - k


@njit(cache=True)
def phase_value(table, nu):
    """Tabulated phase function (n_angle,) [sr^-1] at nu = cos(theta), linear in theta."""
    k, f = angle_interval(table.shape[0], nu)
    return table[k] * (1.0 - f) + table[k + 1] * f


@njit(cache=True)
def proposal_density(cdf, cos_grid, nu):
    """Density [sr^-1] at nu = cos(theta) of the directions that `sample_phase` draws from the
    cumulative masses `cdf` (n_angle,): the mass of nu's interval over its solid angle."""
    k, _ = angle_interval(cdf.shape[0], nu)
    return (cdf[k + 1] - cdf[k]) / (TWO_PI * (cos_grid[k] - cos_grid[k + 1]))


@njit(cache=True)
def pick_interval(cdf, n, u):
    """(k, mass): the interval [k, k+1] of the cumulative probabilities cdf[:n] that holds the
    uniform number u, and its probability (> 0 unless every interval is empty)."""
    k = np.searchsorted(cdf[:n], u, side="right") - 1
    k = min(max(k, 0), n - 2)
    mass = cdf[k + 1] - cdf[k]
    while mass <= 0.0 and k < n - 2:  # u on a flat stretch (rounding): move on
        k += 1
        mass = cdf[k + 1] - cdf[k]
    return k, mass


@njit(cache=True)
def sample_phase(cdf, cos_grid, u):
    """mu drawn with uniform u from the cumulative masses `cdf` (n_angle,) over the nodes
    cos_grid = cos(theta_i); its density is `proposal_density`."""
    k, mass = pick_interval(cdf, cdf.shape[0], u)
    f = min(1.0, max(0.0, (u - cdf[k]) / mass)) if mass > 0.0 else 0.5
    return cos_grid[k] + f * (cos_grid[k + 1] - cos_grid[k])


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
def refined_columns(r, mu, t_end, n_samples, bottom_radius, h_step, density, extinction_maxima,
                    out):
    """Column densities [density x m] of each constituent along the ray (r, mu) from 0 to
    t_end, into out (n_c,): the nodes of `_kernels.columns_along_segment` (dense at the lowest
    point), each interval cut into `altitude_splits` equal parts, trapezoid rule on each. With
    128 nodes alone the sun's columns from inside a deck of optical depth 20 crossed its top
    edge in intervals of 30-50 m: T_sun 5-13 % too small there."""
    n_c = density.shape[0]
    for c in range(n_c):
        out[c] = 0.0
    if t_end <= 0.0:
        return
    t_split, m1, m2 = split_sample_count(r, mu, 0.0, t_end, n_samples)
    total = sample_total(m1, m2, n_samples)
    previous = np.empty(n_c)
    current = np.empty(n_c)
    z_previous = r - bottom_radius
    density_at(z_previous, h_step, density, previous)
    t_previous = 0.0
    for j in range(1, total):
        t = sample_distance(j, r, mu, 0.0, t_end, n_samples, t_split, m1, m2)
        z = radius_along(r, mu, t) - bottom_radius
        parts = altitude_splits(z_previous, z, t - t_previous, h_step, extinction_maxima)
        step = (t - t_previous) / parts
        for k in range(1, parts + 1):
            height = z if k == parts else radius_along(r, mu, t_previous + step * k) - bottom_radius
            density_at(height, h_step, density, current)
            for c in range(n_c):
                out[c] += 0.5 * (previous[c] + current[c]) * step
                previous[c] = current[c]
        t_previous = t
        z_previous = z


@njit(cache=True)
def sun_columns(px, py, pz, sun, bottom_radius, top_radius, h_step, density, extinction_maxima,
                sun_angular_radius, n_sun_samples, column):
    """Visible part of the sun disk V [-] at the point p (`geometry.sun_visible_fraction`; a
    point sun when the radius is 0), with the column densities towards the sun to the top of
    the atmosphere in `column` (n_c,), ray marched (`refined_columns`; `extinction_maxima`
    as `extinction_maxima` returns). As in the other solvers a sun below the horizon is
    attenuated like the horizon ray. Returns 0 (and leaves `column` alone) where the sun is
    hidden."""
    r = math.sqrt(px * px + py * py + pz * pz)
    mu_s = (px * sun[0] + py * sun[1] + pz * sun[2]) / r
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible <= 0.0:
        return 0.0
    r = min(r, top_radius)
    mu = max(mu_s, horizon_cos_zenith(r, bottom_radius))
    t_top = distance_to_sphere(r, mu, top_radius, True)
    refined_columns(r, mu, t_top, n_sun_samples, bottom_radius, h_step, density,
                    extinction_maxima, column)
    return visible


@njit(cache=True)
def optical_depth(extinction, w, column):
    """sum_c extinction[c, w] column[c] [-]."""
    tau = 0.0
    for c in range(column.shape[0]):
        tau += extinction[c, w] * column[c]
    return tau


@njit(cache=True)
def sun_attenuation(px, py, pz, sun, w, bottom_radius, top_radius, h_step, density,
                    extinction, extinction_maxima, sun_angular_radius, n_sun_samples, column):
    """T_sun V at the point p [-]: transmittance to the top of the atmosphere towards the sun
    times the visible part of its disk (`sun_columns`)."""
    visible = sun_columns(px, py, pz, sun, bottom_radius, top_radius, h_step, density,
                          extinction_maxima, sun_angular_radius, n_sun_samples, column)
    if visible <= 0.0:
        return 0.0
    return math.exp(-optical_depth(extinction, w, column)) * visible


@njit(cache=True)
def roulette(weight, floor):
    """Russian roulette below `floor`: the path ends with probability 1 - weight / floor, else
    goes on with the weight `floor`; unbiased. Weights above the floor are kept, so paths
    through conservative, optically thick layers live until they leave them (a survival
    capped below 1 would let the few long paths that reach a deck's sunlit top carry
    exponentially growing weights: a heavy-tailed estimator)."""
    if weight >= floor:
        return weight
    if np.random.random() * floor >= weight:
        return 0.0
    return floor


@njit(cache=True)
def mixed_phase(w, nu, dens, scattering, scatterers, phase):
    """sum_c beta_s,c p_c(nu) [m^-1 sr^-1] at the densities `dens`."""
    total = 0.0
    for s in range(scatterers.shape[0]):
        total += scattering[scatterers[s], w] * dens[scatterers[s]] * phase_value(phase[s, w], nu)
    return total


@njit(cache=True)
def pick_row(shares, u):
    """Index of the row that holds the uniform number u in [0, sum(shares)) [-]."""
    n = shares.shape[0]
    for s in range(n):
        u -= shares[s]
        if u < 0.0:
            return s
    return n - 1


@njit(cache=True)
def sun_proposal_density(w, nu_sun, sun_share, cdf, cos_grid):
    """Density [sr^-1] of the sun-centred proposal (module doc) at nu_sun = cos(angle to the
    sun): sum_c sun_share[c, w] (proposal of p_c around the sun)."""
    total = 0.0
    for s in range(sun_share.shape[0]):
        if sun_share[s, w] > 0.0:
            total += sun_share[s, w] * proposal_density(cdf[s, w], cos_grid, nu_sun)
    return total


@njit(cache=True)
def sun_centred_direction(w, sun, sun_share, cdf, cos_grid):
    """A direction drawn from the sun-centred proposal: a constituent with probability
    sun_share[c, w], then its phase-function proposal about the sun direction."""
    chosen = pick_row(sun_share[:, w], np.random.random())
    mu = sample_phase(cdf[chosen, w], cos_grid, np.random.random())
    return rotate(sun[0], sun[1], sun[2], mu, TWO_PI * np.random.random())


@njit(cache=True)
def scatter_direction(dx, dy, dz, w, bs, dens, scattering, scatterers, phase, cdf, cos_grid,
                      sun, sun_share, sun_probability):
    """(new direction d', weight factor p / q) after a scattering in the air, coming along d.
    Detector directional importance sampling (Buras & Mayer 2011, §3.2; module doc): with
    probability 1 - eps (eps = `sun_probability`) a constituent in proportion to its
    scattering coefficient (sum `bs` [m^-1]) and its phase-function proposal about d, with
    probability eps the sun-centred proposal; p = sum_c beta_s,c p_c(d.d') / beta_s and q the
    density of the whole mixture at d', so the estimate stays unbiased."""
    n_s = scatterers.shape[0]
    if np.random.random() < sun_probability:
        nx, ny, nz = sun_centred_direction(w, sun, sun_share, cdf, cos_grid)
    else:
        pick = np.random.random() * bs
        chosen = n_s - 1
        for s in range(n_s):
            pick -= scattering[scatterers[s], w] * dens[scatterers[s]]
            if pick < 0.0:
                chosen = s
                break
        mu = sample_phase(cdf[chosen, w], cos_grid, np.random.random())
        nx, ny, nz = rotate(dx, dy, dz, mu, TWO_PI * np.random.random())
    nu = dx * nx + dy * ny + dz * nz
    p = mixed_phase(w, nu, dens, scattering, scatterers, phase) / bs
    q = 0.0
    for s in range(n_s):
        q += (scattering[scatterers[s], w] * dens[scatterers[s]]
              * proposal_density(cdf[s, w], cos_grid, nu))
    q *= (1.0 - sun_probability) / bs
    if sun_probability > 0.0:
        nu_sun = sun[0] * nx + sun[1] * ny + sun[2] * nz
        q += sun_probability * sun_proposal_density(w, nu_sun, sun_share, cdf, cos_grid)
    return nx, ny, nz, (p / q if q > 0.0 else 0.0)


@njit(cache=True)
def reflect_direction(nx, ny, nz, w, sun, sun_share, cdf, cos_grid, sun_probability):
    """(new direction d', weight factor p / q) after a Lambertian reflection at the ground
    point with normal n: with probability 1 - eps cosine-distributed about n, with probability
    eps the sun-centred proposal (as `scatter_direction`); p = max(0, n.d') / pi and q the
    mixture's density at d' (a direction into the ground gets the factor 0)."""
    if np.random.random() < sun_probability:
        x, y, z = sun_centred_direction(w, sun, sun_share, cdf, cos_grid)
    else:
        x, y, z = rotate(nx, ny, nz, math.sqrt(np.random.random()),
                         TWO_PI * np.random.random())
    cos_normal = nx * x + ny * y + nz * z
    if cos_normal <= 0.0:
        return x, y, z, 0.0
    p = cos_normal / math.pi
    q = (1.0 - sun_probability) * p
    if sun_probability > 0.0:
        q += sun_probability * sun_proposal_density(
            w, sun[0] * x + sun[1] * y + sun[2] * z, sun_share, cdf, cos_grid)
    return x, y, z, p / q


@njit(cache=True)
def free_flight(ox, oy, oz, dx, dy, dz, w, bottom_radius, top_radius, h_step, density,
                extinction, majorant, dens):
    """(state, point) after a free flight from o along d by delta tracking (module doc):
    SCATTER and the collision point, GROUND and the ground point, or LEAVE."""
    n_c = density.shape[0]
    _, _, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz, bottom_radius,
                                                    top_radius)
    if t_end <= t_start and not hits_ground:
        return LEAVE, ox, oy, oz  # misses the atmosphere
    t = t_start
    while majorant[w] > 0.0:
        t -= math.log(1.0 - np.random.random()) / majorant[w]
        if t >= t_end:
            break
        px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
        density_at(math.sqrt(px * px + py * py + pz * pz) - bottom_radius, h_step, density,
                   dens)
        be = 0.0
        for c in range(n_c):
            be += extinction[c, w] * dens[c]
        if np.random.random() * majorant[w] < be:
            return SCATTER, px, py, pz
    if not hits_ground:
        return LEAVE, ox, oy, oz
    gx, gy, gz = ox + t_end * dx, oy + t_end * dy, oz + t_end * dz
    scale = bottom_radius / math.sqrt(gx * gx + gy * gy + gz * gz)
    return GROUND, gx * scale, gy * scale, gz * scale


@njit(cache=True)
def scattering_coefficient(w, dens, scattering, scatterers):
    """beta_s [m^-1]: sum_c beta_s,c at the densities `dens`."""
    total = 0.0
    for s in range(scatterers.shape[0]):
        total += scattering[scatterers[s], w] * dens[scatterers[s]]
    return total


@njit(cache=True)
def aureole_share(attenuation, w, peak_scattering, column):
    """T' - T [-] at a point whose sun columns are `column` and T_sun V = `attenuation`: the
    sunlight that delta-M scaling counts as still direct there (the forward-scattered beam,
    T' = T exp(tau_peak)), the size of what `aureole_light` estimates."""
    return attenuation * math.expm1(optical_depth(peak_scattering, w, column))


@njit(cache=True)
def aureole_light(ox, oy, oz, dx, dy, dz, root_phase, w, sun, max_orders, bottom_radius,
                  top_radius, h_step, density, extinction, extinction_maxima, scattering,
                  scatterers, phase, cdf, cos_grid, majorant, sun_angular_radius, n_sun_samples,
                  sun_share, peak, scratch):
    """Sunlight [sr^-1 per unit sun irradiance] that reaches o after one or more scatterings in
    the forward peaks only, weighted by the smooth scattering at o (module doc of
    `transport/monte_carlo.py`): a direction w1 from the sun-centred proposal, weight
    root(w1) / q(w1) with `root_phase` = 0 for a collision (its smooth phase function,
    sum_c beta_s,c p*_c / beta_s at the densities in `scratch[2]`, coming along d) or 1 for
    the ground (albedo folded in by the caller: mu / pi); then a walk whose every scattering
    is a peak event: next-event estimates with the peak phase function, directions from the
    whole phase function weighted by peak / whole. The ground ends the walk (not a peak)."""
    dens = scratch[0]
    column = scratch[1]
    nx, ny, nz = sun_centred_direction(w, sun, sun_share, cdf, cos_grid)
    q = sun_proposal_density(w, sun[0] * nx + sun[1] * ny + sun[2] * nz, sun_share, cdf,
                             cos_grid)
    if q <= 0.0:
        return 0.0
    if root_phase == 0:
        root = scratch[2]
        nu = dx * nx + dy * ny + dz * nz
        bs = scattering_coefficient(w, root, scattering, scatterers)
        value = (mixed_phase(w, nu, root, scattering, scatterers, phase)
                 - mixed_phase(w, nu, root, scattering, scatterers, peak)) / bs
    else:
        r = math.sqrt(ox * ox + oy * oy + oz * oz)
        value = max(0.0, (ox * nx + oy * ny + oz * nz) / r) / math.pi
    weight = value / q
    result = 0.0
    for _ in range(max_orders):
        if weight <= 0.0:
            return result
        state, ox, oy, oz = free_flight(ox, oy, oz, nx, ny, nz, w, bottom_radius, top_radius,
                                        h_step, density, extinction, majorant, dens)
        if state != SCATTER:
            return result  # the ground does not scatter in a peak
        be = optical_depth(extinction, w, dens)  # sum_c beta_e,c n_c [m^-1]
        bs = scattering_coefficient(w, dens, scattering, scatterers)
        if be <= 0.0 or bs <= 0.0:
            return result
        weight *= bs / be
        attenuation = sun_attenuation(ox, oy, oz, sun, w, bottom_radius, top_radius, h_step,
                                      density, extinction, extinction_maxima,
                                      sun_angular_radius, n_sun_samples, column)
        if attenuation > 0.0:
            nu_sun = nx * sun[0] + ny * sun[1] + nz * sun[2]
            result += (weight * mixed_phase(w, nu_sun, dens, scattering, scatterers, peak) / bs
                       * attenuation)
        mx, my, mz, factor = scatter_direction(nx, ny, nz, w, bs, dens, scattering, scatterers,
                                               phase, cdf, cos_grid, sun, sun_share,
                                               AUREOLE_SUN_SAMPLING)
        nu = nx * mx + ny * my + nz * mz
        whole = mixed_phase(w, nu, dens, scattering, scatterers, phase)
        weight *= factor * (mixed_phase(w, nu, dens, scattering, scatterers, peak) / whole
                            if whole > 0.0 else 0.0)
        nx, ny, nz = mx, my, mz
    return result


@njit(cache=True)
def aureole_estimate(ox, oy, oz, dx, dy, dz, root_phase, attenuation, w, sun, max_orders,
                     bottom_radius, top_radius, h_step, density, extinction, extinction_maxima,
                     scattering, scatterers, phase, cdf, cos_grid, majorant, sun_angular_radius,
                     n_sun_samples, sun_share, peak, peak_scattering, column, scratch):
    """`aureole_light` at o with at most `max_orders` peak scatterings, run with probability
    r = min(1, (T' - T) / AUREOLE_SHARE) and divided by r (unbiased): where the
    forward-scattered beam is weak (clear air, deep in a thick layer) it is rarely run.
    `column` holds the sun columns at o, `attenuation` its T_sun V."""
    if attenuation <= 0.0 or max_orders <= 0:
        return 0.0
    share = aureole_share(attenuation, w, peak_scattering, column)
    if share <= 0.0:
        return 0.0
    chance = min(1.0, share / AUREOLE_SHARE)
    if np.random.random() >= chance:
        return 0.0
    return aureole_light(ox, oy, oz, dx, dy, dz, root_phase, w, sun, max_orders, bottom_radius,
                         top_radius, h_step, density, extinction, extinction_maxima, scattering,
                         scatterers, phase, cdf, cos_grid, majorant, sun_angular_radius,
                         n_sun_samples, sun_share, peak, scratch) / chance


@njit(cache=True)
def random_walk(ox, oy, oz, dx, dy, dz, weight, state, w, sun, max_orders, rr_start,
                bottom_radius, top_radius, h_step, density, extinction, extinction_maxima,
                scattering, scatterers, phase, cdf, cos_grid, majorant, albedo,
                sun_angular_radius, n_sun_samples, sun_share, sun_probability, peak,
                peak_scattering, dens, column, scratch):
    """Sum of the next-event estimates towards the sun [sr^-1, per unit sun irradiance] of a
    path that starts at o in `state`:
    SCATTER  a collision in the air at o, coming along d; `weight` is the path weight before
             the single-scattering albedo (for a collision drawn with density beta_e T: 1);
    GROUND   at the ground point o, reached along d, with `weight`;
    FLIGHT   flying from o along d, with `weight`.
    Forward peaks (`peak`, `peak_scattering`; module doc of `transport/monte_carlo.py`): once
    the path has scattered smoothly (a ground reflection, or a scattering labelled smooth with
    probability p* / p), its next-event estimates leave out the peak, and every event adds the
    `aureole_estimate` instead."""
    n_c = density.shape[0]
    peaked = False
    for c in range(n_c):
        peaked = peaked or peak_scattering[c, w] > 0.0
    smooth = False
    floor = ROULETTE_SHARE * weight
    result = 0.0
    order = 0
    while True:
        if state == FLIGHT:
            state, ox, oy, oz = free_flight(ox, oy, oz, dx, dy, dz, w, bottom_radius,
                                            top_radius, h_step, density, extinction, majorant,
                                            dens)
            if state == LEAVE:
                return result
            continue
        if state == SCATTER:
            density_at(math.sqrt(ox * ox + oy * oy + oz * oz) - bottom_radius, h_step, density,
                       dens)
            be = 0.0
            for c in range(n_c):
                be += extinction[c, w] * dens[c]
            bs = scattering_coefficient(w, dens, scattering, scatterers)
            if be <= 0.0 or bs <= 0.0:
                return result
            weight *= bs / be
            attenuation = sun_attenuation(ox, oy, oz, sun, w, bottom_radius, top_radius,
                                          h_step, density, extinction, extinction_maxima,
                                          sun_angular_radius, n_sun_samples, column)
            if attenuation > 0.0:
                nu_sun = dx * sun[0] + dy * sun[1] + dz * sun[2]
                p_sun = mixed_phase(w, nu_sun, dens, scattering, scatterers, phase)
                if smooth:
                    p_sun -= mixed_phase(w, nu_sun, dens, scattering, scatterers, peak)
                result += weight * p_sun / bs * attenuation
            if peaked:
                for c in range(n_c):
                    scratch[2, c] = dens[c]
                result += weight * aureole_estimate(
                    ox, oy, oz, dx, dy, dz, 0, attenuation, w, sun, max_orders - order - 1,
                    bottom_radius, top_radius, h_step, density, extinction, extinction_maxima,
                    scattering, scatterers, phase, cdf, cos_grid, majorant, sun_angular_radius,
                    n_sun_samples, sun_share, peak, peak_scattering, column, scratch)
            order += 1
            if order >= max_orders:
                return result
            if order >= rr_start:
                weight = roulette(weight, floor)
                if weight == 0.0:
                    return result
            nx, ny, nz, factor = scatter_direction(dx, dy, dz, w, bs, dens, scattering,
                                                   scatterers, phase, cdf, cos_grid, sun,
                                                   sun_share, sun_probability)
            if peaked and not smooth:
                nu = dx * nx + dy * ny + dz * nz
                whole = mixed_phase(w, nu, dens, scattering, scatterers, phase)
                in_peak = mixed_phase(w, nu, dens, scattering, scatterers, peak)
                smooth = np.random.random() * whole >= in_peak
            dx, dy, dz = nx, ny, nz
            weight *= factor
            state = FLIGHT
            continue
        # Lambertian ground: next-event estimate, then a new direction (`reflect_direction`).
        nx, ny, nz = ox / bottom_radius, oy / bottom_radius, oz / bottom_radius
        mu_s = nx * sun[0] + ny * sun[1] + nz * sun[2]
        if mu_s > 0.0:
            attenuation = sun_attenuation(ox, oy, oz, sun, w, bottom_radius, top_radius,
                                          h_step, density, extinction, extinction_maxima,
                                          sun_angular_radius, n_sun_samples, column)
            result += weight * albedo[w] / math.pi * mu_s * attenuation
            if peaked:
                result += weight * albedo[w] * aureole_estimate(
                    ox, oy, oz, dx, dy, dz, 1, attenuation, w, sun, max_orders - order - 1,
                    bottom_radius, top_radius, h_step, density, extinction, extinction_maxima,
                    scattering, scatterers, phase, cdf, cos_grid, majorant, sun_angular_radius,
                    n_sun_samples, sun_share, peak, peak_scattering, column, scratch)
        smooth = True
        order += 1
        if order >= max_orders:
            return result
        weight *= albedo[w]
        if weight <= 0.0:
            return result
        if order >= rr_start:
            weight = roulette(weight, floor)
            if weight == 0.0:
                return result
        dx, dy, dz, factor = reflect_direction(nx, ny, nz, w, sun, sun_share, cdf, cos_grid,
                                               sun_probability)
        weight *= factor
        if weight <= 0.0:
            return result
        state = FLIGHT


def extinction_maxima(level_extinction: np.ndarray) -> np.ndarray:
    """Tables (1 + n_log, n_z) of the levels' extinction `level_extinction` (n_z,) [m^-1] for
    `altitude_splits`: row 0 holds the largest value at or above each level; row 1 + j the
    largest over levels i .. i + 2^j - 1 (a sparse table: the largest over any range of levels
    in two lookups, `largest_extinction`; Bender & Farach-Colton 2000, "The LCA problem
    revisited", LATIN 2000, doi:10.1007/10719839_9)."""
    rows = [np.asarray(level_extinction, dtype=np.float64)]
    while 2 ** len(rows) <= rows[0].size:
        previous, half = rows[-1], 2 ** (len(rows) - 1)
        row = previous.copy()
        row[:-half] = np.maximum(previous[:-half], previous[half:])
        rows.append(row)
    above = np.maximum.accumulate(rows[0][::-1])[::-1]
    return np.ascontiguousarray(np.stack([above] + rows))


@njit(cache=True)
def largest_extinction(maxima, k_low, k_high):
    """The largest extinction [m^-1] over levels k_low .. k_high of the tables `maxima`
    (`extinction_maxima`)."""
    j = 0
    span = (k_high - k_low + 1) >> 1
    while span > 0:
        j += 1
        span >>= 1
    return max(maxima[1 + j, k_low], maxima[1 + j, k_high - (1 << j) + 1])


@njit(cache=True)
def altitude_splits(z_a, z_b, length, h_step, extinction_maxima):
    """Equal parts into which an interval of `length` [m] between the altitudes z_a and z_b
    (monotonic along it: the lowest point of a ray is a node) is cut so that none holds more
    than INTERVAL_DEPTH of optical depth, bounded by the largest level extinction over those
    altitudes (`largest_extinction`); at most MAX_INTERVAL_SPLITS."""
    n_z = extinction_maxima.shape[1]
    k_low = min(n_z - 1, max(0, int(min(z_a, z_b) / h_step)))
    if extinction_maxima[0, k_low] * length <= INTERVAL_DEPTH:
        return 1  # not even the largest extinction above the interval's bottom fills it
    k_high = min(n_z - 1, max(0, int(max(z_a, z_b) / h_step) + 1))
    depth = largest_extinction(extinction_maxima, k_low, k_high) * length
    if depth <= INTERVAL_DEPTH:
        return 1
    return min(MAX_INTERVAL_SPLITS, int(math.ceil(depth / INTERVAL_DEPTH)))


@njit(cache=True)
def interval_splits(r, mu, t_a, t_b, bottom_radius, h_step, extinction_maxima):
    """`altitude_splits` of the interval [t_a, t_b] of the ray (r, mu)."""
    return altitude_splits(radius_along(r, mu, t_a) - bottom_radius,
                           radius_along(r, mu, t_b) - bottom_radius, t_b - t_a, h_step,
                           extinction_maxima)


@njit(cache=True)
def view_ray_distances(ox, oy, oz, dx, dy, dz, n_intervals, bottom_radius, top_radius, h_step,
                       extinction_maxima, out):
    """(number of nodes, hits_ground, t_end [m]) of the view ray from o along d: the nodes of
    `_kernels.sample_distance` (dense at the lowest point), each interval cut into
    `interval_splits` equal parts, written into out when it is long enough (else only
    counted); 0 nodes when the ray has no length inside the atmosphere."""
    r, mu, t_start, t_end, hits_ground = ray_segment(ox, oy, oz, dx, dy, dz, bottom_radius,
                                                     top_radius)
    if t_end <= t_start:
        return 0, hits_ground, t_end
    t_split, m1, m2 = split_sample_count(r, mu, t_start, t_end, n_intervals)
    total = sample_total(m1, m2, n_intervals)
    n = 0
    t_previous = t_start
    for j in range(total):
        t = sample_distance(j, r, mu, t_start, t_end, n_intervals, t_split, m1, m2)
        parts = (interval_splits(r, mu, t_previous, t, bottom_radius, h_step, extinction_maxima)
                 if j > 0 else 1)
        for k in range(1, parts + 1):
            if n < out.shape[0]:
                out[n] = t_previous + (t - t_previous) * k / parts
            n += 1
        t_previous = t
    return n, hits_ground, t_end


@njit(parallel=True, cache=True)
def view_ray_nodes(origins, directions, sun, n_intervals, bottom_radius, top_radius, h_step,
                   density, extinction_maxima, sun_angular_radius, n_sun_samples):
    """What the first collision along each view ray is drawn from, for all wavelengths at once
    (column densities do not depend on wavelength). Nodes t_j along the part of the ray inside
    the atmosphere (`view_ray_distances`), returned as (count (n_ray,), hits_ground (n_ray,),
    t (n_ray, n_max) [m], view column from the first node (n_ray, n_max, n_c) [density x m]
    (trapezoid rule), density (n_ray, n_max, n_c), column towards the sun (n_ray, n_max,
    n_c), visible part of the sun (n_ray, n_max)). count = 0 when the ray has no length inside
    the atmosphere."""
    n_ray = origins.shape[0]
    n_c = density.shape[0]
    count = np.zeros(n_ray, dtype=np.int64)
    hits = np.zeros(n_ray, dtype=np.bool_)
    ends = np.zeros(n_ray)
    for i in prange(n_ray):
        count[i], hits[i], ends[i] = view_ray_distances(
            origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0], directions[i, 1],
            directions[i, 2], n_intervals, bottom_radius, top_radius, h_step,
            extinction_maxima, np.empty(0))
    n_max = max(2, int(count.max()) if n_ray > 0 else 2)
    t_nodes = np.zeros((n_ray, n_max))
    view_column = np.zeros((n_ray, n_max, n_c))
    node_density = np.zeros((n_ray, n_max, n_c))
    sun_column = np.zeros((n_ray, n_max, n_c))
    visible = np.zeros((n_ray, n_max))
    for i in prange(n_ray):
        ox, oy, oz = origins[i, 0], origins[i, 1], origins[i, 2]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        t_nodes[i, 0] = ends[i]  # the ground hit of a ray with no length (observer on the ground)
        if count[i] == 0:
            continue
        view_ray_distances(ox, oy, oz, dx, dy, dz, n_intervals, bottom_radius, top_radius,
                           h_step, extinction_maxima, t_nodes[i])
        dens = np.empty(n_c)
        col = np.empty(n_c)
        for j in range(count[i]):
            t = t_nodes[i, j]
            px, py, pz = ox + t * dx, oy + t * dy, oz + t * dz
            density_at(math.sqrt(px * px + py * py + pz * pz) - bottom_radius, h_step, density,
                       dens)
            for c in range(n_c):
                node_density[i, j, c] = dens[c]
                if j > 0:
                    view_column[i, j, c] = (view_column[i, j - 1, c] + 0.5 * (
                        node_density[i, j - 1, c] + dens[c]) * (t - t_nodes[i, j - 1]))
            visible[i, j] = sun_columns(px, py, pz, sun, bottom_radius, top_radius, h_step,
                                        density, extinction_maxima, sun_angular_radius,
                                        n_sun_samples, col)
            if visible[i, j] > 0.0:
                for c in range(n_c):
                    sun_column[i, j, c] = col[c]
    return count, hits, t_nodes, view_column, node_density, sun_column, visible


@njit(cache=True)
def first_collision_cdf(n, w, nu_sun, t_nodes, view_column, node_density, sun_column, visible,
                        extinction, scattering, scatterers, phase, tau, cdf):
    """Fill `tau` (n,) with the view optical depth at the n nodes of one ray and `cdf` (n,)
    with the cumulative probability of the intervals between them: half in proportion to the
    chance of the first collision there, exp(-tau_j) - exp(-tau_j+1), half in proportion to
    the single-scattering integrand beta_s p(nu) T T_sun V (trapezoid rule). The second half
    puts collisions where the sun lights the air (in twilight: high up); the first keeps every
    weight within 2x the collision estimator's. Returns False when nothing can collide."""
    for j in range(n):
        tau[j] = optical_depth(extinction, w, view_column[j])
    if n < 2 or tau[n - 1] <= 0.0:
        return False
    # cdf first holds the integrand at the nodes, then the cumulative probabilities.
    for j in range(n):
        cdf[j] = 0.0
        if visible[j] > 0.0:
            cdf[j] = (mixed_phase(w, nu_sun, node_density[j], scattering, scatterers, phase)
                      * math.exp(-tau[j] - optical_depth(extinction, w, sun_column[j]))
                      * visible[j])
    lit_total = 0.0
    for j in range(1, n):
        lit_total += 0.5 * (cdf[j - 1] + cdf[j]) * (t_nodes[j] - t_nodes[j - 1])
    lit_share = 0.5 if lit_total > 0.0 else 0.0
    # 1 - exp(-tau) and its pieces with expm1: for an optically thin ray (a few metres below
    # the top, tau ~ 1e-17) 1 - exp(-tau) rounds to 0 and the masses would divide 0 by 0.
    collide_total = -math.expm1(-tau[n - 1])
    lit_previous = cdf[0]
    cdf[0] = 0.0
    for j in range(1, n):
        lit_mass = (0.5 * (lit_previous + cdf[j]) * (t_nodes[j] - t_nodes[j - 1]) / lit_total
                    if lit_total > 0.0 else 0.0)
        lit_previous = cdf[j]
        collide_mass = (math.exp(-tau[j - 1]) * -math.expm1(tau[j - 1] - tau[j])
                        / collide_total)
        cdf[j] = cdf[j - 1] + lit_share * lit_mass + (1.0 - lit_share) * collide_mass
    for j in range(1, n):
        cdf[j] /= cdf[n - 1]
    return True


@njit(parallel=True, cache=True)
def first_collision_tables(nodes, sun, extinction, scattering, scatterers, phase, directions):
    """`first_collision_cdf` of every ray and wavelength, once for all their paths: (in_air
    (n_ray, n_wl), tau (n_ray, n_wl, n_max), cdf (n_ray, n_wl, n_max))."""
    count, _, t_nodes, view_column, node_density, sun_column, visible = nodes
    n_ray, n_max = t_nodes.shape
    n_wl = extinction.shape[1]
    in_air = np.zeros((n_ray, n_wl), dtype=np.bool_)
    tau = np.zeros((n_ray, n_wl, n_max))
    cdf = np.zeros((n_ray, n_wl, n_max))
    for index in prange(n_ray * n_wl):
        i = index // n_wl
        w = index % n_wl
        nu_sun = (directions[i, 0] * sun[0] + directions[i, 1] * sun[1]
                  + directions[i, 2] * sun[2])
        in_air[i, w] = first_collision_cdf(
            count[i], w, nu_sun, t_nodes[i], view_column[i], node_density[i], sun_column[i],
            visible[i], extinction, scattering, scatterers, phase, tau[i, w], cdf[i, w])
    return in_air, tau, cdf


@njit(cache=True)
def first_collision(n, cdf, tau, t_nodes, u):
    """(distance [m], T [-] to it, interval length / its probability [m]) of a first collision
    drawn with uniform u from `first_collision_cdf`: an interval, then a uniform point in it."""
    k, mass = pick_interval(cdf, n, u)
    f = np.random.random()
    length = t_nodes[k + 1] - t_nodes[k]
    t = t_nodes[k] + f * length
    transmittance = math.exp(-(tau[k] + f * (tau[k + 1] - tau[k])))
    return t, transmittance, length / mass


@njit(parallel=True, cache=True)
def trace_rays(origins, directions, unit_offset, sun, n_paths, batch, seed, max_orders, rr_start,
               bottom_radius, top_radius, h_step, density, extinction, extinction_maxima,
               scattering, scatterers, phase, cdf, majorant, sun_irradiance, albedo,
               sun_angular_radius, n_sun_samples, sun_share, sun_probability, peak,
               peak_scattering, nodes, first):
    """Sums and sums of squares (n_ray, n_wl, n_batch) of the path estimates [W m^-2 sr^-1
    nm^-1] of `n_paths` paths per ray and wavelength, in batches of `batch` paths; `nodes` and
    `first` are what `view_ray_nodes` and `first_collision_tables` return for these rays. Each path
    has two branches: a first collision in the air drawn from `first_collision_cdf` (weight
    T beta_e / pdf), and, when the view ray meets the ground, the ground seen through the
    transmittance T of the whole ray. The work unit (ray, wavelength, batch) is seeded with
    (seed, `unit_offset` + its index): with unit_offset = the units of the rays before these,
    a call on part of the rays gives the same numbers as one call on all of them; a unique
    index (< 2^32) gives a unique seed, as 7919 is odd."""
    n_ray = origins.shape[0]
    n_c, n_wl = extinction.shape
    n_angle = phase.shape[2]
    n_batch = (n_paths + batch - 1) // batch
    sums = np.zeros((n_ray, n_wl, n_batch))
    squares = np.zeros((n_ray, n_wl, n_batch))
    cos_grid = np.cos(np.linspace(0.0, math.pi, n_angle))
    count, hits, t_nodes = nodes[0], nodes[1], nodes[2]
    in_air_all, tau_all, cdf_all = first
    for unit in prange(n_ray * n_wl * n_batch):
        i = unit // (n_wl * n_batch)
        w = (unit // n_batch) % n_wl
        b = unit % n_batch
        index = unit_offset + unit
        np.random.seed((seed * 1_000_003 + index * 7_919 + 12_345) % 4_294_967_296)
        dens = np.empty(n_c)
        column = np.empty(n_c)
        scratch = np.zeros((3, n_c))
        n = count[i]
        in_air = in_air_all[i, w]
        tau = tau_all[i, w]
        first_cdf = cdf_all[i, w]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        ground_transmittance = math.exp(-tau[n - 1]) if n > 0 else 1.0
        t_ground = t_nodes[i, n - 1] if n > 0 else t_nodes[i, 0]
        gx = origins[i, 0] + t_ground * dx
        gy = origins[i, 1] + t_ground * dy
        gz = origins[i, 2] + t_ground * dz
        scale = bottom_radius / math.sqrt(gx * gx + gy * gy + gz * gz)
        total = 0.0
        total_sq = 0.0
        for _ in range(b * batch, min(n_paths, (b + 1) * batch)):
            value = 0.0
            if in_air:
                t, transmittance, inverse_pdf = first_collision(n, first_cdf, tau, t_nodes[i],
                                                                np.random.random())
                px = origins[i, 0] + t * dx
                py = origins[i, 1] + t * dy
                pz = origins[i, 2] + t * dz
                density_at(math.sqrt(px * px + py * py + pz * pz) - bottom_radius, h_step,
                           density, dens)
                be = 0.0
                for c in range(n_c):
                    be += extinction[c, w] * dens[c]
                value += random_walk(
                    px, py, pz, dx, dy, dz, transmittance * be * inverse_pdf, SCATTER, w, sun,
                    max_orders, rr_start, bottom_radius, top_radius, h_step, density,
                    extinction, extinction_maxima, scattering, scatterers, phase, cdf, cos_grid,
                    majorant, albedo, sun_angular_radius, n_sun_samples, sun_share,
                    sun_probability, peak, peak_scattering, dens, column, scratch)
            if hits[i]:
                value += random_walk(
                    gx * scale, gy * scale, gz * scale, dx, dy, dz, ground_transmittance,
                    GROUND, w, sun, max_orders, rr_start, bottom_radius, top_radius, h_step,
                    density, extinction, extinction_maxima, scattering, scatterers, phase, cdf,
                    cos_grid, majorant, albedo, sun_angular_radius, n_sun_samples, sun_share,
                    sun_probability, peak, peak_scattering, dens, column, scratch)
            value *= sun_irradiance[w]
            total += value
            total_sq += value * value
        sums[i, w, b] = total
        squares[i, w, b] = total_sq
    return sums, squares
