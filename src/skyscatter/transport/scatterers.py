"""The constituents of an `OpticalProfile` that scatter light, and their phase functions
sampled in scattering angle for the kernels: what the table precomputation
(`transport/tables.py`) and the Monte Carlo reference (`transport/monte_carlo.py`) both start
from, in a module of neither, so that the reference stays independent of the tables.
"""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile

__all__ = ["sample_phase_functions", "scattering_constituents"]


def scattering_constituents(profile: OpticalProfile) -> tuple[int, ...]:
    """Indices of the constituents that scatter (a phase function and a nonzero scattering
    cross-section at some wavelength)."""
    return tuple(c for c, phase in enumerate(profile.phases)
                 if phase is not None and np.any(profile.scattering_per_density[c] > 0.0))


def sample_phase_functions(profile: OpticalProfile, constituents: tuple[int, ...],
                           n_angle: int, wavelengths_nm: np.ndarray | None = None) -> np.ndarray:
    """p_c at scattering angles theta_i = pi i / (n_angle - 1) for each constituent in
    `constituents`, shape (n_s, n_angle, n_wl) [sr^-1] (linear interpolation in theta between
    samples is what the kernels do)."""
    wl = profile.wavelengths_nm if wavelengths_nm is None else wavelengths_nm
    nu = np.cos(np.linspace(0.0, np.pi, n_angle))
    table = np.empty((len(constituents), n_angle, wl.size))
    for s, c in enumerate(constituents):
        table[s] = profile.phases[c].evaluate(nu, wl)
    return table
