"""Numba kernels that build the precomputed tables (`transport/tables.py`,
`precompute_tables`): single scattering, the ground's direct irradiance, the phase matrices and
the incoming radiance of the scattering density, indirect irradiance, one order of multiple
scattering, and each order's statistics. The tables' cache key (`transport/code_fingerprint.py`)
hashes exactly this code and what it calls; the lookups of the solver live in
`_table_lookup_kernels`, the helpers of both in `_table_common_kernels`.

Conventions (docs/physics/tables.md, Bruneton 2017 functions.glsl; the table layout in
`_table_common_kernels`):
- During the precomputation transmittances come from a wavelength-free table of column
  densities per constituent (n_c, n_r_t, n_mu_t) in the transmittance parameterisation:
  tau = sum_c beta_e,c col_c, so all wavelengths share one lookup. Between two points of a ray,
  col = col_top(start) - col_top(end) (rays that miss the ground) or col_top(end, -mu_end) -
  col_top(start, -mu) (rays that hit it), Bruneton 2017 `GetTransmittance` in columns.
- The scattering density J is stored as the source function J / beta_s (beta_s the scattering
  coefficient) on (r_k, mu_s_l) nodes of the scattering table times outgoing directions
  (theta_o, phi_o) on a regular grid, phi measured from the sun's vertical plane (J is even in
  phi); rays multiply it by the exact beta_s at each sample.
Kernels take arrays, floats and the typed records below (numba passes a NamedTuple of them as
a typed tuple): `TableGrid` (the scattering table's axes and the atmosphere's bounds),
`RayMedium` (what a ray's samples read: the profile and the column table) and `LitOrder` (the
radiance of the previous scattering order).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from skyscatter.transport._kernels import column_below, density_at, radius_along
from skyscatter.transport._table_common_kernels import (
    corner_sum,
    exp_negative,
    fast_acos,
    linear_axis,
    mu_axis,
    mu_s_corner,
    nu_corner,
    nu_interpolation,
    phase_values,
    radius_corner,
    table_ray_distances,
    transmittance_bilinear,
)
from skyscatter.transport.geometry import horizon_cos_zenith, sun_visible_fraction
from skyscatter.transport.table_parameterisation import (
    distance_to_bottom_boundary,
    distance_to_top_boundary,
    irradiance_r_mu_s_from_x,
    mu_s_mapping_constants,
    ray_intersects_ground,
    scattering_mu_from_u,
    scattering_mu_s_from_u,
    scattering_nu_from_u,
    scattering_r_from_u,
    scattering_u_mu_s_from_constants,
    scattering_u_r,
    texel_index,
    transmittance_x_from_r_mu,
    transmittance_x_mu,
    transmittance_x_r,
)


class TableGrid(NamedTuple):
    """The scattering table's axes and the atmosphere it covers."""

    n_r: int  # radii of the scattering table
    n_mu: int  # view zenith cosines
    n_mu_s: int  # sun zenith cosines
    n_nu: int  # cosines of the scattering angle
    bottom_radius: float  # R_b [m]
    top_radius: float  # R_t [m]
    mu_s_min: float  # smallest cos(sun zenith) tabulated [-]
    sun_angle_share: float  # of the mu_s axis (table_parameterisation.scattering_u_mu_s)
    radius_warp: np.ndarray  # the u_r axis's warp (table_parameterisation.scattering_u_r)
    cubic_source: bool  # the source function interpolated cubically in radius (`radius_taps`)


class RayMedium(NamedTuple):
    """What the samples of a ray read for one wavelength batch."""

    h_step: float  # spacing of the profile's levels [m]
    density: np.ndarray  # (n_c, n_z) profile densities on those levels
    columns: np.ndarray  # (n_c, n_r_t, n_mu_t) column densities to the top [density m]
    extinction: np.ndarray  # (n_c, n_wl) extinction per density of the batch
    cumulative: np.ndarray  # (n_c, n_z) columns below each level (_kernels.cumulative_columns)


class LitOrder(NamedTuple):
    """The radiance of the previous scattering order, as the next one reads it."""

    tables: np.ndarray  # the interleaved tables, 1-D (`flat_tables`)
    n_t: int  # tables interleaved: n_s single-scattering tables or 1 multiple
    use_phase: bool  # apply the phase functions (the single-scattering tables)
    phase_table: np.ndarray  # (n_s, n_angle, n_wl) phase functions [sr^-1]


@njit(cache=True)
def cell_nu(mu, mu_s, i_nu, n_nu):
    """nu of slice i_nu of a scattering-table cell (mu, mu_s): the slices are azimuths, so
    every nu lies within the values the two directions allow (`scattering_nu_from_u`)."""
    return scattering_nu_from_u(i_nu / (n_nu - 1), mu, mu_s)


@njit(cache=True)
def columns_to_top(r, mu, bottom_radius, top_radius, columns, out):
    """Column densities from (r, mu) to the top, bilinear in `columns` (n_c, n_r_t, n_mu_t),
    into out (n_c,). For rays that do not hit the ground."""
    x_mu, x_r = transmittance_x_from_r_mu(r, mu, bottom_radius, top_radius)
    i, a = linear_axis(x_r * (columns.shape[1] - 1), columns.shape[1])
    j, b = linear_axis(x_mu * (columns.shape[2] - 1), columns.shape[2])
    for c in range(columns.shape[0]):
        out[c] = ((1.0 - a) * ((1.0 - b) * columns[c, i, j] + b * columns[c, i, j + 1])
                  + a * ((1.0 - b) * columns[c, i + 1, j] + b * columns[c, i + 1, j + 1]))


# Table rays are refined where the medium is optically thick (`_refined_distances`): an interval
# of the base law (`table_ray_distances`) across which the vertical optical depth changes by
# more than REFINE_OPTICAL_DEPTH is halved, again and again (at most REFINE_PASSES times),
# while the light from its start still reaches the ray's origin by more than
# exp(-REFINE_DEPTH_LIMIT), up to REFINED_SAMPLES_FACTOR times the base samples in all. The
# source function changes with the vertical optical depth (the sun's light by exp(-tau / mu_s));
# the exponential weights of `_ray_weights` already make the view's own transmittance exact.
# Clear air (Earth's whole vertical optical depth about 0.5) is hardly refined; a cloud deck
# of optical depth 20 gets its samples where the light comes from, its first optical depths.
# On a deck of optical depth 8 seen from above (tests/transport/test_transport_tables.py) the
# first order's largest error was 4.3 % refining by 0.5 in the ray's or the vertical optical
# depth, 11.7 % by 0.5 in the vertical alone, 1.7 % by 0.15 in the vertical alone.
REFINE_OPTICAL_DEPTH = 0.15
REFINE_DEPTH_LIMIT = 10.0
REFINE_PASSES = 8
REFINED_SAMPLES_FACTOR = 2
# A table ray ends where it is opaque: where its optical depth from the origin exceeds
# OPAQUE_OPTICAL_DEPTH at every wavelength, what lies beyond reaches the origin by less than
# e^-40 = 4e-18, below float32's resolution (6e-8) of any cell brighter than e^-23 of the
# light it would add. The first order likewise skips the samples whose light reaches the
# origin through more than that optical depth, the sun's path and the view's together. Only
# optically thick layers get there (a ray inside a cloud deck, or through one at a slant);
# Earth's and Mars's clear rays never do.
OPAQUE_OPTICAL_DEPTH = 40.0


@njit(cache=True)
def _grey_depths(r, mu, tj, hits_ground, start, grey, grid, columns, here):
    """(optical depth from the ray's start, vertical optical depth above the point) at distance
    tj along the table ray (r, mu), in the grey extinction per column density `grey` (n_c,);
    start (n_c,): `columns_to_top` of the ray's start as `_ray_samples` takes it; here scratch."""
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    rj = _ray_radius(r, mu, tj, bottom_radius, top_radius)
    mj = min(max((r * mu + tj) / rj, -1.0), 1.0)
    columns_to_top(rj, -mj if hits_ground else mj, bottom_radius, top_radius, columns, here)
    along = 0.0
    for c in range(grey.size):
        along += grey[c] * max(here[c] - start[c] if hits_ground else start[c] - here[c], 0.0)
    columns_to_top(rj, 1.0, bottom_radius, top_radius, columns, here)
    vertical = 0.0
    for c in range(grey.size):
        vertical += grey[c] * here[c]
    return along, vertical


@njit(cache=True)
def _refined_distances(r, mu, hits_ground, t, total, start, grid, medium):
    """Refine the `total` distances t (increasing, t.size >= the refined count) of the table ray
    (r, mu) where the medium is optically thick (REFINE_OPTICAL_DEPTH and the constants beside
    it), in the largest extinction of the batch's wavelengths; returns the new count."""
    n_c = medium.extinction.shape[0]
    grey = np.empty(n_c)
    for c in range(n_c):
        grey[c] = medium.extinction[c].max()
    capacity = min(t.size, REFINED_SAMPLES_FACTOR * (total - 1) + 1)
    here = np.empty(n_c)
    along = np.empty(capacity)
    vertical = np.empty(capacity)
    for j in range(total):
        along[j], vertical[j] = _grey_depths(r, mu, t[j], hits_ground, start, grey, grid,
                                             medium.columns, here)
    new_t = np.empty(capacity)
    new_along = np.empty(capacity)
    new_vertical = np.empty(capacity)
    for _ in range(REFINE_PASSES):
        k = 0
        for j in range(total):
            if (j > 0 and k + 1 + total - j <= capacity
                    and along[j - 1] < REFINE_DEPTH_LIMIT
                    and abs(vertical[j] - vertical[j - 1]) > REFINE_OPTICAL_DEPTH):
                new_t[k] = 0.5 * (t[j - 1] + t[j])
                new_along[k], new_vertical[k] = _grey_depths(r, mu, new_t[k], hits_ground,
                                                             start, grey, grid, medium.columns,
                                                             here)
                k += 1
            new_t[k], new_along[k], new_vertical[k] = t[j], along[j], vertical[j]
            k += 1
        if k == total:
            break
        total = k
        t[:total] = new_t[:total]
        along[:total] = new_along[:total]
        vertical[:total] = new_vertical[:total]
    return total


# Pieces per interval between two ray samples over which the column along the ray is taken as
# the column in altitude times the interval's length over its rise (`_ray_samples`): exact for
# the profile's densities wherever the ray's slope is constant; 4 pieces bound the slope's change
# within a piece where the ray curves away from the horizontal.
ALONG_RAY_PIECES = 4


@njit(cache=True)
def _ray_radius(r, mu, t, bottom_radius, top_radius):
    """Radius [m] at distance t along the ray (r, mu), inside the atmosphere's bounds."""
    return min(max(radius_along(r, mu, t), bottom_radius), top_radius)


@njit(cache=True)
def _ray_samples(r, mu, hits_ground, n_samples, grid, medium, t, radius, mu_t, dens, col_view):
    """Samples of the table ray (r, mu) up to the ground or the top (`table_ray_distances`,
    refined where the medium is optically thick: `_refined_distances`): distances t, radii,
    cosines mu_t, densities dens (n, n_c) and view columns col_view (n, n_c) from the start.
    The columns are integrated along the ray (ALONG_RAY_PIECES), not read from the column
    table: its interpolation between rows misjudges an oblique ray's path through a layer a
    few of its rows thick. The arrays hold REFINED_SAMPLES_FACTOR n_samples + 1 samples.
    Returns the number of samples (0 for a ray of zero length)."""
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    h_step, density, columns = medium.h_step, medium.density, medium.columns
    n_c = density.shape[0]
    if hits_ground:
        d = distance_to_bottom_boundary(r, mu, bottom_radius)
    else:
        d = distance_to_top_boundary(r, mu, top_radius)
    if d <= 0.0:
        return 0
    start = np.empty(n_c)
    columns_to_top(r, -mu if hits_ground else mu, bottom_radius, top_radius, columns, start)
    total = table_ray_distances(r, mu, d, hits_ground, n_samples, t)
    total = _refined_distances(r, mu, hits_ground, t, total, start, grid, medium)
    low = np.empty(n_c)
    high = np.empty(n_c)
    level = np.empty(n_c)
    h_a = 0.0
    for j in range(total):
        tj = t[j]
        rj = _ray_radius(r, mu, tj, bottom_radius, top_radius)
        radius[j] = rj
        mu_t[j] = min(max((r * mu + tj) / rj, -1.0), 1.0)
        density_at(rj - bottom_radius, h_step, density, dens[j])
        if j == 0:
            col_view[0, :] = 0.0
            h_a = rj - bottom_radius
            column_below(h_a, h_step, density, medium.cumulative, low)
            continue
        col_view[j, :] = col_view[j - 1, :]
        step = (tj - t[j - 1]) / ALONG_RAY_PIECES
        # pieces from the previous sample (h_a, low) to this one, whose end the next interval
        # starts from
        for piece in range(1, ALONG_RAY_PIECES + 1):
            if piece < ALONG_RAY_PIECES:
                h_b = _ray_radius(r, mu, t[j - 1] + piece * step, bottom_radius,
                                  top_radius) - bottom_radius
            else:
                h_b = rj - bottom_radius
            column_below(h_b, h_step, density, medium.cumulative, high)
            rise = h_b - h_a
            if abs(rise) > 1e-9 * step:
                for c in range(n_c):
                    col_view[j, c] += max((high[c] - low[c]) * step / rise, 0.0)
            else:  # horizontal: the density at the piece's altitude
                density_at(h_a, h_step, density, level)
                for c in range(n_c):
                    col_view[j, c] += level[c] * step
            for c in range(n_c):
                low[c] = high[c]
            h_a = h_b
    return total


@njit(cache=True)
def _exponential_end_weights(a):
    """(int_0^1 (1 - s) e^(-a s) ds, int_0^1 s e^(-a s) ds): the weights of the two ends of
    an interval of optical depth a >= 0 for an integrand linear between them times the
    transmittance (series below a = 1e-3, where the closed form cancels)."""
    if a < 1e-3:
        i0 = 1.0 - a / 2.0 + a * a / 6.0
        i1 = 0.5 - a / 3.0 + a * a / 8.0
    else:
        e = math.exp(-a)
        i0 = (1.0 - e) / a
        i1 = (1.0 - e * (1.0 + a)) / (a * a)
    return i0 - i1, i1


@njit(cache=True)
def _ray_weights(total, tau, extinct, beta, out):
    """out[j, w]: the weight of S(p_j) in int_0^d beta(p) S(p) T(x, p) dt over `total` ray
    samples with optical depths tau (total, n_wl) from the ray's start (from the columns) and
    extinction coefficients extinct (total, n_wl), taken in optical depth:
    int beta S T dt = int (beta / beta_e) S e^(-tau) dtau with (beta / beta_e) S linear in tau
    between samples (beta (total, n_wl)), exact in the transmittance for any density between
    the samples. An interval scatters at most the light its own column takes out of the ray,
    so a layer thinner than the samples (fog, a cloud deck) cannot create light, and the
    orders of an optically thick layer converge. At a sample outside every constituent (above
    a cloud deck's top) beta / beta_e is the other end's: the interval's optical depth is the
    layer's."""
    n_wl = tau.shape[1]
    out[:total, :] = 0.0
    for w in range(n_wl):
        ratio_before = 0.0
        for j in range(total):
            ratio = beta[j, w] / extinct[j, w] if extinct[j, w] > 0.0 else -1.0
            if j > 0:
                a = max(tau[j, w] - tau[j - 1, w], 0.0)
                w0, w1 = _exponential_end_weights(a)
                base = math.exp(-tau[j - 1, w]) * a
                out[j - 1, w] += base * w0 * (ratio_before if ratio_before >= 0.0
                                              else max(ratio, 0.0))
                out[j, w] += base * w1 * (ratio if ratio >= 0.0 else max(ratio_before, 0.0))
            ratio_before = ratio


@njit(cache=True)
def _opaque_end(total, tau, view_depth):
    """The samples of a ray with optical depths tau (total, n_wl) from its origin up to the
    first beyond OPAQUE_OPTICAL_DEPTH at every wavelength (included: it closes the last
    interval); view_depth (total,) receives each sample's smallest optical depth."""
    for j in range(total):
        view_depth[j] = tau[j].min()
        if view_depth[j] > OPAQUE_OPTICAL_DEPTH:
            return j + 1
    return total


@njit(cache=True)
def _ray_depths(total, col_view, dens, extinction):
    """(tau, extinct): the optical depth from the ray's start and the extinction coefficient
    (total, n_wl) at each of its samples (columns col_view and densities dens (total, n_c)),
    in `extinction` (n_c, n_wl)."""
    n_c, n_wl = extinction.shape
    tau = np.empty((total, n_wl))
    extinct = np.empty((total, n_wl))
    for j in range(total):
        for w in range(n_wl):
            depth = 0.0
            coefficient = 0.0
            for c in range(n_c):
                depth += extinction[c, w] * col_view[j, c]
                coefficient += extinction[c, w] * dens[j, c]
            tau[j, w] = depth
            extinct[j, w] = coefficient
    return tau, extinct


@njit(cache=True)
def _view_weights(total, tau, extinct, dens, coefficients):
    """view (n_k, total, n_wl): for each k of `coefficients` (n_k, n_c, n_wl), the weights of
    a source S at the ray's samples in int beta_k S T dt, beta_k = sum_c dens_c
    coefficients[k, c] (`_ray_weights`)."""
    n_k, n_c, n_wl = coefficients.shape
    beta = np.empty((total, n_wl))
    view = np.empty((n_k, total, n_wl))
    for k in range(n_k):
        for j in range(total):
            for w in range(n_wl):
                value = 0.0
                for c in range(n_c):
                    value += dens[j, c] * coefficients[k, c, w]
                beta[j, w] = value
        _ray_weights(total, tau, extinct, beta, view[k])
    return view


@njit(cache=True)
def _table_ray(i_r, i_mu, n_samples, grid, medium, coefficients):
    """The ray of scattering-table cell (i_r, i_mu): (r, mu, total, t, radius, mu_t, dens,
    col_view, view, view_depth) with its `total` samples (`_ray_samples`, up to
    `_opaque_end`), each sample's smallest optical depth from the origin view_depth (total,)
    and the weights `_view_weights` of `coefficients` (n_k, n_c, n_wl)."""
    n_r, n_mu = grid.n_r, grid.n_mu
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    n_c = medium.extinction.shape[0]
    n_max = REFINED_SAMPLES_FACTOR * n_samples + 8
    r = scattering_r_from_u((i_r + 0.5) / n_r, bottom_radius, top_radius, n_r,
                            grid.radius_warp)
    mu, hits_ground = scattering_mu_from_u((i_mu + 0.5) / n_mu, r, bottom_radius, top_radius,
                                           n_mu)
    t = np.empty(n_max)
    radius = np.empty(n_max)
    mu_t = np.empty(n_max)
    dens = np.empty((n_max, n_c))
    col_view = np.empty((n_max, n_c))
    total = _ray_samples(r, mu, hits_ground, n_samples, grid, medium, t, radius, mu_t, dens,
                         col_view)
    tau, extinct = _ray_depths(total, col_view, dens, medium.extinction)
    view_depth = np.empty(total)
    total = _opaque_end(total, tau, view_depth)
    view = _view_weights(total, tau, extinct, dens, coefficients)
    return r, mu, total, t, radius, mu_t, dens, col_view, view, view_depth


@njit(cache=True)
def mu_s_nodes(grid):
    """cos(sun zenith) [-] of the n_mu_s nodes of `grid` (a `TableGrid`)."""
    nodes = np.empty(grid.n_mu_s)
    for i_s in range(grid.n_mu_s):
        nodes[i_s] = scattering_mu_s_from_u((i_s + 0.5) / grid.n_mu_s, grid.bottom_radius,
                                            grid.top_radius, grid.mu_s_min,
                                            grid.sun_angle_share, grid.n_mu_s)
    return nodes


@njit(cache=True)
def radius_taps(k, a, n):
    """(first node, 4 weights) interpolating at fractional index k + a on an axis of n nodes:
    Catmull-Rom's cubic through nodes k-1..k+2 (Catmull & Rom 1974; Keys 1981, IEEE Trans. ASSP
    29(6), 1153, doi:10.1109/TASSP.1981.1163711, with a = -1/2), at the two end cells the
    quadratic through the three nearest nodes, on an axis of 2 nodes the line (the weights
    beyond the axis 0)."""
    if n < 3:
        return k, 1.0 - a, a, 0.0, 0.0
    if k == 0:
        return 0, 0.5 * (a - 1.0) * (a - 2.0), -a * (a - 2.0), 0.5 * a * (a - 1.0), 0.0
    if k + 2 > n - 1:
        return k - 1, 0.5 * a * (a - 1.0), 1.0 - a * a, 0.5 * a * (a + 1.0), 0.0
    a2 = a * a
    a3 = a2 * a
    return (k - 1, 0.5 * (-a3 + 2.0 * a2 - a), 0.5 * (3.0 * a3 - 5.0 * a2 + 2.0),
            0.5 * (-3.0 * a3 + 4.0 * a2 + a), 0.5 * (a3 - a2))


@njit(cache=True, error_model="numpy")
def _sun_at_samples(r_mu_s, nu, t, radius, mu_h, d_min, d_max, top_radius, n_mu_t, mu_s_j,
                    column_i, column_a):
    """For the samples (t, radius (total,)) of a ray whose cell has r mu_s = `r_mu_s` and nu:
    the sun's zenith cosine at each, mu_s_j = (r mu_s + t nu) / r_j, and where the sun
    transmittance is looked up, the column (lower entry and weight) of the transmittance
    table's x_mu axis of n_mu_t entries (`transmittance_x_mu`, the sun held at the horizon
    mu_h where below it; d_min, d_max per sample from `transmittance_x_r`), into mu_s_j,
    column_i and column_a. A loop of its own, without exceptions, so that it vectorises."""
    for j in range(mu_s_j.size):
        mu_s_j[j] = min(max((r_mu_s + t[j] * nu) / radius[j], -1.0), 1.0)
        x_mu = transmittance_x_mu(radius[j], max(mu_s_j[j], mu_h[j]), top_radius, d_min[j],
                                  d_max[j])
        column_i[j], column_a[j] = linear_axis(x_mu * (n_mu_t - 1), n_mu_t)


@njit(cache=True, inline="always")
def _sun_at_sample(sun_table, sun_table_is_depth, view_depth, i, a, j, b, sun, power_bits,
                   power):
    """The sun's transmittance at a sample of a table ray, bilinear in `sun_table` at row
    i + a and column j + b, into sun (n_wl,); where the table holds optical depths
    (`single_scattering_table`), False when the sun and the view together cross more than
    OPAQUE_OPTICAL_DEPTH (view_depth: the view's smallest) and sun is left as it is
    (power_bits, power: the scratch of `exp_negative`)."""
    transmittance_bilinear(sun_table, i, a, j, b, sun)
    if sun_table_is_depth:
        if sun.min() + view_depth > OPAQUE_OPTICAL_DEPTH:
            return False  # no light from there: no exponentials
        exp_negative(sun, sun, power_bits, power)
    return True


@njit(cache=True, inline="always")
def _add_sample(acc, view, j, visible, sun):
    """acc[s] += visible view[s, j] sun for every constituent s (acc (n_s, n_wl))."""
    for s in range(acc.shape[0]):
        acc_s = acc[s]  # row views: see `multiple_scattering_table`
        view_s = view[s, j]
        for w in range(acc_s.size):
            acc_s[w] += visible * view_s[w] * sun[w]


@njit(parallel=True, cache=True, error_model="numpy")
def single_scattering_table(grid, medium, n_samples, sun_table, sun_table_is_depth, scatterers,
                            factor, sun_angular_radius, table, scaled_extinction,
                            scaled_sun_table, scaled_factor, scaled_table):
    """Single scattering without phase function, per scattering constituent, into `table`:
    table[s, cell, w] = factor[s, w] * int_0^d T(x, p) n_s(p) T_sun(p) V(p) dt, with
    factor = E_sun beta_s,s [W m^-2 nm^-1 / density]; (n_r, n_mu, n_mu_s, n_nu, n_s, n_wl)
    float32 (interleaved, `scattering_lookup`; any strides, so the tables' own slots can be
    written without a copy beside them). T(x, p) from the ray's columns, T_sun bilinear
    in `sun_table` (n_r_t, n_mu_t, n_wl) in the transmittance table's parameterisation: the
    transmittances themselves (no exponential per cell), or where `sun_table_is_depth` the
    optical depths, exponentiated after the interpolation: interpolating T itself overestimates
    the sun inside an optically thick layer (T falls by e^-1.4 between two of 512 rows in a
    stratus deck). Bruneton 2017,
    `ComputeSingleScattering`; V = visible part of the sun disk. `grid`: a `TableGrid`,
    `medium`: a `RayMedium`.

    With a second medium (`scaled_table` not empty: the delta-M scaled one of the orders >= 2,
    its extinction per density `scaled_extinction` (n_c, n_wl), its `scaled_sun_table` and
    `scaled_factor`) its first order goes into `scaled_table` in the same pass, on the same
    ray samples (those of `medium`, whose extinction is the larger: its samples and its opaque
    end serve both): the cells' geometry and the sun's position at each sample, two thirds of
    the work, are found once for both, and the two sun tables, side by side in one array, are
    looked up together. Two media share a pass only where the sun tables hold transmittances
    (no optically thick layer: `tables._FirstOrders`)."""
    n_r, n_mu, n_mu_s, n_nu = grid.n_r, grid.n_mu, grid.n_mu_s, grid.n_nu
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    extinction = medium.extinction
    n_s = scatterers.size
    n_wl = extinction.shape[1]
    two = scaled_table.size > 0
    n_r_t, n_mu_t = sun_table.shape[0], sun_table.shape[1]
    # mu_s >= mu_h + alpha + alpha^2 / 2 >= cos(theta_h - alpha): the whole sun disk is above
    # the horizon, `sun_visible_fraction` = 1 (its own fast exit costs a cos and a sin).
    sun_clear = sun_angular_radius * (1.0 + 0.5 * sun_angular_radius)
    # beta_s = n_s: the density of each scattering constituent, weighed into its own table
    selection = np.zeros((n_s, extinction.shape[0], n_wl))
    for s in range(n_s):
        selection[s, scatterers[s], :] = 1.0
    nodes = mu_s_nodes(grid)
    # both media's sun transmittances side by side: one bilinear lookup per sample serves both
    pair_table = np.empty((n_r_t, n_mu_t, 2 * n_wl) if two else (0, 0, 0))
    if two:
        pair_table[:, :, :n_wl] = sun_table
        pair_table[:, :, n_wl:] = scaled_sun_table
    for row in prange(n_r * n_mu):
        i_r = row // n_mu
        i_mu = row % n_mu
        r, mu, total, t, radius, mu_t, dens, col_view, view, view_depth = _table_ray(
            i_r, i_mu, n_samples, grid, medium, selection)
        if total == 0:
            table[i_r, i_mu] = 0.0
            if two:
                scaled_table[i_r, i_mu] = 0.0
            continue
        scaled_view = view
        if two:
            tau, extinct = _ray_depths(total, col_view, dens, scaled_extinction)
            scaled_view = _view_weights(total, tau, extinct, dens, selection)
        # Per sample: the horizon, and the r part of the transmittance lookup towards the sun.
        mu_h = np.empty(total)
        row_i = np.empty(total, dtype=np.int64)
        row_a = np.empty(total)
        row_d_min = np.empty(total)
        row_d_max = np.empty(total)
        for j in range(total):
            mu_h[j] = horizon_cos_zenith(radius[j], bottom_radius)
            x_r, row_d_min[j], row_d_max[j] = transmittance_x_r(radius[j], bottom_radius,
                                                                top_radius)
            row_i[j], row_a[j] = linear_axis(x_r * (n_r_t - 1), n_r_t)
        sun = np.empty(n_wl)
        power_bits = np.empty(n_wl, dtype=np.int32)
        power = power_bits.view(np.float32)
        pair = np.empty(2 * n_wl)
        pair_exact = pair[:n_wl]  # views made once per ray, not per sample
        pair_scaled = pair[n_wl:]
        acc = np.empty((n_s, n_wl))
        scaled_acc = np.empty((n_s, n_wl))
        mu_s_j = np.empty(total)
        column_i = np.empty(total, dtype=np.int64)
        column_a = np.empty(total)
        for i_s in range(n_mu_s):
            mu_s = nodes[i_s]
            for i_nu in range(n_nu):
                nu = cell_nu(mu, mu_s, i_nu, n_nu)
                acc[:, :] = 0.0
                scaled_acc[:, :] = 0.0
                _sun_at_samples(r * mu_s, nu, t, radius, mu_h, row_d_min, row_d_max, top_radius,
                                n_mu_t, mu_s_j, column_i, column_a)
                for j in range(total):
                    visible = 1.0
                    if mu_s_j[j] < mu_h[j] + sun_clear:  # else the whole disk is up
                        visible = sun_visible_fraction(radius[j], mu_s_j[j], bottom_radius,
                                                       sun_angular_radius)
                        if visible <= 0.0:
                            continue
                    if two:
                        transmittance_bilinear(pair_table, row_i[j], row_a[j], column_i[j],
                                               column_a[j], pair)
                        _add_sample(acc, view, j, visible, pair_exact)
                        _add_sample(scaled_acc, scaled_view, j, visible, pair_scaled)
                    elif _sun_at_sample(sun_table, sun_table_is_depth, view_depth[j], row_i[j],
                                        row_a[j], column_i[j], column_a[j], sun, power_bits,
                                        power):
                        _add_sample(acc, view, j, visible, sun)
                for s in range(n_s):
                    for w in range(n_wl):
                        table[i_r, i_mu, i_s, i_nu, s, w] = acc[s, w] * factor[s, w]
                if two:
                    for s in range(n_s):
                        for w in range(n_wl):
                            scaled_table[i_r, i_mu, i_s, i_nu, s, w] = (scaled_acc[s, w]
                                                                        * scaled_factor[s, w])


@njit(cache=True)
def _direct_irradiance(r, mu_s, grid, medium, sun_irradiance, sun_angular_radius, col, out):
    """out (n_wl,) = E_sun T_sun max(mu_s, 0) V on a horizontal surface at radius r [W m^-2
    nm^-1]; col (n_c,) scratch. `grid`: a `TableGrid`, `medium`: a `RayMedium`."""
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    extinction = medium.extinction
    out[:] = 0.0
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible <= 0.0 or mu_s <= 0.0:
        return
    columns_to_top(r, mu_s, bottom_radius, top_radius, medium.columns, col)
    for w in range(extinction.shape[1]):
        tau = 0.0
        for c in range(extinction.shape[0]):
            tau += extinction[c, w] * col[c]
        out[w] = sun_irradiance[w] * math.exp(-tau) * mu_s * visible


@njit(cache=True)
def direct_ground_irradiance(n_points, grid, medium, sun_irradiance, sun_angular_radius):
    """Direct sun irradiance on the ground E_sun T_sun max(mu_s, 0) V at mu_s = -1 + 2 i /
    (n_points - 1), (n_points, n_wl) [W m^-2 nm^-1]. `grid`: a `TableGrid`, `medium`: a
    `RayMedium`."""
    n_c, n_wl = medium.extinction.shape
    out = np.zeros((n_points, n_wl))
    col = np.empty(n_c)
    for i in range(n_points):
        _direct_irradiance(grid.bottom_radius, -1.0 + 2.0 * i / (n_points - 1), grid, medium,
                           sun_irradiance, sun_angular_radius, col, out[i])
    return out


@njit(parallel=True, cache=True)
def direct_irradiance_nodes(n_r_e, n_mu_s_e, grid, medium, sun_irradiance, sun_angular_radius):
    """Direct sun on horizontal surfaces, E_sun T_sun max(mu_s, 0) V, on the irradiance nodes
    (as `indirect_irradiance`), (n_r_e, n_mu_s_e, n_wl) [W m^-2 nm^-1]. `grid`: a `TableGrid`,
    `medium`: a `RayMedium`."""
    n_c, n_wl = medium.extinction.shape
    out = np.zeros((n_r_e, n_mu_s_e, n_wl))
    for node in prange(n_r_e * n_mu_s_e):
        i = node // n_mu_s_e
        j = node % n_mu_s_e
        r, mu_s = irradiance_r_mu_s_from_x(j / (n_mu_s_e - 1), i / (n_r_e - 1),
                                           grid.bottom_radius, grid.top_radius)
        _direct_irradiance(r, mu_s, grid, medium, sun_irradiance, sun_angular_radius,
                           np.empty(n_c), out[i, j])
    return out


@njit(parallel=True, cache=True)
def peak_differences(scaled_single, single, kept, smooth_phase, slot, grid, out):
    """What the first order of the delta-M scaled medium has more than the exact first order's
    smooth part (`phase_truncation`), D_s = scaled_single_s - kept_s single_s, on every cell
    of the scattering table, into out (n_r, n_mu, n_mu_s, n_nu, n_c + 1, n_wl) float32, any
    strides: D_s without phase function into out[..., slot[s], :] for the constituents with
    slot[s] >= 0 (the clipped ones, whose p* kinks at the truncation angle: the lookups apply
    it per ray), sum_s p*_s(nu) D_s of the others into the last entry (the orders >= 2; p*
    from `smooth_phase` (n_s, n_angle, n_wl) at each cell's nu). Tables (n_r, n_mu, n_mu_s,
    n_nu, n_s, n_wl) without phase functions, as `single_scattering_table` writes them;
    kept = 1 - f (n_s, n_wl). `grid`: a `TableGrid`. The scaled medium attenuates less, so
    each difference is >= 0; where the true one is ~0 (air above the particles) the two
    quadratures can differ by a hair in either direction (measured: 33 of 131 072 cells of a
    small table, down to -0.8 % of its largest value), which is clipped to 0."""
    n_r, n_mu, n_mu_s, n_nu, n_s, n_wl = single.shape
    last = out.shape[4] - 1
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    nodes = mu_s_nodes(grid)
    for row in prange(n_r * n_mu):
        i_r = row // n_mu
        i_mu = row % n_mu
        r = scattering_r_from_u((i_r + 0.5) / n_r, bottom_radius, top_radius, n_r,
                                grid.radius_warp)
        mu, _ = scattering_mu_from_u((i_mu + 0.5) / n_mu, r, bottom_radius, top_radius, n_mu)
        phase = np.empty(n_s * n_wl)
        for i_s in range(n_mu_s):
            mu_s = nodes[i_s]
            for i_nu in range(n_nu):
                nu = cell_nu(mu, mu_s, i_nu, n_nu)
                phase_values(smooth_phase, nu, phase)
                out[i_r, i_mu, i_s, i_nu, last] = 0.0
                for s in range(n_s):
                    for w in range(n_wl):
                        difference = max(scaled_single[i_r, i_mu, i_s, i_nu, s, w]
                                         - kept[s, w] * single[i_r, i_mu, i_s, i_nu, s, w], 0.0)
                        if slot[s] >= 0:
                            out[i_r, i_mu, i_s, i_nu, slot[s], w] = difference
                        else:
                            out[i_r, i_mu, i_s, i_nu, last, w] += phase[s * n_wl + w] * difference


@njit(parallel=True, cache=True)
def phase_matrices(phase_table, cos_direct, cos_mirror, solid_angle):
    """Phase matrices of the sphere integral, (n_s, n_wl, n_out, n_in) float32:
    P[o, i] = (p(cos_direct[o, i]) + p(cos_mirror[o, i])) solid_angle[i], each row normalised
    to sum 1; p from `phase_table` (n_s, n_angle, n_wl) as in `phase_values`."""
    n_s, n_angle, n_wl = phase_table.shape
    n_out, n_in = cos_direct.shape
    out = np.empty((n_s, n_wl, n_out, n_in), dtype=np.float32)
    for o in prange(n_out):
        row = np.empty((n_s, n_wl, n_in))
        direct = np.empty(n_s * n_wl)
        mirror = np.empty(n_s * n_wl)
        for i in range(n_in):
            phase_values(phase_table, cos_direct[o, i], direct)
            phase_values(phase_table, cos_mirror[o, i], mirror)
            for s in range(n_s):
                for w in range(n_wl):
                    row[s, w, i] = (direct[s * n_wl + w] + mirror[s * n_wl + w]) * solid_angle[i]
        for s in range(n_s):
            for w in range(n_wl):
                total = 0.0
                for i in range(n_in):
                    total += row[s, w, i]
                for i in range(n_in):
                    out[s, w, o, i] = row[s, w, i] / total
    return out


@njit(cache=True)
def _ground_seen(r, mu, grid, medium, albedo, col_a, col_b, out):
    """For a ray (r, mu) that hits the ground: the distance d to it [m], and out[w] = T(x, g)
    albedo / pi, what the Lambertian ground's irradiance is multiplied by on the way to x."""
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    columns, extinction = medium.columns, medium.extinction
    n_c, n_wl = extinction.shape
    d = distance_to_bottom_boundary(r, mu, bottom_radius)
    mu_g = min(max((r * mu + d) / bottom_radius, -1.0), 1.0)
    columns_to_top(bottom_radius, -mu_g, bottom_radius, top_radius, columns, col_a)
    columns_to_top(r, -mu, bottom_radius, top_radius, columns, col_b)
    for w in range(n_wl):
        tau = 0.0
        for c in range(n_c):
            tau += extinction[c, w] * max(col_a[c] - col_b[c], 0.0)
        out[w] = math.exp(-tau) * albedo[w] / math.pi
    return d


@njit(cache=True)
def _add_ground_radiance(r, mu_s, nu, d, seen, ground_irradiance, bottom_radius, out):
    """out[w] += radiance of the Lambertian ground at distance d along a ray from radius r:
    seen[w] (`_ground_seen`) times E(mu_s(g)), E from `ground_irradiance` (n_g, n_wl) on
    mu_s = -1 + 2 i / (n_g - 1)."""
    mu_s_g = min(max((r * mu_s + d * nu) / bottom_radius, -1.0), 1.0)
    n_g = ground_irradiance.shape[0]
    i, a = linear_axis(0.5 * (mu_s_g + 1.0) * (n_g - 1), n_g)
    for w in range(out.size):
        out[w] += seen[w] * ((1.0 - a) * ground_irradiance[i, w] + a * ground_irradiance[i + 1, w])


@njit(cache=True)
def _nu_profile(flat, n_mu, n_mu_s, n_nu, i_r, a_r, i_mu, a_mu, i_s, a_s, profile):
    """profile (n_nu m,) = the interleaved tables `flat` (n_r, n_mu, n_mu_s, n_nu, m as 1-D,
    `flat_tables`) interpolated at the r, mu and mu_s corners (lower entries and weights) on
    every nu slice (`corner_sum`): the part of `scattering_lookup` that lookups differing only
    in nu share.
    For one (r, mu, mu_s) corner the slices are n_nu m contiguous numbers."""
    size = profile.size
    s_s = size
    s_mu = n_mu_s * s_s
    s_r = n_mu * s_mu
    profile[:] = 0.0
    corner_sum(flat, i_r * s_r + i_mu * s_mu + i_s * s_s, s_r, s_mu, s_s, a_r, a_mu, a_s,
               profile)


@njit(parallel=True, cache=True)
def incoming_radiance(grid, medium, theta_in, phi_in, previous, ground_irradiance, albedo,
                      r_nodes):
    """Radiance of the previous order arriving at the scattering-density nodes (the (r, mu_s)
    nodes of `grid`, a `TableGrid`, of its r nodes first .. stop - 1, r_nodes = (first, stop)),
    from the directions (theta_in[a], phi_in[p]) (phi from the sun's vertical plane): the
    scattering lookup in `previous` (a `LitOrder`; with phase functions when its `use_phase`,
    i.e. the single-scattering tables) plus the ground lit by `ground_irradiance` for
    directions that hit it (`medium`: a `RayMedium`). Returns (n_wl, n_a n_p, (stop - first)
    n_mu_s) float32, the layout of the matrix product that follows. Bruneton 2017,
    `ComputeScatteringDensity`, the inner part. The directions of one zenith angle share their
    r, mu and mu_s corners: the tables are interpolated there once, on every nu slice
    (`_nu_profile`), and each azimuth only interpolates in nu (`nu_interpolation`, as
    `scattering_lookup`)."""
    n_r, n_mu, n_mu_s, n_nu = grid.n_r, grid.n_mu, grid.n_mu_s, grid.n_nu
    bottom_radius, top_radius, mu_s_min = grid.bottom_radius, grid.top_radius, grid.mu_s_min
    tables, n_t = previous.tables, previous.n_t
    use_phase, phase_table = previous.use_phase, previous.phase_table
    extinction = medium.extinction
    n_c, n_wl = extinction.shape
    n_a = theta_in.size
    n_p = phi_in.size
    first, stop = r_nodes
    radiance = np.zeros((n_wl, n_a * n_p, (stop - first) * n_mu_s), dtype=np.float32)
    nodes = mu_s_nodes(grid)
    for kl in prange((stop - first) * n_mu_s):
        k = first + kl // n_mu_s
        l = kl % n_mu_s
        r = scattering_r_from_u((k + 0.5) / n_r, bottom_radius, top_radius, n_r,
                                grid.radius_warp)
        mu_s = nodes[l]
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        # the node's r and mu_s corners, and each direction's mu corner, serve all azimuths
        i_r, a_r = radius_corner(r, bottom_radius, top_radius, n_r, grid.radius_warp)
        i_s, a_s = mu_s_corner(mu_s, bottom_radius, top_radius, mu_s_min, grid.sun_angle_share,
                               n_mu_s)
        weights = np.ones(n_t * n_wl)
        profile = np.empty(n_nu * n_t * n_wl)
        value = np.empty(n_wl)
        seen = np.empty(n_wl)
        col_a = np.empty(n_c)
        col_b = np.empty(n_c)
        for a in range(n_a):
            mu_in = math.cos(theta_in[a])
            sin_in = math.sin(theta_in[a])
            hits_ground = ray_intersects_ground(r, mu_in, bottom_radius)
            i_mu, a_mu = mu_axis(r, mu_in, hits_ground, bottom_radius, top_radius, n_mu)
            d = 0.0
            if hits_ground:
                d = _ground_seen(r, mu_in, grid, medium, albedo, col_a, col_b, seen)
            _nu_profile(tables, n_mu, n_mu_s, n_nu, i_r, a_r, i_mu, a_mu, i_s, a_s, profile)
            for p in range(n_p):
                nu_in = min(max(mu_in * mu_s + sin_in * sin_s * math.cos(phi_in[p]), -1.0), 1.0)
                if use_phase:
                    phase_values(phase_table, nu_in, weights)
                i_nu, a_nu = nu_corner(nu_in, mu_in, mu_s, n_nu)
                value[:] = 0.0
                nu_interpolation(profile, weights, i_nu, a_nu, value)
                if hits_ground:
                    _add_ground_radiance(r, mu_s, nu_in, d, seen, ground_irradiance,
                                         bottom_radius, value)
                for w in range(n_wl):
                    radiance[w, a * n_p + p, kl] = value[w]
    return radiance


@njit(parallel=True, cache=True)
def indirect_irradiance(n_r_e, n_mu_s_e, n_theta, n_phi, grid, previous):
    """Irradiance on a horizontal surface from the sky radiance of one order,
    E = int_{mu > 0} L(r, mu, mu_s, nu) mu d omega, on the irradiance nodes (r = R_b + i (R_t -
    R_b) / (n_r_e - 1), mu_s = -1 + 2 j / (n_mu_s_e - 1)); midpoint rule with n_theta polar
    angles in [0, pi/2] and n_phi azimuths in [0, pi] (L is even in the azimuth); L from
    `previous` (a `LitOrder`) on the axes of `grid` (a `TableGrid`). Returns (n_r_e, n_mu_s_e,
    n_wl). Bruneton 2017, `ComputeIndirectIrradiance`."""
    n_r, n_mu, n_mu_s, n_nu = grid.n_r, grid.n_mu, grid.n_mu_s, grid.n_nu
    bottom_radius, top_radius, mu_s_min = grid.bottom_radius, grid.top_radius, grid.mu_s_min
    tables, n_t = previous.tables, previous.n_t
    use_phase, phase_table = previous.use_phase, previous.phase_table
    n_wl = phase_table.shape[2]
    out = np.zeros((n_r_e, n_mu_s_e, n_wl))
    d_theta = 0.5 * math.pi / n_theta
    d_phi = math.pi / n_phi
    for node in prange(n_r_e * n_mu_s_e):
        i = node // n_mu_s_e
        j = node % n_mu_s_e
        r, mu_s = irradiance_r_mu_s_from_x(j / (n_mu_s_e - 1), i / (n_r_e - 1), bottom_radius,
                                           top_radius)
        sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
        weights = np.ones(n_t * n_wl)
        profile = np.empty(n_nu * n_t * n_wl)
        value = np.empty(n_wl)
        i_r, a_r = radius_corner(r, bottom_radius, top_radius, n_r, grid.radius_warp)
        i_s, a_s = mu_s_corner(mu_s, bottom_radius, top_radius, mu_s_min, grid.sun_angle_share,
                               n_mu_s)
        for a in range(n_theta):
            theta = (a + 0.5) * d_theta
            mu_in = math.cos(theta)
            sin_in = math.sin(theta)
            solid = 2.0 * mu_in * sin_in * d_theta * d_phi  # x 2: the mirrored half
            i_mu, a_mu = mu_axis(r, mu_in, False, bottom_radius, top_radius, n_mu)
            # the azimuths of one zenith angle share their r, mu and mu_s corners
            _nu_profile(tables, n_mu, n_mu_s, n_nu, i_r, a_r, i_mu, a_mu, i_s, a_s, profile)
            for p in range(n_phi):
                phi = (p + 0.5) * d_phi
                nu_in = min(max(mu_in * mu_s + sin_in * sin_s * math.cos(phi), -1.0), 1.0)
                if use_phase:
                    phase_values(phase_table, nu_in, weights)
                i_nu, a_nu = nu_corner(nu_in, mu_in, mu_s, n_nu)
                value[:] = 0.0
                nu_interpolation(profile, weights, i_nu, a_nu, value)
                for w in range(n_wl):
                    out[i, j, w] += value[w] * solid
    return out


@njit(cache=True)
def _linear_slab(source, k, a_r, o, a_th, slab):
    """slab[:] = the source (n_r, n_theta, n_block) bilinear at fractional radius index
    k + a_r and view zenith index o + a_th."""
    c00 = np.float32((1.0 - a_r) * (1.0 - a_th))
    c01 = np.float32((1.0 - a_r) * a_th)
    c10 = np.float32(a_r * (1.0 - a_th))
    c11 = np.float32(a_r * a_th)
    block00 = source[k, o]
    block01 = source[k, o + 1]
    block10 = source[k + 1, o]
    block11 = source[k + 1, o + 1]
    for q in range(slab.size):
        slab[q] = c00 * block00[q] + c01 * block01[q] + c10 * block10[q] + c11 * block11[q]


@njit(cache=True)
def _cubic_slab(source, k, a_r, o, a_th, slab):
    """slab[:] = the source (n_r, n_theta, n_block) at fractional radius index k + a_r
    (`radius_taps`) and view zenith index o + a_th (linear), clipped at 0 (a cubic can undershoot
    where the source falls steeply, at a cloud's edge)."""
    last = source.shape[0] - 1
    k0, w0, w1, w2, w3 = radius_taps(k, a_r, last + 1)
    # the taps past the axis's end have weight 0 (`radius_taps`): any node will do
    k2, k3 = min(k0 + 2, last), min(k0 + 3, last)
    low, high = np.float32(1.0 - a_th), np.float32(a_th)
    c0, c1, c2, c3 = np.float32(w0), np.float32(w1), np.float32(w2), np.float32(w3)
    s0l, s0h = source[k0, o], source[k0, o + 1]
    s1l, s1h = source[k0 + 1, o], source[k0 + 1, o + 1]
    s2l, s2h = source[k2, o], source[k2, o + 1]
    s3l, s3h = source[k3, o], source[k3, o + 1]
    for q in range(slab.size):
        value = (c0 * (low * s0l[q] + high * s0h[q]) + c1 * (low * s1l[q] + high * s1h[q])
                 + c2 * (low * s2l[q] + high * s2h[q]) + c3 * (low * s3l[q] + high * s3h[q]))
        slab[q] = max(value, np.float32(0.0))


@njit(cache=True, error_model="numpy")
def _slab_corners(r_ratio, t_ratio, mu_t, cell_mu_s, cell_nu, n_mu_s, n_phi, n_wl, mapping,
                  corner, weights):
    """For every cell (mu_s, nu) of a ray (cell_mu_s, cell_nu (n_cells,)), where its sample
    at r_j = r / r_ratio, t = t_ratio r_j, view zenith cosine mu_t reads the (mu_s, phi) slab
    of `multiple_scattering_table`: the slab offset of the lower corner (corner (n_cells,))
    and the bilinear weights of the four corners (weights (4, n_cells)). The sun's zenith
    cosine at the sample is (r mu_s + t nu) / r_j, its azimuth from the view's vertical plane
    phi = acos((nu - mu_t mu_s_j) / (sin_t sin_s_j)). `mapping`: (R_b, R_t, mu_s_min, d_min,
    d_max, A, sun_angle_share) (`scattering_u_mu_s_from_constants`). A loop without calls
    that do not inline, so that it vectorises: it is most of this kernel's work."""
    bottom_radius, top_radius, mu_s_min = mapping[0], mapping[1], mapping[2]
    d_min, d_max, big_a, share = mapping[3], mapping[4], mapping[5], mapping[6]
    sin_t = math.sqrt(max(1.0 - mu_t * mu_t, 0.0))
    size = float(n_mu_s)  # an integer's division by it would keep the loop from vectorising
    for c in range(cell_mu_s.size):
        nu = cell_nu[c]
        mu_s_j = min(max(r_ratio * cell_mu_s[c] + t_ratio * nu, -1.0), 1.0)
        l, a_l = linear_axis(texel_index(scattering_u_mu_s_from_constants(
            mu_s_j, bottom_radius, top_radius, mu_s_min, d_min, d_max, big_a, share, size),
            n_mu_s), n_mu_s)
        denominator = sin_t * math.sqrt(max(1.0 - mu_s_j * mu_s_j, 0.0))
        cos_phi = min(max((nu - mu_t * mu_s_j) / max(denominator, 1e-12), -1.0), 1.0)
        cos_phi = cos_phi if denominator > 1e-12 else 1.0
        m, a_m = linear_axis(fast_acos(cos_phi) / math.pi * (n_phi - 1), n_phi)
        corner[c] = (l * n_phi + m) * n_wl
        weights[0, c] = (1.0 - a_l) * (1.0 - a_m)
        weights[1, c] = (1.0 - a_l) * a_m
        weights[2, c] = a_l * (1.0 - a_m)
        weights[3, c] = a_l * a_m


@njit(parallel=True, cache=True)
def multiple_scattering_table(grid, medium, n_samples, scattering, source, n_phi):
    """One order of multiple scattering: int_0^d T(x, p) J(p, v) dt for every cell, with
    J(p, v) = beta_s(p) S(r, theta, mu_s, phi): beta_s(p) = sum_c n_c(p) scattering[c] the
    scattering coefficient at the samples (weighed in by `_ray_weights`), S the source
    function J / beta_s interpolated
    in `source` (n_r, n_theta, n_mu_s * n_phi * n_wl) (r, mu_s on the scattering-table nodes;
    theta = view zenith and phi = azimuth from the sun on regular grids over [0, pi]). For each
    ray sample the (r, theta) interpolation is done once, to a (mu_s, phi) slab shared by the
    n_mu_s x n_nu cells of the ray. Returns (n_r, n_mu, n_mu_s, n_nu, n_wl) float32.
    Bruneton 2017, `ComputeMultipleScattering`. `grid`: a `TableGrid`, `medium`: a
    `RayMedium`."""
    n_r, n_mu, n_mu_s, n_nu = grid.n_r, grid.n_mu, grid.n_mu_s, grid.n_nu
    bottom_radius, top_radius, mu_s_min = grid.bottom_radius, grid.top_radius, grid.mu_s_min
    n_wl = medium.extinction.shape[1]
    n_theta = source.shape[1]
    n_block = source.shape[2]
    table = np.zeros((n_r, n_mu, n_mu_s, n_nu, n_wl), dtype=np.float32)
    nodes = mu_s_nodes(grid)
    n_cells = n_mu_s * n_nu
    d_min, d_max, big_a = mu_s_mapping_constants(bottom_radius, top_radius, mu_s_min)
    mapping = np.array([bottom_radius, top_radius, mu_s_min, d_min, d_max, big_a,
                        grid.sun_angle_share])
    for row in prange(n_r * n_mu):
        i_r = row // n_mu
        i_mu = row % n_mu
        r, mu, total, t, radius, mu_t, dens, _, view, _ = _table_ray(
            i_r, i_mu, n_samples, grid, medium, scattering[None])
        if total == 0:
            continue
        cell_mu_s = np.empty(n_cells)
        cell_nu_flat = np.empty(n_cells)
        for c in range(n_cells):
            cell_mu_s[c] = nodes[c // n_nu]
            cell_nu_flat[c] = cell_nu(mu, cell_mu_s[c], c % n_nu, n_nu)
        # float32 sums, as the source and the table are: twice the numbers per vector
        # instruction of float64 (a ray's ~32-64 terms round to ~1e-6 of their sum)
        acc = np.zeros((n_cells, n_wl), dtype=np.float32)
        view_j = np.empty(n_wl, dtype=np.float32)
        slab = np.empty(n_block, dtype=np.float32)
        corner = np.empty(n_cells, dtype=np.int64)
        weights = np.empty((4, n_cells))
        for j in range(total):
            k, a_r = linear_axis(texel_index(scattering_u_r(radius[j], bottom_radius, top_radius,
                                                      n_r, grid.radius_warp), n_r), n_r)
            o, a_th = linear_axis(math.acos(mu_t[j]) / math.pi * (n_theta - 1), n_theta)
            if grid.cubic_source:
                _cubic_slab(source, k, a_r, o, a_th, slab)
            else:
                _linear_slab(source, k, a_r, o, a_th, slab)
            _slab_corners(r / radius[j], t[j] / radius[j], mu_t[j], cell_mu_s, cell_nu_flat,
                          n_mu_s, n_phi, n_wl, mapping, corner, weights)
            for w in range(n_wl):
                view_j[w] = view[0, j, w]
            for c in range(n_cells):
                b00 = corner[c]
                b01 = b00 + n_wl
                b10 = b00 + n_phi * n_wl
                b11 = b10 + n_wl
                w00 = np.float32(weights[0, c])
                w01 = np.float32(weights[1, c])
                w10 = np.float32(weights[2, c])
                w11 = np.float32(weights[3, c])
                # row views: their loop over w indexes from 0, which spares numba's
                # negative-index checks and lets it vectorise (1.7x this kernel)
                s00 = slab[b00:b00 + n_wl]
                s01 = slab[b01:b01 + n_wl]
                s10 = slab[b10:b10 + n_wl]
                s11 = slab[b11:b11 + n_wl]
                acc_cell = acc[c]
                for w in range(n_wl):
                    acc_cell[w] += view_j[w] * (w00 * s00[w] + w01 * s01[w]
                                                + w10 * s10[w] + w11 * s11[w])
        for c in range(n_cells):
            for w in range(n_wl):
                table[i_r, i_mu, c // n_nu, c % n_nu, w] = acc[c, w]
    return table


@njit(cache=True)
def order_statistics(tables, use_phase, phase_table, grid):
    """(mean over all cells, value at the ground looking at the zenith with the sun there) of
    the radiance of one order [W m^-2 sr^-1 nm^-1], each (n_wl,), from interleaved tables
    (n_r, n_mu, n_mu_s, n_nu, n_t, n_wl) on `grid` (a `TableGrid`); with phase functions
    applied (`use_phase`) for the single-scattering tables."""
    bottom_radius, top_radius = grid.bottom_radius, grid.top_radius
    n_r, n_mu, n_mu_s, n_nu, n_t, n_wl = tables.shape
    partial = np.zeros((n_r, n_wl))
    nodes = mu_s_nodes(grid)
    for i_r in range(n_r):
        r = scattering_r_from_u((i_r + 0.5) / n_r, bottom_radius, top_radius, n_r,
                                grid.radius_warp)
        weights = np.ones(n_t * n_wl)
        for i_mu in range(n_mu):
            mu, _ = scattering_mu_from_u((i_mu + 0.5) / n_mu, r, bottom_radius, top_radius,
                                         n_mu)
            for i_s in range(n_mu_s):
                mu_s = nodes[i_s]
                for i_nu in range(n_nu):
                    nu = cell_nu(mu, mu_s, i_nu, n_nu)
                    if use_phase:
                        phase_values(phase_table, nu, weights)
                    for t in range(n_t):
                        for w in range(n_wl):
                            partial[i_r, w] += (weights[t * n_wl + w]
                                                * tables[i_r, i_mu, i_s, i_nu, t, w])
    mean = partial.sum(axis=0) / (n_r * n_mu * n_mu_s * n_nu)
    weights = np.ones(n_t * n_wl)
    if use_phase:
        phase_values(phase_table, 1.0, weights)
    zenith = np.zeros(n_wl)
    for t in range(n_t):
        for w in range(n_wl):
            zenith[w] += weights[t * n_wl + w] * tables[0, n_mu // 2, n_mu_s - 1, n_nu - 1, t, w]
    return mean, zenith
