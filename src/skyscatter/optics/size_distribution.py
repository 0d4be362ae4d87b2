"""Particle size distributions and the radius quadratures that average optics over them.

Each distribution is a frozen dataclass with `quadrature(n_radii) -> (radii_m, weights)`: radii
r_i [m] and number fractions w_i (sum 1) such that the mean of any smooth f(r) over the particle
number, <f> = int f(r) n(r) dr / int n(r) dr, is sum_i w_i f(r_i). The nodes are spaced evenly
in ln r over a range that leaves out at most `TAIL_FRACTION` of each of the moments <r^0> ...
<r^4> at either end (number, cross-section, volume and the r^4 in v_eff all covered), and the
weights are trapezoid weights in ln r times dN/d ln r, renormalised. For the smooth, fast-decaying
distributions below (log-normal, gamma) the trapezoid rule in ln r converges exponentially
(Trefethen & Weideman 2014, SIAM Rev. 56, 385, doi:10.1137/130932132), so the truncation of the
tails sets the error; for `JungePowerLaw`, whose density does not vanish at the ends of its
range, the error is second order in the node spacing h (Euler-Maclaurin: h^2/12 (f'(b) - f'(a))).

Distributions:
    LogNormal       dN/d ln r Gaussian in ln r (`from_effective`: Hansen & Travis 1974)
    Gamma           n(r) ∝ r^(shape-1) exp(-r/scale)
    ModifiedGamma   Hansen & Travis (1974) eq. 2.56 in (r_eff, v_eff), a gamma distribution
    JungePowerLaw   dN/d ln r ∝ r^-nu between two radii (Junge 1955)
    Monodisperse    one radius (for tests and single particles)

`effective_radius` and `effective_variance` are Hansen & Travis's (1974) a and b (the
cross-section-weighted mean radius and variance) evaluated on a quadrature. Reference: Hansen &
Travis (1974), "Light scattering in planetary atmospheres", Space Sci. Rev. 16, 527,
doi:10.1007/BF00168069.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from skyscatter.errors import InputError

__all__ = [
    "TAIL_FRACTION",
    "Gamma",
    "JungePowerLaw",
    "LogNormal",
    "ModifiedGamma",
    "Monodisperse",
    "SizeDistribution",
    "effective_radius",
    "effective_variance",
]

TAIL_FRACTION = 1.0e-6  # -, share of each moment <r^0>..<r^4> left out at either end of the range
_HIGHEST_MOMENT = 4     # r^4 enters v_eff; r^3 (volume), r^2 (cross-sections), r^0 lie below


class SizeDistribution(Protocol):
    """A number distribution of particle radii that can be averaged over."""

    def quadrature(self, n_radii: int) -> tuple[np.ndarray, np.ndarray]:
        """Radii [m] and number fractions [-] (sum 1), both shape (n,), radii increasing."""
        ...


def _positive(name: str, value: float, allowed: str = "> 0") -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise InputError(f"{name} = {value!r} must be finite and {allowed}", key=name,
                         value=value, allowed=allowed)
    return value


def _check_n_radii(n_radii: int) -> int:
    if isinstance(n_radii, bool) or not isinstance(n_radii, int | np.integer) or n_radii < 2:
        raise InputError(f"n_radii = {n_radii!r} must be an integer >= 2", key="n_radii",
                         value=n_radii, allowed="integer >= 2")
    return int(n_radii)


def _log_quadrature(log_density, r_min: float, r_max: float,
                    n_radii: int) -> tuple[np.ndarray, np.ndarray]:
    """Trapezoid rule in ln r on [r_min, r_max]: nodes and normalised weights.

    `log_density(ln_r)` is ln(dN/d ln r) up to a constant; it is shifted by its maximum before
    exponentiating so that no weight under- or overflows.
    """
    ln_r = np.linspace(math.log(r_min), math.log(r_max), _check_n_radii(n_radii))
    log_w = log_density(ln_r)
    w = np.exp(log_w - np.max(log_w))
    w[0] *= 0.5
    w[-1] *= 0.5
    return np.exp(ln_r), w / w.sum()


@dataclass(frozen=True)
class LogNormal:
    r"""Log-normal distribution, dN/d ln r ∝ exp(-(ln r - ln r_g)^2 / (2 ln^2 sigma_g)).

    Moments <r^n> = r_g^n exp(n^2 ln^2 sigma_g / 2); r_eff = r_g exp(2.5 ln^2 sigma_g),
    v_eff = exp(ln^2 sigma_g) - 1 (Hansen & Travis 1974, Space Sci. Rev. 16, 527,
    doi:10.1007/BF00168069).

    Parameters
    ----------
    median_radius_m : float
        Median (geometric mean) radius r_g, > 0. [m]
    geometric_std : float
        Geometric standard deviation sigma_g, > 1. [-]
    """

    median_radius_m: float
    geometric_std: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "median_radius_m",
                           _positive("median_radius_m", self.median_radius_m))
        sigma_g = float(self.geometric_std)
        if not math.isfinite(sigma_g) or sigma_g <= 1.0:
            raise InputError(f"geometric_std = {sigma_g!r} must be finite and > 1 (1 would be "
                             "one radius: use Monodisperse)", key="geometric_std",
                             value=sigma_g, allowed="> 1")
        object.__setattr__(self, "geometric_std", sigma_g)

    @classmethod
    def from_effective(cls, effective_radius_m: float, effective_variance: float) -> LogNormal:
        """ln^2 sigma_g = ln(1 + v_eff), r_g = r_eff / (1 + v_eff)^2.5 (inverting the relations in
        the class docstring; Hansen & Travis 1974, doi:10.1007/BF00168069). r_eff [m] > 0,
        v_eff [-] > 0."""
        r_eff = _positive("effective_radius_m", effective_radius_m)
        v_eff = _positive("effective_variance", effective_variance)
        return cls(r_eff / (1.0 + v_eff) ** 2.5, math.exp(math.sqrt(math.log1p(v_eff))))

    def quadrature(self, n_radii: int) -> tuple[np.ndarray, np.ndarray]:
        """Radii [m] and number fractions [-]; see the module docstring."""
        from scipy.special import ndtri

        mu = math.log(self.median_radius_m)
        s = math.log(self.geometric_std)
        z = float(-ndtri(TAIL_FRACTION))  # one-sided normal tail TAIL_FRACTION
        # r^n dN/d ln r is the same Gaussian centred on mu + n s^2: moment 0 sets the lower end,
        # the highest moment the upper one.
        r_min = math.exp(mu - z * s)
        r_max = math.exp(mu + _HIGHEST_MOMENT * s * s + z * s)
        return _log_quadrature(lambda ln_r: -0.5 * ((ln_r - mu) / s) ** 2, r_min, r_max,
                               n_radii)


@dataclass(frozen=True)
class Gamma:
    r"""Gamma distribution of radii, n(r) = dN/dr ∝ r^(k - 1) exp(-r / theta).

    <r> = k theta, <r^n> = theta^n Gamma(k + n) / Gamma(k); r_eff = (k + 2) theta,
    v_eff = 1 / (k + 2) (follows from the moments; Hansen & Travis 1974, Space Sci. Rev. 16, 527,
    doi:10.1007/BF00168069).

    Parameters
    ----------
    shape : float
        Shape k, > 0. [-]
    scale_m : float
        Scale theta, > 0. [m]
    """

    shape: float
    scale_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", _positive("shape", self.shape))
        object.__setattr__(self, "scale_m", _positive("scale_m", self.scale_m))

    def quadrature(self, n_radii: int) -> tuple[np.ndarray, np.ndarray]:
        """Radii [m] and number fractions [-]; see the module docstring."""
        from scipy.special import gammainccinv, gammaincinv

        k, theta = self.shape, self.scale_m
        # r^n n(r) dr is a gamma distribution of shape k + n: the lower end from n = 0,
        # the upper end from the highest moment.
        r_min = theta * float(gammaincinv(k, TAIL_FRACTION))
        r_max = theta * float(gammainccinv(k + _HIGHEST_MOMENT, TAIL_FRACTION))
        return _log_quadrature(lambda ln_r: k * ln_r - np.exp(ln_r) / theta, r_min, r_max,
                               n_radii)


@dataclass(frozen=True)
class ModifiedGamma:
    r"""Hansen & Travis's size distribution in effective radius a and effective variance b.

    n(r) ∝ r^((1 - 3b)/b) exp(-r / (a b)), 0 < b < 1/2 (Hansen & Travis 1974, Space Sci. Rev.
    16, 527, eq. 2.56, doi:10.1007/BF00168069): a `Gamma` of shape k = (1 - 2b)/b and scale
    theta = a b, for which r_eff = (k + 2) theta = a and v_eff = 1/(k + 2) = b. Mars dust of
    Tomasko et al. (1999), J. Geophys. Res. 104, 8987, doi:10.1029/1998JE900016: a = 1.6 µm,
    b = 0.2 (k = 3, theta = 0.32 µm).

    Parameters
    ----------
    effective_radius_m : float
        Effective radius a = <r^3>/<r^2>, > 0. [m]
    effective_variance : float
        Effective variance b, in (0, 0.5). [-]
    """

    effective_radius_m: float
    effective_variance: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "effective_radius_m",
                           _positive("effective_radius_m", self.effective_radius_m))
        b = float(self.effective_variance)
        if not math.isfinite(b) or not 0.0 < b < 0.5:
            raise InputError(f"effective_variance = {b!r} must lie in (0, 0.5) (the gamma "
                             "shape (1 - 2b)/b must be > 0)", key="effective_variance",
                             value=b, allowed="(0, 0.5)")
        object.__setattr__(self, "effective_variance", b)

    def as_gamma(self) -> Gamma:
        """The same distribution as `Gamma(shape=(1 - 2b)/b, scale_m=a b)`."""
        b = self.effective_variance
        return Gamma((1.0 - 2.0 * b) / b, self.effective_radius_m * b)

    def quadrature(self, n_radii: int) -> tuple[np.ndarray, np.ndarray]:
        """Radii [m] and number fractions [-]; see the module docstring."""
        return self.as_gamma().quadrature(n_radii)


@dataclass(frozen=True)
class JungePowerLaw:
    r"""Junge's power law, dN/d ln r ∝ r^-nu for r_min <= r <= r_max, 0 outside.

    Junge (1955), J. Meteorol. 12, 13, doi:10.1175/1520-0469(1955)012<0013:TSDAAO>2.0.CO;2;
    nu ~ 3 for continental aerosol. The quadrature nodes end exactly on the two edges.

    Parameters
    ----------
    exponent : float
        Exponent nu (any finite value). [-]
    min_radius_m, max_radius_m : float
        Radius range, 0 < min_radius_m < max_radius_m. [m]
    """

    exponent: float
    min_radius_m: float
    max_radius_m: float

    def __post_init__(self) -> None:
        nu = float(self.exponent)
        if not math.isfinite(nu):
            raise InputError(f"exponent = {nu!r} must be finite", key="exponent", value=nu,
                             allowed="finite")
        object.__setattr__(self, "exponent", nu)
        r1 = _positive("min_radius_m", self.min_radius_m)
        r2 = _positive("max_radius_m", self.max_radius_m)
        if r2 <= r1:
            raise InputError(f"max_radius_m = {r2!r} must be > min_radius_m = {r1!r}",
                             key="max_radius_m", value=r2, allowed=f"> {r1!r} m")
        object.__setattr__(self, "min_radius_m", r1)
        object.__setattr__(self, "max_radius_m", r2)

    def quadrature(self, n_radii: int) -> tuple[np.ndarray, np.ndarray]:
        """Radii [m] and number fractions [-]; see the module docstring."""
        nu = self.exponent
        return _log_quadrature(lambda ln_r: -nu * ln_r, self.min_radius_m, self.max_radius_m,
                               n_radii)


@dataclass(frozen=True)
class Monodisperse:
    """All particles of one radius; `quadrature` returns that radius with weight 1.

    Parameters
    ----------
    radius_m : float
        Radius, > 0. [m]
    """

    radius_m: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius_m", _positive("radius_m", self.radius_m))

    def quadrature(self, n_radii: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """([radius_m], [1.0]); `n_radii` is ignored (one radius is exact)."""
        return np.array([self.radius_m]), np.array([1.0])


def _moments(radii: ArrayLike, weights: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(radii, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    if r.shape != w.shape or r.ndim != 1 or r.size == 0:
        raise InputError(f"radii {r.shape} and weights {w.shape} must be 1-D of one length",
                         key="weights", value=w.shape, allowed=f"shape {r.shape}")
    return r, w


def effective_radius(radii: ArrayLike, weights: ArrayLike) -> float:
    """Effective radius r_eff = <r^3> / <r^2> (Hansen & Travis 1974, their a,
    doi:10.1007/BF00168069) of a quadrature (radii [m], number weights [-]). [m]"""
    r, w = _moments(radii, weights)
    return float(np.sum(w * r**3) / np.sum(w * r**2))


def effective_variance(radii: ArrayLike, weights: ArrayLike) -> float:
    """Effective variance v_eff = <(r - r_eff)^2 r^2> / (r_eff^2 <r^2>) (Hansen & Travis 1974,
    their b, doi:10.1007/BF00168069) of a quadrature (radii [m], number weights [-]). [-]"""
    r, w = _moments(radii, weights)
    r_eff = effective_radius(r, w)
    return float(np.sum(w * (r - r_eff) ** 2 * r**2) / (r_eff**2 * np.sum(w * r**2)))
