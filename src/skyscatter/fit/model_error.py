"""How far each forward model is from the exact answer: the model-error term of a fit.

A fit weighs each residual by sigma^2 = sigma_measured^2 + sigma_model^2 (Rodgers 2000,
"Inverse Methods for Atmospheric Sounding", §3.2: the forward-model error adds its covariance
to the measurement's; Dubovik & King 2000, JGR 105, 20673, doi:10.1029/2000JD900282, §3 weigh
AERONET's sky radiances the same way). Without it a fast model's bias of several per cent
would be read as information the data do not hold, and the stated uncertainties would be too
small. sigma_model is relative for radiance and transmittance (a fraction of the model's
value) and absolute for chromaticity x, y.

The numbers are 1-sigma readings of docs/techniques.md (each solver against the in-project
Monte Carlo over 51 directions, 8 bands, sun zenith 0-80 deg; a median |error| m of a
normal error is 0.67 sigma, so sigma ~ 1.5 m, and the 95th percentile ~ 2 sigma):

    lut        radiance median 0.5-0.9 % (clear Earth), 0.7-2.5 % (hazy), 0.7-1.5 % (Mars);
               95th percentile 2-7 %  -> 0.02;   Delta xy 0.001 -> 0.002
    hillaire   median 6-11 % (clear Earth), 11-25 % (hazy); 95th 10-54 %  -> 0.10 (Earth);
               Delta xy 0.004-0.011 -> 0.01. Mars: 48-76 %: not a forward model for Mars
               (use lut; a fit with it states that sigma_model).
    schuler, single   single scattering only: 46-56 % (worst band) -> 0.5; Delta xy 0.02 -> 0.03
    luminance  (integrated over the visible, so below the worst band's error) median at sun
               zenith 30 deg: lut 0.4-2.0 % -> 0.02; hillaire 3.3-6.0 % (Earth) -> 0.06;
               schuler 28-43 % -> 0.35
    montecarlo its own standard error per value (added by the model, not from this table)

Direct-sun transmittance is ray marched (`transport.transmittance.ray_marched_transmittance`,
1024 trapezoid intervals) by every model: Beer-Lambert along the spherical path, exact for the
atmosphere up to the quadrature, 1e-4 relative -> 0.001 (a sweep interpolates it: 0.002).

How the model errors of different values are related is not known; the covariance
(Rodgers 2000 §3.2.1, S_f) is

    S_f,ij = sigma_i sigma_j (rho [kind_i = kind_j] + (1 - rho) [i = j])

with a share rho of the variance common to all values of one kind (the model's overall level)
and the rest independent (its pattern). `error_covariance` adds the measurements' diagonal
and `whitened` divides the residuals by the Cholesky factor of the sum, so chi^2 = r^T S^-1 r.
rho = 0 (independent, the default) is what the synthetic retrievals support: the truth within
2 sigma in 98-100 % of 50 trials with the tables' and with hillaire's sweep; rho = 0.5 leaves
the tables' fits as good but biases hillaire's (its angular pattern is wrong, and a common
level that is let go leaves the pattern to decide: 92 %), rho = 1 fails it (0-2 %)
(docs/fit.md, benchmarks/bench_fit_coverage.py).

Public names: `CORRELATION`, `MODEL_ERRORS`, `error_covariance`, `model_error`, `whitened`.
"""

from __future__ import annotations

import numpy as np

from skyscatter.errors import InputError

__all__ = ["CORRELATION", "MODEL_ERRORS", "error_covariance", "model_error", "whitened"]

# solver -> (radiance [relative], transmittance [relative], chromaticity x, y [absolute],
#            luminance [relative])
MODEL_ERRORS: dict[str, tuple[float, float, float, float]] = {
    "lut": (0.02, 0.001, 0.002, 0.02),
    "hillaire": (0.10, 0.001, 0.01, 0.06),
    "schuler": (0.5, 0.001, 0.03, 0.35),
    "single": (0.5, 0.001, 0.03, 0.35),
    "montecarlo": (0.0, 0.001, 0.0, 0.0),
}
CORRELATION = 0.0  # share of the model error's variance common to all values of one kind
SWEEP_TRANSMITTANCE = 0.002  # interpolated transmittance: quadrature + log-linear interpolation


def model_error(solver: str, kind: np.ndarray, predicted: np.ndarray,
                override: float | None = None, *, sweep: bool = False) -> np.ndarray:
    """sigma_model of each predicted value (kinds as `measurements.Measurements.kind`): the
    table above for `solver`, or `override` (a fraction for radiance and luminance, an
    absolute x, y error for chromaticity) for every value but transmittance."""
    if solver not in MODEL_ERRORS and override is None:
        raise InputError(f"no model error is known for the {solver!r} solver: give one "
                         "(--model-error FRACTION)", key="model_error", value=solver,
                         allowed=", ".join(MODEL_ERRORS))
    radiance, transmittance, chromaticity, luminance = MODEL_ERRORS.get(
        solver, (0.0, 0.001, 0.0, 0.0))
    if override is not None:
        radiance = chromaticity = luminance = override
    if sweep:
        transmittance = SWEEP_TRANSMITTANCE
    kind = np.asarray(kind).astype(str)
    predicted = np.abs(np.asarray(predicted, dtype=np.float64))
    relative = {"radiance": radiance, "transmittance": transmittance, "luminance": luminance}
    sigma = np.full(kind.shape, chromaticity, dtype=np.float64)
    for name, fraction in relative.items():
        sigma = np.where(kind == name, fraction * predicted, sigma)
    return sigma


def error_covariance(uncertainty: np.ndarray, sigma_model: np.ndarray, kind: np.ndarray,
                     correlation: float = CORRELATION) -> np.ndarray:
    """S = diag(uncertainty^2) + S_f (module docstring), (n, n)."""
    kind = np.asarray(kind).astype(str)
    same = kind[:, None] == kind[None, :]
    shared = correlation * np.outer(sigma_model, sigma_model) * same
    return shared + np.diag(np.asarray(uncertainty) ** 2 + (1.0 - correlation)
                            * np.asarray(sigma_model) ** 2)


def whitened(difference: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """L^-1 difference for S = L L^T (Cholesky): residuals whose squares sum to chi^2."""
    from scipy.linalg import solve_triangular

    factor = np.linalg.cholesky(covariance)
    return solve_triangular(factor, difference, lower=True)
