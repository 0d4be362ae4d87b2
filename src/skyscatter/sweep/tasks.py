"""What the workers of a sweep run: build one atmosphere's solver, compute one chunk from it.

Plain functions of picklable arguments (Dask ships them to worker processes, which may be on
other machines). `build_solver` is the expensive, once-per-atmosphere part (with the "lut"
solver: the precomputed tables, from the table cache where the worker can see one);
`compute_chunk` the per-chunk part, `render.radiance_grid` on one sun zenith.

Public names: `build_solver`, `compute_chunk`.
"""

from __future__ import annotations

import numpy as np

from skyscatter.render.radiance_grid import sky_radiance_grid, surface_irradiance_grid
from skyscatter.sweep.plan import SweepPlan
from skyscatter.transport.solvers import Solver, SurfaceSolver, make_solver

__all__ = ["build_solver", "compute_chunk"]


def build_solver(plan: SweepPlan, atmosphere: int) -> Solver:
    """The solver of atmosphere `atmosphere` of `plan` on its monochromatic wavelengths."""
    model = plan.atmosphere(atmosphere)
    profile = model.optical_profile(np.asarray(plan.wavelengths_nm), monochromatic=True)
    return make_solver(plan.solver, profile, plan.solver_options(model))


def compute_chunk(engine: Solver, plan: SweepPlan, chunk: int) -> dict[str, np.ndarray]:
    """The arrays of chunk `chunk` (one atmosphere at one sun zenith) from its solver:
    radiance (n_view, n_azimuth, n_wl) [W m^-2 sr^-1 nm^-1], toa_irradiance (n_wl,)
    [W m^-2 nm^-1]; standard_error (as radiance) from a Monte Carlo solver; direct_normal,
    diffuse_horizontal, global_horizontal (n_wl,) [W m^-2 nm^-1] and direct_transmittance
    (n_wl,) [-] from a solver that lights surfaces. In a sweep over times the radiance and
    the irradiances on surfaces are those of the star at the time's distance
    (`Star.irradiance_scale_at`); toa_irradiance stays the config's (the dataset's
    sun_distance(time) gives the scale)."""
    atmosphere, index = plan.chunk(chunk)
    sun = [plan.sun_zeniths_deg[index]]
    scale = 1.0
    if plan.sun_distances_m:
        star = plan.atmosphere(atmosphere).planet.star
        scale = star.irradiance_scale_at(plan.sun_distances_m[index])
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
