"""A retrieval in stages: fit with a fast model, refine with an exact one, check at the answer.

    1. fit      `weighted_fit` with the fast forward model (a solver or a sweep), each residual
                weighted by sigma^2 = sigma_measured^2 + sigma_model^2 (`model_error`)
    2. refine   (optional) the same with the tables ("lut"), started from stage 1's answer
    3. check    (optional) each exact solver ("lut", "montecarlo") evaluated once at the
                answer: its residuals against the measurements, normalised by the measured
                sigma (and the Monte Carlo's own noise) only, and how far the fitted model is
                from it - what the model-error term assumed, measured at this sky

The report (`Retrieval.report`, JSON-ready) holds the estimates, 1-sigma uncertainties,
covariance and correlation, chi-square / degrees of freedom, the parameters the data do not
constrain and why, every row with its residuals, the checks and the time of each stage.

Public names: `Retrieval`, `retrieve`.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from skyscatter.fit.least_squares import LOOSE_FRACTION, WeightedFit, weighted_fit
from skyscatter.fit.measurements import Measurements
from skyscatter.fit.model_error import CORRELATION, error_covariance, whitened
from skyscatter.fit.parameters import FreeParameter

__all__ = ["Retrieval", "retrieve"]


class ForwardModel(Protocol):
    """What a stage needs: a name, a check of the rows before any work, and predictions."""

    name: str

    def check(self, measurements: Measurements) -> None: ...

    def predict(self, values: dict[str, float], measurements: Measurements
                ) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass
class Retrieval:
    """The answer of `retrieve`: the last stage's fit and the whole report."""

    keys: list[str]
    fit: WeightedFit
    report: dict[str, Any]

    @property
    def estimates(self) -> dict[str, float]:
        """key -> estimate."""
        return dict(zip(self.keys, map(float, self.fit.estimates), strict=True))

    @property
    def uncertainties(self) -> dict[str, float]:
        """key -> 1-sigma uncertainty."""
        return dict(zip(self.keys, map(float, self.fit.uncertainties), strict=True))


def retrieve(measurements: Measurements, free: Sequence[FreeParameter], model: ForwardModel,
             *, refine: ForwardModel | None = None, checks: Sequence[ForwardModel] = (),
             relative_weights: bool = False,
             model_error_correlation: float = CORRELATION) -> Retrieval:
    """Fit `free` to `measurements` with `model`, then `refine`, then `checks` (module
    docstring); `model_error_correlation` as `model_error.error_covariance`."""
    clock = time.perf_counter()
    stages = [model] + ([refine] if refine is not None else [])
    for stage in [*stages, *checks]:
        stage.check(measurements)
    keys = [p.key for p in free]
    fit: WeightedFit | None = None
    stage_reports = []
    for stage in stages:
        fit = weighted_fit(_residuals(stage, measurements, keys, model_error_correlation),
                           free,
                           relative_weights=relative_weights,
                           start=None if fit is None else fit.estimates)
        stage_reports.append(_stage_report(stage.name, keys, fit))
    assert fit is not None
    values = dict(zip(keys, map(float, fit.estimates), strict=True))
    predicted, model_sigma = stages[-1].predict(values, measurements)
    check_reports, check_columns = [], {}
    for check in checks:
        start = time.perf_counter()
        exact, noise = check.predict(values, measurements)
        sigma = np.hypot(measurements.uncertainty, _noise_only(check, noise, exact))
        normalised = (measurements.value - exact) / sigma
        check_columns[check.name] = exact
        check_reports.append({
            "model": check.name,
            "chi_square_measurement_only": float(normalised @ normalised),
            "values": measurements.size,
            "rms_normalised_residual": float(np.sqrt(np.mean(normalised ** 2))),
            "fitted_model_minus_check": _differences(measurements, predicted, exact),
            "seconds": time.perf_counter() - start})
    report = {
        "parameters": [_parameter(p, fit, i) for i, p in enumerate(free)],
        "correlation": _matrix(fit.correlation),
        "covariance": _matrix(fit.covariance),
        "covariance_scaling": ("scaled by the reduced chi-square (--relative-weights)"
                               if fit.scaled else "absolute: (J^T W J)^-1 from the stated "
                               "uncertainties, not scaled by the reduced chi-square"),
        "model_error_correlation": model_error_correlation,
        "chi_square": fit.chi_square, "degrees_of_freedom": fit.degrees_of_freedom,
        "reduced_chi_square": _finite(fit.reduced_chi_square),
        "singular_values": [float(s) for s in fit.singular_values],
        "not_constrained": fit.unconstrained,
        "not_constrained_rule": f"1-sigma above {100 * LOOSE_FRACTION:.0f} % of the bounds' "
                                "width, or in a direction of near-zero singular value of J",
        "stages": stage_reports, "checks": check_reports,
        "rows": _rows(measurements, predicted, model_sigma, check_columns),
        "seconds": time.perf_counter() - clock,
    }
    return Retrieval(keys, fit, report)


def _residuals(model: ForwardModel, measurements: Measurements, keys: list[str],
               correlation: float):
    """p -> the whitened residuals L^-1 (y - f(p)) under the measurement and model-error
    covariance at p (`model_error.error_covariance`)."""
    def weighted(p: np.ndarray) -> np.ndarray:
        predicted, model_sigma = model.predict(dict(zip(keys, map(float, p), strict=True)),
                                               measurements)
        covariance = error_covariance(measurements.uncertainty, model_sigma,
                                      measurements.kind, correlation)
        return whitened(measurements.value - predicted, covariance)
    return weighted


def _noise_only(check: ForwardModel, noise: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """The check's own noise (the Monte Carlo's standard error), without the table's model
    error: a check states the measured sigma only, so the model error is what it tests."""
    if check.name == "montecarlo":
        return noise
    return np.zeros_like(exact)


def _differences(measurements: Measurements, fitted: np.ndarray, exact: np.ndarray
                 ) -> dict[str, float]:
    """Median and largest |fitted / check - 1| (radiance, transmittance) and |dx|, |dy|."""
    out = {}
    for kind, relative in (("radiance", True), ("transmittance", True),
                           ("chromaticity", False), ("luminance", True)):
        index = measurements.where(kind)
        if index.size:
            d = fitted[index] - exact[index]
            d = np.abs(d / exact[index]) if relative else np.abs(d)
            name = f"{kind}_{'relative' if relative else 'absolute'}"
            out[f"{name}_median"] = float(np.median(d))
            out[f"{name}_max"] = float(np.max(d))
    return out


def _stage_report(name: str, keys: list[str], fit: WeightedFit) -> dict[str, Any]:
    return {"model": name, "estimates": dict(zip(keys, map(float, fit.estimates), strict=True)),
            "uncertainties": dict(zip(keys, map(_finite, fit.uncertainties), strict=True)),
            "chi_square": fit.chi_square, "reduced_chi_square": _finite(fit.reduced_chi_square),
            "evaluations": fit.evaluations, "seconds": fit.seconds,
            "converged": fit.success, "message": fit.message}


def _parameter(p: FreeParameter, fit: WeightedFit, i: int) -> dict[str, Any]:
    return {"key": p.key, "estimate": float(fit.estimates[i]),
            "uncertainty": _finite(fit.uncertainties[i]), "low": p.low, "high": p.high,
            "start": p.start,
            "constrained": not any(n["key"] in (p.key, "all") for n in fit.unconstrained)}


def _rows(measurements: Measurements, predicted: np.ndarray, model_sigma: np.ndarray,
          checks: dict[str, np.ndarray]) -> list[dict[str, Any]]:
    """Each value with its fit: normalised_residual is (measured - fitted) / sqrt(sigma^2 +
    sigma_model^2), the row's own share (chi-square also counts the model error's
    correlation between rows)."""
    rows = []
    for i in range(measurements.size):
        row: dict[str, Any] = {"row": int(measurements.row[i]),
                               "quantity": str(measurements.kind[i])}
        for name in ("sun_zenith_deg", "view_zenith_deg", "relative_azimuth_deg",
                     "wavelength_nm"):
            value = float(getattr(measurements, name)[i])
            if np.isfinite(value):
                row[name] = value
        row.update({"measured": float(measurements.value[i]),
                    "uncertainty": float(measurements.uncertainty[i]),
                    "model_error": float(model_sigma[i]), "fitted": float(predicted[i]),
                    "normalised_residual": float((measurements.value[i] - predicted[i])
                                                 / np.hypot(measurements.uncertainty[i],
                                                            model_sigma[i]))})
        for name, values in checks.items():
            row[f"check_{name}"] = float(values[i])
        rows.append(row)
    return rows


def _matrix(matrix: np.ndarray) -> list[list[float | None]]:
    return [[_finite(v) for v in row] for row in np.asarray(matrix)]


def _finite(value: float) -> float | None:
    """JSON has no NaN or inf: None stands for them."""
    value = float(value)
    return value if np.isfinite(value) else None
