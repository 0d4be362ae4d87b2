"""Variants of an atmosphere for comparisons: some constituents only, or one constituent's
amount scaled ("a dustier Mars", "Earth without aerosol").

Public names: `only_constituents`, `scaled_constituent`, `load_variant`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from skyscatter.atmosphere.config import load_atmosphere
from skyscatter.atmosphere.model import Atmosphere
from skyscatter.atmosphere.profiles import ScaledProfile
from skyscatter.checks import Bounds
from skyscatter.errors import InputError

__all__ = ["SCALE_FACTOR", "load_variant", "only_constituents", "scaled_constituent"]

# A constituent's amount times 0 (removed) to 1e6: a million times any constituent's amount is
# beyond every comparison; inf or NaN would reach the solvers as NaN optics.
SCALE_FACTOR = Bounds(0.0, 1e6)


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
