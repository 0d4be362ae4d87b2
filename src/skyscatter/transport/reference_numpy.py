"""Slow, literal numpy twins of the transport kernels, for tests and `validate`.

Uniform steps, no tables, no tricks: every sample point marches its own path to the sun.
Use with few rays only.
"""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile

__all__ = ["optical_depth", "single_scattering_radiance"]


def _segment(origin: np.ndarray, direction: np.ndarray, profile: OpticalProfile
             ) -> tuple[float, float, bool]:
    """(t_start, t_end, hits_ground) of a ray inside the atmosphere, by plain quadratics."""
    b = float(origin @ direction)
    c_top = float(origin @ origin) - profile.top_radius_m**2
    disc_top = b * b - c_top
    if disc_top < 0.0:
        return 0.0, 0.0, False
    t_start = max(0.0, -b - np.sqrt(disc_top))
    t_end = -b + np.sqrt(disc_top)
    disc_ground = b * b - (float(origin @ origin) - profile.bottom_radius_m**2)
    if disc_ground >= 0.0 and b < 0.0:
        # Near root; >= 0 for an origin on or above the ground (clamp its rounding error).
        return t_start, max(t_start, min(t_end, -b - np.sqrt(disc_ground))), True
    return t_start, max(t_end, t_start), False


def _extinction(points: np.ndarray, profile: OpticalProfile) -> np.ndarray:
    altitude = np.linalg.norm(points, axis=-1) - profile.bottom_radius_m
    return profile.extinction_at(altitude)


def optical_depth(origin: np.ndarray, direction: np.ndarray, distance_m: float,
                  profile: OpticalProfile, n_steps: int = 20000) -> np.ndarray:
    """Optical depth (n_wl,) along a straight path of `distance_m` (trapezoid, uniform)."""
    t = np.linspace(0.0, distance_m, n_steps + 1)
    extinction = _extinction(origin + t[:, None] * direction, profile)
    return np.trapezoid(extinction, t, axis=0)


def single_scattering_radiance(origin: np.ndarray, direction: np.ndarray,
                               sun_direction: np.ndarray, profile: OpticalProfile, *,
                               n_steps: int = 2000, n_sun_steps: int = 2000) -> np.ndarray:
    """Single-scattered + once-reflected radiance (n_wl,) for one ray and a point sun."""
    origin = np.asarray(origin, dtype=np.float64)
    direction = np.asarray(direction, dtype=np.float64)
    sun = np.asarray(sun_direction, dtype=np.float64)
    t_start, t_end, hits_ground = _segment(origin, direction, profile)
    n_wl = profile.n_wavelengths
    if t_end <= t_start and not hits_ground:
        return np.zeros(n_wl)
    t = np.linspace(t_start, t_end, n_steps + 1)
    points = origin + t[:, None] * direction
    extinction = _extinction(points, profile)
    tau_view = np.concatenate([np.zeros((1, n_wl)), np.cumsum(
        0.5 * (extinction[1:] + extinction[:-1]) * np.diff(t)[:, None], axis=0)])
    sun_transmittance = np.array([_sun_transmittance(p, sun, profile, n_sun_steps)
                                  for p in points])
    altitude = np.linalg.norm(points, axis=-1) - profile.bottom_radius_m
    nu = float(direction @ sun)
    radiance = np.zeros(n_wl)
    for c, phase in enumerate(profile.phases):
        if phase is None:
            continue
        density = np.interp(altitude, profile.altitudes_m, profile.density[c], right=0.0)
        integrand = density[:, None] * np.exp(-tau_view) * sun_transmittance
        radiance += (np.trapezoid(integrand, t, axis=0) * profile.scattering_per_density[c]
                     * phase.evaluate(nu, profile.wavelengths_nm))
    if hits_ground:
        ground = points[-1]
        mu_s = max(float(ground @ sun) / np.linalg.norm(ground), 0.0)
        radiance += (profile.ground_albedo / np.pi * np.exp(-tau_view[-1])
                     * _sun_transmittance(ground, sun, profile, n_sun_steps) * mu_s)
    return radiance * profile.toa_irradiance


def _sun_transmittance(point: np.ndarray, sun: np.ndarray, profile: OpticalProfile,
                       n_steps: int) -> np.ndarray:
    """Transmittance to the top towards a point sun; zero when the ground is in the way."""
    t_start, t_end, hits_ground = _segment(point * (1.0 + 1e-12), sun, profile)
    if hits_ground:
        return np.zeros(profile.n_wavelengths)
    return np.exp(-optical_depth(point, sun, t_end, profile, n_steps))
