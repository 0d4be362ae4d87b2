"""The sum of all scattering orders of an optically thick atmosphere from its last few orders.

The orders of a cloud deck converge slowly: each is ~0.95 of the one before in a stratus of
optical depth 20, and the shape of its radiance field keeps changing for 20-30 orders before one
mode takes over, so the geometric series of `tables._geometric_tail` (one ratio per wavelength
for the whole table) stays off by several percent in places until then. The partial sums
x_n = sum_{m <= n} Delta S_m of the orders are the iterates of a linear fixed-point iteration
(Delta S_{n+1} = K Delta S_n: `tables` module docstring), the case vector extrapolation methods
are built for. Reduced-rank extrapolation (RRE; Mesina 1977, Comput. Methods Appl. Mech. Eng.
10, 165, doi:10.1016/0045-7825(77)90004-4; Eddy 1979; Sidi 2017, "Vector Extrapolation Methods
with Applications", SIAM, doi:10.1137/1.9781611974966, ch. 1) estimates the limit from the last
k + 1 orders as

    s_n = sum_{i=0..k} gamma_i x_{n-k+i},   sum_i gamma_i = 1,
    gamma minimising |sum_i gamma_i Delta S_{n-k+i}|   (a (k+1) x (k+1) linear system),

per wavelength (each wavelength is its own iteration); s_n is exact once the orders lie in a
space of k modes. The sky light on the ground, a linear function of the same orders, is
extrapolated with the same gamma. The iteration stops once the estimates have converged: the
change |s_n / s_(n-1) - 1| (median and 95th percentile over the cells) times rho / (1 - rho),
rho the ratio of successive changes, is below ERROR_MEDIAN and ERROR_P95.

Measured on `earth-overcast` at 550 nm against 70 orders plus their geometric tail: stopped at
16 orders, |e| of the orders >= 2 median / 95th / 99th percentile 0.07 / 1.06 / 3.0 %, where
the geometric series needs 30 orders for 0.13 / 2.2 / 3.4 % (docs/physics/tables.md).
"""

from __future__ import annotations

from collections import deque

import numpy as np

__all__ = ["EXTRAPOLATION_DELTAS", "EXTRAPOLATION_FIRST_ORDER", "OrderExtrapolation"]

# k + 1 = 6 orders per estimate: with 4 the 95th percentile above needs 2 orders more, with 7
# little is gained (benchmarks/bench_order_extrapolation.py)
EXTRAPOLATION_DELTAS = 6
# the first order kept: after the orders where the geometric series stops thin atmospheres
# (Earth and `mars-physical` at 6), so that they neither change nor hold the extra tables
EXTRAPOLATION_FIRST_ORDER = 7
# the estimate's error left, from the changes of the last three estimates |s_n / s_(n-1) - 1|
# (`OrderExtrapolation.add`): median and 95th percentile over the cells
ERROR_MEDIAN = 1e-3
ERROR_P95 = 1e-2
# cells below this fraction of the median estimate are left out of the agreement test (dark
# corners of the table, where a relative change says nothing)
DARK_CELL = 1e-3
# every SAMPLE_STRIDE-th cell enters the least-squares system and the agreement test
SAMPLE_STRIDE = 7


class OrderExtrapolation:
    """Feed it each order's table and ground-irradiance increments (`add`); it answers with
    the tails to add (the estimated sum of all orders less the partial sums) once its
    estimates have settled (module docstring)."""

    def __init__(self, first_order: int = EXTRAPOLATION_FIRST_ORDER,
                 deltas: int = EXTRAPOLATION_DELTAS) -> None:
        self.first_order = first_order
        self._deltas: deque[np.ndarray] = deque(maxlen=deltas)
        self._samples: deque[np.ndarray] = deque(maxlen=deltas)  # `_sample` of each delta
        self._irradiance: deque[np.ndarray] = deque(maxlen=deltas)
        self._previous_tail: np.ndarray | None = None
        self._changes: deque[np.ndarray] = deque(maxlen=3)

    def add(self, order: int, partial: np.ndarray, delta: np.ndarray,
            delta_irradiance: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        """After order `order`: `partial` (..., n_wl) the sum of the orders so far (this one
        included), `delta` (..., n_wl) this order, `delta_irradiance` (..., n_wl) its
        increment of the ground irradiance. Returns (tail of `partial`, tail of the irradiance),
        in the dtypes of `delta` and `delta_irradiance`, once the estimate's error left is
        below ERROR_MEDIAN and ERROR_P95, else None."""
        if order < self.first_order:
            return None
        self._deltas.append(delta)
        self._samples.append(_sample(delta))
        self._irradiance.append(delta_irradiance)
        if len(self._deltas) < self._deltas.maxlen:
            return None
        cumulative = _rre_cumulative_weights(np.stack(self._samples))
        if cumulative is None:
            self._previous_tail = None
            self._changes.clear()
            return None
        tail_sample = _tail(cumulative, list(self._samples))
        previous, self._previous_tail = self._previous_tail, tail_sample
        if previous is None:
            return None
        estimate = _sample(partial) + tail_sample
        lit = estimate > 0.0
        if not np.any(lit):
            return None
        lit &= estimate > DARK_CELL * np.median(estimate[lit])
        # s_n - s_(n-1), with s_(n-1) = x_n - Delta S_n + tail_(n-1)
        change = np.abs(tail_sample - previous + self._samples[-1])[lit] / estimate[lit]
        self._changes.append(np.array([np.median(change), np.percentile(change, 95)]))
        if len(self._changes) < self._changes.maxlen:
            return None
        # the estimates converge geometrically too: what is left of the change is the change
        # times rho / (1 - rho), rho the larger of its last two ratios
        older, old, new = self._changes
        with np.errstate(divide="ignore", invalid="ignore"):
            rho = np.maximum(new / old, old / older)
        if not np.all(rho < 1.0):
            return None
        left = new * rho / (1.0 - rho)
        if left[0] > ERROR_MEDIAN or left[1] > ERROR_P95:
            return None
        return _tail(cumulative, list(self._deltas)), _tail(cumulative, list(self._irradiance))


def _sample(table: np.ndarray) -> np.ndarray:
    """Every SAMPLE_STRIDE-th cell of `table` (..., n_wl) (any memory layout, no copy of the
    whole), as float64 (n_cells, n_wl)."""
    cells = np.unravel_index(np.arange(0, int(np.prod(table.shape[:-1])), SAMPLE_STRIDE),
                             table.shape[:-1])
    return table[cells].astype(np.float64)


def _rre_cumulative_weights(deltas: np.ndarray) -> np.ndarray | None:
    """C_l = gamma_0 + ... + gamma_l (k + 1, n_wl) of RRE from the last k + 1 orders
    `deltas` (k + 1, n_cells, n_wl); None where a system is singular (an order of zeros)."""
    gram = np.einsum("imw,jmw->wij", deltas, deltas)
    n = gram.shape[-1]
    # Tikhonov term far below the orders' own scale: keeps nearly parallel late orders solvable
    scale = np.trace(gram, axis1=1, axis2=2)[:, None, None]
    if not np.all(scale > 0.0):
        return None
    y = np.linalg.solve(gram / scale + 1e-12 * np.eye(n), np.ones((gram.shape[0], n, 1)))[..., 0]
    total = y.sum(axis=1)
    if not np.all(np.isfinite(y)) or np.any(total == 0.0):
        return None
    return np.cumsum(y / total[:, None], axis=1).T


def _tail(cumulative: np.ndarray, deltas: list[np.ndarray]) -> np.ndarray:
    """s_n - x_n = sum_i gamma_i (x_(n-k+i) - x_n) = -sum_{l=1..k} C_(l-1) Delta_l, with
    Delta_0 .. Delta_k the last k + 1 orders (`deltas`, each (..., n_wl)), in their dtype."""
    tail = np.zeros_like(deltas[0])
    term = np.empty_like(tail)
    for l in range(1, len(deltas)):
        np.multiply(deltas[l], cumulative[l - 1].astype(tail.dtype), out=term)
        tail -= term
    return tail
