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
    3 wavelengths (about 5 s). No forward-peak truncation: the brute-force references count the
    orders one by one, and truncation moves the light of the peaks' higher orders into the
    orders >= 2 and the aureole (checked against the Monte Carlo instead)."""
    return precompute_tables(profile, TableResolution(truncation_angle_deg=0.0), orders=2)
