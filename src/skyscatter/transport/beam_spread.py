"""The forward peaks' spread of a low sun's beam: delta-M's scaled sun, corrected.

The tables' orders >= 2 are computed in the delta-M scaled medium (`phase_truncation`): light
scattered in a particle's forward peak counts as unscattered, so the sun's beam at a point is
E exp(-tau*), tau* = tau_e - tau_p along the straight line to the sun (tau_p the peak events'
optical depth f beta_s). That is exact only if a few degrees of deflection do not change the
light's way through the air. With the sun a few degrees above the horizon they do: its path
grows as 1 / sin(elevation), so light turned a few degrees down goes through far more air or
into the ground, and light turned up through less. Through Mars's dust (`mars-physical`, peaks
clipped at 15 deg) the light that reaches the lowest kilometres with the sun 83-87 deg from the
zenith is 8-12 % less than the scaled beam, and the tables' sky above the horizon was as much
too bright (docs/validation.md).

This module computes the ratio

    G(h, theta) = (E T_e + light scattered only in peaks, any number of times) / (E T*)

at altitude h and sun zenith angle theta, and the tables multiply their scaled sun by it. The
light scattered only in peaks is solved in the sun's vertical plane: every peak event turns the
light by the peak's angle projected on that plane, K(delta) = integral p_peak(sqrt(delta^2 +
a^2)) da (small angles: the deflection across the plane tilts the path by its square only), and
along a line in a direction delta from the sun's

    F(x, delta) = integral T_e(x, y) beta_p(y) [K * (direct + F)](y, delta) ds,

marched on nodes in (h, theta, delta) and converged by Gauss-Seidel sweeps away from the sun's
axis (`_beam_spread_kernels.sweep`). With the sun high G is 1 to within 1 % (the path hardly
changes with the angle), and without clipped peaks it is 1. Checked against a forward Monte
Carlo of the peaks alone in the spherical atmosphere (`tests/transport/test_beam_spread.py`).
Optically thick layers (a cloud deck, fog, a dust storm) are not corrected: the nodes do not
resolve them (`RESOLVED_DEPTH`). The same error of delta-M for a nearly horizontal line of
sight is corrected by `sight_spread`, where this module's G is trusted.

Public names: `BeamSpread`, `beam_spread`, `projected_peak` (the peak seen edge-on, also used by
`sight_spread`), `ANGLE_FACTOR`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _beam_spread_kernels

__all__ = ["ANGLE_FACTOR", "BeamSpread", "beam_spread", "projected_peak"]

# The resolution below was chosen against the same solver at 64 samples per line, 48
# altitudes and 12 sweeps on `mars-physical` (16 bands, altitudes 0-20 km, sun 75-89 deg from
# the zenith): G within 1.1 % there, 0.06 % median.
# Directions: up to this multiple of the truncation angle from the sun's (several peak events
# add up their angles; 2 gave the same G), in steps of DELTA_STEP_DEG.
ANGLE_FACTOR = 1.4
DELTA_STEP_DEG = 2.0
# Sun zenith angles: every THETA_STEP_DEG where the beam's path changes fast with the angle
# (from LOW_SUN_DEG on), every 10 deg above; the last where the top of the atmosphere still
# sees the sun.
LOW_SUN_DEG = 50.0
THETA_STEP_DEG = 1.0
# Altitudes: HEIGHT_NODES uniform in `_layer_share` (half by altitude, half by the peak
# events' vertical optical depth), so that a thin layer (a cloud deck) gets its own.
HEIGHT_NODES = 32
# Samples along each line (and towards the sun): this many uniform in `_layer_share` on each
# stretch where the altitude rises or falls, and as many denser near the line's start.
MARCH_STEPS = 24
# Sweeps: at most MAX_SWEEPS (3 gave the same G as 12 to 0.1 %), fewer once no G where the
# scaled beam is above 1e-3 of the sun changes by more than TOLERANCE.
MAX_SWEEPS = 4
TOLERANCE = 1e-2
BEAM_FLOOR = 1e-9  # below this share of the sun the scaled beam is left as it is
# Where the solver is trusted: at most this vertical optical depth between two of its
# altitudes (measured: `earth-fog`, 0.44, moved 3-6 % away from DISORT, where the tables were
# within 0.5-1 %; a deck of optical depth 20, 1.3, lost 97 % of a lossless beam at its base;
# the Mars presets have 0.01-0.03, `mars-dust-storm` 0.29); beyond it, or with less than
# MIN_PEAK_COLUMN of peak events in the vertical column (G within about 0.7 % of 1), the
# tables keep delta-M's beam. Along the sun's path up to PEAK_DEPTH_TRUSTED peak events
# (the Monte Carlo of tests/transport/test_beam_spread.py checks it to about 4), G fading to
# 1 at twice that.
RESOLVED_DEPTH = 0.15
MIN_PEAK_COLUMN = 0.01
# G fades to 1 over the last this many degrees before the sun reaches a point's horizon (the
# Monte Carlo checks it to 88 deg from the zenith, not beyond).
HORIZON_FADE_DEG = 2.0
PEAK_DEPTH_TRUSTED = 4.0


@dataclass(frozen=True)
class BeamSpread:
    """G (n_h, n_theta, n_wl) [-] on altitudes `altitudes_m` and sun zenith angles
    `sun_zenith_rad` (module docstring): `beam` for the light a point scatters, `irradiance`
    for the light on a horizontal surface there (each direction's light weighted by its
    cosine)."""

    altitudes_m: np.ndarray
    sun_zenith_rad: np.ndarray
    beam: np.ndarray
    irradiance: np.ndarray

    def beam_at(self, altitude_m: ArrayLike, mu_s: ArrayLike) -> np.ndarray:
        """`beam` at altitudes `altitude_m` [m] and sun zenith cosines `mu_s` (same shape S),
        shape S + (n_wl,), bilinear, clamped to the nodes' ranges."""
        return self._interpolate(self.beam, altitude_m, mu_s)

    def irradiance_at(self, altitude_m: ArrayLike, mu_s: ArrayLike) -> np.ndarray:
        """`irradiance` as `beam_at`."""
        return self._interpolate(self.irradiance, altitude_m, mu_s)

    def _interpolate(self, table: np.ndarray, altitude_m: ArrayLike, mu_s: ArrayLike
                     ) -> np.ndarray:
        h = np.clip(np.asarray(altitude_m, dtype=np.float64), self.altitudes_m[0],
                    self.altitudes_m[-1])
        theta = np.clip(np.arccos(np.clip(mu_s, -1.0, 1.0)), self.sun_zenith_rad[0],
                        self.sun_zenith_rad[-1])
        a, ta = _bracket(h, self.altitudes_m)
        b, tb = _bracket(theta, self.sun_zenith_rad)
        ta, tb = ta[..., None], tb[..., None]
        return ((1.0 - ta) * ((1.0 - tb) * table[a, b] + tb * table[a, b + 1])
                + ta * ((1.0 - tb) * table[a + 1, b] + tb * table[a + 1, b + 1]))


def beam_spread(profile: OpticalProfile, peak_per_density: np.ndarray,
                peak_phase: np.ndarray, truncation_angle_deg: float) -> BeamSpread | None:
    """G of `profile` (module docstring) with peak scattering `peak_per_density` (n_c, n_wl)
    (f beta_s per density of each constituent, 0 where none is clipped) and the normalised
    peak `peak_phase` (n_angle, n_wl) [sr^-1] sampled uniformly over [0, pi] (the clipped
    constituents' peaks mixed); None where it is not trusted (`RESOLVED_DEPTH`: a cloud
    deck, fog, a dust storm) or nothing to correct, which then keep delta-M's beam."""
    bottom, top = profile.bottom_radius_m, profile.top_radius_m
    levels = profile.altitudes_m
    extinction = np.ascontiguousarray(profile.density.T @ profile.extinction_per_density)
    peak = np.ascontiguousarray(profile.density.T @ peak_per_density)
    dz = float(levels[1] - levels[0])
    share = _layer_share(levels, peak)
    altitudes = _altitude_nodes(levels, share, top - bottom)
    column = _vertical_depth(levels, extinction)
    between = np.diff([np.interp(altitudes, levels, column[:, w])
                       for w in range(column.shape[1])], axis=1)
    if (between.max(initial=0.0) > RESOLVED_DEPTH
            or np.trapezoid(peak, levels, axis=0).max() < MIN_PEAK_COLUMN):
        return None
    theta = _sun_zenith_nodes(bottom, top)
    deltas, kernel = _projected_kernel(peak_phase, truncation_angle_deg)
    args = (bottom, top, altitudes, theta)
    rays = (dz, levels, share, MARCH_STEPS)
    depth = _beam_spread_kernels.sun_depths(*args, extinction, column, *rays)
    smooth = np.ascontiguousarray(extinction - peak)
    scaled_depth = _beam_spread_kernels.sun_depths(*args, smooth,
                                                   _vertical_depth(levels, smooth), *rays)
    direct, scaled = np.exp(-depth), np.exp(-scaled_depth)
    # how far the solver is trusted: G fades to 1 as the peak events along the sun's path go
    # from PEAK_DEPTH_TRUSTED to twice that, and as the sun sets (HORIZON_FADE_DEG)
    with np.errstate(invalid="ignore"):  # inf - inf where the ground hides the sun
        peak_depth = np.where(np.isfinite(depth), depth - scaled_depth, np.inf)
    trust = (np.clip(2.0 - peak_depth / PEAK_DEPTH_TRUSTED, 0.0, 1.0)
             * np.clip((np.pi / 2.0 - theta[None, :, None]) / np.radians(HORIZON_FADE_DEG),
                       0.0, 1.0))
    # the solver's own error (the source interpolated between nodes where it falls steeply:
    # +1 % with the sun 86 deg from the zenith, +18 % at 90 deg, for a peak that deflects
    # nothing) divided out: G is the light with the peak over the light without deflection,
    # both marched on the same nodes
    solve = (args, extinction, column, peak, rays, direct, scaled)
    beam, irradiance = _peak_light(*solve, deltas, kernel)
    kept_beam, kept_irradiance = _peak_light(*solve, np.zeros(1),
                                                np.ones((extinction.shape[1], 1, 1)))
    beam = _ratio(beam, kept_beam, scaled > BEAM_FLOOR)
    irradiance = _ratio(irradiance, kept_irradiance,
                        scaled * np.cos(theta)[None, :, None] > BEAM_FLOOR)
    return BeamSpread(altitudes, theta, 1.0 + trust * (beam - 1.0),
                      1.0 + trust * (irradiance - 1.0))


def _peak_light(args: tuple, extinction: np.ndarray, column: np.ndarray, peak: np.ndarray,
                rays: tuple, direct: np.ndarray, scaled: np.ndarray, deltas: np.ndarray,
                kernel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(direct + light scattered only in peaks (n_h, n_theta, n_w), the same on a horizontal
    surface) with directions `deltas` and projected peak `kernel`
    (`_projected_kernel`)."""
    theta = args[3]
    source = np.ascontiguousarray(
        kernel[:, :, deltas.size // 2].T[None, None] * direct[:, :, None, :])
    field = np.zeros(source.shape)
    for _ in range(MAX_SWEEPS):
        change = _beam_spread_kernels.sweep(*args, deltas, extinction, column, peak, *rays,
                                            kernel, direct, scaled, source, field)
        if change < TOLERANCE:
            break
    # on a horizontal surface each direction counts with its cosine (zenith angle theta - delta)
    cosine = np.maximum(np.cos(theta[:, None] - deltas[None, :]), 0.0)  # (n_theta, n_delta)
    mu_s = np.maximum(np.cos(theta), 0.0)[None, :, None]
    return (direct + field.sum(axis=2),
            direct * mu_s + np.einsum("hmdw,md->hmw", field, cosine))


def _ratio(light: np.ndarray, reference: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """light / reference where `kept` (the scaled beam above BEAM_FLOOR), else 1 (the ground
    hides the sun, or too little of it is left to matter)."""
    use = kept & (reference > 0.0)
    return np.ascontiguousarray(np.where(use, light / np.where(use, reference, 1.0), 1.0))


def _vertical_depth(levels: np.ndarray, extinction: np.ndarray) -> np.ndarray:
    """Optical depth from the ground to each level (n_z, n_w), trapezoid (exact: the
    extinction is linear between levels)."""
    steps = 0.5 * (extinction[1:] + extinction[:-1]) * np.diff(levels)[:, None]
    return np.ascontiguousarray(np.concatenate([np.zeros((1, extinction.shape[1])),
                                                np.cumsum(steps, axis=0)]))


def _layer_share(levels: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """On `levels`: the mean of the altitude's share of the atmosphere and the vertical peak
    depth's share of the column (of the wavelength with the most), a coordinate that
    increases with altitude and gives a thin layer of particles (a cloud deck) half of its
    range: where the march and the nodes are placed uniformly."""
    column = peak[:, int(np.argmax(np.trapezoid(peak, levels, axis=0)))]
    depth = np.concatenate([[0.0], np.cumsum(0.5 * (column[1:] + column[:-1])
                                             * np.diff(levels))])
    return 0.5 * levels / levels[-1] + 0.5 * depth / max(depth[-1], np.finfo(float).tiny)


def _altitude_nodes(levels: np.ndarray, share: np.ndarray, height: float) -> np.ndarray:
    """HEIGHT_NODES altitudes from the ground to `height`, uniform in `share` (a deck gets half
    of them, its top one within a sixteenth of its depth of the clear air above, where G is
    1)."""
    u = np.arange(HEIGHT_NODES) / (HEIGHT_NODES - 1)
    nodes = np.interp(u, share, levels)
    nodes[-1] = height
    return np.unique(nodes)


def _sun_zenith_nodes(bottom: float, top: float) -> np.ndarray:
    """0 to LOW_SUN_DEG every 10 deg, then every THETA_STEP_DEG to where the top of the
    atmosphere sees the sun last (90 deg + its horizon's dip), in radians."""
    last = 90.0 + np.degrees(np.arccos(bottom / top))
    low = np.arange(LOW_SUN_DEG, last, THETA_STEP_DEG)
    return np.radians(np.concatenate([np.arange(0.0, LOW_SUN_DEG, 10.0), low, [last]]))


def _projected_kernel(peak_phase: np.ndarray, truncation_angle_deg: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """(deltas (n_d,) [rad], K (n_wl, n_d, n_d)): column j of K the share of light going at
    delta_j that one peak event sends to delta_i, the peak projected on the sun's vertical
    plane (module docstring), each column normalised to 1: an event keeps all light, also
    next to the last node, where the share it would send beyond is spread over the others."""
    half = int(round(ANGLE_FACTOR * truncation_angle_deg / DELTA_STEP_DEG))
    step = np.radians(DELTA_STEP_DEG)
    deltas = step * np.arange(-half, half + 1)
    profile = projected_peak(peak_phase, truncation_angle_deg, step, 2 * half + 1)
    separation = np.abs(np.arange(deltas.size)[:, None] - np.arange(deltas.size)[None, :])
    kernel = profile[:, separation]
    total = kernel.sum(axis=1, keepdims=True)
    return deltas, np.ascontiguousarray(np.where(total > 0.0, kernel / np.where(
        total > 0.0, total, 1.0), 0.0))


def projected_peak(peak_phase: np.ndarray, truncation_angle_deg: float, step_rad: float,
                   n: int) -> np.ndarray:
    """The peak `peak_phase` (n_angle, n_wl) [sr^-1], sampled uniformly over [0, pi] and 0
    beyond `truncation_angle_deg`, projected on a plane through its axis, K(delta) =
    integral p_peak(sqrt(delta^2 + a^2)) da, at delta = 0, step_rad, .. (n - 1) step_rad:
    (n_wl, n), not normalised."""
    n_angle, n_wl = peak_phase.shape
    theta = np.linspace(0.0, np.pi, n_angle)
    # across the plane: to the truncation angle, finer than the peak's samples
    across = np.linspace(0.0, np.radians(truncation_angle_deg), 256)
    angle = np.hypot(step_rad * np.arange(n)[:, None], across[None, :])
    return np.stack([np.trapezoid(np.interp(angle, theta, peak_phase[:, w], right=0.0),
                                  across, axis=1) for w in range(n_wl)])


def _bracket(x: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(i, t): x between nodes[i] and nodes[i + 1], t the fraction (x within the nodes)."""
    i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
    return i, np.clip((x - nodes[i]) / (nodes[i + 1] - nodes[i]), 0.0, 1.0)
