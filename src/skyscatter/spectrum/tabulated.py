"""Quantities that are either one number or a table over wavelength.

Configs give many optical parameters per wavelength (Costa 2020 Table 1 lists values at
680/550/440 nm). `SpectralParameter` holds either form and evaluates on any grid by linear
interpolation in wavelength, held constant outside the tabulated range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["SpectralParameter"]


@dataclass(frozen=True)
class SpectralParameter:
    """A scalar, or values at tabulated wavelengths [nm] (ascending after construction)."""

    values: tuple[float, ...]
    wavelengths_nm: tuple[float, ...] | None = None

    @classmethod
    def constant(cls, value: float) -> SpectralParameter:
        return cls((float(value),), None)

    @classmethod
    def table(cls, wavelengths_nm: ArrayLike, values: ArrayLike) -> SpectralParameter:
        wl = np.asarray(wavelengths_nm, dtype=np.float64).ravel()
        v = np.asarray(values, dtype=np.float64).ravel()
        if wl.size != v.size or wl.size == 0:
            raise ValueError("wavelengths and values must have the same, non-zero length")
        order = np.argsort(wl)
        return cls(tuple(v[order]), tuple(wl[order]))

    @property
    def is_constant(self) -> bool:
        return self.wavelengths_nm is None

    def at(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        """Values on `wavelengths_nm` [nm]; result has the shape of the input."""
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        if self.wavelengths_nm is None:
            return np.full(wl.shape, self.values[0])
        return np.interp(wl, self.wavelengths_nm, self.values)
