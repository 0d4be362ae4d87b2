"""Public constants of `skyscatter.api` that are cheap to import (no solver, no optics).

The command line names them in its help text, which it builds before any work; importing
`skyscatter.api` itself takes about half a second, so `skyscatter --help` reads them here.
Each is defined in its own layer and only re-exported: `DEFAULT_WAVELENGTH_BINS`
(`spectrum.grid`, the bins of images and tables when none are asked for), `COLOUR_RANGE_NM`
(`spectrum.grid`, the range of the colour-matching functions, which images are made over) and
`VALIDATION_CASES` (`validate.suite.CASES`: case key -> (module, one line on what it checks))
and `CUBE_LAYOUTS` (`render.cube_map`, the cube map camera's layouts), `AU_M`
(`spectrum.star`, the astronomical unit).
`solver_descriptions()` reads the solver registry (`transport.solvers.SOLVERS`) only when called,
because the registry imports the solvers themselves.
"""

from skyscatter.render.cube_map import CUBE_LAYOUTS
from skyscatter.spectrum.grid import COLOUR_RANGE_NM, DEFAULT_WAVELENGTH_BINS
from skyscatter.spectrum.star import AU_M
from skyscatter.validate.suite import CASES as VALIDATION_CASES

__all__ = [
    "AU_M",
    "COLOUR_RANGE_NM",
    "CUBE_LAYOUTS",
    "DEFAULT_WAVELENGTH_BINS",
    "VALIDATION_CASES",
    "solver_descriptions",
]


def solver_descriptions() -> dict[str, str]:
    """Name -> one line on the solver, of every registered solver, in registration order."""
    from skyscatter.transport.solvers import SOLVERS  # the solvers import numba: only on demand
    return dict(SOLVERS)
