r"""Monte Carlo reference solver: sky radiance of any `OpticalProfile`, exact up to noise.

Backward (adjoint) path tracing from the observer, one wavelength at a time (Marchuk et al.
1980, "The Monte Carlo Methods in Atmospheric Optics", Springer, ch. 2; Novák et al. 2018,
"Monte Carlo methods for volumetric light transport simulation", Comput. Graph. Forum 37(2),
551, doi:10.1111/cgf.13383). A path starts where the view ray is inside the atmosphere
(observers in space: where it enters; rays that miss the atmosphere see 0) and estimates

    L(x, v) = int T(x, y) beta_s(y) int p(y, v.w) L(y, w) dw dt + T(x, g) L_ground(g)

with the collision estimator. Each path has two branches:
- the first collision y along the view ray is drawn from a table of `n_view_intervals`
  intervals (`_monte_carlo_kernels.first_collision_cdf`): an interval with probability
  (1/2) (its share of the collision probability 1 - T) + (1/2) (its share of the
  single-scattering integrand beta_s p T T_sun V), then a uniform point in it; the weight is
  T(y) beta_e(y) / pdf(y). This forced, defensive importance sampling (Marchuk et al. 1980
  §2.4; Hesterberg 1995, Technometrics 37, 185) removes the paths that would leave without a
  collision and, in twilight, puts half of the collisions into the still sunlit air;
- when the view ray meets the ground, the ground branch starts there with weight T(x, g);
- after the first event, free flights use delta tracking against a constant majorant
  (Woodcock et al. 1965; Novák et al. 2018 §5.1), so collisions have density beta_e T exactly;
- at a collision y the weight is multiplied by the single-scattering albedo beta_s / beta_e
  (absorbers act through beta_e), and the next-event estimate towards the sun is added:
  weight * E_sun * p_mix(nu) * T_sun(y) * V(y), p_mix = sum_c beta_s,c p_c / beta_s;
- the path continues in a direction drawn by detector directional importance sampling
  (Buras & Mayer 2011, "Efficient unbiased variance reduction techniques for Monte Carlo
  simulations of radiative transfer in cloudy atmospheres: The solution", JQSRT 112, 434,
  §3.2, doi:10.1016/j.jqsrt.2010.10.005, with the sun in the detector's place): with
  probability 1 - eps from the phase function about the path direction (a constituent chosen
  in proportion to beta_s,c), with probability eps (`sun_sampling_probability`) from the
  phase functions about the sun direction (constituents in proportion to tau_s,c p_c(0),
  `sun_proposal_shares`), and weighted by p_mix / q with q the density of the whole mixture,
  so the estimate stays unbiased. Weights p / q grow by up to 1 / (1 - eps) per order, so in
  optically thick layers eps > 0 is ruinous (the default is 0 there: `default_sun_sampling`);
- at the Lambertian ground the estimate weight * albedo / pi * E_sun * mu_s * T_sun * V is
  added, the weight is multiplied by the albedo and a new direction is drawn in the same way
  (cosine-distributed with probability 1 - eps, weight (mu / pi) / q);
- after `rr_start` orders, Russian roulette below a tenth of the path's starting weight (it
  ends with probability 1 - weight / floor, else goes on at the floor): unbiased, and paths
  whose weight stays near 1 (conservative layers) live until they leave, however many orders
  that takes. (A survival probability capped below 1 made the few paths that climb through
  an optically thick deck to its sunlit top carry weights growing as 1.05^order: a
  heavy-tailed estimator that found a third of the light under `earth-overcast`.)
  `max_orders` cuts the series (1: single scattering plus one ground reflection of direct
  sunlight, as `SingleScatteringSolver`). Paths leaving the top end.

Forward peaks (issue 17). Each phase function is split at `peak_truncation_deg` (theta_c) into
a smooth part p*_c, equal to p_c beyond theta_c and clipped to p_c(theta_c) inside it, and a
peak P_c = p_c - p*_c (the clip of `phase_truncation.truncate_forward_peak`; the kernels use
p* = p - P, so the two parts sum to p exactly whatever the clip). Sunlight that reaches a point
after scatterings in the peaks alone (the forward-scattered beam that delta-M scaling counts
as direct; in a cloud deck of optical depth 20 it carries most of the light in the top
layers) would otherwise be found only by paths whose direction happens to lie within a
degree of the sun before a next-event estimate through a peak of hundreds of sr^-1: rare,
huge contributions. Every light path is therefore counted once, by the last smooth event
before the sun (a scattering through p* or a ground reflection):
- a path's next-event estimates use p* once the path has scattered smoothly (each scattering
  is labelled smooth with probability p*_mix / p_mix after its direction is drawn; a ground
  reflection is smooth), the whole p before (the aureole seen from the observer);
- at each collision and ground reflection an aureole walk (`aureole_light`) estimates the
  light arriving there by one or more peak scatterings, weighted by that event's smooth
  scattering: a direction from the sun-centred proposal, then scatterings in the peaks only
  (directions half from p about the walk's direction, half from the sun-centred proposal,
  weighted by P / q), each with a next-event estimate through P. The walk
  runs with probability min(1, (T' - T) / 0.01), T' - T = T_sun (exp(tau_peak) - 1) the
  forward-scattered beam of delta-M at the point, and is divided by it (unbiased, and rarely
  run in clear air or deep in a thick layer, where the beam is weak).
Measured against DISORT (delta-M with 64 streams, 512 moments) for water droplets of 10 um
(forward peak 592 sr^-1) under a slab of optical depth 8 and 20 and a 500 m deck of optical
depth 10 (tests/transport/test_transport_monte_carlo.py; docs/validation.md). theta_c = 0
gives the plain estimator.

The view ray's intervals (`n_view_intervals`, dense at the lowest point) and the sun's
(`n_sun_samples`) are each cut into equal parts holding at most 0.05 optical depth
(`_monte_carlo_kernels.interval_splits`): 256 view intervals put 70 m and 2.8 optical depths
of a stratus deck into one interval, whose trapezoid column across the deck's edges made the
radiance 25 % too dark 40 deg from the zenith, and 128 sun intervals crossed the deck's top in
30-50 m steps from inside it (T_sun 5-13 % too small, the light under and above the deck 4-8 %).

T_sun is ray marched to the top of the atmosphere with `n_sun_samples` intervals (dense at the
lowest point, trapezoid rule, cut as above; `_monte_carlo_kernels.refined_columns`), and T
along the view ray from the same rule on `n_view_intervals` intervals: the only
discretisations, 2e-4 in optical depth for the zenith and 2e-3 for a sun 5 deg high at the
defaults in clear air (measured against 20 000 intervals), T_sun within 0.25 % of 16 384
intervals inside the top of `earth-overcast`'s deck. The sun is a point source unless the
profile gives it a radius, in which case V is the part of its disk above the geometric horizon
(`geometry.sun_visible_fraction`) and a sun below the horizon is attenuated like the horizon
ray, as in the other solvers; the sun disk's own radiance is not included. Phase functions are
tabulated at `n_angle` scattering angles (`scatterers.sample_phase_functions`) and interpolated
linearly in angle. Each result is a mean over `n_samples` paths per ray and wavelength with its
standard error; a fixed `seed` gives the same numbers for any number of threads. With
`target_relative_error` the rays whose relative standard error is above it in some band get
more paths, predicted from their variance, in up to `ADAPTIVE_ROUNDS` rounds and at most
`max_samples` (stopping on the estimated error biases the mean by a small fraction of a
standard error; the rounds start from `n_samples` paths so that the estimate is settled).

Noise (docs/validation.md, benchmarks/bench_monte_carlo.py; 16 rays x 3 bands, 4 seeds of
2000 paths against one run of 16 000): `mars-physical` (Mie dust) median relative standard
error 1.3, 1.4, 1.9, 3.6 % at sun zenith 0, 30, 60, 85 (with eps = 0 alone 1.3, 1.4, 2.2,
4.6 %; before the aureole walks 1.5, 1.6, 2.2, 4.7 %, and with plain sampling 3.0, 4.0, 6.5,
15.4 %), 93-95 % of the seeds within 2 standard errors of the long run. Thick layers
(benchmarks/compare_monte_carlo_thick.py): droplet slabs and the `earth-overcast` deck within
two standard errors of DISORT, 1-3 % with 20 000 paths.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.checks import checked_integer, checked_number
from skyscatter.errors import InputError
from skyscatter.transport import _monte_carlo_kernels
from skyscatter.transport.geometry import broadcast_rays
from skyscatter.transport.phase_truncation import truncate_forward_peak
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["MonteCarloSolver"]

PATHS_PER_CALL = 1 << 20  # paths (rays x wavelengths x samples) per kernel call, for progress
# eps, the probability of the sun-centred part of the direction proposal (module doc): 0.3 gave
# the lowest noise of 0.1, 0.3 and 0.5 for mars-physical, HG dust and Earth with aerosol
# (sun zenith 0, 30, 85; benchmarks/bench_monte_carlo.py measures it).
SUN_SAMPLING_PROBABILITY = 0.3
# Columns that scatter more than this vertical optical depth in some band get eps = 0 by
# default: the mixture's weights grow by 1 / (1 - eps) per order, and paths through thick
# layers have hundreds (a droplet deck of optical depth 10: within 1 standard error of DISORT
# with eps = 0, 30-60 % too dark with 0.3).
THICK_COLUMN_OPTICAL_DEPTH = 2.0
# theta_c: the phase functions' forward peaks within this angle are estimated by the aureole
# walks (module doc); 0 turns them off.
PEAK_TRUNCATION_DEG = 20.0
# Only peaks reaching this phase function [sr^-1] are split off: a next-event estimate through
# a lower peak (Henyey-Greenstein g 0.7: 1.5 sr^-1) is no heavy tail, and the walks would cost
# Earth's clear sky 30 % of its speed for nothing (Mie dust: 20-40, cloud droplets: 592).
PEAK_MIN_PHASE = 10.0
ADAPTIVE_ROUNDS = 3  # rounds of extra paths towards target_relative_error
ADAPTIVE_MAX_FACTOR = 32  # default max_samples: this many times n_samples
MAX_SAMPLES_LIMIT = 1_000_000_000  # largest max_samples accepted (work units must stay < 2^32)


def mean_and_standard_error(sums: np.ndarray, squares: np.ndarray,
                            paths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(mean, standard error of the mean) (n_ray, n_wl) from the sums and sums of squares
    (n_ray, n_wl) of `paths` (n_ray,) path estimates per ray and wavelength."""
    n = paths[:, None]
    mean = sums / n
    variance = np.maximum(squares / n - mean * mean, 0.0) * n / (n - 1)
    return mean, np.sqrt(variance / n)


def sun_proposal_shares(profile: OpticalProfile, scatterers: np.ndarray,
                        phase: np.ndarray) -> np.ndarray:
    """Shares [-] (n_s, n_wl) of the constituents in the sun-centred proposal: in proportion to
    tau_s,c p_c(0), the column scattering optical depth times the forward peak of the phase
    function (phase (n_s, n_wl, n_angle) [sr^-1] from theta = 0), so that the constituents
    whose peak makes the next-event estimate spike get the sun-centred samples; each column
    sums to 1 (equal shares where nothing scatters)."""
    column = np.trapezoid(np.asarray(profile.density, dtype=np.float64),
                          np.asarray(profile.altitudes_m, dtype=np.float64), axis=1)
    depth = np.asarray(profile.scattering_per_density, dtype=np.float64) * column[:, None]
    weight = depth[scatterers] * phase[:, :, 0]
    total = weight.sum(axis=0)
    shares = np.full_like(weight, 1.0 / scatterers.size)
    return np.divide(weight, total, out=shares, where=total > 0.0)


def default_sun_sampling(profile: OpticalProfile) -> float:
    """eps [-] for `profile`: `SUN_SAMPLING_PROBABILITY`, or 0 where the column scatters more
    than `THICK_COLUMN_OPTICAL_DEPTH` in some band (module doc)."""
    column = np.trapezoid(np.asarray(profile.density, dtype=np.float64),
                          np.asarray(profile.altitudes_m, dtype=np.float64), axis=1)
    depth = column @ np.asarray(profile.scattering_per_density, dtype=np.float64)
    return 0.0 if np.max(depth) > THICK_COLUMN_OPTICAL_DEPTH else SUN_SAMPLING_PROBABILITY


class MonteCarloSolver:
    """Sky radiance by backward Monte Carlo path tracing with all scattering orders.

    Parameters
    ----------
    profile : OpticalProfile
        The atmosphere.
    n_samples : int
        Paths per view ray and wavelength.
    seed : int
        Seed of the random numbers (results are reproducible for a fixed seed).
    max_orders : int
        Most scattering events (air or ground) per path; 1 gives single scattering.
    rr_start : int
        Order from which Russian roulette may end a path.
    n_angle : int
        Scattering angles of the phase-function tables.
    n_sun_samples : int
        Ray-marching intervals of the transmittance towards the sun.
    n_view_intervals : int
        Intervals along each view ray from which the first collision is drawn.
    batch : int
        Paths per work unit (one random-number seed each).
    sun_sampling_probability : float or None
        eps in [0, 1): the probability of drawing a new direction about the sun instead of
        about the path (module doc); 0 is plain phase-function sampling. Default:
        `default_sun_sampling` (0.3, or 0 for optically thick columns).
    target_relative_error : float or None
        If given, in (0, 1]: rays whose relative standard error is above it in some band get
        more paths until it is reached (or `max_samples`).
    max_samples : int or None
        Most paths per ray and wavelength with `target_relative_error` (default 32 x
        `n_samples`).
    peak_truncation_deg : float
        theta_c [deg] of the forward peaks' aureole walks (module doc); 0 turns them off.
    """

    name = "montecarlo"

    def __init__(self, profile: OpticalProfile, n_samples: int = 1024, seed: int = 0, *,
                 max_orders: int = 1000, rr_start: int = 8, n_angle: int = 4097,
                 n_sun_samples: int = 128, n_view_intervals: int = 256,
                 batch: int = 256, sun_sampling_probability: float | None = None,
                 target_relative_error: float | None = None,
                 max_samples: int | None = None,
                 peak_truncation_deg: float = PEAK_TRUNCATION_DEG) -> None:
        if n_samples < 2:
            raise InputError("the Monte Carlo solver needs at least 2 paths per ray",
                             key="n_samples", value=n_samples)
        if max_orders < 1:
            raise InputError("max_orders must be at least 1", key="max_orders",
                             value=max_orders)
        self.profile = profile
        self.n_samples = int(n_samples)
        self.seed = int(seed)
        self.max_orders = int(max_orders)
        self.rr_start = int(rr_start)
        self.n_sun_samples = int(n_sun_samples)
        self.n_view_intervals = int(n_view_intervals)
        self.batch = int(batch)
        self.peak_truncation_deg = checked_number("peak_truncation_deg", peak_truncation_deg,
                                                  0.0, 90.0)
        self.sun_sampling_probability = (
            default_sun_sampling(profile) if sun_sampling_probability is None else checked_number(
                "sun_sampling_probability", sun_sampling_probability, 0.0, 1.0, high_open=True))
        self.target_relative_error = (None if target_relative_error is None else checked_number(
            "target_relative_error", target_relative_error, 0.0, 1.0, low_open=True))
        self.max_samples = (ADAPTIVE_MAX_FACTOR * self.n_samples if max_samples is None
                            else checked_integer("max_samples", max_samples, self.n_samples,
                                                 MAX_SAMPLES_LIMIT))
        self._h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
        self._scatterers = np.array(scattering_constituents(profile), dtype=np.int64)
        phase = sample_phase_functions(profile, tuple(self._scatterers), n_angle)
        if self._scatterers.size == 0:  # nothing scatters: one dummy isotropic row
            self._scatterers = np.zeros(1, dtype=np.int64)
            phase = np.full((1, n_angle, profile.n_wavelengths), 0.25 / np.pi)
        self._phase = np.ascontiguousarray(np.transpose(phase, (0, 2, 1)))
        smooth, fraction = truncate_forward_peak(phase, self.peak_truncation_deg)
        fraction = np.where(phase[:, 0, :] >= PEAK_MIN_PHASE, fraction, 0.0)
        clipped = np.where(fraction[:, None, :] > 0.0, smooth * (1.0 - fraction[:, None, :]),
                           phase)
        self._peak = np.ascontiguousarray(np.transpose(np.maximum(phase - clipped, 0.0),
                                                       (0, 2, 1)))
        self._cdf = _monte_carlo_kernels.phase_cdf(self._phase)
        self._sun_share = sun_proposal_shares(profile, self._scatterers, self._phase)
        scattering = np.asarray(profile.scattering_per_density, dtype=np.float64).copy()
        mask = np.zeros(scattering.shape[0], dtype=bool)
        mask[list(scattering_constituents(profile))] = True
        scattering[~mask] = 0.0
        self._scattering = np.ascontiguousarray(scattering)
        peak_scattering = np.zeros_like(scattering)
        peak_scattering[self._scatterers] = scattering[self._scatterers] * fraction
        self._peak_scattering = np.ascontiguousarray(peak_scattering)
        self._extinction = np.ascontiguousarray(profile.extinction_per_density,
                                                dtype=np.float64)
        self._density = np.ascontiguousarray(profile.density, dtype=np.float64)
        # Largest extinction over the levels: a majorant of the linearly interpolated density.
        level_extinction = self._density.T @ self._extinction  # (n_z, n_wl)
        self._majorant = np.ascontiguousarray(np.max(level_extinction, axis=0) * (1.0 + 1e-12))
        self._extinction_maxima = _monte_carlo_kernels.extinction_maxima(
            np.max(level_extinction, axis=1))

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1] seen from `position` (planet-centred
        [m], (3,) or broadcastable to the directions) along `view_directions` (..., 3), with
        the sun along `sun_direction` (3,); the mean over the paths. Returns (..., n_wl)."""
        return self.sky_radiance_with_error(position, view_directions, sun_direction,
                                            progress)[0]

    def sky_radiance_with_error(self, position: ArrayLike, view_directions: ArrayLike,
                                sun_direction: ArrayLike,
                                progress: Callable[[int], None] | None = None
                                ) -> tuple[np.ndarray, np.ndarray]:
        """(mean, standard error of the mean) of the sky radiance [W m^-2 sr^-1 nm^-1], each
        (..., n_wl); arguments as `sky_radiance`. `progress(n)` is called with the number of
        rays done after each chunk of the first `n_samples` paths per ray. With
        `target_relative_error`, rays whose relative standard error is above it in some band
        get more paths afterwards, in up to `ADAPTIVE_ROUNDS` rounds of multiples of
        `n_samples`, at most `max_samples` in all."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = np.asarray(sun_direction, dtype=np.float64)
        sun = np.ascontiguousarray(sun / np.linalg.norm(sun))
        n_ray, n_wl = directions.shape[0], self.profile.n_wavelengths
        tally = (np.zeros((n_ray, n_wl)), np.zeros((n_ray, n_wl)), np.zeros(n_ray))
        units = self._trace(origins, directions, sun, np.arange(n_ray), self.n_samples, 0,
                            tally, progress)
        for _ in range(ADAPTIVE_ROUNDS if self.target_relative_error is not None else 0):
            extra = self._extra_paths(*tally)
            for count in np.unique(extra[extra > 0]):
                units = self._trace(origins, directions, sun, np.flatnonzero(extra == count),
                                    int(count), units, tally, None)
        mean, error = mean_and_standard_error(*tally)
        out_shape = shape + (n_wl,)
        return mean.reshape(out_shape), error.reshape(out_shape)

    def _trace(self, origins: np.ndarray, directions: np.ndarray, sun: np.ndarray,
               rays: np.ndarray, n_paths: int, unit_offset: int,
               tally: tuple[np.ndarray, np.ndarray, np.ndarray],
               progress: Callable[[int], None] | None) -> int:
        """Trace `n_paths` more paths per wavelength for each ray index in `rays`, adding their
        sums, sums of squares and path counts to `tally`; work units are numbered from
        `unit_offset` (`_monte_carlo_kernels.trace_rays`). Returns the next free unit number."""
        p = self.profile
        sums, squares, paths = tally
        units_per_ray = p.n_wavelengths * ((n_paths + self.batch - 1) // self.batch)
        chunk = max(1, PATHS_PER_CALL // (n_paths * p.n_wavelengths))
        for start in range(0, rays.size, chunk):
            chosen = rays[start:start + chunk]
            ray_origins = np.ascontiguousarray(origins[chosen])
            ray_directions = np.ascontiguousarray(directions[chosen])
            nodes = _monte_carlo_kernels.view_ray_nodes(
                ray_origins, ray_directions, sun, self.n_view_intervals, p.bottom_radius_m,
                p.top_radius_m, self._h_step, self._density, self._extinction_maxima,
                float(p.sun_angular_radius_rad), self.n_sun_samples)
            first = _monte_carlo_kernels.first_collision_tables(
                nodes, sun, self._extinction, self._scattering, self._scatterers, self._phase,
                ray_directions)
            batch_sums, batch_squares = _monte_carlo_kernels.trace_rays(
                ray_origins, ray_directions, unit_offset + start * units_per_ray, sun, n_paths,
                self.batch, self.seed, self.max_orders, self.rr_start, p.bottom_radius_m,
                p.top_radius_m, self._h_step, self._density, self._extinction,
                self._extinction_maxima, self._scattering, self._scatterers, self._phase,
                self._cdf, self._majorant,
                np.ascontiguousarray(p.toa_irradiance, dtype=np.float64),
                np.ascontiguousarray(p.ground_albedo, dtype=np.float64),
                float(p.sun_angular_radius_rad), self.n_sun_samples, self._sun_share,
                self.sun_sampling_probability, self._peak, self._peak_scattering, nodes, first)
            sums[chosen] += batch_sums.sum(axis=2)
            squares[chosen] += batch_squares.sum(axis=2)
            paths[chosen] += n_paths
            if progress is not None:
                progress(chosen.size)
        return unit_offset + rays.size * units_per_ray

    def _extra_paths(self, sums: np.ndarray, squares: np.ndarray,
                     paths: np.ndarray) -> np.ndarray:
        """More paths per ray (n_ray,), a multiple of `n_samples`, that bring its largest
        relative standard error over the bands to `target_relative_error` if the variance
        stays as estimated, within `max_samples`; 0 for rays at the target or without light."""
        mean, error = mean_and_standard_error(sums, squares, paths)
        with np.errstate(divide="ignore", invalid="ignore"):
            relative = np.where(mean > 0.0, error / mean, 0.0).max(axis=1)
        needed = paths * (relative / self.target_relative_error) ** 2
        extra = np.ceil((needed - paths) / self.n_samples) * self.n_samples
        return np.where(relative > self.target_relative_error,
                        np.minimum(extra, self.max_samples - paths), 0).astype(np.int64)

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf, n_samples: int = 256) -> np.ndarray:
        """Transmittance [-] from `position` along `directions` over `distance_m` [m] (inf:
        out of the atmosphere, towards a light source; 0 when the ground blocks the path, so
        for a light below the horizon), ray marched (`_kernels.transmittance_rays`,
        deterministic). Returns (..., n_wl)."""
        return ray_marched_transmittance(self.profile, position, directions, distance_m,
                                         n_samples)
