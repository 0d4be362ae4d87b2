"""Bounded weighted least squares with the covariance of the answer and what it cannot tell.

Minimises chi^2(p) = sum_i ((y_i - f_i(p)) / sigma_i)^2 within the bounds by the trust-region
reflective method (`scipy.optimize.least_squares(method="trf")`; Branch, Coleman & Li 1999,
SIAM J. Sci. Comput. 21, 1, doi:10.1137/S1064827595289108), on each parameter rescaled to
u = (p - low) / (high - low) in [0, 1] so one finite-difference step (`DIFF_STEP` of the
bounds' width) and one trust region suit every parameter.

At the solution, with J the Jacobian of the weighted residuals (central differences, one
evaluation each side per parameter) r_i = (y_i - f_i) / sigma_i,

    C = (J^T J)^-1                       (Rodgers 2000, "Inverse Methods for Atmospheric
                                          Sounding", eq. 2.27 without a prior: sigma_i absolute)
    C_scaled = C chi^2 / (m - n)         (sigma_i only relative weights: scaled by the reduced
                                          chi-square, as scipy.optimize.curve_fit's
                                          absolute_sigma=False)

for m values and n parameters; 1-sigma uncertainties are sqrt(diag C), correlations
C_ij / sqrt(C_ii C_jj). The singular values s_k of J (on the rescaled parameters) say what the
data constrain (Rodgers 2000 §2.4-2.5): a direction with s_k / s_max < `DEGENERATE` is not
constrained, and the parameters with the largest share of it are named; the pseudo-inverse
leaves it out of C, so their uncertainty is reported as unbounded (inf). A parameter is also
"not constrained" when its 1-sigma uncertainty exceeds `LOOSE_FRACTION` of its bounds' width,
and its uncertainty is then a statement of the bounds more than of the data.

Public names: `DEGENERATE`, `DIFF_STEP`, `LOOSE_FRACTION`, `WeightedFit`, `weighted_fit`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from skyscatter.fit.parameters import FreeParameter

__all__ = ["DEGENERATE", "DIFF_STEP", "LOOSE_FRACTION", "WeightedFit", "weighted_fit"]

DIFF_STEP = 1e-3  # of the bounds' width: well above a solver's rounding (1e-10 relative),
# small enough that the curvature of f over the step is below the noise
DEGENERATE = 1e-3  # s_k / s_max below it: a direction the data do not see (rescaled units)
LOOSE_FRACTION = 0.25  # 1-sigma above a quarter of the bounds' width: not constrained
AT_BOUND = 1e-6  # rescaled distance from a bound that counts as on it


@dataclass
class WeightedFit:
    """The answer of `weighted_fit`, in the parameters' own units."""

    estimates: np.ndarray  # (n,)
    uncertainties: np.ndarray  # (n,) 1-sigma; inf where not constrained by any direction
    covariance: np.ndarray  # (n, n)
    correlation: np.ndarray  # (n, n); NaN where an uncertainty is inf
    residuals: np.ndarray  # (m,) weighted, (y - f) / sigma
    chi_square: float
    degrees_of_freedom: int
    scaled: bool  # covariance scaled by the reduced chi-square
    singular_values: np.ndarray  # of J on the rescaled parameters, descending
    evaluations: int
    seconds: float
    success: bool
    message: str
    unconstrained: list[dict[str, str]] = field(default_factory=list)

    @property
    def reduced_chi_square(self) -> float:
        """chi^2 / (m - n); NaN without degrees of freedom."""
        dof = self.degrees_of_freedom
        return self.chi_square / dof if dof > 0 else float("nan")


def weighted_fit(residuals: Callable[[np.ndarray], np.ndarray],
                 parameters: Sequence[FreeParameter], *, relative_weights: bool = False,
                 start: np.ndarray | None = None, max_evaluations: int = 200) -> WeightedFit:
    """The bounded least-squares fit of the weighted residuals `residuals(p)` ((m,), already
    divided by their sigma) over `parameters` (module docstring), from their starts or
    `start`. `relative_weights`: the sigmas are relative only; scale the covariance by the
    reduced chi-square."""
    from scipy.optimize import least_squares

    low = np.array([p.low for p in parameters])
    width = np.array([p.width for p in parameters])
    first = np.array([p.start for p in parameters]) if start is None else np.asarray(start)
    u0 = np.clip((first - low) / width, 0.0, 1.0)
    clock = time.perf_counter()
    solution = least_squares(lambda u: residuals(low + u * width), u0, bounds=(0.0, 1.0),
                             method="trf", jac="2-point", diff_step=DIFF_STEP, x_scale=1.0,
                             max_nfev=max_evaluations)
    jacobian = _central_jacobian(lambda u: residuals(low + u * width), solution.x,
                                 solution.fun)
    seconds = time.perf_counter() - clock
    m, n = jacobian.shape
    chi_square = float(solution.fun @ solution.fun)
    singular = np.linalg.svd(jacobian, compute_uv=False)
    covariance_u, degenerate = _covariance(jacobian)
    dof = m - n
    scaled = bool(relative_weights and dof > 0)
    if scaled:
        covariance_u = covariance_u * (chi_square / dof)
    covariance = covariance_u * np.outer(width, width)
    sigma = np.sqrt(np.diag(covariance))
    sigma[degenerate] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        correlation = covariance / np.outer(sigma, sigma)
    correlation[degenerate, :] = np.nan
    correlation[:, degenerate] = np.nan
    estimates = low + solution.x * width
    notes = _unconstrained(parameters, jacobian, sigma, solution.x)
    return WeightedFit(estimates, sigma, covariance, correlation, solution.fun.copy(),
                       chi_square, dof, scaled, singular,
                       int(solution.nfev) + 2 * len(parameters), seconds,
                       bool(solution.success), str(solution.message), notes)


def _central_jacobian(function: Callable[[np.ndarray], np.ndarray], u: np.ndarray,
                      at_u: np.ndarray) -> np.ndarray:
    """d function / d u at `u` by central differences of step `DIFF_STEP` (error O(h^2): the
    optimiser's forward differences are off by f'' h / 2, 0.05 % for Beer-Lambert at
    airmass 5), one-sided inside [0, 1] where a bound is within the step."""
    columns = []
    for k in range(u.size):
        up, down = u.copy(), u.copy()
        up[k] = min(1.0, u[k] + DIFF_STEP)
        down[k] = max(0.0, u[k] - DIFF_STEP)
        high = function(up) if up[k] != u[k] else at_u
        low = function(down) if down[k] != u[k] else at_u
        columns.append((high - low) / (up[k] - down[k]))
    return np.stack(columns, axis=-1)


def _covariance(jacobian: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(J^T J)^-1 on the constrained directions (pseudo-inverse, singular values below
    DEGENERATE s_max left out), and a mask of the parameters in a left-out direction."""
    _, s, vt = np.linalg.svd(jacobian, full_matrices=False)
    n = jacobian.shape[1]
    degenerate = np.zeros(n, dtype=bool)
    if s.size == 0 or s[0] == 0.0:
        return np.full((n, n), np.inf), np.ones(n, dtype=bool)
    kept = s > DEGENERATE * s[0]
    for k in np.flatnonzero(~kept):
        degenerate |= np.abs(vt[k]) > 0.3  # the parameters with a large share of it
    inverse = (vt[kept].T / s[kept] ** 2) @ vt[kept]
    if s.size < n:  # fewer values than parameters: nothing is constrained alone
        degenerate[:] = True
    return inverse, degenerate


def _unconstrained(parameters: Sequence[FreeParameter], jacobian: np.ndarray,
                   sigma: np.ndarray, u: np.ndarray) -> list[dict[str, str]]:
    """Each parameter the data do not constrain, with the reason."""
    notes = []
    _, s, vt = np.linalg.svd(jacobian, full_matrices=False)
    for k in np.flatnonzero(s <= DEGENERATE * (s[0] if s.size else 0.0)):
        names = [p.key for p, v in zip(parameters, vt[k], strict=True) if abs(v) > 0.3]
        for name in names:
            others = [other for other in names if other != name]
            why = (f"only a combination with {', '.join(others)} is constrained" if others
                   else "the measurements do not change with it")
            notes.append({"key": name, "reason": f"{why} (singular value "
                          f"{s[k] / s[0]:.1e} of the largest)"})
    if jacobian.shape[0] < len(parameters):
        notes.append({"key": "all", "reason": f"{jacobian.shape[0]} values for "
                      f"{len(parameters)} parameters"})
    named = {note["key"] for note in notes}
    for p, sd, at in zip(parameters, sigma, u, strict=True):
        if p.key in named:
            continue
        if np.isfinite(sd) and sd > LOOSE_FRACTION * p.width:
            notes.append({"key": p.key, "reason": f"1-sigma {sd:.3g} is "
                          f"{100 * sd / p.width:.0f} % of the bounds' width {p.width:g} "
                          f"(more than {100 * LOOSE_FRACTION:.0f} %)"})
        elif min(at, 1.0 - at) < AT_BOUND:
            notes.append({"key": p.key, "reason": "the estimate sits on a bound; its "
                          "uncertainty assumes the bound is not there"})
    return notes
