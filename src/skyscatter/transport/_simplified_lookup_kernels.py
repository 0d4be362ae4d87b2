"""Numba kernel of the simplified (single-scattering) Bruneton solver
(`transport/bruneton_simplified.py`): one quadrilinear lookup of the single-scattering tables
per ray plus the directly lit ground, with the lookup helpers of the full table solver
(`_table_lookup_kernels`, Bruneton 2017 functions.glsl `GetSkyRadiance`) and nothing of its
multiple scattering, sky irradiance, twilight march or aureole.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport._table_common_kernels import phase_values
from skyscatter.transport._table_lookup_kernels import (
    RAYS_PER_BLOCK,
    scattering_corners,
    scattering_lookup,
    transmittance_along,
    transmittance_to_top,
    view_ray_start,
)
from skyscatter.transport.geometry import sun_visible_fraction
from skyscatter.transport.table_parameterisation import distance_to_bottom_boundary


@njit(parallel=True, cache=True)
def sky_radiance_rays(origins, directions, sun_direction, geometry, single, sizes, radius_warp,
                      phase_table, transmittance, sun_irradiance, ground_albedo, out):
    """Radiance into out (n_ray, n_wl) [W m^-2 sr^-1 nm^-1]: sum_s p_s(nu) S_s(r, mu, mu_s, nu)
    from `single` (the tables (n_r, n_mu, n_mu_s, n_nu, n_s, n_wl) flat, `sizes` = (n_r, n_mu,
    n_mu_s, n_nu)), plus for rays that meet the ground albedo / pi E_sun T_sun max(mu_s, 0) V
    seen through T(x, g). origins (n_ray, 3); directions (n_ray, 3), normalised here;
    geometry = (bottom_radius, top_radius, mu_s_min, sun_angle_share, sun_angular_radius).
    Observers in space start at the top boundary; rays that miss the atmosphere get 0."""
    bottom_radius, top_radius, mu_s_min, sun_angle_share, sun_angular_radius = geometry
    n_r, n_mu, n_mu_s, n_nu = sizes
    n_ray = directions.shape[0]
    n_wl = out.shape[1]
    n_s = phase_table.shape[0]
    n_blocks = (n_ray + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        weights = np.empty(n_s * n_wl)
        pair_values = np.empty(2 * n_s * n_wl)
        value = np.empty(n_wl)
        t_view = np.empty(n_wl)
        t_sun = np.empty(n_wl)
        scratch = np.empty(n_wl)
        for i in range(block * RAYS_PER_BLOCK, min(n_ray, (block + 1) * RAYS_PER_BLOCK)):
            out[i, :] = 0.0
            inside, r, mu, mu_s, nu, hits_ground = view_ray_start(
                origins[i, 0], origins[i, 1], origins[i, 2], directions[i, 0], directions[i, 1],
                directions[i, 2], sun_direction, bottom_radius, top_radius)
            if not inside:
                continue
            phase_values(phase_table, nu, weights)
            value[:] = 0.0
            i_r, a_r, i_mu, a_mu, i_s, a_s, i_nu, a_nu = scattering_corners(
                r, mu, mu_s, nu, hits_ground, bottom_radius, top_radius, mu_s_min,
                sun_angle_share, n_r, n_mu, n_mu_s, n_nu, radius_warp)
            scattering_lookup(single, n_mu, n_mu_s, n_nu, weights, i_r, a_r, i_mu, a_mu, i_s,
                              a_s, i_nu, a_nu, pair_values, value)
            if hits_ground:
                d = distance_to_bottom_boundary(r, mu, bottom_radius)
                mu_s_g = min(max((r * mu_s + d * nu) / bottom_radius, -1.0), 1.0)
                transmittance_along(r, mu, d, True, bottom_radius, top_radius, transmittance,
                                    t_view, scratch)
                transmittance_to_top(bottom_radius, max(mu_s_g, 0.0), bottom_radius,
                                     top_radius, transmittance, t_sun)
                direct = max(mu_s_g, 0.0) * sun_visible_fraction(
                    bottom_radius, mu_s_g, bottom_radius, sun_angular_radius)
                for w in range(n_wl):
                    value[w] += (ground_albedo[w] / math.pi * sun_irradiance[w] * t_sun[w]
                                 * direct * t_view[w])
            for w in range(n_wl):
                out[i, w] = value[w]
