"""Light that grazes the planet's limb: the bending and the transmittance of a ray whose lowest
point lies at tangent altitude h. They set the light in the umbra of a lunar eclipse
(`render.lunar_eclipse`).

Bending: in a spherically stratified atmosphere a ray keeps n r sin(z) = n0 r0 (Bouguer's
invariant), and the total deflection of a ray with its lowest point at r0 = R + h is

    δ(r0) = -2 ∫_{r0}^{r_top} n0 r0 / sqrt(n² r² - n0² r0²) · (1/n) dn/dr dr

(e.g. Born & Wolf, Principles of Optics, §3.2.2; the astronomical refraction integral of
Smart, Spherical Astronomy, §58, taken through the whole atmosphere). With r = r0 + s² the
1/sqrt singularity at r0 becomes regular and Gauss-Legendre in s integrates it. For an
exponential atmosphere of scale height H this is δ ≈ (n0 - 1) sqrt(2π r0 / H) e^(-h/H), about
70' at h = 0 for Earth, twice the 35' horizontal refraction seen from the ground (the test).

Refractivity follows the air's density: n - 1 = (n_s - 1) N(h) / N_s, with n_s - 1 of standard
air at 550 nm (Peck & Reeder 1972; `optics.refractive_index`) at N_s = 2.5469e25 m⁻³. The
density is the profile's Rayleigh constituent: a number density [m⁻³], or a density relative
to the ground (read as standard air there). The dispersion of refraction (1.5 % over the
visible) is left out.

Transmittance: the product of the table transmittances from the tangent point out of the
atmosphere along both halves of the ray.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.optics.phase import PenndorfPhase, RayleighPhase
from skyscatter.optics.refractive_index import (
    AIR_NUMBER_DENSITY_288K_M3,
    refractivity_air_peck_reeder_1972,
)

__all__ = ["grazing_deflection_rad", "grazing_transmittance"]

_REFERENCE_WAVELENGTH_NM = 550.0
_QUADRATURE_NODES = 96
_ABSOLUTE_DENSITY_M3 = 1e20  # a ground density above this is a number density, else relative


def _air_refractivity(profile) -> tuple[np.ndarray, np.ndarray]:
    """(altitudes [m], n - 1 [-]) of the profile's Rayleigh-scattering air."""
    for density, phase in zip(profile.density, profile.phases, strict=True):
        if isinstance(phase, RayleighPhase | PenndorfPhase):
            standard = float(refractivity_air_peck_reeder_1972(_REFERENCE_WAVELENGTH_NM))
            if density[0] > _ABSOLUTE_DENSITY_M3:
                return profile.altitudes_m, standard * density / AIR_NUMBER_DENSITY_288K_M3
            return profile.altitudes_m, standard * density
    raise InputError("this atmosphere has no Rayleigh-scattering gas, so its refraction is "
                     "unknown", key="atmosphere", value=profile.names)


def grazing_deflection_rad(profile, tangent_altitudes_m: ArrayLike) -> np.ndarray:
    """Total bending [rad] of rays through the atmosphere of `profile` (an OpticalProfile) whose
    lowest point lies at `tangent_altitudes_m` (n,) [m] (module docstring)."""
    h0 = np.atleast_1d(np.asarray(tangent_altitudes_m, dtype=np.float64))
    altitudes, refractivity = _air_refractivity(profile)
    gradient = np.gradient(refractivity, altitudes)  # d(n - 1)/dh [m⁻¹]
    radius = profile.bottom_radius_m
    top = profile.top_radius_m
    r0 = radius + np.clip(h0, 0.0, top - radius)
    nodes, weights = np.polynomial.legendre.leggauss(_QUADRATURE_NODES)
    span = np.sqrt(np.maximum(top - r0, 0.0))[:, None]  # s in [0, sqrt(r_top - r0)]
    s = 0.5 * span * (nodes + 1.0)
    r = r0[:, None] + s * s
    n = 1.0 + np.interp(r - radius, altitudes, refractivity)
    n0 = 1.0 + np.interp(r0 - radius, altitudes, refractivity)[:, None]
    dn_dr = np.interp(r - radius, altitudes, gradient)
    root = np.sqrt(np.maximum((n * r) ** 2 - (n0 * r0[:, None]) ** 2, 1e-300))
    integrand = -2.0 * n0 * r0[:, None] / root * dn_dr / n * 2.0 * s
    return (integrand * (0.5 * span) * weights).sum(axis=1)


def grazing_transmittance(solver, tangent_altitudes_m: ArrayLike) -> np.ndarray:
    """Transmittance (n, n_wl) [-] of the whole ray tangent at `tangent_altitudes_m` (n,) [m]:
    from the tangent point out of the atmosphere both ways (`solver.transmittance`)."""
    h0 = np.atleast_1d(np.asarray(tangent_altitudes_m, dtype=np.float64))
    top = solver.profile.top_radius_m - solver.profile.bottom_radius_m
    points = np.zeros((h0.size, 3))
    # held 1 m above the ground, where a horizontal ray would graze it
    points[:, 2] = solver.profile.bottom_radius_m + np.clip(h0, 1.0, top)
    forward = np.tile([1.0, 0.0, 0.0], (h0.size, 1))
    return solver.transmittance(points, forward) * solver.transmittance(points, -forward)
