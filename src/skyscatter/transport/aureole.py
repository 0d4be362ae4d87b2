"""The sun's aureole of light scattered two or more times in forward peaks.

The tables' orders >= 2 treat a particle's forward peak as undeflected light (`phase_truncation`),
so light that only ever scattered in peaks is direct sunlight to them; once is in the exact
single scattering. Scattered n >= 2 times in peaks it still arrives within a few degrees of the
sun: along a line of sight, with x = sum_s f_s beta_s,s times the path, the peak events are a
Poisson process and the angles add up (small-angle approximation: every peak event keeps the
light close to the line of sight, the path length is that of the line of sight), so

    L(psi) = E_sun T exp(...) sum_{n >= 2} x^n / n! p_peak^(n)(psi),

T the transmittance of the line of sight, p_peak^(n) the n-fold convolution of the normalised
peak p_peak = (p - (1 - f) p*) / f on the sphere. With the peak's Legendre moments chi_l that sum
is sum_l (2 l + 1) / (4 pi) (exp(x chi_l) - 1 - x chi_l) P_l(cos psi) in closed form: the
multiple-forward-scattering aureole of the sun photometry literature (Deirmendjian 1957, Ann.
Geophys. 13, 286; Nakajima, Tanaka & Yamauchi 1983, Appl. Opt. 22, 2951,
doi:10.1364/AO.22.002951), and the IMS correction of Nakajima & Tanaka (1988, J. Quant.
Spectrosc. Radiat. Transfer 40, 51, doi:10.1016/0022-4073(88)90031-3) in its exact series form.

The lookups (`_table_lookup_kernels.peak_aureole`) replace the line of sight's T x^n / n! by the
path from the sun to the eye: the light enters along the sun, its n peak events lie at
increasing depth, and between them it travels in directions that turn from the sun's to the
view's. With a low sun the two paths differ a lot: seen 5-10 deg above a sun 5 deg high through
Mars dust, the line of sight's T and x made the aureole 1.3-1.5 x the exact light scattered only
in the peaks (a Monte Carlo of the peaks alone); the path gives 0.96-1.02 x.

Light scattered once in a particle's smooth part p* and n >= 1 times in the peaks is, to the
orders >= 2, light scattered once with p* and undeflected: they give it p*(psi). The peaks blur
it: the clipped p* is flat inside the truncation angle with a kink there, and the real light is
p* convolved with the peaks, darker inside that angle and brighter beyond (delta-M's own error:
10 deg from a sun 60 deg from the zenith in a Martian dust storm the tables were 5.5-6.2 %
too bright against the Monte Carlo, 2.5-2.8 % with this term). With the peak events a Poisson
process of depth x along the path and the smooth event anywhere on it (its depth y = r x, r the
smooth over the peak scattering of the clipped constituents), the change is

    dL(psi) = E_sun T exp(x) x B(x, psi),
    B(x, psi) = r sum_l (2 l + 1) / (4 pi) chi*_l (exp(-x (1 - chi_l)) - 1) P_l(cos psi),

chi*_l the Legendre moments of p*: zero over the sphere (it moves light, it adds none), and
T exp(x) the delta-M scaled transmittance that light had in the orders >= 2.

Public names: `PeakAureole`, `peak_aureole`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

__all__ = ["PeakAureole", "peak_aureole"]

# Legendre degrees of the peak: its narrowest, a 10 um cloud droplet's diffraction peak at 360 nm
# (size parameter 175, about 0.3 deg wide), has moments near 0 from degree ~600 on.
MAX_DEGREE = 2048
# Aureole tabulated out to this multiple of the truncation angle: the peaks of several events
# widen as the square root of their number.
ANGLE_FACTOR = 3.0
X_NODES = 64  # path peak depths x, uniform in log(1 + x) over [0, x_max]
# Largest path peak depth tabulated: beyond it the line of sight's transmittance is below
# exp(-700) and the aureole nothing (exp(x) stays finite in double precision).
X_LIMIT = 700.0


@dataclass(frozen=True)
class PeakAureole:
    """The aureole's angular shape G(x, psi) / (exp(x) - 1 - x) [sr^-1] (integrating to 1
    over the sphere where psi_max holds it all; p_peak^(2) as x -> 0), per wavelength, on path
    peak depths x uniform in log(1 + x) over [0, x_max] and angles from the sun psi uniform
    over [0, psi_max]: `shape` (n_x, n_psi, n_wl); and on the same nodes the peaks' blur of
    light scattered once in the smooth part, B(x, psi) [sr^-1] (module docstring): `blur`."""

    shape: np.ndarray
    blur: np.ndarray
    x_max: float
    psi_max_rad: float


def peak_aureole(peak_phase: np.ndarray, truncation_angle_deg: float, x_max: float, *,
                 smooth_phase: np.ndarray | None = None, smooth_ratio: np.ndarray | None = None
                 ) -> PeakAureole:
    """The aureole of a peak `peak_phase` (n_angle, n_wl) [sr^-1] sampled uniformly over
    [0, pi] (zero beyond the truncation angle, integrating to 1 or 0 per wavelength), for path
    peak depths up to `x_max` (capped at `X_LIMIT`); with the clipped smooth phase function
    `smooth_phase` (n_angle, n_wl) [sr^-1] and the smooth over the peak scattering
    `smooth_ratio` (n_wl,) also the peaks' blur of light scattered once in it (module
    docstring; zero without them)."""
    n_angle, n_wl = peak_phase.shape
    theta = np.linspace(0.0, np.pi, n_angle)
    psi_max = min(ANGLE_FACTOR * np.radians(truncation_angle_deg), np.pi)
    inside = theta <= np.radians(truncation_angle_deg) + theta[1]
    moments = _moments(theta, inside, peak_phase)
    x_max = min(max(float(x_max), 1e-3), X_LIMIT)
    x = np.expm1(np.log1p(x_max) * np.arange(X_NODES) / (X_NODES - 1))
    x[0] = 1e-6  # the limit x -> 0 (0 / 0 at 0 itself)
    xc = x[:, None, None] * moments[None]  # (n_x, degree + 1, n_wl)
    series = (np.expm1(xc) - xc) / (np.expm1(x) - x)[:, None, None]
    psi = theta[theta <= psi_max]
    shape = np.maximum(_legendre_sum(series, psi), 0.0)
    blur = np.zeros_like(shape)
    if smooth_phase is not None and smooth_ratio is not None:
        # B / r = sum_l (2 l + 1) / (4 pi) chi*_l exp(-x) (exp(x chi_l) - 1) P_l
        # + (exp(-x) - 1) p*: the series only where the peak's moments are not 0, so that p*'s
        # own series (a kink: it converges slowly) is never summed
        smooth = _moments(theta, np.ones(n_angle, dtype=bool), smooth_phase)
        blurred = _legendre_sum(smooth[None] * np.exp(-x)[:, None, None] * np.expm1(xc), psi)
        blur = smooth_ratio * (blurred + np.expm1(-x)[:, None, None]
                               * smooth_phase[None, :psi.size])
    return PeakAureole(np.ascontiguousarray(shape), np.ascontiguousarray(blur), x_max,
                       float(psi[-1]))


def _moments(theta: np.ndarray, inside: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Normalised Legendre moments chi_l, l = 0 .. MAX_DEGREE, (degree + 1, n_wl) of
    `phase` (n_angle, n_wl) sampled at `theta`, integrated over the angles `inside` (where
    it is not zero); 0 where it is 0."""
    # rectangles of the sampling's step: the trapezoid rule, sin(theta) being 0 at both ends
    weight = 2.0 * np.pi * np.sin(theta[inside]) * theta[1]
    moments = legendre.legvander(np.cos(theta[inside]), MAX_DEGREE).T @ (
        phase[inside] * weight[:, None])
    total = moments[0]
    return np.where(total > 0.0, moments / np.where(total > 0.0, total, 1.0), 0.0)


def _legendre_sum(coefficients: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """sum_l (2 l + 1) / (4 pi) c_l P_l(cos psi) of `coefficients` (n_x, degree + 1, n_wl)
    at the angles `psi`: (n_x, n_psi, n_wl)."""
    n_x, _, n_wl = coefficients.shape
    degree = np.arange(MAX_DEGREE + 1)
    terms = coefficients * ((2 * degree + 1) / (4.0 * np.pi))[None, :, None]
    table = (legendre.legvander(np.cos(psi), MAX_DEGREE)
             @ terms.transpose(1, 0, 2).reshape(MAX_DEGREE + 1, -1))
    return table.reshape(psi.size, n_x, n_wl).transpose(1, 0, 2)
