"""Kernels of the clouds' shadows in the air (`transport.air_shadows` has the equations): the
water towards the sun on a map of sun-parallel lines, and the sunlight the shaded air along
each view ray no longer scatters.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.atmosphere._cloud_sampling import BASE_R, TOP_R, smooth_layer_water
from skyscatter.atmosphere.cloud_noise import hash32
from skyscatter.transport._cloud_kernels import _table_lookup
from skyscatter.transport._two_stream import EDDINGTON, beam_passed

__all__ = ["MAP_MAX_STEPS", "MAP_STEP_M", "SHADOW_SAMPLES", "shadow_loss", "sun_line_water"]

MAP_STEP_M = 60.0  # step along each sun-parallel line of the map [m] ...
MAP_MAX_STEPS = 160  # ... at most this many per line (a low sun's long slant through a layer)
SHADOW_SAMPLES = 16  # samples along the shaded stretch of each view ray, denser near its start


@njit(cache=True, parallel=True)
def sun_line_water(origin, e1, e2, sun, corner, texel, levels, params, profiles, textures,
                   out):
    """out (n_u, n_w, n_levels, n_layers): the water [g m^-2] of each layer towards the sun
    along the line through origin + u e1 + w e2 (u, w at texel centres from `corner` (2,) in
    steps of `texel` [m]) parallel to unit `sun`, from where it leaves the sphere of each
    radius in `levels` (ascending) [m]."""
    n_u, n_w, n_levels, n_layers = out.shape
    top = levels[n_levels - 1]
    for iu in prange(n_u):
        cumulative = np.zeros((MAP_MAX_STEPS + 1, n_layers))
        for iw in range(n_w):
            u = corner[0] + (iu + 0.5) * texel
            w = corner[1] + (iw + 0.5) * texel
            qx = origin[0] + u * e1[0] + w * e2[0]
            qy = origin[1] + u * e1[1] + w * e2[1]
            qz = origin[2] + u * e1[2] + w * e2[2]
            b = qx * sun[0] + qy * sun[1] + qz * sun[2]
            c = qx * qx + qy * qy + qz * qz
            if b * b - c + top * top <= 0.0:
                out[iu, iw] = 0.0
                continue
            a_top = -b + math.sqrt(b * b - c + top * top)
            a_start = _exit(b, c, levels[0])
            steps = min(max(int(math.ceil((a_top - a_start) / MAP_STEP_M)), 1), MAP_MAX_STEPS)
            da = (a_top - a_start) / steps
            for step in range(steps):
                a = a_start + (step + 0.5) * da
                x, y, z = qx + a * sun[0], qy + a * sun[1], qz + a * sun[2]
                r = math.sqrt(x * x + y * y + z * z)
                for layer in range(n_layers):
                    water = 0.0
                    if params[layer, BASE_R] <= r <= params[layer, TOP_R]:
                        water = smooth_layer_water(params, profiles, textures, layer, x, y, z,
                                                   r) * da
                    cumulative[step + 1, layer] = cumulative[step, layer] + water
            for k in range(n_levels):
                f = min(max((_exit(b, c, levels[k]) - a_start) / da, 0.0), float(steps))
                j = min(int(f), steps - 1)
                f -= j
                for layer in range(n_layers):
                    passed = (cumulative[j, layer] * (1.0 - f) + cumulative[j + 1, layer] * f)
                    out[iu, iw, k, layer] = cumulative[steps, layer] - passed


@njit(cache=True, inline="always")
def _exit(b, c, radius):
    """Where the line q + a s (b = q.s, c = |q|^2) leaves the sphere `radius`: its larger
    root, or its closest approach to the centre if it passes outside."""
    disc = b * b - c + radius * radius
    return -b + math.sqrt(disc) if disc > 0.0 else -b


@njit(cache=True, parallel=True)
def shadow_loss(origin, directions, ray_ids, stretch, start_transmittance, sun, shadow_map,
                air, clouds, out):
    """out (n, n_wl): the sunlight [W m^-2 sr^-1 nm^-1] the air along each view ray no
    longer scatters towards `origin` because clouds shade it (`transport.air_shadows`); each
    ray's jitter follows from its id in `ray_ids` (n,).

    `stretch` (n, 2): the distances [m] between which the ray is marched;
    `start_transmittance` (n, n_wl): the air's transmittance from `origin` to the first;
    `shadow_map` = (water (n_u, n_w, n_levels, n_layers) of `sun_line_water`, e1, e2,
    corner, texel, levels); `air` = (bottom radius [m], altitude step [m], density (n_s, n_z),
    scattering per density (n_s, n_wl), extinction per density (n_c, n_wl), all densities
    (n_c, n_z), phase tables (n_s, n_angles, n_wl) at theta = pi i / (n_angles - 1), r_nodes,
    mu_nodes and the air's transmittance towards the sun (n_r, n_mu, n_wl), the sun's
    top-of-atmosphere irradiance (n_wl,)); `clouds` = (mass extinction, asymmetry) (n_layers,
    n_wl) [m^2 g^-1], [-]."""
    (bottom, h_step, density, scattering, extinction, all_density, phase, r_nodes, mu_nodes,
     sun_air, sun_toa) = air
    cloud_extinction, asymmetry = clouds
    n_wl = out.shape[1]
    for i in prange(directions.shape[0]):
        out[i] = 0.0
        t_a, t_b = stretch[i, 0], stretch[i, 1]
        if t_b <= t_a:
            continue
        v = directions[i]
        nu = v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2]
        phases = _phases(phase, nu)
        depth = np.zeros(n_wl)  # the air's optical depth from the stretch's start
        t_air = np.empty(n_wl)
        paths = np.empty(cloud_extinction.shape[0])
        all_at = np.empty(all_density.shape[0])
        scattering_at = np.empty(density.shape[0])
        jitter = (float(hash32(ray_ids[i])) + 0.5) / 4294967296.0
        length = t_b - t_a
        previous = t_a
        for j in range(SHADOW_SAMPLES):
            lo = t_a + length * (j / SHADOW_SAMPLES) ** 2
            hi = t_a + length * ((j + 1) / SHADOW_SAMPLES) ** 2
            t = lo + jitter * (hi - lo)
            x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
            r = math.sqrt(x * x + y * y + z * z)
            # the air's optical depth from the last sample (midpoint extinction)
            tm = 0.5 * (previous + t)
            xm, ym, zm = origin[0] + tm * v[0], origin[1] + tm * v[1], origin[2] + tm * v[2]
            _densities(all_density, math.sqrt(xm * xm + ym * ym + zm * zm) - bottom, h_step,
                       all_at)
            for k in range(n_wl):
                sigma = 0.0
                for c in range(all_at.size):
                    sigma += all_at[c] * extinction[c, k]
                depth[k] += sigma * (t - previous)
            previous = t
            if not _sun_water(shadow_map, origin, x, y, z, r, paths):
                continue
            mu_s = (x * sun[0] + y * sun[1] + z * sun[2]) / r
            _table_lookup(sun_air, r_nodes, mu_nodes, r, mu_s, t_air)
            _densities(density, r - bottom, h_step, scattering_at)
            for k in range(n_wl):
                tau, gamma_tau = 0.0, 0.0
                for layer in range(paths.size):
                    cloud_depth = cloud_extinction[layer, k] * paths[layer]
                    tau += cloud_depth
                    gamma_tau += EDDINGTON * (1.0 - asymmetry[layer, k]) * cloud_depth
                direct = math.exp(-tau)
                # the two-stream's net flux
                slab = beam_passed(gamma_tau * max(mu_s, 0.0), direct, max(mu_s, 0.0))
                single, total = 0.0, 0.0
                for c in range(scattering_at.size):
                    sigma = scattering_at[c] * scattering[c, k]
                    single += sigma * phases[c, k]
                    total += sigma
                glow = total * max(mu_s, 0.0) * max(slab - direct, 0.0) / (2.0 * math.pi)
                trans = start_transmittance[i, k] * math.exp(-depth[k])
                out[i, k] += (sun_toa[k] * t_air[k] * trans
                              * (single * (1.0 - direct) - glow) * (hi - lo))



@njit(cache=True, inline="always")
def _densities(density, h, h_step, out):
    """out[c] = constituent c's density at altitude h [m], linear between the levels."""
    x = min(max(h / h_step, 0.0), density.shape[1] - 1.0)
    i = min(int(x), density.shape[1] - 2)
    f = x - i
    for c in range(out.size):
        out[c] = density[c, i] * (1.0 - f) + density[c, i + 1] * f


@njit(cache=True)
def _phases(phase, nu):
    """The constituents' phase functions (n_s, n_wl) [sr^-1] at cos(scattering angle) nu."""
    n_s, n_angles, n_wl = phase.shape
    x = math.acos(min(1.0, max(-1.0, nu))) / math.pi * (n_angles - 1)
    j = min(int(x), n_angles - 2)
    f = x - j
    out = np.empty((n_s, n_wl))
    for s in range(n_s):
        for k in range(n_wl):
            out[s, k] = phase[s, j, k] * (1.0 - f) + phase[s, j + 1, k] * f
    return out


@njit(cache=True)
def _sun_water(shadow_map, origin, x, y, z, r, paths):
    """paths[:] = each layer's water [g m^-2] towards the sun from the point (x, y, z),
    |p| = r (bilinear in the map, linear in radius between its levels); whether any."""
    water, e1, e2, corner, texel, levels = shadow_map
    n_u, n_w, n_levels, n_layers = water.shape
    paths[:] = 0.0
    if r >= levels[n_levels - 1]:
        return False
    dx, dy, dz = x - origin[0], y - origin[1], z - origin[2]
    fu = min(max((dx * e1[0] + dy * e1[1] + dz * e1[2] - corner[0]) / texel - 0.5, 0.0),
             n_u - 1.0)
    fw = min(max((dx * e2[0] + dy * e2[1] + dz * e2[2] - corner[1]) / texel - 0.5, 0.0),
             n_w - 1.0)
    iu, iw = min(int(fu), max(n_u - 2, 0)), min(int(fw), max(n_w - 2, 0))
    fu, fw = fu - iu, fw - iw
    iu1, iw1 = min(iu + 1, n_u - 1), min(iw + 1, n_w - 1)
    fl = 0.0
    if n_levels > 1:
        fl = min(max((r - levels[0]) / (levels[1] - levels[0]), 0.0), n_levels - 1.0)
    il = min(int(fl), max(n_levels - 2, 0))
    fl -= il
    il1 = min(il + 1, n_levels - 1)
    any_water = False
    for layer in range(n_layers):
        low = ((water[iu, iw, il, layer] * (1.0 - fw) + water[iu, iw1, il, layer] * fw)
               * (1.0 - fu)
               + (water[iu1, iw, il, layer] * (1.0 - fw) + water[iu1, iw1, il, layer] * fw) * fu)
        high = ((water[iu, iw, il1, layer] * (1.0 - fw) + water[iu, iw1, il1, layer] * fw)
                * (1.0 - fu)
                + (water[iu1, iw, il1, layer] * (1.0 - fw) + water[iu1, iw1, il1, layer] * fw)
                * fu)
        paths[layer] = low * (1.0 - fl) + high * fl
        any_water |= paths[layer] > 0.0
    return any_water
