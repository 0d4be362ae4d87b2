"""What several validation cases share: the table solver of an atmosphere, with the run's
cache and log.

Public names: `table_solver`.
"""

from __future__ import annotations

from skyscatter.atmosphere.model import Atmosphere, OpticalProfile
from skyscatter.transport.lut_solver import LutSolver
from skyscatter.transport.solvers import SolverOptions, make_solver
from skyscatter.validate.report import ValidationSettings

__all__ = ["table_solver"]


def table_solver(atmosphere: Atmosphere, profile: OpticalProfile,
                 settings: ValidationSettings, orders: int | None = None) -> LutSolver:
    """The precomputed-table solver of `profile` (sampled from `atmosphere`) with the
    atmosphere's own scattering orders (or `orders`), tables from `settings.cache`."""
    options = SolverOptions(orders=atmosphere.scattering_orders if orders is None else orders,
                            cache=settings.cache,
                            log=lambda message: settings.log(f"  {message}"))
    return make_solver("lut", profile, options)
