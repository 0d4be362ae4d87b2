"""numba kernels of `beam_spread`: the sun's optical depths and the light scattered only in
forward peaks, marched in the sun's vertical plane.

A point of the plane is (h, theta): its altitude and its angle from the sun's axis through the
planet's centre (the sun's zenith angle there); a direction is its angle delta from the sun's,
positive towards the point's zenith. Along a straight line delta does not change; (h, theta)
do. Public names: `sun_depths`, `sweep`.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__ = ["sun_depths", "sweep"]


@njit(cache=True)
def _level_index(altitude, dz, n_levels):
    """(i, t): `altitude` between levels i and i + 1 (every dz from the ground), t the fraction;
    i = -1 above the last level (nothing there), the ground's level below the ground."""
    if altitude <= 0.0:
        return 0, 0.0
    i = int(altitude / dz)
    if i >= n_levels - 1:
        return -1, 0.0
    return i, altitude / dz - i


@njit(cache=True)
def _at_level(table, i, t, w):
    """table[:, w] between levels i and i + 1 (`_level_index`)."""
    if i < 0:
        return 0.0
    return table[i, w] * (1.0 - t) + table[i + 1, w] * t


@njit(cache=True)
def _below(table, column, i, t, dz, w):
    """Vertical optical depth from the ground to the altitude between levels i and i + 1
    (`_level_index`), exact for `table` linear between levels; column[i, w] the depth to
    level i. Above the last level: the whole column."""
    if i < 0:
        return column[column.shape[0] - 1, w]
    return column[i, w] + dz * t * (table[i, w] + 0.5 * t * (table[i + 1, w] - table[i, w]))


@njit(cache=True)
def _step_depth(altitude_from, altitude_to, below_from, below_to, beta_from, beta_to, length):
    """Optical depth of a step of `length` along which the altitude goes monotonically from
    altitude_from to altitude_to: the mean extinction over the altitudes it crosses times its
    length (exact through a thin layer, which a trapezoid in the distance is not), the
    trapezoid where it stays level (within 1 m)."""
    if abs(altitude_to - altitude_from) > 1.0:
        return (below_to - below_from) / (altitude_to - altitude_from) * length
    return 0.5 * (beta_from + beta_to) * length


@njit(cache=True)
def _bracket(x, nodes):
    """(i, t) with nodes[i] <= x <= nodes[i + 1], t the fraction; clamped to the ends."""
    n = nodes.size
    if x <= nodes[0]:
        return 0, 0.0
    if x >= nodes[n - 1]:
        return n - 2, 1.0
    i = min(np.searchsorted(nodes, x, side="right") - 1, n - 2)
    return i, (x - nodes[i]) / (nodes[i + 1] - nodes[i])


@njit(cache=True)
def _piece(r_from, r_to, r, mu, tangent2, sign, bottom, levels, share, n, out, k):
    """Append to out[k:] n distances along the ray from radius r (direction cosine mu, the
    squared tangent radius tangent2) where its radius goes monotonically from r_from to r_to,
    uniform in `share` (a coordinate increasing with altitude on `levels`), the last at r_to;
    sign -1 while the ray descends, +1 while it rises. Returns the new k."""
    u_from = np.interp(r_from - bottom, levels, share)
    u_to = np.interp(r_to - bottom, levels, share)
    for j in range(1, n + 1):
        radius = r_to if j == n else bottom + np.interp(u_from + (u_to - u_from) * j / n,
                                                        share, levels)
        out[k] = max(-r * mu + sign * np.sqrt(max(radius * radius - tangent2, 0.0)), 0.0)
        k += 1
    return k


@njit(cache=True)
def _ray_samples(r, mu, bottom, top, levels, share, n_steps, out):
    """Distances along the ray from radius r with zenith cosine mu to where it leaves the top
    or meets the ground, sorted into out[:count] from 0: n_steps every equal step of `share`
    on each piece where the radius changes monotonically (so that a thin layer, a cloud deck,
    gets its samples), and n_steps denser near the start (quadratic in the distance, for the
    long nearly level stretches). Returns (count, whether the ray meets the ground)."""
    tangent2 = r * r * (1.0 - mu * mu)
    out[0] = 0.0
    k = 1
    ground = False
    if mu >= 0.0:
        k = _piece(r, top, r, mu, tangent2, 1.0, bottom, levels, share, n_steps, out, k)
    elif tangent2 < bottom * bottom:
        ground = True
        k = _piece(r, bottom, r, mu, tangent2, -1.0, bottom, levels, share, n_steps, out, k)
    else:
        tangent = np.sqrt(tangent2)
        k = _piece(r, tangent, r, mu, tangent2, -1.0, bottom, levels, share, n_steps, out, k)
        k = _piece(tangent, top, r, mu, tangent2, 1.0, bottom, levels, share, n_steps, out, k)
    end = out[k - 1]
    for j in range(1, n_steps):
        out[k] = end * (j / n_steps) ** 2
        k += 1
    out[:k].sort()
    return k, ground


@njit(parallel=True, cache=True)
def sun_depths(bottom, top, h_nodes, theta_nodes, extinction, column, dz, levels, share,
               n_steps):
    """Optical depth towards the sun from each node (n_h, n_theta, n_w), inf where the ground
    is in the way; `extinction` (n_z, n_w) [m^-1] on `levels` every dz [m], `column` its
    vertical optical depth from the ground to each level; sampled by `_ray_samples` with
    `share` on those levels."""
    n_h, n_t, n_w = h_nodes.size, theta_nodes.size, extinction.shape[1]
    n_levels = extinction.shape[0]
    out = np.zeros((n_h, n_t, n_w))
    for node in prange(n_h * n_t):
        k = node // n_t
        m = node % n_t
        r = bottom + h_nodes[k]
        mu = np.cos(theta_nodes[m])
        samples = np.empty(4 * n_steps + 1)
        count, ground = _ray_samples(r, mu, bottom, top, levels, share, n_steps, samples)
        if ground:
            out[k, m, :] = np.inf
            continue
        beta, below = np.empty(n_w), np.empty(n_w)
        altitude = h_nodes[k]
        lv, lt = _level_index(altitude, dz, n_levels)
        for w in range(n_w):
            beta[w] = _at_level(extinction, lv, lt, w)
            below[w] = _below(extinction, column, lv, lt, dz, w)
        for j in range(1, count):
            s = samples[j]
            previous, altitude = altitude, np.sqrt(r * r + s * s + 2.0 * r * mu * s) - bottom
            lv, lt = _level_index(altitude, dz, n_levels)
            for w in range(n_w):
                beta_here = _at_level(extinction, lv, lt, w)
                below_here = _below(extinction, column, lv, lt, dz, w)
                out[k, m, w] += _step_depth(previous, altitude, below[w], below_here, beta[w],
                                            beta_here, s - samples[j - 1])
                beta[w], below[w] = beta_here, below_here
    return out


@njit(cache=True)
def _source_at(source, a, ta, b, tb, i, w):
    """source[:, :, i, w] bilinear between nodes (a, b) and (a + 1, b + 1)."""
    return ((1.0 - ta) * ((1.0 - tb) * source[a, b, i, w] + tb * source[a, b + 1, i, w])
            + ta * ((1.0 - tb) * source[a + 1, b, i, w] + tb * source[a + 1, b + 1, i, w]))


@njit(parallel=True, cache=True)
def sweep(bottom, top, h_nodes, theta_nodes, deltas, extinction, column, peak, dz, levels,
          share, n_steps, kernel, direct, scaled, source, field):
    """One Gauss-Seidel sweep of the light scattered only in peaks, field (n_h, n_theta,
    n_delta, n_w): at each node, for each direction delta_i, on the samples of
    `_ray_samples` and exact in each step's optical depth,

        F(x, delta_i) = integral T_e(x, y) beta_p(y) S(y, delta_i) ds

    along the line from x towards where the light came from, y = x + s (sin delta, cos delta),
    up to the top or the ground, with S = K (direct + F) the light the peak events at y send
    into delta_i (`kernel` (n_w, n_delta, n_delta): column j where light at delta_j goes,
    `direct` (n_h, n_theta, n_w) the unscattered sun, at delta = 0, the middle node). Nodes
    are taken away from the sun's axis (theta up) and from the top down, so that the lines,
    which rise towards the sun while it is above the point's horizon, read nodes already
    updated; `source` (n_h, n_theta, n_delta, n_w) is updated with each node. Returns the
    largest change of the field's integral over delta relative to the scaled beam `scaled`
    (n_h, n_theta, n_w) (a change of G), where that beam is above 1e-3 of the sun."""
    n_h, n_t, n_d, n_w = field.shape
    n_levels = extinction.shape[0]
    change = 0.0
    for m in range(n_t):
        for k in range(n_h - 1, -1, -1):
            r = bottom + h_nodes[k]
            x0, y0 = r * np.sin(theta_nodes[m]), r * np.cos(theta_nodes[m])
            for i in prange(n_d):
                ox, oy = np.sin(deltas[i]), np.cos(deltas[i])
                samples = np.empty(4 * n_steps + 1)
                count, _ = _ray_samples(r, np.cos(theta_nodes[m] - deltas[i]), bottom, top,
                                        levels, share, n_steps, samples)
                transmittance = np.ones(n_w)
                total = np.zeros(n_w)
                ratio = np.zeros(n_w)  # beta_p S / beta_e at the previous sample
                beta, below = np.empty(n_w), np.empty(n_w)
                altitude = h_nodes[k]
                for j in range(count):
                    s = samples[j]
                    px, py = x0 + s * ox, y0 + s * oy
                    previous, altitude = altitude, np.sqrt(px * px + py * py) - bottom
                    lv, lt = _level_index(altitude, dz, n_levels)
                    # a point beyond the sun's axis is its mirror image, seen mirrored
                    theta = np.arctan2(px, py)
                    mirrored = np.int64(i)  # prange may give an unsigned index
                    if theta < 0.0:
                        theta = -theta
                        mirrored = np.int64(n_d - 1) - np.int64(i)
                    a, ta = _bracket(altitude, h_nodes)
                    b, tb = _bracket(theta, theta_nodes)
                    for w in range(n_w):
                        beta_here = _at_level(extinction, lv, lt, w)
                        below_here = _below(extinction, column, lv, lt, dz, w)
                        ratio_here = 0.0
                        if beta_here > 0.0:
                            ratio_here = (_at_level(peak, lv, lt, w) / beta_here
                                          * _source_at(source, a, ta, b, tb, mirrored, w))
                        if j > 0:
                            # exact in the step's optical depth, the ratio linear in it
                            step = np.exp(-_step_depth(previous, altitude, below[w],
                                                       below_here, beta[w], beta_here,
                                                       s - samples[j - 1]))
                            total[w] += transmittance[w] * (1.0 - step) * 0.5 * (
                                ratio[w] + ratio_here)
                            transmittance[w] *= step
                        beta[w], below[w], ratio[w] = beta_here, below_here, ratio_here
                for w in range(n_w):
                    field[k, m, i, w] = total[w]
            for w in range(n_w):
                previous = 0.0
                for j in range(n_d):
                    previous += source[k, m, j, w]
                scattered = 0.0
                for j in range(n_d):
                    scattered += field[k, m, j, w]
                centre = n_d // 2
                for i in range(n_d):
                    value = kernel[w, i, centre] * direct[k, m, w]
                    for j in range(n_d):
                        value += kernel[w, i, j] * field[k, m, j, w]
                    source[k, m, i, w] = value
                # the source's integral is direct + the field's (K conserves light)
                if scaled[k, m, w] > 1e-3:
                    change = max(change, abs(scattered + direct[k, m, w] - previous)
                                 / scaled[k, m, w])
    return change
