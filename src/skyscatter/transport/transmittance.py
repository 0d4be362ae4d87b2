"""Transmittance along rays, ray marched through the profile without any table.

T = exp(-sum_c beta_e,c N_c) with N_c the column density of constituent c between the ray's
start and its end [density x m], integrated with the trapezoid rule on samples dense at
the segment's lowest point (`_kernels.transmittance_rays`, `_kernels.columns_along_segment`;
docs/physics/single_scattering.md). It is the transmittance of the solvers that keep no table:
the single-scattering solver and the Monte Carlo reference, which share it from this module so
that the reference imports nothing of the solvers it checks.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _kernels
from skyscatter.transport.geometry import broadcast_rays

__all__ = ["ray_marched_transmittance"]


def ray_marched_transmittance(profile: OpticalProfile, position: ArrayLike,
                              directions: ArrayLike, distance_m: ArrayLike = np.inf,
                              n_samples: int = 256) -> np.ndarray:
    """Transmittance [-] (..., n_wl) of `profile` from `position` along `directions` over
    `distance_m` [m] (inf: out of the atmosphere, towards a light source; 0 when the ground
    blocks the path): trapezoid columns with `n_samples` intervals
    (`_kernels.transmittance_rays`)."""
    origins, dirs, shape = broadcast_rays(position, directions)
    distances = np.broadcast_to(np.asarray(distance_m, dtype=np.float64), shape).ravel()
    h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
    result = _kernels.transmittance_rays(
        origins, dirs, np.ascontiguousarray(distances), n_samples, profile.bottom_radius_m,
        profile.top_radius_m, h_step, np.ascontiguousarray(profile.density, dtype=np.float64),
        np.ascontiguousarray(profile.extinction_per_density, dtype=np.float64))
    return result.reshape(shape + (profile.n_wavelengths,))
