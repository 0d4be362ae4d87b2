"""Where a solver's sky holds (`SolverDomain`), and the angles of the analytic sky models fitted
to skies seen from Earth's ground (`cie`, `preetham`).

Those models describe the sky dome of a ground observer on Earth with the sun up, as functions
of the view zenith angle theta (Z in the CIE standard), the angle gamma (chi) between the view
and the sun, and the sun's zenith angle theta_s (Z_s). Outside that domain they refuse with an
`InputError` naming the solvers that can (a one-line message, not a silent guess). Views below
the horizon (the ground) get no radiance from them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport.geometry import broadcast_rays

__all__ = ["ANYWHERE", "EARTH_GROUND_DAYLIGHT", "GROUND_OBSERVER_MAX_M", "GroundSkyAngles",
           "SolverDomain", "ground_sky_angles", "solver_domain"]

# Highest observer the ground models accept [m]: their skies were measured from the ground;
# from 1 km the horizon dips 1 deg and the air below holds ~10 % of the column, the order of
# the models' own scatter against measurements.
GROUND_OBSERVER_MAX_M = 1000.0
# Planets the Earth-fitted models accept: a radius within 1 % of Earth's mean 6371.0 km
# (IUGG; the configs use 6360-6378 km).
EARTH_RADIUS_RANGE_M = (6.307e6, 6.435e6)


@dataclass(frozen=True)
class SolverDomain:
    """Where a solver's `sky_radiance` answers; outside it raises InputError.

    ground_only        observers within GROUND_OBSERVER_MAX_M of the ground only
    sun_above_horizon  the sun's centre at or above the horizon only
    earth_only         a planet of Earth's size only
    """

    ground_only: bool = False
    sun_above_horizon: bool = False
    earth_only: bool = False


ANYWHERE = SolverDomain()
EARTH_GROUND_DAYLIGHT = SolverDomain(ground_only=True, sun_above_horizon=True, earth_only=True)


def solver_domain(solver: object) -> SolverDomain:
    """The solver's `domain` attribute; ANYWHERE for the solvers that declare none."""
    return getattr(solver, "domain", ANYWHERE)


class GroundSkyAngles(NamedTuple):
    """Per ray, shape S: cos theta (view zenith), gamma [rad] (view to sun), theta_s [rad]."""

    cos_view_zenith: np.ndarray
    sun_angle: np.ndarray
    sun_zenith: np.ndarray


def check_earth(profile: OpticalProfile, model: str) -> None:
    """InputError unless `profile` is a planet of Earth's size (`EARTH_RADIUS_RANGE_M`)."""
    low, high = EARTH_RADIUS_RANGE_M
    if not low <= profile.bottom_radius_m <= high:
        raise InputError(
            f"solver {model!r} describes Earth's sky only; this planet's radius is "
            f"{profile.bottom_radius_m / 1e3:.0f} km (use --solver lut, single or schuler)",
            key="solver", value=model, allowed="a planet of Earth's radius")


def ground_sky_angles(profile: OpticalProfile, position: ArrayLike, view_directions: ArrayLike,
                      sun_direction: ArrayLike, model: str
                      ) -> tuple[GroundSkyAngles, tuple[int, ...], np.ndarray]:
    """(angles, S, origins (n, 3)) of the rays from `position` along `view_directions` with the
    sun along `sun_direction` (3,); InputError for an observer above GROUND_OBSERVER_MAX_M or
    a sun below the horizon (`model` names the solver in the message)."""
    origins, directions, shape = broadcast_rays(position, view_directions)
    radius = np.linalg.norm(origins, axis=1)
    altitude = radius - profile.bottom_radius_m
    if np.any(np.abs(altitude) > GROUND_OBSERVER_MAX_M):
        worst = float(altitude[np.argmax(np.abs(altitude))])
        raise InputError(
            f"solver {model!r} describes the sky of an observer on the ground only (within "
            f"{GROUND_OBSERVER_MAX_M:g} m); this one is at {worst:.0f} m (use --solver lut, "
            "single or schuler)", key="solver", value=model,
            allowed=f"observers within {GROUND_OBSERVER_MAX_M:g} m of the ground")
    up = origins / radius[:, None]
    sun = np.asarray(sun_direction, dtype=np.float64)
    sun = sun / np.linalg.norm(sun)
    cos_sun_zenith = up @ sun
    if np.any(cos_sun_zenith < 0.0):
        degrees = float(np.degrees(np.arccos(np.clip(cos_sun_zenith.min(), -1.0, 1.0))))
        raise InputError(
            f"solver {model!r} describes the daylit sky only; the sun is {degrees:.2f} deg "
            "from the zenith, below the horizon (use --solver lut for twilight)",
            key="solver", value=model, allowed="the sun at or above the horizon")
    angles = GroundSkyAngles(
        cos_view_zenith=np.einsum("ij,ij->i", up, directions).reshape(shape),
        sun_angle=np.arccos(np.clip(directions @ sun, -1.0, 1.0)).reshape(shape),
        sun_zenith=np.arccos(np.clip(cos_sun_zenith, -1.0, 1.0)).reshape(shape))
    return angles, shape, origins
