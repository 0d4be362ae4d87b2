"""Optics of cloud particles per gram of condensed water: liquid droplets from Mie theory, ice
from the geometric-optics limit.

A cloud's extinction coefficient is its water content w [g m^-3] times a mass extinction
coefficient k_ext [m^2 g^-1], so the renderer's density field can be the water content itself.

Liquid water (`liquid_cloud_optics`): droplets of Hansen & Travis's (1974) modified gamma
distribution in effective radius r_eff and variance v_eff, water index of Segelstein (1981)
(`optics.particle_index`), Mie theory (`optics.mie.particle_optics`):

    k_ext = <C_ext> / (rho_w 4/3 pi <r^3>),   rho_w = 1e6 g m^-3

which tends to 3 Q_ext / (4 rho_w r_eff) with Q_ext -> 2 for droplets much larger than the
wavelength (Stephens 1978, J. Atmos. Sci. 35, 2123, eq. 7,
doi:10.1175/1520-0469(1978)035<2123:RPIEWC>2.0.CO;2). Phase function: the Mie table.

Ice (`ice_cloud_optics`): crystals much larger than visible wavelengths, in the geometric-optics
limit Q_ext = 2 for any convex particle whose effective radius is r_eff = 3 V / (4 A), V its
volume and A its mean projected area (Foot 1988, Q. J. R. Meteorol. Soc. 114, 145,
doi:10.1002/qj.49711447908; Grenfell & Warren 1999, J. Geophys. Res. 104, 31697,
doi:10.1029/1999JD900496):

    k_ext = 3 / (2 rho_i r_eff),   rho_i = 0.917e6 g m^-3

single-scattering albedo 1 (ice absorbs ~1e-9 of visible light per wavelength: Warren & Brandt
2008, J. Geophys. Res. 113, D14220, doi:10.1029/2007JD009744) and a Henyey-Greenstein phase
function of asymmetry g = 0.75, that of the severely roughened crystals which fit
polarimetric and infrared observations of cirrus best (Yang et al. 2013, J. Atmos. Sci. 70,
330, doi:10.1175/JAS-D-12-039.1; Cole et al. 2013, J. Atmos. Sci. 70, 3768: g = 0.75 at
0.65 um for all sizes). The smooth HG drops the 22 deg halo; say so where halos matter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.mie import MIE_WAVELENGTHS_NM, MieOptics, particle_optics
from skyscatter.optics.particle_index import load_material
from skyscatter.optics.phase import HenyeyGreensteinPhase, PhaseFunction
from skyscatter.optics.size_distribution import ModifiedGamma

__all__ = [
    "ICE_ASYMMETRY",
    "ICE_DENSITY_G_M3",
    "WATER_DENSITY_G_M3",
    "CloudOptics",
    "ice_cloud_optics",
    "liquid_cloud_optics",
]

WATER_DENSITY_G_M3 = 1.0e6  # liquid water near 0 °C, 999.8 kg m^-3 (CRC Handbook), rounded
ICE_DENSITY_G_M3 = 0.917e6  # ice Ih at 0 °C, 916.7 kg m^-3 (Petrenko & Whitworth 1999)
ICE_ASYMMETRY = 0.75  # roughened ice crystals in the visible (Yang et al. 2013; module docstring)
MIE_RADII = 2000  # nodes of the radius quadrature: the Mie integrals to < 1e-4 for v_eff >= 0.05


@dataclass(frozen=True, eq=False)
class CloudOptics:
    """Optics of one kind of cloud particle per gram of water, on `wavelengths_nm`.

    mass_extinction_m2_g (n_wl,) [m^2 g^-1], single_scattering_albedo (n_wl,) [-],
    asymmetry (n_wl,) [-], `phase` a `PhaseFunction` [sr^-1]; `description` names the source.
    """

    wavelengths_nm: np.ndarray
    mass_extinction_m2_g: np.ndarray
    single_scattering_albedo: np.ndarray
    asymmetry: np.ndarray
    phase: PhaseFunction
    description: str


def _checked_radius(effective_radius_um: float, low: float, high: float) -> float:
    value = float(effective_radius_um)
    if not np.isfinite(value) or not low <= value <= high:
        raise InputError(f"effective_radius_um = {effective_radius_um!r} is not allowed: a "
                         f"number >= {low:g} and <= {high:g}", key="effective_radius_um",
                         value=effective_radius_um, allowed=f">= {low:g} and <= {high:g}")
    return value


def liquid_cloud_optics(effective_radius_um: float, effective_variance: float,
                        wavelengths_nm: ArrayLike) -> CloudOptics:
    """Water droplets (module docstring) on `wavelengths_nm` [nm]: Mie theory on 360-900 nm
    in 10 nm steps (cached on disk), interpolated linearly. Radii 1-40 um (larger ones exceed
    the Mie code's size parameter at 360 nm)."""
    radius_um = _checked_radius(effective_radius_um, 1.0, 40.0)
    distribution = ModifiedGamma(radius_um * 1e-6, effective_variance)
    table = particle_optics(distribution, load_material("water"), MIE_WAVELENGTHS_NM,
                            n_radii=MIE_RADII)
    radii, weights = distribution.quadrature(MIE_RADII)
    mean_volume_m3 = 4.0 / 3.0 * np.pi * float(np.sum(weights * radii**3))
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    optics = MieOptics(table)
    k_ext = optics.extinction_per_density(wl) / (WATER_DENSITY_G_M3 * mean_volume_m3)
    albedo = optics.scattering_per_density(wl) / optics.extinction_per_density(wl)
    return CloudOptics(wl, k_ext, albedo, optics.phase.asymmetry(wl), optics.phase,
                       f"liquid water, Mie, r_eff {radius_um:g} um, v_eff {effective_variance:g}")


def ice_cloud_optics(effective_radius_um: float, wavelengths_nm: ArrayLike) -> CloudOptics:
    """Ice crystals of effective radius 3 V / (4 A) [um], 5-100 um, on `wavelengths_nm` [nm]
    (module docstring: geometric optics, HG g = 0.75)."""
    radius_um = _checked_radius(effective_radius_um, 5.0, 100.0)
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    k_ext = np.full(wl.shape, 3.0 / (2.0 * ICE_DENSITY_G_M3 * radius_um * 1e-6))
    return CloudOptics(wl, k_ext, np.ones(wl.shape), np.full(wl.shape, ICE_ASYMMETRY),
                       HenyeyGreensteinPhase(ICE_ASYMMETRY),
                       f"ice, geometric optics, r_eff {radius_um:g} um, HG g {ICE_ASYMMETRY}")
