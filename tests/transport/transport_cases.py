"""Small atmospheres built directly from arrays, with answers known in closed form."""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere.model import OpticalProfile
from skyscatter.optics.phase import HenyeyGreensteinPhase, RayleighPhase
from skyscatter.transport.tables import TableResolution

EARTH_RADIUS_M = 6_360_000.0
# Small tables for the tests that check behaviour rather than accuracy (about 1 s each).
SMALL = TableResolution(transmittance_r=32, transmittance_mu=128, scattering_r=16,
                        scattering_mu=64, scattering_mu_s=16, scattering_nu=8, irradiance_r=8,
                        irradiance_mu_s=32, ray_samples=32, multiple_ray_samples=16,
                        sphere_theta=16, sphere_phi=8, density_theta=17, density_phi=9,
                        irradiance_theta=8, irradiance_phi=16, phase_angles=1025)


def homogeneous_shell(extinction_per_m: float, albedo: float = 0.0, thickness_m: float = 10_000.0,
                      n_wl: int = 3, single_scattering_albedo: float = 1.0,
                      sun_angular_radius_rad: float = 0.0) -> OpticalProfile:
    """One constituent of constant density 1 in a shell; isotropic phase function (HG g=0)."""
    wl = np.linspace(450.0, 650.0, n_wl)
    altitudes = np.linspace(0.0, thickness_m, 201)
    return OpticalProfile(
        wavelengths_nm=wl, bottom_radius_m=EARTH_RADIUS_M,
        top_radius_m=EARTH_RADIUS_M + thickness_m, altitudes_m=altitudes,
        density=np.ones((1, altitudes.size)),
        extinction_per_density=np.full((1, n_wl), extinction_per_m),
        scattering_per_density=np.full((1, n_wl), extinction_per_m * single_scattering_albedo),
        phases=(HenyeyGreensteinPhase(0.0),), names=("haze",),
        ground_albedo=np.full(n_wl, albedo), toa_irradiance=np.full(n_wl, 1.5),
        sun_angular_radius_rad=sun_angular_radius_rad)


def exponential_earth() -> OpticalProfile:
    """Bruneton-like Rayleigh (H = 8 km) + Mie (H = 1.2 km) atmosphere, 60 km thick."""
    wl = np.array([440.0, 550.0, 680.0])
    altitudes = np.linspace(0.0, 60_000.0, 2001)
    density = np.stack([np.exp(-altitudes / 8000.0), np.exp(-altitudes / 1200.0)])
    rayleigh = 1.24062e-6 * (wl / 1000.0) ** -4
    extinction = np.stack([rayleigh, np.full(3, 4.44e-6)])
    scattering = np.stack([rayleigh, np.full(3, 3.996e-6)])
    return OpticalProfile(
        wavelengths_nm=wl, bottom_radius_m=EARTH_RADIUS_M, top_radius_m=EARTH_RADIUS_M + 60e3,
        altitudes_m=altitudes, density=density, extinction_per_density=extinction,
        scattering_per_density=scattering, phases=(RayleighPhase(), HenyeyGreensteinPhase(0.8)),
        names=("rayleigh", "mie"), ground_albedo=np.full(3, 0.1),
        toa_irradiance=np.array([1.9, 1.85, 1.5]), sun_angular_radius_rad=0.0)


def cloud_deck(optical_depth: float, base_m: float = 1000.0, top_m: float = 1100.0,
               thickness_m: float = 20_000.0) -> OpticalProfile:
    """A non-absorbing, isotropically scattering deck of `optical_depth` between base_m and
    top_m in an otherwise empty 20 km atmosphere; levels 50 m apart (the density ramps to 0
    over one level on each side, inside the optical depth); black ground, sun of 1."""
    altitudes = np.arange(0.0, thickness_m + 1.0, 50.0)
    density = ((altitudes >= base_m) & (altitudes <= top_m)).astype(float)
    extinction = optical_depth / np.trapezoid(density, altitudes)
    return OpticalProfile(
        wavelengths_nm=np.array([550.0]), bottom_radius_m=EARTH_RADIUS_M,
        top_radius_m=EARTH_RADIUS_M + thickness_m, altitudes_m=altitudes,
        density=density[None, :], extinction_per_density=np.array([[extinction]]),
        scattering_per_density=np.array([[extinction]]), phases=(HenyeyGreensteinPhase(0.0),),
        names=("deck",), ground_albedo=np.zeros(1), toa_irradiance=np.ones(1),
        sun_angular_radius_rad=0.0)
