"""Wavelength grids [nm], their cells, and exact cell averages of tabulated spectra.

A spectral grid is a 1-D, strictly ascending array of wavelengths λ_j [nm]. Each wavelength
stands for a cell [e_j, e_{j+1}]; a spectrum on the grid is read as piecewise constant over the
cells. That reading is what makes colour (`colour.cmf_weights`) and band sums exact, so tabulated
spectra are put on a grid by their *cell average* (`cell_average`), not by point sampling: point
samples of the solar spectrum alias its Fraunhofer lines on coarse grids (point values at 400 nm
differ by up to 10 % between ASTM G173-03, Kurucz 1992 and Gueymard 2004, band means by 1 %).

The default grid follows Bruneton & Neyret (2008) / Elek (2010): `count` equal bins over
360–830 nm, each represented by its centre; `DEFAULT_WAVELENGTH_BINS` bins unless a caller says
otherwise (images, the viewer's full tables, the CLI's --wavelengths).

The shipped data bound the wavelengths a user may ask for (`checked_data_wavelengths`): images
need the CIE 1931 colour-matching functions, tabulated over `COLOUR_RANGE_NM` = 360–830 nm
(data/colour_cie.npz); monochromatic radiance needs the solar spectrum (ASTM G173, from 280 nm:
the 1 nm cell around a wavelength must lie inside it, hence 280.5 nm) and the refractive-index
fits of the gases, measured to 1690 nm (Peck & Reeder 1972 for air, 230–1690 nm; Bideau-Mehu
et al. 1973 for CO2, 181–1695 nm): `MONOCHROMATIC_RANGE_NM` = 280.5–1690 nm. The ozone
cross-sections end at 830 nm; past it they are taken as 0 (`optics.absorption`, optical depth
~0.001 in the Wulf bands).

Public names: `wavelength_grid`, `cell_edges`, `cell_widths`, `cell_average`, `checked_grid`,
`checked_wavelengths`, `checked_data_wavelengths`, `COLOUR_RANGE_NM`, `MONOCHROMATIC_RANGE_NM`,
`DEFAULT_WAVELENGTH_BINS`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.checks import checked_finite_array
from skyscatter.errors import InputError

__all__ = [
    "COLOUR_RANGE_NM",
    "DEFAULT_WAVELENGTH_BINS",
    "MONOCHROMATIC_RANGE_NM",
    "cell_average",
    "cell_edges",
    "cell_widths",
    "checked_data_wavelengths",
    "checked_grid",
    "checked_wavelengths",
    "wavelength_grid",
]

DEFAULT_WAVELENGTH_BINS = 16  # bins over 360-830 nm of images and tables when none are asked for
SINGLE_WAVELENGTH_CELL_NM = 1.0  # nm; width given to a one-wavelength grid (monochromatic use)
COLOUR_RANGE_NM = (360.0, 830.0)  # nm; the CIE 1931 colour-matching functions (colour_cie.npz)
MONOCHROMATIC_RANGE_NM = (280.5, 1690.0)  # nm; solar spectrum + gas refractive indices (above)


def checked_wavelengths(wavelengths_nm: ArrayLike, name: str = "wavelengths_nm") -> np.ndarray:
    """`wavelengths_nm` as a float64 array of any shape, each value checked to be > 0 and finite.

    Raises `InputError` naming the argument, the first bad value and what is allowed
    (`checks.checked_finite_array`).
    """
    return checked_finite_array(name, wavelengths_nm, "nm", positive=True)


def checked_data_wavelengths(wavelengths_nm: ArrayLike, monochromatic: bool = False,
                             name: str = "wavelengths_nm") -> np.ndarray:
    """`checked_wavelengths`, and each within the range the shipped data cover:
    `COLOUR_RANGE_NM` for images, `MONOCHROMATIC_RANGE_NM` with `monochromatic` (radiance).

    Raises `InputError` naming the first wavelength outside, the range and why it ends there.
    """
    wl = checked_wavelengths(wavelengths_nm, name)
    low, high = MONOCHROMATIC_RANGE_NM if monochromatic else COLOUR_RANGE_NM
    outside = (wl < low) | (wl > high)
    if np.any(outside):
        value = float(wl[tuple(np.argwhere(outside)[0])])
        reason = ("the solar spectrum and the gases' refractive indices" if monochromatic
                  else "the CIE colour-matching functions that make colour")
        raise InputError(f"{name}: {value:g} nm is outside {low:g}-{high:g} nm, the range of "
                         f"{reason}; choose wavelengths inside it", key=name, value=value,
                         allowed=f"{low:g} <= wavelength <= {high:g} [nm]")
    return wl


def checked_grid(wavelengths_nm: ArrayLike, name: str = "wavelengths_nm") -> np.ndarray:
    """`wavelengths_nm` as a 1-D float64 grid: positive, finite, strictly ascending.

    A scalar is a one-wavelength grid and comes back with shape (1,); 2-D and higher input is
    refused (a grid is one axis). Raises `InputError` with the bad value and what is allowed.
    """
    wl = checked_wavelengths(wavelengths_nm, name)
    if wl.ndim == 0:
        wl = wl.reshape(1)
    if wl.ndim != 1 or wl.size == 0:
        raise InputError(f"{name} must be a non-empty 1-D grid of wavelengths; got shape "
                         f"{wl.shape}", key=name, value=wl.shape,
                         allowed="shape (n_wl,), n_wl >= 1")
    steps = np.diff(wl)
    if np.any(steps <= 0.0):
        i = int(np.argmax(steps <= 0.0))
        raise InputError(
            f"{name} must be strictly ascending; got {float(wl[i])!r} then {float(wl[i + 1])!r} "
            f"at index {i + 1}", key=name, value=float(wl[i + 1]),
            allowed="strictly ascending wavelengths [nm]")
    return wl


def wavelength_grid(count: int = DEFAULT_WAVELENGTH_BINS, start_nm: float = 360.0,
                    stop_nm: float = 830.0) -> np.ndarray:
    """Centres of `count` equal bins between `start_nm` and `stop_nm`.

        λ_j = start + (j + 1/2) (stop - start) / count,   j = 0 .. count-1

    The binning of Bruneton & Neyret (2008), doi:10.1111/j.1467-8659.2008.01245.x, and Elek
    (2010, "Rendering parametrizable planetary atmospheres with multiple scattering in real
    time", CESCG) for 360–830 nm; `cell_edges` of the result are exactly the bin edges.

    Parameters
    ----------
    count : int
        Number of wavelengths (bins), >= 1. [-]
    start_nm, stop_nm : float
        Edges of the spectral range, 0 <= start < stop. [nm]

    Returns
    -------
    ndarray, shape (count,)
        Bin centres, ascending. [nm]
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError(f"count must be an integer >= 1; got {count!r}", key="count",
                         value=count, allowed="integer >= 1")
    start, stop = float(start_nm), float(stop_nm)
    if not (np.isfinite(start) and np.isfinite(stop) and 0.0 <= start < stop):
        raise InputError(
            f"need 0 <= start_nm < stop_nm (finite, in nm); got start_nm={start_nm!r}, "
            f"stop_nm={stop_nm!r}", key="start_nm/stop_nm", value=(start_nm, stop_nm),
            allowed="0 <= start_nm < stop_nm [nm]")
    return start + (np.arange(count, dtype=np.float64) + 0.5) * ((stop - start) / count)


def cell_edges(wavelengths_nm: ArrayLike,
               single_cell_width_nm: float = SINGLE_WAVELENGTH_CELL_NM) -> np.ndarray:
    """Edges of the cells each grid wavelength stands for.

    Inner edges lie halfway between neighbours; the first and last cells are symmetric about their
    wavelength (edge = λ_0 - (e_1 - λ_0), λ_{n-1} + (λ_{n-1} - e_{n-1})). A first edge that would
    fall below 0 nm is clamped to 0. A single wavelength gets a cell `single_cell_width_nm`
    (default 1 nm) wide centred on it. For
    `wavelength_grid(count, start, stop)` the edges are start + k (stop - start)/count.

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,)
        Grid, strictly ascending. [nm]

    Returns
    -------
    ndarray, shape (n_wl + 1,)
        Cell edges, ascending. [nm]
    """
    wl = checked_grid(wavelengths_nm)
    if wl.size == 1:
        half = 0.5 * single_cell_width_nm
        return np.array([max(wl[0] - half, 0.0), wl[0] + half])
    inner = 0.5 * (wl[1:] + wl[:-1])
    first = max(2.0 * wl[0] - inner[0], 0.0)
    last = 2.0 * wl[-1] - inner[-1]
    return np.concatenate(([first], inner, [last]))


def cell_widths(wavelengths_nm: ArrayLike) -> np.ndarray:
    """Widths of the grid cells, `np.diff(cell_edges(wavelengths_nm))`, shape (n_wl,). [nm]

    Multiply a spectral density on the grid by these to get band-integrated quantities
    (W m⁻² nm⁻¹ -> W m⁻²).
    """
    return np.diff(cell_edges(wavelengths_nm))


def _cumulative_integral(x: np.ndarray, y: np.ndarray, at: np.ndarray) -> np.ndarray:
    """∫_{x_0}^{at} f dλ of the piecewise-linear interpolant f of (x, y), f = 0 outside [x_0, x_N].

    x: (N,) ascending; y: (..., N); at: (M,) -> (..., M). Exact for a piecewise-linear f.
    """
    dx = np.diff(x)
    segment = 0.5 * (y[..., 1:] + y[..., :-1]) * dx
    total = np.concatenate((np.zeros(y.shape[:-1] + (1,)), np.cumsum(segment, axis=-1)), axis=-1)
    a = np.clip(at, x[0], x[-1])
    i = np.clip(np.searchsorted(x, a, side="right") - 1, 0, x.size - 2)
    t = a - x[i]
    slope = (y[..., i + 1] - y[..., i]) / dx[i]
    return total[..., i] + y[..., i] * t + 0.5 * slope * t * t


def cell_average(table_wavelengths_nm: ArrayLike, table_values: ArrayLike,
                 wavelengths_nm: ArrayLike) -> np.ndarray:
    """Average of a tabulated spectrum over each cell of a grid, integrated exactly.

        f̄_j = 1/(e_{j+1} - e_j) ∫_{e_j}^{e_{j+1}} f(λ) dλ

    with f the piecewise-linear interpolant of the table (the usual reading of a tabulated
    spectrum) and f = 0 outside the tabulated range, so a cell that sticks out of the table is
    averaged with zeros there. Cells come from `cell_edges`. No sampling: a 29 nm cell over a
    Fraunhofer line gets the line's true share, and summing f̄_j × width_j over any set of
    adjacent cells gives the table's integral over them.

    Parameters
    ----------
    table_wavelengths_nm : array_like, shape (N,)
        Wavelengths of the table, strictly ascending, N >= 2. [nm]
    table_values : array_like, shape (..., N)
        Tabulated values, wavelength last. [any unit per nm, or dimensionless]
    wavelengths_nm : array_like, shape (n_wl,)
        Target grid. [nm]

    Returns
    -------
    ndarray, shape (..., n_wl)
        Cell averages, in the unit of `table_values`.
    """
    x = checked_grid(table_wavelengths_nm, "table_wavelengths_nm")
    y = np.asarray(table_values, dtype=np.float64)
    if x.size < 2 or y.shape[-1:] != x.shape:
        raise InputError(
            f"table_values must have the table wavelengths on its last axis, with >= 2 points; "
            f"got table_wavelengths_nm {x.shape} and table_values {y.shape}",
            key="table_values", value=y.shape, allowed=f"shape (..., {x.size})")
    edges = cell_edges(wavelengths_nm)
    integral = _cumulative_integral(x, y, edges)
    return np.diff(integral, axis=-1) / np.diff(edges)
