"""Optical properties of atmospheric constituents, per unit density and per wavelength.

refractive_index  n - 1 of air, N2, O2, Ar, CO2, H2, He, CH4 and the number density each holds at
rayleigh          King factors, Rayleigh cross-sections, `RayleighOptics`, tabulated coefficients
gases             molar masses, custom gases, `GasMixture` (Rayleigh optics of a gas mixture)
absorption        ozone cross-section (Malicet/Brion 295 K), `AbsorberOptics`
aerosol           Ångström law, `AngstromOptics`
phase             phase-function kernels (numba) and `PhaseFunction` objects
size_distribution particle size distributions and their radius quadratures
particle_index    complex refractive indices of particle materials, Maxwell Garnett mixing
mie               Mie theory (and ADA) for a particle population, `MieOptics`

Import from the submodules (`from skyscatter.optics.rayleigh import RayleighOptics`).
"""
