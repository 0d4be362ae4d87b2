"""The CIE standard general sky: the 15 relative luminance distributions of clear, partly cloudy
and overcast skies, as a solver.

Model. CIE S 011/E:2003 = ISO 15469:2004(E), "Spatial Distribution of Daylight - CIE Standard
General Sky"; Kittler, Perez & Darula (1998), "A set of standard skies characterizing
daylight conditions for computer and energy conscious design", Final Report US-SK 92 052;
Darula & Kittler (2002), "CIE general sky standard defining luminance distributions", Proc.
eSim 2002, Montreal. The luminance of a sky element at zenith angle Z, at the angle chi from
the sun (sun zenith Z_s), relative to the zenith's:

    L / L_z = f(chi) phi(Z) / (f(Z_s) phi(0)),
    gradation   phi(Z) = 1 + a exp(b / cos Z)        (phi(90 deg) = 1),
    indicatrix  f(chi) = 1 + c [exp(d chi) - exp(d pi / 2)] + e cos^2 chi,

with (a, b) from six gradation groups and (c, d, e) from six indicatrix groups; each of the 15
types pairs one of each (`SKY_TYPES`, the standard's Table 1). Type 12 is the CIE standard
clear sky (low turbidity), 13 the clear sky of a polluted atmosphere, 1 the CIE standard
overcast sky (Moon & Spencer 1942), 5 the uniform sky.

Absolute level and colour (our choice; the standard gives relative luminance only): the zenith
spectral radiance L_z(lambda) of the same atmosphere from the "lut" solver (the tables cached as
for `--solver lut`), so L(lambda) = L_z(lambda) f(chi) phi(Z) / (f(Z_s) phi(0)): the whole dome
has the zenith's colour, and the comparison with the exact solvers measures the distribution
alone. Below the horizon (the ground) the radiance is 0.

Domain: Earth, observers on the ground (within `ground_sky.GROUND_OBSERVER_MAX_M`), the sun at
or above the horizon; otherwise InputError (`ground_sky`). Transmittance: the "lut" solver's.
Accuracy: the standard's types are fits to sky scanner measurements (Kittler et al. 1998: the
15 types cover the measured skies of Tokyo, Berkeley and Bratislava); measured against the exact
solvers in docs/techniques.md.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.transport.ground_sky import (
    EARTH_GROUND_DAYLIGHT,
    check_earth,
    ground_sky_angles,
)

__all__ = ["SKY_TYPES", "CieSkySolver", "cie_relative_luminance"]

# CIE S 011/E:2003 Table 1: type -> (a, b, c, d, e); gradation group (I-VI) and indicatrix
# group (1-6) in the comment
SKY_TYPES: dict[int, tuple[float, float, float, float, float]] = {
    1: (4.0, -0.70, 0.0, -1.0, 0.00),  # I.1   CIE standard overcast sky, steep gradation
    2: (4.0, -0.70, 2.0, -1.5, 0.15),  # I.2   overcast, steep gradation, slight brightening
    3: (1.1, -0.80, 0.0, -1.0, 0.00),  # II.1  overcast, moderately graded, azimuthal uniformity
    4: (1.1, -0.80, 2.0, -1.5, 0.15),  # II.2  overcast, moderately graded, slight brightening
    5: (0.0, -1.00, 0.0, -1.0, 0.00),  # III.1 sky of uniform luminance
    6: (0.0, -1.00, 2.0, -1.5, 0.15),  # III.2 partly cloudy, no gradation, slight brightening
    7: (0.0, -1.00, 5.0, -2.5, 0.30),  # III.3 partly cloudy, brighter circumsolar region
    8: (0.0, -1.00, 10.0, -3.0, 0.45),  # III.4 partly cloudy, distinct solar corona
    9: (-1.0, -0.55, 2.0, -1.5, 0.15),  # IV.2  partly cloudy, obscured sun
    10: (-1.0, -0.55, 5.0, -2.5, 0.30),  # IV.3 partly cloudy, brighter circumsolar region
    11: (-1.0, -0.55, 10.0, -3.0, 0.45),  # IV.4 white-blue sky, distinct solar corona
    12: (-1.0, -0.32, 10.0, -3.0, 0.45),  # V.4  CIE standard clear sky, low turbidity
    13: (-1.0, -0.32, 16.0, -3.0, 0.30),  # V.5  CIE standard clear sky, polluted atmosphere
    14: (-1.0, -0.15, 16.0, -3.0, 0.30),  # VI.5 cloudless turbid sky, broad solar corona
    15: (-1.0, -0.15, 24.0, -2.8, 0.15),  # VI.6 white-blue turbid sky, broad solar corona
}
DEFAULT_SKY_TYPE = 12


def _gradation(cos_zenith: np.ndarray, a: float, b: float) -> np.ndarray:
    """phi(Z) = 1 + a exp(b / cos Z) [-]; 1 at and below the horizon (b < 0)."""
    cos_z = np.maximum(np.asarray(cos_zenith, dtype=np.float64), 0.0)
    with np.errstate(divide="ignore"):
        return 1.0 + a * np.exp(np.where(cos_z > 0.0, b / np.where(cos_z > 0.0, cos_z, 1.0),
                                          -np.inf))


def _indicatrix(chi: np.ndarray, c: float, d: float, e: float) -> np.ndarray:
    """f(chi) = 1 + c [exp(d chi) - exp(d pi / 2)] + e cos^2 chi [-], chi [rad]."""
    chi = np.asarray(chi, dtype=np.float64)
    return 1.0 + c * (np.exp(d * chi) - np.exp(d * np.pi / 2.0)) + e * np.cos(chi) ** 2


def cie_relative_luminance(sky_type: int, cos_view_zenith: ArrayLike, sun_angle_rad: ArrayLike,
                           sun_zenith_rad: ArrayLike) -> np.ndarray:
    """L / L_z [-] of CIE standard general sky `sky_type` (1-15) at view zenith cosine
    `cos_view_zenith`, `sun_angle_rad` [rad] from the sun, the sun `sun_zenith_rad` [rad] from
    the zenith (module docstring); the arguments broadcast."""
    a, b, c, d, e = _sky_type(sky_type)
    return (_indicatrix(sun_angle_rad, c, d, e) * _gradation(cos_view_zenith, a, b)
            / (_indicatrix(sun_zenith_rad, c, d, e) * _gradation(1.0, a, b)))


def _sky_type(sky_type: int) -> tuple[float, float, float, float, float]:
    if isinstance(sky_type, bool) or sky_type not in SKY_TYPES:
        raise InputError(f"CIE sky type {sky_type!r} must be an integer from 1 to 15 (12: the "
                         "CIE standard clear sky)", key="sky_type", value=sky_type,
                         allowed="1-15")
    return SKY_TYPES[sky_type]


class CieSkySolver:
    """The CIE standard general sky `sky_type` (module docstring), its zenith spectral radiance
    and transmittance from the solver `make_zenith_solver()` returns (the "lut" solver of the
    same profile), made once the profile and sky type are known to be valid."""

    name = "cie"
    domain = EARTH_GROUND_DAYLIGHT

    def __init__(self, profile: OpticalProfile, make_zenith_solver: Callable[[], object],
                 sky_type: int = DEFAULT_SKY_TYPE) -> None:
        check_earth(profile, self.name)
        _sky_type(sky_type)
        self.profile = profile
        self.sky_type = sky_type
        self._zenith_solver = make_zenith_solver()

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1], S + (n_wl,) (`Solver.sky_radiance`);
        InputError outside the domain (`ground_sky`)."""
        angles, shape, origins = ground_sky_angles(self.profile, position, view_directions,
                                                   sun_direction, self.name)
        unique, index = np.unique(origins, axis=0, return_inverse=True)
        ups = unique / np.linalg.norm(unique, axis=1, keepdims=True)
        zenith = self._zenith_solver.sky_radiance(unique, ups, sun_direction)  # (n_u, n_wl)
        relative = cie_relative_luminance(self.sky_type, angles.cos_view_zenith,
                                          angles.sun_angle, angles.sun_zenith)
        relative = np.where(angles.cos_view_zenith >= 0.0, relative, 0.0)
        radiance = relative[..., None] * zenith[index.reshape(shape)]
        if progress is not None:
            progress(int(np.prod(shape)))
        return radiance

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] S + (n_wl,): the zenith solver's (`Solver.transmittance`)."""
        return self._zenith_solver.transmittance(position, directions, distance_m)
