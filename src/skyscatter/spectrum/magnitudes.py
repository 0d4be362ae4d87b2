"""Stellar magnitudes as spectra: the Johnson V band, its zero point, and black-body stars.

- `V_PASSBAND_BESSELL_1990`: the Johnson–Cousins V response of Bessell (1990), PASP 102, 1181,
  Table 2, doi:10.1086/132749, 470–700 nm every 10 nm, peak normalised to 1. Bessell & Murphy
  (2012), PASP 124, 140, doi:10.1086/664083, §2, read these tables as *energy* response
  functions; the band mean of a spectrum F_λ is therefore

      <F>_V = ∫ F_λ S(λ) dλ / ∫ S(λ) dλ                                           (1)

  with S read as piecewise linear between the tabulated points and 0 outside 470–700 nm.
- `V_ZERO_POINT_FLUX`: f_λ of a V = 0 star, 363.1e-11 erg cm⁻² s⁻¹ Å⁻¹ = 3.631e-11
  W m⁻² nm⁻¹, Bessell, Castelli & Plez (1998), A&A 333, 231, Table A2
  (1998A&A...333..231B); it is the AB-like constant of V = -2.5 log10 <F>_V - 21.100 in cgs.
- Pogson's magnitude scale (Pogson 1856, MNRAS 17, 12, doi:10.1093/mnras/17.1.12):

      V = -2.5 log10(<F>_V / F_0)                                                   (2)

- `colour_temperature_from_b_minus_v`: Ballesteros (2012), EPL 97, 34008,
  doi:10.1209/0295-5075/97/34008, eq. 14, the temperature of the black body whose B-V equals
  the star's.
- `stellar_irradiance`: a black body of that temperature scaled so that (1) and (2) give the
  star's V; put on a grid by exact cell averages like `spectrum.star.Star.irradiance_toa`.
- `v_magnitude_of_spectrum`: (1)–(2) for a spectrum given on a grid (piecewise constant over its
  cells, `spectrum.grid`).

Checks (tests/spectrum/test_spectrum_magnitudes.py): the ASTM G173-03 solar spectrum gives
V = -26.761 against -26.76 (Willmer 2018, ApJS 236, 47, doi:10.3847/1538-4365/aabfdf, Table 3);
a V = 0.03, B-V = 0 star has f_λ(555.6 nm) = 3.434e-11 W m⁻² nm⁻¹ (Vega measured: 3.44e-11,
Hayes 1985, IAU Symp. 111, 225).

Public names: `V_PASSBAND_BESSELL_1990`, `V_ZERO_POINT_FLUX`, `v_band_mean`,
`v_magnitude_of_spectrum`, `colour_temperature_from_b_minus_v`, `stellar_irradiance`. The
T = 7000 K / (B-V + 0.56) of Müller (2012, M.Sc. thesis, Hasso-Plattner-Institut, eq. 4.26)
gives 5785 K for the Sun, close to the 5778 K used here, but diverges for blue stars (B-V -> -0.56).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.checks import checked_finite_array
from skyscatter.errors import InputError
from skyscatter.spectrum.grid import cell_average, cell_edges, checked_grid
from skyscatter.spectrum.star import planck_spectral_radiance

__all__ = [
    "V_PASSBAND_BESSELL_1990",
    "V_ZERO_POINT_FLUX",
    "colour_temperature_from_b_minus_v",
    "stellar_irradiance",
    "v_band_mean",
    "v_magnitude_of_spectrum",
]

# Bessell (1990), PASP 102, 1181, Table 2, column V: wavelength [nm], normalised response [-].
V_PASSBAND_BESSELL_1990 = np.array([
    [470.0, 0.000], [480.0, 0.030], [490.0, 0.163], [500.0, 0.458], [510.0, 0.780],
    [520.0, 0.967], [530.0, 1.000], [540.0, 0.973], [550.0, 0.898], [560.0, 0.792],
    [570.0, 0.684], [580.0, 0.574], [590.0, 0.461], [600.0, 0.359], [610.0, 0.270],
    [620.0, 0.197], [630.0, 0.135], [640.0, 0.081], [650.0, 0.045], [660.0, 0.025],
    [670.0, 0.017], [680.0, 0.013], [690.0, 0.009], [700.0, 0.000],
])
V_PASSBAND_BESSELL_1990.flags.writeable = False

# Bessell, Castelli & Plez (1998), A&A 333, 231, Table A2: f_λ(V = 0) = 363.1e-11 erg cm⁻² s⁻¹ Å⁻¹;
# 1 erg cm⁻² s⁻¹ Å⁻¹ = 1e-2 W m⁻² nm⁻¹.
V_ZERO_POINT_FLUX = 3.631e-11  # W m⁻² nm⁻¹

_POGSON = 2.5  # mag per decade of flux: 5 mag = factor 100 exactly (Pogson 1856)
_GAUSS_NODES = 8  # Gauss–Legendre nodes per passband segment / grid cell for black bodies
_PASSBAND_INTEGRAL = float(np.trapezoid(V_PASSBAND_BESSELL_1990[:, 1],
                                        V_PASSBAND_BESSELL_1990[:, 0]))  # nm


def v_band_mean(wavelengths_nm: ArrayLike, irradiance: ArrayLike) -> np.ndarray:
    """Band mean <F>_V of a spectrum on a grid, eq. (1) of the module docstring.

        <F>_V = Σ_j F_j S̄_j Δ_j / ∫ S dλ

    F_j is read as constant over cell j (`grid.cell_edges`), S̄_j is the exact cell average of
    the piecewise-linear Bessell (1990) V response, Δ_j the cell width; exact for a spectrum that
    is piecewise constant over the cells. Cells outside 470–700 nm contribute nothing.

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid, strictly ascending; should cover 470–700 nm. [nm]
    irradiance : array_like, shape (..., n_wl)
        Spectral irradiance (or any spectral density), wavelength last. [W m⁻² nm⁻¹]

    Returns
    -------
    ndarray, shape (...)
        Band-mean spectral irradiance. [W m⁻² nm⁻¹]
    """
    wl = checked_grid(wavelengths_nm)
    f = np.asarray(irradiance, dtype=np.float64)
    if f.shape[-1:] != wl.shape:
        raise InputError(f"irradiance must have the grid's {wl.size} wavelengths on its last "
                         f"axis; got shape {f.shape}", key="irradiance", value=f.shape,
                         allowed=f"(..., {wl.size})")
    weights = cell_average(V_PASSBAND_BESSELL_1990[:, 0], V_PASSBAND_BESSELL_1990[:, 1], wl)
    weights = weights * np.diff(cell_edges(wl))
    covered = weights.sum() / _PASSBAND_INTEGRAL
    if covered < 1.0 - 1e-9:
        raise InputError(
            f"the wavelength grid {wl[0]:g}–{wl[-1]:g} nm covers only {100 * covered:.1f} % of "
            "the V passband (470–700 nm); extend the grid to get a V magnitude",
            key="wavelengths_nm", value=(float(wl[0]), float(wl[-1])),
            allowed="cells covering 470–700 nm")
    return f @ weights / _PASSBAND_INTEGRAL


def v_magnitude_of_spectrum(wavelengths_nm: ArrayLike, irradiance: ArrayLike) -> np.ndarray:
    """Johnson V magnitude of a spectral irradiance given on a grid.

        V = -2.5 log10(<F>_V / F_0),   F_0 = 3.631e-11 W m⁻² nm⁻¹

    <F>_V from `v_band_mean` (Bessell 1990 response, cell-exact); F_0 from Bessell, Castelli &
    Plez (1998), Table A2; Pogson (1856) scale. The inverse of `stellar_irradiance` (exactly so
    on fine grids; on a 16-bin 360–830 nm grid the two differ by < 0.01 mag because the grid
    spectrum is read as constant over 29 nm cells).

    Parameters
    ----------
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid covering 470–700 nm. [nm]
    irradiance : array_like, shape (..., n_wl)
        Spectral irradiance at the observer, normal to the beam. [W m⁻² nm⁻¹]

    Returns
    -------
    ndarray, shape (...)
        V magnitude; +inf for a spectrum with no flux in the band. [mag]
    """
    mean = v_band_mean(wavelengths_nm, irradiance)
    with np.errstate(divide="ignore"):
        return -_POGSON * np.log10(mean / V_ZERO_POINT_FLUX)


def colour_temperature_from_b_minus_v(b_minus_v: ArrayLike) -> np.ndarray:
    """Black-body temperature with the given B-V colour index.

        T = 4600 K (1 / (0.92 (B-V) + 1.7) + 1 / (0.92 (B-V) + 0.62))

    Ballesteros (2012), EPL 97, 34008, doi:10.1209/0295-5075/97/34008, eq. 14: black-body
    temperature of main-sequence stars from B-V, good to about ±100–150 K over 0 <= B-V <= 1.5
    (his Fig. 2); the Sun's B-V = 0.65 gives 5778 K. The denominators vanish at
    B-V = -0.674; inputs are clipped to [-0.4, 3.0] (40 600 K ... 1 860 K), the range of real
    stars, so every result is finite and positive.

    Parameters
    ----------
    b_minus_v : array_like, shape S
        Johnson B-V colour index. [mag]

    Returns
    -------
    ndarray, shape S
        Colour temperature. [K]
    """
    bv = np.clip(checked_finite_array("b_minus_v", b_minus_v, "mag"), -0.4, 3.0)
    return 4600.0 * (1.0 / (0.92 * bv + 1.7) + 1.0 / (0.92 * bv + 0.62))


def _planck_cell_averages(temperature_k: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mean of B_λ(T) over each cell [e_j, e_{j+1}], 8-point Gauss–Legendre per cell; (n_t, n)."""
    nodes, weights = np.polynomial.legendre.leggauss(_GAUSS_NODES)
    half = 0.5 * np.diff(edges)
    samples = (0.5 * (edges[1:] + edges[:-1]))[:, None] + half[:, None] * nodes
    return planck_spectral_radiance(samples, temperature_k) @ weights * 0.5


def _planck_v_band_means(temperature_k: np.ndarray) -> np.ndarray:
    """<B_λ(T)>_V of eq. (1), exact to ~1e-12: Gauss–Legendre on each 10 nm passband segment."""
    x, s = V_PASSBAND_BESSELL_1990[:, 0], V_PASSBAND_BESSELL_1990[:, 1]
    nodes, weights = np.polynomial.legendre.leggauss(_GAUSS_NODES)
    half = 0.5 * np.diff(x)
    samples = (0.5 * (x[1:] + x[:-1]))[:, None] + half[:, None] * nodes  # (23, 8)
    response = np.interp(samples, x, s)
    b = planck_spectral_radiance(samples, temperature_k)  # (n_t, 23, 8)
    integral = np.einsum("tsk,sk,k,s->t", b, response, weights, half)
    return integral / _PASSBAND_INTEGRAL


def stellar_irradiance(v_magnitude: ArrayLike, temperature_k: ArrayLike,
                       wavelengths_nm: ArrayLike) -> np.ndarray:
    """Spectral irradiance of black-body stars of given V magnitude, on a grid, above the air.

        E_j = F_0 10^(-0.4 V) × B̄_j(T) / <B(T)>_V

    B̄_j = mean of the Planck radiance B_λ(T) (`star.planck_spectral_radiance`) over grid cell
    j (8-point Gauss–Legendre per cell, as `Star.irradiance_toa`); <B>_V = its exact Bessell
    (1990) V band mean, eq. (1), independent of the grid; F_0 = 3.631e-11 W m⁻² nm⁻¹ (Bessell,
    Castelli & Plez 1998). So the star has exactly magnitude V, and Σ_j E_j Δ_j is the scaled
    black body's exact flux over the grid's range, whatever the grid. A black body is a coarse
    stellar spectrum (no Balmer jump, no molecular bands in M stars); its colour is what the eye
    sees of a star, which is what we render.

    Cost: the spectrum is computed once per distinct temperature (a catalogue's B-V has 3
    decimals, so 118 000 Hipparcos stars have ~2 700 distinct temperatures).

    Parameters
    ----------
    v_magnitude : array_like, shape S
        Johnson V magnitude outside the atmosphere. [mag]
    temperature_k : array_like, shape S (broadcast with v_magnitude)
        Black-body (colour) temperature, > 0, e.g. `colour_temperature_from_b_minus_v`. [K]
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelength grid, strictly ascending. [nm]

    Returns
    -------
    ndarray, shape S + (n_wl,)
        Spectral irradiance normal to the beam, top of the atmosphere. [W m⁻² nm⁻¹]
    """
    wl = checked_grid(wavelengths_nm)
    v = checked_finite_array("v_magnitude", v_magnitude, "mag")
    t = checked_finite_array("temperature_k", temperature_k, "K")
    if np.any(t <= 0.0):
        raise InputError(f"temperature_k must be > 0; got {float(t[t <= 0.0].flat[0])!r} [K]",
                         key="temperature_k", value=float(t[t <= 0.0].flat[0]),
                         allowed="> 0 [K]")
    v, t = np.broadcast_arrays(v, t)
    unique_t, inverse = np.unique(t, return_inverse=True)
    shape = (_planck_cell_averages(unique_t, cell_edges(wl))
             / _planck_v_band_means(unique_t)[:, None])
    scale = V_ZERO_POINT_FLUX * 10.0 ** (-v / _POGSON)
    return shape[inverse.reshape(t.shape)] * scale[..., None]
