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
changes fastest near the horizon; F is read from the finished tables as the orders read their
incoming radiance (`_table_build_kernels.incoming_radiance`) on the scattering-density grid
with a 1 deg view zenith axis, and the integral is one more pass of the orders' ray integral
(`_table_build_kernels.multiple_scattering_table`) with beta_p as the scattering
coefficient, added to M. Measured against the Monte Carlo in docs/validation.md.

Public names: `sight_spread_source`, `view_zenith_angles`.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import correlate1d

from skyscatter.transport.beam_spread import ANGLE_FACTOR, projected_peak

__all__ = ["SIGHT_THETA", "sight_spread_source", "view_zenith_angles"]

# View zenith angles of the source over [0, pi], both ends included: 1 deg apart, the blur's
# step (the field near the horizon changes by tens of percent within a few degrees).
SIGHT_THETA = 181
# The blur across the view's plane (`_across`) holds sin(view zenith) at its value this far from
# the zenith and the nadir.
ACROSS_MIN_DEG = 10.0


def sight_spread_source(field: np.ndarray, n_mu_s: int, n_phi: int,
                        blur: tuple[np.ndarray, float]) -> np.ndarray:
    """K * F - F (module docstring) for `multiple_scattering_table`: (n_r, SIGHT_THETA,
    n_mu_s * n_phi * n_wl) float32, from the field F (n_wl, SIGHT_THETA * n_phi, n_r * n_mu_s)
    (`incoming_radiance`'s layout) on the scattering-density nodes, view zenith angles
    `view_zenith_angles()` and n_phi azimuths from the sun's regular over [0, pi]. `blur`:
    (the normalised peak (n_angle, n_wl) [sr^-1] sampled uniformly over [0, pi], its
    truncation angle [deg])."""
    n_wl = field.shape[0]
    theta = view_zenith_angles()
    values = field.reshape(n_wl, theta.size, n_phi, -1, n_mu_s).transpose(3, 4, 1, 2, 0)
    kernel = _vertical_kernel(*blur)
    spread = _mean_square_angle(blur[0])
    source = np.empty((values.shape[0], theta.size, n_mu_s * n_phi * n_wl), dtype=np.float32)
    for i, node in enumerate(values):  # (n_mu_s, n_theta, n_phi, n_wl) of one radius
        node = node.astype(np.float64)
        change = _blur_zenith(node, kernel) - node + _across(node, theta, spread)
        source[i] = change.transpose(1, 0, 2, 3).reshape(theta.size, -1)
    return source


def view_zenith_angles() -> np.ndarray:
    """The source's view zenith angles [rad]: SIGHT_THETA regular over [0, pi]."""
    return np.linspace(0.0, np.pi, SIGHT_THETA)


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
