"""Astro tests: astropy (the independent reference) must work offline and quietly.

astropy may not download IERS tables or ephemerides here: it uses its bundled IERS-B table and
the 'builtin' (ERFA) ephemeris. Dates beyond the table (2050) or before UTC existed (1950) make
it warn ("dubious year", degraded accuracy of UT1 − UTC); those warnings are expected.
"""

import warnings

import pytest

try:
    from astropy.utils import iers
    from astropy.utils.data import conf

    iers.conf.auto_download = False
    iers.conf.auto_max_age = None
    iers.conf.iers_degraded_accuracy = "warn"
    conf.allow_internet = False
except ImportError:  # astropy is a test extra; the astropy comparisons skip without it
    pass


@pytest.fixture(autouse=True)
def quiet_astropy():
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*dubious year.*")
        warnings.filterwarnings("ignore", message=".*(IERS|iers|ERFA|erfa).*")
        warnings.filterwarnings("ignore", message=".*Tried to get polar motions.*")
        warnings.filterwarnings("ignore", message=".*leap-second.*")
        try:
            from astropy.utils.exceptions import AstropyWarning
            from erfa import ErfaWarning

            warnings.filterwarnings("ignore", category=ErfaWarning)
            warnings.filterwarnings("ignore", category=AstropyWarning)
        except ImportError:
            pass
        yield
