"""Fixtures shared by the table tests (test_transport_tables.py, test_transport_twilight.py):
computed once per session."""

import pytest
from transport_cases import exponential_earth

from skyscatter.transport.tables import TableResolution, precompute_tables


@pytest.fixture(scope="session")
def profile():
    return exponential_earth()


@pytest.fixture(scope="session")
def tables_two_orders(profile):
    """Bruneton's default resolution, mu_s down to cos(120 deg), orders 1 and 2, the profile's
    3 wavelengths (about 5 s)."""
    return precompute_tables(profile, TableResolution(), orders=2)
