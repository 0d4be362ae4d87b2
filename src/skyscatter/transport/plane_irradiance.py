r"""Spectral irradiance on a tilted plane ("plane of array") from a solver's own sky.

A plane of tilt beta from the horizontal, its normal n pointing up and towards the compass
azimuth gamma (from north towards east; gamma = 180 deg faces south), receives

    E_beam   = E_dn max(n.s, 0)                     the sun's direct normal irradiance E_dn [1]
    E_sky    = E_dh int_{z > 0} L(w) max(n.w, 0) dw
                    / int_{z > 0} L(w) w_z dw        the sky's diffuse radiance L [2]
    E_ground = rho E_gh (1 - cos beta) / 2          the ground's reflected light [3]

[1] E_dn and the global horizontal E_gh come from the solver's `ground_irradiance` (its visible
    part of the sun's disk, its transmittance); s is the unit vector towards the sun.
[2] L is the solver's own sky radiance distribution (aureole, horizon brightening, the darker
    sky opposite the sun), integrated over the upper hemisphere: Gauss-Legendre in cos(zenith)
    on (0, 1), the midpoint rule in azimuth. The integrand has a kink where the plane's horizon
    crosses the sky (n.w = 0), so the error falls as the square of the step: 32 x 64 nodes
    integrate a test radiance a + b cos(zenith) on a vertical plane to 4.1e-4 of its closed
    form a pi / 2 + 2 b / 3, an isotropic one on planes of any tilt to 4.1e-4 or better
    (tests/test_scientist_outputs.py); the Earth's sky on a vertical plane differs from a
    128 x 256 quadrature by 0.04 % (measured). Not an isotropic-sky model: for an
    isotropic sky L this is the classical E_dh (1 + cos beta) / 2 (Liu & Jordan 1963, Solar
    Energy 7, 53, doi:10.1016/0038-092X(63)90006-9). The ratio keeps the solver's own diffuse
    horizontal irradiance E_dh, so that a horizontal plane gets exactly E_gh: the table
    solver's radiance integrates over the hemisphere to 0.2-0.4 % less than its irradiance
    table (Earth preset, its 8 orders, 450-700 nm, sun at 30 and 60 deg; measured), the
    single-scattering solver's to within 1e-6 (its E_dh is this integral).
[3] A flat, uniform, Lambertian ground of the atmosphere's albedo rho, lit by E_gh, seen over
    the plane's view factor of the ground (1 - cos beta) / 2 (Duffie & Beckman 2013, Solar
    Engineering of Thermal Processes, 4th ed., eq. 2.15.1); the air between the ground and
    the plane is neglected (a plane at the ground).

The observer stands above the north pole (`single_scattering.observer_position`), where the
local east-north-up frame is the world's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position

__all__ = ["PlaneIrradiance", "plane_irradiance", "plane_normal"]


@dataclass(frozen=True)
class PlaneIrradiance:
    """Spectral irradiance on one plane [W m^-2 nm^-1], each (n_wl,)."""

    beam: np.ndarray  # the sun's direct light
    sky_diffuse: np.ndarray  # the sky's diffuse light, from its radiance distribution
    ground_reflected: np.ndarray  # the Lambertian ground's light

    @property
    def total(self) -> np.ndarray:
        return self.beam + self.sky_diffuse + self.ground_reflected


def plane_normal(tilt_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit normal (3,) in east-north-up of a plane tilted `tilt_deg` from the horizontal
    towards the compass azimuth `azimuth_deg` (from north towards east) [deg]."""
    return local_frame_directions(np.radians(tilt_deg), np.radians(azimuth_deg))


def plane_irradiance(solver, sun_direction: np.ndarray, normal: np.ndarray,
                     altitude_m: float = 0.0, *, n_zenith: int = 32,
                     n_azimuth: int = 64) -> PlaneIrradiance:
    """Beam, sky-diffuse and ground-reflected irradiance on the plane of unit `normal` (3,)
    with the sun along `sun_direction` (3,), both east-north-up, for an observer `altitude_m`
    [m] above the ground; `solver` is a `SurfaceSolver`. Quadrature: module docstring."""
    position = observer_position(altitude_m, solver.profile.bottom_radius_m)
    normal = np.asarray(normal, dtype=np.float64)
    sun = np.asarray(sun_direction, dtype=np.float64)
    direct_horizontal, diffuse_horizontal = solver.ground_irradiance(position, sun)
    mu_s = float(sun[2])
    direct_normal = direct_horizontal / mu_s if mu_s > 0.0 else np.zeros_like(direct_horizontal)
    beam = direct_normal * max(float(normal @ sun), 0.0)
    nodes, weights = np.polynomial.legendre.leggauss(n_zenith)
    cos_zenith = 0.5 * (nodes + 1.0)
    azimuth = (np.arange(n_azimuth) + 0.5) * 2.0 * np.pi / n_azimuth
    zenith, azimuth = np.meshgrid(np.arccos(cos_zenith), azimuth, indexing="ij")
    directions = local_frame_directions(zenith, azimuth)
    solid_angle = np.broadcast_to((0.5 * weights * np.pi / n_azimuth * 2.0)[:, None],
                                  zenith.shape)  # dw = dmu dphi
    weight = np.maximum(directions @ normal, 0.0) * solid_angle
    weight_horizontal = directions[..., 2] * solid_angle
    radiance = solver.sky_radiance(position, directions, sun)
    on_plane = np.einsum("ij,ijk->k", weight, radiance)
    on_horizontal = np.einsum("ij,ijk->k", weight_horizontal, radiance)
    sky = np.divide(diffuse_horizontal * on_plane, on_horizontal,
                    out=np.zeros_like(on_plane), where=on_horizontal > 0.0)
    ground = (solver.profile.ground_albedo * (direct_horizontal + diffuse_horizontal)
              * 0.5 * (1.0 - float(normal[2])))
    return PlaneIrradiance(beam, sky, ground)
