"""Hillaire 2020 solver: small tables computed in milliseconds, multiple scattering from an
isotropic second-order approximation, the sky from a per-observer sky-view table.

S. Hillaire, "A Scalable and Production Ready Sky and Atmosphere Rendering Technique",
Comput. Graph. Forum 39(4), 13-22 (EGSR 2020), doi:10.1111/cgf.14050, section 5:

- transmittance table, 256 (mu) x 64 (r) in Bruneton's parameterisation (Bruneton & Neyret
  2008, doi:10.1111/j.1467-8659.2008.01245.x; x_r = rho / H, x_mu from the distance to the
  top). The atmosphere is separable (`atmosphere.model`), so the table holds each
  constituent's column density (`_kernels.column_table`) and T = exp(-sum_c beta_e,c N_c) is
  formed per wavelength: one table serves any number of wavelengths;
- multiple-scattering table Psi_ms, 32 (altitude) x 32 (sun zenith cosine), eqs. 5-9: the
  light scattered twice with isotropic phase functions, L_2nd, and the share f_ms of light an
  isotropic medium scatters back to a point, each integrated over the sphere (64 directions),
  summed over all orders as a geometric series, Psi_ms = L_2nd / (1 - f_ms). Unlike the
  paper's table (uniform in altitude and mu_s, read linearly), the rows crowd at the ground
  (h = H x^2), the columns where the sun sets for the air above the observer (mu_s from 0 to
  the top's horizon; `multiple_scattering_nodes`), and log Psi_ms is interpolated, as Psi_ms
  falls by orders of magnitude there: read linearly from the paper's table the Earth's sky
  with the sun 4 deg below the horizon came out up to 3.7 times too bright;
- the radiance along a ray, eq. 10 with eq. 1: single scattering with every constituent's own
  phase function plus sigma_s Psi_ms at each sample, and the sunlit Lambertian ground;
- the sky-view table, 192 azimuths from the sun x 108 latitudes with the paper's square-root
  mapping that crowds rows at the horizon (section 5.3), for one observer inside the
  atmosphere; `sky_radiance` interpolates it bilinearly for frames of `SKY_VIEW_MIN_RAYS` rays
  or more and marches each ray otherwise;
- aerial perspective: the paper's froxel volume needs a camera frustum, which the solver
  contract does not have; `aerial_perspective` marches each segment with the same source.

Spectral on the profile's wavelengths, for any profile: all constituents, their own phase
functions, absorbers through extinction minus scattering, the ground albedo per wavelength.
Limits (docs/techniques.md, "Hillaire 2020"): orders >= 2 see isotropic phase functions and a
medium that is laterally uniform around each point (the paper's assumptions), which is good
for thin clear air but not for thick or strongly forward-scattering media (Mars' dust); the
ground reflects the direct sun only; transmittance along views is ray marched
(`transport/transmittance.py`), as the paper marches its view rays. Kernels:
`transport/_hillaire_kernels.py`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _hillaire_kernels, _kernels
from skyscatter.transport.geometry import (
    broadcast_rays,
    horizon_cos_zenith,
    horizontal_towards,
    segment_rays,
)
from skyscatter.transport.single_scattering import hemisphere_irradiance
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["HillaireSolver", "multiple_scattering_nodes", "multiple_scattering_sun_centre",
           "sky_view_directions"]

TRANSMITTANCE_SIZE = (64, 256)  # (r, mu), the paper's 256 x 64 texture
TRANSMITTANCE_SAMPLES = 128  # intervals per column integral of the transmittance table
MULTIPLE_SCATTERING_SIZE = (32, 32)  # (altitude, mu_s)
# Gauss-Legendre zenith cosines on each side of the horizon x azimuths: 64 directions
MULTIPLE_SCATTERING_DIRECTIONS = (4, 8)
MULTIPLE_SCATTERING_SAMPLES = 32  # intervals per ray of the multiple-scattering table
# log Psi_ms where Psi_ms = 0 (the night side's full shadow; ~1e-2 sr^-1 by day): exp of it,
# and of anything interpolated towards it, underflows to 0 or to ~1e-170 of its neighbour
ZERO_LOG = -800.0
SKY_VIEW_SIZE = (108, 192)  # (latitude, azimuth from the sun)
# One observer inside the atmosphere with at least this many rays reads the sky-view table
# (which costs as much as its 20 736 rays marched); fewer rays are marched one by one.
SKY_VIEW_MIN_RAYS = 1 << 16
CHUNK_RAYS = 16384  # rays per kernel call: bounds the per-ray phase values (n_c x n_wl each)


class HillaireSolver:
    """Answers the solver questions with Hillaire 2020's tables (module docstring).

    Parameters
    ----------
    profile : OpticalProfile
        The atmosphere; its wavelengths are those of every result.
    n_samples : int
        Intervals per view ray (and per node of the sky-view table).
    """

    name = "hillaire"

    def __init__(self, profile: OpticalProfile, n_samples: int = 64) -> None:
        self.profile = profile
        self.n_samples = int(n_samples)
        self._h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
        self._density = np.ascontiguousarray(profile.density, dtype=np.float64)
        self._extinction = np.ascontiguousarray(profile.extinction_per_density,
                                                dtype=np.float64)
        scatters = np.array([phase is not None for phase in profile.phases])
        self._scattering = np.ascontiguousarray(  # (n_c, n_wl), 0 for pure absorbers
            np.where(scatters[:, None], profile.scattering_per_density, 0.0), dtype=np.float64)
        self._albedo = np.ascontiguousarray(profile.ground_albedo, dtype=np.float64)
        # (n_c, 64, 256) column densities [density x m] to the top
        self.transmittance_columns = _kernels.column_table(
            TRANSMITTANCE_SIZE[0], TRANSMITTANCE_SIZE[1], TRANSMITTANCE_SAMPLES,
            profile.bottom_radius_m, profile.top_radius_m, self._h_step, self._density)
        gauss_x, gauss_w = np.polynomial.legendre.leggauss(MULTIPLE_SCATTERING_DIRECTIONS[0])
        self._mu_s_centre = multiple_scattering_sun_centre(profile.bottom_radius_m,
                                                           profile.top_radius_m)
        # the table's node radii [m] (32,) and sun zenith cosines (32,)
        self.multiple_scattering_radii, self.multiple_scattering_sun_cosines = (
            multiple_scattering_nodes(profile.bottom_radius_m, profile.top_radius_m,
                                      self._mu_s_centre))
        # Psi_ms, L_2nd and f_ms (32, 32, n_wl), per unit sun irradiance
        self.multiple_scattering, self.second_order, self.f_ms = (
            _hillaire_kernels.multiple_scattering_table(
                self.multiple_scattering_radii, self.multiple_scattering_sun_cosines,
                gauss_x, gauss_w,
                MULTIPLE_SCATTERING_DIRECTIONS[1], MULTIPLE_SCATTERING_SAMPLES,
                profile.bottom_radius_m, profile.top_radius_m, self._h_step, self._density,
                self._extinction, self._scattering, self.transmittance_columns, self._albedo,
                float(profile.sun_angular_radius_rad)))

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1] (..., n_wl) seen from `position`
        (planet-centred [m], (3,) or broadcastable) along unit `view_directions` (..., 3) with
        the sun along `sun_direction` (3,): bilinear in the sky-view table of one observer
        inside the atmosphere with `SKY_VIEW_MIN_RAYS` rays or more, marched per ray
        otherwise. `progress(n)` is called with the number of rays done."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = _unit(sun_direction)
        n_wl = self.profile.n_wavelengths
        if self._uses_sky_view(origins):
            origin = origins[0]
            table = self.sky_view_table(origin, sun)
            radiance = np.empty((directions.shape[0], n_wl))
            r = float(np.linalg.norm(origin))
            _hillaire_kernels.sky_view_lookup(
                table, _sun_frame(origin, sun), directions,
                float(np.arccos(horizon_cos_zenith(r, self.profile.bottom_radius_m))),
                radiance)
            if progress is not None:
                progress(directions.shape[0])
        else:
            radiance, _ = self._march(origins, directions, np.full(directions.shape[0], np.inf),
                                      sun, True, progress)
        return radiance.reshape(shape + (n_wl,))

    def sky_view_table(self, position: ArrayLike, sun_direction: ArrayLike) -> np.ndarray:
        """The sky-view table (108, 192, n_wl) [W m^-2 sr^-1 nm^-1] of the observer at
        `position` (3,) inside the atmosphere: the radiance marched along
        `sky_view_directions`, sunlit ground included below the horizon."""
        origin = np.asarray(position, dtype=np.float64).reshape(3)
        sun = _unit(sun_direction)
        local = sky_view_directions(float(np.linalg.norm(origin)),
                                    self.profile.bottom_radius_m)
        directions = np.ascontiguousarray((local @ _sun_frame(origin, sun)).reshape(-1, 3))
        radiance, _ = self._march(origin[None], directions,
                                  np.full(directions.shape[0], np.inf), sun, True, None)
        return radiance.reshape(local.shape[:2] + (self.profile.n_wavelengths,))

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] (..., n_wl) from `position` along `directions` over `distance_m`
        (inf: out of the atmosphere; 0 when the ground blocks the path): ray marched, as the
        paper's view rays (`ray_marched_transmittance`)."""
        return ray_marched_transmittance(self.profile, position, directions, distance_m)

    def aerial_perspective(self, position: ArrayLike, points: ArrayLike,
                           sun_direction: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """(inscattered [W m^-2 sr^-1 nm^-1], transmittance [-]), each (..., n_wl), between
        the observer at `position` and `points` (..., 3) [m]: the segment marched with the
        sky's source (single scattering + sigma_s Psi_ms), `LutSolver.aerial_perspective`
        has the meaning."""
        origins, directions, distances, shape = segment_rays(position, points)
        inscattered, transmittance = self._march(origins, directions, distances,
                                                 _unit(sun_direction), False, None)
        n_wl = self.profile.n_wavelengths
        return inscattered.reshape(shape + (n_wl,)), transmittance.reshape(shape + (n_wl,))

    def ground_irradiance(self, position: ArrayLike, sun_direction: ArrayLike
                          ) -> tuple[np.ndarray, np.ndarray]:
        """(direct, diffuse) spectral irradiance [W m^-2 nm^-1], each (n_wl,), on a horizontal
        surface at `position`: `hemisphere_irradiance` of this solver's sky (all orders)."""
        return hemisphere_irradiance(self, position, sun_direction)

    def _uses_sky_view(self, origins: np.ndarray) -> bool:
        """One observer inside the atmosphere (ground included) and enough rays."""
        if origins.shape[0] < SKY_VIEW_MIN_RAYS or np.any(origins != origins[0]):
            return False
        r = float(np.linalg.norm(origins[0]))
        return self.profile.bottom_radius_m <= r <= self.profile.top_radius_m

    def _march(self, origins: np.ndarray, directions: np.ndarray, distances: np.ndarray,
               sun: np.ndarray, with_ground: bool,
               progress: Callable[[int], None] | None) -> tuple[np.ndarray, np.ndarray]:
        """(radiance [W m^-2 sr^-1 nm^-1], transmittance), each (n, n_wl), along rays
        (`_hillaire_kernels.march_rays`), in chunks."""
        p = self.profile
        radiance = np.empty((directions.shape[0], p.n_wavelengths))
        transmittance = np.empty_like(radiance)
        psi = self.multiple_scattering
        log_psi = np.log(psi, out=np.full_like(psi, ZERO_LOG), where=psi > 0.0)
        for start in range(0, directions.shape[0], CHUNK_RAYS):
            stop = min(start + CHUNK_RAYS, directions.shape[0])
            chunk_origins = origins if origins.shape[0] == 1 else origins[start:stop]
            radiance[start:stop], transmittance[start:stop] = _hillaire_kernels.march_rays(
                chunk_origins, directions[start:stop], distances[start:stop], sun,
                self.n_samples, p.bottom_radius_m, p.top_radius_m, self._h_step,
                self._density, self._extinction, self._scattering,
                self._phase_scattering(directions[start:stop] @ sun),
                self.transmittance_columns, log_psi, self._mu_s_centre, self._albedo,
                float(p.sun_angular_radius_rad), with_ground)
            if progress is not None:
                progress(stop - start)
        return radiance * p.toa_irradiance, transmittance

    def _phase_scattering(self, nu: np.ndarray) -> np.ndarray:
        """beta_s,c p_c(nu) (n, n_c, n_wl) per unit density; 0 for pure absorbers."""
        p = self.profile
        out = np.zeros((nu.size, len(p.phases), p.n_wavelengths))
        for c, phase in enumerate(p.phases):
            if phase is not None:
                out[:, c, :] = phase.evaluate(nu, p.wavelengths_nm) * p.scattering_per_density[c]
        return out


def multiple_scattering_sun_centre(bottom_radius: float, top_radius: float) -> float:
    """The sun zenith cosine c around which the multiple-scattering table's columns crowd:
    halfway between the sun setting for the ground (0) and for the top of the atmosphere
    (its geometric horizon). The viewer's fast model reads it from `/api/fast`."""
    return 0.5 * horizon_cos_zenith(top_radius, bottom_radius)


def multiple_scattering_nodes(bottom_radius: float, top_radius: float, mu_s_centre: float
                              ) -> tuple[np.ndarray, np.ndarray]:
    """(radii [m], sun zenith cosines) of the multiple-scattering table's nodes, the
    `MULTIPLE_SCATTERING_SIZE` values x = k / (n - 1) of
    `_hillaire_kernels.multiple_scattering_coordinates` inverted: h = H x^2, and mu_s =
    c +- (1 -+ c) ((x - x_c) / (1 - x_c or x_c))^2 on either side of x_c = (1 + c) / 2."""
    n_h, n_mu = MULTIPLE_SCATTERING_SIZE
    radii = bottom_radius + (top_radius - bottom_radius) * np.linspace(0.0, 1.0, n_h) ** 2
    x = np.linspace(0.0, 1.0, n_mu)
    c = mu_s_centre
    x_c = 0.5 * (1.0 + c)
    above = c + (1.0 - c) * (np.maximum(x - x_c, 0.0) / (1.0 - x_c)) ** 2
    below = c - (1.0 + c) * (np.maximum(x_c - x, 0.0) / x_c) ** 2
    return radii, np.where(x >= x_c, above, below)


def sky_view_directions(r: float, bottom_radius: float) -> np.ndarray:
    """Local directions (108, 192, 3) of the sky-view table's nodes for an observer at radius
    r [m]: x towards the sun's azimuth, z up (`_hillaire_kernels.sky_view_coordinates` gives
    the mapping: rows from the zenith to the nadir crowded at the horizon, whose zenith angle
    theta_h is that of the geometric horizon, azimuths 0 .. pi from the sun)."""
    n_lat, n_lon = SKY_VIEW_SIZE
    half = n_lat // 2
    theta_h = float(np.arccos(horizon_cos_zenith(r, bottom_radius)))
    above = np.arange(half) / (half - 0.5)
    below = (np.arange(half) + 0.5) / (half - 0.5)
    theta = np.concatenate([theta_h * (1.0 - (1.0 - above) ** 2),
                            theta_h + (np.pi - theta_h) * below**2])
    phi = np.linspace(0.0, np.pi, n_lon)
    sin_theta = np.sin(theta)[:, None]
    return np.stack(np.broadcast_arrays(sin_theta * np.cos(phi), sin_theta * np.sin(phi),
                                        np.cos(theta)[:, None]), axis=-1)


def _sun_frame(origin: np.ndarray, sun: np.ndarray) -> np.ndarray:
    """Rows: the horizontal towards the sun's azimuth, the other horizontal, up, of the
    observer at `origin`; `local @ frame` turns local directions into world ones."""
    up = origin / np.linalg.norm(origin)
    x_axis = horizontal_towards(up, sun)
    return np.ascontiguousarray(np.stack([x_axis, np.cross(up, x_axis), up]))


def _unit(vector: ArrayLike) -> np.ndarray:
    v = np.array(vector, dtype=np.float64).reshape(3)
    return v / np.linalg.norm(v)
