"""Numba kernels that look the precomputed tables up at run time (`transport/lut_solver.py`):
sky radiance along rays, transmittance, aerial perspective, the radiance of lit surfaces and
ground irradiance, with single scattering ray-marched through the sunlit part of each view ray
in twilight (`lit_single_scattering`, and its per-observer view table). None of this code
changes the tables, so it is outside their cache key (`transport/code_fingerprint.py`); the
kernels that build the tables live in `_table_build_kernels`, the helpers of both in
`_table_common_kernels`.

Conventions (docs/physics/tables.md, Bruneton 2017 functions.glsl; the table layout in
`_table_common_kernels`):
- Transmittances come from the transmittance table (n_r_t, n_mu_t, n_wl): to the top by one
  bilinear lookup, between two points of a ray as the ratio of two (`transmittance_along`).
- Observers in space are moved to the top boundary along each ray first (`_enter_atmosphere`);
  rays that miss the atmosphere see nothing.
- The parallel loops give each block of RAYS_PER_BLOCK rays its own scratch arrays.
Kernels take arrays and floats only.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from skyscatter.transport._kernels import density_at, sun_cosines
from skyscatter.transport._table_common_kernels import (
    corner_sum,
    fast_acos,
    linear_axis,
    mu_axis,
    mu_axis_from_u,
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
    horizon_zenith_angle,
    irradiance_x_from_r_mu_s,
    ray_intersects_ground,
    scattering_mu_from_u,
    scattering_u_mu_of_angle,
    transmittance_x_from_r_mu,
    transmittance_x_mu,
    transmittance_x_r,
    view_sun_azimuth,
    view_sun_cos_azimuth,
)

RAYS_PER_BLOCK = 64  # rays that share scratch arrays in the parallel loops of the lookups


class LookupTables(NamedTuple):
    """What the lookups read besides the rays, as one record (numba passes it as a typed
    tuple): the tables of an `AtmosphereTables` and the profile arrays of the twilight march.
    Flat (no tuple fields), so that a parallel loop can pass it to the per-ray helpers: numba's
    parfors take no nested tuple into a `prange` body."""

    bottom_radius: float  # R_b [m]
    top_radius: float  # R_t [m]
    mu_s_min: float  # smallest cos(sun zenith) tabulated [-]
    sun_angle_share: float  # of the mu_s axis (table_parameterisation.scattering_u_mu_s)
    scattering: np.ndarray  # the interleaved scattering tables, 1-D (`flat_tables`)
    n_r: int  # the sizes (n_r, n_mu, n_mu_s, n_nu) of the scattering tables
    n_mu: int
    n_mu_s: int
    n_nu: int
    radius_warp: np.ndarray  # the u_r axis's warp (table_parameterisation.scattering_u_r)
    # (n_s + n_c, n_angle, n_wl) [sr^-1]: the phase function of each table before the orders
    # >= 2, those of the single scattering then of the peak corrections (`tables.lookup_phase`)
    phase_table: np.ndarray
    transmittance: np.ndarray  # (n_r_t, n_mu_t, n_wl) to the top [-]
    irradiance: np.ndarray  # (n_r_e, n_mu_s_e, n_wl) indirect irradiance [W m^-2 nm^-1]
    sun_irradiance: np.ndarray  # (n_wl,) E_sun at the top [W m^-2 nm^-1]
    sun_angular_radius: float  # [rad]
    h_step: float  # spacing of the profile's levels [m]
    density: np.ndarray  # (n_c, n_z) profile densities on those levels
    scatterers: np.ndarray  # (n_s,) int64: the constituents that scatter
    single_factor: np.ndarray  # (n_s, n_wl) E_sun beta_s per density
    slant_depth: np.ndarray  # (n_r_t, n_mu_t, n_wl) -ln(transmittance) to the top [-]
    peak_depth: np.ndarray  # (n_r_t, n_mu_t, n_wl) the particles' peak depth to the top [-]
    aureole_shape: np.ndarray  # (n_x, n_psi, n_wl) multiple peak scattering [sr^-1]
    aureole_blur: np.ndarray  # (n_x, n_psi, n_wl) the peaks' blur of smooth light [sr^-1]
    aureole_x_max: float  # largest peak depth of aureole_shape [-]
    aureole_psi_max: float  # its largest angle from the sun [rad]; 0: no aureole


@njit(cache=True)
def lookup_scratch(n_t, n_wl):
    """(weights, pair_values) for `scattering_lookup` of n_t tables of n_wl wavelengths:
    weights 1 (for the tables without a phase function), the other scratch."""
    return np.ones(n_t * n_wl), np.empty(2 * n_t * n_wl)


@njit(cache=True)
def scattering_lookup(flat, n_mu, n_mu_s, n_nu, weights, i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu,
                      a_nu, pair_values, out):
    """out[w] += sum_t weights[t n_wl + w] * table_t(w) interpolated at the corners of
    `scattering_corners`.

    `flat` is the interleaved table (n_r, n_mu, n_mu_s, n_nu, n_t, n_wl) as a 1-D view
    (`flat_tables`): for each (r, mu, mu_s) corner the two nu slices and all tables and
    wavelengths are 2 n_t n_wl contiguous numbers, read in one loop (`corner_sum`) into the
    scratch array pair_values (2 n_t n_wl), then interpolated in nu (`nu_interpolation`)."""
    m = weights.size
    s_s = n_nu * m
    s_mu = n_mu_s * s_s
    s_r = n_mu * s_mu
    pair_values[:] = 0.0
    corner_sum(flat, i_r * s_r + i_mu * s_mu + i_s * s_s + i_nu * m, s_r, s_mu, s_s, a_r,
               a_mu, a_s, pair_values)
    nu_interpolation(pair_values, weights, 0, a_nu, out)


@njit(cache=True)
def scattering_corners(r, mu, mu_s, nu, hits_ground, bottom_radius, top_radius, mu_s_min,
                       sun_angle_share, n_r, n_mu, n_mu_s, n_nu, radius_warp):
    """Lower entries and weights (i_r, a_r, i_mu, a_mu, i_mu_s, a_mu_s, i_nu, a_nu) of the
    quadrilinear lookup of (r, mu, mu_s, nu) in a scattering table. The mu interpolation stays
    inside the half chosen by `hits_ground`."""
    i_r, a_r = radius_corner(r, bottom_radius, top_radius, n_r, radius_warp)
    i_mu, a_mu = mu_axis(r, mu, hits_ground, bottom_radius, top_radius, n_mu)
    i_s, a_s = mu_s_corner(mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share, n_mu_s)
    i_nu, a_nu = nu_corner(nu, mu, mu_s, n_nu)
    return i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu


# --------------------------------------------------------------------------------------------
# Transmittance, and observers in space
# --------------------------------------------------------------------------------------------

@njit(cache=True)
def transmittance_in_row(transmittance, i, a, x_mu, out):
    """`transmittance_to_top` with the r part (row i, weight a, from `transmittance_x_r`)
    done by the caller: bilinear at (i + a, x_mu (n_mu_t - 1)), into out (n_wl,)."""
    j, b = linear_axis(x_mu * (transmittance.shape[1] - 1), transmittance.shape[1])
    transmittance_bilinear(transmittance, i, a, j, b, out)


@njit(cache=True)
def transmittance_to_top(r, mu, bottom_radius, top_radius, transmittance, out):
    """Transmittance from (r, mu) to the top, bilinear in `transmittance` (n_r_t, n_mu_t,
    n_wl), into out (n_wl,) (Bruneton 2017, `GetTransmittanceToTopAtmosphereBoundary`)."""
    x_mu, x_r = transmittance_x_from_r_mu(r, mu, bottom_radius, top_radius)
    i, a = linear_axis(x_r * (transmittance.shape[0] - 1), transmittance.shape[0])
    transmittance_in_row(transmittance, i, a, x_mu, out)


@njit(cache=True)
def transmittance_along(r, mu, d, hits_ground, bottom_radius, top_radius, transmittance, out,
                        scratch):
    """Transmittance over the distance d along the ray (r, mu), into out (n_wl,): the ratio of
    two lookups, capped at 1 (Bruneton 2017, `GetTransmittance`); rays that hit the ground use
    the upward rays -mu at both ends."""
    r_d = math.sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0))
    r_d = min(max(r_d, bottom_radius), top_radius)
    mu_d = min(max((r * mu + d) / r_d, -1.0), 1.0)
    if hits_ground:
        transmittance_to_top(r_d, -mu_d, bottom_radius, top_radius, transmittance, out)
        transmittance_to_top(r, -mu, bottom_radius, top_radius, transmittance, scratch)
    else:
        transmittance_to_top(r, mu, bottom_radius, top_radius, transmittance, out)
        transmittance_to_top(r_d, mu_d, bottom_radius, top_radius, transmittance, scratch)
    for w in range(out.size):
        out[w] = min(out[w] / scratch[w], 1.0) if scratch[w] > 0.0 else 0.0


@njit(cache=True)
def _enter_atmosphere(ox, oy, oz, dx, dy, dz, top_radius):
    """Move an observer in space to the top boundary along the ray (Bruneton 2017,
    `GetSkyRadiance`): (x, y, z, travelled distance, inside) with inside False when the ray
    misses the atmosphere; also for a ray that leaves from the top itself (r = top, not
    pointing down: no length inside, as in `geometry.atmosphere_segment`)."""
    r = math.sqrt(ox * ox + oy * oy + oz * oz)
    r_mu = ox * dx + oy * dy + oz * dz
    if r < top_radius or (r == top_radius and r_mu < 0.0):
        return ox, oy, oz, 0.0, True
    discriminant = r_mu * r_mu - r * r + top_radius * top_radius
    if r_mu >= 0.0 or discriminant < 0.0:
        return ox, oy, oz, 0.0, False
    d = -r_mu - math.sqrt(discriminant)
    return ox + d * dx, oy + d * dy, oz + d * dz, d, True


# --------------------------------------------------------------------------------------------
# Twilight: single scattering ray-marched at lookup time, the orders >= 2 interpolated
# geometrically in mu_s
# --------------------------------------------------------------------------------------------

# Sun zenith cosines between which the lookups go over from the single-scattering table to
# `lit_single_scattering` (smoothstep in mu_s): the table by day (median error 0.05 %), the
# march once the sun nears the horizon, where interpolating the table in mu_s across the
# terminator leaks light into the planet's shadow (docs/physics/tables.md, "Twilight").
EXACT_SINGLE_FROM_COS = math.cos(math.radians(85.0))
EXACT_SINGLE_TO_COS = math.cos(math.radians(90.0))
# Samples of each sunlit piece of a view ray (`lit_single_scattering`); 32 keep the order-1
# radiance within ~0.3 % of a 256-sample ray march (tests/transport/test_transport_tables.py).
EXACT_SINGLE_SAMPLES = 16


@njit(cache=True)
def exact_single_weight(mu_s):
    """Share [0, 1] of single scattering taken from `lit_single_scattering` rather than from
    the table at the ray's start, cos(sun zenith) mu_s [-]: 0 above EXACT_SINGLE_FROM_COS, 1
    below EXACT_SINGLE_TO_COS, smoothstep between (continuous with its derivative, so a
    time-lapse shows no switch)."""
    x = (EXACT_SINGLE_FROM_COS - mu_s) / (EXACT_SINGLE_FROM_COS - EXACT_SINGLE_TO_COS)
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


@njit(cache=True)
def geometric_mu_s_correction(flat, n_mu, n_mu_s, n_nu, weights, first, i_r, a_r, i_mu, a_mu,
                              i_s, a_s, i_nu, a_nu, share, slices, out):
    """out[w] += share * (geometric - linear interpolation in mu_s) of the tables of the
    interleaved `flat` from table `first` on (the peak corrections and the orders >= 2),
    summed with their `weights` (as `scattering_lookup`'s), at the corners of
    `scattering_corners`; slices (2, n_wl) is scratch.

    In twilight the orders >= 2 fall by a factor of 3-10 from one mu_s cell to the next (the
    lit air recedes), and linear interpolation between the cells overestimates them by up to
    the ratio's arithmetic / geometric mean; v0^(1 - a) v1^a follows an exponential decay
    exactly. The two mu_s slices are each interpolated linearly in (r, mu, nu), as
    `scattering_lookup` does; `share` (`exact_single_weight`) blends it in as the sun sets,
    so daytime lookups are unchanged."""
    n_wl = out.size
    m = weights.size
    s_nu = m
    s_s = n_nu * s_nu
    s_mu = n_mu_s * s_s
    s_r = n_mu * s_mu
    slices[:, :] = 0.0
    base = i_r * s_r + i_mu * s_mu + i_s * s_s + i_nu * s_nu
    for dr in range(2):
        wr = a_r if dr == 1 else 1.0 - a_r
        for dm in range(2):
            wm = wr * (a_mu if dm == 1 else 1.0 - a_mu)
            if wm == 0.0:
                continue
            for ds in range(2):
                offset = base + dr * s_r + dm * s_mu + ds * s_s
                for k in range(first * n_wl, m):
                    slices[ds, k % n_wl] += wm * weights[k] * (
                        (1.0 - a_nu) * flat[offset + k] + a_nu * flat[offset + m + k])
    for w in range(n_wl):
        v0 = slices[0, w]
        v1 = slices[1, w]
        if v0 > 0.0 and v1 > 0.0:
            linear = (1.0 - a_s) * v0 + a_s * v1
            geometric = math.exp((1.0 - a_s) * math.log(v0) + a_s * math.log(v1))
            out[w] += share * (geometric - linear)


@njit(cache=True)
def _cylinder_roots(r, mu, mu_s, nu, radius):
    """(t_1, t_2, found): distances along the ray (r, mu) where the distance of the point
    from the planet-sun axis, q(t)^2 = |p|^2 - (p . s)^2 with p . s = r mu_s + t nu and
    |p|^2 = r^2 + 2 r mu t + t^2, equals `radius` [m]: (1 - nu^2) t^2 + 2 r (mu - mu_s nu) t
    + r^2 (1 - mu_s^2) - radius^2 = 0. found is False when q > radius all along the ray; a
    ray parallel to the axis is inside for all t when q < radius (t_1 = -inf, t_2 = inf)."""
    a = 1.0 - nu * nu
    b = r * (mu - mu_s * nu)
    c = r * r * (1.0 - mu_s * mu_s) - radius * radius
    if a <= 1e-12:
        if c < 0.0:
            return -math.inf, math.inf, True
        return 0.0, 0.0, False
    discriminant = b * b - a * c
    if discriminant <= 0.0:
        return 0.0, 0.0, False
    root = math.sqrt(discriminant)
    return (-b - root) / a, (-b + root) / a, True


@njit(cache=True)
def shadow_interval(r, mu, mu_s, nu, bottom_radius, sun_angular_radius):
    """(t_a, t_b) [m]: the distances along the ray (r, mu) (sun zenith cosine mu_s, view-sun
    cosine nu at its start) where no part of the sun disk is above the horizon, the planet's
    umbra; empty when t_a >= t_b.

    For a point sun the shadow is the half-cylinder {p . s < 0, q < R_b} behind the planet
    (q the distance from the planet-sun axis; `_cylinder_roots`). The top limb of a disk of
    angular radius alpha stays above the horizon while q cos alpha - (p . s) sin alpha > R_b
    (psi = sun zenith - alpha, r sin psi = q cos alpha - (p . s) sin alpha, and the limb sets
    when r sin psi = R_b), so each end of the interval is moved inwards to the cylinder of
    radius (R_b - |p . s| sin alpha) / cos alpha, with p . s taken at the end (two fixed-point
    steps from the point-sun end, where `sun_visible_fraction` = 1/2)."""
    t_1, t_2, found = _cylinder_roots(r, mu, mu_s, nu, bottom_radius)
    if not found:
        return 0.0, 0.0
    # behind the planet: p . s = r mu_s + t nu < 0
    lo, hi = t_1, t_2
    if nu > 0.0:
        hi = min(hi, -r * mu_s / nu)
    elif nu < 0.0:
        lo = max(lo, -r * mu_s / nu)
    elif mu_s >= 0.0:
        return 0.0, 0.0
    if lo >= hi:
        return 0.0, 0.0
    sin_alpha = math.sin(sun_angular_radius)
    cos_alpha = math.cos(sun_angular_radius)
    if sin_alpha > 0.0:
        if lo == t_1 and math.isfinite(lo):
            end = lo
            for _ in range(2):  # |p . s| at the moved end, once more
                shrunk = (bottom_radius - abs(r * mu_s + end * nu) * sin_alpha) / cos_alpha
                end, _, inside = _cylinder_roots(r, mu, mu_s, nu, shrunk)
                if not inside:
                    return 0.0, 0.0
            lo = max(lo, end)
        if hi == t_2 and math.isfinite(hi):
            end = hi
            for _ in range(2):
                shrunk = (bottom_radius - abs(r * mu_s + end * nu) * sin_alpha) / cos_alpha
                _, end, inside = _cylinder_roots(r, mu, mu_s, nu, shrunk)
                if not inside:
                    return 0.0, 0.0
            hi = min(hi, end)
    return lo, hi


@njit(cache=True)
def _piece_distances(t_0, t_1, dense_at_start, n_samples, out):
    """n_samples + 1 distances from t_0 to t_1 into out, crowded quadratically at t_0
    (`dense_at_start`) or at t_1: the shadow's edge of a sunlit piece of a view ray."""
    length = t_1 - t_0
    for k in range(n_samples + 1):
        if dense_at_start:
            out[k] = t_0 + length * (k / n_samples) ** 2
        else:
            out[k] = t_1 - length * ((n_samples - k) / n_samples) ** 2
    out[n_samples] = t_1


@njit(cache=True)
def _lit_piece(r, mu, mu_s, nu, samples, total, hits_ground, bottom_radius, top_radius,
               sun_angular_radius, h_step, density, scatterers, transmittance, observer, here,
               sun, dens, out):
    """out[s, w] += int T(x, p) n_s(p) T_sun(p) V(p) dt, trapezoid rule on the `total`
    increasing distances `samples` along the ray (r, mu). observer (n_wl,): T from the ray's
    start to the top (along -mu for rays that hit the ground); the others are scratch. T(x, p)
    is the ratio of two transmittance lookups, as in `transmittance_along` (the observer's
    half hoisted out of the loop); T_sun as in `single_scattering_table`."""
    n_wl = out.shape[1]
    n_r_t = transmittance.shape[0]
    # the whole disk is up when mu_s >= mu_h + sun_clear (as in `single_scattering_table`)
    sun_clear = sun_angular_radius * (1.0 + 0.5 * sun_angular_radius)
    for k in range(total):
        t = samples[k]
        weight = 0.5 * ((t - samples[k - 1] if k > 0 else 0.0)
                        + (samples[k + 1] - t if k < total - 1 else 0.0))
        if weight <= 0.0:
            continue
        r_p = math.sqrt(max(r * r + 2.0 * r * mu * t + t * t, 0.0))
        r_p = min(max(r_p, bottom_radius), top_radius)
        mu_p = min(max((r * mu + t) / r_p, -1.0), 1.0)
        mu_s_p = min(max((r * mu_s + t * nu) / r_p, -1.0), 1.0)
        mu_h = horizon_cos_zenith(r_p, bottom_radius)
        visible = 1.0
        if mu_s_p < mu_h + sun_clear:
            visible = sun_visible_fraction(r_p, mu_s_p, bottom_radius, sun_angular_radius)
            if visible <= 0.0:
                continue
        # both lookups at r_p share the r part (`transmittance_to_top` in two halves)
        x_r, d_min, d_max = transmittance_x_r(r_p, bottom_radius, top_radius)
        row, a_row = linear_axis(x_r * (n_r_t - 1), n_r_t)
        transmittance_in_row(transmittance, row, a_row, transmittance_x_mu(
            r_p, max(mu_s_p, mu_h), top_radius, d_min, d_max), sun)
        density_at(r_p - bottom_radius, h_step, density, dens)
        transmittance_in_row(transmittance, row, a_row, transmittance_x_mu(
            r_p, -mu_p if hits_ground else mu_p, top_radius, d_min, d_max), here)
        if hits_ground:
            for w in range(n_wl):
                here[w] = min(here[w] / observer[w], 1.0) if observer[w] > 0.0 else 0.0
        else:
            for w in range(n_wl):
                here[w] = min(observer[w] / here[w], 1.0) if here[w] > 0.0 else 0.0
        for w in range(n_wl):
            here[w] *= sun[w] * visible * weight
        for s in range(scatterers.size):
            n_s = dens[scatterers[s]]
            for w in range(n_wl):
                out[s, w] += n_s * here[w]


@njit(cache=True)
def lit_single_scattering(r, mu, mu_s, nu, d, hits_ground, bottom_radius, top_radius,
                          sun_angular_radius, n_samples, h_step, density, scatterers,
                          transmittance, samples, observer, here, sun, dens, out):
    """Single scattering without phase function along the view ray (r, mu) up to distance d
    [m] (the ground or the top), out (n_s, n_wl) = int_0^d T(x, p) n_s(p) T_sun(p) V(p) dt
    [density m], ray-marched over the parts of the ray outside the planet's umbra only
    (`shadow_interval`): up to two pieces of n_samples intervals each, densest at the
    shadow's edge, where a twilight sky gets its light; a ray without umbra is sampled as a
    table ray (`table_ray_distances`). The integrand is that of `single_scattering_table`,
    with T_sun and T(x, p) from the transmittance table and the densities of the profile
    (`_kernels.density_at`). Radiance = sum_s p_s(nu) E_sun beta_s,s out[s]. samples
    (n_samples + 8,), observer, here, sun (n_wl,) and dens (n_c,) are scratch."""
    out[:, :] = 0.0
    if d <= 0.0:
        return
    if hits_ground:
        transmittance_to_top(r, -mu, bottom_radius, top_radius, transmittance, observer)
    else:
        transmittance_to_top(r, mu, bottom_radius, top_radius, transmittance, observer)
    t_a, t_b = shadow_interval(r, mu, mu_s, nu, bottom_radius, sun_angular_radius)
    if t_a >= t_b or t_b <= 0.0 or t_a >= d:  # no umbra on [0, d]: one piece
        total = table_ray_distances(r, mu, d, hits_ground, n_samples, samples)
        _lit_piece(r, mu, mu_s, nu, samples, total, hits_ground, bottom_radius, top_radius,
                   sun_angular_radius, h_step, density, scatterers, transmittance, observer,
                   here, sun, dens, out)
        return
    if t_a > 0.0:
        _piece_distances(0.0, t_a, False, n_samples, samples)
        _lit_piece(r, mu, mu_s, nu, samples, n_samples + 1, hits_ground, bottom_radius,
                   top_radius, sun_angular_radius, h_step, density, scatterers, transmittance,
                   observer, here, sun, dens, out)
    if t_b < d:
        _piece_distances(max(t_b, 0.0), d, True, n_samples, samples)
        _lit_piece(r, mu, mu_s, nu, samples, n_samples + 1, hits_ground, bottom_radius,
                   top_radius, sun_angular_radius, h_step, density, scatterers, transmittance,
                   observer, here, sun, dens, out)


# The view table of `single_scattering_view_table`: view zenith on the scattering table's mu
# mapping (`scattering_mu_from_u`), the azimuth from the sun's vertical plane uniform.
VIEW_TABLE_MU = 256
VIEW_TABLE_PHI = 64
# The view table holds log(value): in twilight the light of neighbouring directions differs by
# orders of magnitude, which linear interpolation would smear into the darker one (measured:
# 95th percentile 5 % at sun zenith 96 deg linear, see tests). Values below the floor
# [density m] are 0 for any purpose (an air column of 1e-300 molecules m^-2).
VIEW_TABLE_FLOOR = 1e-300
# `aureole_view_table`: angles from the sun x angles about it; the Poisson law of the peak
# events along the path changes on the scale of degrees (the path's depths), the aureole's shape
# G(x, psi) on the peak's own width, which stays per pixel
AUREOLE_VIEW_PSI = 96
AUREOLE_VIEW_CHI = 65
AUREOLE_LOG_FLOOR = -700.0  # log T' where the path is dark (exp gives 0)


@njit(parallel=True, cache=True)
def single_scattering_view_table(r, mu_s, n_samples, tables):
    """`lit_single_scattering` for every view direction of one observer at radius r [m]
    inside the atmosphere with the sun at zenith cosine mu_s: (VIEW_TABLE_MU, VIEW_TABLE_PHI,
    n_s, n_wl), the logarithm of each value (floored at VIEW_TABLE_FLOOR), on view zenith
    cosines mu on the scattering table's mapping (`scattering_mu_from_u`) x azimuths
    phi = pi k / (VIEW_TABLE_PHI - 1) from the sun's vertical plane,
    nu = mu mu_s + sqrt((1 - mu^2)(1 - mu_s^2)) cos phi. For one
    observer and sun the single scattering depends on (mu, phi) only, so a frame marches
    16 k rays instead of one per pixel and `view_table_lookup` interpolates (the sky-view
    table of Hillaire 2020, "A scalable and production ready sky and atmosphere rendering
    technique", Comput. Graph. Forum 39(4), doi:10.1111/cgf.14050, §5.3).
    `tables`: the `LookupTables` record of the tables and the profile."""
    bottom_radius, top_radius = tables.bottom_radius, tables.top_radius
    sun_angular_radius, h_step, density = tables.sun_angular_radius, tables.h_step, tables.density
    scatterers, transmittance = tables.scatterers, tables.transmittance
    n_s = scatterers.size
    n_wl = transmittance.shape[2]
    table = np.zeros((VIEW_TABLE_MU, VIEW_TABLE_PHI, n_s, n_wl))
    sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
    for i in prange(VIEW_TABLE_MU):
        samples = np.empty(n_samples + 8)
        observer = np.empty(n_wl)
        here = np.empty(n_wl)
        sun = np.empty(n_wl)
        dens = np.empty(density.shape[0])
        mu, hits_ground = scattering_mu_from_u((i + 0.5) / VIEW_TABLE_MU, r, bottom_radius,
                                               top_radius, VIEW_TABLE_MU)
        sin_v = math.sqrt(max(1.0 - mu * mu, 0.0))
        if hits_ground:
            d = distance_to_bottom_boundary(r, mu, bottom_radius)
        else:
            d = distance_to_top_boundary(r, mu, top_radius)
        for k in range(VIEW_TABLE_PHI):
            nu = mu * mu_s + sin_v * sin_s * math.cos(math.pi * k / (VIEW_TABLE_PHI - 1))
            nu = min(max(nu, -1.0), 1.0)
            lit_single_scattering(r, mu, mu_s, nu, d, hits_ground, bottom_radius, top_radius,
                                  sun_angular_radius, n_samples, h_step, density, scatterers,
                                  transmittance, samples, observer, here, sun, dens,
                                  table[i, k])
            for s in range(n_s):
                for w in range(n_wl):
                    table[i, k, s, w] = math.log(max(table[i, k, s, w], VIEW_TABLE_FLOOR))
    return table


@njit(cache=True)
def view_table_lookup(view_table, r, mu, mu_s, nu, hits_ground, bottom_radius, top_radius,
                      out):
    """Lookup of `single_scattering_view_table` for the ray (r, mu, nu) of its observer,
    bilinear in the logarithm (geometric interpolation), into out (n_s, n_wl)."""
    n_mu, n_phi = view_table.shape[0], view_table.shape[1]
    i, a = mu_axis(r, mu, hits_ground, bottom_radius, top_radius, n_mu)
    k, b = linear_axis(view_sun_azimuth(nu, mu, mu_s) / math.pi * (n_phi - 1), n_phi)
    floor = 0.5 * math.log(VIEW_TABLE_FLOOR)  # below it a corner was dark: 0
    for s in range(out.shape[0]):
        for w in range(out.shape[1]):
            out[s, w] = 0.0
            log_value = ((1.0 - a) * ((1.0 - b) * view_table[i, k, s, w]
                                      + b * view_table[i, k + 1, s, w])
                         + a * ((1.0 - b) * view_table[i + 1, k, s, w]
                                + b * view_table[i + 1, k + 1, s, w]))
            if log_value > floor:
                out[s, w] = math.exp(log_value)


@njit(cache=True)
def sky_view_grid_nodes(r, n_mu, n_phi, bottom_radius, top_radius):
    """The view directions of a sky-view grid for an observer at radius r [m], in the
    observer's frame (x towards the sun's azimuth, z up):
    (n_mu, n_phi, 3), view zenith cosines on the scattering table's mapping
    (`scattering_mu_from_u`, each node moved 1e-12 into its side of the horizon so that the
    lookups take the same side) x azimuths phi = pi k / (n_phi - 1) from the sun's."""
    nodes = np.empty((n_mu, n_phi, 3))
    mu_h = horizon_cos_zenith(r, bottom_radius)
    for i in range(n_mu):
        mu, hits_ground = scattering_mu_from_u((i + 0.5) / n_mu, r, bottom_radius, top_radius,
                                               n_mu)
        mu = min(mu, mu_h - 1e-12) if hits_ground else max(mu, mu_h + 1e-12)
        mu = min(max(mu, -1.0), 1.0)
        sin_v = math.sqrt(max(1.0 - mu * mu, 0.0))
        for k in range(n_phi):
            phi = math.pi * k / (n_phi - 1)
            nodes[i, k, 0] = sin_v * math.cos(phi)
            nodes[i, k, 1] = sin_v * math.sin(phi)
            nodes[i, k, 2] = mu
    return nodes


# `exp_by_squaring`: exp(x) as exp(x / 2^EXP_HALVINGS)^(2^EXP_HALVINGS), the inner exponential
# by its Taylor polynomial of degree 9; arguments below EXP_DARKEST give 0
EXP_HALVINGS = 10
EXP_DARKEST = 0.5 * math.log(VIEW_TABLE_FLOOR)


@njit(cache=True, error_model="numpy")
def exp_by_squaring(x):
    """exp(x) for EXP_DARKEST < x <= 50 within 1e-8 relative (within 1e-12 for x >= -40;
    `tests/transport/test_sky_view_grid.py`), 0 below: no call, so loops over it vectorise,
    unlike math.exp (numba has no vector math library). The Taylor remainder of
    y = x / 1024 >= -0.34 is below y^10 / 10! = 5e-12, and squaring 10 times multiplies a
    relative error by 1024."""
    y = x * (1.0 / (1 << EXP_HALVINGS))
    p = 1.0 + y * (1.0 + y * (1.0 / 2.0 + y * (1.0 / 6.0 + y * (1.0 / 24.0 + y * (
        1.0 / 120.0 + y * (1.0 / 720.0 + y * (1.0 / 5040.0 + y * (1.0 / 40320.0 + y * (
            1.0 / 362880.0)))))))))
    for _ in range(EXP_HALVINGS):
        p *= p
    return p if x > EXP_DARKEST else 0.0


@njit(parallel=True, cache=True, error_model="numpy")
def sky_view_grid_lookup(log_grid, up, sun_direction, cos_exact, bottom_radius, r,
                         directions, out, exact):
    """The radiance along `directions` (n_ray, 3) of one observer at radius r [m] (unit
    vertical `up`), interpolated in `log_grid` (n_mu, n_phi, n_wl), the logarithm of the
    radiance at `sky_view_grid_nodes`: bilinear on the table's mu axis (each side of the
    horizon kept to its half, `mu_axis_from_u`) and in the azimuth from the sun, into out
    (n_ray, n_wl). Rays whose cos(angle from the sun) exceeds cos_exact are left to the
    caller: exact[j] = True, out[j] untouched. In blocks of RAYS_PER_BLOCK rays: their grid
    coordinates in one loop, then their radiances, both free of calls that do not inline, so
    that they vectorise (the angles by `fast_acos`, within 2e-8 rad; the exponential by
    `exp_by_squaring`): 3 x faster than one ray at a time with the library's functions."""
    n_mu, n_phi, n_wl = log_grid.shape
    mu_s = up[0] * sun_direction[0] + up[1] * sun_direction[1] + up[2] * sun_direction[2]
    theta_h = horizon_zenith_angle(r, bottom_radius)
    n_rays = directions.shape[0]
    for block in prange((n_rays + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK):
        first = block * RAYS_PER_BLOCK
        count = min(RAYS_PER_BLOCK, n_rays - first)
        i_mu, a_mu, k_phi, b_phi = _grid_block(count)
        dark = np.empty(count, dtype=np.bool_)
        for q in range(count):
            j = first + q
            dx, dy, dz = directions[j, 0], directions[j, 1], directions[j, 2]
            norm = math.sqrt(dx * dx + dy * dy + dz * dz)
            # no direction gives no light, as `sky_radiance_rays`
            dark[q] = not norm > 0.0
            scale = 0.0 if dark[q] else 1.0 / norm
            nu = (dx * sun_direction[0] + dy * sun_direction[1] + dz * sun_direction[2]) * scale
            mu = min(max((dx * up[0] + dy * up[1] + dz * up[2]) * scale, -1.0), 1.0)
            exact[j] = nu > cos_exact and not dark[q]
            i_mu[q], a_mu[q], k_phi[q], b_phi[q] = view_grid_cell(
                mu, nu, mu_s, theta_h, ray_intersects_ground(r, mu, bottom_radius), n_mu, n_phi)
        for q in range(count):
            if dark[q]:
                out[first + q] = 0.0
        _log_bilinear_block(log_grid, first, i_mu, a_mu, k_phi, b_phi,
                            exact[first:first + count] | dark, out)


@njit(cache=True, inline="always")
def view_grid_cell(mu, nu, mu_s, theta_h, hits_ground, n_mu, n_phi):
    """(i_mu, a_mu, k_phi, b_phi): the cell of the view (mu, nu) on a grid of
    `sky_view_grid_nodes` (n_mu, n_phi) with the sun at zenith cosine mu_s and the horizon at
    zenith angle theta_h [rad]: lower entries and weights on its mu axis (each side of the
    horizon kept to its half) and its azimuth axis (angles by `fast_acos`, so that loops over
    it vectorise)."""
    i_mu, a_mu = mu_axis_from_u(scattering_u_mu_of_angle(fast_acos(mu), theta_h, hits_ground,
                                                         n_mu), hits_ground, n_mu)
    k_phi, b_phi = linear_axis(
        fast_acos(view_sun_cos_azimuth(nu, mu, mu_s)) / math.pi * (n_phi - 1), n_phi)
    return i_mu, a_mu, k_phi, b_phi


@njit(cache=True)
def _grid_block(count):
    """Scratch for the grid coordinates of a block of `count` rays: lower entries and weights
    on the grid's two axes."""
    return (np.empty(count, dtype=np.int64), np.empty(count), np.empty(count, dtype=np.int64),
            np.empty(count))


@njit(cache=True, error_model="numpy", inline="always")
def _log_bilinear_block(log_grid, first, i_index, a_weight, k_index, b_weight, skip, out):
    """out[first + q] = exp of `log_grid` (n_i, n_k, n_wl) interpolated bilinearly at
    (i_index[q] + a_weight[q], k_index[q] + b_weight[q]) for each ray q of a block not to
    `skip` (`exp_by_squaring`; the loop over wavelengths vectorises)."""
    for q in range(skip.size):
        if skip[q]:
            continue
        row = out[first + q]
        a, b = a_weight[q], b_weight[q]
        g00, g01 = log_grid[i_index[q], k_index[q]], log_grid[i_index[q], k_index[q] + 1]
        g10, g11 = log_grid[i_index[q] + 1, k_index[q]], log_grid[i_index[q] + 1, k_index[q] + 1]
        for w in range(row.size):
            row[w] = exp_by_squaring((1.0 - a) * ((1.0 - b) * g00[w] + b * g01[w])
                                     + a * ((1.0 - b) * g10[w] + b * g11[w]))


@njit(cache=True)
def sun_grid_frame(up, sun_direction):
    """(e1, e2): unit vectors across the sun's direction, e1 in the sun's vertical plane on
    the zenith's side (for a sun at the zenith or the nadir: any), e2 = s x e1."""
    mu_s = up[0] * sun_direction[0] + up[1] * sun_direction[1] + up[2] * sun_direction[2]
    e1 = up - mu_s * sun_direction
    if math.sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]) < 1e-9:
        helper = np.zeros(3)
        helper[0 if abs(sun_direction[0]) < 0.9 else 1] = 1.0
        e1 = helper - (helper[0] * sun_direction[0] + helper[1] * sun_direction[1]
                       + helper[2] * sun_direction[2]) * sun_direction
    e1 = e1 / math.sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2])
    return e1, np.cross(sun_direction, e1)


@njit(cache=True)
def sun_grid_psi(i, n_psi, psi_max):
    """Angle from the sun [rad] of node i of a sun grid's n_psi: psi_max (i / (n_psi - 1))^2,
    dense next to the sun, where the particles' forward peaks are."""
    return psi_max * (i / (n_psi - 1)) ** 2


@njit(cache=True)
def sun_grid_nodes(up, sun_direction, n_psi, n_chi, psi_max):
    """The view directions (n_psi, n_chi, 3) of a sun grid: angles from the sun
    `sun_grid_psi` x angles about the sun from its vertical plane chi = pi k / (n_chi - 1),
    0 on the zenith's side (the sky is symmetric about that plane)."""
    e1, e2 = sun_grid_frame(up, sun_direction)
    nodes = np.empty((n_psi, n_chi, 3))
    for i in range(n_psi):
        psi = sun_grid_psi(i, n_psi, psi_max)
        for k in range(n_chi):
            chi = math.pi * k / (n_chi - 1)
            nodes[i, k] = math.cos(psi) * sun_direction + math.sin(psi) * (
                math.cos(chi) * e1 + math.sin(chi) * e2)
    return nodes


@njit(parallel=True, cache=True, error_model="numpy")
def sun_grid_lookup(log_grid, up, sun_direction, psi_max, theta_h, horizon_band, directions,
                    out, exact):
    """The radiance along `directions` (n_ray, 3), all within psi_max of the sun, of one
    observer whose horizon lies theta_h from the zenith [rad], interpolated in `log_grid`
    (n_psi, n_chi, n_wl), the logarithm of the radiance at `sun_grid_nodes`: bilinear in
    sqrt(psi / psi_max) and in chi, into out (n_ray, n_wl). A ray whose cell may reach across
    the horizon (the sky's light jumps there), or comes within `horizon_band` [rad] of it
    (where the twilight sky changes fastest in elevation), is left to the caller:
    exact[j] = True, out[j] untouched. In blocks of RAYS_PER_BLOCK rays, vectorised as
    `sky_view_grid_lookup`."""
    n_psi, n_chi, n_wl = log_grid.shape
    e1, e2 = sun_grid_frame(up, sun_direction)
    chi_step = math.pi / (n_chi - 1)
    n_rays = directions.shape[0]
    for block in prange((n_rays + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK):
        first = block * RAYS_PER_BLOCK
        count = min(RAYS_PER_BLOCK, n_rays - first)
        i_psi, a_psi, k_chi, b_chi = _grid_block(count)
        for q in range(count):
            j = first + q
            dx, dy, dz = directions[j, 0], directions[j, 1], directions[j, 2]
            scale = 1.0 / math.sqrt(dx * dx + dy * dy + dz * dz)
            nu = (dx * sun_direction[0] + dy * sun_direction[1] + dz * sun_direction[2]) * scale
            x1 = (dx * e1[0] + dy * e1[1] + dz * e1[2]) * scale
            x2 = (dx * e2[0] + dy * e2[1] + dz * e2[2]) * scale
            mu = (dx * up[0] + dy * up[1] + dz * up[2]) * scale
            psi = fast_acos(min(max(nu, -1.0), 1.0))
            i, a = linear_axis(math.sqrt(psi / psi_max) * (n_psi - 1), n_psi)
            across = math.sqrt(x1 * x1 + x2 * x2)
            cos_chi = min(max(x1 / across, -1.0), 1.0) if across > 1e-12 else 1.0
            k, b = linear_axis(fast_acos(cos_chi) / chi_step, n_chi)
            i_psi[q], a_psi[q], k_chi[q], b_chi[q] = i, a, k, b
            # the cell's reach: its extent in psi plus its widest arc in chi
            outer = sun_grid_psi(i + 1, n_psi, psi_max)
            reach = outer - sun_grid_psi(i, n_psi, psi_max) + outer * chi_step
            exact[j] = abs(fast_acos(min(max(mu, -1.0), 1.0)) - theta_h) <= reach + horizon_band
        _log_bilinear_block(log_grid, first, i_psi, a_psi, k_chi, b_chi,
                            exact[first:first + count], out)


# --------------------------------------------------------------------------------------------
# Lookups for the solver
# --------------------------------------------------------------------------------------------

# `simplex_exponential`: a divided difference over nodes closer together than this is summed as
# its Taylor series, to the term below 1e-17 of the first (at most SIMPLEX_SERIES_TERMS), wider
# ones by the recurrence, whose cancellation then costs at most ~1e-16 / span^3 = 1e-12 relative
SIMPLEX_SERIES_SPAN = 0.05
SIMPLEX_SERIES_TERMS = 12
SIMPLEX_MAX_NODES = 4
SIMPLEX_WORK = 2 * SIMPLEX_MAX_NODES + SIMPLEX_SERIES_TERMS


@njit(cache=True)
def simplex_exponential(depths, n, work):
    """int exp(-sum_k depths[k] g_k) over the gaps g_0 .. g_n >= 0 with sum g_k = 1 [-], n <= 3:
    the share of the vertical column between n ordered events, each gap crossed in a direction
    of slant depth depths[k] (`aureole_path`); exp(-x) / n! when all depths are x. In closed
    form by the Hermite-Genocchi formula, (-1)^n [d_0, .., d_n] exp(-d) (de Boor 2005,
    "Divided differences", Surveys in Approximation Theory 1, 46, eq. 1.4). The integral is
    symmetric in the depths, so depths[:n + 1] are sorted in place first; then Q over the
    nodes i .. i + k by the recurrence Q_k(i) = (Q_(k-1)(i) - Q_(k-1)(i + 1)) / (d_(i+k) - d_i),
    or, where those nodes lie within SIMPLEX_SERIES_SPAN, as
    exp(-d_i) sum_j (-1)^j h_j(d - d_i) / (k + j)!, h_j the complete homogeneous symmetric
    polynomials of the nodes' offsets. work: scratch of SIMPLEX_WORK."""
    for i in range(1, n + 1):  # insertion sort
        value = depths[i]
        j = i - 1
        while j >= 0 and depths[j] > value:
            depths[j + 1] = depths[j]
            j -= 1
        depths[j + 1] = value
    q = work[:SIMPLEX_MAX_NODES]
    decay = work[SIMPLEX_MAX_NODES:2 * SIMPLEX_MAX_NODES]
    h = work[2 * SIMPLEX_MAX_NODES:]
    for i in range(n + 1):
        decay[i] = math.exp(-depths[i])
        q[i] = decay[i]
    factorial = 1.0
    for k in range(1, n + 1):
        factorial *= k
        for i in range(n + 1 - k):
            span = depths[i + k] - depths[i]
            if span > SIMPLEX_SERIES_SPAN:
                q[i] = (q[i] - q[i + 1]) / span
                continue
            terms = 1  # up to the term of span^j / j! < 1e-17
            bound = 1.0
            while terms < SIMPLEX_SERIES_TERMS and bound > 1e-17:
                bound *= span / terms
                terms += 1
            h[0] = 1.0
            for j in range(1, terms):
                h[j] = 0.0
            for m in range(i + 1, i + k + 1):
                offset = depths[m] - depths[i]
                for j in range(1, terms):
                    h[j] += offset * h[j - 1]
            total = 0.0
            term_factor = 1.0 / factorial
            for j in range(terms):
                total += term_factor * h[j]
                term_factor *= -1.0 / (k + j + 1.0)
            q[i] = decay[i] * total
    return q[0]


@njit(cache=True)
def _great_circle_mu(mu, mu_s, psi, u):
    """Zenith cosine of the direction a share u of the way from the sun (mu_s) to the view
    (mu) along the great circle between them, psi apart [rad]."""
    sin_psi = math.sin(psi)
    if sin_psi < 1e-9:
        return (1.0 - u) * mu_s + u * mu
    return (math.sin((1.0 - u) * psi) * mu_s + math.sin(u * psi) * mu) / sin_psi


@njit(cache=True)
def aureole_path(r, mu, mu_s, nu, tables, out):
    """The Poisson law of the peak events on the path from the sun to the eye, for the sun's
    light scattered two or more times in the particles' forward peaks and seen along (r, mu)
    at cos(angle from the sun) nu by a ray that misses the ground (E_sun V T (exp(x) - 1 - x)
    G(x, psi), `transport.aureole`, with the line of sight's transmittance T and peak depth x
    replaced by those of that path): out[0, w] = x' (0: no aureole) and out[1, w] = log T',
    from T x^n / n! replaced by F_n = prod_{k=1..n} P_k int exp(-sum_k X_k g_k) dg
    (`simplex_exponential`), n events at increasing depth, the gap g_k between them (a share
    of the vertical column) crossed along the direction u = k / n of the way from the sun to
    the view (`_great_circle_mu`), with slant optical depth X_k and peak depth P_k to the top
    there (plane-parallel in the column's optical depth). F_2 and F_3 fix the Poisson law
    T' x'^n / n! used for all n: x' = 3 F_3 / F_2, T' = 2 F_2 / x'^2; along the sun's own
    direction, or beside it at its elevation, T' = T and x' = x."""
    bottom_radius, top_radius = tables.bottom_radius, tables.top_radius
    n_wl = out.shape[1]
    psi = math.acos(min(max(nu, -1.0), 1.0))
    mu_h = horizon_cos_zenith(r, bottom_radius)
    # slant and peak depths along the directions u = 0, 1/3, 1/2, 2/3, 1 of the path
    shares = (0.0, 1.0 / 3.0, 0.5, 2.0 / 3.0, 1.0)
    depth = np.empty((5, n_wl))
    peak = np.empty((5, n_wl))
    for j in range(5):
        mu_j = max(_great_circle_mu(mu, mu_s, psi, shares[j]), mu_h)
        # bilinear in the depths themselves (as the tables' sun inside thick layers): no
        # logarithm per direction and wavelength
        transmittance_to_top(r, mu_j, bottom_radius, top_radius, tables.slant_depth,
                             depth[j])
        transmittance_to_top(r, mu_j, bottom_radius, top_radius, tables.peak_depth, peak[j])
    gaps = np.empty(SIMPLEX_MAX_NODES)
    work = np.empty(SIMPLEX_WORK)
    for w in range(n_wl):
        out[0, w], out[1, w] = 0.0, AUREOLE_LOG_FLOOR
        gaps[0], gaps[1], gaps[2] = depth[0, w], depth[2, w], depth[4, w]
        second = peak[2, w] * peak[4, w] * simplex_exponential(gaps, 2, work)
        gaps[0], gaps[1], gaps[2], gaps[3] = depth[0, w], depth[1, w], depth[3, w], depth[4, w]
        third = (peak[1, w] * peak[3, w] * peak[4, w]
                 * simplex_exponential(gaps, 3, work))
        if not (second > 0.0 and third > 0.0):
            continue
        x = min(3.0 * third / second, tables.aureole_x_max)
        out[0, w] = x
        out[1, w] = max(math.log(2.0 * second / (x * x)), AUREOLE_LOG_FLOOR)


@njit(cache=True)
def add_aureole(r, mu_s, nu, path, tables, value):
    """value[w] += E_sun V T' ((exp(x') - 1 - x') G(x', psi) + exp(x') x' B(x', psi)) for the
    Poisson law `path` (`aureole_path`) of a view at cos(angle from the sun) nu from radius r:
    the light scattered two or more times in the peaks, and the peaks' blur of light scattered
    once in the smooth part (`transport.aureole`)."""
    bottom_radius, x_max = tables.bottom_radius, tables.aureole_x_max
    shape, blur = tables.aureole_shape, tables.aureole_blur
    n_x, n_psi = shape.shape[0], shape.shape[1]
    visible = sun_visible_fraction(r, mu_s, bottom_radius, tables.sun_angular_radius)
    if visible <= 0.0:
        return
    psi = math.acos(min(max(nu, -1.0), 1.0))
    i_p, a_p = linear_axis(psi / tables.aureole_psi_max * (n_psi - 1), n_psi)
    for w in range(value.size):
        x = path[0, w]
        if not x > 0.0:
            continue
        i_x, a_x = linear_axis(math.log1p(x) / math.log1p(x_max) * (n_x - 1), n_x)
        g = _bilinear_at(shape, i_x, a_x, i_p, a_p, w)
        b = _bilinear_at(blur, i_x, a_x, i_p, a_p, w)
        value[w] += (tables.sun_irradiance[w] * visible
                     * (math.exp(path[1, w]) * (math.expm1(x) - x) * g
                        + math.exp(path[1, w] + x) * x * b))


@njit(cache=True, inline="always")
def _bilinear_at(table, i, a, j, b, w):
    """`table` (n, m, n_wl) at row i + a and column j + b (lower entries and weights), band w
    (`transmittance_bilinear` for one band)."""
    return ((1.0 - a) * ((1.0 - b) * table[i, j, w] + b * table[i, j + 1, w])
            + a * ((1.0 - b) * table[i + 1, j, w] + b * table[i + 1, j + 1, w]))


@njit(parallel=True, cache=True)
def aureole_view_table(r, mu_s, tables):
    """`aureole_path` for the views of one observer at radius r [m] inside the atmosphere with
    the sun at zenith cosine mu_s, within the aureole's reach psi_max of the sun:
    (AUREOLE_VIEW_PSI, AUREOLE_VIEW_CHI, 2, n_wl) on angles from the sun
    psi = psi_max i / (AUREOLE_VIEW_PSI - 1) x angles about the sun from its vertical plane
    chi = pi k / (AUREOLE_VIEW_CHI - 1) (0 on the zenith's side). For one observer and sun the
    path's Poisson law depends on (psi, chi) only and smoothly, so a frame evaluates it on
    this grid instead of for every pixel near the sun (`aureole_view_lookup`); the sharp
    angular shape G(x', psi) stays per pixel (`add_aureole`)."""
    n_wl = tables.sun_irradiance.size
    table = np.zeros((AUREOLE_VIEW_PSI, AUREOLE_VIEW_CHI, 2, n_wl))
    sin_s = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
    for i in prange(AUREOLE_VIEW_PSI):
        psi = tables.aureole_psi_max * i / (AUREOLE_VIEW_PSI - 1)
        nu = math.cos(psi)
        for k in range(AUREOLE_VIEW_CHI):
            chi = math.pi * k / (AUREOLE_VIEW_CHI - 1)
            mu = min(max(nu * mu_s + math.sin(psi) * sin_s * math.cos(chi), -1.0), 1.0)
            aureole_path(r, mu, mu_s, nu, tables, table[i, k])
    return table


@njit(cache=True)
def aureole_view_lookup(table, mu, mu_s, nu, psi_max, out):
    """`aureole_view_table` interpolated bilinearly (x' and log T') for the view (mu, nu) of
    its observer, into out (2, n_wl); x' = 0 (no aureole) where a corner has none."""
    n_psi, n_chi = table.shape[0], table.shape[1]
    psi = math.acos(min(max(nu, -1.0), 1.0))
    i, a = linear_axis(psi / psi_max * (n_psi - 1), n_psi)
    k, b = linear_axis(view_sun_azimuth(mu, nu, mu_s) / math.pi * (n_chi - 1), n_chi)
    for w in range(out.shape[1]):
        corners = (table[i, k, 0, w], table[i, k + 1, 0, w], table[i + 1, k, 0, w],
                   table[i + 1, k + 1, 0, w])
        if not min(corners) > 0.0:
            out[0, w] = 0.0
            continue
        for q in range(2):
            out[q, w] = ((1.0 - a) * ((1.0 - b) * table[i, k, q, w] + b * table[i, k + 1, q, w])
                         + a * ((1.0 - b) * table[i + 1, k, q, w]
                                + b * table[i + 1, k + 1, q, w]))


@njit(parallel=True, cache=True)
def sky_radiance_rays(origins, directions, sun_direction, tables, ground_albedo, view_table,
                      aureole_table, out):
    """Radiance from the tables into out (n_ray, n_wl) [W m^-2 sr^-1 nm^-1]:
    sum_s p_s(nu) S_s + sum_c p*_c(nu) D_c + M (`scattering` = the interleaved
    (S_1..S_n_s, D_1..D_n_c, M) from `flat_tables`, weighted by the rows of `phase_table`;
    sizes n_r, n_mu, n_mu_s, n_nu), plus for rays that hit the ground the Lambertian ground
    albedo / pi (E_sun T_sun max(mu_s, 0) V + E_indirect) seen through T(x, g). origins is
    (1, 3) or (n_ray, 3); directions (n_ray, 3), normalised here. Observers in space start at
    the top boundary; rays that miss the atmosphere get 0. Bruneton 2017, `GetSkyRadiance`
    and the demo's ground shading.

    Single scattering comes from the table by day and from `lit_single_scattering` (ray
    marched outside the planet's umbra, profile densities `density` (n_c, n_z) on levels
    h_step apart, constituents `scatterers` (n_s,), single_factor = E_sun beta_s (n_s, n_wl))
    once the sun at the ray's start nears the horizon, blended by `exact_single_weight`;
    for one origin inside the atmosphere it is read from `view_table`
    (`single_scattering_view_table` of that origin and sun), otherwise (view_table of size 0)
    marched along each ray. The aureole of the peaks' multiple events (`add_aureole`) takes
    its path's Poisson law from `aureole_table` (`aureole_view_table` of that origin and
    sun) where it has entries, else computes it per ray.
    `tables`: the `LookupTables` record of the tables and the profile."""
    bottom_radius, top_radius, mu_s_min = tables.bottom_radius, tables.top_radius, tables.mu_s_min
    scattering, phase_table = tables.scattering, tables.phase_table
    transmittance, irradiance = tables.transmittance, tables.irradiance
    sun_irradiance, sun_angular_radius = tables.sun_irradiance, tables.sun_angular_radius
    h_step, density, scatterers = tables.h_step, tables.density, tables.scatterers
    single_factor = tables.single_factor
    n_ray = directions.shape[0]
    n_r, n_mu, n_mu_s, n_nu = tables.n_r, tables.n_mu, tables.n_mu_s, tables.n_nu
    n_wl = out.shape[1]
    n_s = scatterers.size
    n_t = phase_table.shape[0] + 1
    single_origin = origins.shape[0] == 1
    n_blocks = (n_ray + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        weights, pair_values = lookup_scratch(n_t, n_wl)
        value = np.empty(n_wl)
        t_view = np.empty(n_wl)
        t_sun = np.empty(n_wl)
        scratch = np.empty(n_wl)
        samples = np.empty(EXACT_SINGLE_SAMPLES + 8)
        dens = np.empty(density.shape[0])
        exact = np.empty((n_s, n_wl))
        slices = np.empty((2, n_wl))
        path = np.empty((2, n_wl))
        for i in range(block * RAYS_PER_BLOCK, min(n_ray, (block + 1) * RAYS_PER_BLOCK)):
            for w in range(n_wl):
                out[i, w] = 0.0
            o = 0 if single_origin else i
            inside, r, mu, mu_s, nu, hits_ground = view_ray_start(
                origins[o, 0], origins[o, 1], origins[o, 2], directions[i, 0], directions[i, 1],
                directions[i, 2], sun_direction, bottom_radius, top_radius)
            if not inside:
                continue
            phase_values(phase_table, nu, weights)
            marched = exact_single_weight(mu_s)
            for k in range(n_s * n_wl):
                weights[k] *= 1.0 - marched
            value[:] = 0.0
            i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu = scattering_corners(
                r, mu, mu_s, nu, hits_ground, bottom_radius, top_radius, mu_s_min,
                tables.sun_angle_share, n_r, n_mu, n_mu_s, n_nu, tables.radius_warp)
            scattering_lookup(scattering, n_mu, n_mu_s, n_nu, weights, i_r, a_r, i_mu, a_mu, i_s,
                              a_s, i_nu, a_nu, pair_values, value)
            if marched > 0.0:
                geometric_mu_s_correction(scattering, n_mu, n_mu_s, n_nu, weights, n_s, i_r,
                                          a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu, marched,
                                          slices, value)
            if hits_ground:
                d = distance_to_bottom_boundary(r, mu, bottom_radius)
            else:
                d = distance_to_top_boundary(r, mu, top_radius)
            if marched > 0.0:
                if view_table.shape[0] > 0:
                    view_table_lookup(view_table, r, mu, mu_s, nu, hits_ground, bottom_radius,
                                      top_radius, exact)
                else:
                    lit_single_scattering(r, mu, mu_s, nu, d, hits_ground, bottom_radius,
                                          top_radius, sun_angular_radius,
                                          EXACT_SINGLE_SAMPLES, h_step, density, scatterers,
                                          transmittance, samples, t_view, scratch, t_sun, dens,
                                          exact)
                phase_values(phase_table, nu, weights)
                for s in range(n_s):
                    for w in range(n_wl):
                        value[w] += (marched * weights[s * n_wl + w] * single_factor[s, w]
                                     * exact[s, w])
            if (not hits_ground and tables.aureole_psi_max > 0.0
                    and nu > math.cos(tables.aureole_psi_max)):
                if aureole_table.shape[0] > 0:
                    aureole_view_lookup(aureole_table, mu, mu_s, nu, tables.aureole_psi_max,
                                        path)
                else:
                    aureole_path(r, mu, mu_s, nu, tables, path)
                add_aureole(r, mu_s, nu, path, tables, value)
            if hits_ground:
                mu_s_g = min(max((r * mu_s + d * nu) / bottom_radius, -1.0), 1.0)
                transmittance_along(r, mu, d, True, bottom_radius, top_radius, transmittance,
                                    t_view, scratch)
                visible = sun_visible_fraction(bottom_radius, mu_s_g, bottom_radius,
                                               sun_angular_radius)
                transmittance_to_top(bottom_radius, max(mu_s_g, 0.0), bottom_radius,
                                     top_radius, transmittance, t_sun)
                direct = max(mu_s_g, 0.0) * visible
                irradiance_lookup(bottom_radius, mu_s_g, bottom_radius, top_radius, irradiance,
                                  scratch)
                for w in range(n_wl):
                    ground = sun_irradiance[w] * t_sun[w] * direct + scratch[w]
                    value[w] += ground_albedo[w] / math.pi * ground * t_view[w]
            for w in range(n_wl):
                out[i, w] = value[w]


@njit(cache=True)
def aerial_scratch(tables, n_wl):
    """Scratch arrays of `_aerial_point` and `_aerial_lit_single` for the `LookupTables` record
    `tables` (its single-scattering tables, peak corrections and orders >= 2) at n_wl
    wavelengths: (weights, pair_values, at_point, scratch, slices, samples, observer, here,
    sun, dens, exact)."""
    weights, pair_values = lookup_scratch(tables.phase_table.shape[0] + 1, n_wl)
    return (weights, pair_values, np.empty(n_wl), np.empty(n_wl),
            np.empty((2, n_wl)), np.empty(EXACT_SINGLE_SAMPLES + 8), np.empty(n_wl),
            np.empty(n_wl), np.empty(n_wl), np.empty(tables.density.shape[0]),
            np.empty((tables.scatterers.size, n_wl)))


@njit(cache=True, inline="always")
def ray_start(x, y, z, dx, dy, dz, sun_direction, bottom_radius, top_radius):
    """(r, mu, mu_s, nu, hits_ground) of the unit ray (dx, dy, dz) from (x, y, z) in the
    atmosphere, r clamped to the tables' range."""
    r = math.sqrt(x * x + y * y + z * z)
    mu = (x * dx + y * dy + z * dz) / r
    mu_s, nu = sun_cosines(x, y, z, r, dx, dy, dz, sun_direction)
    r = min(max(r, bottom_radius), top_radius)
    return r, mu, mu_s, nu, ray_intersects_ground(r, mu, bottom_radius)


@njit(cache=True, inline="always")
def view_ray_start(ox, oy, oz, dx, dy, dz, sun_direction, bottom_radius, top_radius):
    """(inside, r, mu, mu_s, nu, hits_ground) of the view ray from o along d (any length,
    normalised here) where it starts in the atmosphere (`_enter_atmosphere`, `ray_start`);
    inside False, and no light, for a zero direction or a ray that misses the atmosphere."""
    norm = math.sqrt(dx * dx + dy * dy + dz * dz)
    if not norm > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, False
    dx, dy, dz = dx / norm, dy / norm, dz / norm
    x, y, z, _, inside = _enter_atmosphere(ox, oy, oz, dx, dy, dz, top_radius)
    if not inside:
        return False, 0.0, 0.0, 0.0, 0.0, False
    r, mu, mu_s, nu, hits_ground = ray_start(x, y, z, dx, dy, dz, sun_direction, bottom_radius,
                                             top_radius)
    return True, r, mu, mu_s, nu, hits_ground


@njit(cache=True)
def segment_start(ox, oy, oz, px, py, pz, sun_direction, bottom_radius, top_radius):
    """(r, mu, mu_s, nu, d, hits_ground) of the segment from o to p where it starts in the
    atmosphere (observers in space move to the top boundary), with d its length in the
    atmosphere before the ground or the top; d = 0 when it has none."""
    dx, dy, dz = px - ox, py - oy, pz - oz
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    if not d > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, False
    dx, dy, dz = dx / d, dy / d, dz / d
    x, y, z, travelled, inside = _enter_atmosphere(ox, oy, oz, dx, dy, dz, top_radius)
    d -= travelled
    if not inside or d <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, False
    r, mu, mu_s, nu, hits_ground = ray_start(x, y, z, dx, dy, dz, sun_direction, bottom_radius,
                                             top_radius)
    if hits_ground:
        d = min(d, distance_to_bottom_boundary(r, mu, bottom_radius))
    else:
        d = min(d, distance_to_top_boundary(r, mu, top_radius))
    return r, mu, mu_s, nu, d, hits_ground


@njit(cache=True)
def _aerial_point(ox, oy, oz, px, py, pz, sun_direction, tables, weights, pair_values,
                  at_point, scratch, slices, inscatter_out, transmittance_out):
    """Light scattered towards the observer o between o and the point p, into inscatter_out
    (n_wl,) [W m^-2 sr^-1 nm^-1], and the transmittance of that segment into
    transmittance_out (n_wl,): S(x, v) - T(x, p) S(p, v) with both lookups in the half of the
    mu axis of the ray at x (Bruneton 2017, `GetSkyRadianceToPoint`, without light shafts).
    Observers in space start at the top boundary; the part of a segment outside the
    atmosphere, or beyond the ground, adds nothing. The other arrays are scratch
    (`aerial_scratch`).

    Returns the segment (r, mu, mu_s, nu, d, hits_ground) at x and the share `marched` of its
    single scattering left out of the table difference, `exact_single_weight` of the lower
    sun of its two ends (from space the top of the atmosphere may be sunlit while the point is
    in twilight); the caller adds that share with `_aerial_lit_single`, as `sky_radiance_rays`
    does for whole rays. With marched > 0 both lookups of the orders >= 2 get
    `geometric_mu_s_correction`, so the difference is taken between geometrically interpolated
    values; by day (marched = 0) the result is the table difference alone. `tables`: the
    `LookupTables` record."""
    bottom_radius, top_radius, mu_s_min = tables.bottom_radius, tables.top_radius, tables.mu_s_min
    scattering, phase_table, transmittance = (tables.scattering, tables.phase_table,
                                              tables.transmittance)
    n_r, n_mu, n_mu_s, n_nu = tables.n_r, tables.n_mu, tables.n_mu_s, tables.n_nu
    n_wl = inscatter_out.size
    n_s = tables.scatterers.size
    for w in range(n_wl):
        inscatter_out[w] = 0.0
        transmittance_out[w] = 1.0
    r, mu, mu_s, nu, d, hits_ground = segment_start(ox, oy, oz, px, py, pz, sun_direction,
                                                    bottom_radius, top_radius)
    if not d > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, False, 0.0
    r_p = math.sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0))
    mu_p = min(max((r * mu + d) / r_p, -1.0), 1.0)
    mu_s_p = min(max((r * mu_s + d * nu) / r_p, -1.0), 1.0)
    r_p = min(max(r_p, bottom_radius), top_radius)
    phase_values(phase_table, nu, weights)
    marched = exact_single_weight(min(mu_s, mu_s_p))
    if marched > 0.0:
        for k in range(n_s * n_wl):
            weights[k] *= 1.0 - marched
    at_point[:] = 0.0
    i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu = scattering_corners(
        r, mu, mu_s, nu, hits_ground, bottom_radius, top_radius, mu_s_min,
        tables.sun_angle_share, n_r, n_mu, n_mu_s, n_nu, tables.radius_warp)
    scattering_lookup(scattering, n_mu, n_mu_s, n_nu, weights, i_r, a_r, i_mu, a_mu, i_s, a_s,
                      i_nu, a_nu, pair_values, inscatter_out)
    if marched > 0.0:
        geometric_mu_s_correction(scattering, n_mu, n_mu_s, n_nu, weights, n_s, i_r, a_r, i_mu,
                                  a_mu, i_s, a_s, i_nu, a_nu, marched, slices, inscatter_out)
    i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu = scattering_corners(
        r_p, mu_p, mu_s_p, nu, hits_ground, bottom_radius, top_radius, mu_s_min,
        tables.sun_angle_share, n_r, n_mu, n_mu_s, n_nu, tables.radius_warp)
    scattering_lookup(scattering, n_mu, n_mu_s, n_nu, weights, i_r, a_r, i_mu, a_mu, i_s, a_s,
                      i_nu, a_nu, pair_values, at_point)
    if marched > 0.0:
        geometric_mu_s_correction(scattering, n_mu, n_mu_s, n_nu, weights, n_s, i_r, a_r, i_mu,
                                  a_mu, i_s, a_s, i_nu, a_nu, marched, slices, at_point)
    transmittance_along(r, mu, d, hits_ground, bottom_radius, top_radius, transmittance,
                        transmittance_out, scratch)
    for w in range(n_wl):
        inscatter_out[w] = max(inscatter_out[w] - transmittance_out[w] * at_point[w], 0.0)
    return r, mu, mu_s, nu, d, hits_ground, marched


@njit(cache=True)
def _aerial_lit_single(r, mu, mu_s, nu, d, hits_ground, marched, tables, weights, samples,
                       observer, here, sun, dens, exact, inscatter_out):
    """inscatter_out[w] += marched sum_s p_s(nu) E_sun beta_s `lit_single_scattering` over the
    segment [0, d] of the ray (r, mu) (its umbra interval clipped to it), the twilight share
    of single scattering that `_aerial_point` left out; from the `LookupTables` record
    `tables`: profile densities `density` on levels h_step apart, constituents `scatterers`,
    single_factor = E_sun beta_s (n_s, n_wl). The other arrays are scratch
    (`aerial_scratch`)."""
    n_wl = inscatter_out.size
    lit_single_scattering(r, mu, mu_s, nu, d, hits_ground, tables.bottom_radius,
                          tables.top_radius, tables.sun_angular_radius, EXACT_SINGLE_SAMPLES,
                          tables.h_step, tables.density, tables.scatterers, tables.transmittance,
                          samples, observer, here, sun, dens, exact)
    phase_values(tables.phase_table, nu, weights)
    single_factor = tables.single_factor
    for s in range(single_factor.shape[0]):
        for w in range(n_wl):
            inscatter_out[w] += (marched * weights[s * n_wl + w] * single_factor[s, w]
                                 * exact[s, w])


@njit(cache=True)
def aerial_segment(ox, oy, oz, px, py, pz, sun_direction, tables, work, inscatter_out,
                   transmittance_out):
    """`_aerial_point` from o to p and, in twilight, `_aerial_lit_single` over the segment:
    the light scattered towards o into inscatter_out and the segment's transmittance into
    transmittance_out (n_wl,). `tables`: the `LookupTables` record; `work`: the scratch arrays
    of `aerial_scratch`."""
    (weights, pair_values, at_point, scratch, slices, samples, observer, here, t_sun, dens,
     exact) = work
    r, mu, mu_s, nu, d, hits_ground, marched = _aerial_point(
        ox, oy, oz, px, py, pz, sun_direction, tables, weights, pair_values, at_point,
        scratch, slices, inscatter_out, transmittance_out)
    if marched > 0.0:
        _aerial_lit_single(r, mu, mu_s, nu, d, hits_ground, marched, tables, weights, samples,
                           observer, here, t_sun, dens, exact, inscatter_out)


@njit(parallel=True, cache=True)
def aerial_perspective_points(origins, points, sun_direction, tables, inscatter_out,
                              transmittance_out):
    """`aerial_segment` from each origin ((1, 3) or (n, 3)) to each point (n, 3), into
    inscatter_out and transmittance_out (n, n_wl).
    `tables`: the `LookupTables` record of the tables and the profile."""
    n_points = points.shape[0]
    n_wl = inscatter_out.shape[1]
    single_origin = origins.shape[0] == 1
    n_blocks = (n_points + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        work = aerial_scratch(tables, n_wl)
        for i in range(block * RAYS_PER_BLOCK, min(n_points, (block + 1) * RAYS_PER_BLOCK)):
            o = 0 if single_origin else i
            aerial_segment(origins[o, 0], origins[o, 1], origins[o, 2], points[i, 0],
                           points[i, 1], points[i, 2], sun_direction, tables, work,
                           inscatter_out[i], transmittance_out[i])


@njit(cache=True)
def add_reflected_light(point, normal, sunlit, albedo, sun_direction, tables, t_view, direct,
                        diffuse, out):
    """out (n_wl,) += T albedo / pi (V E_sun + E_sky), the light a Lambertian surface at
    `point` facing `normal` reflects towards the observer through the transmittance t_view,
    with V = `sunlit` in [0, 1] the part of the sunlight that terrain and clouds let through
    (`surface_irradiance`; direct and diffuse are scratch)."""
    surface_irradiance(point, normal, sun_direction, tables.bottom_radius, tables.top_radius,
                       tables.transmittance, tables.irradiance, tables.sun_irradiance,
                       tables.sun_angular_radius, direct, diffuse)
    for w in range(out.size):
        out[w] += t_view[w] * albedo[w] / math.pi * (sunlit * direct[w] + diffuse[w])


@njit(cache=True)
def irradiance_lookup(r, mu_s, bottom_radius, top_radius, irradiance, out):
    """Indirect irradiance, bilinear in `irradiance` (n_r_e, n_mu_s_e, n_wl), into out."""
    x_mu_s, x_r = irradiance_x_from_r_mu_s(r, mu_s, bottom_radius, top_radius)
    i, a = linear_axis(x_r * (irradiance.shape[0] - 1), irradiance.shape[0])
    j, b = linear_axis(x_mu_s * (irradiance.shape[1] - 1), irradiance.shape[1])
    for w in range(irradiance.shape[2]):
        out[w] = ((1.0 - a) * ((1.0 - b) * irradiance[i, j, w] + b * irradiance[i, j + 1, w])
                  + a * ((1.0 - b) * irradiance[i + 1, j, w]
                         + b * irradiance[i + 1, j + 1, w]))


@njit(parallel=True, cache=True)
def transmittance_rays(origins, directions, distances, bottom_radius, top_radius,
                       transmittance):
    """Transmittance (n_ray, n_wl) from each origin ((1, 3) or (n_ray, 3)) along its direction
    (normalised here) over `distances` [m] from the tables (inf: out of the atmosphere, towards
    a light source; 0 when the ground blocks the path, finite or infinite). Observers in space
    start at the top boundary."""
    n_ray = directions.shape[0]
    n_wl = transmittance.shape[2]
    single_origin = origins.shape[0] == 1
    out = np.ones((n_ray, n_wl))
    for i in prange(n_ray):
        o = 0 if single_origin else np.int64(i)  # (prange's index is unsigned)
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        norm = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not norm > 0.0:
            continue
        dx, dy, dz = dx / norm, dy / norm, dz / norm
        x, y, z, travelled, inside = _enter_atmosphere(origins[o, 0], origins[o, 1],
                                                       origins[o, 2], dx, dy, dz, top_radius)
        distance = distances[i] - travelled
        if not inside or distance <= 0.0:
            continue
        r = math.sqrt(x * x + y * y + z * z)
        mu = (x * dx + y * dy + z * dz) / r
        r = min(max(r, bottom_radius), top_radius)
        hits_ground = ray_intersects_ground(r, mu, bottom_radius)
        if hits_ground:
            d_end = distance_to_bottom_boundary(r, mu, bottom_radius)
            if distance > d_end * (1.0 + 1e-12):
                out[i, :] = 0.0
                continue
        else:
            d_end = distance_to_top_boundary(r, mu, top_radius)
        result = np.empty(n_wl)
        scratch = np.empty(n_wl)
        transmittance_along(r, mu, min(distance, d_end), hits_ground, bottom_radius, top_radius,
                            transmittance, result, scratch)
        for w in range(n_wl):
            out[i, w] = result[w]
    return out


@njit(cache=True)
def surface_irradiance(position, normal, sun_direction, bottom_radius, top_radius,
                       transmittance, irradiance, sun_irradiance, sun_angular_radius, direct,
                       diffuse):
    """(direct, diffuse) irradiance (n_wl,) each [W m^-2 nm^-1] on a surface at `position`
    facing unit `normal`: E_sun T_sun V max(n . s, 0), and the indirect-irradiance table times
    (1 + n . up) / 2, the part of the sky a tilted surface sees (Bruneton 2017,
    `GetSunAndSkyIrradiance`)."""
    x, y, z = position[0], position[1], position[2]
    r = math.sqrt(x * x + y * y + z * z)
    mu_s = (x * sun_direction[0] + y * sun_direction[1] + z * sun_direction[2]) / r
    facing_up = (x * normal[0] + y * normal[1] + z * normal[2]) / r
    facing_sun = (normal[0] * sun_direction[0] + normal[1] * sun_direction[1]
                  + normal[2] * sun_direction[2])
    r = min(max(r, bottom_radius), top_radius)
    irradiance_lookup(r, mu_s, bottom_radius, top_radius, irradiance, diffuse)
    sky_view = 0.5 * (1.0 + facing_up)
    for w in range(diffuse.size):
        diffuse[w] *= sky_view
        direct[w] = 0.0
    visible = sun_visible_fraction(r, mu_s, bottom_radius, sun_angular_radius)
    if visible > 0.0 and facing_sun > 0.0:
        transmittance_to_top(r, max(mu_s, horizon_cos_zenith(r, bottom_radius)),
                             bottom_radius, top_radius, transmittance, direct)
        for w in range(direct.size):
            direct[w] *= sun_irradiance[w] * facing_sun * visible


@njit(parallel=True, cache=True)
def ground_irradiance_points(positions, normals, sun_direction, tables):
    """`surface_irradiance` at `positions` (n, 3) facing unit `normals` (n, 3): (direct,
    diffuse), each (n, n_wl) [W m^-2 nm^-1].
    `tables`: the `LookupTables` record of the tables and the profile."""
    bottom_radius, top_radius = tables.bottom_radius, tables.top_radius
    transmittance, irradiance = tables.transmittance, tables.irradiance
    sun_irradiance, sun_angular_radius = tables.sun_irradiance, tables.sun_angular_radius
    n = positions.shape[0]
    n_wl = transmittance.shape[2]
    direct = np.zeros((n, n_wl))
    diffuse = np.zeros((n, n_wl))
    for i in prange(n):
        surface_irradiance(positions[i], normals[i], sun_direction, bottom_radius, top_radius,
                           transmittance, irradiance, sun_irradiance, sun_angular_radius,
                           direct[i], diffuse[i])
    return direct, diffuse
