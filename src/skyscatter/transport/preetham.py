"""Preetham's analytic daylight: Perez-form distributions of luminance and chromaticity fitted to
a turbidity, as a solver.

Model. A. J. Preetham, P. Shirley, B. Smits, "A Practical Analytic Model for Daylight",
SIGGRAPH 1999, pp. 91-100, doi:10.1145/311535.311545. With theta the view zenith angle, gamma
the angle between the view and the sun, theta_s the sun's zenith angle and T the turbidity:

    F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma)
                                                          (Perez et al. 1993, Sol. Energy 50, 235)
    Y = Y_z F_Y(theta, gamma) / F_Y(0, theta_s),  and the same for x and y,
    Y_z = (4.0453 T - 4.9710) tan chi - 0.2155 T + 2.4192 [kcd m^-2],
          chi = (4/9 - T/120) (pi - 2 theta_s),
    x_z = [T^2 T 1] M_x [theta_s^3 theta_s^2 theta_s 1]^T, y_z likewise with M_y,

with A..E linear in T (the paper's Appendix A.2, `PEREZ_Y`, `PEREZ_X`, `PEREZ_Y_CHROMA`) and
M_x, M_y its zenith chromaticity matrices. The spectral radiance is the CIE daylight spectrum of
chromaticity (x, y) (CIE 015:2018 S0 + M1 S1 + M2 S2, `spectrum.daylight`, as the paper's
section 4 does) scaled to the luminance Y [cd m^-2]: L(lambda) = Y S(lambda) / (K_m int S
ybar), on the profile's wavelengths (0 outside the basis's 300-830 nm). The atmosphere's own
constituents do not enter: the turbidity (`SolverOptions.turbidity`, default 2.5, a clear day)
stands for them. Below the horizon (the ground) the radiance is 0.

Domain: Earth, observers on the ground (within `ground_sky.GROUND_OBSERVER_MAX_M`), the sun at
or above the horizon (InputError otherwise, `ground_sky`); turbidity 1-20 accepted, the fits
made for about 2-10 (the model gives negative or implausible values at low turbidity and low
sun: Zotti, Wilkie & Purgathofer 2007, "A critical review of the Preetham skylight model",
WSCG). Transmittance: ray marched through the profile (`transport.transmittance`), the model
has none of its own.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.errors import InputError
from skyscatter.spectrum.colour import luminance
from skyscatter.spectrum.daylight import daylight_basis, daylight_weights
from skyscatter.transport.ground_sky import (
    EARTH_GROUND_DAYLIGHT,
    check_earth,
    ground_sky_angles,
)
from skyscatter.transport.transmittance import ray_marched_transmittance

__all__ = ["PreethamSolver", "perez", "preetham_xyy"]

# Preetham et al. 1999, Appendix A.2: rows A, B, C, D, E of the Perez coefficients, each
# (per turbidity, constant): coefficient = row[0] T + row[1]
PEREZ_Y = np.array([[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251],
                    [0.1206, -2.5771], [-0.0670, 0.3703]])
PEREZ_X = np.array([[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125],
                    [-0.0641, -0.8989], [-0.0033, 0.0452]])
PEREZ_Y_CHROMA = np.array([[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102],
                           [-0.0441, -1.6537], [-0.0109, 0.0529]])
# Appendix A.2: zenith chromaticity, rows T^2, T, 1; columns theta_s^3, theta_s^2, theta_s, 1
ZENITH_X = np.array([[0.00166, -0.00375, 0.00209, 0.0],
                     [-0.02903, 0.06377, -0.03202, 0.00394],
                     [0.11693, -0.21196, 0.06052, 0.25886]])
ZENITH_Y_CHROMA = np.array([[0.00275, -0.00610, 0.00317, 0.0],
                            [-0.04214, 0.08970, -0.04153, 0.00516],
                            [0.15346, -0.26756, 0.06670, 0.26688]])
DEFAULT_TURBIDITY = 2.5
TURBIDITY_RANGE = (1.0, 20.0)
# 5 nm grid of the CIE daylight basis within the colour-matching functions' 360-830 nm: the
# luminance of each basis function, for the scaling to Y
_LUMINANCE_GRID_NM = np.arange(360.0, 831.0, 5.0)


def perez(cos_theta: ArrayLike, gamma_rad: ArrayLike, coefficients: np.ndarray) -> np.ndarray:
    """F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma) [-]
    for `coefficients` (A, B, C, D, E); the horizon's value at and below it (B < 0)."""
    a, b, c, d, e = coefficients
    cos_t = np.maximum(np.asarray(cos_theta, dtype=np.float64), 0.0)
    gamma = np.asarray(gamma_rad, dtype=np.float64)
    with np.errstate(divide="ignore"):
        gradation = np.exp(np.where(cos_t > 0.0, b / np.where(cos_t > 0.0, cos_t, 1.0),
                                    -np.inf))
    return (1.0 + a * gradation) * (1.0 + c * np.exp(d * gamma) + e * np.cos(gamma) ** 2)


def preetham_xyy(turbidity: float, cos_theta: ArrayLike, gamma_rad: ArrayLike,
                 sun_zenith_rad: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y, Y [cd m^-2]) of the sky at view zenith cosine `cos_theta`, `gamma_rad` [rad] from
    the sun, the sun `sun_zenith_rad` [rad] from the zenith, for `turbidity` (module
    docstring); the arguments broadcast."""
    t = float(turbidity)
    theta_s = np.asarray(sun_zenith_rad, dtype=np.float64)
    chi = (4.0 / 9.0 - t / 120.0) * (np.pi - 2.0 * theta_s)
    zenith_luminance = 1000.0 * ((4.0453 * t - 4.9710) * np.tan(chi) - 0.2155 * t + 2.4192)
    powers_t = np.array([t * t, t, 1.0])
    powers_s = np.stack([theta_s ** 3, theta_s ** 2, theta_s, np.ones_like(theta_s)], axis=-1)
    zenith_x = powers_s @ (powers_t @ ZENITH_X)
    zenith_y = powers_s @ (powers_t @ ZENITH_Y_CHROMA)
    out = []
    for zenith, table in ((zenith_x, PEREZ_X), (zenith_y, PEREZ_Y_CHROMA),
                          (zenith_luminance, PEREZ_Y)):
        coefficients = table[:, 0] * t + table[:, 1]
        out.append(zenith * perez(cos_theta, gamma_rad, coefficients)
                   / perez(1.0, theta_s, coefficients))
    return out[0], out[1], out[2]


class PreethamSolver:
    """Preetham's sky of `turbidity` (module docstring)."""

    name = "preetham"
    domain = EARTH_GROUND_DAYLIGHT

    def __init__(self, profile: OpticalProfile, turbidity: float = DEFAULT_TURBIDITY) -> None:
        check_earth(profile, self.name)
        low, high = TURBIDITY_RANGE
        if isinstance(turbidity, bool) or not low <= turbidity <= high:
            raise InputError(f"turbidity = {turbidity!r} must lie in [{low:g}, {high:g}] "
                             "(2-3: clear, 6-10: hazy)", key="turbidity", value=turbidity,
                             allowed=f"[{low:g}, {high:g}]")
        self.profile = profile
        self.turbidity = float(turbidity)
        self._basis = daylight_basis(profile.wavelengths_nm)  # (3, n_wl)
        self._basis_luminance = luminance(daylight_basis(_LUMINANCE_GRID_NM),
                                          _LUMINANCE_GRID_NM)  # (3,) [cd m^-2 per unit]

    def sky_radiance(self, position: ArrayLike, view_directions: ArrayLike,
                     sun_direction: ArrayLike,
                     progress: Callable[[int], None] | None = None) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1], S + (n_wl,) (`Solver.sky_radiance`);
        InputError outside the domain (`ground_sky`)."""
        angles, shape, _ = ground_sky_angles(self.profile, position, view_directions,
                                             sun_direction, self.name)
        x, y, big_y = preetham_xyy(self.turbidity, angles.cos_view_zenith, angles.sun_angle,
                                   angles.sun_zenith)
        m1, m2 = daylight_weights(x, y)
        y0, y1, y2 = self._basis_luminance
        scale = np.where(angles.cos_view_zenith >= 0.0,
                         np.maximum(big_y, 0.0) / (y0 + m1 * y1 + m2 * y2), 0.0)
        s0, s1, s2 = self._basis
        radiance = scale[..., None] * (s0 + m1[..., None] * s1 + m2[..., None] * s2)
        if progress is not None:
            progress(int(np.prod(shape)))
        return np.maximum(radiance, 0.0)

    def transmittance(self, position: ArrayLike, directions: ArrayLike,
                      distance_m: ArrayLike = np.inf) -> np.ndarray:
        """Transmittance [-] S + (n_wl,), ray marched through the profile."""
        return ray_marched_transmittance(self.profile, position, directions, distance_m)
