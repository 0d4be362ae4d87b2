"""The allowed range of every number in an atmosphere config, and the reason it ends there.

A value outside its range is refused before any work (`ConfigError`: the file, the key, the
value, the range). The ranges are physical: wide enough for every body from a kilometre-sized
asteroid to a brown dwarf, narrow enough to catch a typo, a wrong unit or a value that would
turn into inf, NaN or an atmosphere lost in rounding (a planet radius of 1e30 m leaves
R + top = R in float64, and the sky came out black). Lengths of lists are capped by what they
cost. docs/config.md lists the same ranges in its tables; `config.load_atmosphere` applies them.

Public names: the `Bounds` below, `MAX_CONSTITUENTS`, `MAX_GASES`, `MAX_LAYERS`,
`MAX_LIST_LENGTH`, `MAX_POLYNOMIAL_COEFFICIENTS`, `MAX_TEXT_LENGTH`, `MAX_EXPONENT`,
`CHECK_WAVELENGTHS_NM`.
"""

from __future__ import annotations

import numpy as np

from skyscatter.checks import Bounds
from skyscatter.spectrum.star import AU_M

__all__ = [
    "ABSORPTION_CROSS_SECTION_M2",
    "ALTITUDE_M",
    "ANGSTROM_EXPONENT",
    "ASYMMETRY",
    "CHECK_WAVELENGTHS_NM",
    "CO2_PPM",
    "COLUMN_DOBSON",
    "DENSITY",
    "DEPOLARIZATION",
    "EXTINCTION_PER_M",
    "FRACTION",
    "GAMMA_SHAPE",
    "GEOMETRIC_STD",
    "GRAVITY_M_S2",
    "JUNGE_EXPONENT",
    "LAYER_ALTITUDE_M",
    "LAYER_EDGE_M",
    "LAYER_RATE_PER_M",
    "LAYER_TERM",
    "LOG_NORMAL_VARIANCE",
    "MAX_CONSTITUENTS",
    "MAX_EXPONENT",
    "MAX_GASES",
    "MAX_LAYERS",
    "MAX_LIST_LENGTH",
    "MAX_POLYNOMIAL_COEFFICIENTS",
    "MAX_TEXT_LENGTH",
    "MODIFIED_GAMMA_VARIANCE",
    "MOLAR_MASS_G_MOL",
    "OPTICAL_DEPTH",
    "PARTICLE_RADIUS_UM",
    "PLANET_MASS_KG",
    "PLANET_RADIUS_M",
    "POLARIZABILITY_M3",
    "REFRACTIVE_INDEX_IMAGINARY",
    "REFRACTIVE_INDEX_REAL",
    "REFRACTIVITY",
    "REFRACTIVITY_NUMBER_DENSITY_M3",
    "SCALE_HEIGHT_M",
    "STAR_DISTANCE_AU",
    "STAR_DISTANCE_M",
    "STAR_RADIUS_M",
    "STAR_TEMPERATURE_K",
    "SURFACE_DENSITY_KG_M3",
    "SURFACE_NUMBER_DENSITY_M3",
    "SURFACE_PRESSURE_PA",
    "SURFACE_TEMPERATURE_K",
    "TOP_ALTITUDE_M",
    "WAVELENGTH_NM",
]

# --- the planet and its star ------------------------------------------------------------------
# From a 1 km asteroid to 1.4 solar radii, above the largest brown dwarfs and inflated hot
# Jupiters (~2 Jupiter radii, 1.4e8 m). The solvers were tried at both ends (finite, positive
# radiance); at 1e30 m the atmosphere vanished in rounding.
PLANET_RADIUS_M = Bounds(1e3, 1e9)
# From a 1 km asteroid (~1e12 kg) to 0.5 solar masses, above the heaviest brown dwarfs (80
# Jupiter masses, 1.5e29 kg). Only [gas] uses it, through g = G M / R^2 (`GRAVITY_M_S2`).
PLANET_MASS_KG = Bounds(1e10, 1e30)
# From a 1 km asteroid (5e-4 m s^-2) to a brown dwarf (log g = 5.5 in cgs: 3e3 m s^-2).
GRAVITY_M_S2 = Bounds(1e-4, 1e4)
# A star-planet distance from 0.001 AU (closer than any known planet, outside the Sun's
# 0.0047 AU radius) to 1e6 AU (16 light years: beyond the Oort cloud a star is no planet's sun;
# at 1e308 AU the sky came out black).
STAR_DISTANCE_AU = Bounds(1e-3, 1e6)
STAR_DISTANCE_M = Bounds(1e-3 * AU_M, 1e6 * AU_M)
# From the coolest brown dwarfs (T dwarfs, ~500 K; cooler bodies send no visible light) to
# hotter than the hottest white dwarfs (~2.5e5 K).
STAR_TEMPERATURE_K = Bounds(500.0, 1e6)
# From a neutron star (1e4 m; 1e3 for margin) to the largest red supergiants (UY Scuti,
# 1.2e12 m).
STAR_RADIUS_M = Bounds(1e3, 1e13)
# The height of the atmosphere: from 1 m to 1e8 m (Earth's hydrogen geocorona reaches ~15
# Earth radii). The solvers were tried from 1 m to 1e9 m.
TOP_ALTITUDE_M = Bounds(1.0, 1e8)

# --- [gas] --------------------------------------------------------------------------------------
# Surface temperatures from 10 K (colder than Triton's and Pluto's 38-40 K) to 1e4 K (above
# the hottest known planet, KELT-9b, 4600 K; hotter, molecules dissociate).
SURFACE_TEMPERATURE_K = Bounds(10.0, 1e4)
# From 1e-6 Pa (thinner than Io's 1e-4 Pa; the Rayleigh optical depth is then < 1e-11) to
# 1e8 Pa = 1 kbar (Venus: 9.2e6 Pa; beyond ~1 kbar the ideal gas law of [gas] fails).
SURFACE_PRESSURE_PA = Bounds(1e-6, 1e8)
# The same span as mass and number densities: 1e-14 kg m^-3 (1e-6 Pa of H2 at 1e4 K) to
# 1e3 kg m^-3 (liquid water; Venus' surface air is 65 kg m^-3); 1e12 to 1e29 m^-3 (liquid water
# has 3.3e28 m^-3).
SURFACE_DENSITY_KG_M3 = Bounds(1e-14, 1e3)
SURFACE_NUMBER_DENSITY_M3 = Bounds(1e12, 1e29)
# Mole fractions, volume fractions, albedos, single-scattering albedos, Henyey-Greenstein
# weights: fractions of a whole.
FRACTION = Bounds(0.0, 1.0)
# From the hydrogen atom (1.008 g/mol) to 1000 g/mol (UF6 has 352).
MOLAR_MASS_G_MOL = Bounds(1.0, 1e3)
# n - 1 of gases at their reference density: 3.5e-5 (He) to ~1e-3 (heavy molecules); 0.1 is a
# liquid's order of magnitude.
REFRACTIVITY = Bounds(0.0, 0.1, low_open=True)
# Number density at which a refractivity was measured: 2.55e25 m^-3 at 15 degC and 1 atm.
REFRACTIVITY_NUMBER_DENSITY_M3 = Bounds(1e20, 1e29)
# Polarisability volumes: helium 2.05e-31 m^3 is the smallest of any atom or molecule; 1e-27
# m^3 (1000 A^3) is above any gas molecule's.
POLARIZABILITY_M3 = Bounds(1e-32, 1e-27)
# Depolarisation ratio delta: the King factor (6 + 3 delta) / (6 - 7 delta) has its pole at
# 6/7; measured gases have delta < 0.1 (CO2 0.08).
DEPOLARIZATION = Bounds(0.0, 0.5)
# CO2 in "air" optics [ppm]: Bodhaine's (1999) correction of air's refractive index and King
# factor is linear in the CO2 fraction, for air; at more than 1 % CO2 describe the gas in [gas].
CO2_PPM = Bounds(0.0, 1e4)

# --- density profiles ---------------------------------------------------------------------------
# Exponential scale heights: 1 m (a thinner layer is below every level spacing of the solvers)
# to 1e9 m (flat over any atmosphere).
SCALE_HEIGHT_M = Bounds(1.0, 1e9, low_open=False)
# Densities [m^-3, or relative]: up to 1e30 m^-3 (a liquid has 3e28); relative ones are ~1.
DENSITY = Bounds(0.0, 1e30)
# Profile altitudes (tables, layer tops): 1e5 m below the ground (no surface is that deep) to
# 1e9 m (ten times the highest top).
ALTITUDE_M = Bounds(-1e5, 1e9)
# Base and top of a uniform layer (`type = "layer"`): on or above the ground, up to 1e9 m like
# other profile altitudes; the top must also lie inside the atmosphere (checked by the loader).
LAYER_ALTITUDE_M = Bounds(0.0, 1e9)
# Width of a layer's smooth edges: 0 (sharp) up to the layer's thickness (checked by the loader).
LAYER_EDGE_M = Bounds(0.0, 1e9)
# Bruneton's layer d = clamp(exp_term e^(exp_scale_per_m h) + linear_per_m h + constant, 0, 1):
# the terms matter near [0, 1] only. Rates up to 1 m^-1 (a 1 m feature); terms up to 1e6.
LAYER_RATE_PER_M = Bounds(-1.0, 1.0)
LAYER_TERM = Bounds(-1e6, 1e6)
# exp_scale_per_m x top_altitude_m <= 700: e^709 is the largest float64.
MAX_EXPONENT = 700.0
# A Dobson column [DU]: Earth's ozone ~300, the CO2 of Venus' whole atmosphere ~5e10.
COLUMN_DOBSON = Bounds(0.0, 1e12)

# --- optics -------------------------------------------------------------------------------------
# Vertical optical depth, ground to top, of one constituent: Venus' clouds, the thickest of the
# solar system, have ~30; under 1000 no light gets through within the 1000 scattering orders
# the tables may iterate (diffuse light through tau takes ~tau^2 orders).
OPTICAL_DEPTH = Bounds(0.0, 1e3)
# Extinction or scattering per unit density [m^-1 for a relative profile; m^2 per particle]:
# the densest fog is ~0.1 m^-1 (visibility 40 m); 10 m^-1 is a visibility of 40 cm.
EXTINCTION_PER_M = Bounds(0.0, 10.0)
# Absorption cross-sections [m^2]: 1000 times the strongest molecular band of the atmospheres
# here (ozone's Hartley band, 1.1e-21 m^2); a cm^2 value given as m^2 is often caught.
ABSORPTION_CROSS_SECTION_M2 = Bounds(0.0, 1e-18)
# Angstrom exponents: aerosols measure -1 to 3 (coarse dust to fine smoke), molecules 4.
ANGSTROM_EXPONENT = Bounds(-3.0, 6.0)
# Asymmetry parameters: |g| = 1 is a delta function, which the phase tables cannot hold.
ASYMMETRY = Bounds(-0.999999, 0.999999)
# Wavelengths in a config (tables, polynomial ranges, reference wavelengths) [nm]: from the
# extreme ultraviolet (10 nm) to the far infrared (1e5 nm = 100 µm). skyscatter uses spectra at
# 280.5-1690 nm; measured tables may reach further. Micrometres given as nm (0.55) are caught,
# and a spectral polynomial is tabulated on at most 1e4 points.
WAVELENGTH_NM = Bounds(10.0, 1e5)
# Particle radii [µm]: from a 1 nm cluster to a 1 cm raindrop (Mie is refused beyond size
# parameter 2000, r = 115 µm at 360 nm, with its own message).
PARTICLE_RADIUS_UM = Bounds(1e-3, 1e4)
# Log-normal widths: sigma_g from 1.01 (narrower is one radius to 1 %) to 10 (aerosol modes
# have 1.5-2.5), and v_eff = exp(ln^2 sigma_g) - 1 from 1e-4 (sigma_g = 1.01) to 10
# (sigma_g = 4.7).
GEOMETRIC_STD = Bounds(1.01, 10.0)
LOG_NORMAL_VARIANCE = Bounds(1e-4, 10.0)
# Gamma shapes k: below ~0.02 the lower end of the radius quadrature (the 1e-6 quantile)
# underflows to 0 m; 0.1 leaves margin. Up to 1e6 (nearly one radius).
GAMMA_SHAPE = Bounds(0.1, 1e6)
# Hansen & Travis' effective variance b: the gamma shape is (1 - 2b) / b, >= 0.1 for b <= 0.45
# (measured dust and clouds have 0.05-0.4: Tomasko et al. 1999's Mars dust 0.2-0.4).
MODIFIED_GAMMA_VARIANCE = Bounds(0.0, 0.45, low_open=True)
# Junge exponents nu: continental aerosol ~3 (Junge 1955); -5 to 10 covers any fit.
JUNGE_EXPONENT = Bounds(-5.0, 10.0)
# Refractive index m = n + i k of particles: n from 0.01 (metals have n < 1: silver 0.05) to 10
# (hematite ~3, silicon 4); k from 0 to 10 (metals ~3-4, soot 0.8).
REFRACTIVE_INDEX_REAL = Bounds(0.01, 10.0)
REFRACTIVE_INDEX_IMAGINARY = Bounds(0.0, 10.0)

# --- lengths --------------------------------------------------------------------------------
# Constituents, including a [gas] table's: the presets have at most 3. Each scattering
# constituent adds one channel to the 4-D scattering table (5.2 MB per wavelength at Bruneton's
# table size, 84 MB at the default 16 wavelengths) and ~6 % of a one-constituent precomputation
# (measured at 1/4 table size: 1 constituent 1.0 s, 16 1.7 s, 64 4.6 s, 256 22 s). 16 make a
# 1.4 GB table at 16 wavelengths; 20 000 would need 1.7 TB and days.
MAX_CONSTITUENTS = 16
# Gases in [gas] composition and [[gas.species]]: Earth's dry air has 10 above 1 ppm.
MAX_GASES = 64
# Layers of a "layers" profile (Bruneton's have 2); more is a table: type = "table".
MAX_LAYERS = 100
# Entries of a list (profile table rows, spectral tables, refractive-index tables): 1e5 rows
# resolve 1 m in a 100 km atmosphere, whose solvers sample 2001 levels.
MAX_LIST_LENGTH = 100_000
# Coefficients of a spectral polynomial in lambda [nm]: Meyran's fits are quadratics; at degree
# 8, lambda^8 ~ 2e23 at 830 nm and the terms cancel below float64 precision.
MAX_POLYNOMIAL_COEFFICIENTS = 9
# Characters of a name, a description or another string value.
MAX_TEXT_LENGTH = 1000

# Wavelengths [nm] at which a loaded atmosphere is checked (finite optics, vertical optical
# depth within `OPTICAL_DEPTH`): skyscatter's spectral range, 280.5-1690 nm, every ~20 nm.
CHECK_WAVELENGTHS_NM = np.linspace(280.5, 1690.0, 72)
