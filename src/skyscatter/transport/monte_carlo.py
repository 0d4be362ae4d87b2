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
- the path continues in a direction drawn from the phase function of a constituent chosen in
  proportion to beta_s,c (weight * p_c / proposal, see `_monte_carlo_kernels`);
- at the Lambertian ground the estimate weight * albedo / pi * E_sun * mu_s * T_sun * V is
  added, the weight is multiplied by the albedo and a cosine-distributed direction is drawn;
- after `rr_start` orders, Russian roulette (survival min(0.95, weight), weight / survival)
  ends paths without bias; `max_orders` cuts the series (1: single scattering plus one ground
  reflection of direct sunlight, as `SingleScatteringSolver`). Paths leaving the top end.

T_sun is ray marched to the top of the atmosphere with `n_sun_samples` intervals (dense at the
lowest point, trapezoid rule; `_kernels.columns_along_segment`), and T along the view ray from
the same rule on `n_view_intervals` intervals: the only discretisations, 2e-4 in optical depth
for the zenith and 2e-3 for a sun 5 deg high at the defaults (measured against 20 000
intervals). The sun is a point source unless the profile gives it a radius,
in which case V is the part of its disk above the geometric horizon
(`geometry.sun_visible_fraction`) and a sun below the horizon is attenuated like the horizon
ray, as in the other solvers; the sun disk's own radiance is not included. Phase functions are
tabulated at `n_angle` scattering angles (`scatterers.sample_phase_functions`) and interpolated
linearly in angle. Each result is a mean over `n_samples` paths per ray and wavelength with its
standard error; a fixed `seed` gives the same numbers for any number of threads.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport import _monte_carlo_kernels
from skyscatter.transport.geometry import broadcast_rays
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["MonteCarloSolver"]

PATHS_PER_CALL = 1 << 20  # paths (rays x wavelengths x samples) per kernel call, for progress


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
    """

    name = "montecarlo"

    def __init__(self, profile: OpticalProfile, n_samples: int = 1024, seed: int = 0, *,
                 max_orders: int = 1000, rr_start: int = 8, n_angle: int = 4097,
                 n_sun_samples: int = 128, n_view_intervals: int = 256,
                 batch: int = 256) -> None:
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
        self._h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
        self._scatterers = np.array(scattering_constituents(profile), dtype=np.int64)
        phase = sample_phase_functions(profile, tuple(self._scatterers), n_angle)
        if self._scatterers.size == 0:  # nothing scatters: one dummy isotropic row
            self._scatterers = np.zeros(1, dtype=np.int64)
            phase = np.full((1, n_angle, profile.n_wavelengths), 0.25 / np.pi)
        self._phase = np.ascontiguousarray(np.transpose(phase, (0, 2, 1)))
        self._cdf = _monte_carlo_kernels.phase_cdf(self._phase)
        scattering = np.asarray(profile.scattering_per_density, dtype=np.float64).copy()
        mask = np.zeros(scattering.shape[0], dtype=bool)
        mask[list(scattering_constituents(profile))] = True
        scattering[~mask] = 0.0
        self._scattering = np.ascontiguousarray(scattering)
        self._extinction = np.ascontiguousarray(profile.extinction_per_density,
                                                dtype=np.float64)
        self._density = np.ascontiguousarray(profile.density, dtype=np.float64)
        # Largest extinction over the levels: a majorant of the linearly interpolated density.
        self._majorant = np.ascontiguousarray(
            np.max(self._density.T @ self._extinction, axis=0) * (1.0 + 1e-12))

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
        rays done after each chunk."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = np.asarray(sun_direction, dtype=np.float64)
        sun = np.ascontiguousarray(sun / np.linalg.norm(sun))
        p = self.profile
        n = self.n_samples
        n_ray = directions.shape[0]
        mean = np.empty((n_ray, p.n_wavelengths))
        error = np.empty_like(mean)
        chunk = max(1, PATHS_PER_CALL // (n * p.n_wavelengths))
        for start in range(0, n_ray, chunk):
            stop = min(start + chunk, n_ray)
            nodes = _monte_carlo_kernels.view_ray_nodes(
                origins[start:stop], directions[start:stop], sun, self.n_view_intervals,
                p.bottom_radius_m, p.top_radius_m, self._h_step, self._density,
                float(p.sun_angular_radius_rad), self.n_sun_samples)
            first = _monte_carlo_kernels.first_collision_tables(
                nodes, sun, self._extinction, self._scattering, self._scatterers, self._phase,
                directions[start:stop])
            sums, squares = _monte_carlo_kernels.trace_rays(
                origins[start:stop], directions[start:stop], start, sun, n, self.batch,
                self.seed, self.max_orders, self.rr_start, p.bottom_radius_m,
                p.top_radius_m, self._h_step, self._density, self._extinction,
                self._scattering, self._scatterers, self._phase, self._cdf, self._majorant,
                np.ascontiguousarray(p.toa_irradiance, dtype=np.float64),
                np.ascontiguousarray(p.ground_albedo, dtype=np.float64),
                float(p.sun_angular_radius_rad), self.n_sun_samples, nodes, first)
            m = sums.sum(axis=2) / n
            variance = np.maximum(squares.sum(axis=2) / n - m * m, 0.0) * n / (n - 1)
            mean[start:stop] = m
            error[start:stop] = np.sqrt(variance / n)
            if progress is not None:
                progress(stop - start)
        out_shape = shape + (p.n_wavelengths,)
        return mean.reshape(out_shape), error.reshape(out_shape)

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf, n_samples: int = 256) -> np.ndarray:
        """Transmittance [-] from `position` along `directions` over `distance_m` [m] (inf:
        out of the atmosphere, towards a light source; 0 when the ground blocks the path, so
        for a light below the horizon), ray marched (`_kernels.transmittance_rays`,
        deterministic). Returns (..., n_wl)."""
        return ray_marched_transmittance(self.profile, position, directions, distance_m,
                                         n_samples)
