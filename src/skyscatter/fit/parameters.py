"""The free parameters of a fit: config values named by dotted key, with bounds and a start.

    KEY=LOW:HIGH          start at the config's own value (the middle of the bounds when the
                          config's value lies outside them)
    KEY=LOW:HIGH:START    start at START

e.g. `constituent[2].optics.optical_depth=0.01:1.0:0.1`. The key must name a number of the
config (`atmosphere.config_overrides.get_value`); LOW < HIGH, finite, and START within them.

Public names: `FreeParameter`, `parse_free`, `checked_free`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from skyscatter.atmosphere.config_overrides import get_value
from skyscatter.errors import InputError

__all__ = ["FreeParameter", "checked_free", "parse_free"]

_ALLOWED = "KEY=LOW:HIGH or KEY=LOW:HIGH:START, e.g. planet.ground_albedo=0:0.5"


@dataclass(frozen=True)
class FreeParameter:
    """One fitted config value: its dotted key, bounds and start (in the key's own unit)."""

    key: str
    low: float
    high: float
    start: float | None = None

    @property
    def width(self) -> float:
        """HIGH - LOW."""
        return self.high - self.low


def parse_free(text: str) -> FreeParameter:
    """`KEY=LOW:HIGH[:START]` as a FreeParameter; InputError naming what is wrong."""
    key, sign, bounds = text.partition("=")
    fields = bounds.split(":")
    if not sign or not key.strip() or len(fields) not in (2, 3):
        raise InputError(f"--free {text!r}: give {_ALLOWED}", key="free", value=text,
                         allowed=_ALLOWED)
    try:
        numbers = [float(field) for field in fields]
    except ValueError:
        raise InputError(f"--free {text!r}: LOW, HIGH and START must be numbers", key="free",
                         value=text, allowed=_ALLOWED) from None
    return FreeParameter(key.strip(), numbers[0], numbers[1],
                         numbers[2] if len(numbers) == 3 else None)


def checked_free(free: Sequence[FreeParameter | str], document: Mapping[str, Any]
                 ) -> list[FreeParameter]:
    """The free parameters with their starts filled in from `document`; InputError for a
    key that is not a number of the config, a key given twice, reversed or infinite bounds,
    or a start outside the bounds."""
    if not free:
        raise InputError("no free parameter: give at least one --free KEY=LOW:HIGH",
                         key="free", allowed=_ALLOWED)
    checked: list[FreeParameter] = []
    for item in free:
        parameter = parse_free(item) if isinstance(item, str) else item
        if not isinstance(parameter, FreeParameter):
            raise InputError(f"free parameter {item!r}: give {_ALLOWED}", key="free",
                             value=item, allowed=_ALLOWED)
        key = parameter.key
        if any(p.key == key for p in checked):
            raise InputError(f"--free {key} is given twice", key="free", value=key)
        value = get_value(document, key)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise InputError(f"--free {key}: the config's value {value!r} is not a number; "
                             "only numbers can be fitted", key="free", value=key)
        low, high = parameter.low, parameter.high
        if not (math.isfinite(low) and math.isfinite(high)) or not low < high:
            raise InputError(f"--free {key}={low:g}:{high:g}: the bounds must be finite with "
                             "LOW < HIGH", key="free", value=key, allowed=_ALLOWED)
        start = parameter.start
        if start is None:
            start = float(value) if low <= value <= high else 0.5 * (low + high)
        elif not (math.isfinite(start) and low <= start <= high):
            raise InputError(f"--free {key}: START {start:g} lies outside the bounds "
                             f"{low:g}:{high:g}", key="free", value=key, allowed=_ALLOWED)
        checked.append(FreeParameter(key, low, high, float(start)))
    return checked
