"""Reflectance and transmittance of a homogeneous cloud slab: published values, the tables and
PythonicDISORT.

The case: a plane-parallel slab of optical thickness tau, single-scattering albedo 1,
Henyey-Greenstein phase function g = 0.75, black ground, a beam at normal incidence (mu0 = 1).
Its fluxes are tabulated by van de Hulst (1980), "Multiple Light Scattering", vol. 2, Academic
Press, Table 37, and are DISORT's test problem 3 (Stamnes et al. 1988, Appl. Opt. 27, 2502,
doi:10.1364/AO.27.002502; the test program DISOTEST of DISORT 2.0, "Compare to Ref. VH2,
Table 37"). `PUBLISHED` holds the answers stored in DISOTEST for that problem (beam flux pi,
so the incident irradiance on the slab is pi): upward flux at the top, diffuse and direct
downward flux at the bottom, here divided by pi:

    reflectance               R   = F_up(0) / (pi mu0)
    diffuse transmittance     T_d = F_down,diffuse(tau) / (pi mu0)
    direct transmittance      T_0 = exp(-tau / mu0)

With conservative scattering R + T_d + T_0 = 1.

The tables see the slab as a 1 km layer of constant density on a planet of Earth's radius: for
a sun at the zenith the spherical shell then differs from the plane-parallel slab by about
thickness / radius = 2e-4 in the fluxes. R is the upward radiance at the top integrated over
the hemisphere (Gauss-Legendre in mu, azimuth midpoints), T_d the tables' diffuse ground
irradiance (`LutSolver.ground_irradiance`), T_0 their direct one.

Public names: `PUBLISHED`, `SlabFluxes`, `slab_profile`, `table_slab_fluxes`,
`disort_slab_fluxes`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.optics.phase import HenyeyGreensteinPhase
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.solvers import Solver
from skyscatter.validate.disort import disort_fluxes, plane_parallel_layers

__all__ = ["PUBLISHED", "SlabFluxes", "disort_slab_fluxes", "slab_profile",
           "table_slab_fluxes"]

SLAB_G = 0.75
SLAB_THICKNESS_M = 1000.0
EARTH_RADIUS_M = 6.371e6  # IUGG mean Earth radius (Moritz 2000)


@dataclass(frozen=True)
class SlabFluxes:
    """Fluxes of the slab normalised by the incident irradiance pi mu0 E0 / pi = mu0 E0 [-]."""

    reflectance: float
    diffuse_transmittance: float
    direct_transmittance: float

    @property
    def total(self) -> float:
        """R + T_d + T_0: 1 for a conservative slab (energy). [-]"""
        return self.reflectance + self.diffuse_transmittance + self.direct_transmittance


# optical thickness -> DISOTEST problem 3 answers (FLUP(0), RFLDN(tau), RFLDIR(tau)) / pi:
# tau = 1: 0.247374, 1.73849, 1.15573; tau = 8: 1.59096, 1.54958, 1.05389e-3.
PUBLISHED = {
    1.0: SlabFluxes(0.247374 / np.pi, 1.73849 / np.pi, 1.15573 / np.pi),
    8.0: SlabFluxes(1.59096 / np.pi, 1.54958 / np.pi, 1.05389e-3 / np.pi),
}


def slab_profile(optical_depth: float, g: float = SLAB_G, single_scattering_albedo: float = 1.0,
                 wavelengths_nm: np.ndarray | None = None) -> OpticalProfile:
    """The slab as an `OpticalProfile`: a constant-density HG scatterer 1 km thick on a planet
    of Earth's radius, black ground, top-of-atmosphere irradiance 1 (module docstring)."""
    wavelengths = np.array([550.0]) if wavelengths_nm is None else np.asarray(wavelengths_nm)
    altitudes = np.linspace(0.0, SLAB_THICKNESS_M, 21)
    extinction = optical_depth / SLAB_THICKNESS_M
    n_wl = wavelengths.size
    return OpticalProfile(
        wavelengths_nm=wavelengths, bottom_radius_m=EARTH_RADIUS_M,
        top_radius_m=EARTH_RADIUS_M + SLAB_THICKNESS_M, altitudes_m=altitudes,
        density=np.ones((1, altitudes.size)),
        extinction_per_density=np.full((1, n_wl), extinction),
        scattering_per_density=np.full((1, n_wl), extinction * single_scattering_albedo),
        phases=(HenyeyGreensteinPhase(g),), names=("cloud",), ground_albedo=np.zeros(n_wl),
        toa_irradiance=np.ones(n_wl), sun_angular_radius_rad=0.0)


def table_slab_fluxes(solver: Solver, profile: OpticalProfile, *, n_mu: int = 16,
                      n_azimuth: int = 4) -> SlabFluxes:
    """The fluxes of a sun at the zenith from `solver` (normally `LutSolver`) for `profile`'s
    first wavelength: R from the radiance leaving the top (n_mu Gauss-Legendre nodes in mu x
    n_azimuth azimuth midpoints), T_d and T_0 from `ground_irradiance`."""
    sun = np.array([0.0, 0.0, 1.0])
    x, weight = np.polynomial.legendre.leggauss(n_mu)
    mu, weight = 0.5 * (x + 1.0), 0.5 * weight
    azimuth = (np.arange(n_azimuth) + 0.5) * 2.0 * np.pi / n_azimuth
    zenith, phi = np.meshgrid(np.pi - np.arccos(mu), azimuth, indexing="ij")
    above = np.array([0.0, 0.0, profile.top_radius_m + 1.0])
    radiance = solver.sky_radiance(above, local_frame_directions(zenith, phi), sun)[..., 0]
    upward = 2.0 * np.pi * np.sum(radiance.mean(axis=1) * mu * weight)
    direct, diffuse = solver.ground_irradiance(np.array([0.0, 0.0, profile.bottom_radius_m]),
                                               sun)
    incident = float(profile.toa_irradiance[0])
    return SlabFluxes(float(upward) / incident, float(diffuse[0]) / incident,
                      float(direct[0]) / incident)


def disort_slab_fluxes(profile: OpticalProfile, *, n_streams: int = 32) -> SlabFluxes:
    """The same fluxes from PythonicDISORT (`disort_fluxes`) for `profile`'s first wavelength,
    a sun at the zenith (a conservative slab gets omega = 1 - 1e-9, which DISORT needs:
    `plane_parallel_layers`)."""
    layers = plane_parallel_layers(profile, n_layers=4, n_moments=max(128, 2 * n_streams))
    up, diffuse, direct = disort_fluxes(layers, profile.toa_irradiance, 0.0,
                                        profile.ground_albedo, n_streams=n_streams)
    incident = float(profile.toa_irradiance[0])
    return SlabFluxes(float(up[0]) / incident, float(diffuse[0]) / incident,
                      float(direct[0]) / incident)
