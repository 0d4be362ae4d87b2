"""Public constants of `skyscatter.api` that are cheap to import (no solver, no optics).

The command line names them in its help text, which it builds before any work; importing
`skyscatter.api` itself takes about half a second, so `skyscatter --help` reads them here.
Each is defined in its own layer and only re-exported: `DEFAULT_WAVELENGTH_BINS`
(`spectrum.grid`, the bins of images and tables when none are asked for) and
`VALIDATION_CASES` (`validate.suite.CASES`: case key -> (module, one line on what it checks)).
"""

from skyscatter.spectrum.grid import DEFAULT_WAVELENGTH_BINS
from skyscatter.validate.suite import CASES as VALIDATION_CASES

__all__ = ["DEFAULT_WAVELENGTH_BINS", "VALIDATION_CASES"]
