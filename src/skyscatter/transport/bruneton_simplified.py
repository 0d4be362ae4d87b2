"""The simplified Bruneton & Neyret solver: single scattering only, from a transmittance table
and the single-scattering 4-D table, none of the multiple-scattering or sky-irradiance tables.

Model. E. Bruneton, F. Neyret, "Precomputed Atmospheric Scattering", Comput. Graph. Forum
27(4), 2008, doi:10.1111/j.1467-8659.2008.01245.x, with one scattering order: the first two
of its precomputation steps (transmittance T(r, mu); single scattering S_s(r, mu, mu_s, nu)
per scattering constituent, without its phase function) and, at render time, one quadrilinear
lookup per ray,

    L(x, v) = sum_s p_s(nu) S_s(r, mu, mu_s, nu)
              + [ray meets the ground at g] albedo / pi E_sun T_sun(g) max(mu_s(g), 0) T(x, g).

This is the variant of C. F. Pinheiro, "Renderização de atmosferas planetárias em tempo real"
(2014), §5.1 and §6.5, which keeps two of Bruneton's five precomputation programs: the sky
irradiance E, the orders >= 2 (delta J, delta S) and their copies are dropped, and the ground
is lit by the direct sun only. Here the tables are the project's own (`transport/tables.py`,
`precompute_tables(orders=1)`, cached like the "lut" solver's), of which only the
transmittance, the single-scattering slices and the sampled phase functions are kept: the
orders >= 2 slice of the interleaved table and the (empty at one order) irradiance table are
dropped once built (`SimplifiedTables`).

Domain: any atmosphere, observer and sun height the tables cover (the sun down to the tables'
lowest, 120 deg from the zenith); no multiple scattering (the sky too dark by its share: ~20-30 %
at Earth's zenith in the blue by day, most of the twilight sky), no sky light on the ground, and
in twilight the table's interpolation in mu_s across the terminator that the full solver
replaces by a ray march (`_table_lookup_kernels.exact_single_weight`). Accuracy: the lookup
of the single-scattering table, by day within ~0.1 % of the ray march away from the sun's
forward peak (docs/validation.md; tests/transport/test_bruneton_simplified.py).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.transport import _simplified_lookup_kernels, _table_lookup_kernels
from skyscatter.transport.geometry import broadcast_rays
from skyscatter.transport.tables import AtmosphereTables

__all__ = ["BrunetonSimplifiedSolver", "SimplifiedTables"]

CHUNK_RAYS = 1 << 18  # rays per kernel call, so that progress can be reported


class SimplifiedTables(NamedTuple):
    """What the simplified solver keeps of an `AtmosphereTables` of one order.

    transmittance  (n_r_t, n_mu_t, n_wl) float64 [-]
    single         (n_r, n_mu, n_mu_s, n_nu, n_s, n_wl) float32: S_s without phase
                   [W m^-2 nm^-1]
    phase          (n_s, n_angle, n_wl) float64 [sr^-1]
    geometry       (bottom_radius, top_radius, mu_s_min, sun_angle_share, sun radius [rad])
    radius_warp    the scattering table's radius axis
    """

    transmittance: np.ndarray
    single: np.ndarray
    phase: np.ndarray
    geometry: tuple[float, float, float, float, float]
    radius_warp: np.ndarray

    @property
    def nbytes(self) -> int:
        """Bytes of the tables kept."""
        return self.transmittance.nbytes + self.single.nbytes + self.phase.nbytes

    @classmethod
    def from_tables(cls, tables: AtmosphereTables, sun_angular_radius_rad: float
                    ) -> SimplifiedTables:
        """The single-scattering slices (a copy) and the transmittance of `tables`."""
        single = np.ascontiguousarray(
            tables.scattering[..., :len(tables.scattering_constituents), :])
        return cls(np.ascontiguousarray(tables.transmittance), single,
                   np.ascontiguousarray(tables.phase),
                   (float(tables.bottom_radius_m), float(tables.top_radius_m),
                    float(tables.min_cos_sun_zenith), float(tables.sun_angle_share),
                    float(sun_angular_radius_rad)),
                   np.ascontiguousarray(tables.radius_warp))


class BrunetonSimplifiedSolver:
    """Single scattering from the transmittance and single-scattering tables (module
    docstring); `tables` from `SimplifiedTables.from_tables` of one-order tables."""

    name = "bruneton-simplified"

    def __init__(self, profile: OpticalProfile, tables: SimplifiedTables) -> None:
        self.profile = profile
        self.simplified_tables = tables
        self._albedo = np.ascontiguousarray(profile.ground_albedo, dtype=np.float64)
        self._sun = np.ascontiguousarray(profile.toa_irradiance, dtype=np.float64)

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Diffuse spectral radiance [W m^-2 sr^-1 nm^-1], S + (n_wl,) (`Solver.sky_radiance`)."""
        origins, directions, shape = broadcast_rays(position, view_directions)
        sun = np.asarray(sun_direction, dtype=np.float64)
        sun = sun / np.linalg.norm(sun)
        t = self.simplified_tables
        flat = t.single.reshape(-1)
        sizes = tuple(int(n) for n in t.single.shape[:4])
        out = np.empty((directions.shape[0], self.profile.n_wavelengths))
        for start in range(0, directions.shape[0], CHUNK_RAYS):
            stop = min(start + CHUNK_RAYS, directions.shape[0])
            _simplified_lookup_kernels.sky_radiance_rays(
                origins[start:stop], directions[start:stop], sun, t.geometry, flat, sizes,
                t.radius_warp, t.phase, t.transmittance, self._sun, self._albedo,
                out[start:stop])
            if progress is not None:
                progress(stop - start)
        return out.reshape(shape + (self.profile.n_wavelengths,))

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] S + (n_wl,) from the transmittance table (`Solver.transmittance`;
        the lookups of the "lut" solver)."""
        origins, dirs, shape = broadcast_rays(position, directions)
        distances = np.ascontiguousarray(
            np.broadcast_to(np.asarray(distance_m, dtype=np.float64), shape).reshape(-1))
        t = self.simplified_tables
        result = _table_lookup_kernels.transmittance_rays(
            origins, dirs, distances, t.geometry[0], t.geometry[1], t.transmittance)
        return result.reshape(shape + (self.profile.n_wavelengths,))
