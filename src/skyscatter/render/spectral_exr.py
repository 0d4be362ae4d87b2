"""Spectral EXR channels in the layout of Fichet, Pacanowski & Wilkie (2021), "An OpenEXR
layout for spectral images", JCGT 10(3), 1-18, https://jcgt.org/published/0010/03/01/, which
spectral renderers and viewers (ART, pbrt-v4, Mitsuba's tools, the authors' Spectral Viewer)
read.

An emissive (radiance) image holds, per wavelength, a channel `S0.<wavelength><unit>`: S0 the
first Stokes component (the unpolarised radiance), the wavelength a decimal number with a
comma, not a point, before its fraction (OpenEXR reads a point as a layer separator), and the
unit with an SI prefix, here `nm`: `S0.550,000000nm` (six decimals, as the authors' reference
implementation writes them). The header carries `spectralLayoutVersion` = "1.0" and
`emissiveUnits` = "W.m^-2.sr^-1" (the layout's only emissive unit; each channel holds the
spectral radiance per nm at its wavelength, W m^-2 sr^-1 nm^-1). The layout recommends R, G, B
channels beside the spectra, for viewers that do not read them.
"""

from __future__ import annotations

__all__ = ["FICHET2021_ATTRIBUTES", "fichet2021_channel_name"]

FICHET2021_ATTRIBUTES = {"spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1"}


def fichet2021_channel_name(wavelength_nm: float) -> str:
    """`S0.<wavelength>nm` with a decimal comma and six decimals (module docstring)."""
    return "S0." + f"{wavelength_nm:.6f}".replace(".", ",") + "nm"
