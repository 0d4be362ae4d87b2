"""Optical properties of atmospheric constituents, per unit density and per wavelength.

refractive_index  n - 1 of air and CO2 and the number density each formula holds at
rayleigh          King factors, Rayleigh cross-sections, `RayleighOptics`, tabulated coefficients
absorption        ozone cross-section (Malicet/Brion 295 K), `AbsorberOptics`
aerosol           Ångström law, `AngstromOptics`
phase             phase-function kernels (numba) and `PhaseFunction` objects

Import from the submodules (`from skyscatter.optics.rayleigh import RayleighOptics`).
"""
