r"""Mappings between physical ray parameters and the coordinates of the precomputed tables.

One definition of each mapping, as numba scalar functions that kernels call and that the GLSL
copy of the viewer mirrors (same names). Bruneton (2017), `precomputed_atmospheric_scattering`,
atmosphere/functions.glsl, which refines Bruneton & Neyret (2008), "Precomputed atmospheric
scattering", Comput. Graph. Forum 27(4), 1079, doi:10.1111/j.1467-8659.2008.01245.x, §4;
github.com/ebruneton/precomputed_atmospheric_scattering, atmosphere/functions.glsl.

Symbols:
  r     distance to the planet centre [m]; R_b, R_t bottom and top radius [m]
  mu    cos(view zenith angle) [-]; mu_s cos(sun zenith angle) [-]; nu = cos(view-sun angle) [-]
  H   = sqrt(R_t^2 - R_b^2)   distance from the ground to the top along a horizontal ray [m]
  rho = sqrt(r^2 - R_b^2)     distance from r to the horizon [m]
  d                           distance along the ray to the top (or to the ground) [m]

Texel centres: a table of n entries stores the values at x = i / (n - 1), i = 0..n-1, so that
x = 0 and x = 1 fall on texel centres of a GPU texture with u = tc(x, n) = 0.5/n + x (1 - 1/n)
(`texture_coord_from_unit_range`). A CPU lookup turns u back into a fractional index
f = u n - 0.5 = x (n - 1) (`texel_index`); linear interpolation between entries then equals
the GPU's hardware filtering.

Transmittance table (r, mu), rays that do not hit the ground only:
  x_r = rho / H,   x_mu = (d - d_min) / (d_max - d_min),
  d = distance to the top, d_min = R_t - r, d_max = rho + H;
  inverse mu = (H^2 - rho^2 - d^2) / (2 r d).
Scattering table (r, mu, mu_s, nu), 4-D with axes (u_r, u_mu, u_mu_s, u_nu):
  u_r = tc(W(rho / H), n_r), W a piecewise-linear warp through `radius_warp`[k] at rho / H =
    k / (n_k - 1), increasing from 0 to 1: the identity (Bruneton's u_r) for an atmosphere
    without optically thick layers, and for one with them a share of the radius cells
    proportional to the optical depth they hold (`tables.radius_warp`), so that a cloud deck
    500 m thick gets 13 of 32 cells instead of 1-2;
  rays hitting the ground use the lower half of the mu axis,
    u_mu = 1/2 - 1/2 tc(1 - sqrt(1 - (pi - theta) / (pi - theta_h)), n_mu / 2),
  other rays the upper half,
    u_mu = 1/2 + 1/2 tc(1 - sqrt(1 - theta / theta_h), n_mu / 2),
    theta = acos(mu) the view zenith angle, theta_h = acos(-rho / r) the horizon's;
  cells are uniform in angle at the zenith and the nadir (2.9 deg wide with 128 cells) and
  crowd quadratically at the horizon (0.02 deg), as the sky-view table of Hillaire 2020
  (doi:10.1111/cgf.14050, §5.3). Bruneton's u_mu, linear in the distance to the boundary,
  makes the first cell next to the zenith 18-26 deg wide on Earth and nearly the whole
  hemisphere inside a thin dense layer (a cloud deck 1 km thick: zenith to 80 deg), where
  a forward-peaked radiance changes most (docs/physics/tables.md);
  the half is chosen by the caller's `ray_hits_ground` flag, never recomputed, so rays at the
  horizon stay on their side;
  u_mu_s = tc((1 - s) x_B + s x_theta, n_mu_s), with Bruneton's
    x_B = max(1 - a / A, 0) / (1 + a), a = (d_s - d_min) / (d_max - d_min), d_s the distance
    to the top from the ground along mu_s, d_min = R_t - R_b, d_max = H, and A the same for
    mu_s = mu_s_min (the smallest sun cosine tabulated; below it the first texel is used),
    whose samples crowd near the horizon and leave the daytime sky few (with 40 cells the
    last three at sun zenith 47.9, 36.2 and 0 deg); and x_theta = 1 - sin(theta_s / 2) /
    sin(theta_min / 2) = 1 - sqrt((1 - mu_s) / (1 - mu_s_min)), uniform in the chord of the sun's
    zenith angle theta_s down to theta_min = acos(mu_s_min): nearly uniform in the angle (cells
    1 / cos(theta_s / 2) times as wide as at the zenith, 1.4 x at the horizon), and a square
    root instead of an arc cosine in the tables' innermost loop.
    The share s (`sun_angle_share`) is 0 (Bruneton's axis) except below optically thick layers,
    where the light under the layer changes with exp(-tau / mu_s) across the daytime cells
    (`tables.sun_angle_share`); the inverse is found by bisection;
  u_nu = 1 - phi / pi, phi in [0, pi] the view's azimuth about the local zenith from the
    sun's, cos phi = (nu - mu mu_s) / sqrt((1 - mu^2)(1 - mu_s^2)), with the n_nu slices at
    the exact ends (index f = u_nu (n_nu - 1)): every slice lies inside the view-sun angles
    that (mu, mu_s) allow, |theta - theta_s| .. theta + theta_s. A mapping of nu over all of
    [-1, 1] (Bruneton's (nu + 1) / 2, or 1 - sqrt(acos(nu) / pi) used here before) leaves
    half the slices outside that range (with the sun 60 deg from the zenith and a view 50 deg
    from it, 4 of 8 fall inside with either); uniform in azimuth, the tables on a dusty Mars
    with the sun 30-60 deg from the zenith are 4-5 x closer to the Monte Carlo
    (docs/physics/tables.md).
Irradiance table (r, mu_s), affine: x_r = (r - R_b) / (R_t - R_b), x_mu_s = (mu_s + 1) / 2.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "COS_SUN_ZENITH_MIN",
    "COS_SUN_ZENITH_MIN_EARTH",
    "SPREAD_MIN",
    "angle_from_horizon_dense",
    "distance_to_bottom_boundary",
    "distance_to_top_boundary",
    "horizon_dense_from_angle",
    "horizon_zenith_angle",
    "irradiance_r_mu_s_from_x",
    "irradiance_x_from_r_mu_s",
    "mu_s_mapping_constants",
    "ray_intersects_ground",
    "scattering_mu_from_u",
    "scattering_mu_s_from_u",
    "scattering_nu_from_u",
    "scattering_r_from_u",
    "scattering_r_mu_mu_s_nu_from_uvwz",
    "scattering_u_mu",
    "scattering_u_mu_s",
    "scattering_u_mu_s_from_constants",
    "scattering_u_nu",
    "scattering_u_r",
    "scattering_uvwz_from_r_mu_mu_s_nu",
    "texel_index",
    "texture_coord_from_unit_range",
    "transmittance_r_mu_from_x",
    "transmittance_x_from_r_mu",
    "transmittance_x_mu",
    "transmittance_x_r",
    "unit_range_from_texture_coord",
    "unwarped",
    "view_sun_azimuth",
    "view_sun_spread",
    "warped",
]

# cos(102 deg): Bruneton 2017's suggestion for Earth (definitions.glsl, `mu_s_min`): the sun
# 12 deg below the horizon, the end of nautical twilight.
COS_SUN_ZENITH_MIN_EARTH = math.cos(math.radians(102.0))
# cos(120 deg) = -0.5, the default of every atmosphere (issue 6): astronomical twilight ends at
# 108 deg; from a ground observer's point of view the farthest sunlit air is where the sun is
# about twice the horizon dip lower than for the observer (Earth, top at 100 km: 2 x 10.1
# deg; Mars at 100 km: 2 x 13.8 deg), so the scattered sky is ~0 well before 120 deg and
# the clamp below it does not show. With 40 cells (`TableResolution.scattering_mu_s`) the
# mapping keeps its daytime cells about where 32 cells down to 102 deg had them (the second at
# 36.2 deg instead of 37.4 deg; docs/physics/tables.md, "Twilight").
COS_SUN_ZENITH_MIN = -0.5
# Below this sqrt((1 - mu^2)(1 - mu_s^2)) the view's azimuth from the sun is taken as 0
# (`scattering_u_nu`): a view or a sun within 0.06 deg of the zenith, where the azimuth is
# undefined and the radiance changes by at most spread x its derivative in nu.
SPREAD_MIN = 1e-6


@njit(cache=True)
def texture_coord_from_unit_range(x, n):
    """tc(x, n) = 0.5/n + x (1 - 1/n): x in [0, 1] -> texture coordinate between the centres
    of the first and the last of n texels (Bruneton 2017, `GetTextureCoordFromUnitRange`)."""
    return 0.5 / n + x * (1.0 - 1.0 / n)


@njit(cache=True)
def unit_range_from_texture_coord(u, n):
    """Inverse of `texture_coord_from_unit_range`: x = (u - 0.5/n) / (1 - 1/n)."""
    return (u - 0.5 / n) / (1.0 - 1.0 / n)


@njit(cache=True)
def texel_index(u, n):
    """Fractional array index f = u n - 0.5 of texture coordinate u on an axis of n entries,
    clamped to [0, n - 1] (entry i holds the texel centre u = (i + 0.5) / n)."""
    return min(max(u * n - 0.5, 0.0), n - 1.0)


@njit(cache=True)
def distance_to_top_boundary(r, mu, top_radius):
    """Distance [m] from radius r along mu to the top sphere (far root), clamped >= 0:
    d = -r mu + sqrt(max(r^2 (mu^2 - 1) + R_t^2, 0)) (Bruneton 2017,
    `DistanceToTopAtmosphereBoundary`; valid for r <= R_t)."""
    discriminant = r * r * (mu * mu - 1.0) + top_radius * top_radius
    return max(-r * mu + math.sqrt(max(discriminant, 0.0)), 0.0)


@njit(cache=True)
def distance_to_bottom_boundary(r, mu, bottom_radius):
    """Distance [m] from radius r along mu to the ground (near root), clamped >= 0:
    d = -r mu - sqrt(max(r^2 (mu^2 - 1) + R_b^2, 0)) (Bruneton 2017,
    `DistanceToBottomAtmosphereBoundary`); meaningful when `ray_intersects_ground`."""
    discriminant = r * r * (mu * mu - 1.0) + bottom_radius * bottom_radius
    return max(-r * mu - math.sqrt(max(discriminant, 0.0)), 0.0)


@njit(cache=True)
def ray_intersects_ground(r, mu, bottom_radius):
    """True when the ray (r, mu) meets the ground: mu < 0 and r^2 (mu^2 - 1) + R_b^2 >= 0
    (Bruneton 2017, `RayIntersectsGround`)."""
    return mu < 0.0 and r * r * (mu * mu - 1.0) + bottom_radius * bottom_radius >= 0.0


# --------------------------------------------------------------------------------------------
# Transmittance table (r, mu) <-> (x_mu, x_r), unit ranges; texture u = tc(x, n).
# --------------------------------------------------------------------------------------------

@njit(cache=True)
def transmittance_x_r(r, bottom_radius, top_radius):
    """(x_r, d_min, d_max) of the transmittance mapping at radius r: x_r = rho / H (clamped to
    [0, 1]), d_min = R_t - r, d_max = rho + H [m]. The part of `transmittance_x_from_r_mu` that
    does not depend on mu, for kernels that look up many mu at one r."""
    big_h = math.sqrt(top_radius * top_radius - bottom_radius * bottom_radius)
    rho = math.sqrt(max(r * r - bottom_radius * bottom_radius, 0.0))
    return min(max(rho / big_h, 0.0), 1.0), top_radius - r, rho + big_h


@njit(cache=True)
def transmittance_x_mu(r, mu, top_radius, d_min, d_max):
    """x_mu = (d - d_min) / (d_max - d_min) (clamped to [0, 1]), d = distance to the top; d_min
    and d_max from `transmittance_x_r`."""
    if d_max <= d_min:
        return 0.0
    d = distance_to_top_boundary(r, mu, top_radius)
    return min(max((d - d_min) / (d_max - d_min), 0.0), 1.0)


@njit(cache=True)
def transmittance_x_from_r_mu(r, mu, bottom_radius, top_radius):
    """(r, mu) -> (x_mu, x_r) in [0, 1] for a ray that does not hit the ground:
    x_r = rho / H, x_mu = (d - d_min) / (d_max - d_min), d = distance to the top,
    d_min = R_t - r, d_max = rho + H (Bruneton 2017, `GetTransmittanceTextureUvFromRMu`,
    before the texel-centre mapping). Results are clamped to [0, 1]."""
    x_r, d_min, d_max = transmittance_x_r(r, bottom_radius, top_radius)
    return transmittance_x_mu(r, mu, top_radius, d_min, d_max), x_r


@njit(cache=True)
def transmittance_r_mu_from_x(x_mu, x_r, bottom_radius, top_radius):
    """Inverse of `transmittance_x_from_r_mu`: rho = H x_r, r = sqrt(rho^2 + R_b^2),
    d = d_min + x_mu (d_max - d_min), mu = (H^2 - rho^2 - d^2) / (2 r d) (mu = 1 for d = 0)
    (Bruneton 2017, `GetRMuFromTransmittanceTextureUv`). Returns (r [m], mu [-])."""
    big_h = math.sqrt(top_radius * top_radius - bottom_radius * bottom_radius)
    rho = big_h * x_r
    r = math.sqrt(rho * rho + bottom_radius * bottom_radius)
    d_min = top_radius - r
    d_max = rho + big_h
    d = d_min + x_mu * (d_max - d_min)
    if d <= 0.0:
        return r, 1.0
    mu = (big_h * big_h - rho * rho - d * d) / (2.0 * r * d)
    return r, min(max(mu, -1.0), 1.0)


# --------------------------------------------------------------------------------------------
# Scattering table (r, mu, mu_s, nu, ray_hits_ground) <-> (u_r, u_mu, u_mu_s, u_nu).
# --------------------------------------------------------------------------------------------

@njit(cache=True)
def warped(x, warp):
    """W(x) [-]: piecewise linear through warp[k] at x = k / (warp.size - 1), x clamped to
    [0, 1]; `warp` increases strictly from 0 to 1 (module docstring, u_r)."""
    n = warp.size - 1
    f = min(max(x, 0.0), 1.0) * n
    k = min(int(f), n - 1)
    return warp[k] + (f - k) * (warp[k + 1] - warp[k])


@njit(cache=True)
def unwarped(w, warp):
    """Inverse of `warped`: x with W(x) = w, w clamped to [0, 1]."""
    w = min(max(w, 0.0), 1.0)
    low, high = 0, warp.size - 1
    while high - low > 1:
        middle = (low + high) // 2
        if warp[middle] <= w:
            low = middle
        else:
            high = middle
    return (low + (w - warp[low]) / (warp[high] - warp[low])) / (warp.size - 1)


@njit(cache=True)
def scattering_u_r(r, bottom_radius, top_radius, n_r, radius_warp):
    """u_r = tc(W(rho / H), n_r) [-], W the piecewise-linear `radius_warp` (`warped`)."""
    big_h = math.sqrt(top_radius * top_radius - bottom_radius * bottom_radius)
    rho = math.sqrt(max(r * r - bottom_radius * bottom_radius, 0.0))
    return texture_coord_from_unit_range(warped(min(rho / big_h, 1.0), radius_warp), n_r)


@njit(cache=True)
def scattering_r_from_u(u_r, bottom_radius, top_radius, n_r, radius_warp):
    """Inverse of `scattering_u_r`: r = sqrt((H W^-1(x_r))^2 + R_b^2) [m]."""
    big_h = math.sqrt(top_radius * top_radius - bottom_radius * bottom_radius)
    rho = big_h * unwarped(unit_range_from_texture_coord(u_r, n_r), radius_warp)
    return math.sqrt(rho * rho + bottom_radius * bottom_radius)


@njit(cache=True)
def horizon_dense_from_angle(a):
    """x = 1 - sqrt(1 - a): a in [0, 1], the angle from the zenith (or nadir) as a fraction of
    the angle to the horizon, to a unit range uniform at the pole and dense at the horizon."""
    return 1.0 - math.sqrt(max(1.0 - a, 0.0))


@njit(cache=True)
def angle_from_horizon_dense(x):
    """Inverse of `horizon_dense_from_angle`: a = 1 - (1 - x)^2."""
    return 1.0 - (1.0 - x) * (1.0 - x)


@njit(cache=True)
def horizon_zenith_angle(r, bottom_radius):
    """The zenith angle of the geometric horizon seen from radius r, acos(-rho / r), as
    atan2(R_b, -rho) (the float32 twin keeps its precision next to the horizon) [rad]."""
    return math.atan2(bottom_radius, -math.sqrt(max((r - bottom_radius) * (r + bottom_radius),
                                                    0.0)))


@njit(cache=True)
def scattering_u_mu(r, mu, ray_hits_ground, bottom_radius, top_radius, n_mu):
    """u_mu of the ray (r, mu): lower half of the axis for rays that hit the ground (nadir to
    horizon), upper half for the others (zenith to horizon), each on the angle fraction
    `horizon_dense_from_angle` (module docstring); the view zenith angle as atan2, precise at
    the zenith in float32 too. `top_radius` is unused (the signature is the one of the other
    axes)."""
    mu = min(max(mu, -1.0), 1.0)
    theta = math.atan2(math.sqrt(max((1.0 - mu) * (1.0 + mu), 0.0)), mu)
    return scattering_u_mu_of_angle(theta, horizon_zenith_angle(r, bottom_radius),
                                    ray_hits_ground, n_mu)


@njit(cache=True)
def scattering_u_mu_of_angle(theta, theta_h, ray_hits_ground, n_mu):
    """`scattering_u_mu` of the view zenith angle theta and the horizon's theta_h [rad]."""
    half = n_mu // 2
    if ray_hits_ground:
        x = horizon_dense_from_angle((math.pi - theta) / (math.pi - theta_h))
        return 0.5 - 0.5 * texture_coord_from_unit_range(min(max(x, 0.0), 1.0), half)
    x = horizon_dense_from_angle(theta / theta_h)
    return 0.5 + 0.5 * texture_coord_from_unit_range(min(max(x, 0.0), 1.0), half)


@njit(cache=True)
def scattering_mu_from_u(u_mu, r, bottom_radius, top_radius, n_mu):
    """Inverse of `scattering_u_mu` at radius r: (mu [-], ray_hits_ground)."""
    theta_h = horizon_zenith_angle(r, bottom_radius)
    half = n_mu // 2
    if u_mu < 0.5:
        a = angle_from_horizon_dense(unit_range_from_texture_coord(1.0 - 2.0 * u_mu, half))
        return math.cos(math.pi - a * (math.pi - theta_h)), True
    a = angle_from_horizon_dense(unit_range_from_texture_coord(2.0 * u_mu - 1.0, half))
    return math.cos(a * theta_h), False


# Bisection steps of the inverse mu_s mapping where it has no closed form (`sun_angle_share` >
# 0): 2^-52 of the interval, float64's resolution.
MU_S_BISECTION_STEPS = 52


@njit(cache=True)
def mu_s_mapping_constants(bottom_radius, top_radius, mu_s_min):
    """(d_min, d_max, A) of the mu_s mapping (module docstring): d_min = R_t - R_b, d_max = H,
    A = (D - d_min) / (d_max - d_min) with D the distance to the top from the ground along
    mu_s_min. Constant for an atmosphere; kernels compute it once."""
    big_h = math.sqrt(top_radius * top_radius - bottom_radius * bottom_radius)
    d_min = top_radius - bottom_radius
    d_max = big_h
    big_d = distance_to_top_boundary(bottom_radius, mu_s_min, top_radius)
    return d_min, d_max, (big_d - d_min) / (d_max - d_min)


@njit(cache=True)
def scattering_u_mu_s_from_constants(mu_s, bottom_radius, top_radius, mu_s_min, d_min, d_max,
                                     big_a, sun_angle_share, n_mu_s):
    """`scattering_u_mu_s` with the constants of `mu_s_mapping_constants` given."""
    d = distance_to_top_boundary(bottom_radius, mu_s, top_radius)
    a = (d - d_min) / (d_max - d_min)
    x = max(1.0 - a / big_a, 0.0) / (1.0 + a)
    if sun_angle_share > 0.0:
        x_theta = 1.0 - math.sqrt(max(1.0 - mu_s, 0.0) / (1.0 - mu_s_min))
        x = (1.0 - sun_angle_share) * x + sun_angle_share * max(x_theta, 0.0)
    return texture_coord_from_unit_range(x, n_mu_s)


@njit(cache=True)
def scattering_u_mu_s(mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share, n_mu_s):
    """u_mu_s = tc((1 - s) x_B + s x_theta, n_mu_s), s = `sun_angle_share`; module docstring
    (x_B: Bruneton 2017)."""
    d_min, d_max, big_a = mu_s_mapping_constants(bottom_radius, top_radius, mu_s_min)
    return scattering_u_mu_s_from_constants(mu_s, bottom_radius, top_radius, mu_s_min, d_min,
                                            d_max, big_a, sun_angle_share, n_mu_s)


@njit(cache=True)
def scattering_mu_s_from_u(u_mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share,
                           n_mu_s):
    """Inverse of `scattering_u_mu_s` [-]. Bruneton's axis (`sun_angle_share` 0) in closed form:
    a = A (1 - x) / (1 + x A), d = d_min + min(a, A) (d_max - d_min), mu_s = (H^2 - d^2) /
    (2 R_b d); a share > 0 by bisection in mu_s over [mu_s_min, 1]."""
    d_min, d_max, big_a = mu_s_mapping_constants(bottom_radius, top_radius, mu_s_min)
    if sun_angle_share > 0.0:
        low, high = mu_s_min, 1.0
        for _ in range(MU_S_BISECTION_STEPS):
            middle = 0.5 * (low + high)
            if scattering_u_mu_s_from_constants(middle, bottom_radius, top_radius, mu_s_min,
                                                d_min, d_max, big_a, sun_angle_share,
                                                n_mu_s) < u_mu_s:
                low = middle
            else:
                high = middle
        return 0.5 * (low + high)
    x = unit_range_from_texture_coord(u_mu_s, n_mu_s)
    a = (big_a - x * big_a) / (1.0 + x * big_a)
    d = d_min + min(a, big_a) * (d_max - d_min)
    if d <= 0.0:
        return 1.0
    big_h = d_max
    return min(max((big_h * big_h - d * d) / (2.0 * bottom_radius * d), -1.0), 1.0)


@njit(cache=True)
def view_sun_spread(mu, mu_s):
    """sqrt((1 - mu^2)(1 - mu_s^2)) [-]: nu = mu mu_s + spread cos(phi), phi the azimuth of the
    view about the zenith from the sun's."""
    return math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))


@njit(cache=True)
def view_sun_azimuth(nu, mu, mu_s):
    """phi in [0, pi] [rad], the view's azimuth about the local zenith from the sun's, from
    nu = cos(view-sun angle) and the zenith cosines mu, mu_s; 0 where it is undefined
    (spread <= SPREAD_MIN: a view or a sun at the zenith or the nadir)."""
    return math.acos(view_sun_cos_azimuth(nu, mu, mu_s))


@njit(cache=True)
def view_sun_cos_azimuth(nu, mu, mu_s):
    """cos(`view_sun_azimuth`), clamped to [-1, 1]; 1 where the azimuth is undefined."""
    spread = view_sun_spread(mu, mu_s)
    cos_phi = (nu - mu * mu_s) / spread if spread > SPREAD_MIN else 1.0
    return min(max(cos_phi, -1.0), 1.0)


@njit(cache=True)
def scattering_u_nu(nu, mu, mu_s):
    """u_nu = 1 - phi / pi, phi = `view_sun_azimuth` (module docstring) [-]."""
    return 1.0 - view_sun_azimuth(nu, mu, mu_s) / math.pi


@njit(cache=True)
def scattering_nu_from_u(u_nu, mu, mu_s):
    """Inverse of `scattering_u_nu`: nu = mu mu_s + spread cos(pi (1 - u_nu)), u_nu clamped to
    [0, 1]."""
    phi = math.pi * (1.0 - min(max(u_nu, 0.0), 1.0))
    return mu * mu_s + view_sun_spread(mu, mu_s) * math.cos(phi)


@njit(cache=True)
def scattering_uvwz_from_r_mu_mu_s_nu(r, mu, mu_s, nu, ray_hits_ground, bottom_radius,
                                      top_radius, mu_s_min, sun_angle_share, n_r, n_mu, n_mu_s,
                                      radius_warp):
    """(r, mu, mu_s, nu, ray_hits_ground) -> (u_r, u_mu, u_mu_s, u_nu), the table axis order
    (n_r, n_mu, n_mu_s, n_nu); module docstring. Bruneton 2017,
    `GetScatteringTextureUvwzFromRMuMuSNu` (which returns them as (u_nu, u_mu_s, u_mu, u_r))."""
    return (scattering_u_r(r, bottom_radius, top_radius, n_r, radius_warp),
            scattering_u_mu(r, mu, ray_hits_ground, bottom_radius, top_radius, n_mu),
            scattering_u_mu_s(mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share,
                              n_mu_s),
            scattering_u_nu(nu, mu, mu_s))


@njit(cache=True)
def scattering_r_mu_mu_s_nu_from_uvwz(u_r, u_mu, u_mu_s, u_nu, bottom_radius, top_radius,
                                      mu_s_min, sun_angle_share, n_r, n_mu, n_mu_s,
                                      radius_warp):
    """Inverse of `scattering_uvwz_from_r_mu_mu_s_nu`: (r, mu, mu_s, nu, ray_hits_ground).

    nu lies within the values possible for (mu, mu_s), mu mu_s -+ sqrt((1 - mu^2)(1 - mu_s^2)),
    by construction (u_nu is an azimuth); Bruneton 2017,
    `GetRMuMuSNuFromScatteringTextureFragCoord`, clamps it there."""
    r = scattering_r_from_u(u_r, bottom_radius, top_radius, n_r, radius_warp)
    mu, hits_ground = scattering_mu_from_u(u_mu, r, bottom_radius, top_radius, n_mu)
    mu_s = scattering_mu_s_from_u(u_mu_s, bottom_radius, top_radius, mu_s_min, sun_angle_share,
                                  n_mu_s)
    nu = scattering_nu_from_u(u_nu, mu, mu_s)
    return r, mu, mu_s, nu, hits_ground


# --------------------------------------------------------------------------------------------
# Irradiance table (r, mu_s) <-> (x_mu_s, x_r), affine.
# --------------------------------------------------------------------------------------------

@njit(cache=True)
def irradiance_x_from_r_mu_s(r, mu_s, bottom_radius, top_radius):
    """(r, mu_s) -> (x_mu_s, x_r): x_mu_s = (mu_s + 1) / 2, x_r = (r - R_b) / (R_t - R_b),
    clamped to [0, 1] (Bruneton 2017, `GetIrradianceTextureUvFromRMuS`)."""
    x_r = (r - bottom_radius) / (top_radius - bottom_radius)
    return min(max(0.5 * (mu_s + 1.0), 0.0), 1.0), min(max(x_r, 0.0), 1.0)


@njit(cache=True)
def irradiance_r_mu_s_from_x(x_mu_s, x_r, bottom_radius, top_radius):
    """Inverse of `irradiance_x_from_r_mu_s`: (r [m], mu_s [-])."""
    return bottom_radius + x_r * (top_radius - bottom_radius), 2.0 * x_mu_s - 1.0
