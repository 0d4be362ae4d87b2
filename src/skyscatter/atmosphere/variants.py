"""Variants of an atmosphere for comparisons: some constituents only, or one constituent's
amount scaled ("a dustier Mars", "Earth without aerosol"), or one constituent's phase function
replaced by a Henyey-Greenstein one ("Mars with HG dust").

Public names: `only_constituents`, `scaled_constituent`, `with_hg_phase`,
`with_ground_albedo`, `load_variant`, `mars_hg_dust`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.config_ranges import FRACTION
from skyscatter.atmosphere.model import Atmosphere, ConstituentOptics
from skyscatter.atmosphere.profiles import ScaledProfile
from skyscatter.checks import Bounds
from skyscatter.errors import InputError
from skyscatter.optics.phase import HenyeyGreensteinPhase
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = ["MARS_HG_DUST_G", "SCALE_FACTOR", "load_variant", "mars_hg_dust", "only_constituents",
           "scaled_constituent", "with_ground_albedo", "with_hg_phase"]

# A constituent's amount times 0 (removed) to 1e6: a million times any constituent's amount is
# beyond every comparison; inf or NaN would reach the solvers as NaN optics.
SCALE_FACTOR = Bounds(0.0, 1e6)
# Asymmetry parameter of the Henyey-Greenstein stand-in for Martian dust: the "dusty Mars,
# HG g 0.65" case of issue 17's error table (a test medium, not a retrieval; mars-physical's
# Mie dust, whose phase it replaces, is sourced in its preset).
MARS_HG_DUST_G = 0.65


@dataclass(frozen=True)
class _HgOptics:
    """Another constituent's extinction and scattering, with a Henyey-Greenstein phase."""

    inner: ConstituentOptics
    phase: HenyeyGreensteinPhase

    def extinction_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return self.inner.extinction_per_density(wavelengths_nm)

    def scattering_per_density(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return self.inner.scattering_per_density(wavelengths_nm)


def _check_names(atmosphere: Atmosphere, names: Sequence[str]) -> None:
    known = [c.name for c in atmosphere.constituents]
    for name in names:
        if name not in known:
            raise InputError(f"{atmosphere.name} has no constituent {name!r}; it has "
                             f"{', '.join(known)}", key="constituent", value=name,
                             allowed=", ".join(known))


def only_constituents(atmosphere: Atmosphere, names: Sequence[str],
                      label: str | None = None) -> Atmosphere:
    """`atmosphere` with only the constituents `names` (the others removed), called `label`
    (default: 'NAME[air+ozone]')."""
    _check_names(atmosphere, names)
    kept = tuple(c for c in atmosphere.constituents if c.name in names)
    return replace(atmosphere, constituents=kept,
                   name=label or f"{atmosphere.name}[{'+'.join(names)}]")


def scaled_constituent(atmosphere: Atmosphere, name: str, factor: float,
                       label: str | None = None) -> Atmosphere:
    """`atmosphere` with the density (or the prescribed column) of constituent `name` times
    `factor` (`SCALE_FACTOR`: 0 to 1e6), called `label` (default: 'NAME:CONSTITUENT*FACTOR')."""
    _check_names(atmosphere, [name])
    factor = SCALE_FACTOR.check(f"the factor of {name}", factor)
    scaled = tuple(
        c if c.name != name else
        replace(c, vertical_column=c.vertical_column * factor) if c.vertical_column is not None
        else replace(c, profile=ScaledProfile(c.profile, factor))
        for c in atmosphere.constituents)
    return replace(atmosphere, constituents=scaled,
                   name=label or f"{atmosphere.name}:{name}*{factor:g}")


def with_hg_phase(atmosphere: Atmosphere, name: str, g: float,
                  label: str | None = None) -> Atmosphere:
    """`atmosphere` with the phase function of constituent `name` replaced by a
    Henyey-Greenstein one of asymmetry `g` (-1 < g < 1), its extinction and scattering kept,
    called `label` (default: 'NAME:CONSTITUENT~hg(G)')."""
    _check_names(atmosphere, [name])
    phase = HenyeyGreensteinPhase(g)
    changed = tuple(replace(c, optics=_HgOptics(c.optics, phase)) if c.name == name else c
                    for c in atmosphere.constituents)
    return replace(atmosphere, constituents=changed,
                   name=label or f"{atmosphere.name}:{name}~hg({g:g})")


def with_ground_albedo(atmosphere: Atmosphere, albedo: float,
                       label: str | None = None) -> Atmosphere:
    """`atmosphere` over a grey Lambertian ground of `albedo` (0 to 1) at every wavelength, in
    place of its planet's, called `label` (default: 'NAME:ground=ALBEDO'). The ground lights
    the sky too, so its tables are those of the new ground."""
    albedo = FRACTION.check("the ground albedo", albedo)
    planet = replace(atmosphere.planet, ground_albedo=SpectralParameter.constant(albedo))
    return replace(atmosphere, planet=planet,
                   name=label or f"{atmosphere.name}:ground={albedo:g}")


def mars_hg_dust() -> Atmosphere:
    """`mars-physical` with its Mie dust's phase function replaced by Henyey-Greenstein
    g = `MARS_HG_DUST_G` (optical depth 0.5 kept), called 'mars-hg-dust': a forward-peaked
    medium without the Mie peak's narrow spike (issue 17's "dusty Mars, HG g 0.65")."""
    return with_hg_phase(load_atmosphere("mars-physical"), "dust", MARS_HG_DUST_G,
                         label="mars-hg-dust")


def load_variant(spec: str) -> Atmosphere:
    """A preset or config, or `NAME:CONSTITUENT*FACTOR` (that constituent's amount times
    FACTOR), e.g. `mars-costa:dust*5` for a dustier Mars."""
    name, _, change = spec.partition(":")
    atmosphere = load_atmosphere(name)
    if not change:
        return atmosphere
    constituent, _, factor_text = change.partition("*")
    try:
        factor = float(factor_text)
    except ValueError:
        raise InputError(f"{spec!r}: expected NAME:CONSTITUENT*FACTOR, e.g. "
                         "'mars-costa:dust*5'", key="atmosphere", value=spec) from None
    return scaled_constituent(atmosphere, constituent, factor, label=spec)
