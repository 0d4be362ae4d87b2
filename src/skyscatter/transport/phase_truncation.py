"""Forward-peak truncation of sampled phase functions, for the orders >= 2 of the tables.

A particle's phase function p is split at a truncation angle theta_c into a smooth part and a
forward peak: p = (1 - f) p* + f p_peak, where p* equals p beyond theta_c and is held at
p(theta_c) inside it (normalised to 1), and f, the peak fraction, is the share of scattered
light in the clipped peak. The orders >= 2 are then computed as if the peak did not deflect light
at all: the delta approximation of Potter (1970, J. Atmos. Sci. 27, 943,
doi:10.1175/1520-0469(1970)027<0943:TDFAIR>2.0.CO;2) with the scaling of delta-M (Wiscombe
1977, J. Atmos. Sci. 34, 1408, doi:10.1175/1520-0469(1977)034<1408:TDMRYA>2.0.CO;2):
scattering beta_s* = (1 - f) beta_s and extinction beta_e* = beta_e - f beta_s, phase p*. What
the peak does to the first order is kept exactly by the tables' single scattering, which uses p
itself (the TMS correction of Nakajima & Tanaka 1988, J. Quant. Spectrosc. Radiat. Transfer 40,
51, doi:10.1016/0022-4073(88)90031-3). The quadrature of the orders >= 2 (a few degrees) then
resolves p*, where it cannot resolve a peak of a degree or two.

Public names: `truncate_forward_peak`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MIN_PEAK_FRACTION", "truncate_forward_peak"]

# Peaks that hold less than this share of the scattered light are left alone: nothing to gain,
# and molecules stay exactly as they were (Rayleigh's 1 + cos^2 loses 5e-5 to a 10 deg clip).
MIN_PEAK_FRACTION = 1e-3


def truncate_forward_peak(phase: np.ndarray, truncation_angle_deg: float, *,
                          min_fraction: float = MIN_PEAK_FRACTION
                          ) -> tuple[np.ndarray, np.ndarray]:
    """(p* (n_s, n_angle, n_wl) [sr^-1], f (n_s, n_wl) [-]) of phase functions `phase` sampled
    at angles uniform over [0, pi] (`scatterers.sample_phase_functions`), clipped at
    `truncation_angle_deg` (module docstring). p* is normalised as p is on the samples
    (trapezoid rule in the angle); where the clip would remove less than `min_fraction`
    (e.g. Rayleigh scattering, or an angle of 0) f = 0 and p* = p."""
    n_angle = phase.shape[1]
    theta = np.linspace(0.0, np.pi, n_angle)
    inside = theta < np.radians(truncation_angle_deg)
    clipped = phase.copy()
    if np.any(inside):
        edge = int(np.count_nonzero(inside))
        clipped[:, :edge] = np.minimum(phase[:, :edge], phase[:, edge:edge + 1])
    weight = 2.0 * np.pi * np.sin(theta)
    kept = np.trapezoid(clipped * weight[None, :, None], theta, axis=1)
    total = np.trapezoid(phase * weight[None, :, None], theta, axis=1)
    fraction = np.clip(1.0 - kept / total, 0.0, 1.0)
    changed = fraction >= min_fraction
    smooth = np.where(changed[:, None, :], clipped * (total / kept)[:, None, :], phase)
    return smooth, np.where(changed, fraction, 0.0)
