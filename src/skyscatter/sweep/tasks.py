"""What the workers of a sweep run: build one atmosphere's solver, compute one chunk from it.

Plain functions of picklable arguments (Dask ships them to worker processes, which may be on
other machines). `build_solver` is the expensive, once-per-atmosphere part (with the "lut"
solver: the precomputed tables, from the table cache where the worker can see one);
`compute_chunk` the per-chunk part, `render.radiance_grid` on one sun zenith.

Public names: `AtmosphereSolver`, `build_solver`, `compute_chunk`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.render.radiance_grid import sky_radiance_grid, surface_irradiance_grid
from skyscatter.spectrum.star import Star
from skyscatter.sweep.plan import SweepPlan
from skyscatter.transport.solvers import Solver, SurfaceSolver, make_solver

__all__ = ["AtmosphereSolver", "build_solver", "compute_chunk"]


@dataclass(frozen=True)
class AtmosphereSolver:
    """What `build_solver` makes for one atmosphere: its `solver` and its `star` (at the
    config's distance: a sweep over times scales the light to each time's distance)."""

    solver: Solver
    star: Star


def build_solver(plan: SweepPlan, atmosphere: int) -> AtmosphereSolver:
    """The solver of atmosphere `atmosphere` of `plan` on its monochromatic wavelengths."""
    model = plan.atmosphere(atmosphere)
    profile = model.optical_profile(np.asarray(plan.wavelengths_nm), monochromatic=True)
    return AtmosphereSolver(make_solver(plan.solver, profile, plan.solver_options(model)),
                            model.planet.star)


def compute_chunk(built: AtmosphereSolver, plan: SweepPlan, chunk: int
                  ) -> dict[str, np.ndarray]:
    """The arrays of chunk `chunk` (one atmosphere at one sun zenith) from its solver:
    radiance (n_view, n_azimuth, n_wl) [W m^-2 sr^-1 nm^-1], toa_irradiance (n_wl,)
    [W m^-2 nm^-1]; standard_error (as radiance) from a Monte Carlo solver; direct_normal,
    diffuse_horizontal, global_horizontal (n_wl,) [W m^-2 nm^-1] and direct_transmittance
    (n_wl,) [-] from a solver that lights surfaces. In a sweep over times the radiance and
    the irradiances on surfaces are those of the star at the time's distance
    (`Star.irradiance_scale_at`); toa_irradiance stays the config's (the dataset's
    sun_distance(time) gives the scale)."""
    engine = built.solver
    index = plan.chunk(chunk)[1]
    sun = [plan.sun_zeniths_deg[index]]
    scale = (built.star.irradiance_scale_at(plan.sun_distances_m[index])
             if plan.sun_distances_m else 1.0)
    radiance, error = sky_radiance_grid(engine, plan.altitude_m, sun, plan.view_zeniths_deg,
                                        plan.relative_azimuths_deg)
    toa = np.asarray(engine.profile.toa_irradiance, dtype=np.float64)
    arrays = {"radiance": scale * radiance[0], "toa_irradiance": toa}
    if error is not None:
        arrays["standard_error"] = scale * error[0]
    if isinstance(engine, SurfaceSolver):
        direct_normal, diffuse, global_ = surface_irradiance_grid(engine, plan.altitude_m, sun)
        arrays.update(direct_normal=scale * direct_normal[0], diffuse_horizontal=scale * diffuse[0],
                      global_horizontal=scale * global_[0],
                      direct_transmittance=direct_normal[0] / toa)
    return {name: np.asarray(value, dtype=np.float64) for name, value in arrays.items()}
