"""Schüler's solver: single scattering with closed-form transmittances, no precomputation.

Model. C. Schüler, "An Approximation to the Chapman Grazing-Incidence Function for
Atmospheric Scattering", GPU Pro 3 (ed. W. Engel), CRC Press 2012, pp. 105-118: every
transmittance (observer to sample, sample to sun, observer to the end of the ray) comes from
the column densities of Schüler's approximation of the Chapman function
(`transport/chapman.py`), each constituent of the profile fitted to an exponential (or, for
a layer such as ozone, a thin absorbing shell at its centroid), and single scattering is
marched along the view ray as in the "single" solver (Nishita et al. 1993):

L(x, v) = E_sun [ sum_c p_c(nu) beta_s,c int T(x, p) n_c(p) T_sun(p) ds
                  + albedo / pi T(x, g) T_sun(g) max(mu_s(g), 0) ]

with n_c the profile's own density at the sample (the fit serves the transmittances only).
Samples per view ray: `n_samples` (16 in Schüler's shader), dense at the ray's lowest point
and at the observer (`_table_common_kernels.table_ray_distances`). The sun disk's own radiance
is not included. Kernels: `transport/_schuler_kernels.py`.

Domain: any planet, any observer (in space too), any sun height (the planet's shadow by the
geometric horizon, no refraction); one scattering order only, so the sky is too dark where
multiple scattering matters (about 20-30 % at the zenith of Earth's clear day in the blue,
most of the twilight sky).

Accuracy, against the ray-marched "single" solver on an exponential atmosphere
(tests/transport/test_schuler.py): the Chapman approximation's column error (-2.4 % at 60 deg,
-14 % near 88 deg from the zenith) makes the low sun's light too strong and the horizon too
bright; measured per view and sun in the test.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _schuler_kernels
from skyscatter.transport.chapman import fit_constituents
from skyscatter.transport.geometry import broadcast_rays

__all__ = ["SchulerSolver"]

CHUNK_RAYS = 16384  # rays per kernel call: bounds memory (n_c x n_wl doubles per ray)


class SchulerSolver:
    """Single scattering with the transmittances of Schüler's Chapman approximation (module
    docstring); `n_samples` samples per view ray."""

    name = "schuler"

    def __init__(self, profile: OpticalProfile, n_samples: int = 16) -> None:
        self.profile = profile
        self.n_samples = max(int(n_samples), 2)
        self.model = fit_constituents(profile)
        self._h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
        self._density = np.ascontiguousarray(profile.density, dtype=np.float64)
        self._extinction = np.ascontiguousarray(profile.extinction_per_density,
                                                dtype=np.float64)

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1], S + (n_wl,) (`Solver.sky_radiance`)."""
        p = self.profile
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = np.asarray(sun_direction, dtype=np.float64)
        sun = sun / np.linalg.norm(sun)
        radiance = np.empty((directions.shape[0], p.n_wavelengths))
        for start in range(0, directions.shape[0], CHUNK_RAYS):
            stop = min(start + CHUNK_RAYS, directions.shape[0])
            inscatter, _, ground = _schuler_kernels.single_scattering(
                origins[start:stop], directions[start:stop], sun, self.n_samples, p.bottom_radius_m,
                p.top_radius_m, self._h_step, self._density, self._extinction,
                float(p.sun_angular_radius_rad), tuple(self.model))
            nu = directions[start:stop] @ sun
            chunk = ground * (p.ground_albedo / np.pi)
            for c, phase in enumerate(p.phases):
                if phase is not None:
                    chunk += (phase.evaluate(nu, p.wavelengths_nm)
                              * p.scattering_per_density[c] * inscatter[:, c, :])
            radiance[start:stop] = chunk * p.toa_irradiance
            if progress is not None:
                progress(stop - start)
        return radiance.reshape(shape + (p.n_wavelengths,))

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] S + (n_wl,) from the closed-form columns (`Solver.transmittance`)."""
        origins, dirs, shape = broadcast_rays(position, directions)
        distances = np.broadcast_to(np.asarray(distance_m, dtype=np.float64), shape).ravel()
        p = self.profile
        result = _schuler_kernels.transmittance_rays(
            origins, dirs, np.ascontiguousarray(distances), p.bottom_radius_m, p.top_radius_m,
            self._extinction, tuple(self.model))
        return result.reshape(shape + (p.n_wavelengths,))
