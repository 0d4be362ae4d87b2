r"""Monte Carlo reference through 3D clouds: the diffuse sky radiance of an `OpticalProfile`
with the cloud layers of a `CloudField` in it, exact up to noise.

The renderer's clouds (`transport.clouds`) are an approximation; this reference judges them.
Backward path tracing from the observer, as `MonteCarloSolver` (Marchuk et al. 1980, "The Monte
Carlo Methods in Atmospheric Optics", Springer, ch. 2; Novák et al. 2018, "Monte Carlo methods
for volumetric light transport simulation", Comput. Graph. Forum 37(2), 551,
doi:10.1111/cgf.13383), through the medium

    beta_e(p) = sum_c n_c(h) k_c + k_ext,l w_l(p)
    beta_s(p) = sum_c n_c(h) s_c + omega_l k_ext,l w_l(p)

of the air's constituents c (densities linear between the profile's levels) and the water
content w_l of the cloud layer l at p (`cloud_field.layer_water`; layers do not overlap), with
mass extinction k_ext,l [m^2 g^-1] and single-scattering albedo omega_l. Per path:
- three branches along the view ray, each unbiased for its share of the radiance:
  (a) a collision with the air drawn from the air's first-collision table
      (`_monte_carlo_kernels.first_collision_tables`: forced, so clear-sky rays lose no
      path), weight T_air beta_e,air / pdf times the clouds' transmittance T_c up to it;
  (b) a collision with a cloud drawn by delta tracking through the clouds alone (density
      sigma_c T_c), weight T_air up to it (from the same table);
  (c) where the view ray meets the ground, the ground, weight T_air T_c of the whole ray;
  the first collision of (a) scatters by the air, that of (b) by the cloud;
- then free flights through air and clouds by delta tracking region by region, between the
  shells of the layers (`_cloud_monte_carlo_kernels.free_flight`): inside a layer the majorant
  is the air's plus k_ext,l params[l, WATER] (the largest water content), elsewhere the air's;
  a tentative collision is real with probability beta_e / majorant;
- at a collision the weight is multiplied by beta_s / beta_e (absorption) and the next-event
  estimate weight E_sun p_mix(nu) T_air V T_c is added, p_mix = sum beta_s,c p_c / beta_s
  over the air's constituents and the cloud; at the Lambertian ground (`ground_albedo`)
  weight albedo / pi E_sun mu_s T_air V T_c, and the weight is multiplied by the albedo;
- T_air V is `_monte_carlo_kernels.sun_attenuation` (ray marched with `n_sun_samples`
  intervals, V the visible part of the disk); T_c an unbiased ratio-tracking estimate along
  the same ray (Novák et al. 2014, "Residual ratio tracking for estimating attenuation in
  participating media", ACM TOG 33(6), 179, doi:10.1145/2661229.2661292), with Russian
  roulette below T_c = 0.05; T_air is marched only where T_c > 0;
- the path goes on in a direction drawn from p_mix (a component in proportion to its beta_s,
  then its phase table), or cosine-distributed from the ground, and may branch (below);
- from order `rr_start` on, paths lighter than 0.1 play Russian roulette (survival weight /
  0.1, in units of their importance, below). Not the fixed survival of `MonteCarloSolver` (at
  most 0.95 per order): in a conservative cloud the orders fall off by less (~0.975 per order
  at optical depth 20), so a fixed survival would make the variance grow with each order.
  Paths end when they leave the top, are absorbed (ground, aerosol) or after `max_orders`
  events (a cut; 10^5 by default, far beyond what paths in the presets reach).

Sun-centred branches. About 40 % of a droplet's phase function lies within 2 deg of the
forward direction (p(0) = 200-450 sr^-1 for r_eff 7 um, against 1 / 4 pi on average), and in
a cloud much of the light near the sun has been scattered through that peak, often more than
once: a path that reaches a sunlit collision heading within a degree or two of the sun adds an
estimate hundreds of times the average. Drawn rarely, such paths make a heavy-tailed
estimator whose standard error is too small (a slab of optical depth 3, plain phase sampling:
22 % relative standard error after 4000 paths, single paths at 1000-2800 times the mean).
`MonteCarloSolver`'s cure, a one-sample mixture with a sun-centred proposal (detector
directional importance sampling, Buras & Mayer 2011, JQSRT 112, 434,
doi:10.1016/j.jqsrt.2010.10.005), multiplies weights by up to 1 / (1 - eps) per event, which
the hundreds of events of a path in a cloud turn into noise. Here every event keeps its own
phase-sampled direction and, with probability eps (`sun_sampling_probability`), also starts a
branch in a direction drawn from the clouds' forward peaks about the sun (their phase tables
within `PEAK_DEG` = 10 deg, layers in proportion to column x p(0)); both get the factor
p / (q + eps q_sun), the balance heuristic of multiple importance sampling for these expected
sample counts (Veach & Guibas 1995, SIGGRAPH, 419, doi:10.1145/218380.218498). The sum stays
unbiased, no weight grows, and a path that turns into the sun's peak by its own sampling
arrives light. Branches branch too (they are short: out of the peak they are light and end
in Russian roulette), and a path heading into the peak (importance J = max(1, 4 pi eps q_sun)
> 1) plays the roulette on weight x J. Paths heavier than 2 are split into copies. Measured
with eps = 0.5 (benchmark runs, 4 seeds): a slab of optical depth 3, 4000 paths, 2.4 %
relative standard error (plain sampling 11 %, the seeds' spread 0.9 of the stated error
against 1.5); optical depth 20, 1000 paths, 6.9 % (12 %); no path above 42 times the mean
in 20 000. eps 0.1-0.5 all help; 0.5 gave the lightest tails. Drawing the branches from the
whole phase function instead of its peak, or letting branches not branch, left spikes of
1000 times the mean (a branch in a generic direction that later turned into the peak).

Cloud phase functions are the field's tables (`PHASE_ANGLES` nodes at theta = pi (i / (n -
1))^2, read linearly in i as the renderer reads them), sampled by inverse CDF on the table
(uniform in cos(theta) within an interval, weighted by p / q); the air's are
`MonteCarloSolver`'s (`n_angle` angles, linear in theta). The sun disk itself is not in the
radiance; the sun is a point for the phase function. A fixed `seed` gives the same numbers on
any number of threads. Each value comes with the standard error of its mean over the paths.

Accuracy and noise (tests/transport/test_cloud_monte_carlo.py,
benchmarks/bench_cloud_monte_carlo.py): with no water, the sky of `MonteCarloSolver` within 2.1
combined standard errors (0.6-1.2 % each after 4000 paths); a uniform Mie slab of optical depth
2 within 2.1 of `MonteCarloSolver` with the slab in its profile, from the ground and from
inside the slab (ours 1.0-1.5 % after 20 000 paths). The cumulus preset over the earth preset,
sun zenith 40 deg, 48 x 48 fisheye (1804 rays, 3 wavelengths, 64 paths): 465 s on 2 shared
cores (745 paths/s), 312 MiB, median relative standard error 21.7 % (clear rays 17 %, cloudy
23 %), so about 4 % after 2000 paths (hours on 2 cores). A path into a cumulus cell scatters
about 270 times; most of the time goes to ratio tracking towards the sun through the layer's
sparse parts (a tentative point every ~11 m at the majorant of 0.4 g m^-3).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.cloud_field import BASE_R, PHASE_ANGLES, TOP_R, WATER, CloudField
from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.checks import checked_integer, checked_number
from skyscatter.errors import InputError
from skyscatter.transport import _cloud_monte_carlo_kernels, _monte_carlo_kernels
from skyscatter.transport.geometry import broadcast_rays
from skyscatter.transport.monte_carlo import mean_and_standard_error
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents

__all__ = ["CloudMonteCarlo"]

PATHS_PER_CALL = 1 << 18  # paths (rays x wavelengths x samples) per kernel call, for progress
MAJORANT_MARGIN = 1.0 + 1e-12  # majorants a rounding above the largest coefficient
SUN_SAMPLING_PROBABILITY = 0.5  # eps of the sun-centred branches (module doc)


class CloudMonteCarlo:
    """Diffuse sky radiance through air and 3D clouds by backward Monte Carlo path tracing.

    Parameters
    ----------
    profile : OpticalProfile
        The air (its own constituents; the clouds come from `field`).
    field : CloudField
        The cloud layers, on the profile's wavelengths and planet radius.
    n_samples : int
        Paths per view ray and wavelength (at least 2).
    seed : int
        Seed of the random numbers: a fixed seed gives the same numbers on any thread count.
    max_orders : int
        Most scattering or ground events per path (a cut: the module doc).
    rr_start : int
        Order from which light paths play Russian roulette (module doc).
    n_angle : int
        Scattering angles of the air's phase-function tables.
    n_sun_samples : int
        Ray-marching intervals of the air's transmittance towards the sun.
    n_view_intervals : int
        Intervals along each view ray of the air's first-collision table.
    batch : int
        Paths per work unit (one random-number seed each).
    sun_sampling_probability : float
        eps in [0, 1): the probability that an event starts a sun-centred branch (module
        doc); 0 is plain phase-function sampling.
    """

    def __init__(self, profile: OpticalProfile, field: CloudField, n_samples: int = 1024,
                 seed: int = 0, *, max_orders: int = 100_000, rr_start: int = 4,
                 n_angle: int = 4097, n_sun_samples: int = 128, n_view_intervals: int = 256,
                 batch: int = 64,
                 sun_sampling_probability: float = SUN_SAMPLING_PROBABILITY) -> None:
        self.n_samples = checked_integer("n_samples", n_samples, 2, 1_000_000_000)
        self.seed = checked_integer("seed", seed, 0, 2**32 - 1)
        self.max_orders = checked_integer("max_orders", max_orders, 1, 2**62)
        self.rr_start = checked_integer("rr_start", rr_start, 1, 2**62)
        self.n_sun_samples = checked_integer("n_sun_samples", n_sun_samples, 2, 1_000_000)
        self.n_view_intervals = checked_integer("n_view_intervals", n_view_intervals, 2,
                                                1_000_000)
        self.batch = checked_integer("batch", batch, 1, 1_000_000)
        self.sun_sampling_probability = checked_number(
            "sun_sampling_probability", sun_sampling_probability, 0.0, 1.0, high_open=True)
        _check_compatible(profile, field)
        self.profile = profile
        self.field = field
        self._air = _air_arrays(profile, checked_integer("n_angle", n_angle, 3, 1_000_000))
        self._cloud = _cloud_arrays(field)
        self._regions = _regions(profile, field, self._air[2])
        self._guide = (self.sun_sampling_probability, sun_proposal_shares(field, self._cloud[5]),
                       _peak_cdf(self._cloud[5], self._cloud[7]))
        self._light = (float(profile.bottom_radius_m), float(profile.top_radius_m),
                       float(profile.sun_angular_radius_rad), self.n_sun_samples,
                       np.ascontiguousarray(profile.ground_albedo, dtype=np.float64),
                       np.ascontiguousarray(profile.toa_irradiance, dtype=np.float64))

    def radiance_with_error(self, position: ArrayLike, view_directions: ArrayLike,
                            sun_direction: ArrayLike,
                            progress: Callable[[int], None] | None = None
                            ) -> tuple[np.ndarray, np.ndarray]:
        """(mean, standard error of the mean) of the diffuse spectral radiance [W m^-2 sr^-1
        nm^-1] seen from `position` (planet-centred [m], (3,) or broadcastable to the
        directions) along `view_directions` (..., 3), the sun along `sun_direction` (3,), each
        (..., n_wl); the sun disk itself is not included. `progress(n)` is called with the
        number of rays done after each chunk of rays."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = np.asarray(sun_direction, dtype=np.float64)
        sun = np.ascontiguousarray(sun / np.linalg.norm(sun))
        p = self.profile
        n_ray, n_wl = directions.shape[0], p.n_wavelengths
        sums, squares = np.zeros((n_ray, n_wl)), np.zeros((n_ray, n_wl))
        h_step, density, extinction, scattering, scatterers, phase = self._air[:6]
        chunk = max(1, PATHS_PER_CALL // (self.n_samples * n_wl))
        for start in range(0, n_ray, chunk):
            ray_origins = np.ascontiguousarray(origins[start:start + chunk])
            ray_directions = np.ascontiguousarray(directions[start:start + chunk])
            nodes = _monte_carlo_kernels.view_ray_nodes(
                ray_origins, ray_directions, sun, self.n_view_intervals, p.bottom_radius_m,
                p.top_radius_m, h_step, density, self._air[8], float(p.sun_angular_radius_rad),
                self.n_sun_samples)
            first = _monte_carlo_kernels.first_collision_tables(
                nodes, sun, extinction, scattering, scatterers, phase, ray_directions)
            batch_sums, batch_squares = _cloud_monte_carlo_kernels.trace_rays(
                ray_origins, ray_directions, start, sun,
                (self.n_samples, self.batch), self.seed, (self.max_orders, self.rr_start),
                self._air, self._cloud, self._regions, self._light, self._guide, nodes, first)
            sums[start:start + chunk] = batch_sums.sum(axis=2)
            squares[start:start + chunk] = batch_squares.sum(axis=2)
            if progress is not None:
                progress(ray_origins.shape[0])
        mean, error = mean_and_standard_error(sums, squares, np.full(n_ray, self.n_samples))
        return mean.reshape(shape + (n_wl,)), error.reshape(shape + (n_wl,))


def sun_proposal_shares(field: CloudField, phase: np.ndarray) -> np.ndarray:
    """Shares [-] (n_layers, n_wl) of the layers in the sun-centred proposal: in proportion to
    k_ext params[WATER] (top - base) p_l(0), the largest vertical optical depth of the layer
    times its forward peak (phase (n_layers, n_wl, PHASE_ANGLES) [sr^-1]); each column sums
    to 1 (equal shares where that is 0 everywhere)."""
    params = field.params
    depth = field.mass_extinction_m2_g * (params[:, WATER] * (params[:, TOP_R]
                                                              - params[:, BASE_R]))[:, None]
    weight = depth * phase[:, :, 0]
    total = weight.sum(axis=0)
    shares = np.full_like(weight, 1.0 / max(field.n_layers, 1))
    return np.divide(weight, total, out=shares, where=total > 0.0)


def _peak_cdf(phase: np.ndarray, cos_grid: np.ndarray) -> np.ndarray:
    """Cumulative proposal masses (n_layers, n_wl, n_peak) of the cloud phase tables (n_layers,
    n_wl, PHASE_ANGLES) [sr^-1] cut after the node n_peak - 1, the first at or beyond
    `PEAK_DEG` (`tabulated_phase_cdf` of the forward peak alone)."""
    theta_deg = np.degrees(np.arccos(np.clip(cos_grid, -1.0, 1.0)))
    n_peak = int(np.searchsorted(theta_deg, _cloud_monte_carlo_kernels.PEAK_DEG)) + 1
    return _monte_carlo_kernels.tabulated_phase_cdf(
        np.ascontiguousarray(phase[:, :, :n_peak]), cos_grid[:n_peak])


def _check_compatible(profile: OpticalProfile, field: CloudField) -> None:
    """InputError unless `field` is on the profile's wavelengths and planet and its layers lie
    inside the atmosphere."""
    wavelengths = np.asarray(profile.wavelengths_nm, dtype=np.float64)
    if field.wavelengths_nm.shape != wavelengths.shape or not np.allclose(
            field.wavelengths_nm, wavelengths, rtol=0.0, atol=1e-9):
        raise InputError("the cloud field's wavelengths differ from the profile's: build it "
                         "with cloud_field(clouds, radius, profile.wavelengths_nm)",
                         key="field", value=field.wavelengths_nm,
                         allowed=f"the profile's {wavelengths.size} wavelengths")
    if not np.isclose(field.bottom_radius_m, profile.bottom_radius_m, rtol=1e-12, atol=1e-6):
        raise InputError(f"the cloud field's planet radius {field.bottom_radius_m:g} m differs "
                         f"from the profile's {profile.bottom_radius_m:g} m", key="field",
                         value=field.bottom_radius_m,
                         allowed=f"{profile.bottom_radius_m:g} m")
    if field.n_layers and field.highest_radius_m > profile.top_radius_m:
        top_km = (profile.top_radius_m - profile.bottom_radius_m) / 1e3
        raise InputError(f"a cloud layer reaches above the top of the atmosphere ({top_km:g} "
                         "km): lower it or use a taller atmosphere", key="field",
                         value=field.highest_radius_m - profile.bottom_radius_m,
                         allowed=f"<= {top_km * 1e3:g} m")


def _air_arrays(profile: OpticalProfile, n_angle: int) -> tuple:
    """The air for the kernels, as `MonteCarloSolver` prepares it: (h_step [m], density
    (n_c, n_z), extinction and scattering per density (n_c, n_wl) (zero for the constituents
    that do not scatter), the scatterers' indices (n_s,), their phase tables (n_s, n_wl,
    n_angle) [sr^-1] at theta = pi i / (n_angle - 1), the tables' cumulative proposal masses,
    cos(theta_i) and the levels' largest extinction over the bands as
    `_monte_carlo_kernels.extinction_maxima`)."""
    scatterers = np.array(scattering_constituents(profile), dtype=np.int64)
    phase = sample_phase_functions(profile, tuple(scatterers), n_angle)
    if scatterers.size == 0:  # nothing scatters: one dummy isotropic row
        scatterers = np.zeros(1, dtype=np.int64)
        phase = np.full((1, n_angle, profile.n_wavelengths), 0.25 / np.pi)
    phase = np.ascontiguousarray(np.transpose(phase, (0, 2, 1)))
    scattering = np.asarray(profile.scattering_per_density, dtype=np.float64).copy()
    scattering[np.setdiff1d(np.arange(scattering.shape[0]),
                            scattering_constituents(profile))] = 0.0
    density = np.ascontiguousarray(profile.density, dtype=np.float64)
    extinction = np.ascontiguousarray(profile.extinction_per_density, dtype=np.float64)
    return (float(profile.altitudes_m[1] - profile.altitudes_m[0]), density, extinction,
            np.ascontiguousarray(scattering), scatterers, phase,
            _monte_carlo_kernels.phase_cdf(phase), np.cos(np.linspace(0.0, np.pi, n_angle)),
            _monte_carlo_kernels.extinction_maxima(np.max(density.T @ extinction, axis=1)))


def _cloud_arrays(field: CloudField) -> tuple:
    """The clouds for the kernels: (params, profiles, textures, k_ext [m^2 g^-1] and
    single-scattering albedo (n_layers, n_wl), phase tables (n_layers, n_wl, PHASE_ANGLES)
    [sr^-1], their cumulative proposal masses and the nodes' cos(theta))."""
    cos_grid = np.cos(np.pi * np.linspace(0.0, 1.0, PHASE_ANGLES) ** 2)
    phase = np.ascontiguousarray(np.transpose(field.phase, (0, 2, 1)), dtype=np.float64)
    return (np.ascontiguousarray(field.params), np.ascontiguousarray(field.profiles),
            np.ascontiguousarray(field.textures),
            np.ascontiguousarray(field.mass_extinction_m2_g, dtype=np.float64),
            np.ascontiguousarray(field.single_scattering_albedo, dtype=np.float64), phase,
            _monte_carlo_kernels.tabulated_phase_cdf(phase, cos_grid), cos_grid)


def _regions(profile: OpticalProfile, field: CloudField, extinction: np.ndarray) -> tuple:
    """(radii (n_region + 1,) [m], the layer of each region (n_region,) (-1: none), majorants
    (n_region, n_wl) and the clouds' own majorants (n_layers, n_wl) [m^-1]): the regions are
    the shells between the ground, each layer's base and top and the top of the atmosphere
    (`_cloud_monte_carlo_kernels` module doc)."""
    bottom, top = float(profile.bottom_radius_m), float(profile.top_radius_m)
    params = field.params
    cloud_majorant = (field.mass_extinction_m2_g * params[:, WATER, None]) * MAJORANT_MARGIN
    radii = np.unique(np.clip(np.concatenate([[bottom, top], params[:, BASE_R],
                                              params[:, TOP_R]]), bottom, top))
    middle = 0.5 * (radii[:-1] + radii[1:])
    inside = (params[None, :, BASE_R] <= middle[:, None]) & (middle[:, None]
                                                             <= params[None, :, TOP_R])
    layer = np.where(inside.any(axis=1), inside.argmax(axis=1), -1).astype(np.int64)
    # The air's majorant in a region: the largest extinction on the levels that bracket it
    # (the density is linear between levels, zero above the top one).
    altitudes = np.asarray(profile.altitudes_m, dtype=np.float64)
    h_step = altitudes[1] - altitudes[0]
    level_extinction = np.asarray(profile.density, dtype=np.float64).T @ extinction
    majorant = np.zeros((middle.size, extinction.shape[1]))
    for i in range(middle.size):
        low = int(np.floor((radii[i] - bottom) / h_step))
        high = min(int(np.ceil((radii[i + 1] - bottom) / h_step)), altitudes.size - 1)
        if low <= high:
            majorant[i] = level_extinction[low:high + 1].max(axis=0) * MAJORANT_MARGIN
        if layer[i] >= 0:
            majorant[i] += cloud_majorant[layer[i]]
    return (np.ascontiguousarray(radii), layer, majorant, np.ascontiguousarray(cloud_majorant))
