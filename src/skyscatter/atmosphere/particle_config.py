"""The `type = "mie"` optics of a config constituent: particles from physical parameters.

A size distribution, a refractive index (a shipped material, a constant or a table, optionally
with an inclusion mixed in by Maxwell Garnett) and the Mie options become a `MieOptics`
(`optics.mie`), computed once and cached on disk. docs/config.md documents the keys.
"""

from __future__ import annotations

import numpy as np

from skyscatter.atmosphere import config_ranges as ranges
from skyscatter.atmosphere.config_table import ConfigTable
from skyscatter.checks import Bounds
from skyscatter.errors import ConfigError, InputError
from skyscatter.optics.mie import (
    METHODS,
    MIE_WAVELENGTHS_NM,
    PHASE_AVERAGES,
    MieOptics,
    particle_optics,
)
from skyscatter.optics.particle_index import (
    MATERIALS,
    ComplexIndex,
    load_material,
    maxwell_garnett,
)
from skyscatter.optics.phase import PhaseFunction
from skyscatter.optics.size_distribution import (
    Gamma,
    JungePowerLaw,
    LogNormal,
    ModifiedGamma,
    SizeDistribution,
)

__all__ = ["MIE_WAVELENGTHS_NM", "parse_mie_optics"]

# Wavelengths [nm] of the Mie table of a config: Meyran 2022's 10 nm grid from 360 nm, extended to
# 900 nm so that the 880 nm filter of the Mars rovers is inside it.
MIE_REFERENCE_NM = Bounds(float(MIE_WAVELENGTHS_NM[0]), float(MIE_WAVELENGTHS_NM[-1]))
MICROMETRE_M = 1e-6
DISTRIBUTIONS = ("log-normal", "gamma", "modified-gamma", "junge")


def parse_mie_optics(table: ConfigTable, blend: PhaseFunction | None
                     ) -> tuple[MieOptics, float | None]:
    """(optics, vertical column [m^-2] or None) from an optics table of `type = "mie"`; the
    column is optical_depth / C_ext(reference wavelength) when `optical_depth` is given.
    `blend` is the already parsed `blend` phase table (or None)."""
    size_table = table.table("size_distribution")
    distribution = _parse_distribution(size_table)
    index_table = table.table("refractive_index")
    index = _parse_index(index_table)
    index_table.finish()
    inclusion_table = table.table("inclusion", required=False)
    if inclusion_table is not None:
        fraction = inclusion_table.number("volume_fraction", ranges.FRACTION)
        index = maxwell_garnett(index, _parse_index(inclusion_table), fraction)
        inclusion_table.finish()
    n_radii = table.integer("radii", 5000, low=16, high=100_000)
    phase_average = table.text("phase_average", "scattering", PHASE_AVERAGES)
    method = table.text("method", "mie", METHODS)
    optical_depth = None
    if table.has("optical_depth"):
        optical_depth = table.number("optical_depth", ranges.OPTICAL_DEPTH)
        reference_nm = table.number("reference_wavelength_nm", MIE_REFERENCE_NM, 550.0)
    try:
        particles = particle_optics(distribution, index, MIE_WAVELENGTHS_NM, n_radii=n_radii,
                                    phase_average=phase_average, method=method)
    except InputError as error:
        if error.key != "distribution":
            raise
        raise _too_large(size_table, error) from None
    optics = MieOptics(particles, blend=blend)
    column = None
    if optical_depth is not None:
        column = optical_depth / float(optics.extinction_per_density(np.array([reference_nm]))[0])
    return optics, column


def _too_large(size_table: ConfigTable, error: InputError) -> ConfigError:
    """The size-parameter limit of the Mie code, said in the config's own keys: the radii that
    made the particles too large."""
    radius_keys = sorted(key for key in size_table.asked if key.endswith("_um"))
    return ConfigError(f"{size_table.prefix}: {error}: make {' or '.join(radius_keys)} smaller",
                       path=size_table.path, key=f"{size_table.prefix}.{radius_keys[0]}",
                       value=error.value, allowed=error.allowed)


def _parse_distribution(table: ConfigTable) -> SizeDistribution:
    kind = table.text("type", choices=DISTRIBUTIONS)
    radius = ranges.PARTICLE_RADIUS_UM
    if kind == "log-normal":
        if table.has("effective_radius_um"):
            distribution = LogNormal.from_effective(
                table.number("effective_radius_um", radius) * MICROMETRE_M,
                table.number("effective_variance", ranges.LOG_NORMAL_VARIANCE))
        else:
            distribution = LogNormal(table.number("median_radius_um", radius) * MICROMETRE_M,
                                     table.number("geometric_std", ranges.GEOMETRIC_STD))
    elif kind == "gamma":
        distribution = Gamma(table.number("shape", ranges.GAMMA_SHAPE),
                             table.number("scale_um", radius) * MICROMETRE_M)
    elif kind == "modified-gamma":
        distribution = ModifiedGamma(table.number("effective_radius_um", radius) * MICROMETRE_M,
                                     table.number("effective_variance",
                                                  ranges.MODIFIED_GAMMA_VARIANCE))
    else:
        distribution = JungePowerLaw(table.number("exponent", ranges.JUNGE_EXPONENT),
                                     table.number("min_radius_um", radius) * MICROMETRE_M,
                                     table.number("max_radius_um", radius) * MICROMETRE_M)
    table.finish()
    return distribution


def _parse_index(table: ConfigTable) -> ComplexIndex:
    """`material = "name"`, or `real`/`imaginary` numbers, or lists with `wavelength_nm`
    (the caller finishes the table)."""
    if table.has("material"):
        return load_material(table.text("material", choices=MATERIALS))
    if table.has("wavelength_nm"):
        wavelengths = table.numbers("wavelength_nm", ranges.WAVELENGTH_NM)
        real = table.numbers("real", ranges.REFRACTIVE_INDEX_REAL)
        imaginary = table.numbers("imaginary", ranges.REFRACTIVE_INDEX_IMAGINARY)
        if not wavelengths.size == real.size == imaginary.size:
            raise table.error("real", real.tolist(),
                              "wavelength_nm, real and imaginary of the same length")
        return ComplexIndex.table(wavelengths, real, imaginary)
    return ComplexIndex.constant(table.number("real", ranges.REFRACTIVE_INDEX_REAL),
                                 table.number("imaginary", ranges.REFRACTIVE_INDEX_IMAGINARY,
                                              0.0))
