"""Numba kernels shared by the two jobs of the precomputed tables: building them
(`_table_build_kernels`, run by `transport/tables.py`) and looking them up
(`_table_lookup_kernels`, run by `transport/lut_solver.py`). Everything here is part of the
precomputation, so the tables' cache key (`transport/code_fingerprint.py`) covers it.

Conventions (docs/physics/tables.md, Bruneton 2017 functions.glsl):
- Table coordinates come from `transport/table_parameterisation.py` only. Entry i of an axis of
  n entries holds the texel centre x = i / (n - 1); interpolation is linear on each axis
  (quadrilinear in the 4-D scattering table, the mu axis split into its ground / sky halves).
- Scattering tables are interleaved, (n_r, n_mu, n_mu_s, n_nu, n_t, n_wl): the n_t tables of a
  cell (single scattering per constituent, then multiple) and their wavelengths are adjacent,
  so a lookup reads each (r, mu, mu_s) corner's two nu slices in one contiguous run; it sums
  weights[t, w] * table_t (phase functions for single scattering, 1 for multiple).
- Phase functions inside kernels come from tables (n_s, n_angle, n_wl) sampled uniformly in the
  scattering angle over [0, pi], interpolated linearly.
- Table rays are sampled densest near their lowest point and near the observer
  (`table_ray_distances`); integrals use the trapezoid rule on the samples.
Kernels take arrays and floats only.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from skyscatter.transport.table_parameterisation import (
    scattering_u_mu,
    scattering_u_mu_s,
    scattering_u_nu,
    scattering_u_r,
    texel_index,
)


@njit(cache=True)
def linear_axis(f, n):
    """(i, a): lower entry and weight of the fractional index f on an axis of n >= 2 entries."""
    f = min(max(f, 0.0), n - 1.0)
    i = min(int(f), n - 2)
    return i, f - i


@njit(cache=True, error_model="numpy")
def fast_acos(x):
    """acos(x) [rad] within 2e-8 for x in [-1, 1] (Abramowitz & Stegun 1964, eq. 4.4.46: a
    polynomial times sqrt(1 - |x|)); branch-free, so loops over it vectorise."""
    a = abs(x)
    p = (1.5707963050 + a * (-0.2145988016 + a * (0.0889789874 + a * (-0.0501743046 + a * (
        0.0308918810 + a * (-0.0170881256 + a * (0.0066700901 + a * -0.0012624911)))))))
    angle = math.sqrt(max(1.0 - a, 0.0)) * p
    return angle if x >= 0.0 else math.pi - angle


# exp(-x) for x in [0, EXP_NEGATIVE_MAX] (`exp_negative`): beyond, exp(-x) < 1.8e-35 is taken as
# exp(-EXP_NEGATIVE_MAX), still a normal float32 (2^-115)
EXP_NEGATIVE_MAX = 80.0
LOG2_E = 1.4426950408889634
LN_2 = 0.6931471805599453


@njit(cache=True, inline="always")
def exp_negative(depth, out, power_bits, power):
    """out[w] = exp(-depth[w]) within 1e-8 relative for depth in [0, EXP_NEGATIVE_MAX] (clamped
    to it): exp(-x) = 2^n e^(f ln 2), n = round(-x log2 e), |f| <= 1/2, e^(f ln 2) by its Taylor
    series to degree 7 (remainder 0.347^8 / 8! < 6e-9) and 2^n from the bits of a float32
    (`power` a float32 view of the int32 scratch `power_bits`, both out.size). Branch-free
    loops that vectorise: math.exp is a library call per number (numba's LLVM has no vector
    math library), 3 ns each, most of the single scattering of an optically thick layer."""
    for w in range(out.size):
        y = -min(max(depth[w], 0.0), EXP_NEGATIVE_MAX) * LOG2_E
        n = np.floor(y + 0.5)
        f = (y - n) * LN_2
        out[w] = 1.0 + f * (1.0 + f * (1.0 / 2.0 + f * (1.0 / 6.0 + f * (1.0 / 24.0 + f * (
            1.0 / 120.0 + f * (1.0 / 720.0 + f * (1.0 / 5040.0)))))))
        power_bits[w] = (np.int32(n) + 127) << 23
    for w in range(out.size):
        out[w] *= power[w]


@njit(cache=True, inline="always")  # a call per cell and sample costs 15 % of single scattering
def transmittance_bilinear(transmittance, i, a, j, b, out):
    """Bilinear in `transmittance` (n_r_t, n_mu_t, n_wl) at row i + a and column j + b (lower
    entries and weights), into out (n_wl,)."""
    # row views, whose loop indexes from 0: numba vectorises it (no negative-index checks)
    t00, t01 = transmittance[i, j], transmittance[i, j + 1]
    t10, t11 = transmittance[i + 1, j], transmittance[i + 1, j + 1]
    for w in range(out.size):
        out[w] = ((1.0 - a) * ((1.0 - b) * t00[w] + b * t01[w])
                  + a * ((1.0 - b) * t10[w] + b * t11[w]))


@njit(cache=True)
def phase_values(phase_table, nu, out):
    """Phase functions at nu = cos(scattering angle), linear in the angle, from `phase_table`
    (n_s, n_angle, n_wl) sampled uniformly over [0, pi]; into out[s * n_wl + w] for s < n_s
    (out may be longer: the weights of a lookup, 1 for the multiple-scattering table) [sr^-1]."""
    n_angle = phase_table.shape[1]
    n_wl = phase_table.shape[2]
    theta = math.acos(min(max(nu, -1.0), 1.0))
    i, a = linear_axis(theta / math.pi * (n_angle - 1), n_angle)
    for s in range(phase_table.shape[0]):
        for w in range(n_wl):
            out[s * n_wl + w] = (1.0 - a) * phase_table[s, i, w] + a * phase_table[s, i + 1, w]


@njit(cache=True)
def mu_axis(r, mu, hits_ground, bottom_radius, top_radius, n_mu):
    """(i, a): lower entry and weight of the ray (r, mu) on a mu axis of n_mu entries
    (`scattering_u_mu`), the interpolation kept inside the half chosen by `hits_ground`."""
    return mu_axis_from_u(scattering_u_mu(r, mu, hits_ground, bottom_radius, top_radius, n_mu),
                          hits_ground, n_mu)


@njit(cache=True)
def mu_axis_from_u(u_mu, hits_ground, n_mu):
    """`mu_axis` of the table coordinate u_mu (`scattering_u_mu`)."""
    half = n_mu // 2
    f_mu = u_mu * n_mu - 0.5
    if hits_ground:
        f_mu = min(max(f_mu, 0.0), half - 1.0)
        i_mu = min(int(f_mu), half - 2)
    else:
        f_mu = min(max(f_mu, float(half)), n_mu - 1.0)
        i_mu = min(int(f_mu), n_mu - 2)
    return i_mu, f_mu - i_mu


@njit(cache=True)
def radius_corner(r, bottom_radius, top_radius, n_r, radius_warp):
    """(i, a): lower entry and weight of radius r on a scattering table's r axis."""
    return linear_axis(texel_index(scattering_u_r(r, bottom_radius, top_radius, n_r,
                                                  radius_warp), n_r), n_r)


@njit(cache=True)
def mu_s_corner(mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share, n_mu_s):
    """(i, a): lower entry and weight of mu_s on a scattering table's mu_s axis."""
    return linear_axis(texel_index(
        scattering_u_mu_s(mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share, n_mu_s),
        n_mu_s), n_mu_s)


@njit(cache=True)
def nu_corner(nu, mu, mu_s, n_nu):
    """(i, a): lower entry and weight of nu on a scattering table's nu axis."""
    return linear_axis(scattering_u_nu(nu, mu, mu_s) * (n_nu - 1), n_nu)


@njit(cache=True, inline="always")
def corner_sum(flat, base, s_r, s_mu, s_s, a_r, a_mu, a_s, out):
    """out[k] += the interleaved tables `flat` (1-D, `flat_tables`) trilinear in r, mu and mu_s
    at the corners base + (0 or s_r) + (0 or s_mu) + (0 or s_s) (weights a_r, a_mu, a_s of the
    upper ones), for the out.size contiguous numbers from each corner (its nu slices, tables
    and wavelengths); corners of weight 0 are not read."""
    size = out.size
    for dr in range(2):
        wr = a_r if dr == 1 else 1.0 - a_r
        if wr == 0.0:
            continue
        for dm in range(2):
            wm = wr * (a_mu if dm == 1 else 1.0 - a_mu)
            if wm == 0.0:
                continue
            for ds in range(2):
                ws = wm * (a_s if ds == 1 else 1.0 - a_s)
                if ws == 0.0:
                    continue
                offset = base + dr * s_r + dm * s_mu + ds * s_s
                segment = flat[offset:offset + size]
                for k in range(size):
                    out[k] += ws * segment[k]


@njit(cache=True, inline="always")
def nu_interpolation(profile, weights, i_nu, a_nu, out):
    """out[w] += sum_t weights[t n_wl + w] x `profile` linear in nu between its slices i_nu and
    i_nu + 1 (weight a_nu of the upper), each slice m = weights.size numbers (n_t tables of
    n_wl wavelengths): the tables interpolated in r, mu and mu_s (`corner_sum`) on nu slices,
    with the phase functions (or 1) as weights."""
    m = weights.size
    n_wl = out.size
    below = profile[i_nu * m:(i_nu + 1) * m]  # row views: their loops vectorise
    above = profile[(i_nu + 1) * m:(i_nu + 2) * m]
    for t in range(m // n_wl):
        for w in range(n_wl):
            k = t * n_wl + w
            out[w] += weights[k] * ((1.0 - a_nu) * below[k] + a_nu * above[k])


def flat_tables(tables: np.ndarray) -> np.ndarray:
    """An interleaved scattering table (n_r, n_mu, n_mu_s, n_nu, [n_t,] n_wl) as the 1-D view
    `scattering_lookup` reads (a copy only if it is not C-contiguous)."""
    return np.ascontiguousarray(tables).reshape(-1)


@njit(cache=True)
def table_ray_distances(r, mu, d, hits_ground, n_samples, out):
    """Sample distances along the table ray (r, mu) of length d, increasing from 0 to d, into
    out; returns their number (n_samples + 1). Where they crowd:
    - upward rays (lowest point at the start): t = d (k/n)^2, dense near the start;
    - rays that hit the ground: t = d (1 - cos(pi k/n)) / 2, dense near the observer (the
      attenuation of thick paths) and near the ground (the densest air);
    - rays through a tangent point t_p = -r mu: half the samples on [0, t_p] with the cosine
      law (dense at the observer and at t_p), half on [t_p, d] with t_p + (d - t_p) (k/m)^2.
    Unlike the ray-marching solver (`_kernels.sample_distance`, dense at the tangent point
    only), the observer's end is resolved too: a ray from 1 km just above the horizon has its
    light within ~30 km of the observer in the blue."""
    t_tangent = -r * mu
    if hits_ground:
        for k in range(n_samples + 1):
            out[k] = 0.5 * d * (1.0 - math.cos(math.pi * k / n_samples))
    elif t_tangent <= 0.0 or t_tangent >= d:
        for k in range(n_samples + 1):
            out[k] = d * (k / n_samples) ** 2
    else:
        m1 = n_samples // 2
        m2 = n_samples - m1
        for k in range(m1 + 1):
            out[k] = 0.5 * t_tangent * (1.0 - math.cos(math.pi * k / m1))
        for k in range(1, m2 + 1):
            out[m1 + k] = t_tangent + (d - t_tangent) * (k / m2) ** 2
    out[n_samples] = d
    return n_samples + 1
