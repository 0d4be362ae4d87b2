"""Sky radiance and surface irradiance of one solver on a grid of geometries, as arrays.

The one computation behind `api.sky_radiance_rows`, `api.irradiance_rows` and the chunks of a
sweep (`sweep`): an observer `altitude_m` above the ground, the sun at each zenith angle in the
azimuth 0 (the sky is the same at every azimuth: density depends on altitude only), views at
every (view zenith, azimuth relative to the sun) pair. Angles in degrees, as the API and the
command line give them.

Public names: `sky_radiance_and_error`, `sky_radiance_grid`, `surface_irradiance_grid`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skyscatter.render.scene import sun_direction
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position
from skyscatter.transport.solvers import NoisySolver, Solver, SurfaceSolver

__all__ = ["sky_radiance_and_error", "sky_radiance_grid", "surface_irradiance_grid"]


def sky_radiance_and_error(engine: Solver, position: np.ndarray, directions: np.ndarray,
                           sun: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Diffuse sky radiance [W m^-2 sr^-1 nm^-1] at `directions` (..., 3) seen from `position`,
    shape (..., n_wl), and its standard error for a `NoisySolver` (Monte Carlo), else None."""
    if isinstance(engine, NoisySolver):
        return engine.sky_radiance_with_error(position, directions, sun)
    return engine.sky_radiance(position, directions, sun), None


def sky_radiance_grid(engine: Solver, altitude_m: float, sun_zeniths_deg: Sequence[float],
                      view_zeniths_deg: Sequence[float], relative_azimuths_deg: Sequence[float]
                      ) -> tuple[np.ndarray, np.ndarray | None]:
    """Diffuse sky radiance [W m^-2 sr^-1 nm^-1], shape (n_sun, n_view, n_azimuth, n_wl), and
    its standard error (same shape) for a `NoisySolver` (Monte Carlo), else None. Relative
    azimuth 0 looks towards the sun."""
    position = observer_position(altitude_m, engine.profile.bottom_radius_m)
    view_zenith, azimuth = np.meshgrid(np.radians(view_zeniths_deg),
                                       np.radians(relative_azimuths_deg), indexing="ij")
    directions = local_frame_directions(view_zenith, azimuth)
    radiances, errors = [], []
    for sun_zenith in sun_zeniths_deg:
        radiance, error = sky_radiance_and_error(engine, position, directions,
                                                 sun_direction(sun_zenith, 0.0))
        radiances.append(radiance)
        if error is not None:
            errors.append(error)
    return np.stack(radiances), (np.stack(errors) if errors else None)


def surface_irradiance_grid(engine: SurfaceSolver, altitude_m: float,
                            sun_zeniths_deg: Sequence[float]
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(direct_normal, diffuse_horizontal, global_horizontal) spectral irradiance
    [W m^-2 nm^-1], each of shape (n_sun, n_wl): the sun's direct light on a surface facing it
    (its hidden part left out; 0 with the sun below the horizon), the sky's light on a
    horizontal surface, and their sum on the horizontal (direct_normal cos(sun zenith) +
    diffuse_horizontal)."""
    position = observer_position(altitude_m, engine.profile.bottom_radius_m)
    direct_normals, diffuses, globals_ = [], [], []
    for sun_zenith in sun_zeniths_deg:
        mu = float(np.cos(np.radians(sun_zenith)))
        direct, diffuse = engine.ground_irradiance(position, sun_direction(sun_zenith, 0.0))
        direct_normals.append(direct / mu if mu > 0.0 else np.zeros_like(direct))
        diffuses.append(diffuse)
        globals_.append(direct + diffuse)
    return np.stack(direct_normals), np.stack(diffuses), np.stack(globals_)
