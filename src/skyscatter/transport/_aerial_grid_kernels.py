"""Kernels of the aerial-perspective grid: the light the air scatters between one observer
and the surfaces of a frame, tabulated per frame on view directions x distances and
interpolated per surface point (the aerial-perspective volume of Hillaire 2020, "A scalable
and production ready sky and atmosphere rendering technique", Comput. Graph. Forum 39(4),
doi:10.1111/cgf.14050, §5.4, on the sky-view grid's directions instead of the camera's
froxels).

The grid's directions are those of `sky_view_grid_nodes` (the tables' mu mapping, crowded
at the horizon, each side of it kept to its half; azimuths from the sun's vertical plane),
restricted to the cells the frame's points fall in. Along each direction its depth nodes
sit at d_end j / (n_depth - 1), with d_end the frame's farthest point or, nearer, the
ground (`grid_depth`): the in-scattered light of rays that end on the planet then stays on
the same node where it stops growing. The grid holds L_in / (1 - T), the in-scattered light
per unit of extinguished light, which changes slowly along a ray (in a uniform medium it is
J / beta at every distance), and each point gets it back as that ratio, interpolated
trilinearly, times its own 1 - T from the transmittance table.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.transport._table_common_kernels import linear_axis
from skyscatter.transport._table_lookup_kernels import (
    RAYS_PER_BLOCK,
    add_reflected_light,
    aerial_scratch,
    aerial_segment,
    segment_start,
    transmittance_along,
    view_grid_cell,
)
from skyscatter.transport.table_parameterisation import (
    distance_to_bottom_boundary,
    horizon_zenith_angle,
    ray_intersects_ground,
)


@njit(cache=True)
def grid_depth(r, mu, bottom_radius, d_max):
    """d_end [m]: where the last depth node of the view (r, mu) sits, the ground's distance
    along rays that meet it when nearer than the frame's farthest point d_max."""
    if ray_intersects_ground(r, mu, bottom_radius):
        return min(distance_to_bottom_boundary(r, mu, bottom_radius), d_max)
    return d_max


@njit(parallel=True, cache=True)
def aerial_grid_cells(origin, points, sun_direction, cos_exact, bottom_radius, top_radius,
                      n_mu, n_phi, i_mu, k_phi, distance, exact):
    """Per point (n, 3) seen from `origin` (3,) inside the atmosphere: its cell on a grid of
    `sky_view_grid_nodes` (n_mu, n_phi) into i_mu and k_phi, its distance in the atmosphere
    [m] into distance (`segment_start`), and exact[j] = True where the grid does not serve it
    (within acos(cos_exact) of the sun, where the particles' phase functions peak, or no
    segment at all)."""
    r = math.sqrt(origin[0] ** 2 + origin[1] ** 2 + origin[2] ** 2)
    mu_s = (origin[0] * sun_direction[0] + origin[1] * sun_direction[1]
            + origin[2] * sun_direction[2]) / r
    theta_h = horizon_zenith_angle(min(max(r, bottom_radius), top_radius), bottom_radius)
    for j in prange(points.shape[0]):
        _, mu, _, nu, d, hits_ground = segment_start(
            origin[0], origin[1], origin[2], points[j, 0], points[j, 1], points[j, 2],
            sun_direction, bottom_radius, top_radius)
        i_mu[j], _, k_phi[j], _ = view_grid_cell(mu, nu, mu_s, theta_h, hits_ground, n_mu,
                                                 n_phi)
        distance[j] = d
        exact[j] = nu > cos_exact or not d > 0.0


@njit(cache=True)
def aerial_grid_node_points(origin, directions, d_max, bottom_radius, top_radius, n_depth):
    """The points (n_a, n_b, n_depth, 3) of the grid's nodes along world `directions`
    (n_a, n_b, 3) from `origin` (3,): d_end j / (n_depth - 1), j = 0 .. n_depth - 1
    (`grid_depth`)."""
    r = math.sqrt(origin[0] ** 2 + origin[1] ** 2 + origin[2] ** 2)
    r_0 = min(max(r, bottom_radius), top_radius)
    n_a, n_b = directions.shape[0], directions.shape[1]
    nodes = np.empty((n_a, n_b, n_depth, 3))
    for a in range(n_a):
        for b in range(n_b):
            v = directions[a, b]
            mu = (origin[0] * v[0] + origin[1] * v[1] + origin[2] * v[2]) / r
            d_end = grid_depth(r_0, mu, bottom_radius, d_max)
            for j in range(n_depth):
                nodes[a, b, j] = origin + (d_end * j / (n_depth - 1)) * v
    return nodes


@njit(parallel=True, cache=True)
def surface_radiance_points(origin, points, normals, lit, albedo, sun_direction, tables,
                            ratio_grid, n_mu, n_phi, i_first, k_first, d_max, exact, out):
    """Radiance (n, n_wl) reaching `origin` (3,) from Lambertian surfaces at `points` (n, 3)
    facing `normals` (n, 3), with spectral `albedo` ((n, n_wl) or (1, n_wl)), lit by the
    part `lit` (n,) in [0, 1] of the sunlight (0 in a terrain shadow, a cloud's transmittance
    under a cloud): L_in + T albedo / pi (lit E_sun + E_sky)
    (`add_reflected_light`), into out. L_in and T of the `exact` points by `aerial_segment`,
    of the others from `ratio_grid` (`_interpolated_segment`; only for one observer inside the
    atmosphere). `tables`: the `LookupTables` record."""
    n_points = points.shape[0]
    n_wl = out.shape[1]
    one_albedo = albedo.shape[0] == 1
    # the observer's horizon, for the grid's cells
    r = math.sqrt(origin[0] ** 2 + origin[1] ** 2 + origin[2] ** 2)
    theta_h = horizon_zenith_angle(min(max(r, tables.bottom_radius), tables.top_radius),
                                   tables.bottom_radius)
    n_blocks = (n_points + RAYS_PER_BLOCK - 1) // RAYS_PER_BLOCK
    for block in prange(n_blocks):
        work = aerial_scratch(tables, n_wl)
        t_view, direct, diffuse = np.empty(n_wl), np.empty(n_wl), np.empty(n_wl)
        scratch = np.empty(n_wl)
        for i in range(block * RAYS_PER_BLOCK, min(n_points, (block + 1) * RAYS_PER_BLOCK)):
            if exact[i]:
                aerial_segment(origin[0], origin[1], origin[2], points[i, 0], points[i, 1],
                               points[i, 2], sun_direction, tables, work, out[i], t_view)
            else:
                _interpolated_segment(origin, points[i], sun_direction, tables, ratio_grid,
                                      n_mu, n_phi, i_first, k_first, d_max, theta_h, scratch,
                                      out[i], t_view)
            add_reflected_light(points[i], normals[i], lit[i], albedo[0 if one_albedo else i],
                                sun_direction, tables, t_view, direct, diffuse, out[i])


@njit(cache=True)
def _interpolated_segment(origin, point, sun_direction, tables, ratio_grid, n_mu, n_phi,
                          i_first, k_first, d_max, theta_h, scratch, inscatter_out,
                          transmittance_out):
    """The segment from `origin` to `point`: its transmittance T from the table
    (`transmittance_along`) into transmittance_out, and the light scattered towards the
    observer in front of the point, (1 - T) times `ratio_grid` (n_a, n_b, n_depth, n_wl)
    interpolated trilinearly in the grid's mu and azimuth axes (cells from i_first and
    k_first of a grid of n_mu x n_phi, `view_grid_cell`, the observer's horizon at zenith
    angle theta_h) and d / d_end (`grid_depth`), into inscatter_out."""
    bottom_radius, top_radius = tables.bottom_radius, tables.top_radius
    r, mu, mu_s, nu, d, hits_ground = segment_start(
        origin[0], origin[1], origin[2], point[0], point[1], point[2], sun_direction,
        bottom_radius, top_radius)
    transmittance_along(r, mu, d, hits_ground, bottom_radius, top_radius, tables.transmittance,
                        transmittance_out, scratch)
    i, a, k, b = view_grid_cell(mu, nu, mu_s, theta_h, hits_ground, n_mu, n_phi)
    i -= i_first
    k -= k_first
    n_depth = ratio_grid.shape[2]
    j, c = linear_axis(d / grid_depth(r, mu, bottom_radius, d_max) * (n_depth - 1), n_depth)
    for w in range(inscatter_out.size):
        ratio = 0.0
        for di in range(2):
            wi = a if di else 1.0 - a
            for dk in range(2):
                wk = b if dk else 1.0 - b
                row = ratio_grid[i + di, k + dk]
                ratio += wi * wk * ((1.0 - c) * row[j, w] + c * row[j + 1, w])
        inscatter_out[w] = ratio * (1.0 - transmittance_out[w])
