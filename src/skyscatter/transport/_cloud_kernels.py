"""Kernels that march rays through cloud layers (`transport.clouds`).

`march_clouds` integrates, per ray and wavelength, the light the clouds scatter towards the
observer and their transmittance, layer by layer in the order the ray meets them:

    L = sum_k T_k omega J_k (1 - exp(-sigma_k dt)),   T_{k+1} = T_k exp(-sigma_k dt)

(Hillaire 2016 eq. 4, for a source J constant over each step; here J is taken at both ends
of each step and integrated as exponential in between, so that an optically thick step - a
cumulus's sunlit skin is ~10 m deep - gets its light right without noise), with
sigma = k_ext w the extinction coefficient of the water content w (`atmosphere.cloud_field`)
and J the light each sample scatters per unit scattering:

    J = E_sun T_air(h, mu_s) p(nu) e^(-tau_sun)                      single scattering
        + E_sun T_air mu_s B(d_sun, d_anti; mu_s)                       the sun, diffused
        + E_down D(d_up, d_down) + E_up D(d_down, d_up)                sky and ground

- single scattering of the sunlight exactly: the star's top-of-atmosphere irradiance through
  the air (transmittance table) and through the cloud's water towards it, W_sun [g m^-2]
  (marched from `LIGHT_FIRST_M`, doubling; tau_sun = k_ext W_sun), with the particles' phase
  function (the Mie table with its diffraction peak: the silver lining);
- the light scattered more than once, from a conservative two-stream slab in Eddington's
  approximation around each sample (`transport._two_stream`): B for the sunlight, a beam
  entering a horizontal slab whose optical depths from the sample to its lit and far faces are
  the water paths towards the sun and away from it made vertical (d = k_ext W mu_s); D for the
  sky's diffuse light from above (the indirect-irradiance table) and the ground's from below,
  entering vertical slabs of the water above and below, the ground's dimmed by the clouds
  around (`transport.clouds.ground_shade`, in the table: against the cloud column above each
  sample, which left a broken field's cloud bodies 6-12 % too dark). Against DISORT for a
  conservative slab (HG g = 0.75; tests/transport/test_clouds.py) this gives the reflectance
  and transmittance within a few per cent for the sun up to 40 degrees from the zenith; 3D
  clouds are judged against the Monte Carlo reference (docs/clouds.md).

A sheet layer (cirrus) is sampled once per ray, in the middle of its chord through the
shell, with its water paths to the sun and to the shell's faces taken as uniform.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from skyscatter.atmosphere._cloud_sampling import (
    BASE_R,
    COLUMN_BINS,
    COLUMN_SHARES,
    FAR_END,
    FAR_START,
    SHEET,
    TOP_R,
    column_cover,
    coverage_map_factor,
    edge_margin,
    layer_water,
    phase_table_index,
    smooth_layer_water,
)
from skyscatter.atmosphere.cloud_noise import hash32
from skyscatter.transport._two_stream import EDDINGTON, beam_source, diffuse_source

__all__ = [
    "AMBIENT_FIRST_M",
    "LIGHT_FIRST_M",
    "LIGHT_MAX_M",
    "COARSE_STEPS",
    "EDGE_BISECTIONS",
    "EMPTY_TO_COARSE",
    "MAX_STEPS",
    "MIN_STEP_M",
    "NEAR_EDGE",
    "NEAR_STEP_M",
    "OPTICAL_STEP",
    "STEP_GROWTH",
    "STEP_M",
    "TRANSMITTANCE_CUTOFF",
    "cloud_water_paths",
    "march_clouds",
]

STEP_M = 80.0  # step along view rays near the observer [m]: a cumulus edge ramp is ~100-300 m
STEP_GROWTH = 0.006  # steps grow with distance as the pixels' footprint: 80 m at 13 km
COARSE_STEPS = 3  # in empty air the march takes steps this many times longer ...
EMPTY_TO_COARSE = 3  # ... after this many empty samples, and backs up when it meets a cloud
MAX_STEPS = 256  # per layer crossed
EDGE_BISECTIONS = 7  # a cloud's edge is found to 1/128 of the step that met it
OPTICAL_STEP = 2.0  # inside a cloud a step spans at most this optical depth (1.5: 0.3 %
# closer to the slab's integral, 1.4 x the time) ...
MIN_STEP_M = 5.0  # ... and is at least this long [m]: a cumulus's skin in 4-6 samples
LIGHT_FIRST_M = 12.0  # the water path towards the sun: segments from 12 m, doubling ...
LIGHT_MAX_M = 6000.0  # ... up to this far (9 samples; the light beyond is long lost) [m]
AMBIENT_FIRST_M = 50.0  # the water away from the sun, above and below: segments from 50 m,
# doubling (from 25 m, and 12 m away from the sun: the same images within 0.1 %, 7 % slower)
NEAR_EDGE = 2.0  # an empty sample this many edge ramps from a cloud (`edge_margin`) ...
NEAR_STEP_M = 20.0  # ... ends its step there and the march goes on in steps this long [m]:
# a ray through the edge of a cumulus for 100 m was met by 40 % of the jitters (its step
# of 240 m sampled once), 88 % so
TRANSMITTANCE_CUTOFF = 1e-3  # a ray stops when every wavelength's transmittance is below this


@njit(cache=True, inline="always")
def _sphere_roots(b, c, radius):
    """Roots (t0, t1) of |o + t v|^2 = radius^2 with b = o . v, c = |o|^2; (nan, nan) if none."""
    disc = b * b - c + radius * radius
    if disc < 0.0:
        return math.nan, math.nan
    root = math.sqrt(disc)
    return -b - root, -b + root


@njit(cache=True)
def _shell_intervals(o, v, base_r, top_r, t_max, out):
    """The (at most two) intervals of t in [0, t_max] where o + t v lies between the spheres
    base_r and top_r, into `out` (2, 2); returns their number."""
    b = o[0] * v[0] + o[1] * v[1] + o[2] * v[2]
    c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
    t0, t1 = _sphere_roots(b, c, top_r)
    if math.isnan(t0):
        return 0
    s0, s1 = _sphere_roots(b, c, base_r)
    if math.isnan(s0):  # the ray's line misses the inner sphere
        s0, s1 = t1, t1
    count = _add_interval(max(t0, 0.0), min(t1, s0, t_max), out, 0)
    return _add_interval(max(t0, s1, 0.0), min(t1, t_max), out, count)


@njit(cache=True, inline="always")
def _add_interval(lo, hi, out, count):
    if hi > lo:
        out[count, 0], out[count, 1] = lo, hi
        count += 1
    return count


@njit(cache=True)
def _path_water(params, profiles, textures, layer, x, y, z, dx, dy, dz, length, first):
    """Water path [g m^-2] of `layer` from (x, y, z) along the unit (dx, dy, dz) over
    `length` [m], midpoint sums on segments that start `first` [m] long and double: fine
    where the light is lost (a cumulus's sunlit skin is ~10 m deep), coarse beyond; the water
    without its detail erosion (`smooth_layer_water`)."""
    total = 0.0
    start = 0.0
    segment = first
    while start < length:
        end = min(start + segment, length)
        s = 0.5 * (start + end)
        px, py, pz = x + s * dx, y + s * dy, z + s * dz
        r = math.sqrt(px * px + py * py + pz * pz)
        total += smooth_layer_water(params, profiles, textures, layer, px, py, pz, r) * (
            end - start)
        start = end
        segment *= 2.0
    return total


@njit(cache=True)
def _exit_length(x, y, z, r, dx, dy, dz, base_r, top_r):
    """Distance from a point inside a shell along (dx, dy, dz) to the shell's edge."""
    b = x * dx + y * dy + z * dz
    c = r * r
    t_top = _sphere_roots(b, c, top_r)[1]
    s0, _ = _sphere_roots(b, c, base_r)
    if not math.isnan(s0) and s0 > 0.0:
        return min(t_top, s0)
    return t_top


@njit(cache=True)
def _table_lookup(table, r_nodes, mu_nodes, r, mu, out):
    """out[:] = bilinear `table` (n_r, n_mu, n_wl) at (r, mu), clamped; nodes uniform."""
    n_r, n_mu = r_nodes.size, mu_nodes.size
    x = (r - r_nodes[0]) / (r_nodes[-1] - r_nodes[0]) * (n_r - 1) if n_r > 1 else 0.0
    y = (mu - mu_nodes[0]) / (mu_nodes[-1] - mu_nodes[0]) * (n_mu - 1)
    x = min(max(x, 0.0), n_r - 1.0)
    y = min(max(y, 0.0), n_mu - 1.0)
    i = min(int(x), max(n_r - 2, 0))
    j = min(int(y), n_mu - 2)
    fx = x - i if n_r > 1 else 0.0
    fy = y - j
    i1 = min(i + 1, n_r - 1)
    for k in range(out.size):
        value = ((table[i, j, k] * (1 - fy) + table[i, j + 1, k] * fy) * (1 - fx)
                 + (table[i1, j, k] * (1 - fy) + table[i1, j + 1, k] * fy) * fx)
        out[k] = value


@njit(cache=True, inline="always")
def _fine_step(t):
    """Step [m] of the march at distance t [m] from the observer (module constants)."""
    return max(STEP_M, STEP_GROWTH * t)


@njit(cache=True, inline="always")
def _jitter(index):
    """A per-ray offset in (0, 1) from an integer hash of the ray's index: turns the banding
    of fixed steps into fine grain (never 0: a sample on a layer's boundary could miss it)."""
    return (float(hash32(index)) + 0.5) / 4294967296.0


@njit(cache=True, inline="always")
def _ground_distance(o, v, bottom_r):
    """Distance along the ray to the planet's ground (inf if it does not meet it; 0 for a
    ray from the ground into it)."""
    b = o[0] * v[0] + o[1] * v[1] + o[2] * v[2]
    c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
    if b >= 0.0:
        return math.inf
    t0 = _sphere_roots(b, c, bottom_r)[0]
    return math.inf if math.isnan(t0) else max(t0, 0.0)


@njit(cache=True, parallel=True)
def march_clouds(origin, directions, ray_ids, max_distance, bottom_r, sun, cloud, light,
                 radiance, transmittance, depth, hit):
    """Light scattered by the clouds towards `origin` (3,) along unit `directions` (n, 3), up
    to `max_distance` (n,) [m] or the ground of radius `bottom_r` [m] (module docstring), lit
    by a sun along unit `sun` (3,). Each ray's jitter follows from its id in `ray_ids` (n,)
    (its pixel): the same ray has the same jitter in whatever batch and order it is marched.

    `cloud` = (params, profiles, textures, mass extinction [m^2 g^-1], single-scattering
    albedo, asymmetry, phase table) of a `CloudField`; `light` = (r_nodes (n_r,) radii [m],
    mu_nodes (n_mu,) sun zenith cosines, both uniform; then over them (n_r, n_mu, n_wl) the
    air's transmittance towards the sun [-], the clear sky's diffuse irradiance from above
    and the irradiance the ground reflects up [W m^-2 nm^-1]; the sun's top-of-atmosphere
    irradiance (n_wl,) [W m^-2 nm^-1]) (`transport.clouds.cloud_lighting`). Writes radiance
    (n, n_wl) [W m^-2 sr^-1 nm^-1], transmittance (n, n_wl) [-], depth (n,) the
    transmittance-weighted distance of the scattering [m] and hit (n,) whether any cloud was
    met."""
    params = cloud[0]
    n_wl = cloud[3].shape[1]
    n_layers = params.shape[0]
    for i in prange(directions.shape[0]):
        v = directions[i]
        sun_phase = _phases_at(v[0] * sun[0] + v[1] * sun[1] + v[2] * sun[2], cloud[6])
        state = np.zeros(4)  # transmittance-weighted distance and weight, hit, stop
        trans = np.ones(n_wl)
        glow = np.zeros(n_wl)
        scratch = np.empty((5, n_wl))
        intervals = np.empty((2 * n_layers, 3))
        pieces = np.empty((2, 2))
        count = 0
        t_max = min(max_distance[i], _ground_distance(origin, v, bottom_r))
        for layer in range(n_layers):
            found = _shell_intervals(origin, v, params[layer, BASE_R], params[layer, TOP_R],
                                     t_max, pieces)
            for k in range(found):
                intervals[count, 0], intervals[count, 1] = pieces[k, 0], pieces[k, 1]
                intervals[count, 2] = layer
                count += 1
        order = np.argsort(intervals[:count, 0])
        jitter = _jitter(ray_ids[i])
        for o in range(count):
            row = intervals[order[o]]
            if row[0] > params[int(row[2]), FAR_START]:  # beyond a tile per pixel: _far_layer
                _far_layer(origin, v, row[0], row[1], int(row[2]), jitter, sun, cloud, light,
                           sun_phase, trans, glow, scratch, state)
            elif params[int(row[2]), SHEET] > 0.0:
                _cross_sheet(origin, v, row[0], row[1], int(row[2]), sun, cloud, light,
                             sun_phase, trans, glow, scratch, state)
            else:
                _march_layer(origin, v, row[0], row[1], int(row[2]), jitter, sun, cloud, light,
                             sun_phase, trans, glow, scratch, state)
            if state[3] > 0.0:
                break
        radiance[i] = glow
        transmittance[i] = trans
        depth[i] = state[0] / state[1] if state[1] > 0.0 else 0.0
        hit[i] = state[2] > 0.0


@njit(cache=True)
def _march_layer(origin, v, t0, t1, layer, jitter, sun, cloud, light, sun_phase, trans,
                 glow, scratch, state):
    """March one crossing [t0, t1] of a volume layer (module docstring) in segments that
    cover it: coarse in empty air, short near a cloud's edge (an empty sample within
    `NEAR_EDGE` ramps of one ends its step); where a sample meets cloud, the segments restart at the
    cloud's edge (`_cloud_edge`) and go at most `OPTICAL_STEP` deep. Each segment's
    extinction comes from the water at a jittered point in it; its source J is taken at both
    ends (the end of one is the start of the next) and integrated as exponential in between,
    against the segment's attenuation."""
    params, profiles, textures = cloud[0], cloud[1], cloud[2]
    extinction, albedo = cloud[3], cloud[4]
    mid = trans.size // 2
    start_source, end_source = scratch[0], scratch[1]
    s = t0
    last_empty = t0  # where the water was last seen to be 0 (or the layer's edge)
    coarse = True
    inside = False  # the last sample was in a cloud whose edge has been found
    have_start = False
    empties = 0
    steps = 0
    thick_cap = math.inf  # step cap from the last sample's extinction
    refined = False
    while s < t1 and steps < MAX_STEPS:
        steps += 1
        step = max(min(_fine_step(s) * (COARSE_STEPS if coarse else 1), thick_cap),
                   (t1 - s) / (MAX_STEPS + 1 - steps))  # the last steps reach t1
        step = min(step, t1 - s)
        t = s + jitter * step
        water = _water_along(origin, v, t, layer, params, profiles, textures)
        if water <= 0.0:
            margin = _margin_along(origin, v, t, layer, params, profiles, textures)
            refined = have_start = inside = False
            last_empty = t
            if margin > -NEAR_EDGE:
                empties = 0
                coarse = False
                thick_cap = NEAR_STEP_M
                # a long step is looked at again from its sample on, a short one is done
                s = t if step > NEAR_STEP_M else s + step
                continue
            empties += 1
            coarse |= empties >= EMPTY_TO_COARSE
            thick_cap = math.inf
            s += step
            continue
        if not inside:  # entering a cloud: start the segments at its edge
            s = _cloud_edge(origin, v, last_empty, t, layer, params, profiles, textures)
            inside = True
            coarse = False
            continue
        thick_cap = max(OPTICAL_STEP / (extinction[layer, mid] * water), MIN_STEP_M)
        if step > 1.5 * thick_cap and not refined:  # too thick: walk it again, shorter
            refined = True
            continue
        refined = False
        empties = 0
        state[2] = 1.0
        if not have_start:
            _source_at(origin, v, s, layer, sun, cloud, light, sun_phase, start_source,
                       scratch[2], scratch[3])
        _source_at(origin, v, s + step, layer, sun, cloud, light, sun_phase, end_source,
                   scratch[2], scratch[3])
        if not _add_segment(extinction[layer], albedo[layer], water, (s, step), start_source,
                            end_source, trans, glow, (1.0, 1.0), state):
            state[3] = 1.0
            return
        start_source[:] = end_source
        have_start = True
        s += step


@njit(cache=True)
def _add_segment(extinction, albedo, water, segment, j0, j1, trans, glow, shares, state):
    """One segment (start, length [m]) through `water` [g m^-3] with the source J going from
    j0 to j1 (n_wl,) along it (module docstring), per band: glow += share_glow trans albedo
    int J sigma e^(-sigma x) dx, trans *= e^(-sigma length); the mid band's extinction, times
    share_depth, weights the segment's mean depth into state[0:2]. `shares` = (share_glow,
    share_depth). Returns whether any band's transmittance is still above the cutoff."""
    start, length = segment
    share_glow, share_depth = shares
    mid = trans.size // 2
    sigma_mid = extinction[mid] * water
    extinct_mid = math.exp(-sigma_mid * length)
    weight = share_depth * trans[mid] * (1.0 - extinct_mid)
    state[0] += weight * (start + _mean_depth(sigma_mid, length, extinct_mid))
    state[1] += weight
    alive = False
    for k in range(trans.size):
        sigma = extinction[k] * water
        e = math.exp(-sigma * length)
        glow[k] += trans[k] * albedo[k] * _segment_integral(j0[k], j1[k], sigma, length,
                                                            e) * share_glow
        trans[k] *= e
        alive |= trans[k] > TRANSMITTANCE_CUTOFF
    return alive


@njit(cache=True, inline="always")
def _water_along(origin, v, t, layer, params, profiles, textures):
    """Water content [g m^-3] of `layer` at distance t along the ray."""
    x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
    return layer_water(params, profiles, textures, layer, x, y, z,
                       math.sqrt(x * x + y * y + z * z))


@njit(cache=True, inline="always")
def _margin_along(origin, v, t, layer, params, profiles, textures):
    """`edge_margin` of `layer` at distance t along the ray."""
    x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
    return edge_margin(params, profiles, textures, layer, x, y, z,
                       math.sqrt(x * x + y * y + z * z))


@njit(cache=True)
def _cloud_edge(origin, v, outside, inside, layer, params, profiles, textures):
    """Where the ray enters cloud between `outside` (no water) and `inside` (water) [m]:
    `EDGE_BISECTIONS` halvings, the end inside the cloud. Every ray then lights a cloud from
    its edge, whatever its jitter (else the sunlit skin, ~10 m deep, is caught by some pixels
    and stepped over by their neighbours: grain). A cloud that reaches the layer's boundary
    (`outside` is t0 there) starts at it."""
    if _water_along(origin, v, outside, layer, params, profiles, textures) > 0.0:
        return outside
    for _ in range(EDGE_BISECTIONS):
        middle = 0.5 * (outside + inside)
        if _water_along(origin, v, middle, layer, params, profiles, textures) > 0.0:
            inside = middle
        else:
            outside = middle
    return inside


@njit(cache=True, inline="always")
def _segment_integral(j0, j1, sigma, step, e):
    """int_0^step J(x) sigma e^(-sigma x) dx with J exponential from j0 to j1 (linear when
    either is 0); `e` = e^(-sigma step)."""
    if j0 > 0.0 and j1 > 0.0:
        a = math.log(j0 / j1) / step
        rate = sigma + a
        if abs(rate * step) < 1e-8:
            return j0 * sigma * step
        return j0 * sigma * -math.expm1(-rate * step) / rate
    if sigma * step < 1e-8:
        return 0.5 * (j0 + j1) * sigma * step
    slope = (j1 - j0) / step
    return j0 * (1.0 - e) + slope * (1.0 - e * (1.0 + sigma * step)) / sigma


@njit(cache=True, inline="always")
def _mean_depth(sigma, step, e):
    """Mean depth [m] of the light's extinction in a segment: int x sigma e^(-sigma x) /
    (1 - e^(-sigma step)) over [0, step]."""
    if sigma * step < 1e-6:
        return 0.5 * step
    return 1.0 / sigma - step * e / (1.0 - e)


@njit(cache=True)
def _cross_sheet(origin, v, t0, t1, layer, sun, cloud, light, sun_phase, trans, glow,
                 scratch, state):
    """A sheet layer's crossing [t0, t1]: one sample in the middle of the chord, its water
    uniform across the shell's thickness (module docstring)."""
    params, profiles, textures = cloud[0], cloud[1], cloud[2]
    extinction, albedo = cloud[3], cloud[4]
    t = 0.5 * (t0 + t1)
    x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
    r = math.sqrt(x * x + y * y + z * z)
    water = layer_water(params, profiles, textures, layer, x, y, z, r)
    if water <= 0.0:
        return
    state[2] = 1.0
    mu_s = (x * sun[0] + y * sun[1] + z * sun[2]) / r
    half = 0.5 * (params[layer, TOP_R] - params[layer, BASE_R])
    source = scratch[0]
    slant = water * min(half / max(abs(mu_s), 0.05), LIGHT_MAX_M)
    _light_source(r, mu_s, (x * v[0] + y * v[1] + z * v[2]) / r, v @ sun, slant, slant,
                  water * half, water * half, layer, cloud, light, sun_phase, source,
                  scratch[2], scratch[3])
    length = t1 - t0
    mid = trans.size // 2
    state[0] += trans[mid] * (1.0 - math.exp(-extinction[layer, mid] * water * length)) * t
    state[1] += trans[mid] * (1.0 - math.exp(-extinction[layer, mid] * water * length))
    for k in range(trans.size):
        e = math.exp(-extinction[layer, k] * water * length)
        glow[k] += trans[k] * albedo[layer, k] * source[k] * (1.0 - e)
        trans[k] *= e


@njit(cache=True)
def _source_at(origin, v, t, layer, sun, cloud, light, sun_phase, out, down, up):
    """J (n_wl,) (module docstring) at distance t along the view ray inside a volume layer:
    the water towards the sun, above and below marched from there."""
    params, profiles, textures = cloud[0], cloud[1], cloud[2]
    x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
    radius = math.sqrt(x * x + y * y + z * z)
    ux, uy, uz = x / radius, y / radius, z / radius
    base_r, top_r = params[layer, BASE_R], params[layer, TOP_R]
    r = min(max(radius, base_r), top_r)
    length = min(_exit_length(x, y, z, r, sun[0], sun[1], sun[2], base_r, top_r), LIGHT_MAX_M)
    w_sun = _path_water(params, profiles, textures, layer, x, y, z, sun[0], sun[1], sun[2],
                        length, LIGHT_FIRST_M)
    length = min(_exit_length(x, y, z, r, -sun[0], -sun[1], -sun[2], base_r, top_r),
                 LIGHT_MAX_M)
    w_anti = _path_water(params, profiles, textures, layer, x, y, z, -sun[0], -sun[1], -sun[2],
                         length, AMBIENT_FIRST_M)
    w_up = _path_water(params, profiles, textures, layer, x, y, z, ux, uy, uz, top_r - r,
                       AMBIENT_FIRST_M)
    w_down = _path_water(params, profiles, textures, layer, x, y, z, -ux, -uy, -uz, r - base_r,
                         AMBIENT_FIRST_M)
    mu_s = ux * sun[0] + uy * sun[1] + uz * sun[2]
    mu_view = ux * v[0] + uy * v[1] + uz * v[2]
    _light_source(r, mu_s, mu_view, v @ sun, w_sun, w_anti, w_up, w_down, layer, cloud, light,
                  sun_phase, out, down, up)


@njit(cache=True)
def _light_source(r, mu_s, mu_view, nu, w_sun, w_anti, w_up, w_down, layer, cloud, light,
                  sun_phase, out, down, up):
    """J (n_wl,) at radius r [m], sun zenith cosine mu_s, view zenith cosine mu_view and
    cos(view, sun) nu, from the water paths towards the sun, away from it, above and below
    [g m^-2] (module docstring); `down` and `up` are scratch."""
    extinction, asymmetry = cloud[3], cloud[5]
    r_nodes, mu_nodes, sun_air, sky_down, ground_up, sun_toa = light
    _table_lookup(sun_air, r_nodes, mu_nodes, r, mu_s, out)
    _table_lookup(sky_down, r_nodes, mu_nodes, r, mu_s, down)
    _table_lookup(ground_up, r_nodes, mu_nodes, r, mu_s, up)
    slab_mu = max(mu_s, 0.0)
    for k in range(out.size):
        k_ext = extinction[layer, k]
        g = asymmetry[layer, k]
        gamma = EDDINGTON * (1.0 - g)
        sun = sun_toa[k] * out[k]  # E_sun T_air
        direct = math.exp(-k_ext * w_sun)
        # the beam's part through the whole slab (below 1e-6 of it: nothing to C)
        through = direct * math.exp(-k_ext * w_anti) if direct > 1e-6 else 0.0
        diffuse_sun = sun * slab_mu * beam_source(
            g, gamma, k_ext * w_sun * slab_mu, k_ext * w_anti * slab_mu, direct, through,
            slab_mu, mu_view)
        d_up, d_down = k_ext * w_up, k_ext * w_down
        sky = (down[k] * diffuse_source(g, gamma, d_up, d_down, mu_view)
               + up[k] * diffuse_source(g, gamma, d_down, d_up, -mu_view))
        out[k] = sun * sun_phase[layer, k] * direct + max(diffuse_sun, 0.0) + max(sky, 0.0)


@njit(cache=True)
def _phases_at(nu, phase):
    """The layers' phase functions (n_layers, n_wl) [sr^-1] at cos(scattering angle) nu."""
    n_layers, _, n_wl = phase.shape
    out = np.empty((n_layers, n_wl))
    j, w = phase_table_index(nu)
    for layer in range(n_layers):
        for k in range(n_wl):
            out[layer, k] = phase[layer, j, k] * (1.0 - w) + phase[layer, j + 1, k] * w
    return out


@njit(cache=True, parallel=True)
def cloud_water_paths(origins, directions, max_distance, bottom_r, params, profiles, textures,
                      out):
    """Water path [g m^-2] (n, n_layers) of each layer along the rays from `origins` (n, 3)
    along unit `directions` (n, 3) up to `max_distance` (n,) [m] or the ground of radius
    `bottom_r`, marched as `march_clouds`
    marches a view ray (the sun's transmittance through the clouds, cloud shadows)."""
    n_layers = params.shape[0]
    for i in prange(directions.shape[0]):
        o = origins[i]
        v = directions[i]
        pieces = np.empty((2, 2))
        t_max = min(max_distance[i], _ground_distance(o, v, bottom_r))
        for layer in range(n_layers):
            found = _shell_intervals(o, v, params[layer, BASE_R], params[layer, TOP_R],
                                     t_max, pieces)
            total = 0.0
            sheet = params[layer, SHEET] > 0.0
            for k in range(found):
                t0, t1 = pieces[k, 0], pieces[k, 1]
                steps = 1 if sheet else min(MAX_STEPS, max(1, int(math.ceil((t1 - t0) / STEP_M))))
                dt = (t1 - t0) / steps
                for step in range(steps):
                    t = t0 + (step + 0.5) * dt
                    x, y, z = o[0] + t * v[0], o[1] + t * v[1], o[2] + t * v[2]
                    r = math.sqrt(x * x + y * y + z * z)
                    total += layer_water(params, profiles, textures, layer, x, y, z, r) * dt
            out[i, layer] = total


@njit(cache=True)
def _far_layer(origin, v, t0, t1, layer, jitter, sun, cloud, light, sun_phase, trans, glow,
               scratch, state):
    """A layer's crossing [t0, t1] beyond `FAR_START` (`atmosphere.cloud_field`: where a pixel
    covers a tile): the independent columns of `_cross_columns`, blended smoothly (weight
    f = smoothstep((t0 - FAR_START) / (FAR_END - FAR_START))) with the march up to `FAR_END`."""
    params = cloud[0]
    start, end = params[layer, FAR_START], params[layer, FAR_END]
    f = min(max((t0 - start) / (end - start), 0.0), 1.0) if end > start else 1.0
    f = f * f * (3.0 - 2.0 * f)
    near_trans, near_glow, near_state = trans.copy(), glow.copy(), state.copy()
    if f < 1.0:
        if params[layer, SHEET] > 0.0:
            _cross_sheet(origin, v, t0, t1, layer, sun, cloud, light, sun_phase, near_trans,
                         near_glow, scratch, near_state)
        else:
            _march_layer(origin, v, t0, t1, layer, jitter, sun, cloud, light, sun_phase,
                         near_trans, near_glow, scratch, near_state)
    _cross_columns(origin, v, t0, t1, layer, sun, cloud, light, sun_phase, trans, glow,
                   scratch, state)
    if f < 1.0:
        alive = False
        for k in range(trans.size):
            trans[k] = f * trans[k] + (1.0 - f) * near_trans[k]
            glow[k] = f * glow[k] + (1.0 - f) * near_glow[k]
            alive |= trans[k] > TRANSMITTANCE_CUTOFF
        state[0] = f * state[0] + (1.0 - f) * near_state[0]
        state[1] = f * state[1] + (1.0 - f) * near_state[1]
        state[2] = max(state[2], near_state[2])
        state[3] = 0.0 if alive else 1.0


@njit(cache=True)
def _cross_columns(origin, v, t0, t1, layer, sun, cloud, light, sun_phase, trans, glow,
                   scratch, state):
    """The independent column approximation of a layer's crossing [t0, t1] (Cahalan et al.
    1994; `atmosphere.cloud_field`): at the map factor m where the ray is halfway through,
    a fraction c_col(m) of cloudy columns in the `COLUMN_SHARES`, each a uniform slab
    of its share's mean water path / thickness marched as `_march_layer` marches water
    (segments at most `OPTICAL_STEP` deep, the source of `_source_at` at both ends with its
    water paths through the slab), and 1 - c_col clear:
    L += T c_col <L_col>, T <- T (1 - c_col (1 - <T_col>)), <> the mean over the shares."""
    params, profiles = cloud[0], cloud[1]
    extinction, albedo = cloud[3], cloud[4]
    t = 0.5 * (t0 + t1)
    m = coverage_map_factor(params, profiles, layer, origin[0] + t * v[0],
                            origin[1] + t * v[1], origin[2] + t * v[2])
    paths = np.empty(COLUMN_BINS)
    cover = column_cover(profiles, layer, m, paths)
    if cover <= 0.0:
        return
    n_wl = trans.size
    mid = n_wl // 2
    mean_t = np.zeros(n_wl)
    mean_glow = np.zeros(n_wl)
    column_t = np.empty(n_wl)
    start_source, end_source = scratch[0], scratch[1]
    state[2] = 1.0
    for b in range(COLUMN_BINS):
        water = paths[b] / (params[layer, TOP_R] - params[layer, BASE_R])
        column_t[:] = 1.0
        if water > 0.0:
            _column_source_at(origin, v, t0, layer, water, sun, cloud, light, sun_phase,
                              start_source, scratch[2], scratch[3])
            step = max(OPTICAL_STEP / (extinction[layer, mid] * water), MIN_STEP_M)
            s = t0
            for _ in range(MAX_STEPS):
                if s >= t1:
                    break
                dt = min(step, t1 - s)
                _column_source_at(origin, v, s + dt, layer, water, sun, cloud, light,
                                  sun_phase, end_source, scratch[2], scratch[3])
                share = COLUMN_SHARES[b]
                if not _add_segment(extinction[layer], albedo[layer], water, (s, dt),
                                    start_source, end_source, column_t, mean_glow,
                                    (share, trans[mid] * cover * share), state):
                    break
                start_source[:] = end_source
                s += dt
        for k in range(n_wl):
            mean_t[k] += column_t[k] * COLUMN_SHARES[b]
    alive = False
    for k in range(n_wl):
        glow[k] += trans[k] * cover * mean_glow[k]
        trans[k] *= 1.0 - cover * (1.0 - mean_t[k])
        alive |= trans[k] > TRANSMITTANCE_CUTOFF
    if not alive:
        state[3] = 1.0


@njit(cache=True)
def _column_source_at(origin, v, t, layer, water, sun, cloud, light, sun_phase, out, down, up):
    """J (n_wl,) as `_source_at`, in a uniform slab of `water` [g m^-3] filling the layer's
    shell: its water paths are `water` times the lengths to the shell's faces."""
    params = cloud[0]
    x, y, z = origin[0] + t * v[0], origin[1] + t * v[1], origin[2] + t * v[2]
    radius = math.sqrt(x * x + y * y + z * z)
    ux, uy, uz = x / radius, y / radius, z / radius
    base_r, top_r = params[layer, BASE_R], params[layer, TOP_R]
    r = min(max(radius, base_r), top_r)
    mu_s = ux * sun[0] + uy * sun[1] + uz * sun[2]
    to_sun = min(_shell_length(r, mu_s, base_r, top_r), LIGHT_MAX_M)
    away = min(_shell_length(r, -mu_s, base_r, top_r), LIGHT_MAX_M)
    _light_source(r, mu_s, ux * v[0] + uy * v[1] + uz * v[2], v @ sun, water * to_sun,
                  water * away, water * (top_r - r), water * (r - base_r), layer, cloud, light,
                  sun_phase, out, down, up)


@njit(cache=True, inline="always")
def _shell_length(r, mu, base_r, top_r):
    """Distance [m] from radius r in [base_r, top_r] along zenith cosine mu to the shell's
    edge: the top, or the base where the ray goes down and meets it (0 from the base)."""
    length = -r * mu + math.sqrt(max(r * r * (mu * mu - 1.0) + top_r * top_r, 0.0))
    disc = r * r * (mu * mu - 1.0) + base_r * base_r
    if mu < 0.0 and disc >= 0.0:
        length = min(length, max(-r * mu - math.sqrt(disc), 0.0))
    return length
