"""The CIE standard general sky (CIE S 011/E:2003 = ISO 15469:2004) and how close a computed
clear sky comes to it.

Relative luminance of a sky element at zenith angle Z, at angular distance chi from the sun
whose zenith angle is Zs:

    L / L_z = f(chi) phi(Z) / (f(Zs) phi(0)),
    phi(Z)  = 1 + a exp(b / cos Z)                        (gradation)
    f(chi)  = 1 + c [exp(d chi) - exp(d pi / 2)] + e cos^2 chi   (indicatrix)

Coefficients of the clear-sky types from the standard's Table 1, as digested in
shared/research/reference-data.md §1.2 (verified against three public implementations there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.colour import luminance
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.transport.single_scattering import observer_position

__all__ = ["CIE_SKY_TYPES", "CieFit", "cie_relative_luminance", "compare_with_cie"]

# type: (a, b, c, d, e, description), CIE S 011/E:2003 Table 1
CIE_SKY_TYPES = {
    11: (-1.0, -0.55, 10.0, -3.0, 0.45, "white-blue sky with distinct solar corona"),
    12: (-1.0, -0.32, 10.0, -3.0, 0.45, "CIE standard clear sky, low luminance turbidity"),
    13: (-1.0, -0.32, 16.0, -3.0, 0.30, "CIE standard clear sky, polluted atmosphere"),
}


def cie_relative_luminance(sky_type: int, view_zenith_rad: ArrayLike,
                           sun_angle_rad: ArrayLike, sun_zenith_rad: float) -> np.ndarray:
    """L / L_zenith of CIE sky `sky_type` at view zenith angles Z < 90 deg and angular
    distances chi from the sun (module docstring)."""
    if sky_type not in CIE_SKY_TYPES:
        raise InputError(f"CIE sky type {sky_type!r} is not tabulated here; choose one of "
                         f"{', '.join(map(str, CIE_SKY_TYPES))}", key="sky_type",
                         value=sky_type)
    a, b, c, d, e, _ = CIE_SKY_TYPES[sky_type]
    zenith = np.asarray(view_zenith_rad, dtype=np.float64)
    chi = np.asarray(sun_angle_rad, dtype=np.float64)

    def gradation(z: np.ndarray | float) -> np.ndarray:
        return 1.0 + a * np.exp(b / np.cos(z))

    def indicatrix(x: np.ndarray | float) -> np.ndarray:
        return 1.0 + c * (np.exp(d * x) - np.exp(d * np.pi / 2.0)) + e * np.cos(x) ** 2

    return (indicatrix(chi) * gradation(zenith)
            / (indicatrix(sun_zenith_rad) * gradation(0.0)))


@dataclass(frozen=True)
class CieFit:
    """A computed sky's relative luminance against each CIE type, for one sun zenith."""

    sun_zenith_deg: float
    view_zenith_deg: np.ndarray  # (n_z,)
    azimuth_deg: np.ndarray  # (n_a,) from the sun
    relative_luminance: np.ndarray  # (n_z, n_a) ours, L / L_zenith
    cie: dict[int, np.ndarray]  # type -> (n_z, n_a)
    rms: dict[int, float]  # type -> root-mean-square of ours / CIE - 1

    @property
    def closest_type(self) -> int:
        return min(self.rms, key=self.rms.get)


def compare_with_cie(solver, sun_zenith_deg: float,
                     view_zenith_deg: ArrayLike = tuple(range(0, 81, 10)),
                     azimuth_deg: ArrayLike = tuple(range(0, 181, 30)),
                     min_sun_distance_deg: float = 10.0) -> CieFit:
    """Our sky's luminance pattern from a ground observer (`solver.sky_radiance`, luminance
    from the CIE 1931 weights) against each CIE clear-sky type. Directions within
    `min_sun_distance_deg` of the sun are left out of the RMS (the aureole, where the types'
    indicatrix is steepest and a pixel's position matters most)."""
    profile = solver.profile
    zenith = np.radians(np.asarray(view_zenith_deg, dtype=np.float64))
    azimuth = np.radians(np.asarray(azimuth_deg, dtype=np.float64))
    z, a = np.meshgrid(zenith, azimuth, indexing="ij")
    sun_zenith = np.radians(sun_zenith_deg)
    views = local_frame_directions(z, a)
    sun = local_frame_directions(np.array(sun_zenith), np.array(0.0))
    origin = observer_position(0.0, profile.bottom_radius_m)
    radiance = solver.sky_radiance(origin, views, sun)
    zenith_radiance = solver.sky_radiance(origin, np.array([0.0, 0.0, 1.0]), sun)
    ours = (luminance(radiance, profile.wavelengths_nm)
            / luminance(zenith_radiance, profile.wavelengths_nm))
    chi = np.arccos(np.clip(views @ sun, -1.0, 1.0))
    use = chi > np.radians(min_sun_distance_deg)
    cie = {t: cie_relative_luminance(t, z, chi, sun_zenith) for t in CIE_SKY_TYPES}
    rms = {t: float(np.sqrt(np.mean((ours[use] / cie[t][use] - 1.0) ** 2))) for t in cie}
    return CieFit(float(sun_zenith_deg), np.degrees(zenith), np.degrees(azimuth), ours, cie,
                  rms)
