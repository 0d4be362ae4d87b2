"""The forward peaks' spread of lines of sight: delta-M's undeflected view rays, corrected.

The tables carry the orders >= 2 to the eye through the scaled transmittance exp(-tau*),
tau* = tau_e - tau_p (`phase_truncation`): light scattered in a particle's forward peak on its
way counts as if it kept its direction. That is the error `beam_spread` corrects in a low
sun's beam, here along the line of sight: a view a few degrees above the horizon crosses the
dust as such a beam does, and a peak event a few degrees down or up brings it the light of a
lower or higher view, which near the horizon differs most (the ground below, the bright
horizon, the darker sky above). To first order in the peak events (the perturbation of the
delta-M equation by the peak's true shape),

    L = L* + integral_0^d T*(x, p) beta_p(p) [K * F - F](p, v) dt,

F the radiance field that the peaks deflect and K * F its blur by one peak event. F is the
tables' orders >= 2 (with the first order's scaled-medium difference, which holds the light
scattered once and carried on through peaks) and the ground; the light of the first order
itself is exact in the tables, and what the peaks make of it near the sun is in the aureole's
closed forms (`aureole`), so neither is blurred again. The blur is taken in the view's
vertical plane, the peak projected on it (`beam_spread.projected_peak`), where the field
changes fastest near the horizon; it is looked up in the finished tables
(`_table_lookup_kernels.sky_radiance_rays`) on the scattering-density grid with a 1 deg view
zenith axis, and the integral is one more pass of the orders' ray integral
(`_table_build_kernels.multiple_scattering_table`) with beta_p as the scattering
coefficient, added to M. Measured against the Monte Carlo in docs/validation.md.

Public names: `sight_spread_source`.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import correlate1d

from skyscatter.transport import _table_lookup_kernels
from skyscatter.transport.beam_spread import ANGLE_FACTOR, projected_peak

__all__ = ["SIGHT_THETA", "sight_spread_source"]

# View zenith angles of the source over [0, pi], both ends included: 1 deg apart, the blur's
# step (the field near the horizon changes by tens of percent within a few degrees).
SIGHT_THETA = 181
# The blur across the view's plane (`_across`) holds sin(view zenith) at its value this far from
# the zenith and the nadir.
ACROSS_MIN_DEG = 10.0


def sight_spread_source(lookup: _table_lookup_kernels.LookupTables, albedo: np.ndarray,
                        radii: np.ndarray, mu_s: np.ndarray, blur: tuple[np.ndarray, float],
                        n_phi: int) -> np.ndarray:
    """K * F - F (module docstring) for `multiple_scattering_table`: (n_r, SIGHT_THETA,
    n_mu_s * n_phi * n_wl) float32 on the radii `radii` [m] and sun zenith cosines `mu_s` of
    its nodes, view zenith angles regular over [0, pi] and n_phi azimuths from the sun's
    regular over [0, pi]. `lookup`: the finished tables; `albedo` (n_wl,) the ground's;
    `blur`: (the normalised peak (n_angle, n_wl) [sr^-1] sampled uniformly over [0, pi],
    its truncation angle [deg])."""
    kernel = _vertical_kernel(*blur)
    spread = _mean_square_angle(blur[0])
    field_tables = _orders_and_ground(lookup)
    theta = np.linspace(0.0, np.pi, SIGHT_THETA)
    phi = np.linspace(0.0, np.pi, n_phi)
    origins, directions = _node_rays(mu_s, theta, phi)
    n_wl = albedo.size
    source = np.empty((radii.size, theta.size, mu_s.size * n_phi * n_wl), dtype=np.float32)
    empty_view = np.zeros((0, 2, 0, n_wl))
    empty_aureole = np.zeros((0, 0, 2, n_wl))
    sun = np.array([0.0, 0.0, 1.0])
    field = np.empty((directions.shape[0], n_wl))
    for i, r in enumerate(radii):
        _table_lookup_kernels.sky_radiance_rays(origins * r, directions, sun, field_tables,
                                                albedo, empty_view, empty_aureole, field)
        values = field.reshape(mu_s.size, theta.size, n_phi, n_wl)
        change = _blur_zenith(values, kernel) - values + _across(values, theta, spread)
        source[i] = change.transpose(1, 0, 2, 3).reshape(theta.size, -1)
    return source


def _vertical_kernel(peak_phase: np.ndarray, truncation_angle_deg: float) -> np.ndarray:
    """The peak projected on a vertical plane at the source's zenith steps, -n .. n steps
    (n_wl, 2 n + 1), each wavelength's weights summing to 1."""
    step = np.pi / (SIGHT_THETA - 1)
    half = int(np.ceil(ANGLE_FACTOR * np.radians(truncation_angle_deg) / step))
    side = projected_peak(peak_phase, truncation_angle_deg, step, half + 1)
    kernel = np.concatenate([side[:, :0:-1], side], axis=1)
    return kernel / kernel.sum(axis=1, keepdims=True)


def _mean_square_angle(peak_phase: np.ndarray) -> np.ndarray:
    """<theta^2> [rad^2] of the normalised peak (n_angle, n_wl) sampled uniformly over
    [0, pi]: (n_wl,)."""
    theta = np.linspace(0.0, np.pi, peak_phase.shape[0])
    return np.trapezoid(2.0 * np.pi * np.sin(theta)[:, None] * theta[:, None] ** 2 * peak_phase,
                        theta, axis=0)


def _across(values: np.ndarray, theta: np.ndarray, mean_square: np.ndarray) -> np.ndarray:
    """The blur across the view's vertical plane, in the small-angle (diffusion) limit:
    <theta^2> / 4 (cot theta dF/dtheta + d^2F/dphi^2 / sin^2 theta), the part of the sphere's
    Laplacian that a deflection perpendicular to the plane sees (half of the peak's mean
    square angle lies across it), for `values` as `_blur_zenith`'s. Within ACROSS_MIN_DEG of
    the zenith and the nadir, where the azimuth's nodes are far apart for the peak, sin theta
    is held at its value there."""
    n_phi = values.shape[2]
    d_phi = np.pi / (n_phi - 1)
    padded = np.concatenate([values[:, :, 1:2], values, values[:, :, -2:-1]], axis=2)
    second = (padded[:, :, 2:] - 2.0 * values + padded[:, :, :-2]) / d_phi**2
    slope = np.gradient(values, theta, axis=1)
    sine = np.maximum(np.sin(theta), np.sin(np.radians(ACROSS_MIN_DEG)))[None, :, None, None]
    cosine = np.cos(theta)[None, :, None, None]
    return mean_square / 4.0 * (cosine / sine * slope + second / sine**2)


def _orders_and_ground(lookup: _table_lookup_kernels.LookupTables
                       ) -> _table_lookup_kernels.LookupTables:
    """`lookup` with the orders >= 2 as its only table, no constituent of its own (no first
    order, looked up or marched) and no aureole: its lookups are F, the orders >= 2 and the
    ground."""
    n_s = lookup.scatterers.size
    n_wl = lookup.single_factor.shape[1]
    orders = np.ascontiguousarray(lookup.scattering.reshape(-1, n_s + 1, n_wl)[:, n_s])
    return lookup._replace(
        scattering=orders.reshape(-1), phase_table=lookup.phase_table[:0],
        scatterers=lookup.scatterers[:0], single_factor=lookup.single_factor[:0],
        aureole_psi_max=0.0)


def _node_rays(mu_s: np.ndarray, theta: np.ndarray, phi: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """(origins on the unit sphere, view directions), each (n_mu_s * n_theta * n_phi, 3) in
    that order, with the sun along +z: at an origin the sun is arccos(mu_s) from the zenith,
    and the view theta from the zenith and phi in azimuth from the sun's."""
    sun_zenith = np.arccos(np.clip(mu_s, -1.0, 1.0))
    up = np.stack([np.sin(sun_zenith), np.zeros_like(mu_s), np.cos(sun_zenith)], axis=1)
    # towards the sun along the ground (the sun at the zenith: any azimuth will do)
    towards = np.stack([-np.cos(sun_zenith), np.zeros_like(mu_s), np.sin(sun_zenith)], axis=1)
    across = np.array([0.0, 1.0, 0.0])
    s, c = np.sin(theta)[None, :, None, None], np.cos(theta)[None, :, None, None]
    directions = (c * up[:, None, None, :] + s * (
        np.cos(phi)[None, None, :, None] * towards[:, None, None, :]
        + np.sin(phi)[None, None, :, None] * across))
    origins = np.broadcast_to(up[:, None, None, :], directions.shape)
    return (np.ascontiguousarray(origins.reshape(-1, 3)),
            np.ascontiguousarray(directions.reshape(-1, 3)))


def _blur_zenith(values: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """`values` (n_mu_s, n_theta, n_phi, n_wl) on view zenith angles regular over [0, pi] and
    azimuths regular over [0, pi], blurred along the zenith angle by `kernel` (n_wl, 2 n + 1):
    past the zenith or the nadir a view continues on the other side, the azimuth phi
    becoming pi - phi."""
    n = kernel.shape[1] // 2
    mirrored = values[:, :, ::-1]
    extended = np.concatenate([mirrored[:, n:0:-1], values, mirrored[:, -2:-n - 2:-1]], axis=1)
    n_theta = values.shape[1]
    out = np.empty_like(values)
    for w in range(values.shape[3]):
        out[..., w] = correlate1d(extended[..., w], kernel[w], axis=1)[:, n:n + n_theta]
    return out
