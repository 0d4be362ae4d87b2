"""Complex refractive index of particle materials, and the Maxwell Garnett mixing rule.

Convention: m = n + i k with k >= 0 for an absorbing material (Bohren & Huffman 1983,
"Absorption and Scattering of Light by Small Particles", Wiley, doi:10.1002/9783527618156,
whose fields vary as exp(-i omega t)). Libraries with the other sign (miepython: n - i k) get
the conjugate at the call (`optics.mie`), nowhere else.

`ComplexIndex` holds a constant index or a table over wavelength, interpolated linearly in n and
k and held constant outside the table (as `spectrum.tabulated.SpectralParameter`).
`load_material(name)` returns the shipped materials (`MATERIALS`; sources in
skyscatter/data/PROVENANCE.md):

    hematite          alpha-Fe2O3, 360-830 nm (CosmoScout VR mars_ehlers.json, a stand-in for
                      the Amsterdam-Granada database data of Meyran 2022's Mars thesis)
    water             liquid water, 300-1000 nm (Segelstein 1981, via PyPI miepython)
    soot              1.95 + 0.79 i at all wavelengths (Bond & Bergstrom 2006)
    mars-dust-costa   n = 1.52, k = 0.013/0.006/0.001 at 440/550/680 nm (Costa et al. 2020)

`maxwell_garnett` mixes an inclusion into a host (Maxwell Garnett 1904; Bohren & Huffman §8.5).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from importlib import resources

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "MATERIALS",
    "SOOT_BOND_BERGSTROM_2006",
    "ComplexIndex",
    "load_material",
    "maxwell_garnett",
]


@dataclass(frozen=True)
class ComplexIndex:
    """Complex refractive index m = n + i k (k >= 0), constant or tabulated over wavelength.

    Build with `ComplexIndex.constant(n, k)` or `ComplexIndex.table(wavelengths_nm, n, k)`;
    the fields are tuples (hashable, exact in `repr`, which cache keys use).

    Parameters
    ----------
    n : tuple of float
        Real part(s), > 0. [-]
    k : tuple of float
        Imaginary part(s), >= 0. [-]
    wavelengths_nm : tuple of float or None
        Table wavelengths, strictly increasing; None for a constant. [nm]
    """

    n: tuple[float, ...]
    k: tuple[float, ...]
    wavelengths_nm: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        n = tuple(float(v) for v in np.atleast_1d(self.n))
        k = tuple(float(v) for v in np.atleast_1d(self.k))
        if len(n) != len(k) or not n:
            raise InputError(f"refractive index: n has {len(n)} values and k {len(k)}; they "
                             "must have one, equal length", key="k", value=len(k),
                             allowed=f"{len(n)} values")
        if not all(math.isfinite(v) and v > 0.0 for v in n):
            raise InputError(f"refractive index n = {list(n)} must be finite and > 0", key="n",
                             value=n, allowed="> 0")
        if not all(math.isfinite(v) and v >= 0.0 for v in k):
            raise InputError(f"refractive index k = {list(k)} must be finite and >= 0 (m = n + "
                             "i k, absorption has k > 0)", key="k", value=k, allowed=">= 0")
        if self.wavelengths_nm is None:
            if len(n) != 1:
                raise InputError(f"refractive index: {len(n)} values need wavelengths_nm",
                                 key="wavelengths_nm", value=None, allowed=f"{len(n)} values")
            wl = None
        else:
            wl = tuple(float(v) for v in np.atleast_1d(self.wavelengths_nm))
            if len(wl) != len(n) or not all(math.isfinite(v) and v > 0.0 for v in wl) \
                    or any(b <= a for a, b in zip(wl, wl[1:], strict=False)):
                raise InputError(f"refractive index wavelengths_nm = {list(wl)} must be "
                                 f"{len(n)} finite values > 0, strictly increasing",
                                 key="wavelengths_nm", value=wl,
                                 allowed="strictly increasing, > 0 nm")
        object.__setattr__(self, "n", n)
        object.__setattr__(self, "k", k)
        object.__setattr__(self, "wavelengths_nm", wl)

    @classmethod
    def constant(cls, n: float, k: float = 0.0) -> ComplexIndex:
        """The same m = n + i k at every wavelength."""
        return cls((n,), (k,))

    @classmethod
    def table(cls, wavelengths_nm: ArrayLike, n: ArrayLike, k: ArrayLike) -> ComplexIndex:
        """n and k at tabulated wavelengths [nm] (sorted here)."""
        wl = np.asarray(wavelengths_nm, dtype=np.float64).ravel()
        n = np.asarray(n, dtype=np.float64).ravel()
        k = np.asarray(k, dtype=np.float64).ravel()
        if n.shape != wl.shape or k.shape != wl.shape:
            raise InputError(f"refractive index table: {wl.size} wavelengths, {n.size} n and "
                             f"{k.size} k values; they must have one length",
                             key="wavelengths_nm", value=wl.size, allowed="equal lengths")
        real, imaginary = SpectralParameter.table(wl, n), SpectralParameter.table(wl, k)
        return cls(real.values, imaginary.values, real.wavelengths_nm)

    @property
    def is_constant(self) -> bool:
        return self.wavelengths_nm is None

    def at(self, wavelengths_nm: ArrayLike) -> np.ndarray:
        """m = n + i k on `wavelengths_nm` [nm], complex, the shape of the input. [-]"""
        real = SpectralParameter(self.n, self.wavelengths_nm).at(wavelengths_nm)
        imaginary = SpectralParameter(self.k, self.wavelengths_nm).at(wavelengths_nm)
        return real + 1j * imaginary


# Bond & Bergstrom (2006), Aerosol Sci. Technol. 40, 27, doi:10.1080/02786820500421521: the
# index they recommend for light-absorbing carbon (550 nm), held constant over wavelength (a
# constant index gives the absorption ~ 1/lambda they report for small soot particles).
SOOT_BOND_BERGSTROM_2006 = ComplexIndex.constant(1.95, 0.79)

_CONSTANT_MATERIALS = {"soot": SOOT_BOND_BERGSTROM_2006}
_TABLE_MATERIALS = ("hematite", "mars-dust-costa", "water")  # data/refractive_index_<name>.csv
MATERIALS: tuple[str, ...] = tuple(sorted((*_CONSTANT_MATERIALS, *_TABLE_MATERIALS)))


def load_material(name: str) -> ComplexIndex:
    """Refractive index of a shipped material (`MATERIALS`).

    Tables: skyscatter/data/refractive_index_<name>.csv (header wavelength_nm,n,k; `#` lines
    name the source); see data/PROVENANCE.md. hematite: CosmoScout VR mars_ehlers.json,
    360-830 nm (stand-in for the Amsterdam-Granada data of Meyran 2022); water: Segelstein
    (1981), M.S. thesis, Univ. Missouri-Kansas City, 300-1000 nm, from PyPI miepython (MIT);
    mars-dust-costa: Costa et al. (2021), IEEE TVCG 27(2), 785, doi:10.1109/TVCG.2020.3030333,
    Table 1. soot: `SOOT_BOND_BERGSTROM_2006`, a constant.
    """
    key = str(name).strip().lower()
    if key in _CONSTANT_MATERIALS:
        return _CONSTANT_MATERIALS[key]
    if key not in _TABLE_MATERIALS:
        raise InputError(f"unknown particle material {name!r}; allowed: {', '.join(MATERIALS)}",
                         key="material", value=name, allowed=", ".join(MATERIALS))
    path = resources.files("skyscatter").joinpath("data", f"refractive_index_{key}.csv")
    lines = [line for line in path.read_text(encoding="utf-8").splitlines()
             if line.strip() and not line.startswith("#")]
    if lines[0].replace(" ", "") != "wavelength_nm,n,k":
        raise ValueError(f"{path}: header {lines[0]!r}, expected 'wavelength_nm,n,k'")
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return ComplexIndex.table(table[:, 0], table[:, 1], table[:, 2])


def _maxwell_garnett_values(m0: np.ndarray, m_a: np.ndarray, v: float) -> np.ndarray:
    """The Maxwell Garnett formula on complex arrays (see `maxwell_garnett`)."""
    eps0 = m0 * m0
    eps_a = m_a * m_a
    difference = eps_a - eps0
    eps = eps0 * (eps_a + 2.0 * eps0 + 2.0 * v * difference) / (eps_a + 2.0 * eps0 - v * difference)
    m = np.sqrt(eps)
    return m.real + 1j * np.abs(m.imag)


def maxwell_garnett(host: ComplexIndex | complex, inclusion: ComplexIndex | complex,
                    volume_fraction: float) -> ComplexIndex:
    r"""Effective index of a host with spherical inclusions: the Maxwell Garnett rule.

    m^2 = m0^2 [mA^2 + 2 m0^2 + 2 v (mA^2 - m0^2)] / [mA^2 + 2 m0^2 - v (mA^2 - m0^2)],
    m0 the host (matrix), mA the inclusion, v its volume fraction. Maxwell Garnett (1904),
    Phil. Trans. R. Soc. A 203, 385, doi:10.1098/rsta.1904.0024; Bohren & Huffman (1983), §8.5,
    doi:10.1002/9783527618156; as written in Meyran 2022 §3.3.2. v = 0 gives the host, v = 1 the
    inclusion; to first order in v, m^2 = m0^2 (1 + 3 v (mA^2 - m0^2) / (mA^2 + 2 m0^2)).
    The root with k >= 0 is returned (the principal square root; |Im| guards rounding).

    Two tables are mixed on the union of their wavelengths (exact there); between those
    wavelengths the result is interpolated linearly like any `ComplexIndex`.

    Parameters
    ----------
    host, inclusion : ComplexIndex or complex
        Refractive indices (a complex number is a constant), k >= 0. [-]
    volume_fraction : float
        Volume fraction v of the inclusion, in [0, 1]. [-]

    Returns
    -------
    ComplexIndex
        Effective refractive index of the mixture. [-]
    """
    host = _as_index(host, "host")
    inclusion = _as_index(inclusion, "inclusion")
    v = float(volume_fraction)
    if not 0.0 <= v <= 1.0:
        raise InputError(f"volume_fraction = {v!r} must lie in [0, 1]", key="volume_fraction",
                         value=v, allowed="[0, 1]")
    if host.is_constant and inclusion.is_constant:
        m = _maxwell_garnett_values(host.at(550.0), inclusion.at(550.0), v)
        return ComplexIndex.constant(float(m.real), float(m.imag))
    grids = [index.wavelengths_nm for index in (host, inclusion) if not index.is_constant]
    wl = np.unique(np.concatenate(grids))
    m = _maxwell_garnett_values(host.at(wl), inclusion.at(wl), v)
    return ComplexIndex.table(wl, m.real, m.imag)


def _as_index(value: ComplexIndex | complex, name: str) -> ComplexIndex:
    if isinstance(value, ComplexIndex):
        return value
    if not isinstance(value, numbers.Number):
        raise InputError(f"{name} = {value!r} must be a ComplexIndex or a complex number",
                         key=name, value=value, allowed="ComplexIndex or complex")
    m = complex(value)
    return ComplexIndex.constant(m.real, m.imag)
