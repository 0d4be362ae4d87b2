"""Phase functions p(nu) [sr^-1], normalised to 1 over 4 pi sr; nu = cos(scattering angle).

Two layers:

- numba kernels `rayleigh`, `penndorf`, `henyey_greenstein`, `double_henyey_greenstein`,
  `cornette_shanks`: plain arithmetic compiled with `@njit(cache=True)`, so the same function works
  on floats inside other kernels and on numpy arrays (of equal or broadcastable shapes) in Python;
- the `PhaseFunction` protocol and its frozen dataclasses (`RayleighPhase`, `PenndorfPhase`,
  `HenyeyGreensteinPhase`, `DoubleHenyeyGreensteinPhase`, `CornetteShanksPhase`, `TabulatedPhase`)
  that a constituent carries: `evaluate(nu, wavelengths_nm) -> S + (n_wl,)` and
  `asymmetry(wavelengths_nm) -> (n_wl,)`, with parameters that may vary with wavelength.

Sources: Costa et al. (2021), IEEE TVCG 27(2), 785, doi:10.1109/TVCG.2020.3030333 (cited as
Costa 2020 below, its VIS 2020 presentation), Eqs. 9, 10, 16; Penndorf (1957); Henyey &
Greenstein (1941); Kattawar (1975); Cornette & Shanks (1992). Each function's docstring gives
its equation and DOI.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from skyscatter.errors import InputError
from skyscatter.spectrum.tabulated import SpectralParameter

__all__ = [
    "CornetteShanksPhase",
    "DoubleHenyeyGreensteinPhase",
    "HenyeyGreensteinPhase",
    "PenndorfPhase",
    "PhaseFunction",
    "RayleighPhase",
    "TabulatedPhase",
    "angle_blended_phase",
    "cornette_shanks",
    "cornette_shanks_asymmetry",
    "double_henyey_greenstein",
    "henyey_greenstein",
    "penndorf",
    "rayleigh",
]


# --------------------------------------------------------------------------------------------
# Kernels: scalar or array in, same out. nu = cos(scattering angle) [-]: nu = 1 is forward
# scattering (the light keeps its direction), nu = -1 is backscattering.
# --------------------------------------------------------------------------------------------

@njit(cache=True)
def rayleigh(nu):
    """Rayleigh phase function p(nu) = 3 / (16 pi) (1 + nu^2) [sr^-1].

    Costa et al. (2020), IEEE TVCG, Eq. 9 (isotropic molecules, no depolarisation correction);
    Chandrasekhar (1960), Radiative Transfer, §18. nu = cos(scattering angle) [-].
    """
    return 3.0 / (16.0 * np.pi) * (1.0 + nu * nu)


@njit(cache=True)
def penndorf(nu):
    """Penndorf's fit to the phase function of air, p(nu) = 0.7629 (1 + 0.932 nu^2) / (4 pi).

    Costa et al. (2020), IEEE TVCG, Eq. 10; Penndorf (1957), J. Opt. Soc. Am. 47, 176,
    doi:10.1364/JOSA.47.000176. As printed it integrates to 0.7629 (2 + 2 * 0.932 / 3) / 2
    = 0.99992 over 4 pi sr, not exactly 1; we keep the published constants. [sr^-1]
    """
    return 0.7629 * (1.0 + 0.932 * nu * nu) / (4.0 * np.pi)


@njit(cache=True)
def henyey_greenstein(nu, g):
    """Henyey-Greenstein phase function [sr^-1], asymmetry parameter g in (-1, 1).

    p(nu; g) = (1 - g^2) / (4 pi (1 + g^2 - 2 g nu)^(3/2)).
    Henyey & Greenstein (1941), Astrophys. J. 93, 70, doi:10.1086/144246. <nu> = g.
    """
    return (1.0 - g * g) / (4.0 * np.pi * (1.0 + g * g - 2.0 * g * nu) ** 1.5)


@njit(cache=True)
def double_henyey_greenstein(nu, g1, g2, alpha):
    """Two-term Henyey-Greenstein phase function [sr^-1].

    p(nu) = alpha p_HG(nu; g1) + (1 - alpha) p_HG(nu; g2), alpha in [0, 1].
    Kattawar (1975), J. Quant. Spectrosc. Radiat. Transfer 15, 839,
    doi:10.1016/0022-4073(75)90095-3; Costa et al. (2020), IEEE TVCG, Eq. 16. Costa's Eq. 16
    prints (1 + g1^2) in both numerators; that is a typo: the normalised Henyey-Greenstein
    numerator is (1 - g^2) of each lobe's own g, which we use. <nu> = alpha g1 + (1 - alpha) g2.
    """
    return alpha * henyey_greenstein(nu, g1) + (1.0 - alpha) * henyey_greenstein(nu, g2)


@njit(cache=True)
def cornette_shanks(nu, g):
    """Cornette-Shanks phase function p(nu; g) [sr⁻¹]; nu = cos(scattering angle).
    Cornette & Shanks (1992), Appl. Opt. 31, 3152, doi:10.1364/AO.31.003152."""
    k = 3.0 / (8.0 * np.pi) * (1.0 - g * g) / (2.0 + g * g)
    return k * (1.0 + nu * nu) / (1.0 + g * g - 2.0 * g * nu) ** 1.5


def cornette_shanks_asymmetry(g: ArrayLike) -> np.ndarray:
    """Mean cosine of the Cornette-Shanks phase function, <nu> = 3 g (4 + g^2) / (5 (2 + g^2)).

    Follows from integrating `cornette_shanks` against nu over 4 pi sr (Cornette & Shanks 1992,
    doi:10.1364/AO.31.003152); it is not g itself (g = 0.8 gives <nu> = 0.7143).

    Parameters
    ----------
    g : array_like, shape S
        Cornette-Shanks parameter. [-]

    Returns
    -------
    ndarray, shape S
        Asymmetry parameter <cos(scattering angle)>. [-]
    """
    g = np.asarray(g, dtype=np.float64)
    return 3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g))


# --------------------------------------------------------------------------------------------
# Phase-function objects
# --------------------------------------------------------------------------------------------

@runtime_checkable
class PhaseFunction(Protocol):
    """A phase function that may depend on wavelength."""

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        """p at nu = cos(scattering angle), shape S + (n_wl,) for nu of shape S. [sr^-1]"""
        ...

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        """Asymmetry parameter <cos(scattering angle)>, shape (n_wl,). [-]"""
        ...


def _wavelengths(wavelengths_nm: ArrayLike) -> np.ndarray:
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    if wl.ndim > 1:
        raise InputError(f"wavelengths_nm must be a scalar or 1-D array, got shape {wl.shape}",
                         key="wavelengths_nm", value=wl.shape, allowed="shape (n_wl,)")
    return np.atleast_1d(wl)


def _apply(kernel: Callable[..., np.ndarray], nu: ArrayLike, wavelengths_nm: ArrayLike,
           *parameters: SpectralParameter) -> np.ndarray:
    """Evaluate `kernel(nu, *params)` on S + (n_wl,) through one 1-D specialisation."""
    nu = np.asarray(nu, dtype=np.float64)
    wl = _wavelengths(wavelengths_nm)
    shape = nu.shape + wl.shape
    flat_nu = np.ascontiguousarray(np.broadcast_to(nu[..., None], shape)).reshape(-1)
    flat_params = [np.ascontiguousarray(np.broadcast_to(p.at(wl), shape)).reshape(-1)
                   for p in parameters]
    return kernel(flat_nu, *flat_params).reshape(shape)


def _as_parameter(value: SpectralParameter | float, name: str, low: float, high: float,
                  closed: bool) -> SpectralParameter:
    """Convert a float to a constant SpectralParameter and check its values lie in range."""
    param = value if isinstance(value, SpectralParameter) else SpectralParameter.constant(value)
    v = np.asarray(param.values, dtype=np.float64)
    inside = (v >= low) & (v <= high) if closed else (v > low) & (v < high)
    if not np.all(inside):
        interval = f"[{low}, {high}]" if closed else f"({low}, {high})"
        raise InputError(f"{name} = {list(param.values)} must lie in {interval}", key=name,
                         value=param.values, allowed=interval)
    return param


@dataclass(frozen=True)
class RayleighPhase:
    """Rayleigh phase function (`rayleigh`), the same at every wavelength; <nu> = 0."""

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        return _apply(rayleigh, nu, wavelengths_nm)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return np.zeros(_wavelengths(wavelengths_nm).shape)


@dataclass(frozen=True)
class PenndorfPhase:
    """Penndorf's phase function of air (`penndorf`; integrates to 0.99992); <nu> = 0."""

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        return _apply(penndorf, nu, wavelengths_nm)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return np.zeros(_wavelengths(wavelengths_nm).shape)


@dataclass(frozen=True)
class HenyeyGreensteinPhase:
    """Henyey-Greenstein phase function (`henyey_greenstein`), g(lambda) in (-1, 1); <nu> = g."""

    g: SpectralParameter

    def __post_init__(self) -> None:
        object.__setattr__(self, "g", _as_parameter(self.g, "g", -1.0, 1.0, closed=False))

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        return _apply(henyey_greenstein, nu, wavelengths_nm, self.g)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return self.g.at(_wavelengths(wavelengths_nm))


@dataclass(frozen=True)
class DoubleHenyeyGreensteinPhase:
    """Two-term Henyey-Greenstein phase function (`double_henyey_greenstein`).

    g1, g2 in (-1, 1), alpha in [0, 1], each possibly per wavelength (Costa 2020's Mars dust uses
    g1 = (0.03, 0.4, 0.67) at (680, 550, 440) nm); <nu> = alpha g1 + (1 - alpha) g2.
    """

    g1: SpectralParameter
    g2: SpectralParameter
    alpha: SpectralParameter

    def __post_init__(self) -> None:
        object.__setattr__(self, "g1", _as_parameter(self.g1, "g1", -1.0, 1.0, closed=False))
        object.__setattr__(self, "g2", _as_parameter(self.g2, "g2", -1.0, 1.0, closed=False))
        object.__setattr__(self, "alpha",
                           _as_parameter(self.alpha, "alpha", 0.0, 1.0, closed=True))

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        return _apply(double_henyey_greenstein, nu, wavelengths_nm, self.g1, self.g2, self.alpha)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        wl = _wavelengths(wavelengths_nm)
        alpha = self.alpha.at(wl)
        return alpha * self.g1.at(wl) + (1.0 - alpha) * self.g2.at(wl)


@dataclass(frozen=True)
class CornetteShanksPhase:
    """Cornette-Shanks phase function (`cornette_shanks`) with g(lambda) in (-1, 1).

    <nu> = 3 g (4 + g^2) / (5 (2 + g^2)) (`cornette_shanks_asymmetry`), not g.
    """

    g: SpectralParameter

    def __post_init__(self) -> None:
        object.__setattr__(self, "g", _as_parameter(self.g, "g", -1.0, 1.0, closed=False))

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        return _apply(cornette_shanks, nu, wavelengths_nm, self.g)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return cornette_shanks_asymmetry(self.g.at(_wavelengths(wavelengths_nm)))


_SUBDIVISIONS = 64  # sub-steps per tabulated angle interval for the normalisation integrals


@dataclass(frozen=True, eq=False)
class TabulatedPhase:
    """A phase function tabulated over scattering angle, per wavelength (e.g. from Mie theory).

    Between tabulated angles, log p is interpolated linearly in the angle theta (forward peaks
    of aerosol phase functions are close to exponential in theta). Each tabulated column is then
    renormalised so that 2 pi int_0^pi p(theta) sin(theta) dtheta = 1 for that interpolant
    (integrated with `_SUBDIVISIONS` trapezoid steps per interval). Between tabulated
    wavelengths the normalised columns are interpolated linearly, which keeps the normalisation;
    outside the tabulated wavelengths the nearest column is used. <nu> is integrated the same way.

    Parameters
    ----------
    angles_deg : array_like, shape (n_angle,)
        Scattering angles, strictly increasing from 0 to 180. [deg]
    values : array_like, shape (n_angle, n_wl_tab) or (n_angle,)
        Phase function, any positive scale (it is renormalised). [sr^-1 or relative]
    wavelengths_nm : array_like, shape (n_wl_tab,), or None
        Wavelengths of the columns, strictly increasing; None for one grey column. [nm]
    """

    angles_deg: np.ndarray
    values: np.ndarray
    wavelengths_nm: np.ndarray | None = None
    _log_p: np.ndarray = field(init=False, repr=False)
    _g: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        theta_deg = np.asarray(self.angles_deg, dtype=np.float64)
        p = np.asarray(self.values, dtype=np.float64)
        if p.ndim == 1:
            p = p[:, None]
        if self.wavelengths_nm is None:
            wl = np.array([550.0])
            if p.shape[1] != 1:
                raise InputError("TabulatedPhase: wavelengths_nm is required when values has "
                                 f"{p.shape[1]} columns", key="wavelengths_nm", value=None)
        else:
            wl = np.atleast_1d(np.asarray(self.wavelengths_nm, dtype=np.float64))
        if theta_deg.ndim != 1 or theta_deg.size < 2 or np.any(np.diff(theta_deg) <= 0.0) \
                or theta_deg[0] != 0.0 or theta_deg[-1] != 180.0:
            raise InputError("TabulatedPhase: angles_deg must increase strictly from 0 to 180",
                             key="angles_deg", value=theta_deg, allowed="0 ... 180, increasing")
        if p.shape != (theta_deg.size, wl.size):
            raise InputError(f"TabulatedPhase: values has shape {p.shape}, expected "
                             f"(n_angle, n_wl_tab) = {(theta_deg.size, wl.size)}",
                             key="values", value=p.shape)
        if wl.ndim != 1 or np.any(np.diff(wl) <= 0.0):
            raise InputError("TabulatedPhase: wavelengths_nm must increase strictly",
                             key="wavelengths_nm", value=wl)
        if not np.all(np.isfinite(p)) or np.any(p <= 0.0):
            raise InputError("TabulatedPhase: values must be finite and > 0", key="values",
                             value="non-positive or non-finite entries", allowed="> 0")
        theta = np.deg2rad(theta_deg)
        log_p = np.log(p)
        fine = _refine(theta)
        p_fine = np.exp(_interp_columns(fine, theta, log_p))  # (n_fine, n_wl_tab)
        weight = 2.0 * np.pi * np.sin(fine)[:, None]
        norm = np.trapezoid(p_fine * weight, fine, axis=0)
        log_p = log_p - np.log(norm)
        g = np.trapezoid(p_fine / norm * weight * np.cos(fine)[:, None], fine, axis=0)
        for name, value in (("angles_deg", theta_deg), ("values", p), ("wavelengths_nm", wl),
                            ("_log_p", log_p), ("_g", g)):
            value = np.array(value)
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        """Names the table by a SHA-256 of its arrays: cache fingerprints hash this repr, and
        numpy's own repr elides the middle of large arrays."""
        digest = hashlib.sha256()
        for array in (self.angles_deg, self.values, self.wavelengths_nm):
            digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        return (f"TabulatedPhase({self.angles_deg.size} angles x {self.wavelengths_nm.size} "
                f"wavelengths, sha256={digest.hexdigest()})")

    def _wavelength_weights(self, wl: np.ndarray) -> np.ndarray:
        """Linear-interpolation weights, shape (n_wl_tab, n_wl), held constant outside."""
        eye = np.eye(self.wavelengths_nm.size)
        return np.array([np.interp(wl, self.wavelengths_nm, row) for row in eye])

    def evaluate(self, nu: ArrayLike, wavelengths_nm: np.ndarray) -> np.ndarray:
        nu = np.asarray(nu, dtype=np.float64)
        wl = _wavelengths(wavelengths_nm)
        theta = np.arccos(np.clip(nu, -1.0, 1.0)).reshape(-1)
        p_tab = np.exp(_interp_columns(theta, np.deg2rad(self.angles_deg), self._log_p))
        return (p_tab @ self._wavelength_weights(wl)).reshape(nu.shape + wl.shape)

    def asymmetry(self, wavelengths_nm: np.ndarray) -> np.ndarray:
        return self._g @ self._wavelength_weights(_wavelengths(wavelengths_nm))


def angle_blended_phase(forward: PhaseFunction, backward: PhaseFunction, angles_deg: ArrayLike,
                        wavelengths_nm: ArrayLike) -> TabulatedPhase:
    """Blend of two phase functions whose weight moves linearly with the scattering angle.

    p(theta) ∝ (1 - theta/pi) p_forward(theta) + (theta/pi) p_backward(theta), renormalised
    at every wavelength (by `TabulatedPhase`): pure `forward` at 0 deg, pure `backward` at 180 deg.
    This is the "hybrid" Mars dust of Meyran (2022, M.Sc. thesis, Hochschule Hannover, §4.1):
    the forward peak of a Mie phase function with Costa et al.'s double Henyey-Greenstein in side
    and back scattering. The thesis does not print its weight; the linear-in-angle weight is the
    reading of the thesis's §4.1 and §5.1.1 (the hybrid "converges to" Costa's function in back
    scattering and keeps the Mie forward peak).

    Parameters
    ----------
    forward, backward : PhaseFunction
        The phase functions that dominate at 0 and at 180 deg.
    angles_deg : array_like, shape (n_angle,)
        Angles of the table, strictly increasing from 0 to 180; fine near 0 to keep the
        forward peak. [deg]
    wavelengths_nm : array_like, shape (n_wl,)
        Wavelengths of the table, strictly increasing. [nm]
    """
    theta_deg = np.asarray(angles_deg, dtype=np.float64)
    wl = _wavelengths(wavelengths_nm)
    nu = np.cos(np.deg2rad(theta_deg))
    weight = (theta_deg / 180.0)[:, None]
    values = ((1.0 - weight) * forward.evaluate(nu, wl)
              + weight * backward.evaluate(nu, wl))
    return TabulatedPhase(theta_deg, values, wl)


def _refine(theta: np.ndarray) -> np.ndarray:
    """Split each interval of `theta` into `_SUBDIVISIONS` equal steps."""
    t = np.linspace(0.0, 1.0, _SUBDIVISIONS + 1)[:-1]
    inner = (theta[:-1, None] + np.diff(theta)[:, None] * t[None, :]).reshape(-1)
    return np.append(inner, theta[-1])


def _interp_columns(x: np.ndarray, xp: np.ndarray, fp: np.ndarray) -> np.ndarray:
    """Linear interpolation of every column of fp (n_xp, n_col) at x (n_x,) -> (n_x, n_col)."""
    i = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, xp.size - 2)
    t = ((x - xp[i]) / (xp[i + 1] - xp[i]))[:, None]
    return fp[i] * (1.0 - t) + fp[i + 1] * t
